//! A scenario's files: the tool shape and path files a patch scenario names (read relative to the
//! scenario's folder), and everything `coiffure run --out DIR` writes. The CLI and the Python binding both
//! call [`run_in`] and [`write_output`], so a run gives the same files whichever door it came through.

use super::global::GlobalScenario;
use super::live::LiveScenario;
use super::patch::Scenario;
use super::run::{run, run_patch, ScenarioFile, ScenarioOutput, ScenarioSummary};
use super::ScenarioError;
use crate::path::{ToolPath, Waypoint};
use std::fmt::Write as _;
use std::path::Path;
use tools::shape::ToolShape;

fn io_err(path: &Path, what: impl std::fmt::Display) -> ScenarioError {
    ScenarioError::File { path: path.to_path_buf(), message: what.to_string() }
}

/// Reads a tool path CSV `t,x,y,z[,rx,ry,rz]` (s, m, rotation vector in rad; header line required); errors
/// name the file and line.
pub fn read_path_csv(path: &Path) -> Result<Vec<Waypoint>, ScenarioError> {
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, format!("cannot read tool path: {e}")))?;
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim().starts_with("t,x,y,z") => {}
        _ => return Err(io_err(path, "line 1 must be the header t,x,y,z[,rx,ry,rz]")),
    }
    let mut out = vec![];
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| io_err(path, format!("line {}: not a number", i + 1)))?;
        if v.len() != 4 && v.len() != 7 {
            return Err(io_err(path, format!("line {}: expected 4 or 7 values, got {}", i + 1, v.len())));
        }
        let rotation = if v.len() == 7 { [v[4], v[5], v[6]] } else { [0.0; 3] };
        out.push(Waypoint { t: v[0], position: [v[1], v[2], v[3]], rotation });
    }
    Ok(out)
}

/// A patch scenario's tool: its shape (built in, or a shape TOML file relative to `dir`) and its path
/// (`tool.path` inline, or `tool.path_file`, a CSV relative to `dir`).
pub fn load_tool(s: &Scenario, dir: &Path) -> Result<(ToolShape, ToolPath), ScenarioError> {
    let shape = match ToolShape::builtin(&s.tool.shape) {
        Ok(shape) => shape,
        Err(_) => {
            let p = dir.join(&s.tool.shape);
            let t = std::fs::read_to_string(&p)
                .map_err(|e| ScenarioError::Invalid(format!("tool.shape {:?} is neither built in nor a readable file ({}: {e})", s.tool.shape, p.display())))?;
            ToolShape::from_toml(&t).map_err(|e| io_err(&p, format!("tool shape: {e}")))?
        }
    };
    let waypoints = match (&s.tool.path_file, s.tool.path.is_empty()) {
        (Some(f), true) => read_path_csv(&dir.join(f))?,
        (None, false) => s.tool.path.clone(),
        (Some(_), false) => return Err(ScenarioError::Invalid("give tool.path or tool.path_file, not both".into())),
        (None, true) => return Err(ScenarioError::Invalid("the tool needs a path: tool.path or tool.path_file".into())),
    };
    let path = ToolPath::new(waypoints).map_err(|e| ScenarioError::Invalid(format!("tool path: {e}")))?;
    Ok((shape, path))
}

/// Runs a scenario whose relative file names (tool shape and path files, a `[live] hairstyle`) are looked
/// up in `dir`.
pub fn run_in(file: &ScenarioFile, dir: &Path) -> Result<ScenarioOutput, ScenarioError> {
    match file {
        ScenarioFile::Patch(s) => {
            let (shape, path) = load_tool(s, dir)?;
            run_patch(s, shape, &path)
        }
        ScenarioFile::Live(s) => super::run::run_live_on(s, std::sync::Arc::new(s.scene_in(dir)?)),
        other => run(other),
    }
}

/// Writes what `coiffure run SCENARIO --out DIR` writes for `output`, a run of `file` named `name`:
/// `summary.json` always; `force.csv` (patch, live); `profile.csv` (patch: the combing rig's recording); `wetness.csv`, `hairstyle.hair`, `pieces.hair`
/// (global); and `summary.txt`, whose text is returned (the CLI prints it).
pub fn write_output(file: &ScenarioFile, output: &ScenarioOutput, name: &str, out: &Path) -> Result<String, ScenarioError> {
    std::fs::create_dir_all(out).map_err(|e| io_err(out, format!("cannot create: {e}")))?;
    write_json(out, output)?;
    let text = match file {
        ScenarioFile::Patch(s) => patch_text(s, output, name, &write_force(out, output)?, &write_profile(out, output)?),
        ScenarioFile::Global(s) => write_global(s, output, name, out)?,
        ScenarioFile::Live(s) => {
            let trace = write_force(out, output)?;
            live_text(&live_head(s, name), output, &trace, out)
        }
    };
    write_text(out, &text)?;
    Ok(text)
}

