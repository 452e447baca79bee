//! Physics validation of the strand model against analytic or independently computed answers
//! (DESIGN.md section 8). Every tolerance is stated next to its assertion; the figures are in docs/physics.md.

use nalgebra::{DVector, Vector3};
use strand::analytic::{cantilever_frequency, cantilever_tip_deflection, elastica_cantilever_tip, greenhill_critical_length};
use strand::hair_type::HairType;
use strand::helix::segment_transform;
use strand::integrator::{Integrator, Strand};
use strand::kinematics::{centerline, segment_frames};
use strand::model::{ModelKind, StrandModel};
use strand::state::{RootFrame, StrandState};
use strand::statics::{natural_frequencies, sag_free_rest, solve_equilibrium, tip, StaticOptions};

fn h1_model(kind: ModelKind, length: f64, segments: usize) -> StrandModel {
    let h = HairType::H1;
    StrandModel::new(kind, length, segments, h.section().unwrap(), h.material().unwrap()).unwrap()
}

/// Horizontal root along +x, major axis along +y: the strand sags in -z by bending about its major axis.
fn horizontal_root() -> RootFrame {
    RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap()
}

/// Flexural rigidity about the major axis and weight per length.
fn ei_q(m: &StrandModel) -> (f64, f64) {
    (m.rigidities()[1], m.linear_density() * 9.81)
}

fn shooting_tip(ei: f64, q: f64, length: f64) -> (f64, f64) {
    elastica_cantilever_tip(ei, q, length, 20000)
}

#[test]
fn helix_rest_shape_is_exact() {
    // A strand whose segments all have the rest Darboux vector (tau, kappa) is one helix of radius
    // kappa/|Omega|^2 and pitch 2 pi tau/|Omega|^2. Tolerance 1e-9 m (DESIGN.md 8).
    for (kind, omega) in [(ModelKind::Reduced, Vector3::new(40.0, 120.0, 0.0)), (ModelKind::Full, Vector3::new(-25.0, 60.0, 80.0))] {
        let mut m = h1_model(kind, 0.3, 24).with_uniform_rest(omega.x, omega.y, omega.z);
        m.gravity = Vector3::zeros();
        let root = RootFrame::new(Vector3::new(0.01, 0.02, 0.3), Vector3::new(0.0, 0.3, -1.0), Vector3::x()).unwrap();
        let st = StrandState::at_rest(&m, root.clone());
        let w2 = omega.norm_squared();
        let axis = root.rotation * omega / omega.norm();
        // Centre of the circle traced by the projection: from the paper's formula, r0 + R0 (w x n0_perp)/|Omega|.
        let e0 = Vector3::x();
        let om = omega / omega.norm();
        let perp = e0 - om * om.dot(&e0);
        let centre = root.position + root.rotation * (om.cross(&perp) / omega.norm());
        let radius = omega.y.hypot(omega.z) / w2;
        let pitch = 2.0 * std::f64::consts::PI * omega.x / w2;
        for (s, x) in centerline(&m, &st, 97) {
            let (_, p) = segment_transform(&omega, s);
            let exact = root.position + root.rotation * p;
            assert!((x - exact).norm() < 1e-9, "{kind:?} s={s}: {}", (x - exact).norm());
            let rel = x - centre;
            let dist = (rel - axis * axis.dot(&rel)).norm();
            assert!((dist - radius).abs() < 1e-9, "radius {dist} vs {radius}");
            // Advance along the axis is pitch per turn: axial speed tau/|Omega| times s.
            let along = axis.dot(&(x - root.position));
            assert!((along - pitch * s * omega.norm() / (2.0 * std::f64::consts::PI)).abs() < 1e-9);
        }
    }
}

#[test]
fn small_deflection_cantilever() {
    // Tip deflection q L^4 / (8 EI) of a short horizontal strand (deflection/L about 0.3 %).
    // With 32 constant-curvature segments the discretisation error is O(1/N^2); tolerance 0.2 %.
    for kind in [ModelKind::Reduced, ModelKind::Full] {
        let m = h1_model(kind, 0.02, 32);
        let st = StrandState::at_rest(&m, horizontal_root());
        let eq = solve_equilibrium(&m, &st, &[], &StaticOptions::default()).unwrap();
        let t = tip(&m, &st, &eq.q);
        let (ei, q) = ei_q(&m);
        let expected = cantilever_tip_deflection(q, m.length, ei);
        let rel = (-t.z - expected).abs() / expected;
        assert!(rel < 2e-3, "{kind:?}: tip {} vs {expected} ({rel})", -t.z);
        assert!(eq.stable);
    }
}

