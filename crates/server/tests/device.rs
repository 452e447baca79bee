//! `coiffure serve --device` driven by `coiffure device-sim` end to end: real processes, UDP on loopback,
//! a WebSocket viewer watching the device status (issue 13's acceptance).

mod common;

use common::{bin, scratch};
use std::net::TcpStream;
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

/// `coiffure serve --device udp:127.0.0.1:0` on a small built-in hairstyle (5000 render strands standing for
/// 20 hairs each: the force of a full head).
fn serve(extra: &[&str]) -> common::Server {
    let mut args = vec!["--render-strands", "5000", "--hairs-per-render-strand", "20", "--device", "udp:127.0.0.1:0"];
    args.extend_from_slice(extra);
    common::serve(&args)
}

/// Watches the viewer protocol's DEVICE messages (0x89): (seconds since `t0`, state, counters).
fn watch_device(http: &str, t0: Instant, stop: mpsc::Receiver<()>) -> std::thread::JoinHandle<Vec<(f64, u8, [u32; 6])>> {
    let stream = TcpStream::connect(http).unwrap();
    let (mut ws, _) = tungstenite::client(format!("ws://{http}/ws"), stream).unwrap();
    ws.get_mut().set_read_timeout(Some(Duration::from_millis(200))).unwrap();
    std::thread::spawn(move || {
        let mut seen = Vec::new();
        while stop.try_recv().is_err() {
            match ws.read() {
                Ok(tungstenite::Message::Binary(b)) if b.len() == 27 && b[0] == 0x89 => {
                    let u = |i: usize| u32::from_le_bytes(b[3 + 4 * i..7 + 4 * i].try_into().unwrap());
                    seen.push((t0.elapsed().as_secs_f64(), b[2], [u(0), u(1), u(2), u(3), u(4), u(5)]));
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(e) => panic!("viewer connection: {e}"),
            }
        }
        seen
    })
}

/// Rows of device-sim's CSV: t, x, y, z, fx, fy, fz, latency_us, flags (the felt force's hx, hy, hz after them
/// left out).
fn read_csv(path: &PathBuf) -> Vec<[f64; 9]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), haptics::sim::CSV_HEADER);
    lines.map(|l| l.split(',').take(9).map(|x| x.parse::<f64>().unwrap()).collect::<Vec<_>>().try_into().unwrap()).collect()
}

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

