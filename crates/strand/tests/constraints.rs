//! Point constraints in the step: pins (clip) and contacts with friction, against analytic answers.

use nalgebra::Vector3;
use strand::constraint::{ConstraintKind, ConstraintOptions, PointConstraint};
use strand::kinematics::{frame_at, segment_frames};
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};

fn h1(length: f64, n: usize) -> StrandModel {
    let h = HairType::H1;
    StrandModel::new(ModelKind::Reduced, length, n, h.section().unwrap(), h.material().unwrap()).unwrap()
}

fn point(s: &Strand, at: f64) -> Vector3<f64> {
    frame_at(&s.model, &s.state.q, &segment_frames(&s.model, &s.state), at).position
}

#[test]
fn a_pinned_point_stays_put_while_the_root_shakes() {
    // A curly 15 cm strand pinned at mid-length while its root is shaken (2 cm at 2 Hz) for 1 s at 1 ms:
    // the pinned point stays within 1e-6 m of its target at every step.
    let m = h1(0.15, 16).with_uniform_rest(10.0, 30.0, 0.0);
    let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(1.0, 0.0, -0.5), Vector3::y()).unwrap();
    let mut s = Strand::new(m, root).unwrap();
    let target = point(&s, 0.075);
    let opts = ConstraintOptions::default();
    let w = 2.0 * std::f64::consts::PI * 2.0;
    let mut worst = 0.0f64;
    for n in 0..1000 {
        let t = n as f64 * 1e-3;
        s.state.root.velocity = Vector3::new(0.02 * w * (w * t).cos(), 0.0, 0.0);
        s.state.root.acceleration = Vector3::new(-0.02 * w * w * (w * t).sin(), 0.0, 0.0);
        let pin = PointConstraint { s: 0.075, kind: ConstraintKind::Pin { target }, velocity: Vector3::zeros() };
        s.step_constrained(1e-3, &[], &[pin], &opts).unwrap();
        worst = worst.max((point(&s, 0.075) - target).norm());
    }
    println!("largest pin drift: {worst:.3e} m");
    assert!(worst < 1e-6, "pinned point drifted {worst} m");
}

#[test]
fn a_propped_cantilever_carries_three_eighths_of_its_weight() {
    // A short horizontal strand (small deflection) resting at its tip on a support at the root's height:
    // the support force of a propped cantilever under uniform load is 3 q L / 8 (Euler-Bernoulli).
    // After 2 s the contact force is within 2 % of it (16 segments), the tip sits on the support within
    // 1e-7 m, and friction stays inside the Coulomb cone.
    let mut m = h1(0.02, 16);
    m.damping = 0.05;
    let root = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap();
    let mut s = Strand::new(m.clone(), root).unwrap();
    let opts = ConstraintOptions::default();
    let h = 1e-3;
    let mut force = Vector3::zeros();
    for _ in 0..2000 {
        let tip = point(&s, m.length);
        let contact = PointConstraint {
            s: m.length,
            kind: ConstraintKind::Contact { normal: Vector3::z(), depth: (-tip.z).max(0.0), friction: 0.3 },
            velocity: Vector3::zeros(),
        };
        let p = s.step_constrained(h, &[], &[contact], &opts).unwrap();
        force = p[0] / h;
        assert!(force.z >= 0.0, "a contact only pushes");
        assert!(force.xy().norm() <= 0.3 * force.z + 1e-15, "friction outside the cone");
    }
    let q = m.linear_density() * 9.81;
    let expected = 3.0 * q * m.length / 8.0;
    println!("support force {:.6e} N, 3qL/8 = {expected:.6e} N", force.z);
    assert!((force.z - expected).abs() < 0.02 * expected, "support force {} vs 3qL/8 = {expected}", force.z);
    assert!(point(&s, m.length).z.abs() < 1e-7, "tip at {}", point(&s, m.length).z);
}

