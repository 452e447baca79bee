//! The lattice carrying a hairstyle: node masses and attachment.

use hairstyle::{Hairstyle, HairstyleParams};
use lattice::lattice::{CarryParams, LatticeParams};

fn style() -> Hairstyle {
    Hairstyle::generate(&HairstyleParams {
        guide_count: 80,
        render_count: 3000,
        seed: 21,
        ..Default::default()
    })
    .unwrap()
}

/// Node masses carry the hair: their sum is the hair's mass (render vertex masses; the B-spline
/// weights sum to 1) plus the small empty-node mass, to 1e-12 relative; nodes inside the head are
/// fully attached and nodes far from it free.
#[test]
fn lattice_carries_the_hair_mass() {
    let h = style();
    let carry = CarryParams::default();
    let hl = h.lattice(&carry, LatticeParams::default()).unwrap();
    let hair: f64 = h.render_vertex_masses().unwrap().iter().sum();
    let n = hl.model.node_count();
    let expected = hair + n as f64 * carry.empty_node_mass;
    assert!((hl.model.total_mass() - expected).abs() < 1e-12 * expected);
    // 3000 caucasian hairs of ~0.19 m: about 3000 x 0.19 x 1300 x pi (40e-6)^2 ~ 4e-3 kg
    assert!(hair > 1e-3 && hair < 1e-2, "{hair} kg");
    let t = hl.model.params.metaball.threshold;
    let mut inside = 0;
    for (x, a) in hl.model.rest.iter().zip(&hl.model.attachment) {
        if h.head.body.field(x) > t {
            assert_eq!(*a, 1.0);
            inside += 1;
        }
        if h.head.signed_distance(x) > carry.attach_distance + carry.attach_falloff {
            assert_eq!(*a, 0.0);
        }
    }
    assert!(inside > 10);
    assert_eq!(hl.binding.len(), h.render.positions.len());
}

/// Minimum signed distance (m, negative inside) of the render vertices to the head/body surface
/// after FFD of the lattice nodes `nodes` (world), the head at pose `head`.
fn min_render_distance(
    h: &Hairstyle,
    hl: &hairstyle::global::HairLattice,
    nodes: &[nalgebra::Point3<f64>],
    head: &nalgebra::Isometry3<f64>,
    out: &mut Vec<nalgebra::Point3<f64>>,
) -> f64 {
    hl.binding.apply_parallel(nodes, out).unwrap();
    let inv = head.inverse();
    out.iter()
        .map(|p| h.head.signed_distance(&(inv * p)))
        .fold(f64::INFINITY, f64::min)
}

/// Head shake: 2000 render strands on a 4 cm lattice (9 x 9 x 11 nodes) under gravity, with the
/// body's metaballs as obstacles, dt = 10 ms.
/// 1. Settle 2 s with the head still: equilibrium X0 (node speeds < 1 mm/s).
/// 2. Shake: head translated sideways y = A sin(2 pi f t), A = 3 cm, f = 2 Hz, for 1 s; then hold
///    still 2 s.
/// Inertia: the mean distance of the free, hair-carrying nodes from where a rigidly carried
/// equilibrium would put them (head * X0) peaks above 2 mm during the shake (measured 4.4 mm;
/// a lattice with no inertia would show 0) and stays below A.
/// Settling: 2 s after the shake every node is back at X0 within 0.5 mm (measured 0.08 mm).
/// Head: no render vertex (FFD of the lattice, `Binding::apply_parallel`) is more than 6 mm
/// inside the head/body surface (first-order distance (T - F)/|grad F|) at any step, and after
/// settling no deeper than 3.5 mm. Measured: 0 at rest, 2.6 mm at the gravity equilibrium,
/// 4.6 mm at worst during the shake. The 1 mm the lead asked for is NOT met at this lattice
/// resolution: the lattice nodes collide, the render vertices between them (4 cm cells) sag
/// into the scalp where the lattice sags.
#[test]
fn head_shake_moves_hair_with_inertia_and_it_settles_back() {
    use hairstyle::global::body_in_world;
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
    let h = Hairstyle::generate(&HairstyleParams {
        guide_count: 60,
        render_count: 2000,
        seed: 21,
        ..Default::default()
    })
    .unwrap();
    let carry = CarryParams {
        cell: 0.04,
        ..Default::default()
    };
    let hl = h.lattice(&carry, LatticeParams::default()).unwrap();
    let m = &hl.model;
    assert_eq!((m.ffd.nx, m.ffd.ny, m.ffd.nz), (9, 9, 11));
    let mut out = Vec::new();
    let dt = 0.01;
    let still = Isometry3::identity();
    let body = body_in_world(&h.head.body, &still);
    let mut s = m.rest_state(&still);
    assert!(min_render_distance(&h, &hl, &s.positions, &still, &mut out) > -1e-6);
    for _ in 0..200 {
        m.step(&mut s, dt, &still, Some(&body));
    }
    let vmax = s.velocities.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(vmax < 1e-3, "not settled: {vmax} m/s");
    let x0: Vec<Point3<f64>> = s.positions.clone();
    let free: Vec<usize> = (0..m.node_count())
        .filter(|&i| m.attachment[i] == 0.0 && m.masses[i] > 10.0 * carry.empty_node_mass)
        .collect();
    assert!(free.len() > 10, "{} free nodes", free.len());
    let (a, f) = (0.03, 2.0);
    let (mut max_lag, mut min_dist): (f64, f64) = (0.0, f64::INFINITY);
    for k in 0..300 {
        let t = (k + 1) as f64 * dt;
        let y = if t <= 1.0 {
            a * (2.0 * std::f64::consts::PI * f * t).sin()
        } else {
            0.0
        };
        let head = Isometry3::from_parts(Translation3::new(0.0, y, 0.0), UnitQuaternion::identity());
        let body = body_in_world(&h.head.body, &head);
        m.step(&mut s, dt, &head, Some(&body));
        if t <= 1.0 {
            let lag = free
                .iter()
                .map(|&i| (s.positions[i] - head * x0[i]).norm())
                .sum::<f64>()
                / free.len() as f64;
            max_lag = max_lag.max(lag);
        }
        min_dist = min_dist.min(min_render_distance(&h, &hl, &s.positions, &head, &mut out));
    }
    assert_eq!(s.rejected_steps, 0);
    assert!(max_lag > 2e-3 && max_lag < a, "lag {max_lag} m");
    let back = x0
        .iter()
        .zip(&s.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    assert!(back < 5e-4, "not back at equilibrium: {back} m");
    assert!(min_dist > -6e-3, "render vertex {min_dist} m inside the head");
    let end = min_render_distance(&h, &hl, &s.positions, &still, &mut out);
    assert!(end > -3.5e-3, "render vertex {end} m inside the head after settling");
}
