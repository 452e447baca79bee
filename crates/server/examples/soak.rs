//! Soak test of `coiffure serve` (issue 16; bench/RESULTS.md): a real server on loopback driven for a bounded
//! time by WebSocket clients the way a long session and a careless or hostile client would, reporting memory,
//! frames, forces and the tool proxy's health.
//!
//! `cargo build --release -p coiffure-server --examples && target/release/examples/soak [SECONDS] [RENDER_STRANDS]`
//! (defaults 60 s and 100,000). It starts `target/release/coiffure serve` (beside this example) and runs:
//! - the controller: comb strokes with jitter through the back hair at 120 Hz, every tool in turn (10 s each,
//!   the primary button held half of the time: cuts, blowing, spraying, clipping), a SET_HAIR every 15 s, a
//!   RESET every 60 s, a NaN pose and a 2 m teleport every 5 s, one burst of 1,000 RESETs at a third of the run;
//! - two watchers that read everything, one slow viewer (a message every 100 ms), and a viewer that connects,
//!   reads a little and leaves, every 3 s.
//! It prints one JSON object: server resident memory (after 10 % of the run, at the end, peak), frames received
//! by the controller and late ones (more than 100 ms after the previous), the same for the two watchers (with the
//! frame numbers they never got: dropped for them, latest wins), the largest force and non-finite
//! ones, non-finite proxies, the runaway count, and the server's own summary line (haptic loop timing).

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tungstenite::Message;

type Ws = tungstenite::WebSocket<TcpStream>;

fn connect(http: &str) -> Ws {
    let stream = TcpStream::connect(http).expect("connect");
    // A 100,000-strand SCENE is 17 MB: the server's limits (64 MiB + 16) rather than tungstenite's 16 MiB frames.
    let config = tungstenite::protocol::WebSocketConfig::default().max_message_size(Some(80 << 20)).max_frame_size(Some(80 << 20));
    let (ws, _) = tungstenite::client::client_with_config(format!("ws://{http}/ws"), stream, Some(config)).expect("upgrade");
    ws
}

fn pose(p: Vector3<f64>, q: &UnitQuaternion<f64>, buttons: u32) -> Vec<u8> {
    let mut b = vec![0x01, 1];
    for x in [p.x, p.y, p.z, q.i, q.j, q.k, q.w] {
        b.extend_from_slice(&(x as f32).to_le_bytes());
    }
    b.extend_from_slice(&buttons.to_le_bytes());
    b
}

/// What a FRAME says about the tool: (haptic time s, proxy, device point, force N, runaways).
fn frame_tool(f: &[u8]) -> (f64, Vector3<f64>, Vector3<f64>, Vector3<f64>, u32) {
    let f32_at = |i: usize| f32::from_le_bytes(f[i..i + 4].try_into().unwrap()) as f64;
    let v = |i: usize| Vector3::new(f32_at(i), f32_at(i + 4), f32_at(i + 8));
    // docs/protocol.md: 2 header, u32 seq, f32 time, u8 tool, u8 flags, u16 contacts, proxy, quaternion, device, force.
    let runaways = u32::from_le_bytes(f[f.len() - 4..].try_into().unwrap());
    (f32_at(6), v(14), v(42), v(54), runaways)
}

fn rss(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| s.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok()))
        .map_or(0, |kb| kb * 1024)
}

#[derive(Default, Debug)]
struct Seen {
    frames: u64,
    late: u64,
    largest_gap: f64,
    max_force: f64,
    nonfinite_force: u64,
    nonfinite_proxy: u64,
    max_lag: f64,
    runaways: u32,
    errors: u64,
    /// The controller's connection failed (when and why): the soak goes on without it.
    controller_lost: Option<String>,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args.get(1).map_or(60.0, |s| s.parse().expect("SECONDS"));
    let strands: usize = args.get(2).map_or(100_000, |s| s.parse().expect("RENDER_STRANDS"));
    assert!(seconds >= 10.0, "run at least 10 s");
    let exe = std::env::current_exe().unwrap();
    let bin = exe.parent().and_then(|d| d.parent()).map(|d| d.join("coiffure")).filter(|p| p.is_file()).expect("target/release/coiffure next to the example: cargo build --release -p coiffure-server");
    let web = std::env::temp_dir().join(format!("coiffure-soak-{}", std::process::id()));
    std::fs::create_dir_all(&web).unwrap();
    std::fs::write(web.join("index.html"), "<!doctype html><title>soak</title>").unwrap();
    let mut child = Command::new(&bin)
        .args(["serve", "--port", "0", "--render-strands", &strands.to_string(), "--duration", &format!("{}", seconds + 5.0), "--web"])
        .arg(&web)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the server");
    let pid = child.id();
    // The server's warnings (e.g. a viewer disconnected, and why) are kept and printed in the report.
    let warnings = Arc::new(Mutex::new(Vec::<String>::new()));
    let err_reader = {
        let (err, warnings) = (BufReader::new(child.stderr.take().unwrap()), warnings.clone());
        std::thread::spawn(move || {
            for l in err.lines().map_while(Result::ok) {
                if l.contains("WARN") || l.contains("ERROR") {
                    warnings.lock().unwrap().push(l);
                }
            }
        })
    };
    let out = BufReader::new(child.stdout.take().unwrap());
    let lines = Arc::new(Mutex::new(Vec::<String>::new()));
    let (url_tx, url_rx) = std::sync::mpsc::channel();
    let l2 = lines.clone();
    let reader = std::thread::spawn(move || {
        for l in out.lines().map_while(Result::ok) {
            if let Some(rest) = l.split("listening on http://").nth(1) {
                let _ = url_tx.send(rest.split('/').next().unwrap().to_string());
            }
            l2.lock().unwrap().push(l);
        }
    });
    let http = url_rx.recv_timeout(Duration::from_secs(300)).expect("the server's URL");
    let stop = Arc::new(AtomicBool::new(false));
    let t0 = Instant::now();
    let seen = Arc::new(Mutex::new(Seen::default()));