/// Writes the outputs of a replayed record (those of a `[live]` scenario) with `head`, the lines that say
/// what was replayed; returns the `summary.txt` text.
pub fn write_replay(output: &ScenarioOutput, head: &str, out: &Path) -> Result<String, ScenarioError> {
    std::fs::create_dir_all(out).map_err(|e| io_err(out, format!("cannot create: {e}")))?;
    write_json(out, output)?;
    let trace = write_force(out, output)?;
    let text = live_text(head, output, &trace, out);
    write_text(out, &text)?;
    Ok(text)
}

/// Writes `device_force.csv` in `out` (the force of every device step of a replayed record,
/// [`super::live::DeviceTrace::to_csv`]); returns its path.
pub fn write_device_force(out: &Path, device: &super::live::DeviceTrace) -> Result<std::path::PathBuf, ScenarioError> {
    let p = out.join("device_force.csv");
    write(&p, device.to_csv().as_bytes())?;
    Ok(p)
}

/// Writes one output file whole (`hairstyle::formats::write_atomic`: never half-written under its name).
fn write(p: &Path, bytes: &[u8]) -> Result<(), ScenarioError> {
    hairstyle::formats::write_atomic(p, bytes).map_err(|e| io_err(p, format!("cannot write: {e}")))
}

fn write_text(out: &Path, text: &str) -> Result<(), ScenarioError> {
    let p = out.join("summary.txt");
    write(&p, text.as_bytes())
}

/// The contents of `summary.json`: the summary's fields and `kind` ("patch", "global", "live", "replay").
pub fn summary_json(o: &ScenarioOutput) -> serde_json::Value {
    #[derive(serde::Serialize)]
    struct J<'a> {
        kind: &'a str,
        #[serde(flatten)]
        summary: &'a ScenarioSummary,
    }
    serde_json::to_value(J { kind: o.kind, summary: &o.summary }).expect("a summary of numbers and strings serialises")
}

/// Writes `summary.json` ([`summary_json`]).
fn write_json(out: &Path, o: &ScenarioOutput) -> Result<(), ScenarioError> {
    let p = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary_json(o)).map_err(|e| io_err(&p, e))?;
    write(&p, (text + "\n").as_bytes())
}

/// `force.csv`; returns its path.
fn write_force(out: &Path, o: &ScenarioOutput) -> Result<std::path::PathBuf, ScenarioError> {
    let p = out.join("force.csv");
    write(&p, o.force.to_csv().as_bytes())?;
    Ok(p)
}

/// `profile.csv` (a combing rig's recording, [`super::combing::CombingProfile::to_csv`]); returns its path.
fn write_profile(out: &Path, o: &ScenarioOutput) -> Result<std::path::PathBuf, ScenarioError> {
    let p = out.join("profile.csv");
    write(&p, o.profile.to_csv().as_bytes())?;
    Ok(p)
}

/// The combing rig's lines of a patch run's `summary.txt`: all strokes, then each stroke if there are several.
fn combing_text(summary: &super::patch::Summary) -> String {
    let line = |label: &str, work: f64, peak: f64, mean: f64, fifths: &[f64; 5]| {
        let f: Vec<String> = fifths.iter().map(|x| format!("{x:.3e}")).collect();
        format!("{label:<16}work {work:.4e} J, peak {peak:.4e} N, mean {mean:.4e} N; work by fifth from the roots {} J\n", f.join(" "))
    };
    let c = &summary.combing;
    let mut text = line("combing", c.combing_work_j, c.combing_peak_n, c.combing_mean_n, &c.work_fifths_j);
    let p = &summary.per_stroke;
    if summary.strokes > 1 {
        for i in 0..p.combing_work_j.len() {
            text += &line(&format!("  stroke {}", i + 1), p.combing_work_j[i], p.combing_peak_n[i], p.combing_mean_n[i], &p.work_fifths_j[i]);
        }
    }
    text
}

fn patch_text(s: &Scenario, o: &ScenarioOutput, name: &str, trace: &Path, profile: &Path) -> String {
    let ScenarioSummary::Patch(summary) = &o.summary else { unreachable!("a patch run gives a patch summary") };
    format!(
        "scenario        {name}\nhair type       {} ({} strands x {} segments, {:?} model), each standing for {:.1} hairs; tress {:.3} g\n\
         tool            {} ({} force model)\nsteps           {} at {} s ({} with contact, {} clamped by the safety net)\n\
         peak force      {:.4e} N\nmean force      {:.4e} N (over steps with contact)\nwork            {:.4e} J\n{}wall time       {:.2} s\ntrace           {}\nprofile         {}\n",
        s.patch.hair_type,
        s.patch.strands,
        s.patch.segments,
        s.patch.model,
        summary.represents,
        summary.tress_mass_kg * 1e3,
        s.tool.shape,
        s.tool.force_model,
        summary.steps,
        s.dt,
        summary.contact_steps,
        summary.strand_clamped_steps,
        summary.peak_force_n,
        summary.mean_force_n,
        summary.work_j,
        combing_text(summary),
        o.wall_time_s,
        trace.display(),
        profile.display()
    )
}

