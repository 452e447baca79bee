//! A fixed number of 1 ms steps of 4 of the benchmark's strands (curly Caucasian, 25 cm, reduced model), either
//! as one SIMD batch ([`strand::StrandBatch`]) or one by one, for counting cycles with `perf stat` or comparing
//! wall time in one run (`compare`: both, alternating in blocks, and the ratio scalar / batch). Run:
//! `cargo run --release -p coiffure-strand --example batch_count -- [batch|scalar|compare] [N] [steps]`
//! (default: compare 16 20000). Prints the cost per strand-step and the segment-steps per second on one core.

use nalgebra::Vector3;
use strand::{HairType, ModelKind, RootFrame, Strand, StrandBatch, StrandModel};

fn strands(n: usize) -> Vec<Strand> {
    let h = HairType::CAUCASIAN;
    let (tw, bd) = h.rest_curvature();
    let m = StrandModel::new(ModelKind::Reduced, 0.25, n, h.section().unwrap(), h.material().unwrap()).unwrap().with_uniform_rest(tw, bd, 0.0);
    (0..4)
        .map(|k| {
            // Slightly different roots so the lanes are not identical.
            let root = RootFrame::new(Vector3::new(0.002 * k as f64, 0.0, 0.3), Vector3::new(0.3, 0.01 * k as f64, -1.0), Vector3::y()).unwrap();
            Strand::new(m.clone(), root).unwrap()
        })
        .collect()
}

/// Seconds per strand-step over `steps` steps of the 4 strands.
fn run(batched: bool, s: &mut [Strand], batch: &mut StrandBatch, steps: usize) -> f64 {
    let t = std::time::Instant::now();
    for _ in 0..steps {
        if batched {
            let mut refs: Vec<&mut Strand> = s.iter_mut().collect();
            batch.step(1e-3, &mut refs, &[]).unwrap();
        } else {
            for x in s.iter_mut() {
                x.step(1e-3, &[]).unwrap();
            }
        }
    }
    t.elapsed().as_secs_f64() / (steps * s.len()) as f64
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().cloned().unwrap_or_else(|| "compare".into());
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    let steps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(20000);
    let mut batch = StrandBatch::new(n, 2);
    let report = |what: &str, per: f64| println!("{what} N={n}: {:.2} us per strand-step, {:.2} M segment-steps/s", per * 1e6, n as f64 / per / 1e6);
    match mode.as_str() {
        "batch" | "scalar" => {
            let mut s = strands(n);
            let per = run(mode == "batch", &mut s, &mut batch, steps);
            report(&mode, per);
            println!("tip z {:.6} m", s[0].dynamics.frames[n].position.z);
        }
        _ => {
            // Alternate blocks so both see the same machine load; best block of each.
            let (mut sb, mut ss) = (strands(n), strands(n));
            let blocks = 10;
            let (mut best_b, mut best_s) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..blocks {
                best_b = best_b.min(run(true, &mut sb, &mut batch, steps / blocks));
                best_s = best_s.min(run(false, &mut ss, &mut batch, steps / blocks));
            }
            report("batch", best_b);
            report("scalar", best_s);
            let diff = sb.iter().zip(&ss).map(|(a, b)| (&a.state.q - &b.state.q).amax()).fold(0.0, f64::max);
            println!("ratio scalar / batch: {:.2}x (best of {blocks} alternating blocks; max |q| difference {diff:.1e} rad/m)", best_s / best_b);
        }
    }
}
