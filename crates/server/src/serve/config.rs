//! `coiffure serve`'s arguments, and their validation into the [`Config`] the server runs with.

use super::access::{new_token, Access};
use anyhow::{anyhow, Context};
use clap::Args;
use engine::session::{InputKind, SceneOptions, SessionParams};
use haptics::device::DeviceProfile;
use haptics::udp::{UdpDevice, UdpParams, UdpStatus};
use haptics::workspace::Workspace;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

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
    /// Do not hold the CPUs' wake-up latency at 0 while serving (`SessionParams::cpu_latency_hold`, Linux PM QoS
    /// through /dev/cpu_dma_latency, root only): by default idle CPUs poll instead of halting, so that the device
    /// loop's timer wakes it on time (bench/RESULTS.md); this flag saves an idle CPU's power instead.
    #[arg(long)]
    pub no_cpu_latency_hold: bool,
    /// Run the haptic loop without its strand budget (`SessionParams::budget`, docs/protocol.md "Strand budget"): always
    /// up to 56 strands near the tool, however long the steps take on this machine (for benchmarks).
    #[arg(long)]
    pub no_strand_budget: bool,
    /// The strand budget's floor, strands (`BudgetParams::min_strands`, default 16): the fewest strands near the
    /// tool the budget leaves simulated on a slow host; the budget also starts here if `BudgetParams::start`
    /// is below it.
    #[arg(long)]
    pub min_strands: Option<usize>,
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


/// What `coiffure serve` runs with: its arguments checked (each error names its option).
pub(super) struct Config {
    /// The built viewer's folder.
    pub web: PathBuf,
    /// Who may open `/ws` and `/debug/carried`.
    pub access: Access,
    /// A viewer's time limit (`--viewer-timeout`).
    pub viewer_timeout: Duration,
    /// Options of the built-in scene (and of a loaded hairstyle's).
    pub opts: SceneOptions,
    /// Parameters every session of this server starts with.
    pub params: SessionParams,
    /// Real-time priority of the haptic thread, if any.
    pub haptic_priority: Option<i32>,
    /// `--device`: the bound UDP device and its counters.
    pub udp: Option<(UdpDevice, Arc<UdpStatus>)>,
}

impl Config {
    /// Checks `args` (ranges, token, device profile and workspace) and binds the device socket of `--device`.
    pub fn from_args(args: &ServeArgs) -> anyhow::Result<Config> {
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
        let mut opts = SceneOptions { render_strands: args.render_strands, guides: args.guides, ..SceneOptions::default() };
        match args.load_budget {
            None => {}
            Some(t) if t.is_finite() && t >= 0.0 && t <= 3600.0 => opts.load.max_seconds = t,
            Some(t) => return Err(anyhow!("--load-budget must be in [0, 3600] s, got {t}")),
        }
        let haptic_priority = (args.haptic_priority != 0).then_some(args.haptic_priority);
        let profile = device_profile(&args.device_profile)?;
        let input = if args.device.is_some() { InputKind::Device } else { InputKind::Pointer };
        let mut params = SessionParams { haptic_priority, hairs_per_render_strand: args.hairs_per_render_strand, haptic_rate_hz: args.haptic_rate, device_rate_hz: args.device_rate, profile, input, cpu_latency_hold: !args.no_cpu_latency_hold, ..SessionParams::default() };
        if let Some(lag) = args.max_proxy_lag {
            params.haptic.max_proxy_lag = lag;
        }
        params.budget.enabled = !args.no_strand_budget;
        if let Some(n) = args.min_strands {
            params.budget.min_strands = n;
            params.budget.start = params.budget.start.max(n);
        }
        params.validate().context("--hairs-per-render-strand, --haptic-rate, --device-rate, --max-proxy-lag, --min-strands")?;
        let udp = match &args.device {
            Some(spec) => Some(bind_device(spec, args, &profile)?),
            None => None,
        };
        Ok(Config { web, access, viewer_timeout, opts, params, haptic_priority, udp })
    }
}

/// Binds `--device`'s UDP socket with the profile's workspace (or `--device-workspace`) and prints where.
fn bind_device(spec: &str, args: &ServeArgs, profile: &DeviceProfile) -> anyhow::Result<(UdpDevice, Arc<UdpStatus>)> {
    let addr = parse_device(spec)?;
    let workspace = match &args.device_workspace {
        Some(w) => Workspace::parse(w, profile).map_err(|e| anyhow!("--device-workspace: {e}"))?,
        None => Workspace::for_profile(profile),
    };
    let dev = UdpDevice::bind_with(&addr.to_string(), UdpParams { workspace, ..UdpParams::for_profile(profile) }).with_context(|| format!("cannot bind the device socket {addr}"))?;
    let local = dev.local_addr()?;
    println!(
        "coiffure serve: device on udp:{local} ({}, {:.1} N; workspace: head = ({:.3}, {:.3}, {:.3}) m + {} x device; device loop {} Hz)",
        profile.name, profile.max_force, workspace.offset.x, workspace.offset.y, workspace.offset.z, workspace.scale, args.device_rate
    );
    let status = dev.status();
    Ok((dev, status))
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
