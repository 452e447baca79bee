//! Soak test of `coiffure serve` (issue 16; bench/RESULTS.md): a real server on loopback driven for a bounded
//! time by WebSocket clients the way a long session and a careless or hostile client would, reporting memory,
//! frames, forces and the tool proxy's health.
//!
//! `cargo build --release -p coiffure-server --examples && target/release/examples/soak [SECONDS] [RENDER_STRANDS]`
//! (defaults 60 s and 100,000). It starts `target/release/coiffure serve` (beside this example; more of its
//! options in the environment variable `SOAK_SERVE_ARGS`, e.g. `--no-strand-budget`) and runs:
//! - the controller: comb strokes with jitter through the back hair at 120 Hz, every tool in turn (10 s each,
//!   the primary button held half of the time: cuts, blowing, spraying, clipping), a SET_HAIR every 15 s, a
//!   RESET every 60 s, a NaN pose and a 2 m teleport every 5 s, one burst of 1,000 RESETs at a third of the run;
//! - two watchers that read everything, one slow viewer (a message every 100 ms), and a viewer that connects,
//!   reads a little and leaves, every 3 s.
//! It prints one JSON object: server resident memory (after 10 % of the run, at the end, peak); for the
//! controller and each watcher, FRAMEs received, skipped (latest wins), gaps over 100 ms split into the viewer's
//! own stalls and the server's (`Watch`), lateness behind the schedule, and whether it was on time
//! (docs/protocol.md, "Frames on time"); `frames_on_time` (every watcher on time and the server's frame thread
//! never more than 100 ms behind its schedule); the largest force and non-finite ones, non-finite proxies, the runaway count, and the
//! server's own summary lines (haptic loop timing, the writers' pickup delays; the strand budget); and the CPU time other processes'
//! real-time threads used meanwhile (a run beside another real-time haptic loop measures the machine).

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
    // The runaway count, before the hair's surface (u8 treatment, f32 tool friction) that ends the FRAME.
    let runaways = u32::from_le_bytes(f[f.len() - 9..f.len() - 5].try_into().unwrap());
    (f32_at(6), v(14), v(42), v(54), runaways)
}

fn rss(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| s.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok()))
        .map_or(0, |kb| kb * 1024)
}

/// The frame rate the soak asks of the server (`--fps`), and so the FRAMEs' schedule: FRAME n is due n / FPS s
/// after the server's first.
const FPS: f64 = 60.0;
/// A gap between FRAMEs over this is not on time (docs/protocol.md, "Frames on time").
const ON_TIME: f64 = 0.1;
/// How long a watcher's read waits before it returns to say the watcher is running (its own scheduling probe).
const POLL: Duration = Duration::from_millis(5);

/// One reading viewer's account of the FRAMEs (the controller and the watchers): when each arrived, and the
/// viewer's own stalls (its thread not running), so that a gap caused by the client is told apart from one
/// caused by the server. On time (docs/protocol.md): at a viewer that reads, no gap over [`ON_TIME`] between
/// FRAMEs other than the viewer's own stall; skipped frames (latest wins) are counted.
#[derive(Default)]
struct Watch {
    /// (received, s after the soak's start; sequence number) of every FRAME.
    frames: Vec<(f64, u32)>,
    /// When the loop last came back from a read (or the previous frame), and the largest own stall since the last FRAME, s.
    last_return: Option<Instant>,
    stall_since_frame: f64,
    largest_stall: f64,
    stalls_over_50ms: u64,
    /// Gaps over [`ON_TIME`]: (at s, gap s, frames skipped in it, own stall in it s).
    gaps: Vec<(f64, f64, u32, f64)>,
}

impl Watch {
    /// Notes that the loop is back from a read at `now`, after asking to wait at most `poll`: the time beyond is
    /// the viewer's own stall (its thread not scheduled, or busy with its own work).
    fn back(&mut self, now: Instant, poll: Duration) {
        if let Some(prev) = self.last_return {
            let stall = (now - prev).saturating_sub(poll).as_secs_f64();
            self.stall_since_frame = self.stall_since_frame.max(stall);
            self.largest_stall = self.largest_stall.max(stall);
            self.stalls_over_50ms += (stall > 0.05) as u64;
        }
        self.last_return = Some(now);
    }

    /// A FRAME with sequence `seq` arrived at `now`.
    fn frame(&mut self, t0: Instant, now: Instant, seq: u32) {
        let at = (now - t0).as_secs_f64();
        if let Some(&(prev, q)) = self.frames.last() {
            let gap = at - prev;
            if gap > ON_TIME {
                self.gaps.push((at, gap, seq.saturating_sub(q + 1), self.stall_since_frame));
            }
        }
        self.stall_since_frame = 0.0;
        self.frames.push((at, seq));
    }

