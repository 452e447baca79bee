//! A long recorded session (issue 32; bench/RESULTS.md): `coiffure serve --device --record` driven by
//! `coiffure device-sim` combing the back hair back and forth (bench/device-comb.toml, `--repeat`) for SECONDS;
//! then the record is read, its size checked against what its steps encode to, replayed headless, and compared
//! bit for bit with the recorded forces and with the forces the device received.
//!
//! `cargo build --release -p coiffure-server --examples && target/release/examples/record_soak [SECONDS] [RENDER_STRANDS]`
//! (defaults 60 s and 100,000; the server at normal priority, `--haptic-priority 0`). It prints two JSON objects:
//! first, as soon as the session ends, `session`: the server's resident memory at minute 1 (or at a tenth of a
//! shorter run), at the end and its peak, sampled every 5 s; the record's size (and the size its steps encode
//! to), steps, bytes per step and per hour; and the server's summary lines; then, after the replay (about half
//! the session's length on an idle machine), the replay's step counts, differences and wall time.

use engine::record::{Ending, Record};
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn rss(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| s.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok()))
        .map_or(0, |kb| kb * 1024)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args.get(1).map_or(60.0, |s| s.parse().expect("SECONDS"));
    let strands: usize = args.get(2).map_or(100_000, |s| s.parse().expect("RENDER_STRANDS"));
    assert!(seconds >= 20.0, "run at least 20 s");
    let exe = std::env::current_exe().unwrap();
    let bin = exe.parent().and_then(|d| d.parent()).map(|d| d.join("coiffure")).filter(|p| p.is_file()).expect("target/release/coiffure next to the example: cargo build --release -p coiffure-server");
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::temp_dir().join(format!("coiffure-record-soak-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("index.html"), "<!doctype html><title>record soak</title>").unwrap();
    let (rec_path, csv) = (dir.join("session.rec"), dir.join("felt.csv"));
    let mut server = Command::new(&bin)
        .args(["serve", "--port", "0", "--haptic-priority", "0", "--device", "udp:127.0.0.1:0", "--render-strands", &strands.to_string(), "--duration", &format!("{}", seconds + 8.0), "--web"])
        .arg(&dir)
        .arg("--record")
        .arg(&rec_path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start the server");
    let pid = server.id();
    let lines = Arc::new(Mutex::new(Vec::<String>::new()));
    let (udp_tx, udp_rx) = std::sync::mpsc::channel();
    let reader = {
        let (out, lines) = (BufReader::new(server.stdout.take().unwrap()), lines.clone());
        std::thread::spawn(move || {
            for l in out.lines().map_while(Result::ok) {
                if let Some(rest) = l.split("device on udp:").nth(1) {
                    let _ = udp_tx.send(rest.split_whitespace().next().unwrap().to_string());
                }
                lines.lock().unwrap().push(l);
            }
        })
    };
    let udp = udp_rx.recv_timeout(Duration::from_secs(300)).expect("the server's device address");
    let mut sim = Command::new(&bin)
        .args(["device-sim", "--server", &format!("udp:{udp}"), "--rate", "1000", "--repeat", "--duration", &seconds.to_string(), "--out"])
        .arg(&csv)
        .arg("--path")
        .arg(repo.join("bench/device-comb.toml"))
        .stdout(Stdio::piped())
        .spawn()
        .expect("start device-sim");
    // Resident memory every 5 s while the device streams.
    let t0 = Instant::now();
    let first = seconds.min(600.0) / 10.0;
    let first = if seconds >= 600.0 { 60.0 } else { first };
    let (mut at_first, mut peak, mut last, mut samples) = (0u64, 0u64, 0u64, vec![]);
    while sim.try_wait().unwrap().is_none() {
        let t = t0.elapsed().as_secs_f64();
        let m = rss(pid);
        if m > 0 && t <= seconds {
            if at_first == 0 && t >= first {
                at_first = m;
            }
            peak = peak.max(m);
            last = m;
            samples.push((t.round() as u64, m >> 20));
        }
        std::thread::sleep(Duration::from_secs(5));
    }
    let sim_out = String::from_utf8_lossy(&sim.wait_with_output().unwrap().stdout).trim().to_string();
    let status = server.wait().unwrap();
    reader.join().unwrap();
    let lines = lines.lock().unwrap().clone();
    assert!(status.success(), "the server failed: {lines:?}");
    // The record: whole, and as large as its steps encode to.
    let bytes = std::fs::read(&rec_path).unwrap();
    let read = Record::read(&bytes).unwrap();
    assert_eq!(read.ending, Ending::Complete, "a record written to its end");
    let rec = read.record;
    let mut chunks = 0usize;
    let mut at = 8;
    while at < bytes.len() {
        at += 8 + u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        chunks += 1;
    }
    // `to_bytes` writes the same steps in chunks of 1,000 haptic steps; each chunk costs 8 + 1 + 2 x 12 bytes.
    let whole = rec.to_bytes();
    let mut whole_chunks = 0usize;
    let mut at = 8;
    while at < whole.len() {
        at += 8 + u32::from_le_bytes(whole[at..at + 4].try_into().unwrap()) as usize;
        whole_chunks += 1;
    }
    let expected = whole.len() as i64 + 33 * (chunks as i64 - whole_chunks as i64);
    // The session's figures now (memory, record), before the replay: replaying in lockstep on one thread takes
    // about half the session's length on an idle machine.
    let pick = |k: &str| lines.iter().find(|l| l.contains(k)).cloned().unwrap_or_default();
    let session = serde_json::json!({
        "seconds": seconds,
        "render_strands": strands,
        "rss_mib": { "at_s": first, "first": at_first >> 20, "end": last >> 20, "peak": peak >> 20, "end_over_first": last as f64 / at_first.max(1) as f64 },
        "rss_samples_mib": samples.iter().step_by(12).collect::<Vec<_>>(),
        "record": {
            "bytes": bytes.len(), "expected_bytes": expected, "chunks": chunks,
            "haptic_steps": rec.steps.len(), "global_steps": rec.global_inputs.len(), "seconds": rec.seconds(),
            "bytes_per_step": bytes.len() as f64 / rec.steps.len().max(1) as f64,
            "mb_per_hour": bytes.len() as f64 / rec.seconds() * 3600.0 / 1e6,
        },
        "server": { "summary": pick("haptic loop:"), "record": pick("record:"), "budget": pick("strand budget:") },
    });
    println!("{}", serde_json::to_string_pretty(&serde_json::json!({ "session": session })).unwrap());
    // Replay, compared with the recorded forces and with what the device received.
    let settings = rec.settings.clone().expect("serve writes its settings");
    let scene = Arc::new(engine::session::Scene::builtin(&settings.scene_options()).unwrap());
    let params = settings.session_params(rec.rate_hz).unwrap();
    let r0 = Instant::now();
    // The force of every device step (several per haptic step at a device rate above the haptic rate).
    let forces = engine::replay::replay_device_steps(scene, params, &rec).unwrap();
    let replay_s = r0.elapsed().as_secs_f64();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let differ = (0..rec.steps.len()).filter(|&i| forces[i].last().map(|f| bits(f.as_slice())) != Some(bits(rec.steps[i].force.as_slice()))).count();
    let text = std::fs::read_to_string(&csv).unwrap();
    let felt: Vec<(f64, [f64; 3])> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect::<Vec<_>>())
        .filter(|r| r[4].is_finite() && r[8] == 0.0)
        .map(|r| (r[0], [r[4], r[5], r[6]]))
        .collect();
    let times: Vec<f64> = felt.iter().map(|r| r.0).collect();
    let (mut answered, mut equal, mut peak_force) = (0usize, 0usize, 0.0f64);
    for (step, (_, f)) in rec.steps_reading(&times).into_iter().zip(&felt) {
        if let Some((i, j)) = step {
            answered += 1;
            peak_force = peak_force.max(nalgebra::Vector3::from(*f).norm());
            equal += (bits(forces[i][j].as_slice()) == bits(f)) as usize;
        }
    }
    let report = serde_json::json!({
        "replay": { "steps": forces.len(), "forces_differing_from_record": differ, "wall_s": replay_s },
        "device": { "poses_answered_in_record": answered, "equal_bit_for_bit": equal, "peak_force_n": peak_force, "device_sim": sim_out },
    });
    println!("{}", serde_json::to_string_pretty(&report).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}