#[test]
fn large_deflection_cantilever_matches_shooting() {
    // q L^3 / EI = 10: the tip drops by about half the length. Tolerance 2e-3 L on the tip position
    // with 32 segments (error measured: see docs/physics.md).
    let m = h1_model(ModelKind::Reduced, 0.1, 32);
    let (ei, q) = ei_q(&m);
    let (xs, zs) = shooting_tip(ei, q, m.length);
    let st = StrandState::at_rest(&m, horizontal_root());
    let eq = solve_equilibrium(&m, &st, &[], &StaticOptions::default()).unwrap();
    let t = tip(&m, &st, &eq.q);
    let err = ((t.x - xs).powi(2) + (t.z - zs).powi(2)).sqrt();
    assert!(zs < -0.3 * m.length, "the test should be in the large-deflection regime: z = {zs}");
    assert!(err < 2e-3 * m.length, "tip ({}, {}) vs shooting ({xs}, {zs}): error {err}", t.x, t.z);
    assert!(t.y.abs() < 1e-12, "no out-of-plane motion: {}", t.y);
}

#[test]
fn dynamic_cantilever_settles_on_the_static_solution() {
    // The default integrator (linearly implicit Euler, 1 ms) with damping (relaxation time 0.2 s) settles
    // where statics says: tip within 1e-5 L after 3 s.
    let mut m = h1_model(ModelKind::Reduced, 0.1, 16);
    m.damping = 0.2;
    let mut strand = Strand::new(m.clone(), horizontal_root()).unwrap();
    for _ in 0..3000 {
        strand.step(1e-3, &[]).unwrap();
    }
    let eq = solve_equilibrium(&m, &strand.state, &[], &StaticOptions::default()).unwrap();
    let sim_tip = segment_frames(&m, &strand.state)[m.segments].position;
    let err = (sim_tip - tip(&m, &strand.state, &eq.q)).norm();
    assert!(err < 1e-5 * m.length, "error {err}");
}

#[test]
fn cantilever_natural_frequencies() {
    // w_n = (beta_n L)^2 sqrt(EI / (rho A L^4)), beta L = 1.8751, 4.6941 (Euler-Bernoulli).
    // 32 segments: tolerance 0.5 % on the first, 1 % on the second.
    // Without gravity the lowest modes are the bending modes (twist modes are far stiffer).
    let mut m = h1_model(ModelKind::Reduced, 0.05, 32);
    m.gravity = Vector3::zeros();
    let (ei, _) = ei_q(&m);
    let w = natural_frequencies(&m, &StrandState::at_rest(&m, horizontal_root())).unwrap();
    for (n, tol) in [5e-3, 1e-2].into_iter().enumerate() {
        let exact = cantilever_frequency(n, ei, m.linear_density(), m.length);
        assert!((w[n] - exact).abs() < tol * exact, "mode {}: {} vs {exact}", n + 1, w[n]);
    }
}

#[test]
fn simulated_oscillation_has_the_first_natural_period() {
    // Release a slightly bent strand without gravity or damping (implicit midpoint, h = 0.1 ms) and time the
    // tip's zero crossings over two periods: within 1 % of 2 pi / w1 (analytic).
    let mut m = h1_model(ModelKind::Reduced, 0.05, 16);
    m.gravity = Vector3::zeros();
    m.air_drag = 0.0;
    m.damping = 0.0;
    let (ei, _) = ei_q(&m);
    let w1 = cantilever_frequency(0, ei, m.linear_density(), m.length);
    let mut strand = Strand::new(m.clone(), horizontal_root()).unwrap();
    strand.integrator = Integrator::ImplicitMidpoint;
    // First-mode-like initial shape: curvature proportional to (L - s)^2.
    for i in 0..m.segments {
        let s = (i as f64 + 0.5) * m.segment_length();
        strand.state.q[2 * i + 1] = 0.5 * (1.0 - s / m.length).powi(2);
    }
    let h = 1e-4;
    let mut last_z = segment_frames(&m, &strand.state)[m.segments].position.z;
    let mut crossings = vec![];
    while crossings.len() < 5 && strand.state.time < 1.0 {
        strand.step(h, &[]).unwrap();
        let z = segment_frames(&m, &strand.state)[m.segments].position.z;
        if (z > 0.0) != (last_z > 0.0) {
            crossings.push(strand.state.time - h * z / (z - last_z));
        }
        last_z = z;
    }
    let period = crossings[4] - crossings[0];
    let expected = 2.0 * (2.0 * std::f64::consts::PI / w1);
    assert!((period - expected).abs() < 1e-2 * expected, "two periods {period} vs {expected}");
}

