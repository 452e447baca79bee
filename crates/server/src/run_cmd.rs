//! `coiffure run SCENARIO.toml`: a scenario of any kind (patch, global tools, `[live]`), headless; writes
//! its trace, `summary.txt` and `summary.json` (the engine's in-memory output, `engine::scenario::run`).
//! `coiffure replay RECORD`: a `coiffure serve --record` file replayed into the outputs of a live scenario.

use anyhow::{Context, Result};
use clap::Args;
use engine::scenario::{ScenarioFile, ScenarioOutput, ScenarioSummary};
use std::sync::Arc;
use std::path::{Path, PathBuf};

/// Arguments of `coiffure run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scenario file (TOML; see docs/scenarios.md).
    scenario: PathBuf,
    /// Output folder (default: a folder named after the scenario in the current directory).
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: &RunArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.scenario).with_context(|| format!("cannot read scenario {}", args.scenario.display()))?;
    let file = ScenarioFile::from_toml(&text).with_context(|| format!("malformed scenario {}", args.scenario.display()))?;
    let stem = args.scenario.file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let name = file.name().map(str::to_string).unwrap_or(stem);
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&name));
    let dir = args.scenario.parent().unwrap_or(Path::new("."));
    let o = engine::scenario::run_in(&file, dir)?;
    print!("{}", engine::scenario::write_output(&file, &o, &name, &out)?);
    Ok(())
}

/// Arguments of `coiffure replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// A record written by `coiffure serve --record FILE`.
    record: PathBuf,
    /// Output folder (default: a folder named after the record in the current directory).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Render strands of the built-in hairstyle (default: the record's, which says what the server ran).
    #[arg(long)]
    render_strands: Option<usize>,
    /// Guide strands (default: the record's).
    #[arg(long)]
    guides: Option<usize>,
    /// Real hairs per render strand (default: the record's).
    #[arg(long)]
    hairs_per_render_strand: Option<f64>,
}

/// `coiffure replay RECORD`: the recorded session replayed headless into `force.csv`, `summary.txt` and
/// `summary.json` (the outputs of a `[live]` scenario), and `device_force.csv` (the force of every device step). A record cut short (the server died, the disk filled)
/// is replayed up to its last whole chunk, and the output says where it was cut and what is lost.
pub fn replay(args: &ReplayArgs) -> Result<()> {
    let bytes = std::fs::read(&args.record).with_context(|| format!("cannot read the record {}", args.record.display()))?;
    let read = engine::record::Record::read(&bytes).with_context(|| format!("{}", args.record.display()))?;
    let ending = ending_lines(&read);
    let rec = read.record;
    // The scene and settings the server ran, from the record; the options override them.
    let settings = rec.settings.clone().unwrap_or_default();
    let mut opts = settings.scene_options();
    opts.render_strands = args.render_strands.unwrap_or(opts.render_strands);
    opts.guides = args.guides.unwrap_or(opts.guides);
    let scene = Arc::new(engine::session::Scene::builtin(&opts)?);
    let mut params = settings.session_params(rec.rate_hz).map_err(|e| anyhow::anyhow!("{}: the record's settings: {e}", args.record.display()))?;
    params.hairs_per_render_strand = args.hairs_per_render_strand.unwrap_or(params.hairs_per_render_strand);
    params.validate().context("--hairs-per-render-strand, or the record's settings")?;
    let (force, summary, device) = engine::scenario::live::replay_record(scene, params, &rec)?;
    let o = ScenarioOutput { kind: "replay", wall_time_s: summary.wall_time_s, force, global_rows: vec![], profile: Default::default(), summary: ScenarioSummary::Live(summary), hair: None };
    let stem = args.record.file_stem().and_then(|s| s.to_str()).unwrap_or("replay").to_string();
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&stem));
    let head = format!(
        "record          {} ({} haptic steps at {} Hz = {:.3} s, {} global steps)\n{ending}scene           built-in head, {} render strands, {} guides\n",
        args.record.display(), rec.steps.len(), rec.rate_hz, rec.seconds(), rec.global_inputs.len(), opts.render_strands, opts.guides
    );
    print!("{}", engine::scenario::write_replay(&o, &head, &out)?);
    // The force at the device loop's rate (what the device rendered; force.csv has one line per physics step).
    let p = engine::scenario::write_device_force(&out, &device)?;
    println!("device steps    {} (force sent at every device step: {})", device.time.len(), p.display());
    Ok(())
}

/// What the output says about how a record ends: nothing when whole; else where it stopped and what is lost.
fn ending_lines(read: &engine::record::ReadRecord) -> String {
    use engine::record::Ending;
    match &read.ending {
        Ending::Complete => String::new(),
        Ending::Stopped(why) => format!("record ending    recording stopped before the session ended: {why}\n"),
        Ending::Cut(c) => format!(
            "record ending    cut: read up to byte {} of {} ({} bytes lost): {}; the steps the session ran after that are lost (the server writes a chunk at least every {} s, so at most about that much if it died)\n",
            c.offset,
            c.file_bytes,
            c.file_bytes - c.offset,
            c.why,
            engine::record::RecordParams::default().flush_interval
        ),
    }
}
