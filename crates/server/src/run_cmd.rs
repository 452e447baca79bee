//! `coiffure run SCENARIO.toml`: a scenario of any kind (patch, global tools, `[live]`), headless; writes
//! its trace, `summary.txt` and `summary.json` (the engine's in-memory output, `engine::scenario::run`).
//! `coiffure replay RECORD`: a `coiffure serve --record` file replayed into the outputs of a live scenario.

use anyhow::{bail, Context, Result};
use clap::Args;
use engine::path::{ToolPath, Waypoint};
use engine::scenario::{GlobalScenario, LiveScenario, Scenario, ScenarioFile, ScenarioOutput, ScenarioSummary};
use std::io::Write;
use std::sync::Arc;
use std::path::{Path, PathBuf};
use tools::shape::ToolShape;

/// Arguments of `coiffure run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scenario file (TOML; see docs/scenarios.md).
    scenario: PathBuf,
    /// Output folder (default: a folder named after the scenario in the current directory).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Reads a tool path CSV `t,x,y,z[,rx,ry,rz]` (header line required), naming the line of any error.
fn read_path_csv(path: &Path) -> Result<Vec<Waypoint>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read tool path {}", path.display()))?;
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim().starts_with("t,x,y,z") => {}
        _ => bail!("{}: line 1 must be the header t,x,y,z[,rx,ry,rz]", path.display()),
    }
    let mut out = vec![];
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .with_context(|| format!("{}: line {}: not a number", path.display(), i + 1))?;
        if v.len() != 4 && v.len() != 7 {
            bail!("{}: line {}: expected 4 or 7 values, got {}", path.display(), i + 1, v.len());
        }
        let rotation = if v.len() == 7 { [v[4], v[5], v[6]] } else { [0.0; 3] };
        out.push(Waypoint { t: v[0], position: [v[1], v[2], v[3]], rotation });
    }
    Ok(out)
}

pub fn run(args: &RunArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.scenario).with_context(|| format!("cannot read scenario {}", args.scenario.display()))?;
    let file = ScenarioFile::from_toml(&text).with_context(|| format!("malformed scenario {}", args.scenario.display()))?;
    let stem = args.scenario.file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let name = file.name().map(str::to_string).unwrap_or(stem);
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&name));
    match &file {
        ScenarioFile::Patch(s) => run_patch(args, s, &name, &out),
        ScenarioFile::Global(s) => run_global(s, &name, &out, engine::scenario::run(&file)?),
        ScenarioFile::Live(s) => run_live(s, &name, &out, engine::scenario::run(&file)?),
    }
}

/// Writes `summary.json` (the summary as the engine serialises it, with the kind).
fn write_json(out: &Path, o: &ScenarioOutput) -> Result<()> {
    #[derive(serde::Serialize)]
    struct J<'a> {
        kind: &'a str,
        #[serde(flatten)]
        summary: &'a ScenarioSummary,
    }
    let text = serde_json::to_string_pretty(&J { kind: o.kind, summary: &o.summary })?;
    let p = out.join("summary.json");
    std::fs::write(&p, text + "\n").with_context(|| format!("cannot write {}", p.display()))
}

/// Writes `force.csv`.
fn write_force(out: &Path, o: &ScenarioOutput) -> Result<PathBuf> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let p = out.join("force.csv");
    std::fs::write(&p, o.force.to_csv()).with_context(|| format!("cannot write {}", p.display()))?;
    Ok(p)
}

