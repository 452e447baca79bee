//! `coiffure serve`: the live session behind an HTTP server (the built viewer) and a WebSocket (`/ws`, binary
//! protocol in docs/protocol.md). One frame pump thread reads the session's latest snapshots at the frame
//! rate, encodes one FRAME message and hands it to every viewer; each viewer's task sends it on. Several
//! viewers may watch; the first to connect controls the tool until it leaves or another sends TAKE_CONTROL.

use crate::delivery::{DeliveryStats, Frame, PublishLog};
use crate::outbox::Outbox;
use crate::protocol::{self, ClientMessage, WireError};
use anyhow::{anyhow, Context};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::IntoResponse;
use axum::routing::get;
use axum::Router;
use clap::Args;
use engine::record::{RecordFile, RecordSettings, RecordStatus, RecordTarget};
use engine::session::{Command, HapticSnapshot, InputKind, LatticeSnapshot, Scene, SceneOptions, Session, SessionIo, SessionParams};
use triple_buffer::Output;
use futures_util::{SinkExt, StreamExt};
use haptics::backends::VirtualHandle;
use haptics::device::{DeviceProfile, DeviceReading, HapticDevice};
use haptics::udp::{UdpDevice, UdpParams, UdpStatus};
use haptics::workspace::Workspace;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tower_http::services::ServeDir;

/// Arguments of `coiffure serve`.
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Address to bind.
    #[arg(long, default_value = "127.0.0.1")]
    pub addr: std::net::IpAddr,
    /// Port (0: any free port; the chosen one is printed).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Folder of the built viewer (default: web/dist here, else beside the sources).
    #[arg(long)]
    pub web: Option<PathBuf>,
    /// Number of render strands of the built-in hairstyle.
    #[arg(long, default_value_t = 100_000)]
    pub render_strands: usize,
    /// Number of guide strands.
    #[arg(long, default_value_t = 200)]
    pub guides: usize,
    /// Real hairs each render strand stands for (`SessionParams::hairs_per_render_strand`: the local strands'
    /// reaction on the tool scales with it). With fewer render strands than hairs on a head (100 000), e.g.
    /// 5000 for software rendering, 20 keeps the hand's force that of a full head.
    #[arg(long, default_value_t = 1.0)]
    pub hairs_per_render_strand: f64,
    /// Visual frames per second sent to viewers.
    #[arg(long, default_value_t = 60.0)]
    pub fps: f64,
    /// Record the session to this file for replay (`coiffure replay`): created at start, written as the session
    /// runs (a chunk at least every 0.5 s), readable up to its last whole chunk if the server dies.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Stop by itself after this many seconds (for benchmarks and scripts).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Real-time (SCHED_FIFO) priority of the 1 kHz haptic thread, 1..=99, or 0 for normal priority (when
    /// real-time, the frame thread runs one below it and the network threads that write FRAMEs two below, so
    /// that FRAMEs leave on time on a busy machine). Needs root or CAP_SYS_NICE; without the right the loop runs
    /// at normal priority and a warning says so.
    #[arg(long, default_value_t = 10)]
    pub haptic_priority: i32,
    /// Run the haptic loop without its strand budget (`SessionParams::budget`, docs/protocol.md "Strand budget"): always
    /// up to 56 strands near the tool, however long the steps take on this machine (for benchmarks).
    #[arg(long)]
    pub no_strand_budget: bool,
    /// Haptic physics rate, Hz, in (0, 4000] (`SessionParams::haptic_rate_hz`): the local strands' step, which
    /// publishes the local force model the device loop renders.
    #[arg(long, default_value_t = 1000.0)]
    pub haptic_rate: f64,
    /// Device loop rate, Hz: a whole multiple of `--haptic-rate`, at most 10000 (`SessionParams::device_rate_hz`):
    /// the coupling and its passivity control run at this rate against the local force model.
    #[arg(long, default_value_t = 4000.0)]
    pub device_rate: f64,
    /// Runaway guard distance, m (`HapticParams::max_proxy_lag`, default 0.2): a tool proxy farther than this
    /// from the device, or non-finite, is put back on the device with zero force and counted (FRAME's runaways).
    #[arg(long)]
    pub max_proxy_lag: Option<f64>,
    /// A haptic device drives the tool instead of the mouse: it streams poses in the UDP protocol
    /// (docs/protocol.md) to `udp:PORT` (on 127.0.0.1) or `udp:ADDR:PORT`; port 0 takes any free port
    /// (printed). The viewers watch; the toolbar still works.
    #[arg(long)]
    pub device: Option<String>,
    /// Device profile (force, force-rate and stiffness limits): phantom-omni, phantom-desktop or omega3.
    #[arg(long, default_value = "phantom-omni")]
    pub device_profile: String,
    /// Device workspace to head frame, `SCALE` or `SCALE,X,Y,Z`: head = (X, Y, Z) + SCALE x device (m).
    /// Default per profile: scale 2, the workspace's centre 13 cm behind the head's centre (0,-0.13,0).
    #[arg(long)]
    pub device_workspace: Option<String>,
    /// Other web origins allowed to open the WebSocket (e.g. `http://localhost:3000`), besides the page this
    /// server serves (same origin). Repeatable. Clients that send no Origin (scripts) are not browsers and
    /// are let through (with the token, when one is required).
    #[arg(long)]
    pub allow_origin: Vec<String>,
    /// A viewer with a message waiting, or a send unfinished, for this long is disconnected, s. Default 30
    /// (`outbox::BEHIND_LIMIT`).
    #[arg(long)]
    pub viewer_timeout: Option<f64>,
    /// Access token required on `/ws` (`?token=...`, which the viewer takes from its own URL). Binding to a
    /// non-loopback address without one generates one and prints the URL with it.
    #[arg(long)]
    pub token: Option<String>,
    /// Time budget of one LOAD (read, fit, build), s (`hairstyle::LoadLimits::max_seconds`, default 30): a LOAD
    /// over it is answered by ERROR 5 and the live hairstyle stays.
    #[arg(long)]
    pub load_budget: Option<f64>,
}


