//! Time integration of a strand.
//!
//! - [`Integrator::LinearlyImplicitEuler`] (default, haptic rate): one linear solve per step,
//!   `(M + h D + h^2 K) qdot+ = (M + h D) qdot + h F(q, qdot)`, `q+ = q + h qdot+`, with `D = (nu/rho A) M + tau K`
//!   (air drag and internal damping) and `K` the diagonal elastic stiffness. Stable and dissipative. Solved in
//!   O(N) for the velocity change by an articulated-body recursion, without assembling `M`.
//! - [`Integrator::ImplicitMidpoint`]: symplectic, no numerical dissipation; solved by simplified Newton
//!   iterations with the matrix `M + h/2 D + h^2/4 K`. Used to check energy behaviour.
//!
//! A step that would produce a non-finite state is rejected and the previous state kept (an error is
//! returned), so a simulation never explodes silently.

use crate::dynamics::{Dynamics, PointForce};
use crate::error::{Result, StrandError};
use crate::model::StrandModel;
use crate::state::{RootFrame, StrandState};
use nalgebra::{DMatrix, DVector, Rotation3};

/// Largest rotation (rad) any segment's coordinates may add in one step: `|qdot_j| h l`.
pub const MAX_STEP_ROTATION: f64 = 0.5;

/// How long (s) the geometric stiffness of a strand's constraint loads outlasts them: the time constant over
/// which it fades once the loads are gone or smaller ([`Dynamics::geometric_stiffness`]'s `kept` is
/// `exp(-h / GEOMETRIC_STIFFNESS_MEMORY)`, 0.905 a step at 1 ms). A numerical choice, not a fit: ten steps of the
/// 1 kHz step, longer than a contact's on-off chatter (every other step) and short against a comb stroke through
/// a wisp (0.1 s and more). Without it, the heavy wet caucasian tress clamped strand-steps on some tress layouts
/// (docs/combing.md; test `the_heavy_wet_caucasian_tress_is_stable_on_every_layout`).
pub const GEOMETRIC_STIFFNESS_MEMORY: f64 = 0.01;

/// The share of the remembered geometric stiffness a step of `h` s keeps, `exp(-h / GEOMETRIC_STIFFNESS_MEMORY)`
/// (dimensionless; 0.905 at 1 ms): [`Dynamics::geometric_stiffness`]'s `kept`, for the scalar step and the batch.
pub(crate) fn geometric_stiffness_kept(h: f64) -> f64 {
    (-h / GEOMETRIC_STIFFNESS_MEMORY).exp()
}

/// Time-stepping scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// Linearly implicit (semi-implicit) Euler: one evaluation and one Cholesky solve per step.
    #[default]
    LinearlyImplicitEuler,
    /// Implicit midpoint rule with simplified Newton iterations (energy-conserving to second order).
    ImplicitMidpoint,
}

impl RootFrame {
    /// Moves the root along its current velocity and acceleration for `h` seconds (constant accelerations).
    pub fn advance(&mut self, h: f64) {
        self.position += self.velocity * h + self.acceleration * (0.5 * h * h);
        self.velocity += self.acceleration * h;
        let w_mid = self.angular_velocity + self.angular_acceleration * (0.5 * h);
        self.rotation = Rotation3::new(w_mid * h).into_inner() * self.rotation;
        self.angular_velocity += self.angular_acceleration * h;
    }
}

/// A strand ready to simulate: its model, state, integrator and workspace.
#[derive(Debug, Clone)]
pub struct Strand {
    /// Immutable parameters.
    pub model: StrandModel,
    /// Current state.
    pub state: StrandState,
    /// Integration scheme used by [`Strand::step`].
    pub integrator: Integrator,
    /// Workspace and results of the last evaluation.
    pub dynamics: Dynamics,
    /// Number of steps whose velocities were scaled down by the safety net (see [`MAX_STEP_ROTATION`]).
    pub clamped_steps: u64,
    /// The forces the point constraints applied in the last step: (arc length from the root, m; force on the
    /// strand, N). The next linearly implicit step takes their geometric stiffness implicitly
    /// ([`Dynamics::geometric_stiffness`]). Empty after a step without constraints.
    pub constraint_loads: Vec<(f64, nalgebra::Vector3<f64>)>,
    /// Workspace: the step's system matrix, factorized in place.
    system: DMatrix<f64>,
    /// Workspace: right-hand side, then solution, of the step's linear system.
    pub(crate) rhs: DVector<f64>,
    /// A step begun by [`Strand::prepare_step`]: its time step (s) and unconstrained velocities.
    pub(crate) prepared: Option<(f64, DVector<f64>)>,
}