fn run_patch(args: &RunArgs, scenario: &Scenario, name: &str, out: &Path) -> Result<()> {
    let dir = args.scenario.parent().unwrap_or(Path::new("."));
    let shape = match ToolShape::builtin(&scenario.tool.shape) {
        Ok(s) => s,
        Err(_) => {
            let p = dir.join(&scenario.tool.shape);
            let t = std::fs::read_to_string(&p).with_context(|| format!("tool.shape {:?} is neither built in nor a readable file ({})", scenario.tool.shape, p.display()))?;
            ToolShape::from_toml(&t).with_context(|| format!("tool shape {}", p.display()))?
        }
    };
    let waypoints = match (&scenario.tool.path_file, scenario.tool.path.is_empty()) {
        (Some(f), true) => read_path_csv(&dir.join(f))?,
        (None, false) => scenario.tool.path.clone(),
        (Some(_), false) => bail!("give tool.path or tool.path_file, not both"),
        (None, true) => bail!("the tool needs a path: tool.path or tool.path_file"),
    };
    let path = ToolPath::new(waypoints).map_err(|e| anyhow::anyhow!("tool path: {e}"))?;
    let o = engine::scenario::run_patch(scenario, shape, &path)?;
    let ScenarioSummary::Patch(summary) = &o.summary else { unreachable!("a patch run gives a patch summary") };
    let wall = o.wall_time_s;
    let trace_path = write_force(out, &o)?;
    write_json(out, &o)?;
    let text = format!(
        "scenario        {name}\nhair type       {} ({} strands x {} segments, {:?} model), each standing for {:.1} hairs; tress {:.3} g\n\
         tool            {} ({} force model)\nsteps           {} at {} s ({} with contact, {} clamped by the safety net)\n\
         peak force      {:.4e} N\nmean force      {:.4e} N (over steps with contact)\nwork            {:.4e} J\nwall time       {:.2} s\ntrace           {}\n",
        scenario.patch.hair_type,
        scenario.patch.strands,
        scenario.patch.segments,
        scenario.patch.model,
        summary.represents,
        summary.tress_mass * 1e3,
        scenario.tool.shape,
        scenario.tool.force_model,
        summary.steps,
        scenario.dt,
        summary.contact_steps,
        summary.clamped_steps,
        summary.peak_force,
        summary.mean_force,
        summary.work,
        wall,
        trace_path.display()
    );
    std::fs::write(out.join("summary.txt"), &text).with_context(|| format!("cannot write {}", out.join("summary.txt").display()))?;
    print!("{text}");
    Ok(())
}