/// The UDP address of `--device`: `udp:PORT` (127.0.0.1) or `udp:ADDR:PORT`.
pub fn parse_device(spec: &str) -> anyhow::Result<SocketAddr> {
    let rest = spec.strip_prefix("udp:").ok_or_else(|| anyhow!("--device {spec:?}: expected udp:PORT or udp:ADDR:PORT (the UDP protocol of docs/protocol.md)"))?;
    if let Ok(port) = rest.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    rest.parse::<SocketAddr>().map_err(|e| anyhow!("--device {spec:?}: expected udp:PORT or udp:ADDR:PORT: {e}"))
}

/// The device profile named by `--device-profile`.
fn device_profile(name: &str) -> anyhow::Result<DeviceProfile> {
    DeviceProfile::by_name(name).ok_or_else(|| anyhow!("--device-profile {name:?}: expected phantom-omni, phantom-desktop, omega3 or phantom-premium-6dof"))
}

/// The viewer folder: `--web`, else `./web/dist`, else `web/dist` beside the sources.
fn viewer_dir(arg: &Option<PathBuf>) -> anyhow::Result<PathBuf> {
    let candidates: Vec<PathBuf> = match arg {
        Some(p) => vec![p.clone()],
        None => vec![PathBuf::from("web/dist"), Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/dist")],
    };
    for c in &candidates {
        if c.join("index.html").is_file() {
            return Ok(c.clone());
        }
    }
    Err(anyhow!(
        "the viewer is not built: {} has no index.html. Build it with `npm --prefix web ci && npm --prefix web run build` (from the repository root), or pass --web DIR",
        candidates[0].display()
    ))
}

struct Control {
    controller: Option<u64>,
    viewers: Vec<Arc<Outbox>>,
}

struct App {
    scene_msg: Mutex<Arc<Vec<u8>>>,
    scene: Mutex<Arc<Scene>>,
    frames: watch::Receiver<Arc<Frame>>,
    /// How on time the writers hand FRAMEs on (their pickup delays).
    delivery: DeliveryStats,
    /// When the latest FRAMEs were published (for the writers' pickup delays).
    published: PublishLog,
    device: Mutex<VirtualHandle>,
    commands: Mutex<Sender<Command>>,
    control: Mutex<Control>,
    next_id: AtomicU64,
    started: Instant,
    latest_lattice: Mutex<Vec<[f32; 3]>>,
    /// The head pose of the latest lattice (head frame to world).
    latest_head: Mutex<nalgebra::Isometry3<f64>>,
    /// Latest (kept length per guide, active guides, their displacements, samples per guide).
    latest_guides: Mutex<(Arc<Vec<u16>>, Vec<u32>, Vec<nalgebra::Vector3<f64>>, usize)>,
    /// Options of the built-in scene (head, guides, lattice cell) a loaded hairstyle is put on.
    opts: SceneOptions,
    /// Parameters every session of this server starts with.
    params: SessionParams,
    /// The running session (replaced when a hairstyle file is loaded).
    session: Mutex<Option<Session>>,
    /// A new session's snapshot outputs, for the frame thread to take over.
    swap: Mutex<Option<(Output<LatticeSnapshot>, Output<HapticSnapshot>)>>,
    /// `--device`: the UDP device each session reads (a clone on the same socket), and its counters.
    udp: Option<(UdpDevice, Arc<UdpStatus>)>,
    /// Who may open `/ws`.
    access: Access,
    /// When the last SAVE was served.
    last_save: Mutex<Option<Instant>>,
    /// Held while a LOAD reads, fits and builds (one at a time: a second is refused, not queued).
    loading: Mutex<()>,
    /// A viewer's time limit (`--viewer-timeout`).
    viewer_timeout: Duration,
    /// The record's status with `--record` (its stop is told to every viewer, ERROR 7).
    record: Option<Arc<RecordStatus>>,
}

/// Shortest time between two SAVEs (each writes the whole hairstyle).
pub const SAVE_INTERVAL: Duration = Duration::from_secs(1);

impl App {
    /// The device a new session reads: the UDP device's clone with `--device`, else None (the mouse).
    fn session_device(&self) -> Result<Option<Box<dyn HapticDevice>>, String> {
        match &self.udp {
            Some((d, _)) => d.try_clone().map(|d| Some(Box::new(d) as Box<dyn HapticDevice>)).map_err(|e| format!("cannot share the device socket: {e}")),
            None => Ok(None),
        }
    }

    /// The viewers now. Messages are posted outside the control lock, which the frame thread also takes:
    /// nobody holds it for long.
    fn viewers(&self) -> Vec<Arc<Outbox>> {
        self.control.lock().unwrap().viewers.clone()
    }

    fn broadcast(&self, msg: &[u8]) {
        for v in self.viewers() {
            v.post(msg.to_vec());
        }
    }

    fn broadcast_control(&self) {
        let c = self.control.lock().unwrap();
        let n = c.viewers.len() as u32;
        for v in &c.viewers {
            v.post(protocol::encode_control(c.controller == Some(v.id), n));
        }
    }
}

/// Frame pump statistics (information, logged at the end).
#[derive(Default)]
struct PumpStats {
    frames: u64,
    /// The runaway guard's count in the latest frame (of the current session).
    runaways: u64,
    encode_seconds: f64,
    bytes: u64,
    /// Frames sent more than one frame period after their scheduled time (the frame thread was not run in time).
    late: u64,
    /// The largest delay of a frame behind its scheduled time, s.
    max_late: f64,
    /// The longest time from a frame's turn to its publication (encoding, and any wait for a lock), s.
    max_build: f64,
}

/// Runs the server until Ctrl-C (or `--duration`).
pub fn run(args: &ServeArgs) -> anyhow::Result<()> {
    let web = viewer_dir(&args.web)?;
    if !(args.fps > 0.0 && args.fps <= 240.0) {
        return Err(anyhow!("--fps must be in (0, 240], got {}", args.fps));
    }
    // Access: a token is required off loopback (generated unless given).
    let token = match (&args.token, args.addr.is_loopback()) {
        (Some(t), _) if t.len() < 8 || !t.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_') => {
            return Err(anyhow!("--token must be at least 8 characters of letters, digits, '-' or '_'"));
        }
        (Some(t), _) => Some(t.clone()),
        (None, false) => Some(new_token()?),
        (None, true) => None,
    };
    let access = Access { allow_origins: args.allow_origin.clone(), token };
    let viewer_timeout = match args.viewer_timeout {
        None => crate::outbox::BEHIND_LIMIT,
        Some(t) if t.is_finite() && t > 0.0 && t <= 3600.0 => Duration::from_secs_f64(t),
        Some(t) => return Err(anyhow!("--viewer-timeout must be in (0, 3600] s, got {t}")),
    };
    let t0 = Instant::now();
    let mut opts = SceneOptions { render_strands: args.render_strands, guides: args.guides, ..SceneOptions::default() };
    match args.load_budget {
        None => {}
        Some(t) if t.is_finite() && t >= 0.0 && t <= 3600.0 => opts.load.max_seconds = t,
        Some(t) => return Err(anyhow!("--load-budget must be in [0, 3600] s, got {t}")),
    }
    let scene = Arc::new(Scene::builtin(&opts).context("building the built-in scene")?);
    tracing::info!("scene: {} render strands, {} guides, {} lattice nodes, built in {:.2} s", scene.render.strands(), scene.guides.len(), scene.lattice.node_count(), t0.elapsed().as_secs_f64());
    let haptic_priority = (args.haptic_priority != 0).then_some(args.haptic_priority);
    let profile = device_profile(&args.device_profile)?;
    let input = if args.device.is_some() { InputKind::Device } else { InputKind::Pointer };
    let mut params = SessionParams { haptic_priority, hairs_per_render_strand: args.hairs_per_render_strand, haptic_rate_hz: args.haptic_rate, device_rate_hz: args.device_rate, profile, input, ..SessionParams::default() };
    if let Some(lag) = args.max_proxy_lag {
        params.haptic.max_proxy_lag = lag;
    }
    params.budget.enabled = !args.no_strand_budget;
    params.validate().context("--hairs-per-render-strand, --haptic-rate, --device-rate, --max-proxy-lag")?;
    let udp = match &args.device {
        Some(spec) => {
            let addr = parse_device(spec)?;
            let workspace = match &args.device_workspace {
                Some(w) => Workspace::parse(w, &profile).map_err(|e| anyhow!("--device-workspace: {e}"))?,
                None => Workspace::for_profile(&profile),
            };
            let dev = UdpDevice::bind_with(&addr.to_string(), UdpParams { workspace, ..UdpParams::for_profile(&profile) }).with_context(|| format!("cannot bind the device socket {addr}"))?;
            let local = dev.local_addr()?;
            println!(
                "coiffure serve: device on udp:{local} ({}, {:.1} N; workspace: head = ({:.3}, {:.3}, {:.3}) m + {} x device; device loop {} Hz)",
                profile.name, profile.max_force, workspace.offset.x, workspace.offset.y, workspace.offset.z, workspace.scale, args.device_rate
            );
            let status = dev.status();
            Some((dev, status))
        }
        None => None,
    };
    let first_device = match &udp {
        Some((d, _)) => Some(Box::new(d.try_clone()?) as Box<dyn HapticDevice>),
        None => None,
    };
    let record = match &args.record {
        Some(path) => Some(RecordTarget {
            sink: Box::new(RecordFile::create(path).with_context(|| format!("cannot create the record {}", path.display()))?),
            settings: Some(RecordSettings::of(&opts, &params)),
        }),
        None => None,
    };
    let (session, io) = Session::start_recording(scene.clone(), params, first_device, record).context("starting the session")?;
    let record_status = session.record_status();
    let SessionIo { device, commands, lattice, haptic } = io;
    let scene_msg = Arc::new(protocol::encode_scene(&scene, params.global.nozzle_standoff));
    let (frame_tx, frame_rx) = watch::channel(Arc::new(Frame::none()));
    let stop = Arc::new(AtomicBool::new(false));
    let app = Arc::new(App {
        scene_msg: Mutex::new(scene_msg),
        scene: Mutex::new(scene),
        frames: frame_rx,
        delivery: DeliveryStats::default(),
        published: PublishLog::default(),
        device: Mutex::new(device),
        commands: Mutex::new(commands),
        control: Mutex::new(Control { controller: None, viewers: Vec::new() }),
        next_id: AtomicU64::new(1),
        started: Instant::now(),
        latest_lattice: Mutex::new(Vec::new()),
        latest_head: Mutex::new(nalgebra::Isometry3::identity()),
        latest_guides: Mutex::new((Arc::new(Vec::new()), Vec::new(), Vec::new(), 2)),
        opts,
        params,
        session: Mutex::new(Some(session)),
        access,
        last_save: Mutex::new(None),
        loading: Mutex::new(()),
        viewer_timeout,
        swap: Mutex::new(None),
        udp,
        record: record_status,
    });
    let app_end = app.clone();

    // Frame pump thread.
    let (stop_p, app_p, fps) = (stop.clone(), app.clone(), args.fps);
    let frame_priority = haptic_priority.map(|p| (p - 1).max(1));
    let pump = std::thread::Builder::new().name("coiffure-frames".into()).spawn(move || {
        // Frames on time on a busy machine: the frame thread (about 45 us of work per frame) runs real-time
        // just below the haptic loop, when the haptic loop does.
        if let Some(p) = frame_priority {
            if let Err(why) = haptics::realtime::request_realtime(p) {
                tracing::warn!("the frame thread runs at normal priority: {why}");
            }
        }
        let (mut lattice, mut haptic) = (lattice, haptic);
        let mut st = PumpStats::default();
        let mut kept_sent = 0u64;
        let mut record_stop_sent = false;
        let period = Duration::from_secs_f64(1.0 / fps);
        let start = Instant::now();
        while !stop_p.load(Ordering::Relaxed) {
            // A loaded hairstyle's session: its snapshots from now on, and its strands' kept points to all.
            // (The frame thread never waits for a lock a slower thread may hold: try_lock, and retry next frame.)
            if let Some((l, h)) = app_p.swap.try_lock().ok().and_then(|mut s| s.take()) {
                (lattice, haptic) = (l, h);
                kept_sent = u64::MAX;
            }
            let c0 = cpu_time();
            let w0 = Instant::now();
            let behind = w0.saturating_duration_since(start + period * st.frames as u32).as_secs_f64();
            st.max_late = st.max_late.max(behind);
            if behind > period.as_secs_f64() {
                st.late += 1;
            }
            let (lat, hap) = (lattice.read(), haptic.read());
            let msg = protocol::encode_frame(st.frames as u32, lat, hap);
            // After a scissors cut or a reset: every viewer gets the strands' kept points (STRANDS) before the frame.
            if lat.kept_version != kept_sent {
                kept_sent = lat.kept_version;
                let s = protocol::encode_strands(&lat.kept);
                for v in app_p.viewers() {
                    v.post(s.clone());
                }
            }
            // The latest state for SAVE (skipped while a SAVE reads it: the next frame's will do).
            if let (Ok(mut l), Ok(mut h)) = (app_p.latest_lattice.try_lock(), app_p.latest_head.try_lock()) {
                l.clear();
                l.extend(lat.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]));
                *h = lat.head;
            }
            if let Ok(mut g) = app_p.latest_guides.try_lock() {
                let samples = if hap.active.is_empty() { 2 } else { (hap.displacement.len() / hap.active.len()).max(2) };
                *g = (lat.kept.clone(), hap.active.clone(), hap.displacement.clone(), samples);
            }
            st.bytes += msg.len() as u64;
            st.runaways = hap.runaways;
            let published = Instant::now();
            app_p.published.note(st.frames as u32, published);
            let _ = frame_tx.send(Arc::new(Frame { bytes: msg, published }));
            st.max_build = st.max_build.max((published - w0).as_secs_f64());
            // Recording stopped (disk full, file unwritable): every viewer is told why, once.
            if let Some(why) = app_p.record.as_ref().and_then(|r| r.stopped()).filter(|_| !record_stop_sent) {
                record_stop_sent = true;
                app_p.broadcast(&record_stopped(why));
            }
            // The device's status to every viewer, about 10 times a second.
            if let Some((_, status)) = &app_p.udp {
                if st.frames % (fps / 10.0).ceil().max(1.0) as u64 == 0 {
                    app_p.broadcast(&protocol::encode_device(&status.counts()));
                }
            }
            st.encode_seconds += match (c0, cpu_time()) {
                (Some(a), Some(b)) => b - a,
                _ => w0.elapsed().as_secs_f64(),
            };
            st.frames += 1;
            let next = start + period * st.frames as u32;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
        }
        st
    })?;

    // The runtime's threads (the viewers' writers and readers) run real-time one below the frame thread, so
    // that a FRAME is not queued behind normal work on a busy machine; heavy jobs (LOAD, SAVE) go back to normal
    // priority on their blocking thread (`delivery::normal_priority`).
    let worker_priority = frame_priority.map(|p| (p - 1).max(1));
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .on_thread_start(move || {
            if let Some(p) = worker_priority {
                if let Err(why) = haptics::realtime::request_realtime(p) {
                    tracing::debug!("a runtime thread runs at normal priority: {why}");
                }
            }
        })
        .build()?;
    let addr = SocketAddr::new(args.addr, args.port);
    let duration = args.duration;
    let app_token = app.access.token.clone();
    let served = rt.block_on(async move {
        let router = Router::new().route("/ws", get(ws_handler)).route("/debug/carried", axum::routing::post(carried_handler)).fallback_service(ServeDir::new(&web)).with_state(app.clone());
        let listener = tokio::net::TcpListener::bind(addr).await.with_context(|| format!("cannot bind {addr}"))?;
        let local = listener.local_addr()?;
        match &app_token {
            Some(t) => println!("coiffure serve: listening on http://{local}/?token={t} (viewer from {}; the token is required)", web.display()),
            None => println!("coiffure serve: listening on http://{local}/ (viewer from {})", web.display()),
        }
        use std::io::Write;
        let _ = std::io::stdout().flush();
        let shutdown = async move {
            match duration {
                Some(d) => tokio::time::sleep(Duration::from_secs_f64(d.max(0.0))).await,
                None => {
                    let _ = tokio::signal::ctrl_c().await;
                }
            }
        };
        // TCP_NODELAY: a FRAME leaves at once. With Nagle's algorithm a FRAME (smaller than a segment) waits for
        // the ACK of the previous one, which a viewer that only reads sends late (delayed ACKs, 40-200 ms):
        // before, a reading viewer got a fifth of its FRAMEs about 30 ms late and gaps up to 193 ms.
        axum::serve(nodelay(listener), router).with_graceful_shutdown(shutdown).await.context("server failed")?;
        anyhow::Ok(())
    });
    stop.store(true, Ordering::Relaxed);
    let st = pump.join().map_err(|_| anyhow!("the frame thread panicked"))?;
    let session = app_end.session.lock().unwrap().take().ok_or_else(|| anyhow!("no session to stop"))?;
    let report = session.stop();
    let f = st.frames.max(1) as f64;
    println!(
        "frames sent: {} ({:.1} us CPU and {:.0} bytes per frame; {} more than a period late, the latest {:.1} ms behind, built in at most {:.1} ms); haptic loop: {} steps at {} Hz, step mean {:.1} us, p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us, {} over the period, the device loop waited {} times ({} stalls), {} step panics, {} runaways; device loop: {} steps at {} Hz, step mean {:.1} us, p99.9 {:.0} us, max {:.0} us, {} misses ({:.3} %, {} periods skipped), {} step panics, real-time priority: {}; global: {} steps, mean {:.2} ms; delivery: {}",
        st.frames, 1e6 * st.encode_seconds / f, st.bytes as f64 / f, st.late, 1e3 * st.max_late, 1e3 * st.max_build,
        report.physics.steps, args.haptic_rate, 1e6 * report.physics.step_mean, 1e6 * report.physics.step_p50, 1e6 * report.physics.step_p99, 1e6 * report.physics.step_p999, 1e6 * report.physics.step_max, report.physics.over, report.physics.waits, report.physics.stalls, report.physics.panics, st.runaways,
        report.haptic.steps, args.device_rate, 1e6 * report.haptic.step_mean, 1e6 * report.haptic.step_p999, 1e6 * report.haptic.step_max, report.haptic.misses, 100.0 * report.haptic.misses as f64 / report.haptic.steps.max(1) as f64, report.haptic.skipped, report.haptic.panics, report.haptic.realtime,
        report.global_steps, 1e3 * report.global_step_mean, app_end.delivery.summary()
    );
    let b = &report.budget;
    if b.enabled {
        println!(
            "strand budget: {} changes, lowest {} strands, {} at the end (of {}), {:.1} % of {} steps limited",
            b.changes, b.lowest, b.last, params.max_active, 100.0 * b.limited_steps as f64 / b.steps.max(1) as f64, b.steps
        );
    } else {
        println!("strand budget: off");
    }
    if let Some((_, status)) = &app_end.udp {
        let c = status.counts();
        println!(
            "device: {} poses accepted, rejected {} (invalid {}, teleport {}, out of order {}, duplicate {}), {} malformed, {} from another sender, lost {} times, {} forces sent",
            c.accepted, c.rejected_total(), c.rejected[0], c.rejected[1], c.rejected[2], c.rejected[3], c.malformed, c.foreign, c.lost, c.answered
        );
    }
    if let Some(r) = &report.record {
        let secs = r.steps as f64 / args.haptic_rate;
        match &r.stopped {
            None => println!("record: {} haptic steps ({secs:.1} s), {} global steps, {} bytes written to {}", r.steps, r.global_steps, r.bytes, r.name),
            Some(why) => println!("record: stopped early, {} haptic steps ({secs:.1} s) in {} ({} bytes); {} steps after it not recorded: {why}", r.steps, r.name, r.bytes, r.unrecorded),
        }
    }
    served
}

