//! FFD of 150,000 strands x 32 vertices (4.8 M vertices) on a 16^3 lattice of 2 cm cells through
//! the compact binding ([`lattice::ffd::CompactBinding`], 40 bytes a vertex, f32 output), on one
//! core and on all cores (rayon); and on all cores followed by the push-out of the vertices inside
//! a head (`MetaballSet::push_out_many_f32`, the built-in head, neck and shoulders of 9 cm head
//! radius centred 2 cm below the vertices' box, 0.5 mm skin).
//! Run: `cargo bench -p coiffure-lattice --bench ffd_compact`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lattice::ffd::{CompactBinding, FfdLattice};
use lattice::metaball::{Metaball, MetaballSet, PUSH_OUT_SKIN};
use nalgebra::{Point3, Vector3};

fn bench(c: &mut Criterion) {
    let ffd = FfdLattice::new(Point3::new(-0.15, -0.15, 0.0), 0.02, [16, 16, 16]).unwrap();
    let n = 150_000 * 32;
    let pts: Vec<[f32; 3]> = (0..n)
        .map(|i| {
            let f = i as f64;
            [
                (-0.1 + 0.2 * (f * 0.618).fract()) as f32,
                (-0.1 + 0.2 * (f * 0.414).fract()) as f32,
                (0.02 + 0.2 * (f * 0.732).fract()) as f32,
            ]
        })
        .collect();
    let binding = CompactBinding::new(&ffd, &pts, false).unwrap();
    drop(pts);
    let nodes: Vec<Point3<f64>> = ffd
        .rest_positions()
        .iter()
        .enumerate()
        .map(|(i, p)| p + Vector3::new(1e-3 * (i as f64).sin(), 0.0, 2e-3))
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut g = c.benchmark_group("ffd_compact");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("150k_strands_x32_one_core", |b| {
        b.iter(|| binding.apply(&nodes, &mut out).unwrap())
    });
    g.bench_function("150k_strands_x32_all_cores", |b| {
        b.iter(|| binding.apply_parallel(&nodes, &mut out).unwrap())
    });
    let head = MetaballSet::head_neck_shoulders(0.09);
    let head = MetaballSet::new(head.balls.iter().map(|b| Metaball::new(b.centre + Vector3::new(0.0, 0.0, -0.02), b.radius)).collect());
    binding.apply_parallel(&nodes, &mut out).unwrap();
    let moved = head.push_out_many_f32(&mut out, 0.25, PUSH_OUT_SKIN);
    eprintln!("push-out moves {moved} of {n} vertices ({:.1} %)", 100.0 * moved as f64 / n as f64);
    g.bench_function("150k_strands_x32_all_cores_push_out", |b| {
        b.iter(|| {
            binding.apply_parallel(&nodes, &mut out).unwrap();
            head.push_out_many_f32(&mut out, 0.25, PUSH_OUT_SKIN)
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(5));
    targets = bench
}
criterion_main!(benches);