impl Strand {
    /// A strand at its rest shape, at rest, clamped to `root`.
    pub fn new(model: StrandModel, root: RootFrame) -> Result<Self> {
        model.validate()?;
        root.validate()?;
        let state = StrandState::at_rest(&model, root);
        let dynamics = Dynamics::new(&model);
        let n = model.dofs();
        Ok(Self { model, state, integrator: Integrator::default(), dynamics, clamped_steps: 0, constraint_loads: Vec::new(), system: DMatrix::zeros(n, n), rhs: DVector::zeros(n), prepared: None })
    }

    /// Whether the strand's next linearly implicit step takes a geometric stiffness (its last step's constraint
    /// loads, or earlier ones still fading: [`GEOMETRIC_STIFFNESS_MEMORY`]), alone or in a
    /// [`crate::batch::StrandBatch`]'s lane.
    pub fn takes_geometric_stiffness(&self) -> bool {
        !self.constraint_loads.is_empty() || self.dynamics.geometric.iter().any(|&g| g > 0.0)
    }

    /// Whether a step begun by [`Strand::prepare_step`] (or [`crate::batch::StrandBatch::prepare`]) waits for
    /// [`Strand::finish_step`].
    pub fn has_prepared_step(&self) -> bool {
        self.prepared.is_some()
    }

    /// Total energy (kinetic + gravity + elastic) at the current state, J.
    pub fn energy(&mut self) -> f64 {
        self.dynamics.evaluate(&self.model, &self.state, &[], false);
        self.dynamics.total_energy()
    }

    /// Advances the state by `h` seconds with the chosen integrator and `external` point forces (held
    /// constant over the step). The root moves with its own velocity and acceleration. On failure the state
    /// is left unchanged and the error says why.
    pub fn step(&mut self, h: f64, external: &[PointForce]) -> Result<()> {
        self.check_step_input(h, external)?;
        let qdot_new = match self.integrator {
            Integrator::LinearlyImplicitEuler => self.linearly_implicit_velocity(h, external)?,
            Integrator::ImplicitMidpoint => self.midpoint_velocity(h, external)?,
        };
        self.commit_step(h, qdot_new)
    }

    /// Checks the time step and point forces of a step.
    pub(crate) fn check_step_input(&self, h: f64, external: &[PointForce]) -> Result<()> {
        if !(h.is_finite() && h > 0.0) {
            return Err(StrandError::InvalidParameter { field: "dt", reason: format!("must be a finite positive time step, got {h}") });
        }
        for pf in external {
            if !(pf.s.is_finite() && pf.force.iter().chain(pf.torque.iter()).all(|f| f.is_finite())) {
                return Err(StrandError::InvalidParameter { field: "point force", reason: format!("must be finite, got {pf:?}") });
            }
        }
        Ok(())
    }

    /// Applies the new velocities: positions by the integrator's rule, root motion, time. Rejects (and keeps the
    /// old state) if anything is non-finite.
    pub(crate) fn commit_step(&mut self, h: f64, mut qdot_new: DVector<f64>) -> Result<()> {
        // Safety net: a segment may turn by at most MAX_STEP_ROTATION per step. Beyond that the linearized step
        // is meaningless (it happens when a contact drives the nearly massless twist of the reduced model); the
        // velocities are scaled down and the event counted in `clamped_steps`.
        let turn = qdot_new.amax() * h * self.model.segment_length();
        if turn > MAX_STEP_ROTATION {
            qdot_new *= MAX_STEP_ROTATION / turn;
            self.clamped_steps += 1;
        }
        let q_new = match self.integrator {
            Integrator::LinearlyImplicitEuler => &self.state.q + &qdot_new * h,
            Integrator::ImplicitMidpoint => &self.state.q + (&self.state.qdot + &qdot_new) * (0.5 * h),
        };
        if !qdot_new.iter().chain(q_new.iter()).all(|x| x.is_finite()) {
            return Err(StrandError::NonFinite { what: "state", time: self.state.time });
        }
        self.state.q = q_new;
        self.state.qdot = qdot_new;
        self.constraint_loads.clear();
        self.state.root.advance(h);
        self.state.time += h;
        Ok(())
    }