#[test]
fn greenhill_buckling_of_a_standing_strand() {
    // A strand standing up under its own weight buckles beyond q L^3 / EI = 7.837.
    // At 0.9 L_c the upright state is stable and a perturbed strand returns to it; at 1.1 L_c it is unstable
    // and the equilibrium is visibly bent (tip off axis by more than 5 % of L).
    let probe = h1_model(ModelKind::Reduced, 0.1, 24);
    let (ei, q) = ei_q(&probe);
    let lc = greenhill_critical_length(ei, q);
    for (factor, should_stand) in [(0.9, true), (1.1, false)] {
        let m = h1_model(ModelKind::Reduced, factor * lc, 24);
        let root = RootFrame::new(Vector3::zeros(), Vector3::z(), Vector3::y()).unwrap();
        let mut st = StrandState::at_rest(&m, root);
        let upright = solve_equilibrium(&m, &st, &[], &StaticOptions::default()).unwrap();
        assert_eq!(upright.stable, should_stand, "upright stability at {factor} L_c");
        for i in 0..m.segments {
            st.q[2 * i + 1] = 0.05;
        }
        let eq = solve_equilibrium(&m, &st, &[], &StaticOptions::default()).unwrap();
        let t = tip(&m, &st, &eq.q);
        let lateral = t.x.hypot(t.y);
        assert!(eq.stable);
        if should_stand {
            assert!(lateral < 1e-6 * m.length, "{factor} L_c: lateral {lateral}");
        } else {
            assert!(lateral > 0.05 * m.length, "{factor} L_c: lateral {lateral}");
        }
    }
}

fn curly_released(kind: ModelKind) -> Strand {
    let m = h1_model(kind, 0.15, 12).with_uniform_rest(20.0, 40.0, 10.0);
    let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(1.0, 0.0, -0.3), Vector3::y()).unwrap();
    Strand::new(m, root).unwrap()
}

#[test]
fn implicit_midpoint_keeps_energy_without_damping() {
    // No drag, no damping: a curly strand falls and swings under gravity for 0.3 s at h = 0.1 ms.
    // Energy drift stays below 1e-3 of the kinetic energy it reaches.
    for kind in [ModelKind::Reduced, ModelKind::Full] {
        let mut strand = curly_released(kind);
        strand.model.air_drag = 0.0;
        strand.model.damping = 0.0;
        strand.integrator = Integrator::ImplicitMidpoint;
        let e0 = strand.energy();
        let (mut drift, mut kmax) = (0.0f64, 0.0f64);
        for _ in 0..3000 {
            strand.step(1e-4, &[]).unwrap();
            let e = strand.energy();
            drift = drift.max((e - e0).abs());
            kmax = kmax.max(strand.dynamics.kinetic_energy);
        }
        assert!(kmax > 0.0);
        assert!(drift < 1e-3 * kmax, "{kind:?}: drift {drift} J, max kinetic {kmax} J");
    }
}

#[test]
fn energy_decreases_with_damping() {
    // With air drag and internal damping, the default integrator at 1 ms never gains energy
    // (per step, allowing 1e-12 J of round-off) and loses most of it within 2 s.
    let mut strand = curly_released(ModelKind::Reduced);
    strand.model.damping = 0.01;
    let mut e = strand.energy();
    let e0 = e;
    let mut e_min = e;
    for _ in 0..2000 {
        strand.step(1e-3, &[]).unwrap();
        let e_new = strand.energy();
        assert!(e_new <= e + 1e-12, "energy rose by {} J at t = {}", e_new - e, strand.state.time);
        e = e_new;
        e_min = e_min.min(e);
    }
    let st = &strand.state;
    let eq = solve_equilibrium(&strand.model, st, &[], &StaticOptions::default()).unwrap();
    let mut at_eq = strand.clone();
    at_eq.state.q = eq.q;
    at_eq.state.qdot.fill(0.0);
    let e_eq = at_eq.energy();
    assert!((e - e_eq) < 0.05 * (e0 - e_eq), "remaining {} of {}", e - e_eq, e0 - e_eq);
}

