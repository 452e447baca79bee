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
/// after FFD of the lattice nodes `nodes` (world), the head at pose `head`: (plain FFD, FFD then
/// push-out by `HairLattice::render_positions` with the 0.5 mm skin).
fn min_render_distance(
    h: &Hairstyle,
    hl: &hairstyle::global::HairLattice,
    nodes: &[nalgebra::Point3<f64>],
    head: &nalgebra::Isometry3<f64>,
    out: &mut Vec<nalgebra::Point3<f64>>,
) -> (f64, f64) {
    let inv = head.inverse();
    let min = |out: &Vec<nalgebra::Point3<f64>>| {
        out.iter()
            .map(|p| h.head.signed_distance(&(inv * p)))
            .fold(f64::INFINITY, f64::min)
    };
    hl.binding.apply_parallel(nodes, out).unwrap();
    let raw = min(out);
    let body = hairstyle::global::body_in_world(&h.head.body, head);
    hl.render_positions(nodes, &body, lattice::metaball::PUSH_OUT_SKIN, out)
        .unwrap();
    (raw, min(out))
}

/// Head shake: 2000 render strands on a 4 cm lattice (11 x 8 x 11 nodes) under gravity, with the
/// body's metaballs as obstacles, dt = 10 ms.
/// 1. Settle 2 s with the head still: equilibrium X0 (node speeds < 1 mm/s).
/// 2. Shake: head translated sideways y = A sin(2 pi f t), A = 3 cm, f = 2 Hz, for 1 s; then hold
///    still 2 s.
/// Inertia: the mean distance of the free, hair-carrying nodes from where a rigidly carried
/// equilibrium would put them (head * X0) peaks above 2 mm during the shake (measured 4.4 mm;
/// a lattice with no inertia would show 0) and stays below A.
/// Settling: 2 s after the shake every node is back at X0 within 0.5 mm (measured 0.08 mm).
/// Head: with the push-out of `HairLattice::render_positions` (0.5 mm skin) no render vertex is
/// more than 0.1 mm inside the head/body surface (first-order distance (T - F)/|grad F|) at any
/// step. Without it (plain FFD, `Binding::apply_parallel`) the lattice nodes collide but the
/// vertices between them (4 cm cells) sag into the scalp where the lattice sags: no deeper than
/// 6 mm at any step and 3.5 mm after settling (measured in the assertion messages).
#[test]
fn head_shake_moves_hair_with_inertia_and_it_settles_back() {
    use hairstyle::global::body_in_world;
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
    let (h, carry) = shake_hairstyle();
    let hl = h.lattice(&carry, LatticeParams::default()).unwrap();
    let m = &hl.model;
    assert_eq!((m.ffd.nx, m.ffd.ny, m.ffd.nz), (11, 8, 11));
    let mut out = Vec::new();
    let dt = 0.01;
    let still = Isometry3::identity();
    let body = body_in_world(&h.head.body, &still);
    let mut s = m.rest_state(&still);
    let mut w = lattice::lattice::LatticeWorkspace::default();
    assert!(min_render_distance(&h, &hl, &s.positions, &still, &mut out).0 > -1e-6);
    for _ in 0..200 {
        m.step(&mut s, &mut w, dt, &still, Some(&body));
    }
    let vmax = s.velocities.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(vmax < 1e-3, "not settled: {vmax} m/s");
    let x0: Vec<Point3<f64>> = s.positions.clone();
    let free: Vec<usize> = (0..m.node_count())
        .filter(|&i| m.attachment[i] == 0.0 && m.masses[i] > 10.0 * carry.empty_node_mass)
        .collect();
    assert!(free.len() > 10, "{} free nodes", free.len());
    let (a, f) = (0.03, 2.0);
    let (mut max_lag, mut min_dist, mut min_pushed): (f64, f64, f64) =
        (0.0, f64::INFINITY, f64::INFINITY);
    for k in 0..300 {
        let t = (k + 1) as f64 * dt;
        let y = if t <= 1.0 {
            a * (2.0 * std::f64::consts::PI * f * t).sin()
        } else {
            0.0
        };
        let head = Isometry3::from_parts(Translation3::new(0.0, y, 0.0), UnitQuaternion::identity());
        let body = body_in_world(&h.head.body, &head);
        m.step(&mut s, &mut w, dt, &head, Some(&body));
        if t <= 1.0 {
            let lag = free
                .iter()
                .map(|&i| (s.positions[i] - head * x0[i]).norm())
                .sum::<f64>()
                / free.len() as f64;
            max_lag = max_lag.max(lag);
        }
        let (raw, pushed) = min_render_distance(&h, &hl, &s.positions, &head, &mut out);
        min_dist = min_dist.min(raw);
        min_pushed = min_pushed.min(pushed);
    }
    assert_eq!(s.rejected_steps, 0);
    assert!(max_lag > 2e-3 && max_lag < a, "lag {max_lag} m");
    let back = x0
        .iter()
        .zip(&s.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    assert!(back < 5e-4, "not back at equilibrium: {back} m");
    let (end, end_pushed) = min_render_distance(&h, &hl, &s.positions, &still, &mut out);
    eprintln!(
        "deepest render vertex: plain FFD {min_dist} m during, {end} m after; pushed out \
         {min_pushed} m during, {end_pushed} m after"
    );
    assert!(min_pushed > -1e-4, "pushed render vertex {min_pushed} m inside the head");
    assert!(end_pushed > -1e-4, "pushed render vertex {end_pushed} m inside after settling");
    assert!(min_dist > -6e-3, "render vertex {min_dist} m inside the head");
    assert!(end > -3.5e-3, "render vertex {end} m inside the head after settling");
}

/// Result of [`dryer_run`]: (largest gravity sag of a node from its rest position after settling,
/// force-weighted displacement of the blown nodes along the force, largest displacement, largest
/// distance from the pre-dryer equilibrium 3 s after the dryer stops, total dryer force, anchors'
/// total force), m and N.
/// The hairstyle of the head-shake and dryer tests (2000 render strands, 60 guides) and its 4 cm lattice cells.
/// Groomed with one flow point for the whole scalp (`fringe_flow: None`: the fringe falls forward), the
/// hairstyle these tests' figures were measured on (a swept-back fringe tried on the way made the lattice
/// 8 x 8 x 11 nodes and left one empty, fully attached node inside the chest 2.7 mm from where it was after the
/// shake: the contact's attraction band gives such nodes more than one equilibrium).
fn shake_hairstyle() -> (Hairstyle, CarryParams) {
    let h = Hairstyle::generate(&HairstyleParams {
        guide_count: 60,
        render_count: 2000,
        seed: 21,
        fringe_flow: None,
        ..Default::default()
    })
    .unwrap();
    (h, CarryParams { cell: 0.04, ..Default::default() })
}

type DryerRun = (f64, f64, f64, f64, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>);

/// Settle 2 s, blow 3 s, stop 3 s (the scenario of `dryer_blows_the_hair_and_it_settles_back`).
fn dryer_run(params: LatticeParams) -> DryerRun {
    use nalgebra::{Isometry3, Vector3};
    use tools::dryer::{Cone, HairDrag, HairDryer};
    let (h, carry) = shake_hairstyle();
    let hl = h.lattice(&carry, params).unwrap();
    let m = &hl.model;
    let hair = h.params.hair().unwrap();
    let area = hair.section().unwrap().area();
    let drag = HairDrag {
        hair_diameter: 2.0 * (area / std::f64::consts::PI).sqrt(),
        ..Default::default()
    };
    let dryer = HairDryer {
        cone: Cone {
            apex: Vector3::new(-0.4, -0.1, -0.1),
            axis: Vector3::x(),
            half_angle: 0.6,
            range: 0.8,
        },
        air_speed: 10.0,
        ..Default::default()
    };
    let still = Isometry3::identity();
    let dt = 0.01;
    let mut s = m.rest_state(&still);
    let mut w = lattice::lattice::LatticeWorkspace::default();
    for _ in 0..200 {
        m.step(&mut s, &mut w, dt, &still, None);
    }
    let x0 = s.positions.clone();
    let sag = x0.iter().zip(&m.rest).map(|(x, r)| (x - r).norm()).fold(0.0, f64::max);
    let forces: Vec<Vector3<f64>> = (0..m.node_count())
        .map(|i| {
            let len = (m.masses[i] - carry.empty_node_mass).max(0.0) / (hair.density * area);
            dryer
                .hair_force(&x0[i].coords, len, carry.cell * carry.cell, &drag)
                .unwrap()
        })
        .collect();
    let total: Vector3<f64> = forces.iter().sum();
    for _ in 0..300 {
        m.step_with_forces(&mut s, &mut w, dt, &still, None, &forces).unwrap();
    }
    let disp: Vec<Vector3<f64>> = s.positions.iter().zip(&x0).map(|(x, y)| x - y).collect();
    let along: f64 = forces.iter().zip(&disp).map(|(f, d)| f.dot(d)).sum::<f64>() / total.norm();
    let max = disp.iter().map(|d| d.norm()).fold(0.0, f64::max);
    let anchors: Vector3<f64> = disp
        .iter()
        .zip(&m.attachment)
        .map(|(d, a)| a * params.attachment_stiffness * d)
        .sum();
    for _ in 0..300 {
        m.step_with_forces(&mut s, &mut w, dt, &still, None, &[]).unwrap();
    }
    let back = s
        .positions
        .iter()
        .zip(&x0)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    (sag, along, max, back, total, anchors)
}

/// A hair dryer on a hanging hairstyle (2000 render strands, 4 cm lattice, default lattice
/// parameters, gravity, no obstacles so the balance below is exact): 10 m/s jet from 0.4 m on the
/// left (-x) of the head blowing along +x across the hair behind it, cone half-angle 0.6 rad, range
/// 0.8 m. Each node gets `HairDryer::hair_force` for the hair it carries (its mass less the
/// empty-node mass over rho A) and a 4 cm x 4 cm frontal area, through
/// `LatticeModel::step_with_forces`.
/// 1. Settle 2 s without the dryer (equilibrium X0), then blow 3 s: the force-weighted mean
///    displacement of the blown nodes along the force is > 0 (the hair moves with the air).
/// 2. Hand estimate: at equilibrium the stiffeners' forces cancel in the sum, so the attachment
///    springs carry the whole dryer force: sum_i a_i k_a (x_i - X0_i) = F_total. Checked to 5 %
///    (the 3 s might not settle the slowest mode completely; measured equal to 1e-7).
/// 3. Dryer off 3 s: every node back within 0.5 mm of X0.
/// 4. Stiffness: the same with every stiffness (stiffeners, bending, attachment) divided by 10:
///    the system is linear to first order (displacements well below the 4 cm cell), so the
///    deflection under the dryer is 10x larger (checked within [7, 13]x) and so is the gravity sag
///    from the rest shape. Measured (default -> softened): force-weighted deflection 1.05 mm ->
///    10.6 mm (largest 1.8 mm -> 18 mm); gravity sag 0.057 mm -> 0.57 mm; see docs/global.md
///    "Hair dryer on the lattice".
#[test]
fn dryer_blows_the_hair_and_it_settles_back() {
    let params = LatticeParams::default();
    let (sag, along, max, back, total, anchors) = dryer_run(params);
    eprintln!(
        "default: total dryer force {total} N, anchors {anchors} N; along {along:.3e} m, max \
         {max:.3e} m, gravity sag {sag:.3e} m, back {back:.3e} m"
    );
    assert!(total.x > 0.0 && along > 0.0, "{total} N, {along} m");
    assert!(
        (anchors - total).norm() < 0.05 * total.norm(),
        "anchors {anchors} N vs dryer {total} N"
    );
    assert!(back < 5e-4, "not back: {back} m");
    let soft = LatticeParams {
        stiffener_stiffness: params.stiffener_stiffness / 10.0,
        bending_stiffness: params.bending_stiffness / 10.0,
        attachment_stiffness: params.attachment_stiffness / 10.0,
        ..params
    };
    let (sag_s, along_s, max_s, back_s, _, _) = dryer_run(soft);
    eprintln!(
        "stiffnesses / 10: along {along_s:.3e} m, max {max_s:.3e} m, gravity sag {sag_s:.3e} m, \
         back {back_s:.3e} m"
    );
    let ratio = along_s / along;
    assert!((7.0..13.0).contains(&ratio), "softened deflection ratio {ratio}");
    assert!((7.0..13.0).contains(&(sag_s / sag)), "softened sag ratio {}", sag_s / sag);
}
