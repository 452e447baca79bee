//! Cost of one lattice step (16^3 nodes, 26-neighbour and second-neighbour stiffeners, implicit Euler with
//! conjugate gradients), and of binding-based FFD of many strand vertices. One core.
//! Run: `cargo bench -p coiffure-lattice --bench lattice_step`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lattice::ffd::{Binding, FfdLattice};
use lattice::lattice::{LatticeModel, LatticeParams};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

fn bench(c: &mut Criterion) {
    // A 16^3 lattice of 2 cm cells around a head, 0.1 g per node (about 400 g of hair in all: generous).
    let ffd = FfdLattice::new(Point3::new(-0.15, -0.15, 0.0), 0.02, [16, 16, 16]).unwrap();
    let model = LatticeModel::uniform(ffd.clone(), 1e-4, LatticeParams::default()).unwrap();
    let mut state = model.rest_state(&Isometry3::identity());
    let mut t = 0.0f64;
    let mut g = c.benchmark_group("lattice");
    g.throughput(Throughput::Elements(1));
    g.bench_function("step_16x16x16_10ms", |b| {
        b.iter(|| {
            // The head nods: the attachment targets move, so the solver has work to do.
            t += 0.01;
            let head = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.01 * (6.0 * t).sin()), UnitQuaternion::from_euler_angles(0.2 * (3.0 * t).sin(), 0.0, 0.0));
            model.step(&mut state, 0.01, &head, None);
        })
    });
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