/// A global-tool scenario's files: `wetness.csv`, `hairstyle.hair` (the final render strands) and
/// `pieces.hair` (the cut pieces where they came to rest); returns the `summary.txt` text.
fn write_global(scenario: &GlobalScenario, o: &ScenarioOutput, name: &str, out: &Path) -> Result<String, ScenarioError> {
    let ScenarioSummary::Global(s) = &o.summary else { unreachable!("a global run gives a global summary") };
    let (hair, pieces) = o.hair.as_ref().expect("a global run gives the hairstyle");
    let trace_path = out.join("wetness.csv");
    let mut csv = String::from("t,wetness_mean,wetness_min,wetness_max,guides_in_cone,blow_force,cluster_energy,mean_tip_z\n");
    for r in &o.global_rows {
        let _ = writeln!(
            csv,
            "{:.4},{:.6e},{:.6e},{:.6e},{},{:.6e},{:.6e},{:.6e}",
            r.t, r.wetness[0], r.wetness[1], r.wetness[2], r.in_cone, r.blow_force, r.cluster_energy, r.mean_tip_z
        );
    }
    write(&trace_path, csv.as_bytes())?;
    let hair_path = out.join("hairstyle.hair");
    hairstyle::write_file(&hair_path, hair).map_err(|e| io_err(&hair_path, e))?;
    let pieces_path = out.join("pieces.hair");
    hairstyle::write_file(&pieces_path, pieces).map_err(|e| io_err(&pieces_path, e))?;
    let h = &scenario.hairstyle;
    Ok(format!(
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
        s.render_length_before_m,
        s.render_length_after_m,
        s.render_mass_before_kg,
        s.render_mass_on_head_kg,
        s.render_mass_cut_kg,
        s.render_mass_on_head_kg + s.render_mass_cut_kg,
        s.clusters,
        s.cluster_energy_j,
        s.pieces_max_field,
        s.lattice_max_displacement_m,
        s.lattice_end_displacement_m,
        s.lattice_peak_force_n,
        o.wall_time_s,
        trace_path.display(),
        hair_path.display(),
        pieces_path.display(),
    ))
}

fn live_head(scenario: &LiveScenario, name: &str) -> String {
    let l = &scenario.live;
    format!(
        "scenario        {name} (live session, lockstep)\n\
         scene           built-in head, {} render strands, {} guides, {} hair (curliness {}, combing ease {}, wetness {})\n\
         tool            {} on a {} device\n",
        l.render_strands, l.guides, l.hair_type, l.curliness, l.combing_ease, l.wetness, scenario.tool.shape, l.device
    )
}

/// The `summary.txt` text of a live run or a replay.
fn live_text(head: &str, o: &ScenarioOutput, trace: &Path, out: &Path) -> String {
    let ScenarioSummary::Live(s) = &o.summary else { unreachable!("a live run gives a live summary") };
    format!(
        "{head}steps           {} haptic steps ({} with contact, {} at the device's force limit; {} readings rejected, {} strand steps failed)\n\
         peak force      {:.4e} N\n\
         mean force      {:.4e} N (over steps with contact)\n\
         displacement    largest {:.4e} m during the run, {:.4e} m during the stroke, {:.4e} m at the end (guide points from their settled positions, relative to the head)\n\
         body            deepest sampled render vertex {:.4e} m inside the head and body as shown ({:.4e} m before the viewer's push-out)\n\
         continuity      {} steps with the tool in the hair (its path there {:.4} m; {} moving, at {:.3} m/s, {:.1} % of them above 5 mN), {:.1} % of them above 5 mN; largest one-step change {:.4e} N; fastest strand tip {:.3} m/s\n\
         haptic step     p50 {:.1} us, p99 {:.1} us, p99.9 {:.1} us, mean {:.1} us (one thread, lockstep)\n\
         wall time       {:.2} s\n\
         outputs         {}, {}, {}\n",
        s.steps, s.contact_steps, s.clamp_steps, s.rejected_readings, s.failed_steps,
        s.peak_force_n, s.mean_force_n, s.max_displacement_m, s.stroke_max_displacement_m, s.final_max_displacement_m, s.max_depth_in_body_m, s.max_depth_before_push_out_m,
        s.in_hair_steps, s.in_hair_path_m, s.stroke_steps, s.in_hair_speed_m_s, 100.0 * s.stroke_force_share, 100.0 * s.in_hair_force_share, s.max_force_change_n, s.max_strand_speed_m_s,
        s.haptic_step_p50_us, s.haptic_step_p99_us, s.haptic_step_p999_us, s.haptic_step_mean_us, s.wall_time_s,
        trace.display(), out.join("summary.txt").display(), out.join("summary.json").display()
    )
}
