//! Cost of one lattice step (16^3 nodes, 26-neighbour and second-neighbour stiffeners, implicit Euler with
//! conjugate gradients), and of binding-based FFD of many strand vertices. One core.
//! Run: `cargo bench -p coiffure-lattice --bench lattice_step`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lattice::ffd::{Binding, FfdLattice};
use lattice::lattice::{FillOrdering, LatticeModel, LatticeParams};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// CPU time of the calling thread, ns (first field of /proc/thread-self/schedstat).
fn thread_cpu_ns() -> u64 {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").expect("Linux /proc/thread-self/schedstat");
    text.split_whitespace().next().and_then(|f| f.parse().ok()).expect("schedstat CPU time")
}

fn bench(c: &mut Criterion) {
    // A 16^3 lattice of 2 cm cells around a head, 0.1 g per node (about 400 g of hair in all: generous).
    let ffd = FfdLattice::new(Point3::new(-0.15, -0.15, 0.0), 0.02, [16, 16, 16]).unwrap();
    let mut g = c.benchmark_group("lattice");
    g.throughput(Throughput::Elements(1));
    // `step_16x16x16_10ms` uses the default (fill-reducing ordering chosen automatically: nested
    // dissection here); `_amd` forces faer's AMD ordering, the solver before issue 4's change.
    let mut state = None;
    for (name, ordering) in [("step_16x16x16_10ms", FillOrdering::Auto), ("step_16x16x16_10ms_amd", FillOrdering::Amd)] {
        let params = LatticeParams { fill_ordering: ordering, ..LatticeParams::default() };
        let model = LatticeModel::uniform(ffd.clone(), 1e-4, params).unwrap();
        let mut s = model.rest_state(&Isometry3::identity());
        let mut t = 0.0f64;
        g.bench_function(name, |b| {
            b.iter(|| {
                // The head nods: the attachment targets move, so the solver has work to do.
                t += 0.01;
                let head = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.01 * (6.0 * t).sin()), UnitQuaternion::from_euler_angles(0.2 * (3.0 * t).sin(), 0.0, 0.0));
                model.step(&mut s, 0.01, &head, None);
            })
        });
        if ordering == FillOrdering::Auto {
            // The same step timed in this thread's CPU time (Linux schedstat, ns), not wall time:
            // under load from other processes this is the cost of a step on one core.
            g.bench_function(format!("{name}_cpu_time"), |b| {
                b.iter_custom(|iters| {
                    let c0 = thread_cpu_ns();
                    for _ in 0..iters {
                        t += 0.01;
                        let head = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.01 * (6.0 * t).sin()), UnitQuaternion::from_euler_angles(0.2 * (3.0 * t).sin(), 0.0, 0.0));
                        model.step(&mut s, 0.01, &head, None);
                    }
                    std::time::Duration::from_nanos(thread_cpu_ns().saturating_sub(c0))
                })
            });
        }
        if let Some(nnz) = s.cache.factor_nonzeros() {
            eprintln!("{name}: Cholesky factor of the 16^3 system matrix holds {nnz} values");
        }
        state.get_or_insert(s);
    }
    let state = state.expect("benchmarked");
    // FFD of 10,000 strands of 32 vertices (320,000 vertices) through a precomputed binding.
    let pts: Vec<Point3<f64>> = (0..320_000)
        .map(|i| {
            let f = i as f64;
            Point3::new(-0.1 + 0.2 * ((f * 0.618).fract()), -0.1 + 0.2 * ((f * 0.414).fract()), 0.02 + 0.2 * ((f * 0.732).fract()))
        })
        .collect();
    let binding = Binding::new(&ffd, &pts).unwrap();
    let nodes: Vec<Point3<f64>> = state.positions.iter().map(|p| p + Vector3::new(0.001, 0.0, 0.0)).collect();
    let mut out = vec![Point3::origin(); pts.len()];
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("ffd_320k_vertices", |b| b.iter(|| binding.apply(&nodes, &mut out).unwrap()));
    g.bench_function("ffd_320k_vertices_both_cores", |b| b.iter(|| binding.apply_parallel(&nodes, &mut out).unwrap()));
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
