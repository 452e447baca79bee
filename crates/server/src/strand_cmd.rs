//! `coiffure strand`: one strand from a spec file, statics or dynamics, centreline as CSV on stdout.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use std::io::Write;
use std::path::PathBuf;
use strand::kinematics::{centerline, segment_frames};
use strand::spec::StrandSpec;
use strand::statics::{solve_equilibrium, StaticOptions};
use strand::{Integrator, Strand, StrandState};

/// Arguments of `coiffure strand`.
#[derive(Debug, Args)]
pub struct StrandArgs {
    /// Strand spec (TOML, SI units; see docs/strand-spec.md).
    #[arg(long)]
    spec: PathBuf,
    /// Solve the static equilibrium under gravity instead of simulating.
    #[arg(long = "static", conflicts_with = "duration")]
    statics: bool,
    /// Simulated time, s.
    #[arg(long)]
    duration: Option<f64>,
    /// Time step, s.
    #[arg(long, default_value_t = 1e-3)]
    dt: f64,
    /// Number of centreline samples printed (root to tip, evenly spaced in arc length).
    #[arg(long, default_value_t = 17)]
    samples: usize,
    /// Write the tip position over time to this CSV file (`t,x,y,z`).
    #[arg(long)]
    trace: Option<PathBuf>,
    /// Integrator for `--duration`.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Euler)]
    integrator: IntegratorArg,
}

/// Integrator names on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum IntegratorArg {
    /// Linearly implicit Euler (default).
    Euler,
    /// Implicit midpoint.
    Midpoint,
}

/// Reads and builds a spec file, with errors that name the file and the field.
pub fn load_spec(path: &std::path::Path) -> Result<(strand::StrandModel, strand::RootFrame)> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read spec {}", path.display()))?;
    let spec: StrandSpec = toml::from_str(&text).with_context(|| format!("malformed spec {}", path.display()))?;
    spec.build().with_context(|| format!("invalid spec {}", path.display()))
}

pub fn run(args: &StrandArgs) -> Result<()> {
    let (model, root) = load_spec(&args.spec)?;
    if args.samples < 2 {
        bail!("--samples must be at least 2, got {}", args.samples);
    }
    let state = if args.statics {
        let start = StrandState::at_rest(&model, root);
        let eq = solve_equilibrium(&model, &start, &[], &StaticOptions::default())?;
        tracing::info!(iterations = eq.iterations, stable = eq.stable, potential_j = eq.potential, "static equilibrium");
        if !eq.stable {
            tracing::warn!("the equilibrium found is not stable");
        }
        StrandState { q: eq.q, ..start }
    } else {
        let duration = args.duration.unwrap_or(0.0);
        if !(duration.is_finite() && duration >= 0.0) {
            bail!("--duration must be a finite number >= 0, got {duration}");
        }
        if !(args.dt.is_finite() && args.dt > 0.0) {
            bail!("--dt must be a finite positive number, got {}", args.dt);
        }
        let mut strand = Strand::new(model.clone(), root)?;
        strand.integrator = match args.integrator {
            IntegratorArg::Euler => Integrator::LinearlyImplicitEuler,
            IntegratorArg::Midpoint => Integrator::ImplicitMidpoint,
        };
        let steps = (duration / args.dt).round() as usize;
        let mut trace = match &args.trace {
            Some(p) => {
                crate::ensure_parent(p)?;
                // Written whole at the end (`write_atomic`): never half-written under its name.
                let mut w = Vec::new();
                writeln!(w, "t,x,y,z")?;
                Some((p, w))
            }
            None => None,
        };
        let started = std::time::Instant::now();
        for n in 0..=steps {
            if let Some((_, w)) = trace.as_mut() {
                let tip = segment_frames(&model, &strand.state)[model.segments].position;
                writeln!(w, "{:.6},{:.9e},{:.9e},{:.9e}", strand.state.time, tip.x, tip.y, tip.z)?;
            }
            if n < steps {
                strand.step(args.dt, &[]).with_context(|| format!("step {n} failed"))?;
            }
        }
        if let Some((p, w)) = trace {
            hairstyle::formats::write_atomic(p, &w).with_context(|| format!("cannot write trace {}", p.display()))?;
        }
        let wall = started.elapsed().as_secs_f64();
        tracing::info!(steps, wall_s = wall, us_per_step = 1e6 * wall / steps.max(1) as f64, "simulated");
        strand.state
    };
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    writeln!(out, "s,x,y,z")?;
    for (s, x) in centerline(&model, &state, args.samples) {
        writeln!(out, "{s:.9e},{:.12e},{:.12e},{:.12e}", x.x, x.y, x.z)?;
    }
    Ok(())
}
