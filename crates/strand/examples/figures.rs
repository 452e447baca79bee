//! Prints the validation figures of docs/physics.md (errors against analytic and independent answers,
//! against the number of segments). Run: `cargo run --release -p coiffure-strand --example figures`.

use nalgebra::Vector3;
use strand::analytic::{cantilever_frequency, cantilever_tip_deflection, elastica_cantilever_tip, greenhill_critical_length};
use strand::integrator::{Integrator, Strand};
use strand::kinematics::segment_frames;
use strand::statics::{natural_frequencies, solve_equilibrium, tip, StaticOptions};
use strand::{HairType, ModelKind, RootFrame, StrandModel, StrandState};

fn h1(kind: ModelKind, length: f64, n: usize) -> StrandModel {
    let h = HairType::H1;
    StrandModel::new(kind, length, n, h.section().unwrap(), h.material().unwrap()).unwrap()
}

fn horizontal() -> RootFrame {
    RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap()
}

fn static_tip(m: &StrandModel, root: RootFrame) -> Vector3<f64> {
    let st = StrandState::at_rest(m, root);
    let eq = solve_equilibrium(m, &st, &[], &StaticOptions::default()).unwrap();
    tip(m, &st, &eq.q) - st.root.position
}

/// Smallest length at which the upright straight strand is unstable (bisection on the Hessian's definiteness).
fn model_critical_length(n: usize) -> f64 {
    let probe = h1(ModelKind::Reduced, 0.1, n);
    let (ei, q) = (probe.rigidities()[1], probe.linear_density() * 9.81);
    let lc = greenhill_critical_length(ei, q);
    let (mut lo, mut hi) = (0.8 * lc, 1.2 * lc);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        let m = h1(ModelKind::Reduced, mid, n);
        let root = RootFrame::new(Vector3::zeros(), Vector3::z(), Vector3::y()).unwrap();
        let st = StrandState::at_rest(&m, root);
        let eq = solve_equilibrium(&m, &st, &[], &StaticOptions::default()).unwrap();
        if eq.stable { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

fn main() {
    println!("## Convergence with the number of segments N (H1 fibre, reduced model)\n");
    println!("| N | small deflection, rel. error | large deflection tip error / L | w1 rel. error | w2 rel. error | Greenhill L_c rel. error |");
    println!("|---|---|---|---|---|---|");
    for n in [4, 8, 16, 32, 64] {
        let m = h1(ModelKind::Reduced, 0.02, n);
        let (ei, q) = (m.rigidities()[1], m.linear_density() * 9.81);
        let small = (-static_tip(&m, horizontal()).z - cantilever_tip_deflection(q, m.length, ei)).abs() / cantilever_tip_deflection(q, m.length, ei);
        let m = h1(ModelKind::Reduced, 0.1, n);
        let (xs, zs) = elastica_cantilever_tip(ei, q, m.length, 20000);
        let t = static_tip(&m, horizontal());
        let large = ((t.x - xs).powi(2) + (t.z - zs).powi(2)).sqrt() / m.length;
        let mut m = h1(ModelKind::Reduced, 0.05, n);
        m.gravity = Vector3::zeros();
        let w = natural_frequencies(&m, &StrandState::at_rest(&m, horizontal())).unwrap();
        let e1 = (w[0] / cantilever_frequency(0, ei, m.linear_density(), m.length) - 1.0).abs();
        let e2 = if w.len() > 1 { (w[1] / cantilever_frequency(1, ei, m.linear_density(), m.length) - 1.0).abs() } else { f64::NAN };
        let lc = (model_critical_length(n) / greenhill_critical_length(ei, q) - 1.0).abs();
        println!("| {n} | {small:.2e} | {large:.2e} | {e1:.2e} | {e2:.2e} | {lc:.2e} |");
    }
    let m = h1(ModelKind::Reduced, 0.1, 32);
    let (ei, q) = (m.rigidities()[1], m.linear_density() * 9.81);
    let (xs, zs) = elastica_cantilever_tip(ei, q, m.length, 20000);
    println!("\nLarge-deflection reference (shooting, L = 0.1 m, qL^3/EI = {:.2}): tip x = {xs:.6} m, z = {zs:.6} m", q * m.length.powi(3) / ei);

    println!("\n## Gauss points per segment (N = 16, large-deflection cantilever, 1 s of dynamics)\n");
    println!("| points | static tip error / L | tip after 1 s vs 8 points (m) |");
    println!("|---|---|---|");
    let run = |g: usize| {
        let mut m = h1(ModelKind::Reduced, 0.1, 16);
        m.quadrature_points = g;
        let mut s = Strand::new(m.clone(), horizontal()).unwrap();
        for _ in 0..1000 {
            s.step(1e-3, &[]).unwrap();
        }
        (static_tip(&m, horizontal()), segment_frames(&m, &s.state)[16].position)
    };
    let (_, ref_dyn) = run(8);
    for g in [1, 2, 3, 4] {
        let (st, dy) = run(g);
        println!("| {g} | {:.2e} | {:.2e} |", ((st.x - xs).powi(2) + (st.z - zs).powi(2)).sqrt() / 0.1, (dy - ref_dyn).norm());
    }

    println!("\n## Energy (curly H1 strand, L = 0.15 m, 12 segments, released under gravity, 0.3 s)\n");
    for (name, integ, h, damp) in [
        ("implicit midpoint, no damping, h = 0.1 ms", Integrator::ImplicitMidpoint, 1e-4, false),
        ("implicit midpoint, no damping, h = 1 ms", Integrator::ImplicitMidpoint, 1e-3, false),
        ("linearly implicit Euler, no damping, h = 1 ms", Integrator::LinearlyImplicitEuler, 1e-3, false),
        ("linearly implicit Euler, drag + damping, h = 1 ms", Integrator::LinearlyImplicitEuler, 1e-3, true),
    ] {
        let m = h1(ModelKind::Reduced, 0.15, 12).with_uniform_rest(20.0, 40.0, 0.0);
        let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(1.0, 0.0, -0.3), Vector3::y()).unwrap();
        let mut s = Strand::new(m, root).unwrap();
        if !damp {
            s.model.air_drag = 0.0;
            s.model.damping = 0.0;
        }
        s.integrator = integ;
        let e0 = s.energy();
        let (mut drift, mut kmax, mut rises) = (0.0f64, 0.0f64, 0usize);
        let mut last = e0;
        let steps = (0.3 / h) as usize;
        for _ in 0..steps {
            s.step(h, &[]).unwrap();
            let e = s.energy();
            drift = drift.max((e - e0).abs());
            kmax = kmax.max(s.dynamics.kinetic_energy);
            if e > last + 1e-15 { rises += 1; }
            last = e;
        }
        println!("- {name}: max |E - E0| = {drift:.3e} J = {:.2e} of the peak kinetic energy {kmax:.3e} J; final E - E0 = {:.3e} J; steps where E rose: {rises}/{steps}", drift / kmax, last - e0);
    }

    println!("\n## Reduced vs full model");
    let a = static_tip(&h1(ModelKind::Reduced, 0.1, 16), horizontal());
    let b = static_tip(&h1(ModelKind::Full, 0.1, 16), horizontal());
    println!("- planar bending (major axis horizontal), L = 0.1 m: tips differ by {:.2e} m", (a - b).norm());
    let vert = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::z()).unwrap();
    let a = static_tip(&h1(ModelKind::Reduced, 0.02, 16), vert.clone());
    let b = static_tip(&h1(ModelKind::Full, 0.02, 16), vert);
    println!("- major axis vertical, L = 0.02 m: reduced tip z = {:.4e} m (must twist to sag), full tip z = {:.4e} m (bends about the stiff axis)", a.z, b.z);
}