#[test]
fn reduced_and_full_models_agree_in_planar_bending() {
    // Bending about the major axis only: the full model's extra coordinate stays 0 and both models give
    // the same statics and dynamics (1e-10 relative).
    let mr = h1_model(ModelKind::Reduced, 0.1, 16);
    let mf = h1_model(ModelKind::Full, 0.1, 16);
    let mut sr = Strand::new(mr.clone(), horizontal_root()).unwrap();
    let mut sf = Strand::new(mf.clone(), horizontal_root()).unwrap();
    for _ in 0..300 {
        sr.step(1e-3, &[]).unwrap();
        sf.step(1e-3, &[]).unwrap();
    }
    for i in 0..16 {
        assert!((sr.state.q[2 * i + 1] - sf.state.q[3 * i + 1]).abs() < 1e-10 * sr.state.q.amax());
        assert!(sf.state.q[3 * i + 2].abs() < 1e-12 * sr.state.q.amax());
    }
    let er = solve_equilibrium(&mr, &sr.state, &[], &StaticOptions::default()).unwrap();
    let ef = solve_equilibrium(&mf, &sf.state, &[], &StaticOptions::default()).unwrap();
    let (tr, tf) = (tip(&mr, &sr.state, &er.q), tip(&mf, &sf.state, &ef.q));
    assert!((tr - tf).norm() < 1e-10 * mr.length, "{tr} vs {tf}");
}

#[test]
fn every_preset_is_stable_at_one_millisecond() {
    // Each hair type, with its natural curl, hanging from a root shaken at 2 Hz with 2 cm amplitude for 1 s
    // at h = 1 ms: every step succeeds, the state stays finite and the strand keeps its length (tip within L).
    for h in HairType::ALL {
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (tw, bd) = h.rest_curvature();
            let m = StrandModel::new(kind, 0.25, 16, h.section().unwrap(), h.material().unwrap()).unwrap().with_uniform_rest(tw, bd, 0.0);
            let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.0, 0.2, -1.0), Vector3::x()).unwrap();
            let mut strand = Strand::new(m.clone(), root).unwrap();
            let w = 2.0 * std::f64::consts::PI * 2.0;
            for n in 0..1000 {
                let t = n as f64 * 1e-3;
                strand.state.root.velocity = Vector3::new(0.02 * w * (w * t).cos(), 0.0, 0.0);
                strand.state.root.acceleration = Vector3::new(-0.02 * w * w * (w * t).sin(), 0.0, 0.0);
                strand.step(1e-3, &[]).unwrap_or_else(|e| panic!("{} {kind:?} at t={t}: {e}", h.name));
            }
            let frames = segment_frames(&m, &strand.state);
            let reach = (frames[m.segments].position - strand.state.root.position).norm();
            assert!(reach <= m.length * (1.0 + 1e-9), "{}: {reach}", h.name);
            assert!(strand.state.qdot.iter().all(|v| v.is_finite()));
        }
    }
}

#[test]
fn sag_free_rest_shape_stays_put() {
    // A groomed wavy shape given the sag-free rest coordinates does not move under gravity:
    // after 0.5 s of simulation the tip has moved less than 1e-7 m. (Short enough to be stable: see below.)
    let m = h1_model(ModelKind::Reduced, 0.06, 16);
    let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(1.0, 0.0, 0.2), Vector3::y()).unwrap();
    let mut groomed = StrandState::at_rest(&m, root);
    for i in 0..m.segments {
        groomed.q[2 * i] = 5.0 * (i as f64).sin();
        groomed.q[2 * i + 1] = -8.0 + 4.0 * (0.7 * i as f64).cos();
    }
    let (sag_free, stable) = sag_free_rest(&m, &groomed, &[]).unwrap();
    assert!(stable);
    let mut strand = Strand::new(sag_free.clone(), groomed.root.clone()).unwrap();
    strand.state = groomed.clone();
    let tip0 = segment_frames(&sag_free, &strand.state)[m.segments].position;
    for _ in 0..500 {
        strand.step(1e-3, &[]).unwrap();
    }
    let moved = (segment_frames(&sag_free, &strand.state)[m.segments].position - tip0).norm();
    assert!(moved < 1e-7, "tip moved {moved} m");
    let _ = DVector::<f64>::zeros(1);
}