#[test]
fn a_simulated_device_combs_the_live_hair_and_faults_are_handled() {
    // The comb stroke of examples/scenarios/live-comb.toml (in the back hair from 0.3 s to 1.05 s, out by
    // 1.45 s) streamed at 1 kHz by a rigid simulated Phantom Omni through the default workspace mapping; then,
    // out of the hair, a NaN pose at 1.6 s, a 10 m teleport at 1.7 s, a duplicate at 1.8 s, and no poses
    // from 2.0 s for 0.3 s. A viewer watches the DEVICE status.
    let server = serve(&[]);
    let dir = scratch("sim");
    let csv = dir.join("trace.csv");
    let t0 = Instant::now();
    let (stop_tx, stop_rx) = mpsc::channel();
    let watcher = watch_device(&server.http, t0, stop_rx);
    let started = t0.elapsed().as_secs_f64();
    let out = bin()
        .args(["device-sim", "--server", &format!("udp:{}", server.udp.as_deref().unwrap()), "--rate", "1000", "--duration", "2.6"])
        .arg("--path")
        .arg(repo("examples/scenarios/live-comb.toml"))
        .args(["--nan-at", "1.6", "--teleport-at", "1.7", "--duplicate-at", "1.8", "--pause", "2.0:0.3", "--out"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::thread::sleep(Duration::from_millis(300));
    stop_tx.send(()).unwrap();
    let status = watcher.join().unwrap();
    let summary = String::from_utf8_lossy(&out.stdout).to_string();
    let rows = read_csv(&csv);
    drop(server);

    // Poses answered, round trip, forces.
    let flagged = |r: &[f64; 9]| r[8] as u32 & 1 == 1;
    let poses: Vec<&[f64; 9]> = rows.iter().filter(|r| !flagged(r) && r[1].is_finite() && r[1].abs() < 5.0).collect();
    let answered: Vec<&&[f64; 9]> = poses.iter().filter(|r| r[7].is_finite()).collect();
    let latency: Vec<f64> = answered.iter().map(|r| r[7] * 1e-6).collect();
    let (p50, p99) = (quantile(latency.clone(), 0.5), quantile(latency.clone(), 0.99));
    let in_hair = answered.iter().filter(|r| r[0] > 0.4 && r[0] < 1.0).map(|r| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt()).fold(0.0, f64::max);
    let largest = answered.iter().map(|r| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt()).fold(0.0, f64::max);
    println!("{summary}");
    println!("poses {} answered {} ({:.1} %), round trip p50 {:.0} us p99 {:.0} us; largest force in the hair {in_hair:.3} N, anywhere {largest:.3} N", poses.len(), answered.len(), 100.0 * answered.len() as f64 / poses.len() as f64, p50 * 1e6, p99 * 1e6);
    assert!(answered.len() as f64 >= 0.95 * poses.len() as f64, "answered {} of {}", answered.len(), poses.len());
    assert!(answered.iter().all(|r| r[4].is_finite() && r[5].is_finite() && r[6].is_finite()), "finite forces");
    // The force travels as f32 components (device-sim's CSV): the magnitude carries their rounding, ~1e-7 N.
    assert!(largest <= 3.3 * (1.0 + 1e-6), "within the Omni's 3.3 N: {largest} N");
    // The hair's resistance: 0.046-0.071 N measured with issue 12's law, 0.12 N with the combing law (on since
    // 2026-11-30; a device alone combs with it since c398972, before which it felt 0.018-0.041 N). Before the
    // device's samples were followed on their own clock (2026-11-28) their arrival jitter made the force buzz
    // at the Omni's rate limit (0.3 N a step) in and out of the hair, and this check asked for 0.05 N.
    assert!(in_hair > 0.025, "the comb in the hair is felt: {in_hair} N");
    // Loose bounds: answers are fresh, not queued (a backlog would put the median at seconds). The 2 ms p99
    // figure on an idle machine is in bench/RESULTS.md; timing targets are not asserted in tests on a shared
    // machine (under a parallel build the p99 reached 140 ms while the median stayed at a few ms).
    assert!(p50 < 0.05 && p99 < 0.5, "round trip p50 {p50} s, p99 {p99} s");

    // The NaN pose, the 10 m teleport and the duplicate: answered with the rejected flag and zero force (a row's
    // t is when it was sent: a stalled simulator sends a scheduled fault a few ms late).
    let rejected: Vec<&[f64; 9]> = rows.iter().filter(|r| flagged(r)).collect();
    for (what, t) in [("NaN", 1.6), ("teleport", 1.7), ("duplicate", 1.8)] {
        let r = rejected.iter().find(|r| (r[0] - t).abs() < 0.05).unwrap_or_else(|| panic!("the {what} pose at {t} s was answered with the flag: {rejected:?}"));
        assert_eq!([r[4], r[5], r[6]], [0.0; 3], "{what}: zero force");
    }
    assert!(rows.iter().any(|r| r[1].is_nan() && flagged(r)), "the NaN row");
    assert!(rows.iter().any(|r| r[1].abs() > 5.0 && flagged(r)), "the teleport row");
    assert_eq!(rejected.len(), 3, "nothing else rejected: {rejected:?}");

    // The pause: no poses for 300 ms (DEVICE comes at 10 Hz). The viewer saw the device connected during the stroke, lost during the
    // pause, and connected again after it.
    let at = |t: f64| started + t;
    let state_in = |a: f64, b: f64| status.iter().filter(|s| s.0 >= at(a) && s.0 <= at(b)).map(|s| s.1).collect::<Vec<_>>();
    println!("device status seen by the viewer: {:?}", status.iter().map(|s| (format!("{:.2}", s.0 - started), s.1)).collect::<Vec<_>>());
    assert!(state_in(0.3, 1.5).contains(&1), "connected during the stroke");
    assert!(state_in(2.1, 2.3).contains(&2), "lost during the pause");
    assert!(state_in(2.4, 2.6).contains(&1), "connected after the pause");
    let last = status.last().unwrap().2;
    // Lost at the pause and at the end of the stream (more if the loaded machine stalled the simulator for
    // over 50 ms: that is a real loss as the server sees it).
    assert!(last[4] >= 2, "lost at the pause and at the end of the stream: {last:?}");
    assert_eq!(last[1], 3, "three rejected poses: {last:?}");
}
