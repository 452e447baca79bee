//! Cost of one 1 ms step against the number of segments, both models, one core.
//! Run: `cargo bench -p coiffure-strand --bench step`. Throughput is reported in segment-steps per second.
//! `batch_1ms/Reduced` steps 4 reduced strands at once ([`strand::StrandBatch`], SIMD lanes); its time is per
//! batch of 4 and its throughput counts the segment-steps of all 4 strands.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use nalgebra::Vector3;
use strand::{HairType, ModelKind, RootFrame, Strand, StrandBatch, StrandModel};

fn strand(kind: ModelKind, segments: usize) -> Strand {
    let h = HairType::CAUCASIAN;
    let (tw, bd) = h.rest_curvature();
    let m = StrandModel::new(kind, 0.25, segments, h.section().unwrap(), h.material().unwrap())
        .unwrap()
        .with_uniform_rest(tw, bd, 0.0);
    let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.3, 0.0, -1.0), Vector3::y()).unwrap();
    let mut s = Strand::new(m, root).unwrap();
    // Start from a moving, non-trivial state.
    for _ in 0..50 {
        s.step(1e-3, &[]).unwrap();
    }
    s
}

fn step(c: &mut Criterion) {
    for kind in [ModelKind::Reduced, ModelKind::Full] {
        let mut group = c.benchmark_group(format!("step_1ms/{kind:?}"));
        for n in [4usize, 8, 16, 32, 64] {
            group.throughput(Throughput::Elements(n as u64));
            let mut s = strand(kind, n);
            group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| {
                    if s.step(1e-3, &[]).is_err() {
                        s = strand(kind, n);
                    }
                })
            });
        }
        group.finish();
    }
}

fn batch(c: &mut Criterion) {
    let mut group = c.benchmark_group("batch_1ms/Reduced");
    for n in [4usize, 8, 16, 32, 64] {
        group.throughput(Throughput::Elements(4 * n as u64));
        let fresh = || (0..4).map(|_| strand(ModelKind::Reduced, n)).collect::<Vec<_>>();
        let mut strands = fresh();
        let mut batch = StrandBatch::new(n, 2);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                let mut refs: Vec<&mut Strand> = strands.iter_mut().collect();
                if batch.step(1e-3, &mut refs, &[]).is_err() {
                    strands = fresh();
                }
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = step, batch
}
criterion_main!(benches);
