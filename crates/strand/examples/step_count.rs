//! A fixed number of 1 ms steps of the benchmark's strand (curly Caucasian, 25 cm), for counting instructions
//! and cycles with `perf stat` (load-independent, unlike wall time). Run:
//! `perf stat -e instructions,cycles cargo run --release -p coiffure-strand --example step_count -- reduced 16 20000`.

use nalgebra::Vector3;
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = if args.first().map(String::as_str) == Some("full") { ModelKind::Full } else { ModelKind::Reduced };
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    let steps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(20000);
    let h = HairType::CAUCASIAN;
    let (tw, bd) = h.rest_curvature();
    let m = StrandModel::new(kind, 0.25, n, h.section().unwrap(), h.material().unwrap()).unwrap().with_uniform_rest(tw, bd, 0.0);
    let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.3, 0.0, -1.0), Vector3::y()).unwrap();
    let mut s = Strand::new(m, root).unwrap();
    let t = std::time::Instant::now();
    for _ in 0..steps {
        s.step(1e-3, &[]).unwrap();
    }
    let e = t.elapsed().as_secs_f64();
    println!("{kind:?} N={n}: {steps} steps, {:.2} us per step (wall clock), tip z {:.6} m", e / steps as f64 * 1e6, s.dynamics.frames[n].position.z);
}