    // The controller: one socket, a thread that sends and the reading here... tungstenite sockets are not split:
    // send and read in one loop with a short read timeout.
    let controller = {
        let (stop, seen, http) = (stop.clone(), seen.clone(), http.clone());
        std::thread::spawn(move || {
            let mut ws = connect(&http);
            ws.get_mut().set_read_timeout(Some(Duration::from_millis(2))).unwrap();
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[Vector3::x(), Vector3::z(), -Vector3::y()])));
            let mut rng = 0x9e37_79b9_7f4a_7c15u64;
            let mut noise = move || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            let (mut next_pose, mut last_frame, mut burst_done) = (Instant::now(), None::<Instant>, false);
            let (mut last_tool, mut last_hair, mut last_reset, mut last_fault) = (u64::MAX, 0u64, 0u64, 0u64);
            while !stop.load(Ordering::Relaxed) {
                let t = t0.elapsed().as_secs_f64();
                if Instant::now() >= next_pose {
                    next_pose += Duration::from_micros(8333);
                    let tool = ((t / 10.0) as u64) % 6;
                    if tool != last_tool {
                        last_tool = tool;
                        let _ = ws.send(Message::Binary(vec![0x03, 1, tool as u8].into()));
                    }
                    // Strokes down the back of the head (z from 0.08 to -0.06 m in 1.5 s), jittered by 2 mm.
                    let phase = (t / 1.5).fract();
                    let x = 0.04 * (t / 7.0).sin();
                    let p = Vector3::new(x + 0.002 * noise(), -0.115 + 0.002 * noise(), 0.08 - 0.14 * phase + 0.002 * noise());
                    let pressed = (t / 5.0) as u64 % 2 == 1;
                    let _ = ws.send(Message::Binary(pose(p, &q, pressed as u32).into()));
                    let s = t as u64;
                    if s / 15 != last_hair {
                        last_hair = s / 15;
                        let mut m = vec![0x04, 1, (last_hair % 4) as u8];
                        m.extend_from_slice(&(0.5f32 * (last_hair % 3) as f32).to_le_bytes());
                        m.extend_from_slice(&0.5f32.to_le_bytes());
                        let _ = ws.send(Message::Binary(m.into()));
                    }
                    if s / 60 != last_reset {
                        last_reset = s / 60;
                        let _ = ws.send(Message::Binary(vec![0x05, 1].into()));
                    }
                    if s / 5 != last_fault {
                        last_fault = s / 5;
                        let _ = ws.send(Message::Binary(pose(Vector3::new(f64::NAN, 0.0, 0.0), &q, 0).into()));
                        let _ = ws.send(Message::Binary(pose(Vector3::new(0.0, -2.0, 0.0), &q, 0).into()));
                    }
                    if !burst_done && t > seconds / 3.0 {
                        burst_done = true;
                        for _ in 0..1000 {
                            let _ = ws.send(Message::Binary(vec![0x05, 1].into()));
                        }
                    }
                }
                match ws.read() {
                    Ok(Message::Binary(b)) if b[0] == 0x82 => {
                        let now = Instant::now();
                        let (_, proxy, device, force, runaways) = frame_tool(&b);
                        let mut s = seen.lock().unwrap();
                        s.frames += 1;
                        if let Some(prev) = last_frame {
                            let gap = (now - prev).as_secs_f64();
                            s.largest_gap = s.largest_gap.max(gap);
                            if gap > 0.1 {
                                s.late += 1;
                            }
                        }
                        last_frame = Some(now);
                        if force.iter().all(|x| x.is_finite()) {
                            s.max_force = s.max_force.max(force.norm());
                        } else {
                            s.nonfinite_force += 1;
                        }
                        if proxy.iter().all(|x| x.is_finite()) {
                            s.max_lag = s.max_lag.max((proxy - device).norm());
                        } else {
                            s.nonfinite_proxy += 1;
                        }
                        s.runaways = runaways;
                    }
                    Ok(Message::Binary(b)) if b[0] == 0x83 => seen.lock().unwrap().errors += 1,
                    Ok(_) => {}
                    Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                    Err(e) => {
                        seen.lock().unwrap().controller_lost = Some(format!("at {:.1} s: {e}", t0.elapsed().as_secs_f64()));
                        break;
                    }
                }
            }
        })
    };
    // Watchers, a slow viewer and churn.
    let mut others = Vec::new();
    // A watcher's view of the frames: (received, gaps over 100 ms, largest gap s, sequence numbers skipped).
    let watched = Arc::new(Mutex::new(Vec::<(u64, u64, f64, u64)>::new()));
    for delay in [None, None, Some(Duration::from_millis(100))] {
        let (stop, http, watched) = (stop.clone(), http.clone(), watched.clone());
        others.push(std::thread::spawn(move || {
            // The watchers measure the server, not this process's own scheduling: real-time when allowed.
            let _ = haptics::realtime::request_realtime(4);
            let mut ws = connect(&http);
            let (mut n, mut late, mut largest, mut skipped, mut last) = (0u64, 0u64, 0f64, 0u64, None::<(Instant, u32)>);
            let mut kept = true;
            while !stop.load(Ordering::Relaxed) {
                match ws.read() {
                    Ok(Message::Binary(b)) if b[0] == 0x82 && delay.is_none() => {
                        let (now, seq) = (Instant::now(), u32::from_le_bytes(b[2..6].try_into().unwrap()));
                        if let Some((t, q)) = last {
                            let gap = (now - t).as_secs_f64();
                            largest = largest.max(gap);
                            late += (gap > 0.1) as u64;
                            // a new session (LOAD) restarts the count; otherwise missing numbers were dropped (latest wins)
                            skipped += seq.saturating_sub(q + 1) as u64;
                        }
                        n += 1;
                        last = Some((now, seq));
                    }
                    Ok(_) => {}
                    Err(_) => {
                        kept = false;
                        break;
                    }
                }
                if let Some(d) = delay {
                    std::thread::sleep(d);
                }
            }
            if delay.is_none() {
                watched.lock().unwrap().push((n, late, largest, skipped));
            }
            kept
        }));
    }
    let churned = Arc::new(AtomicU64::new(0));
    let churn = {
        let (stop, http, churned) = (stop.clone(), http.clone(), churned.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let mut ws = connect(&http);
                for _ in 0..5 {
                    let _ = ws.read();
                }
                let _ = ws.close(None);
                churned.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_secs(3));
            }
        })
    };
    // Memory: every second.
    let (mut early, mut peak) = (0u64, 0u64);
    while t0.elapsed().as_secs_f64() < seconds {
        std::thread::sleep(Duration::from_secs(1));
        let r = rss(pid);
        peak = peak.max(r);
        if early == 0 && t0.elapsed().as_secs_f64() >= 0.1 * seconds {
            early = r;
        }
    }
    let end = rss(pid);
    stop.store(true, Ordering::Relaxed);
    controller.join().expect("controller");
    let slow_kept = others.into_iter().map(|h| h.join().unwrap_or(false)).collect::<Vec<_>>();
    churn.join().unwrap();
    let _ = child.wait();
    reader.join().unwrap();
    err_reader.join().unwrap();
    let summary = lines.lock().unwrap().iter().find(|l| l.contains("haptic loop:")).cloned().unwrap_or_default();
    let s = seen.lock().unwrap();
    let json = serde_json::json!({
        "seconds": seconds,
        "render_strands": strands,
        "rss_mb": { "at_10_percent": early as f64 / 1048576.0, "end": end as f64 / 1048576.0, "peak": peak as f64 / 1048576.0, "end_over_early": end as f64 / early.max(1) as f64 },
        "frames": { "received": s.frames, "per_s": s.frames as f64 / seconds, "late_over_100ms": s.late, "largest_gap_s": s.largest_gap },
        "watcher_frames": watched.lock().unwrap().iter().map(|(n, late, largest, skipped)| serde_json::json!({ "received": n, "per_s": *n as f64 / seconds, "gaps_over_100ms": late, "largest_gap_s": largest, "skipped": skipped })).collect::<Vec<_>>(),
        "forces": { "max_n": s.max_force, "non_finite": s.nonfinite_force },
        "proxy": { "non_finite": s.nonfinite_proxy, "runaways": s.runaways, "max_lag_m": s.max_lag },
        "errors_received": s.errors,
        "controller_lost": s.controller_lost,
        "server_warnings": warnings.lock().unwrap().iter().rev().take(20).rev().cloned().collect::<Vec<_>>(),
        "viewers_still_connected_watcher_watcher_slow": slow_kept,
        "churn_connections": churned.load(Ordering::Relaxed),
        "server_summary": summary,
    });
    println!("{}", serde_json::to_string_pretty(&json).unwrap());
    let _ = std::fs::remove_dir_all(&web);
}