#[test]
fn bad_constraints_are_rejected_without_changing_the_state() {
    let m = h1(0.05, 8);
    let root = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap();
    let mut s = Strand::new(m, root).unwrap();
    let before = s.state.clone();
    let bad = [
        PointConstraint { s: f64::NAN, kind: ConstraintKind::Pin { target: Vector3::zeros() }, velocity: Vector3::zeros() },
        PointConstraint { s: 0.01, kind: ConstraintKind::Pin { target: Vector3::new(f64::INFINITY, 0.0, 0.0) }, velocity: Vector3::zeros() },
        PointConstraint { s: 0.01, kind: ConstraintKind::Contact { normal: Vector3::new(0.0, 0.0, 2.0), depth: 0.0, friction: 0.1 }, velocity: Vector3::zeros() },
        PointConstraint { s: 0.01, kind: ConstraintKind::Contact { normal: Vector3::z(), depth: -1.0, friction: 0.1 }, velocity: Vector3::zeros() },
    ];
    for c in bad {
        assert!(s.step_constrained(1e-3, &[], &[c], &ConstraintOptions::default()).is_err(), "{c:?}");
        assert_eq!(s.state, before);
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Bounds of the soft constraints (ConstraintOptions: compliance, correction speed). Each case is also run with
// `ConstraintOptions::rigid`, the solver as it was before the compliance, to show that the bound is not
// trivially met.
// ---------------------------------------------------------------------------------------------------------------

/// Largest speed of any sampled centreline point (every 1 mm), m/s, from the state's velocities: the points'
/// displacement over a tiny time `dt` of free motion along `qdot` (root velocity included).
fn max_point_speed(s: &Strand) -> f64 {
    let dt = 1e-7;
    let mut ahead = s.clone();
    ahead.state.q += &s.state.qdot * dt;
    ahead.state.root.advance(dt);
    let n = (s.model.length / 1e-3).round() as usize;
    (0..=n)
        .map(|i| {
            let at = s.model.length * i as f64 / n as f64;
            (point(&ahead, at) - point(s, at)).norm() / dt
        })
        .fold(0.0, f64::max)
}

/// A hanging 10 cm H1 strand of 16 segments, root at the origin. Full model: it bends both ways (the reduced
/// model bends only about its soft axis, and a push along the other axis could not move it at all).
fn hanging() -> Strand {
    let h = HairType::H1;
    let m = StrandModel::new(ModelKind::Full, 0.1, 16, h.section().unwrap(), h.material().unwrap()).unwrap();
    let root = RootFrame::new(Vector3::zeros(), -Vector3::z(), Vector3::x()).unwrap();
    Strand::new(m, root).unwrap()
}

#[test]
fn a_contact_next_to_the_root_gets_a_bounded_impulse() {
    // A tooth moving at 0.25 m/s along +x, 1 mm deep into the strand 0.5 mm below its clamped root, where the
    // point can hardly move. One step of 1 ms. The impulse obeys the single-constraint bound
    // |p| <= h^2 k_max (v_max + |v_tooth|) (1e-9 relative), and no point of the strand moves faster than the
    // tooth plus v_max (1e-6 m/s). Rigid (the old solver): the impulse asked for is far beyond.
    let (h, v) = (1e-3, 0.25);
    let contact = PointConstraint {
        s: 0.5e-3,
        kind: ConstraintKind::Contact { normal: Vector3::x(), depth: 1e-3, friction: 0.2 },
        velocity: Vector3::new(v, 0.0, 0.0),
    };
    let opts = ConstraintOptions::default();
    let mut s = hanging();
    let p = s.step_constrained(h, &[], &[contact], &opts).unwrap()[0];
    let bound = h * h * opts.max_stiffness * (opts.max_correction_speed + v);
    let speed = max_point_speed(&s);
    let mut rigid = hanging();
    let p_rigid = rigid.step_constrained(h, &[], &[contact], &ConstraintOptions::rigid(h)).unwrap()[0];
    let speed_rigid = max_point_speed(&rigid);
    println!("soft: impulse {:.3e} N s (bound {bound:.3e}), fastest point {speed:.3e} m/s", p.norm());
    println!("rigid: impulse {:.3e} N s, fastest point {speed_rigid:.3e} m/s", p_rigid.norm());
    assert!(p.norm() <= bound * (1.0 + 1e-9), "impulse {} above the bound {bound}", p.norm());
    assert!(p.x > 0.0, "the tooth pushes");
    assert!(speed <= v + opts.max_correction_speed + 1e-6, "a point moves at {speed} m/s");
    assert!(p_rigid.norm() > 10.0 * bound, "the rigid solve stays within the bound ({})", p_rigid.norm());
}

#[test]
fn a_strand_pinched_between_a_tooth_and_the_scalp_gets_a_finite_compromise() {
    // The scalp is the plane x = -1 mm (normal +x); a tooth (the plane x = x_t, normal -x) comes from x = 1 mm
    // at 0.25 m/s and stops 0.5 mm closer to the scalp than a hair's diameter allows: the point 2 cm down a
    // hanging strand is pinched between contradictory contacts (it cannot be outside both). Over 100 steps of
    // 1 ms every impulse stays within h^2 k_max (v_max + 0.25 m/s + the point's own speed) (1e-9 relative), the
    // impulses settle (the last two steps agree to 1 %) on a finite compromise, and no point of the strand moves
    // faster than 0.5 m/s.
    let h = 1e-3;
    let r = HairType::H1.major_diameter / 2.0;
    let scalp_x = -1e-3;
    let stop = scalp_x + 2.0 * r - 0.5e-3;
    let run = |opts: &ConstraintOptions| {
        let mut s = hanging();
        let (mut worst, mut fastest, mut last) = (0.0f64, 0.0f64, vec![]);
        let mut bound_ok = true;
        for n in 0..100 {
            let (x_t, v_t) = if 1e-3 - 0.25 * n as f64 * h > stop { (1e-3 - 0.25 * (n + 1) as f64 * h, -0.25) } else { (stop, 0.0) };
            let x_t = x_t.max(stop);
            let x = point(&s, 0.02).x;
            let scalp = PointConstraint {
                s: 0.02,
                kind: ConstraintKind::Contact { normal: Vector3::x(), depth: (scalp_x + r - x).max(0.0), friction: 0.0 },
                velocity: Vector3::zeros(),
            };
            let tooth = PointConstraint {
                s: 0.02,
                kind: ConstraintKind::Contact { normal: -Vector3::x(), depth: (x - (x_t - r)).max(0.0), friction: 0.2 },
                velocity: Vector3::new(v_t, 0.0, 0.0),
            };
            let own = max_point_speed(&s);
            let p = s.step_constrained(h, &[], &[scalp, tooth], opts).unwrap();
            let bound = h * h * opts.max_stiffness * (opts.max_correction_speed + 0.25 + own);
            bound_ok &= p.iter().all(|p| p.norm() <= bound * (1.0 + 1e-9));
            worst = worst.max(p[0].norm().max(p[1].norm()));
            fastest = fastest.max(max_point_speed(&s));
            last.push(p[1].norm());
        }
        (worst, fastest, bound_ok, last)
    };
    let (worst, fastest, bound_ok, last) = run(&ConstraintOptions::default());
    let (worst_rigid, fastest_rigid, _, _) = run(&ConstraintOptions::rigid(h));
    println!("soft: largest impulse {worst:.3e} N s, fastest point {fastest:.3e} m/s, last {:.3e}", last[last.len() - 1]);
    println!("rigid: largest impulse {worst_rigid:.3e} N s, fastest point {fastest_rigid:.3e} m/s");
    assert!(bound_ok, "an impulse above its bound");
    assert!(worst.is_finite() && fastest < 0.5, "fastest point {fastest} m/s");
    let (a, b) = (last[last.len() - 2], last[last.len() - 1]);
    assert!(b > 0.0 && (a - b).abs() <= 0.01 * b, "impulses still changing: {a} then {b}");
    assert!(worst_rigid > 10.0 * worst, "the rigid solve is as tame ({worst_rigid})");
}

#[test]
fn a_kinematic_root_pushed_into_the_body_is_not_kicked_out() {
    // The body is the half-space z > 0 above a hanging strand's root (outward normal -z, the scalp seen from
    // below). The root is driven into it at 0.1 m/s for 50 ms (5 mm deep at the end), as a lattice pushed by a
    // tool once did. Every sampled point (every 1.25 mm) inside the body or within a hair radius of it gets a
    // frictionless body contact. Each step every impulse stays within h^2 k_max (v_max + the point's speed)
    // (1e-9 relative), and no point of the strand moves faster than 0.5 m/s (the root moves at 0.1 m/s).
    let h = 1e-3;
    let radius = HairType::H1.major_diameter / 2.0;
    let run = |opts: &ConstraintOptions| {
        let mut s = hanging();
        s.state.root.velocity = Vector3::new(0.0, 0.0, 0.1);
        let (mut worst, mut fastest, mut bound_ok) = (0.0f64, 0.0f64, true);
        for _ in 0..50 {
            let mut cons = Vec::new();
            let own = max_point_speed(&s);
            for i in 0..=80 {
                let at = 0.1 * i as f64 / 80.0;
                let z = point(&s, at).z;
                if z > -radius {
                    cons.push(PointConstraint { s: at, kind: ConstraintKind::Contact { normal: -Vector3::z(), depth: z + radius, friction: 0.0 }, velocity: Vector3::zeros() });
                }
            }
            let bound = h * h * opts.max_stiffness * (opts.max_correction_speed + own);
            let p = s.step_constrained(h, &[], &cons, opts).unwrap();
            let total: f64 = p.iter().map(|p| p.norm()).sum();
            bound_ok &= p.iter().all(|p| p.norm() <= bound * (1.0 + 1e-9));
            worst = worst.max(total);
            fastest = fastest.max(max_point_speed(&s));
        }
        (worst, fastest, bound_ok)
    };
    let opts = ConstraintOptions::default();
    let (worst, fastest, bound_ok) = run(&opts);
    let (worst_rigid, fastest_rigid, _) = run(&ConstraintOptions::rigid(h));
    println!("soft: largest total impulse {worst:.3e} N s ({:.3e} N), fastest point {fastest:.3e} m/s", worst / h);
    println!("rigid: largest total impulse {worst_rigid:.3e} N s ({:.3e} N), fastest point {fastest_rigid:.3e} m/s", worst_rigid / h);
    assert!(bound_ok, "an impulse above its bound");
    assert!(fastest < 0.5, "a point moves at {fastest} m/s");
    assert!(worst_rigid > 10.0 * worst, "the rigid solve is as tame ({worst_rigid})");
}

#[test]
fn a_drag_carries_a_free_point_up_to_its_bound() {
    // A drag at the tip of a hanging 10 cm strand, its obstacle moving at 0.1 m/s along +x (a tooth passing
    // through a wisp). With a generous bound (1 N) the tip leaves the step at the obstacle's velocity (within 2 %:
    // the soft constraint's force mixing R = 1 / (h^2 k_max) against the tip's far larger mobility); with a tight
    // bound (1 uN, below what carrying the tip takes) the impulse is exactly the bound times h (1e-12 relative)
    // and pulls along the relative motion (+x); with a zero bound the step is the free step.
    let v = Vector3::new(0.1, 0.0, 0.0);
    let opts = ConstraintOptions::default();
    let drag = |max_force: f64| PointConstraint { s: 0.1, kind: ConstraintKind::Drag { max_force, slip_speed: 0.0 }, velocity: v };
    let h = 1e-3;
    let tip_velocity = |s: &Strand| {
        let mut ahead = s.clone();
        ahead.state.q += &s.state.qdot * 1e-7;
        (point(&ahead, 0.1) - point(s, 0.1)) / 1e-7
    };
    let mut s = hanging();
    let p = s.step_constrained(h, &[], &[drag(1.0)], &opts).unwrap();
    let u = tip_velocity(&s);
    println!("carried: tip velocity {u:?}, impulse {:?}", p[0]);
    assert!((u - v).norm() < 0.02 * v.norm(), "tip velocity {u} against the obstacle's {v}");
    let mut s = hanging();
    let p = s.step_constrained(h, &[], &[drag(1e-6)], &opts).unwrap();
    assert!((p[0].norm() - 1e-6 * h).abs() < 1e-12 * 1e-6 * h, "impulse {} against the bound {}", p[0].norm(), 1e-6 * h);
    assert!(p[0].x > 0.99 * p[0].norm(), "the drag pulls along the relative motion: {:?}", p[0]);
    // Regularised (slip speed 1 m/s against the relative speed of 0.1 m/s: the obstacle's, the straight hanging
    // tip having no free velocity): the bound is scaled by that relative speed over the slip speed.
    let mut s = hanging();
    let slow = PointConstraint { kind: ConstraintKind::Drag { max_force: 1e-6, slip_speed: 1.0 }, ..drag(1.0) };
    let p = s.step_constrained(h, &[], &[slow], &opts).unwrap();
    let want = 1e-6 * h * 0.1;
    assert!((p[0].norm() - want).abs() < 1e-9 * want, "regularised impulse {} against {want}", p[0].norm());
    let mut free = hanging();
    free.step(h, &[]).unwrap();
    let mut s = hanging();
    s.step_constrained(h, &[], &[drag(0.0)], &opts).unwrap();
    assert!((&s.state.q - &free.state.q).amax() < 1e-15 && (&s.state.qdot - &free.state.qdot).amax() < 1e-12);
    let bad = PointConstraint { kind: ConstraintKind::Drag { max_force: f64::NAN, slip_speed: 0.0 }, ..drag(1.0) };
    assert!(hanging().step_constrained(h, &[], &[bad], &opts).is_err());
}

#[test]
fn a_sliding_drag_opposes_the_relative_motion_it_leaves() {
    // A tooth sliding down a hanging 10 cm strand (0.25 m/s along the strand, 1 cm/s across it) at 3 cm from the
    // root, with a bound well below what carrying the point takes: the impulse is the bound times h and opposes the
    // point's velocity relative to the tooth after the step (Coulomb's maximum dissipation; within 0.01 rad, the
    // finite-difference velocity's error), at 1 and at 0.25 ms. Shortening the impulse that would stop the point
    // turns it along the strand, where the inextensible strand hardly moves, and leaves the part across it short.
    let opts = ConstraintOptions::default();
    let v = Vector3::new(0.01, 0.0, -0.25);
    for h in [1e-3, 2.5e-4] {
        let mut s = hanging();
        let at = 0.03;
        let drag = PointConstraint { s: at, kind: ConstraintKind::Drag { max_force: 2e-6, slip_speed: 0.0 }, velocity: v };
        let p = s.step_constrained(h, &[], &[drag], &opts).unwrap();
        let mut ahead = s.clone();
        ahead.state.q += &s.state.qdot * 1e-7;
        let u = (point(&ahead, at) - point(&s, at)) / 1e-7 - v;
        let angle = (-p[0]).angle(&u);
        println!("h {h}: impulse {:?}, relative velocity after {u:?}, angle {angle:.2e} rad", p[0]);
        assert!((p[0].norm() - 2e-6 * h).abs() < 1e-9 * 2e-6 * h, "impulse {} against the bound", p[0].norm());
        assert!(angle < 0.01, "h {h}: the drag's impulse is {angle} rad off the relative motion's opposite");
    }
}

#[test]
fn a_cushion_pushes_with_its_load_until_its_point_reaches_the_obstacle() {
    // A cushion at the tip of a hanging 10 cm strand (a spine pressing a wisp's outer fibres), normal +x.
    // Clear of the obstacle (depth < 0): the step is the free step under the point force `load` along the normal
    // (an independent path: the force in the step's right-hand side; 1e-9 relative), the impulse exactly load x h,
    // and its friction at most mu load h however fast the obstacle slides along the strand. Packed (depth > 0):
    // with no load it is the plain contact, to the bit; with a load below the contact's push the contact's push,
    // above it the load.
    let n = Vector3::x();
    let h = 1e-3;
    let opts = ConstraintOptions::default();
    let cushion = |depth: f64, load: f64, v: Vector3<f64>| PointConstraint { s: 0.1, kind: ConstraintKind::Cushion { normal: n, depth, friction: 0.3, load, stiffness: 0.0 }, velocity: v };
    let load = 2e-6;
    let mut s = hanging();
    let p = s.step_constrained(h, &[], &[cushion(-1e-4, load, Vector3::zeros())], &opts).unwrap()[0];
    assert!((p - n * load * h).norm() <= 1e-15 * load * h, "impulse {p:?}");
    let mut forced = hanging();
    forced.step(h, &[strand::PointForce { s: 0.1, force: n * load, torque: Vector3::zeros() }]).unwrap();
    let scale = forced.state.qdot.amax();
    assert!(scale > 0.0 && (&s.state.qdot - &forced.state.qdot).amax() <= 1e-9 * scale, "velocities differ by {:e} of {scale:e}", (&s.state.qdot - &forced.state.qdot).amax());
    let sliding = Vector3::new(0.0, 0.0, 0.5);
    let p = hanging().step_constrained(h, &[], &[cushion(-1e-4, load, sliding)], &opts).unwrap()[0];
    let tangential = (p - n * p.dot(&n)).norm();
    assert!((p.dot(&n) - load * h).abs() <= 1e-15 * load * h && tangential <= 0.3 * load * h * (1.0 + 1e-12) && tangential > 0.0, "impulse {p:?}");
    let v = Vector3::new(0.25, 0.0, 0.0);
    let plain = PointConstraint { s: 0.1, kind: ConstraintKind::Contact { normal: n, depth: 1e-4, friction: 0.3 }, velocity: v };
    let pc = hanging().step_constrained(h, &[], &[plain], &opts).unwrap()[0];
    assert_eq!(hanging().step_constrained(h, &[], &[cushion(1e-4, 0.0, v)], &opts).unwrap()[0], pc);
    let below = hanging().step_constrained(h, &[], &[cushion(1e-4, 0.1 * pc.x / h, v)], &opts).unwrap()[0];
    assert!((below - pc).norm() <= 1e-12 * pc.norm(), "{below:?} vs {pc:?}");
    let above = hanging().step_constrained(h, &[], &[cushion(1e-4, 10.0 * pc.x / h, v)], &opts).unwrap()[0];
    assert!((above.x - 10.0 * pc.x).abs() <= 1e-12 * above.x, "{above:?} vs {pc:?}");
    let stiff = |k: f64| PointConstraint { kind: ConstraintKind::Cushion { normal: n, depth: -1e-4, friction: 0.3, load, stiffness: k }, ..cushion(0.0, 0.0, v) };
    for bad in [cushion(f64::NAN, load, v), cushion(-1e-4, -1.0, v), cushion(0.0, f64::INFINITY, v), stiff(-1.0), stiff(f64::NAN)] {
        assert!(hanging().step_constrained(h, &[], &[bad], &opts).is_err());
    }
}

#[test]
fn a_stiff_cushion_is_an_implicit_spring() {
    // A cushion of stiffness k at the tip of a hanging 10 cm strand, its obstacle coming at 0.25 m/s along the
    // normal: the impulse is the layer's load at the step's end, h (load + k h (v_obstacle - u) . n) with u the tip's
    // velocity after the step (measured on the stepped strand by a finite difference; 1e-4 relative, where the
    // explicit load, with the velocity before the step, is 75 % off); and a layer far too stiff for an
    // explicit step (k h^2 / m of the tip's share of the strand ~ 100) stays bounded over 200 steps: the tip never
    // moves faster than the obstacle and the impulse stays below k times the obstacle's travel.
    let n = Vector3::x();
    let (h, v) = (1e-3, Vector3::new(0.25, 0.0, 0.0));
    let opts = ConstraintOptions::default();
    let tip_velocity = |s: &Strand| {
        let mut ahead = s.clone();
        ahead.state.q += &s.state.qdot * 1e-7;
        ahead.state.root.advance(1e-7);
        (point(&ahead, 0.1) - point(s, 0.1)) / 1e-7
    };
    let (load, k) = (1e-6, 0.05);
    let cushion = |load: f64, k: f64| PointConstraint { s: 0.1, kind: ConstraintKind::Cushion { normal: n, depth: -1e-4, friction: 0.0, load, stiffness: k }, velocity: v };
    let mut s = hanging();
    let p = s.step_constrained(h, &[], &[cushion(load, k)], &opts).unwrap()[0];
    let u = tip_velocity(&s);
    let want = h * (load + k * h * (v - u).dot(&n));
    println!("impulse {:.6e} N s, tip {:.4e} m/s, spring {want:.6e}", p.x, u.x);
    assert!((p.x - want).abs() <= 1e-4 * want, "impulse {} against {want}", p.x);
    assert!(p.x > h * load, "the obstacle coming closer raises the load");
    let stiff = 1e3;
    let mut s = hanging();
    for step in 1..=200 {
        let travel = v.x * h * step as f64;
        let p = s.step_constrained(h, &[], &[cushion(0.0, stiff)], &opts).unwrap()[0];
        assert!(p.x >= 0.0 && p.x <= h * stiff * travel, "step {step}: impulse {}", p.x);
        assert!(max_point_speed(&s) <= 1.5 * v.x, "step {step}: a point at {} m/s", max_point_speed(&s));
    }
}

/// Two identical horizontal cantilevers side by side along x, roots `gap` apart in z, whose tips are held on the
/// same height by one contact between them (`linked`: a [`ConstraintLink`] solving both strands together) or
/// the upper tip by an obstacle that follows the lower tip, which moves freely (`!linked`). Returns the contact force on the
/// upper strand (N, z) and the tips' heights (m) after `seconds`.
fn tips_pressed_together(gap: f64, linked: bool, seconds: f64) -> (f64, f64, f64) {
    use strand::constraint::{solve, ConstraintLink};
    let mut m = h1(0.02, 16);
    m.damping = 0.05;
    let at = |z: f64| RootFrame::new(Vector3::new(0.0, 0.0, z), Vector3::x(), Vector3::y()).unwrap();
    let (mut upper, mut lower) = (Strand::new(m.clone(), at(gap)).unwrap(), Strand::new(m.clone(), at(0.0)).unwrap());
    let opts = ConstraintOptions::default();
    let h = 1e-3;
    let mut force = 0.0;
    for _ in 0..(seconds / h).round() as usize {
        let (a, b) = (point(&upper, m.length), point(&lower, m.length));
        // The upper tip must stay at or below the lower one: normal -z from the lower strand to the upper.
        let depth = (a.z - b.z).max(0.0);
        let down = PointConstraint { s: m.length, kind: ConstraintKind::Contact { normal: -Vector3::z(), depth, friction: 0.0 }, velocity: Vector3::zeros() };
        let up = PointConstraint { kind: ConstraintKind::Contact { normal: Vector3::z(), depth, friction: 0.0 }, ..down };
        if linked {
            upper.prepare_step(h, &[]).unwrap();
            lower.prepare_step(h, &[]).unwrap();
            let mut rows = vec![upper.constraint_rows(&[down], &opts).unwrap(), lower.constraint_rows(&[up], &opts).unwrap()];
            solve(&mut rows, &[ConstraintLink { first: (0, 0), second: (1, 0) }], &opts);
            let pb = lower.apply_constraints(rows.pop().unwrap(), &opts).unwrap();
            let pa = upper.apply_constraints(rows.pop().unwrap(), &opts).unwrap();
            assert!((pa[0] + pb[0]).norm() <= 1e-15 * pa[0].norm().max(1e-30), "the strands take opposite impulses");
            force = pa[0].z / h;
        } else {
            force = upper.step_constrained(h, &[], &[down], &opts).unwrap()[0].z / h;
            lower.step(h, &[]).unwrap();
        }
    }
    (force, point(&upper, m.length).z, point(&lower, m.length).z)
}

#[test]
fn two_strands_pressed_together_share_the_contact() {
    // Two identical cantilevers (H1, 2 cm, 16 segments) whose roots are 0.2 mm apart in z, their tips held at one
    // height by a contact between them, solved together (a link). Linear statics: each tip moves gap / 2 and the
    // contact force is half of what holds one tip against an obstacle at the other, free, tip
    // (F = 3 EI gap / (2 L^3) against 3 EI gap / L^3). After 2 s: force ratio 0.5 within 2 %, the tips at the
    // same height within 1 % of the gap, each moved gap / 2 within 3 % (from the free sag, which both share).
    let gap = 2e-4;
    let (f_linked, za, zb) = tips_pressed_together(gap, true, 2.0);
    let (f_fixed, _, free_lower) = tips_pressed_together(gap, false, 2.0);
    println!("linked force {f_linked:.4e} N, fixed-obstacle force {f_fixed:.4e} N, tips {za:.6e} / {zb:.6e} m, free tip {free_lower:.6e} m");
    assert!(f_linked < 0.0 && f_fixed < 0.0, "the contact pushes the upper strand down");
    assert!((f_linked / f_fixed - 0.5).abs() < 0.01, "force ratio {}", f_linked / f_fixed);
    assert!((za - zb).abs() < 0.01 * gap, "tips {za} and {zb}");
    let moved_down = free_lower + gap - za;
    let moved_up = zb - free_lower;
    assert!((moved_down / (0.5 * gap) - 1.0).abs() < 0.03, "upper tip moved {moved_down}");
    assert!((moved_up / (0.5 * gap) - 1.0).abs() < 0.03, "lower tip moved {moved_up}");
}

/// Rows of a pair of cantilevers (as [`tips_pressed_together`], roots `gap` apart in z and `x0` along y) in
/// their first step: the upper strand's tip on the lower one's (row 0 of each, to be linked), and a contact
/// pressing the upper strand's middle down by `press` (m), which couples the upper strand's two rows.
fn pair_rows(gap: f64, x0: f64, press: f64, opts: &ConstraintOptions) -> Vec<strand::constraint::ConstraintRows> {
    let mut m = h1(0.02, 16);
    m.damping = 0.05;
    let at = |z: f64| RootFrame::new(Vector3::new(0.0, x0, z), Vector3::x(), Vector3::y()).unwrap();
    let (mut upper, mut lower) = (Strand::new(m.clone(), at(gap)).unwrap(), Strand::new(m.clone(), at(0.0)).unwrap());
    upper.prepare_step(1e-3, &[]).unwrap();
    lower.prepare_step(1e-3, &[]).unwrap();
    let contact = |s: f64, normal: Vector3<f64>, depth: f64| PointConstraint { s, kind: ConstraintKind::Contact { normal, depth, friction: 0.3 }, velocity: Vector3::zeros() };
    let middle = contact(0.5 * m.length, -Vector3::z(), press);
    vec![
        upper.constraint_rows(&[contact(m.length, -Vector3::z(), gap), middle], opts).unwrap(),
        lower.constraint_rows(&[contact(m.length, Vector3::z(), gap)], opts).unwrap(),
    ]
}

#[test]
fn groups_of_linked_strands_stop_sweeping_on_their_own() {
    // Two pairs of strands, each pair linked by one contact, solved in one call: each pair (a group) stops once
    // its own sweep changed no impulse by more than the tolerance, so the impulses equal bit for bit those of
    // each pair solved alone, and the call runs as many sweeps as the slower pair (the pairs converge at
    // different rates: checked).
    use strand::constraint::{solve, ConstraintLink};
    let opts = ConstraintOptions { tolerance: 0.1, iterations: 200, ..ConstraintOptions::default() };
    let link = |a: usize| ConstraintLink { first: (a, 0), second: (a + 1, 0) };
    let (a, b) = (|| pair_rows(2e-4, 0.0, 1e-3, &opts), || pair_rows(5e-4, 0.01, 3e-3, &opts));
    let (mut alone_a, mut alone_b) = (a(), b());
    let n_a = solve(&mut alone_a, &[link(0)], &opts);
    let n_b = solve(&mut alone_b, &[link(0)], &opts);
    assert!(n_a != n_b && n_a.max(n_b) < opts.iterations, "sweeps {n_a} and {n_b}");
    let mut both: Vec<_> = a().into_iter().chain(b()).collect();
    assert_eq!(solve(&mut both, &[link(0), link(2)], &opts), n_a.max(n_b));
    for (together, alone) in both.iter().zip(alone_a.iter().chain(&alone_b)) {
        assert_eq!(together.impulses, alone.impulses);
    }
}
