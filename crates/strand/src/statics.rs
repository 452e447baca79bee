//! Static equilibrium and the sag-free rest shape.
//!
//! Equilibrium minimises the potential `Pi(q) = U_elastic + V_gravity - sum f . r(s)` (constant point forces)
//! with the root held still. Its gradient is minus the generalized forces of [`crate::dynamics`] at zero
//! velocity; the Hessian comes from central differences of that gradient (2 x 2N evaluations, O(N^2)).
//! Newton steps are damped (Levenberg-Marquardt when the Hessian is not positive definite) and
//! backtracked on `Pi`, so the solver also finds the bent state of a strand beyond its buckling length.
//!
//! Sag-free rest shape: because K is diagonal, a groomed shape `q*` stays put under gravity if
//! `q_rest = q* - K^-1 Q_gravity(q*)`; it is stable if `K - dQ_gravity/dq` is positive definite there.

use crate::dynamics::{Dynamics, PointForce};
use crate::error::{Result, StrandError};
use crate::kinematics::{frame_at, segment_frames};
use crate::model::StrandModel;
use crate::state::StrandState;
use nalgebra::{DMatrix, DVector, Vector3};

/// Options of the equilibrium solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticOptions {
    /// Convergence when the largest Newton update is below `tolerance * (1 + max |q|)`. Default 1e-11.
    pub tolerance: f64,
    /// Maximum Newton iterations. Default 200.
    pub max_iterations: usize,
}

impl Default for StaticOptions {
    fn default() -> Self {
        Self { tolerance: 1e-11, max_iterations: 200 }
    }
}

/// A static equilibrium.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// Coordinates at equilibrium, rad/m.
    pub q: DVector<f64>,
    /// Newton iterations used.
    pub iterations: usize,
    /// Whether the Hessian of the potential is positive definite there (a stable equilibrium).
    pub stable: bool,
    /// Potential energy at equilibrium, J.
    pub potential: f64,
}

struct Potential<'a> {
    model: &'a StrandModel,
    state: StrandState,
    external: &'a [PointForce],
    dynamics: Dynamics,
}

impl Potential<'_> {
    fn at(&mut self, q: &DVector<f64>) -> &mut Self {
        self.state.q.copy_from(q);
        self
    }

    /// Potential energy, J.
    fn value(&mut self) -> f64 {
        self.dynamics.evaluate(self.model, &self.state, &[], false);
        let frames = segment_frames(self.model, &self.state);
        let work: f64 = self
            .external
            .iter()
            .map(|pf| pf.force.dot(&frame_at(self.model, &self.state.q, &frames, pf.s).position))
            .sum();
        self.dynamics.elastic_energy + self.dynamics.gravity_energy - work
    }

    /// Gradient of the potential, i.e. minus the generalized static forces.
    fn gradient(&mut self) -> DVector<f64> {
        self.dynamics.evaluate(self.model, &self.state, self.external, false);
        -&self.dynamics.forces
    }

    /// Hessian by central differences of the gradient, symmetrized.
    fn hessian(&mut self, q: &DVector<f64>) -> DMatrix<f64> {
        let n = q.len();
        let mut h = DMatrix::zeros(n, n);
        for j in 0..n {
            let step = 1e-6 * (1.0 + q[j].abs());
            let mut qp = q.clone();
            qp[j] += step;
            let gp = self.at(&qp).gradient();
            qp[j] -= 2.0 * step;
            let gm = self.at(&qp).gradient();
            h.set_column(j, &((gp - gm) / (2.0 * step)));
        }
        self.at(q);
        (&h + h.transpose()) * 0.5
    }
}

/// Whether a symmetric matrix is positive definite (Cholesky succeeds).
fn positive_definite(m: &DMatrix<f64>) -> bool {
    m.clone().cholesky().is_some()
}