/// `listener` with TCP_NODELAY set on every accepted connection (see where it is used).
fn nodelay(listener: tokio::net::TcpListener) -> impl axum::serve::Listener<Io = tokio::net::TcpStream, Addr = SocketAddr> {
    use axum::serve::ListenerExt;
    listener.tap_io(|tcp| {
        if let Err(e) = tcp.set_nodelay(true) {
            tracing::warn!("cannot set TCP_NODELAY on a connection (its FRAMEs may wait for ACKs): {e}");
        }
    })
}

/// ERROR 7: recording stopped before the session ended, and why (the session goes on).
fn record_stopped(why: &str) -> Vec<u8> {
    protocol::encode_error(&WireError { code: protocol::code::RECORD, message: format!("recording stopped: {why}") })
}

/// CPU time of the calling thread, s, or None if the clock is unavailable.
fn cpu_time() -> Option<f64> {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec into the valid, exclusively borrowed `ts`.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then(|| ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64)
}

/// The WebSocket upgrade, after the access checks ([`check_access`]); messages and frames up to 64 MiB.
async fn ws_handler(ws: WebSocketUpgrade, headers: axum::http::HeaderMap, query: axum::extract::Query<std::collections::HashMap<String, String>>, State(app): State<Arc<App>>) -> axum::response::Response {
    if let Err(why) = check_access(&headers, query.get("token").map(String::as_str), &app.access) {
        tracing::warn!("refused a WebSocket: {why}");
        return (axum::http::StatusCode::FORBIDDEN, why).into_response();
    }
    // The largest message is a LOAD of the largest file (its 2-byte header and 9 bytes of format and options).
    let max = app.opts.load.max_file_bytes + 16;
    ws.max_message_size(max).max_frame_size(max).on_upgrade(move |socket| viewer(socket, app)).into_response()
}

