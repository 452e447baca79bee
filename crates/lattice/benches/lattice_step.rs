//! Cost of one lattice step (16^3 nodes, 26-neighbour and second-neighbour stiffeners, implicit Euler with
//! conjugate gradients), and of binding-based FFD of many strand vertices. One core.
//! Run: `cargo bench -p coiffure-lattice --bench lattice_step`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lattice::ffd::{Binding, FfdLattice};
use lattice::lattice::{BendingJacobian, FactorPrecision, FillOrdering, LatticeModel, LatticeParams};
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
    // `step_16x16x16_10ms` uses the defaults (fill-reducing ordering chosen automatically, bending
    // Jacobian PathBound, f32 factor); `_amd` forces faer's AMD ordering; `_laplacian_f64` is the
    // exact bending Jacobian with an f64 factor (the solver before the PathBound/F32 change);
    // `_pathbound_f64` and `_laplacian_f32` separate the two changes.
    let mut state = None;
    let (lap, path, diag) = (BendingJacobian::Laplacian, BendingJacobian::PathBound, BendingJacobian::DiagonalBound);
    let (f64p, f32p) = (FactorPrecision::F64, FactorPrecision::F32);
    for (name, ordering, bending, precision) in [
        ("step_16x16x16_10ms", FillOrdering::Auto, path, f32p),
        ("step_16x16x16_10ms_laplacian_f64", FillOrdering::Auto, lap, f64p),
        ("step_16x16x16_10ms_pathbound_f64", FillOrdering::Auto, path, f64p),
        ("step_16x16x16_10ms_laplacian_f32", FillOrdering::Auto, lap, f32p),
        ("step_16x16x16_10ms_diagonalbound_f32", FillOrdering::Auto, diag, f32p),
        ("step_16x16x16_10ms_amd", FillOrdering::Amd, path, f32p),
    ] {
        let params = LatticeParams { fill_ordering: ordering, bending_jacobian: bending, factor_precision: precision, ..LatticeParams::default() };
        let model = LatticeModel::uniform(ffd.clone(), 1e-4, params).unwrap();
        let mut s = model.rest_state(&Isometry3::identity());
        let mut w = lattice::lattice::LatticeWorkspace::default();
        let mut t = 0.0f64;
        g.bench_function(name, |b| {
            b.iter(|| {
                // The head nods: the attachment targets move, so the solver has work to do.
                t += 0.01;
                let head = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.01 * (6.0 * t).sin()), UnitQuaternion::from_euler_angles(0.2 * (3.0 * t).sin(), 0.0, 0.0));
                model.step(&mut s, &mut w, 0.01, &head, None);
            })
        });
        if ordering == FillOrdering::Auto && (bending, precision) != (diag, f32p) {
            // The same step timed in this thread's CPU time (Linux schedstat, ns), not wall time:
            // under load from other processes this is the cost of a step on one core.
            g.bench_function(format!("{name}_cpu_time"), |b| {
                b.iter_custom(|iters| {
                    let c0 = thread_cpu_ns();
                    for _ in 0..iters {
                        t += 0.01;
                        let head = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.01 * (6.0 * t).sin()), UnitQuaternion::from_euler_angles(0.2 * (3.0 * t).sin(), 0.0, 0.0));
                        model.step(&mut s, &mut w, 0.01, &head, None);
                    }
                    std::time::Duration::from_nanos(thread_cpu_ns().saturating_sub(c0))
                })
            });
        }
        if let Some(nnz) = w.factor_nonzeros() {
            eprintln!("{name}: Cholesky factor of the 16^3 system matrix holds {nnz} values ({} bytes)", w.factor_bytes().unwrap_or(0));
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