    /// Solves `A x = b` in place with the linearly implicit step's matrix `A = M (1 + h c) + (h tau + h^2) K +
    /// h^2 K_g` at the state of the last sweep (O(N); `K_g` the diagonal geometric stiffness of the last step's
    /// constraint loads, [`Dynamics::geometric`]); false if `A` is not positive definite.
    pub(crate) fn solve_step_matrix(&mut self, h: f64, b: &mut DVector<f64>) -> bool {
        let c = self.model.air_drag / self.model.linear_density();
        self.dynamics.solve_articulated(&self.model, 1.0 + h * c, h * self.model.damping + h * h, h * h, b)
    }

    /// Builds the step's matrix `M (1 + a c) + (a tau + b) K` (with `c = nu / rho A`) into the workspace and
    /// factorizes it in place (Cholesky).
    fn factorize(&mut self, a: f64, b: f64) -> Result<()> {
        let c = self.model.air_drag / self.model.linear_density();
        let d = self.model.dofs_per_segment();
        let rig = self.model.rigidities() * self.model.segment_length();
        self.system.copy_from(&self.dynamics.mass);
        self.system.scale_mut(1.0 + a * c);
        for j in 0..self.system.nrows() {
            self.system[(j, j)] += (a * self.model.damping + b) * rig[j % d];
        }
        if crate::linalg::cholesky_in_place(&mut self.system) {
            Ok(())
        } else {
            Err(StrandError::NotPositiveDefinite { what: "step matrix" })
        }
    }

    /// `qdot+ = qdot + A^-1 (h F - h^2 (K + K_g) qdot)` with `A = M (1 + h c) + (h tau + h^2) K + h^2 K_g`, solved
    /// in O(N) by the articulated-body recursion of [`Dynamics::solve_articulated`] (the dense mass matrix is not
    /// assembled); `K_g` the diagonal geometric stiffness of the last step's constraint loads.
    pub(crate) fn linearly_implicit_velocity(&mut self, h: f64, external: &[PointForce]) -> Result<DVector<f64>> {
        self.dynamics.sweep(&self.model, &self.state, external, true);
        self.dynamics.geometric_stiffness(&self.model, &self.state, &self.constraint_loads, geometric_stiffness_kept(h));
        self.linearly_implicit_rhs(h);
        let mut rhs = std::mem::replace(&mut self.rhs, DVector::zeros(0));
        let ok = self.solve_step_matrix(h, &mut rhs);
        self.rhs = rhs;
        if !ok {
            return Err(StrandError::NotPositiveDefinite { what: "step matrix" });
        }
        Ok(&self.state.qdot + &self.rhs)
    }

    /// The right-hand side `h F - h^2 (K + K_g) qdot` of the linearly implicit step for the velocity change, into
    /// the workspace (the forces and `K_g` must have been evaluated at the current state).
    fn linearly_implicit_rhs(&mut self, h: f64) {
        let d = self.model.dofs_per_segment();
        let rig = self.model.rigidities() * self.model.segment_length();
        for j in 0..self.rhs.len() {
            self.rhs[j] = h * self.dynamics.forces[j] - h * h * (rig[j % d] + self.dynamics.geometric[j]) * self.state.qdot[j];
        }
    }

    /// The same step with the dense mass matrix and a Cholesky factorization (reference for the O(N) path).
    #[cfg(test)]
    fn linearly_implicit_velocity_dense(&mut self, h: f64, external: &[PointForce]) -> Result<DVector<f64>> {
        self.dynamics.evaluate(&self.model, &self.state, external, true);
        self.linearly_implicit_rhs(h);
        self.factorize(h, h * h)?;
        crate::linalg::cholesky_solve_in_place(&self.system, &mut self.rhs);
        Ok(&self.state.qdot + &self.rhs)
    }