/// `POST /debug/carried` (`crate::carried`), after the access checks of `/ws`: the named render vertices carried
/// by the live scene's one law on the lattice and head pose the request gives (JSON in and out); 400 naming
/// what is wrong with a bad request.
async fn carried_handler(headers: axum::http::HeaderMap, query: axum::extract::Query<std::collections::HashMap<String, String>>, State(app): State<Arc<App>>, body: axum::body::Bytes) -> axum::response::Response {
    use axum::http::StatusCode;
    if let Err(why) = check_access(&headers, query.get("token").map(String::as_str), &app.access) {
        return (StatusCode::FORBIDDEN, why).into_response();
    }
    let req = match crate::carried::parse(&body) {
        Ok(r) => r,
        Err(why) => return (StatusCode::BAD_REQUEST, why).into_response(),
    };
    let scene = app.scene.lock().unwrap().clone();
    match tokio::task::spawn_blocking(move || crate::carried::carried(&scene, &req)).await {
        Ok(Ok(answer)) => ([(axum::http::header::CONTENT_TYPE, "application/json")], serde_json::to_vec(&answer).unwrap_or_default()).into_response(),
        Ok(Err(why)) => (StatusCode::BAD_REQUEST, why).into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

/// Who may open `/ws`: the allowed origins besides the served one, and the token if one is required.
#[derive(Debug, Clone, Default)]
pub struct Access {
    /// Origins allowed besides the page's own (`--allow-origin`), e.g. `http://localhost:3000`.
    pub allow_origins: Vec<String>,
    /// The token `/ws?token=` must carry (`--token`, or generated for a non-loopback address).
    pub token: Option<String>,
}

/// Checks a WebSocket upgrade: a browser's Origin must be this server's own (scheme-less host:port equal to
/// the Host header) or allowed, so that another web page open in the user's browser cannot drive the app;
/// and the token must match when one is required. Err says why (sent back with 403).
pub fn check_access(headers: &axum::http::HeaderMap, token: Option<&str>, access: &Access) -> Result<(), String> {
    if let Some(origin) = headers.get(axum::http::header::ORIGIN) {
        let origin = origin.to_str().map_err(|_| "the Origin header is not text".to_string())?;
        let host = headers.get(axum::http::header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
        let origin_host = origin.split_once("://").map_or(origin, |(_, rest)| rest).trim_end_matches('/');
        let same = !host.is_empty() && origin_host.eq_ignore_ascii_case(host);
        if !same && !access.allow_origins.iter().any(|a| a.trim_end_matches('/').eq_ignore_ascii_case(origin)) {
            return Err(format!("origin {origin} is not this server ({host}); start the server with --allow-origin {origin} to allow it"));
        }
    }
    if let Some(want) = &access.token {
        if token != Some(want.as_str()) {
            return Err("a valid access token is required (open the URL the server printed, with ?token=...)".into());
        }
    }
    Ok(())
}

/// A random access token (128 bits from the OS, hex).
fn new_token() -> anyhow::Result<String> {
    use std::io::Read;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut b)).context("cannot read /dev/urandom for an access token")?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

/// One viewer: sends the scene, then frames; handles its messages. Its outgoing messages go through its
/// [`Outbox`] (bounded; FRAMEs are not queued: the writer takes the latest when free); a viewer that falls
/// behind or overflows its queue is disconnected with a close reason (policy violation, 1008), and a message
/// over the size limit is answered by ERROR 1 and a close (message too big, 1009).
async fn viewer(socket: WebSocket, app: Arc<App>) {
    let id = app.next_id.fetch_add(1, Ordering::Relaxed);
    let (mut sink, mut stream) = socket.split();
    let outbox = Arc::new(Outbox::new(id, app.viewer_timeout));
    {
        let mut c = app.control.lock().unwrap();
        c.viewers.push(outbox.clone());
        if c.controller.is_none() {
            c.controller = Some(id);
        }
    }
    // The scene and the strands' kept points (all uncut until the first cut), queued first.
    outbox.post((**app.scene_msg.lock().unwrap()).clone());
    let kept = app.latest_guides.lock().unwrap().0.clone();
    if !kept.is_empty() {
        outbox.post(protocol::encode_strands(&kept));
    }
    if let Some((_, status)) = &app.udp {
        outbox.post(protocol::encode_device(&status.counts()));
    }
    if let Some(why) = app.record.as_ref().and_then(|r| r.stopped()) {
        outbox.post(record_stopped(why));
    }
    app.broadcast_control();
    let mut frames = app.frames.clone();
    let (app_w, out_w) = (app.clone(), outbox.clone());
    let mut closing_w = outbox.closing();
    let mut writer = tokio::spawn(async move {
        // Queued messages first (a STRANDS precedes the FRAME carrying its version), then the latest frame.
        let mut cut = false;
        // Since when the writer has been free to send (its pickup delays are measured from it).
        let mut free_since = Instant::now();
        let mut last_seq = None;
        loop {
            let bytes = match out_w.pop() {
                Some(m) => m,
                None if out_w.closes_after_queue() => {
                    out_w.close_now();
                    break;
                }
                None => tokio::select! {
                    changed = frames.changed() => {
                        if changed.is_err() { break; }
                        let f = frames.borrow_and_update().clone();
                        if f.bytes.is_empty() { continue; }
                        let seq = u32::from_le_bytes(f.bytes[2..6].try_into().expect("FRAME header"));
                        app_w.delivery.pickup(&app_w.published, seq, f.published, last_seq, free_since);
                        last_seq = Some(seq);
                        let mut bytes = f.bytes.clone();
                        let you = app_w.control.lock().map(|c| c.controller == Some(id)).unwrap_or(false);
                        bytes[protocol::FRAME_FLAGS_OFFSET] = you as u8;
                        bytes
                    }
                    _ = out_w.ready() => continue,
                    _ = closing_w.wait_for(Option::is_some) => break,
                },
            };
            out_w.sending(true);
            let sent = tokio::select! {
                r = sink.send(Message::Binary(bytes.into())) => r.is_ok(),
                _ = closing_w.wait_for(Option::is_some) => { cut = true; false }
            };
            out_w.sending(false);
            free_since = Instant::now();
            if !sent {
                break;
            }
        }
        // Say why, unless a send was cut half way (the stream is then broken) or the socket failed.
        let reason = closing_w.borrow().clone();
        if let (Some(reason), false) = (reason, cut) {
            let code = if reason.starts_with("message of") { 1009 } else { 1008 };
            let close = Message::Close(Some(axum::extract::ws::CloseFrame { code, reason: reason.chars().take(120).collect::<String>().into() }));
            let _ = tokio::time::timeout(Duration::from_secs(1), sink.send(close)).await;
        }
    });
    let mut closing = outbox.closing();
    let mut tick = tokio::time::interval(Duration::from_millis(250));
    loop {
        // Stop when the socket fails (the writer ends), the viewer is behind or its queue overflowed.
        let msg = tokio::select! {
            m = stream.next() => match m {
                Some(Ok(m)) => m,
                // Over the size limit (tungstenite's capacity error; the stream cannot go on): ERROR 1 naming the
                // limit, then a close. Other errors: the socket failed.
                Some(Err(e)) if e.to_string().contains("Space limit exceeded") => {
                    let limit = app.opts.load.max_file_bytes + 16;
                    let text = format!("message of more than {limit} bytes, the limit (a LOAD of a file up to {} MiB): {e}", app.opts.load.max_file_bytes >> 20);
                    outbox.post(protocol::encode_error(&WireError { code: protocol::code::MALFORMED, message: text.clone() }));
                    outbox.disconnect_after_queue(text);
                    break;
                }
                Some(Err(_)) | None => break,
            },
            _ = &mut writer => break,
            _ = closing.wait_for(Option::is_some) => break,
            _ = tick.tick() => {
                if let Some(why) = outbox.behind() {
                    outbox.disconnect(why);
                }
                continue;
            }
        };
        let reply = match msg {
            // LOAD and SAVE parse, fit and build scenes for up to seconds: on a blocking thread, so that the
            // runtime's workers keep serving the other viewers.
            Message::Binary(b) if matches!(b.first(), Some(&protocol::client::LOAD) | Some(&protocol::client::SAVE)) => {
                let app = app.clone();
                tokio::task::spawn_blocking(move || {
                    crate::delivery::normal_priority();
                    handle(&app, id, &b)
                })
                .await.unwrap_or_else(|_| Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: "the file operation failed".into() })))
            }
            Message::Binary(b) => handle(&app, id, &b),
            Message::Text(_) => Some(protocol::encode_error(&WireError { code: protocol::code::TEXT, message: "text frames are not part of the protocol; send binary messages (docs/protocol.md)".into() })),
            Message::Close(_) => break,
            _ => None,
        };
        if let Some(r) = reply {
            outbox.post(r);
        }
    }
    // A disconnected viewer's writer says why (at most a second for the close); otherwise it is stopped.
    leave(&app, id);
    let kicked = outbox.closing().borrow().is_some() || outbox.closes_after_queue();
    if !kicked || tokio::time::timeout(Duration::from_secs(2), &mut writer).await.is_err() {
        writer.abort();
    }
}