#[test]
fn sag_free_rest_reports_an_unstable_groom() {
    // A straight strand groomed to stand up, longer than its buckling length, is an equilibrium for any rest
    // shape with Q_gravity = 0, but not a stable one: the stability check must say so.
    let probe = h1_model(ModelKind::Reduced, 0.1, 16);
    let (ei, q) = ei_q(&probe);
    let m = h1_model(ModelKind::Reduced, 1.5 * greenhill_critical_length(ei, q), 16);
    let root = RootFrame::new(Vector3::zeros(), Vector3::z(), Vector3::y()).unwrap();
    let groomed = StrandState::at_rest(&m, root);
    let (_, stable) = sag_free_rest(&m, &groomed, &[]).unwrap();
    assert!(!stable);
}

/// Tip trajectory error of an integrator against the diffsol reference, at times 0.02, 0.04, ..., 0.2 s.
fn integrator_error(integrator: Integrator, h: f64) -> (f64, f64) {
    use strand::reference::{strand_trajectory, ReferenceOptions};
    let mut m = h1_model(ModelKind::Reduced, 0.05, 8).with_uniform_rest(10.0, 30.0, 0.0);
    m.damping = 0.005;
    let root = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap();
    let mut strand = Strand::new(m.clone(), root).unwrap();
    strand.integrator = integrator;
    let times: Vec<f64> = (1..=10).map(|k| 0.02 * k as f64).collect();
    let opts = ReferenceOptions { rtol: 1e-8, atol: 1e-8, ..Default::default() };
    let reference = strand_trajectory(&m, &strand.state, &[], &times, &opts).unwrap();
    let still = strand.state.clone();
    let tip_of = |q: &DVector<f64>| tip(&m, &still, q);
    let (mut err, mut travel) = (0.0f64, 0.0f64);
    let tip0 = tip_of(&strand.state.q);
    let per = (0.02 / h).round() as usize;
    for q_ref in &reference {
        for _ in 0..per {
            strand.step(h, &[]).unwrap();
        }
        err = err.max((tip_of(&strand.state.q) - tip_of(q_ref)).norm());
        travel = travel.max((tip_of(q_ref) - tip0).norm());
    }
    (err, travel)
}

#[test]
fn integrators_converge_to_the_stiff_reference_solution() {
    // A curly 5 cm strand falling under gravity for 0.2 s, against diffsol's BDF (rtol = atol = 1e-8; the
    // midpoint errors below show the reference is good to better than 1e-6 m).
    // Linearly implicit Euler is first order: halving h halves the error (ratio 1.6..2.4), and at the haptic
    // step h = 1 ms the tip error stays below 5 % of the distance the tip travels. Implicit midpoint is second
    // order (ratio 3..5).
    let (e1, travel) = integrator_error(Integrator::LinearlyImplicitEuler, 1e-3);
    let (e2, _) = integrator_error(Integrator::LinearlyImplicitEuler, 5e-4);
    println!("linearly implicit Euler: tip error {e1:.3e} m at 1 ms, {e2:.3e} m at 0.5 ms (tip travel {travel:.3e} m)");
    assert!(e1 < 0.05 * travel, "error {e1} vs travel {travel}");
    assert!((1.6..2.4).contains(&(e1 / e2)), "order: ratio {}", e1 / e2);
    let (m1, _) = integrator_error(Integrator::ImplicitMidpoint, 1e-3);
    let (m2, _) = integrator_error(Integrator::ImplicitMidpoint, 5e-4);
    println!("implicit midpoint: tip error {m1:.3e} m at 1 ms, {m2:.3e} m at 0.5 ms");
    assert!((3.0..5.0).contains(&(m1 / m2)), "order: ratio {}", m1 / m2);
}
