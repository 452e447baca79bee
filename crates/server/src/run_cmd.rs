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
    /// Render strands of the built-in hairstyle the server ran (as `coiffure serve`).
    #[arg(long, default_value_t = 100_000)]
    render_strands: usize,
    /// Guide strands the server ran (as `coiffure serve`).
    #[arg(long, default_value_t = 200)]
    guides: usize,
    /// Real hairs per render strand the server ran with (as `coiffure serve`).
    #[arg(long, default_value_t = 1.0)]
    hairs_per_render_strand: f64,
}

/// `coiffure replay RECORD`: the recorded session replayed headless into `force.csv`, `summary.txt` and
/// `summary.json` (the outputs of a `[live]` scenario).
pub fn replay(args: &ReplayArgs) -> Result<()> {
    let bytes = std::fs::read(&args.record).with_context(|| format!("cannot read the record {}", args.record.display()))?;
    let rec = engine::record::Record::from_bytes(&bytes).with_context(|| format!("{}", args.record.display()))?;
    let opts = engine::session::SceneOptions { render_strands: args.render_strands, guides: args.guides, ..Default::default() };
    let scene = Arc::new(engine::session::Scene::builtin(&opts)?);
    let params = engine::session::SessionParams { hairs_per_render_strand: args.hairs_per_render_strand, ..Default::default() };
    params.validate().context("--hairs-per-render-strand")?;
    let (force, summary) = engine::scenario::live::replay_record(scene, params, &rec)?;
    let o = ScenarioOutput { kind: "replay", wall_time_s: summary.wall_time_s, force, global_rows: vec![], profile: Default::default(), summary: ScenarioSummary::Live(summary), hair: None };
    let stem = args.record.file_stem().and_then(|s| s.to_str()).unwrap_or("replay").to_string();
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&stem));
    let head = format!(
        "record          {} ({} haptic steps at {} Hz, {} global steps)\nscene           built-in head, {} render strands, {} guides\n",
        args.record.display(), rec.steps.len(), rec.rate_hz, rec.global_inputs.len(), args.render_strands, args.guides
    );
    print!("{}", engine::scenario::write_replay(&o, &head, &out)?);
    Ok(())
}
