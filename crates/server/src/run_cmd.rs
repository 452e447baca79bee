//! `coiffure run SCENARIO.toml`: a scripted tool session, headless; writes the force trace and a summary.

use anyhow::{bail, Context, Result};
use clap::Args;
use engine::path::{ToolPath, Waypoint};
use engine::scenario::Scenario;
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
