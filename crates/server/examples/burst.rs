//! The haptic loop's step times around a burst of RESETs (issue 16: "1,000 RESETs in a burst leave the haptic
//! loop's p99.9 step under 1 ms"; bench/RESULTS.md).
//!
//! `cargo build --release -p coiffure-server --examples && target/release/examples/burst [RESETS] [RENDER_STRANDS]`
//! (defaults 1000 and 100,000). Starts `target/release/coiffure serve` (beside this example; real-time haptic
//! loop, its defaults) for 6 s of haptic steps after the scene is built; a viewer takes control and holds the comb
//! in the back hair (POSEs at 60 Hz), and 3 s in sends RESETS RESET messages at once. The server's summary covers
//! the 6 s (6,000 steps: p99.9 is the 6th slowest), and the burst is applied at most 2 per step over about 500 of
//! them, so any cost of the burst's steps shows in p99 and p99.9: compare with `burst 0`, run in the same minutes.
//! Prints the server's haptic loop line.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::Message;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let resets: usize = args.get(1).map_or(1000, |s| s.parse().expect("RESETS"));
    let strands: usize = args.get(2).map_or(100_000, |s| s.parse().expect("RENDER_STRANDS"));
    let exe = std::env::current_exe().unwrap();
    let bin = exe.parent().and_then(|d| d.parent()).map(|d| d.join("coiffure")).filter(|p| p.is_file()).expect("target/release/coiffure next to the example");
    let web = std::env::temp_dir().join(format!("coiffure-burst-{}", std::process::id()));
    std::fs::create_dir_all(&web).unwrap();
    std::fs::write(web.join("index.html"), "<!doctype html><title>burst</title>").unwrap();
    // --duration counts from when the server listens (the scene is built before): about 6 s of haptic steps.
    let mut child = Command::new(&bin)
        .args(["serve", "--port", "0", "--render-strands", &strands.to_string(), "--duration", "6", "--web"])
        .arg(&web)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start the server");
    let mut out = BufReader::new(child.stdout.take().unwrap()).lines().map_while(Result::ok);
    let http = out.by_ref().find_map(|l| l.split("listening on http://").nth(1).map(|r| r.split('/').next().unwrap().to_string())).expect("the server's URL");
    let stream = TcpStream::connect(&http).unwrap();
    let config = tungstenite::protocol::WebSocketConfig::default().max_message_size(Some(80 << 20)).max_frame_size(Some(80 << 20));
    let (mut ws, _) = tungstenite::client::client_with_config(format!("ws://{http}/ws"), stream, Some(config)).expect("upgrade");
    ws.send(Message::Binary(vec![0x02, 1].into())).unwrap();
    ws.get_mut().set_read_timeout(Some(Duration::from_millis(2))).unwrap();
    let t0 = Instant::now();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let mut sent = false;
    let mut next = Instant::now();
    loop {
        if Instant::now() >= next {
            next += Duration::from_micros(16_667);
            // The comb held in the back hair (the soak's stroke, at its middle), turned 90 degrees about x.
            let mut m = vec![0x01, 1];
            for x in [0.0f32, -0.115, 0.01, h, 0.0, 0.0, h] {
                m.extend_from_slice(&x.to_le_bytes());
            }
            m.extend_from_slice(&0u32.to_le_bytes());
            if ws.send(Message::Binary(m.into())).is_err() {
                break;
            }
        }
        if !sent && t0.elapsed() > Duration::from_secs(3) {
            sent = true;
            for _ in 0..resets {
                let _ = ws.send(Message::Binary(vec![0x05, 1].into()));
            }
        }
        match ws.read() {
            Ok(_) => {}
            Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(_) => break,
        }
    }
    let line = out.find(|l| l.contains("haptic loop:")).unwrap_or_default();
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&web);
    let from = line.find("haptic loop:").unwrap_or(0);
    let to = line[from..].find("; global").map_or(line.len(), |i| from + i);
    println!("{resets} RESETs at 3 s (sent: {sent}): {}", &line[from..to]);
}
