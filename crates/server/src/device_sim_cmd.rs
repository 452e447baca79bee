//! `coiffure device-sim`: a simulated haptic device and hand streaming the UDP protocol to a
//! `coiffure serve --device` (`haptics::sim`): the tool path of a scenario file, followed exactly or by a hand
//! pulled by a spring, with faults injected on request; writes what it sent and felt as CSV.

use anyhow::{anyhow, Context};
use clap::Args;
use engine::scenario::LiveScenario;
use haptics::device::DeviceProfile;
use haptics::sim::{self, Faults, Hand, SimParams, SimSummary};
use haptics::workspace::Workspace;
use std::path::PathBuf;

/// Arguments of `coiffure device-sim`.
#[derive(Debug, Args)]
pub struct DeviceSimArgs {
    /// Where `coiffure serve --device` listens: udp:PORT (127.0.0.1) or udp:ADDR:PORT.
    #[arg(long)]
    pub server: String,
    /// A live scenario file (docs/scenarios.md): its `[tool] path` waypoints `{ t, position, rotation,
    /// pressed }` (head frame) are the path; t = 0 is the start of the stream.
    #[arg(long)]
    pub path: PathBuf,
    /// Poses sent per second, Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate: f64,
    /// Length of the run, s (default: the path's last waypoint + 0.2 s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Play the path forward, then backward, and so on until `--duration` (a long session from a short path:
    /// the hand never jumps).
    #[arg(long)]
    pub repeat: bool,
    /// `rigid` (the end-effector follows the path exactly) or `spring` (a hand pulls it towards the path;
    /// the device's mass and damping and the received force act on it).
    #[arg(long, default_value = "rigid")]
    pub hand: String,
    /// Hand stiffness of `--hand spring`, N/m.
    #[arg(long, default_value_t = sim::DEFAULT_HAND_STIFFNESS)]
    pub hand_stiffness: f64,
    /// Hand damping of `--hand spring`, N s/m.
    #[arg(long, default_value_t = sim::DEFAULT_HAND_DAMPING)]
    pub hand_damping: f64,
    /// Device profile (the end-effector's mass and damping; the default workspace): as `serve`.
    #[arg(long, default_value = "phantom-omni")]
    pub device_profile: String,
    /// Device workspace to head frame, as `serve --device-workspace` (must be the server's).
    #[arg(long)]
    pub device_workspace: Option<String>,
    /// Write `t,x,y,z,fx,fy,fz,latency_us,flags` (one row per packet sent; device frame; the time and the
    /// forces received exactly, as the shortest decimals that read back to the same f64) to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Fraction of poses dropped at random, in [0, 1).
    #[arg(long, default_value_t = 0.0)]
    pub loss: f64,
    /// Seed of the random loss.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Send one pose with a NaN position at this time, s (repeatable).
    #[arg(long)]
    pub nan_at: Vec<f64>,
    /// Send one pose 10 m away at this time, s (repeatable).
    #[arg(long)]
    pub teleport_at: Vec<f64>,
    /// Send the previous packet again at this time, s (repeatable).
    #[arg(long)]
    pub duplicate_at: Vec<f64>,
    /// Send nothing from START for LENGTH s: `START:LENGTH` (repeatable).
    #[arg(long)]
    pub pause: Vec<String>,
    /// Speak protocol version 2 (CFP2 poses, answers with the local force model) and render the model at
    /// `--rate` with the device's own coupling, as a device program would (docs/protocol.md); the trace's
    /// hx,hy,hz columns are the force the hand felt.
    #[arg(long)]
    pub render: bool,
}

/// Runs `coiffure device-sim`.
pub fn run(args: &DeviceSimArgs) -> anyhow::Result<()> {
    let server = crate::serve::parse_device(&args.server).map_err(|e| anyhow!("--server: {e}"))?;
    let text = std::fs::read_to_string(&args.path).with_context(|| format!("cannot read {}", args.path.display()))?;
    let scenario: LiveScenario = toml::from_str(&text).with_context(|| format!("{}: not a live scenario with a [tool] path", args.path.display()))?;
    scenario.validate().map_err(|e| anyhow!("{}: {e}", args.path.display()))?;
    let profile = DeviceProfile::by_name(&args.device_profile).ok_or_else(|| anyhow!("--device-profile {:?}: expected phantom-omni, phantom-desktop, omega3 or phantom-premium-6dof", args.device_profile))?;
    let workspace = match &args.device_workspace {
        Some(w) => Workspace::parse(w, &profile).map_err(|e| anyhow!("--device-workspace: {e}"))?,
        None => Workspace::for_profile(&profile),
    };
    let hand = match args.hand.as_str() {
        "rigid" => Hand::Rigid,
        "spring" => Hand::Spring { stiffness: args.hand_stiffness, damping: args.hand_damping },
        h => return Err(anyhow!("--hand {h:?}: expected rigid or spring")),
    };
    let pause = args
        .pause
        .iter()
        .map(|p| {
            let (a, b) = p.split_once(':').ok_or_else(|| anyhow!("--pause {p:?}: expected START:LENGTH (s)"))?;
            Ok((a.trim().parse::<f64>().map_err(|e| anyhow!("--pause {p:?}: {e}"))?, b.trim().parse::<f64>().map_err(|e| anyhow!("--pause {p:?}: {e}"))?))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let end = scenario.tool.path.last().map_or(0.0, |w| w.t);
    if args.repeat && (args.duration.is_none() || end <= 0.0) {
        return Err(anyhow!("--repeat needs --duration and a path longer than 0 s"));
    }
    let params = SimParams {
        rate_hz: args.rate,
        duration: args.duration.unwrap_or(end + 0.2),
        hand,
        profile,
        workspace,
        faults: Faults { loss: args.loss, seed: args.seed, nan_at: args.nan_at.clone(), teleport_at: args.teleport_at.clone(), duplicate_at: args.duplicate_at.clone(), pause },
        render: args.render,
    };
    // With --repeat, path time runs back and forth over [0, end].
    let path_time = |t: f64| if args.repeat { end - (t.rem_euclid(2.0 * end) - end).abs() } else { t };
    let rows = sim::run(server, &|t| scenario.reading(path_time(t)), &params).map_err(|e| anyhow!(e))?;
    if let Some(out) = &args.out {
        crate::ensure_parent(out)?;
        hairstyle::formats::write_atomic(out, sim::to_csv(&rows).as_bytes()).with_context(|| format!("cannot write {}", out.display()))?;
    }
    println!("device-sim: {}", SimSummary::of(&rows));
    Ok(())
}