    /// The report: counts, gaps split into the viewer's own and the server's, and each FRAME's latency behind its
    /// schedule (less the smallest one: loopback's transit). A gap is the server's if, less the viewer's own stall,
    /// it is over [`ON_TIME`], or if it skipped FRAMEs worth over [`ON_TIME`]: while only the viewer stalls, the
    /// server's FRAMEs wait in its socket (seconds of them fit) and none is skipped; skips mean the server's
    /// writer or frame thread was held too.
    fn report(&self, seconds: f64) -> serde_json::Value {
        let skipped: u64 = self.frames.windows(2).map(|w| w[1].1.saturating_sub(w[0].1 + 1) as u64).sum();
        let server_gaps: Vec<_> = self.gaps.iter().filter(|g| g.1 - g.3 > ON_TIME || (g.2 + 1) as f64 / FPS > ON_TIME).collect();
        let lat: Vec<f64> = self.frames.iter().map(|&(t, q)| t - q as f64 / FPS).collect();
        let floor = lat.iter().copied().fold(f64::INFINITY, f64::min);
        let mut lat: Vec<f64> = lat.iter().map(|l| 1e3 * (l - floor)).collect();
        lat.sort_by(f64::total_cmp);
        let pct = |p: f64| lat.get(((lat.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(0.0);
        let late: Vec<f64> = self.frames.iter().filter(|&&(t, q)| t - q as f64 / FPS - floor > 0.02).map(|f| f.0).collect();
        let largest_gap = self.frames.windows(2).map(|w| w[1].0 - w[0].0).fold(0.0, f64::max);
        serde_json::json!({
            "received": self.frames.len(),
            "per_s": self.frames.len() as f64 / seconds,
            "skipped": skipped,
            "largest_gap_ms": 1e3 * largest_gap,
            "gaps_over_100ms": self.gaps.len(),
            "gaps_over_100ms_server_side": server_gaps.len(),
            "on_time": server_gaps.is_empty(),
            "own_largest_stall_ms": 1e3 * self.largest_stall,
            "own_stalls_over_50ms": self.stalls_over_50ms,
            "latency_ms_p50_p99_p999_max": [pct(0.5), pct(0.99), pct(0.999), pct(1.0)],
            "latency_over_20ms": { "frames": late.len(), "first_s": late.first(), "last_s": late.last() },
            "gaps": self.gaps.iter().take(12).map(|g| serde_json::json!({ "at_s": g.0, "gap_ms": 1e3 * g.1, "skipped": g.2, "own_stall_ms": 1e3 * g.3 })).collect::<Vec<_>>(),
        })
    }
}

/// CPU time used during the soak by real-time (SCHED_FIFO or SCHED_RR) threads of other processes (kernel
/// threads aside), from /proc: such threads preempt the server's real-time frame path, so a run where they used
/// much CPU (another haptic loop, say) measured the machine rather than the server.
#[derive(Default)]
struct ForeignRealtime {
    /// CPU ticks of each real-time thread seen at the previous sample, by (pid, tid).
    threads: std::collections::HashMap<(u32, u32), u64>,
    cpu_s: f64,
}

impl ForeignRealtime {
    fn sample(&mut self, exclude: &[u32]) {
        let ticks = 100.0; // USER_HZ
        let Ok(procs) = std::fs::read_dir("/proc") else { return };
        for p in procs.flatten() {
            let Some(pid) = p.file_name().to_str().and_then(|n| n.parse::<u32>().ok()) else { continue };
            if exclude.contains(&pid) {
                continue;
            }
            let Ok(tasks) = std::fs::read_dir(p.path().join("task")) else { continue };
            for t in tasks.flatten() {
                let Some(tid) = t.file_name().to_str().and_then(|n| n.parse::<u32>().ok()) else { continue };
                let Ok(stat) = std::fs::read_to_string(t.path().join("stat")) else { continue };
                // Fields after the command's closing parenthesis: state is field 3; ppid 4; utime 14, stime 15; policy 41.
                let Some(rest) = stat.rsplit_once(')').map(|r| r.1) else { continue };
                let f: Vec<&str> = rest.split_whitespace().collect();
                let field = |n: usize| f.get(n - 3).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
                let (ppid, policy) = (field(4), field(41));
                if ppid == 2 || pid == 2 || !(policy == 1 || policy == 2) {
                    continue;
                }
                let cpu = field(14) + field(15);
                let prev = self.threads.insert((pid, tid), cpu);
                self.cpu_s += prev.map_or(0, |p| cpu.saturating_sub(p)) as f64 / ticks;
            }
        }
    }
}

#[derive(Default)]
struct Seen {
    /// The controller's account of the FRAMEs.
    watch: Watch,
    /// FRAMEs that told the controller it controls the tool (flags bit 0).
    frames_in_control: u64,
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
        .args(["serve", "--port", "0", "--fps", &FPS.to_string(), "--render-strands", &strands.to_string(), "--duration", &format!("{}", seconds + 5.0), "--web"])
        .arg(&web)
        .args(std::env::var("SOAK_SERVE_ARGS").unwrap_or_default().split_whitespace())
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
            // Control, whichever viewer registered first (the watchers connect at the same time).
            ws.send(Message::Binary(vec![0x02, 1].into())).expect("TAKE_CONTROL");
            ws.get_mut().set_read_timeout(Some(Duration::from_millis(2))).unwrap();
            let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[Vector3::x(), Vector3::z(), -Vector3::y()])));
            let mut rng = 0x9e37_79b9_7f4a_7c15u64;
            let mut noise = move || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            let (mut next_pose, mut burst_done) = (Instant::now(), false);
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
                let read = ws.read();
                let now = Instant::now();
                seen.lock().unwrap().watch.back(now, Duration::from_millis(2));
                match read {
                    Ok(Message::Binary(b)) if b[0] == 0x82 => {
                        let (_, proxy, device, force, runaways) = frame_tool(&b);
                        let mut s = seen.lock().unwrap();
                        s.watch.frame(t0, now, u32::from_le_bytes(b[2..6].try_into().unwrap()));
                        s.frames_in_control += (b[11] & 1) as u64;
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
    // The watchers' accounts of the FRAMEs.
    let watched = Arc::new(Mutex::new(Vec::<Watch>::new()));
    for delay in [None, None, Some(Duration::from_millis(100))] {
        let (stop, http, watched) = (stop.clone(), http.clone(), watched.clone());
        others.push(std::thread::spawn(move || {
            // The watchers measure the server, not this process's own scheduling: real-time when allowed (and
            // their own stalls are measured all the same: `Watch::back`).
            let _ = haptics::realtime::request_realtime(4);
            let mut ws = connect(&http);
            if delay.is_none() {
                ws.get_mut().set_read_timeout(Some(POLL)).unwrap();
            }
            let mut w = Watch::default();
            let mut kept = true;
            while !stop.load(Ordering::Relaxed) {
                let read = ws.read();
                let now = Instant::now();
                if delay.is_none() {
                    w.back(now, POLL);
                }
                match read {
                    Ok(Message::Binary(b)) if b[0] == 0x82 && delay.is_none() => w.frame(t0, now, u32::from_le_bytes(b[2..6].try_into().unwrap())),
                    Ok(_) => {}
                    Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
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
                watched.lock().unwrap().push(w);
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
    // Memory, and other processes' real-time threads (which preempt the server's frame path), every second.
    let (mut early, mut peak) = (0u64, 0u64);
    let mut foreign = ForeignRealtime::default();
    while t0.elapsed().as_secs_f64() < seconds {
        std::thread::sleep(Duration::from_secs(1));
        foreign.sample(&[std::process::id(), pid]);
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
    let (summary, budget) = {
        let lines = lines.lock().unwrap();
        let find = |pat: &str| lines.iter().find(|l| l.contains(pat)).cloned().unwrap_or_default();
        (find("haptic loop:"), find("strand budget:"))
    };
    // The server's own count of FRAMEs more than a period behind their schedule (its summary line).
    // The server's frame thread: FRAMEs more than a period late (information), and the latest one's delay behind
    // its schedule, ms, which must be within the on-time bound.
    let server_late = summary.split(" more than a period late").next().and_then(|h| h.rsplit("; ").next()).and_then(|v| v.trim().parse::<u64>().ok());
    let server_behind_ms = summary.split(" ms behind").next().and_then(|h| h.rsplit("the latest ").next()).and_then(|v| v.trim().parse::<f64>().ok());
    let s = seen.lock().unwrap();
    let json = serde_json::json!({
        "seconds": seconds,
        "render_strands": strands,
        "rss_mb": { "at_10_percent": early as f64 / 1048576.0, "end": end as f64 / 1048576.0, "peak": peak as f64 / 1048576.0, "end_over_early": end as f64 / early.max(1) as f64 },
        "frames_on_time": watched.lock().unwrap().iter().all(|w| w.report(seconds)["on_time"] == true) && server_behind_ms.is_some_and(|b| b <= 1e3 * ON_TIME),
        "server_frames_more_than_a_period_late": server_late,
        "server_latest_frame_behind_ms": server_behind_ms,
        "controller_frames": s.watch.report(seconds),
        "watcher_frames": watched.lock().unwrap().iter().map(|w| w.report(seconds)).collect::<Vec<_>>(),
        "forces": { "max_n": s.max_force, "non_finite": s.nonfinite_force },
        "proxy": { "non_finite": s.nonfinite_proxy, "runaways": s.runaways, "max_lag_m": s.max_lag },
        "other_processes_realtime_cpu_s": foreign.cpu_s,
        "other_processes_realtime_threads": foreign.threads.keys().len(),
        "controller_frames_in_control": s.frames_in_control,
        "errors_received": s.errors,
        "controller_lost": s.controller_lost,
        "server_warnings": warnings.lock().unwrap().iter().rev().take(20).rev().cloned().collect::<Vec<_>>(),
        "viewers_still_connected_watcher_watcher_slow": slow_kept,
        "churn_connections": churned.load(Ordering::Relaxed),
        "server_summary": summary,
        "strand_budget": budget,
    });
    println!("{}", serde_json::to_string_pretty(&json).unwrap());
    let _ = std::fs::remove_dir_all(&web);
}