/// `coiffure run` for a global-tool scenario: writes `wetness.csv`, `summary.txt`, `hairstyle.hair` (the final
/// render strands) and `pieces.hair` (the cut pieces where they came to rest).
fn run_global(scenario: &GlobalScenario, name: &str, out: &Path, o: ScenarioOutput) -> Result<()> {
    let wall = o.wall_time_s;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    write_json(out, &o)?;
    let ScenarioSummary::Global(s) = &o.summary else { unreachable!("a global run gives a global summary") };
    let (hair, pieces) = o.hair.as_ref().expect("a global run gives the hairstyle");
    let trace_path = out.join("wetness.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&trace_path).with_context(|| format!("cannot write {}", trace_path.display()))?);
    writeln!(w, "t,wetness_mean,wetness_min,wetness_max,guides_in_cone,blow_force,cluster_energy,mean_tip_z")?;
    for r in &o.global_rows {
        writeln!(
            w,
            "{:.4},{:.6e},{:.6e},{:.6e},{},{:.6e},{:.6e},{:.6e}",
            r.t, r.wetness[0], r.wetness[1], r.wetness[2], r.in_cone, r.blow_force, r.cluster_energy, r.mean_tip_z
        )?;
    }
    w.flush()?;
    let hair_path = out.join("hairstyle.hair");
    hairstyle::write_file(&hair_path, hair)?;
    let pieces_path = out.join("pieces.hair");
    hairstyle::write_file(&pieces_path, pieces)?;
    let h = &scenario.hairstyle;
    let text = format!(
        "scenario        {name}\n\
         hairstyle       {} hair, {:.3} m, {} guides x {} segments, {} render strands\n\
         steps           {} global steps of {} s ({} lattice recoveries)\n\
         wetness before  {:.6}\n\
         wetness after   {:.6} (min {:.6}, max {:.6})\n\
         render cut      {} (mean length {:.6} m -> {:.6} m)\n\
         render mass     {:.9e} kg before (strands cut); {:.9e} kg on head + {:.9e} kg cut = {:.9e} kg\n\
         clusters        {} (kinetic energy at the end {:.3e} J; largest body field at a piece point {:.4}, surface 0.25)\n\
         lattice         largest node displacement by the tools {:.3e} m (end {:.3e} m), peak dryer force {:.3e} N\n\
         wall time       {:.2} s\n\
         outputs         {}, {}, {}\n",
        h.hair_type,
        h.length,
        s.guides,
        h.segments,
        s.render_strands,
        s.steps,
        scenario.global_dt,
        s.recovered_steps,
        s.wetness_before,
        s.wetness_after,
        s.wetness_range_after[0],
        s.wetness_range_after[1],
        s.render_cut,
        s.render_length_before,
        s.render_length_after,
        s.render_mass_before,
        s.render_mass_on_head,
        s.render_mass_cut,
        s.render_mass_on_head + s.render_mass_cut,
        s.clusters,
        s.cluster_energy,
        s.pieces_max_field,
        s.lattice_max_displacement,
        s.lattice_end_displacement,
        s.lattice_peak_force,
        wall,
        trace_path.display(),
        hair_path.display(),
        pieces_path.display(),
    );
    std::fs::write(out.join("summary.txt"), &text).with_context(|| format!("cannot write {}", out.join("summary.txt").display()))?;
    print!("{text}");
    Ok(())
}

/// `coiffure run` for a `[live]` scenario: `force.csv`, `summary.txt`, `summary.json`.
fn run_live(scenario: &LiveScenario, name: &str, out: &Path, o: ScenarioOutput) -> Result<()> {
    let trace_path = write_force(out, &o)?;
    write_json(out, &o)?;
    let l = &scenario.live;
    let head = format!(
        "scenario        {name} (live session, lockstep)\n\
         scene           built-in head, {} render strands, {} guides, {} hair (curliness {}, combing ease {}, wetness {})\n\
         tool            {} on a {} device\n",
        l.render_strands, l.guides, l.hair_type, l.curliness, l.combing_ease, l.wetness, scenario.tool.shape, l.device
    );
    finish_live(out, &o, &head, &trace_path)
}

/// Writes `summary.txt` of a live run or a replay and prints it.
fn finish_live(out: &Path, o: &ScenarioOutput, head: &str, trace_path: &Path) -> Result<()> {
    let ScenarioSummary::Live(s) = &o.summary else { unreachable!("a live run gives a live summary") };
    let text = format!(
        "{head}steps           {} haptic steps ({} with contact, {} at the device's force limit; {} readings rejected, {} strand steps failed)\n\
         peak force      {:.4e} N\n\
         mean force      {:.4e} N (over steps with contact)\n\
         displacement    largest {:.4e} m during the run, {:.4e} m during the stroke, {:.4e} m at the end (guide points from their settled positions)\n\
         continuity      {} steps with the tool in the hair, {:.1} % of them above 5 mN; largest one-step change {:.4e} N; fastest strand tip {:.3} m/s\n\
         haptic step     p50 {:.1} us, p99 {:.1} us, p99.9 {:.1} us, mean {:.1} us (one thread, lockstep)\n\
         wall time       {:.2} s\n\
         outputs         {}, {}, {}\n",
        s.steps, s.contact_steps, s.clamp_steps, s.rejected_readings, s.failed_steps,
        s.peak_force_n, s.mean_force_n, s.max_displacement_m, s.stroke_max_displacement_m, s.final_max_displacement_m,
        s.in_hair_steps, 100.0 * s.in_hair_force_share, s.max_force_change_n, s.max_strand_speed_m_s, s.haptic_step_p50_us, s.haptic_step_p99_us, s.haptic_step_p999_us, s.haptic_step_mean_us, s.wall_time_s,
        trace_path.display(), out.join("summary.txt").display(), out.join("summary.json").display()
    );
    std::fs::write(out.join("summary.txt"), &text).with_context(|| format!("cannot write {}", out.join("summary.txt").display()))?;
    print!("{text}");
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
    let o = ScenarioOutput { kind: "replay", wall_time_s: summary.wall_time_s, force, global_rows: vec![], summary: ScenarioSummary::Live(summary), hair: None };
    let stem = args.record.file_stem().and_then(|s| s.to_str()).unwrap_or("replay").to_string();
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&stem));
    let trace_path = write_force(&out, &o)?;
    write_json(&out, &o)?;
    let head = format!(
        "record          {} ({} haptic steps at {} Hz, {} global steps)\nscene           built-in head, {} render strands, {} guides\n",
        args.record.display(), rec.steps.len(), rec.rate_hz, rec.global_inputs.len(), args.render_strands, args.guides
    );
    finish_live(&out, &o, &head, &trace_path)
}