    fn midpoint_velocity(&mut self, h: f64, external: &[PointForce]) -> Result<DVector<f64>> {
        let v0 = self.state.qdot.clone();
        let mut v1 = v0.clone();
        let mut mid = self.state.clone();
        let max_iterations = 100;
        let mut last = f64::INFINITY;
        for _ in 0..max_iterations {
            mid.qdot = (&v0 + &v1) * 0.5;
            mid.q = &self.state.q + &mid.qdot * (0.5 * h);
            self.dynamics.evaluate(&self.model, &mid, external, true);
            let mut delta = &self.dynamics.mass * (&v1 - &v0) - &self.dynamics.forces * h;
            self.factorize(0.5 * h, 0.25 * h * h)?;
            crate::linalg::cholesky_solve_in_place(&self.system, &mut delta);
            v1 -= &delta;
            let size = delta.amax();
            let scale = 1.0 + v1.amax();
            // Converged, or stalled at round-off level (the update no longer shrinks).
            if size <= 1e-12 * scale || (size <= 1e-8 * scale && size > 0.5 * last) {
                return Ok(v1);
            }
            last = size;
        }
        Err(StrandError::NoConvergence { solver: "implicit midpoint", iterations: max_iterations, residual: last })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::model::ModelKind;
    use crate::section::CrossSection;
    use nalgebra::Vector3;

    #[test]
    fn the_geometric_stiffness_outlasts_its_loads_and_fades() {
        // A load in one step only: the next steps keep its geometric stiffness times exp(-h / memory) a step
        // (1e-12 relative) while it is above a hundredth of the coordinate's elastic stiffness, then drop it; the
        // strand is then batchable again. A larger load replaces the faded value at once.
        let m = StrandModel::new(ModelKind::Full, 0.2, 12, CrossSection::new(45e-6, 33e-6).unwrap(), Material::default()).unwrap().with_uniform_rest(20.0, 60.0, -15.0);
        let mut s = Strand::new(m, RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.0, 0.0, -1.0), Vector3::y()).unwrap()).unwrap();
        let h = 1e-3;
        let kept = geometric_stiffness_kept(h);
        s.constraint_loads = vec![(0.15, Vector3::new(2e-3, -1e-3, 5e-4))];
        s.linearly_implicit_velocity(h, &[]).unwrap();
        let first = s.dynamics.geometric.clone();
        assert!(first.amax() > 0.0 && s.takes_geometric_stiffness());
        s.constraint_loads.clear();
        let d = s.model.dofs_per_segment();
        let rig = s.model.rigidities() * s.model.segment_length();
        let mut expected = first.clone();
        for step in 1..2000 {
            s.linearly_implicit_velocity(h, &[]).unwrap();
            for (j, e) in expected.iter_mut().enumerate() {
                *e = if *e * kept < 1e-2 * rig[j % d] { 0.0 } else { *e * kept };
                let g = s.dynamics.geometric[j];
                assert!((g - *e).abs() <= 1e-12 * e.abs(), "step {step}, coordinate {j}: {g} vs {e}");
            }
            if !s.takes_geometric_stiffness() {
                assert!(step > 1, "faded in one step");
                break;
            }
        }
        assert!(!s.takes_geometric_stiffness(), "the memory never faded");
        s.constraint_loads = vec![(0.15, Vector3::new(2e-3, -1e-3, 5e-4))];
        s.linearly_implicit_velocity(h, &[]).unwrap();
        assert_eq!(s.dynamics.geometric, first, "a load's own bound is taken at once");
    }

    #[test]
    fn articulated_step_matches_the_dense_solve() {
        // The O(N) recursion and the dense Cholesky solve the same system: 1e-10 relative on qdot+.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let mut m = StrandModel::new(kind, 0.2, 12, CrossSection::new(45e-6, 33e-6).unwrap(), Material::default())
                .unwrap()
                .with_uniform_rest(20.0, 60.0, -15.0);
            m.quadrature_points = 3;
            let mut root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.3, 0.1, -1.0), Vector3::y()).unwrap();
            root.velocity = Vector3::new(0.1, -0.2, 0.05);
            root.angular_velocity = Vector3::new(1.0, 0.5, -2.0);
            let mut s = Strand::new(m, root).unwrap();
            for i in 0..s.model.dofs() {
                s.state.q[i] += 25.0 * ((i as f64) * 1.3).sin();
                s.state.qdot[i] = 40.0 * ((i as f64) * 0.7).cos();
            }
            let pf = [PointForce { s: 0.13, force: Vector3::new(1e-4, -2e-4, 5e-5), torque: Vector3::new(1e-9, 3e-9, -2e-9) }];
            for h in [1e-4, 1e-3, 1e-2] {
                let fast = s.linearly_implicit_velocity(h, &pf).unwrap();
                let dense = s.linearly_implicit_velocity_dense(h, &pf).unwrap();
                let err = (&fast - &dense).norm() / dense.norm();
                assert!(err < 1e-10, "{kind:?} h={h}: relative difference {err}");
                let change = (&dense - &s.state.qdot).norm();
                assert!((&fast - &dense).norm() < 1e-8 * change, "{kind:?} h={h}: velocity change differs");
            }
        }
    }
}
