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
