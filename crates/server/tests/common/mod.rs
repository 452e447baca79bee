//! A real `coiffure serve` for the end-to-end tests (tests/access.rs, tests/device.rs, tests/robust.rs): started on a free port
//! with a stub viewer folder, its printed addresses read from its output, killed when dropped.

// Each test binary uses a part of this module.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use tungstenite::client::IntoClientRequest;

/// The `coiffure` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_coiffure"))
}

/// A scratch folder for this test process.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coiffure-e2e-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A running `coiffure serve` (killed when dropped) and what it printed.
pub struct Server {
    child: Child,
    /// host:port of the HTTP and WebSocket server.
    pub http: String,
    /// The printed access token, if any.
    pub token: Option<String>,
    /// host:port of the device socket (`--device`), if any.
    pub udp: Option<String>,
    /// The server's later output lines (keeps the stdout reader going: the server must not see a closed pipe).
    lines: mpsc::Receiver<String>,
}

impl Server {
    /// The server's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Its resident memory now, bytes (VmRSS of /proc/PID/status).
    pub fn rss(&self) -> u64 {
        let s = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).unwrap();
        let kb: u64 = s.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next()?.parse().ok()).unwrap();
        kb * 1024
    }

    /// Kills the server at once (SIGKILL: no clean exit) and waits for it.
    pub fn kill(&mut self) {
        self.child.kill().unwrap();
        self.child.wait().unwrap();
    }

    /// The first later output line containing `text`, within `timeout`.
    pub fn line_with(&self, text: &str, timeout: Duration) -> Option<String> {
        let deadline = Instant::now() + timeout;
        while let Ok(l) = self.lines.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            if l.contains(text) {
                return Some(l);
            }
        }
        None
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `coiffure serve --port 0 --haptic-priority 0 --web STUB` with `args` (and `--duration 60` unless they
/// say); returns once it printed its URL (and, with `--device`, its device address).
pub fn serve(args: &[&str]) -> Server {
    serve_with(args, |_| {})
}

/// [`serve`], with the command set up further by `configure` before it starts (e.g. resource limits).
pub fn serve_with(args: &[&str], configure: impl FnOnce(&mut Command)) -> Server {
    let web = scratch("web");
    std::fs::write(web.join("index.html"), "<!doctype html><title>stub</title>").unwrap();
    let mut cmd = bin();
    cmd.args(["serve", "--port", "0", "--haptic-priority", "0", "--web"])
        .arg(&web)
        .args(if args.contains(&"--duration") { &[][..] } else { &["--duration", "60"][..] })
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::null());
    configure(&mut cmd);
    let mut child = cmd.spawn().unwrap();
    let out = child.stdout.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(out).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    let device = args.contains(&"--device");
    let (mut http, mut token, mut udp) = (None, None, None);
    let deadline = Instant::now() + Duration::from_secs(120);
    while http.is_none() || (device && udp.is_none()) {
        let l = rx.recv_timeout(deadline.saturating_duration_since(Instant::now())).expect("serve printed its addresses");
        if let Some(rest) = l.split("device on udp:").nth(1) {
            udp = rest.split_whitespace().next().map(str::to_string);
        }
        if let Some(rest) = l.split("listening on http://").nth(1) {
            let url = rest.split_whitespace().next().unwrap();
            http = url.split('/').next().map(str::to_string);
            token = url.split("?token=").nth(1).map(str::to_string);
        }
    }
    Server { child, http: http.unwrap(), token, udp, lines: rx }
}

/// Opens `/ws` on `http` (host:port) with an optional Origin and query; the HTTP status of a refusal.
pub fn open(http: &str, origin: Option<&str>, query: &str) -> Result<tungstenite::WebSocket<TcpStream>, u16> {
    let mut req = format!("ws://{http}/ws{query}").into_client_request().unwrap();
    if let Some(o) = origin {
        req.headers_mut().insert("Origin", o.parse().unwrap());
    }
    let stream = TcpStream::connect(http).unwrap();
    match tungstenite::client(req, stream) {
        Ok((ws, _)) => Ok(ws),
        Err(tungstenite::HandshakeError::Failure(tungstenite::Error::Http(r))) => Err(r.status().as_u16()),
        Err(e) => panic!("handshake: {e}"),
    }
}

/// The first binary message of type `kind`, within 20 s.
pub fn first_of(ws: &mut tungstenite::WebSocket<TcpStream>, kind: u8) -> Vec<u8> {
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline {
        if let tungstenite::Message::Binary(b) = ws.read().unwrap() {
            if b[0] == kind {
                return b.to_vec();
            }
        }
    }
    panic!("no message 0x{kind:02x}");
}