fn leave(app: &App, id: u64) {
    {
        let mut c = app.control.lock().unwrap();
        c.viewers.retain(|v| v.id != id);
        if c.controller == Some(id) {
            c.controller = c.viewers.first().map(|v| v.id);
        }
    }
    app.broadcast_control();
}

/// Handles one binary message; returns the reply, if any.
fn handle(app: &App, id: u64, bytes: &[u8]) -> Option<Vec<u8>> {
    let msg = match protocol::parse_client(bytes) {
        Ok(m) => m,
        Err(e) => {
            tracing::debug!("viewer {id}: {}", e.message);
            return Some(protocol::encode_error(&e));
        }
    };
    let controls = app.control.lock().unwrap().controller == Some(id);
    let not_controller = || Some(protocol::encode_error(&WireError { code: protocol::code::NOT_CONTROLLER, message: "another viewer controls the tool; send TAKE_CONTROL first".into() }));
    match msg {
        ClientMessage::Ping(t) => Some(protocol::encode_pong(t)),
        ClientMessage::TakeControl => {
            app.control.lock().unwrap().controller = Some(id);
            app.broadcast_control();
            None
        }
        ClientMessage::Pose { position, rotation, buttons } => {
            if !controls {
                return not_controller();
            }
            if app.udp.is_some() {
                // A haptic device drives the tool (`--device`); the mouse does not fight it.
                return None;
            }
            let time = app.started.elapsed().as_secs_f64();
            app.device.lock().unwrap().push(DeviceReading { time, position, rotation, buttons });
            None
        }
        ClientMessage::Command(c) => {
            if !controls {
                return not_controller();
            }
            let _ = app.commands.lock().unwrap().send(c);
            None
        }
        ClientMessage::Save(format) => {
            // A SAVE writes the whole hairstyle (up to a second of work at 100k strands): only the viewer in
            // control, at most one per `SAVE_INTERVAL`.
            if !controls {
                return not_controller();
            }
            {
                let mut last = app.last_save.lock().unwrap();
                if last.is_some_and(|t| t.elapsed() < SAVE_INTERVAL) {
                    return Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: format!("SAVE at most once every {} s; try again", SAVE_INTERVAL.as_secs_f64()) }));
                }
                *last = Some(Instant::now());
            }
            match save(app, format) {
                Ok(b) => Some(protocol::encode_file(format, &b)),
                Err(e) => Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: e })),
            }
        }
        ClientMessage::Load(format, opts, bytes) => {
            if !controls {
                return not_controller();
            }
            let f = hairstyle::formats::Format::from_path(Path::new(&format!("x.{}", protocol::FORMATS[format]))).expect("known extension");
            let file_error = |message| Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message }));
            // One LOAD at a time (control can move between two viewers' LOADs): a second is refused.
            let Ok(_loading) = app.loading.try_lock() else {
                return file_error("another hairstyle is being loaded; send the LOAD again when its SCENE has arrived".into());
            };
            let start = Instant::now();
            match hairstyle::fit::read_and_fit(f, &bytes, &opts, &app.opts.load) {
                Ok((c, report)) => {
                    if let Err(message) = app.opts.load.check_time(start, "the fit") {
                        return file_error(message);
                    }
                    tracing::info!("loaded hairstyle fitted: scale {:.5} m per unit, up {} front {} ({}), {:.1} % of the strands rooted on the scalp (roots median {:.2} mm, p95 {:.2} mm from it)", report.transform.scale, report.up.name(), report.front.name(), report.orientation_source.name(), 100.0 * report.rooted, 1e3 * report.rooted_distance.median, 1e3 * report.rooted_distance.p95);
                    match load(app, &c, start) {
                        Ok(()) => {
                            let msg = protocol::encode_fit(&report);
                            for v in app.viewers() {
                                v.post(msg.clone());
                            }
                            None
                        }
                        Err(message) => file_error(message),
                    }
                }
                Err(hairstyle::fit::LoadError::Format(e)) => file_error(format!("cannot read the {} file: {e}", protocol::FORMATS[format])),
                Err(e) => file_error(e.to_string()),
            }
        }
    }
}

