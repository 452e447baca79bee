//! `coiffure run SCENARIO.toml`: a scripted tool session, headless; writes the force trace and a summary.

use anyhow::{bail, Context, Result};
use clap::Args;
use engine::path::{ToolPath, Waypoint};
use engine::scenario::{GlobalScenario, Scenario};
use std::io::Write;
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
    // A scenario with [[action]] tables (scissors, dryer, sprayer) is a global-tool scenario.
    let table: toml::Table = toml::from_str(&text).with_context(|| format!("malformed scenario {}", args.scenario.display()))?;
    if table.contains_key("action") || table.contains_key("hairstyle") {
        let scenario: GlobalScenario = toml::from_str(&text).with_context(|| format!("malformed scenario {}", args.scenario.display()))?;
        return run_global(args, &scenario);
    }
    let scenario: Scenario = toml::from_str(&text).with_context(|| format!("malformed scenario {}", args.scenario.display()))?;
    let dir = args.scenario.parent().unwrap_or(Path::new("."));
    let stem = args.scenario.file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let name = scenario.name.clone().unwrap_or(stem);
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
    let started = std::time::Instant::now();
    let (rows, summary) = scenario.run(shape, &path)?;
    let wall = started.elapsed().as_secs_f64();
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&name));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let trace_path = out.join("force.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&trace_path).with_context(|| format!("cannot write {}", trace_path.display()))?);
    writeln!(w, "t,fx,fy,fz,tx,ty,tz,contacts,tool_x,tool_y,tool_z")?;
    for r in &rows {
        writeln!(
            w,
            "{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{:.6e},{:.6e},{:.6e}",
            r.t, r.force.x, r.force.y, r.force.z, r.torque.x, r.torque.y, r.torque.z, r.contacts, r.tool.x, r.tool.y, r.tool.z
        )?;
    }
    w.flush()?;
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
fn run_global(args: &RunArgs, scenario: &GlobalScenario) -> Result<()> {
    let stem = args.scenario.file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let name = scenario.name.clone().unwrap_or(stem);
    let started = std::time::Instant::now();
    let out_data = scenario.run()?;
    let wall = started.elapsed().as_secs_f64();
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(&name));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let trace_path = out.join("wetness.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&trace_path).with_context(|| format!("cannot write {}", trace_path.display()))?);
    writeln!(w, "t,wetness_mean,wetness_min,wetness_max,guides_in_cone,blow_force,cluster_energy,mean_tip_z")?;
    for r in &out_data.rows {
        writeln!(
            w,
            "{:.4},{:.6e},{:.6e},{:.6e},{},{:.6e},{:.6e},{:.6e}",
            r.t, r.wetness[0], r.wetness[1], r.wetness[2], r.in_cone, r.blow_force, r.cluster_energy, r.mean_tip_z
        )?;
    }
    w.flush()?;
    let hair_path = out.join("hairstyle.hair");
    hairstyle::write_file(&hair_path, &out_data.hairstyle)?;
    let pieces_path = out.join("pieces.hair");
    hairstyle::write_file(&pieces_path, &out_data.pieces)?;
    let s = &out_data.summary;
    let h = &scenario.hairstyle;
    let text = format!(
        "scenario        {name}\n\
         hairstyle       {} hair, {:.3} m, {} guides x {} segments, {} render strands\n\
         steps           {} at {} s ({} clamped by the safety net)\n\
         wetness before  {:.6}\n\
         wetness after   {:.6} (min {:.6}, max {:.6})\n\
         rest change     {:.6e} rad/m (rms over guide coordinates, wet set)\n\
         guides cut      {} (mean length {:.6} m -> {:.6} m; dry mass {:.9e} kg -> {:.9e} kg on head + pieces)\n\
         render cut      {} (mean length {:.6} m -> {:.6} m)\n\
         render mass     {:.9e} kg before; {:.9e} kg on head + {:.9e} kg cut = {:.9e} kg\n\
         clusters        {} (kinetic energy at the end {:.3e} J; largest body field at a piece point {:.4}, surface 0.25)\n\
         lattice dryer   largest node displacement {:.3e} m (end {:.3e} m), peak dryer force {:.3e} N\n\
         wall time       {:.2} s\n\
         outputs         {}, {}, {}\n",
        h.hair_type,
        h.length,
        s.guides,
        h.segments,
        s.render_strands,
        s.steps,
        scenario.dt,
        s.clamped_steps,
        s.wetness_before,
        s.wetness_after,
        s.wetness_range_after[0],
        s.wetness_range_after[1],
        s.rest_change,
        s.guides_cut,
        s.guide_length_before,
        s.guide_length_after,
        s.guide_mass_before,
        s.guide_mass_after,
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
