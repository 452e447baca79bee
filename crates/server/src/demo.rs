//! `coiffure demo`: the built-in default scene, headless. A row of strands of the default hair type hangs
//! from a root that sways like a nodding head; prints a summary and writes the tips' trace as CSV.

use anyhow::{Context, Result};
use clap::Args;
use nalgebra::Vector3;
use std::io::Write;
use std::path::PathBuf;
use strand::kinematics::segment_frames;
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};

/// Arguments of `coiffure demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder (the trace goes to OUT/trace.csv).
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Simulated time, s.
    #[arg(long, default_value_t = 3.0)]
    duration: f64,
    /// Number of strands.
    #[arg(long, default_value_t = 8)]
    strands: usize,
    /// Hair type preset.
    #[arg(long, default_value = "H1")]
    hair_type: String,
}

/// Root sway: 2 cm at 1.5 Hz along x, the motion a nodding head gives the scalp.
const SWAY_AMPLITUDE: f64 = 0.02;
const SWAY_HZ: f64 = 1.5;

pub fn run(args: &DemoArgs) -> Result<()> {
    let h = HairType::by_name(&args.hair_type).with_context(|| format!("unknown hair type {:?}", args.hair_type))?;
    if args.strands == 0 || args.strands > 10_000 {
        anyhow::bail!("--strands must be between 1 and 10000, got {}", args.strands);
    }
    if !(args.duration.is_finite() && args.duration > 0.0) {
        anyhow::bail!("--duration must be a finite positive number, got {}", args.duration);
    }
    let (tw, bd) = h.rest_curvature();
    let model = StrandModel::new(ModelKind::Reduced, 0.15, 16, h.section()?, h.material()?)?.with_uniform_rest(tw, bd, 0.0);
    let dt = 1e-3;
    let mut strands: Vec<Strand> = (0..args.strands)
        .map(|i| {
            let y = 0.005 * i as f64;
            let root = RootFrame::new(Vector3::new(0.0, y, 0.3), Vector3::new(0.3, 0.0, -1.0), Vector3::y())?;
            Ok(Strand::new(model.clone(), root)?)
        })
        .collect::<Result<_>>()?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let trace_path = args.out.join("trace.csv");
    // Written whole at the end (`write_atomic`): never half-written under its name.
    let mut trace = Vec::new();
    write!(trace, "t")?;
    for i in 0..args.strands {
        write!(trace, ",x{i},y{i},z{i}")?;
    }
    writeln!(trace)?;
    let steps = (args.duration / dt).round() as usize;
    let w = 2.0 * std::f64::consts::PI * SWAY_HZ;
    let started = std::time::Instant::now();
    let mut max_lag = 0.0f64;
    for n in 0..steps {
        let t = n as f64 * dt;
        write!(trace, "{t:.4}")?;
        for s in strands.iter_mut() {
            let root = &mut s.state.root;
            root.velocity = Vector3::new(SWAY_AMPLITUDE * w * (w * t).cos(), 0.0, 0.0);
            root.acceleration = Vector3::new(-SWAY_AMPLITUDE * w * w * (w * t).sin(), 0.0, 0.0);
            s.step(dt, &[])?;
            let tip = segment_frames(&s.model, &s.state)[s.model.segments].position;
            max_lag = max_lag.max((tip.x - s.state.root.position.x).abs());
            write!(trace, ",{:.6e},{:.6e},{:.6e}", tip.x, tip.y, tip.z)?;
        }
        writeln!(trace)?;
    }
    hairstyle::formats::write_atomic(&trace_path, &trace).with_context(|| format!("cannot write {}", trace_path.display()))?;
    let wall = started.elapsed().as_secs_f64();
    let strand_steps = (steps * args.strands) as f64;
    let energy: f64 = strands.iter_mut().map(|s| s.energy()).sum();
    println!("Coiffure demo: {} strands of {} ({} segments, reduced Super-Helix), {:.1} s at {:.0} Hz", args.strands, h.name, model.segments, args.duration, 1.0 / dt);
    println!("  strand steps          {}", strand_steps);
    println!("  wall time             {:.3} s ({:.1} us per strand step, {:.2}x real time)", wall, 1e6 * wall / strand_steps, args.duration / wall);
    println!("  max tip lag behind root {:.2} mm", 1e3 * max_lag);
    println!("  final energy (all)    {:.6e} J", energy);
    println!("  trace                 {}", trace_path.display());
    Ok(())
}