/// Replaces the live hairstyle by `curves` (m, head frame, as `hairstyle::fit` leaves them): a scene of the built-in head and guides
/// carrying them ([`Scene::from_curves`]), a new session on it, the new SCENE sent to every viewer, then
/// the frame thread switched to the new session's snapshots. The old session stops. Refused while
/// recording (a record is of one scene).
fn load(app: &App, curves: &hairstyle::HairCurves, t0: Instant) -> Result<(), String> {
    if app.record.is_some() {
        return Err("cannot load a hairstyle while recording (--record): a record replays one scene".into());
    }
    let scene = Arc::new(Scene::from_curves(curves, &app.opts).map_err(|e| format!("cannot use the loaded hairstyle: {e}"))?);
    // Over the budget the new scene is dropped before anything live changes.
    app.opts.load.check_time(t0, "building the scene")?;
    let (session, io) = Session::start_with_device(scene.clone(), app.params, app.session_device()?).map_err(|e| e.to_string())?;
    let SessionIo { device, commands, lattice, haptic } = io;
    let old = app.session.lock().unwrap().replace(session);
    *app.device.lock().unwrap() = device;
    *app.commands.lock().unwrap() = commands;
    let msg = Arc::new(protocol::encode_scene(&scene, app.params.global.nozzle_standoff));
    *app.scene.lock().unwrap() = scene.clone();
    *app.scene_msg.lock().unwrap() = msg.clone();
    app.latest_guides.lock().unwrap().0 = Arc::new(Vec::new());
    for v in app.viewers() {
        v.post((*msg).clone());
    }
    *app.swap.lock().unwrap() = Some((lattice, haptic));
    if let Some(old) = old {
        old.stop();
    }
    tracing::info!("loaded a hairstyle: {} render strands, {} lattice nodes, in {:.2} s", scene.render.strands(), scene.lattice.node_count(), t0.elapsed().as_secs_f64());
    Ok(())
}