/// Solves for the static equilibrium of `model` clamped to `start.root`, starting from `start.q`, under
/// gravity and constant `external` point forces. Velocities of `start` are ignored.
pub fn solve_equilibrium(model: &StrandModel, start: &StrandState, external: &[PointForce], opts: &StaticOptions) -> Result<Equilibrium> {
    model.validate()?;
    start.root.validate()?;
    if external.iter().any(|pf| pf.torque != Vector3::zeros()) {
        return Err(StrandError::InvalidParameter { field: "point force", reason: "statics takes forces only (a point torque has no potential)".into() });
    }
    let mut state = start.clone();
    state.qdot.fill(0.0);
    let mut root = state.root.clone();
    root.velocity.fill(0.0);
    root.angular_velocity.fill(0.0);
    root.acceleration.fill(0.0);
    root.angular_acceleration.fill(0.0);
    state.root = root;
    let mut pot = Potential { model, state, external, dynamics: Dynamics::new(model) };
    let mut q = start.q.clone();
    let mut pi = pot.at(&q).value();
    let k = model.stiffness();
    let mut last = f64::INFINITY;
    for it in 0..opts.max_iterations {
        let g = pot.at(&q).gradient();
        let h = pot.hessian(&q);
        // Levenberg-Marquardt shift (relative to K) until the matrix is positive definite.
        let mut mu = 0.0;
        let step = loop {
            let mut a = h.clone();
            for j in 0..k.len() {
                a[(j, j)] += mu * k[j];
            }
            if let Some(ch) = a.cholesky() {
                break -ch.solve(&g);
            }
            mu = if mu == 0.0 { 1e-6 } else { mu * 10.0 };
            if mu > 1e12 {
                return Err(StrandError::NotPositiveDefinite { what: "static Hessian" });
            }
        };
        // Backtracking on the potential.
        let mut t = 1.0;
        let mut q_new = &q + &step * t;
        let mut pi_new = pot.at(&q_new).value();
        while !(pi_new <= pi + 1e-12 * pi.abs().max(1e-30)) && t > 1e-8 {
            t *= 0.5;
            q_new = &q + &step * t;
            pi_new = pot.at(&q_new).value();
        }
        last = (&step * t).amax();
        q = q_new;
        pi = pi_new;
        if !q.iter().all(|x| x.is_finite()) {
            return Err(StrandError::NonFinite { what: "static solution", time: 0.0 });
        }
        if last <= opts.tolerance * (1.0 + q.amax()) {
            let stable = positive_definite(&pot.hessian(&q));
            return Ok(Equilibrium { q, iterations: it + 1, stable, potential: pi });
        }
    }
    Err(StrandError::NoConvergence { solver: "static equilibrium", iterations: opts.max_iterations, residual: last })
}

/// The sag-free rest shape of a groomed state: returns the model whose rest coordinates keep `groomed.q` in
/// equilibrium under gravity (and constant `external` forces), and whether that equilibrium is stable.
pub fn sag_free_rest(model: &StrandModel, groomed: &StrandState, external: &[PointForce]) -> Result<(StrandModel, bool)> {
    let mut sag_free = model.clone();
    sag_free.set_rest_coordinates(&groomed.q);
    let mut state = groomed.clone();
    state.qdot.fill(0.0);
    let mut dynamics = Dynamics::new(&sag_free);
    dynamics.evaluate(&sag_free, &state, external, false);
    let k = model.stiffness();
    let q_rest = DVector::from_fn(k.len(), |j, _| groomed.q[j] - dynamics.forces[j] / k[j]);
    sag_free.set_rest_coordinates(&q_rest);
    sag_free.validate()?;
    let mut pot = Potential { model: &sag_free, state, external, dynamics };
    let stable = positive_definite(&pot.hessian(&groomed.q));
    Ok((sag_free, stable))
}

/// Natural angular frequencies (rad/s, ascending) of small oscillations about the state `at` (which should be an
/// equilibrium): square roots of the generalized eigenvalues of `H v = w^2 M v`, with H the Hessian of the
/// potential (gravity and elasticity) and M the mass matrix. Modes of an unstable equilibrium (negative
/// eigenvalues) are returned as negative numbers `-sqrt(|lambda|)`.
pub fn natural_frequencies(model: &StrandModel, at: &StrandState) -> Result<Vec<f64>> {
    model.validate()?;
    let mut state = at.clone();
    state.qdot.fill(0.0);
    let mut dynamics = Dynamics::new(model);
    dynamics.evaluate(model, &state, &[], true);
    let l_inv = dynamics
        .mass
        .clone()
        .cholesky()
        .ok_or(StrandError::NotPositiveDefinite { what: "mass matrix" })?
        .l()
        .try_inverse()
        .ok_or(StrandError::NotPositiveDefinite { what: "mass matrix" })?;
    let q = state.q.clone();
    let mut pot = Potential { model, state, external: &[], dynamics };
    let h = pot.hessian(&q);
    let a = &l_inv * h * l_inv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut w: Vec<f64> = a.symmetric_eigen().eigenvalues.iter().map(|&x| x.signum() * x.abs().sqrt()).collect();
    w.sort_by(|a, b| a.total_cmp(b));
    Ok(w)
}

/// Tip position (m) of `model` at coordinates `q` with the root of `state`.
pub fn tip(model: &StrandModel, state: &StrandState, q: &DVector<f64>) -> Vector3<f64> {
    let mut s = state.clone();
    s.q.copy_from(q);
    segment_frames(model, &s)[model.segments].position
}