/// The current hairstyle (render strands through the latest lattice, following the active guides, cut
/// strands shortened: `Scene::render_curves`, the law the viewer's shader draws) as file bytes.
fn save(app: &App, format: usize) -> Result<Vec<u8>, String> {
    let scene = app.scene.lock().unwrap().clone();
    let nodes: Vec<nalgebra::Point3<f64>> = app.latest_lattice.lock().unwrap().iter().map(|p| nalgebra::Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
    let head = *app.latest_head.lock().unwrap();
    let (kept, active, disp, samples) = app.latest_guides.lock().unwrap().clone();
    let guides = engine::scene::GuideDisplacements { active: &active, displacement: &disp, samples };
    let curves = scene.render_curves(&nodes, &head, &engine::scene::Scene::kept_lengths_of_points(&kept), &guides);
    let f = hairstyle::formats::Format::from_path(Path::new(&format!("x.{}", protocol::FORMATS[format]))).expect("known extension");
    // thickness (USD `widths`) from the scene's hair type
    let mut curves = curves;
    curves.thickness = Some(vec![scene.hair_type.major_diameter as f32; curves.num_points()]);
    f.write(&curves).map_err(|e| format!("cannot write {}: {e}", protocol::FORMATS[format]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn accepted_connections_send_without_nagle_delays() {
        // Every connection the server accepts has TCP_NODELAY (a FRAME must not wait for the ACK of the one
        // before: a viewer that only reads acknowledges late). Without it, `nodelay()` hands out a socket
        // with the option off (Linux's default) and this fails.
        use axum::serve::Listener;
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let mut listener = nodelay(listener);
        let client = tokio::net::TcpStream::connect(addr).await.unwrap();
        assert!(!client.nodelay().unwrap(), "the default is off (else this test proves nothing)");
        let (served, _) = listener.accept().await;
        assert!(served.nodelay().unwrap());
    }
}
