//! Point constraints solved inside the linearly implicit step: unilateral contacts with Coulomb friction
//! (a tool's surface, the body or another strand touching the strand) and bilateral pins (a clip holding a
//! point of the strand).
//!
//! The step solves `A qdot+ = b + J^T p` with `A = M + hD + h^2 K` (solved in O(N) per right-hand side by the
//! articulated-body recursion of the step), `J` the Jacobians
//! of the constrained points and `p` their impulses (N s, over the step). With `Y = A^-1 J^T` the point
//! velocities after the step are `u = u_free + W p`, `W = J Y` (the Delassus operator).
//!
//! **Soft, bounded constraints** (after MuJoCo's `solref`, and the "soft step" of Catto's solvers). Every
//! constraint row solves, by projected Gauss-Seidel sweeps,
//!
//! `u - v_obstacle + R p = min(beta e, v_max)` (along the error's direction)
//!
//! - `e` is the position error (a contact's penetration depth, a pin's offset to its target), m;
//! - `beta = omega / (2 zeta + h omega)`, `omega = 1 / (tau zeta)`: the error-reduction rate (1/s) of an
//!   implicit spring-damper with time constant `tau` and damping ratio `zeta` ([`ConstraintOptions`]);
//! - `v_max` caps the speed at which an error is corrected: depenetration never asks a point for more than
//!   `v_max` (m/s) on top of the obstacle's own velocity;
//! - `R = 1 / (h^2 k_max)` is the constraint-force mixing (m/s per N s): each constraint is at most as stiff as
//!   a spring of `k_max` (N/m) acting on the distance the point would have to cover in one step. It makes the
//!   regularized problem `(W + R) p = ...` strictly positive definite, so
//!   - no impulse is unbounded: `|p| <= h^2 k_max (v_max + |u_free - v_obstacle|)` for one constraint, even
//!     where the point can hardly move (next to a clamped root, along a taut strand);
//!   - contradictory constraints (a tooth pressing a strand into the scalp, a kinematic root inside the body)
//!     resolve to a finite compromise instead of an impulse race.
//!   Where the point moves freely (mobility `W >> R`) the constraint is as rigid as before.
//!
//! For a contact the normal impulse is >= 0, the tangential impulse is clamped to the Coulomb cone
//! `|p_t| <= mu p_n`; a pin's impulse follows its target's velocity. After the step the positions are projected
//! back onto the pins (post-stabilization, Cline and Pai 2003), by at most `v_max h` per step, so a pinned point
//! does not drift. The force on the strand is `p / h`; the obstacle receives `-p / h`.

use crate::error::{Result, StrandError};
use crate::integrator::{Integrator, Strand};
use crate::kinematics::{frame_at, segment_frames};
use nalgebra::{DVector, Matrix3, Matrix3xX, Vector3};

/// What a point constraint does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConstraintKind {
    /// Unilateral contact along `normal` (from the obstacle to the strand) with Coulomb friction coefficient
    /// `friction` (dimensionless, >= 0).
    Contact {
        /// Unit normal from the obstacle towards the strand.
        normal: Vector3<f64>,
        /// Penetration depth along the normal, m (>= 0).
        depth: f64,
        /// Coulomb friction coefficient.
        friction: f64,
    },
    /// The strand point at `s` is held at `target` (m, world), moving with the constraint's velocity.
    Pin {
        /// Where the point must be, m.
        target: Vector3<f64>,
    },
    /// Coulomb drag without a normal direction: the point is carried along with the constraint's velocity by
    /// a force of at most `max_force` (N), opposing the relative motion (e.g. a tooth passing through a wisp,
    /// whose parted fibres press on it with a load of their own: `tools::entanglement`).
    Drag {
        /// Largest force, N (>= 0).
        max_force: f64,
    },
}

/// A constraint on the centreline point at arc length `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointConstraint {
    /// Arc length from the root, m.
    pub s: f64,
    /// Contact or pin.
    pub kind: ConstraintKind,
    /// Velocity of the obstacle's surface (contact) or of the pin (m/s).
    pub velocity: Vector3<f64>,
}

/// Options of the constraint solver: the compliance of every constraint (tool, body, hair-hair contacts and
/// pins) and the solver's effort. See the module documentation for the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstraintOptions {
    /// Time constant `tau` of the constraint's error correction (MuJoCo's `solref[0]`), s: a penetration or pin
    /// offset decays like a spring-damper of natural frequency `1 / (tau zeta)`. Default 0.004 (4 haptic steps;
    /// MuJoCo advises at least two steps).
    pub time_constant: f64,
    /// Damping ratio `zeta` of that spring-damper (MuJoCo's `solref[1]`), dimensionless. Default 1 (critical).
    pub damping_ratio: f64,
    /// Largest speed at which a position error is corrected, m/s (on top of the obstacle's velocity). Default
    /// 0.05: a strand pushed out of the scalp or a tooth comes out at 5 cm/s at most.
    pub max_correction_speed: f64,
    /// Largest stiffness of one constraint, N/m: sets the constraint-force mixing `R = 1 / (h^2 k_max)`, so one
    /// constraint's impulse over a step is at most `h^2 k_max` times the velocity change it asks for (force at
    /// most `k_max` times the distance it would make the point cover in one step). Default 100 N/m: near the
    /// root of an H1 fibre the bending stiffness `3 EI / s^3` reaches it at s = 0.6 mm, so only points that
    /// can hardly move are softened. `f64::INFINITY` gives rigid constraints.
    pub max_stiffness: f64,
    /// Projected Gauss-Seidel sweeps. Default 30.
    pub iterations: usize,
}

impl Default for ConstraintOptions {
    fn default() -> Self {
        Self { time_constant: 0.004, damping_ratio: 1.0, max_correction_speed: 0.05, max_stiffness: 100.0, iterations: 30 }
    }
}

impl ConstraintOptions {
    /// The solver before compliance was introduced: rigid constraints (no force mixing, no speed cap) removing
    /// half of a position error per step of `h` seconds. Kept to show what the bounds change.
    pub fn rigid(h: f64) -> Self {
        // beta = omega / (2 zeta + h omega) = 0.5 / h  <=>  omega = 2 zeta / h  <=>  tau = h / (2 zeta^2).
        Self { time_constant: 0.5 * h, damping_ratio: 1.0, max_correction_speed: f64::INFINITY, max_stiffness: f64::INFINITY, iterations: 30 }
    }

    /// Error-reduction rate `beta = omega / (2 zeta + h omega)` with `omega = 1 / (tau zeta)`, 1/s, for a step of
    /// `h` seconds.
    pub fn error_reduction_rate(&self, h: f64) -> f64 {
        let omega = 1.0 / (self.time_constant * self.damping_ratio);
        omega / (2.0 * self.damping_ratio + h * omega)
    }

    /// Constraint-force mixing `R = 1 / (h^2 k_max)`, m/s per N s, for a step of `h` seconds (0: rigid).
    pub fn force_mixing(&self, h: f64) -> f64 {
        1.0 / (h * h * self.max_stiffness)
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, reason: String| Err(StrandError::InvalidParameter { field, reason });
        if !(self.time_constant.is_finite() && self.time_constant > 0.0) {
            return bad("time_constant", format!("must be a finite time > 0 s, got {}", self.time_constant));
        }
        if !(self.damping_ratio.is_finite() && self.damping_ratio > 0.0) {
            return bad("damping_ratio", format!("must be finite and > 0, got {}", self.damping_ratio));
        }
        if !(self.max_correction_speed > 0.0) {
            return bad("max_correction_speed", format!("must be > 0 m/s, got {}", self.max_correction_speed));
        }
        if !(self.max_stiffness > 0.0) {
            return bad("max_stiffness", format!("must be > 0 N/m, got {}", self.max_stiffness));
        }
        Ok(())
    }
}

impl PointConstraint {
    fn validate(&self) -> Result<()> {
        let bad = |what: &str| Err(StrandError::InvalidParameter { field: "constraint", reason: format!("{what} in {self:?}") });
        if !self.s.is_finite() || !self.velocity.iter().all(|x| x.is_finite()) {
            return bad("non-finite arc length or velocity");
        }
        match self.kind {
            ConstraintKind::Contact { normal, depth, friction } => {
                if !normal.iter().all(|x| x.is_finite()) || (normal.norm() - 1.0).abs() > 1e-6 {
                    return bad("contact normal must be a unit vector");
                }
                if !(depth.is_finite() && depth >= 0.0) || !(friction.is_finite() && friction >= 0.0) {
                    return bad("depth and friction must be finite and >= 0");
                }
            }
            ConstraintKind::Pin { target } => {
                if !target.iter().all(|x| x.is_finite()) {
                    return bad("non-finite pin target");
                }
            }
            ConstraintKind::Drag { max_force } => {
                if !(max_force.is_finite() && max_force >= 0.0) {
                    return bad("drag force must be finite and >= 0");
                }
            }
        }
        Ok(())
    }
}

/// Pseudo-inverse of a 3 x 3 Delassus block: directions in which the point cannot move (e.g. along the
/// tangent of a taut, inextensible strand: relative mobility below 1e-4) get no impulse instead of an
/// unbounded one.
fn pinv3(w: &Matrix3<f64>) -> Matrix3<f64> {
    let tol = 1e-4 * w.norm();
    w.pseudo_inverse(tol).unwrap_or_else(|_| Matrix3::zeros())
}

/// Two unit vectors orthogonal to `n` and to each other.
fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let t1 = n.cross(&helper).normalize();
    (t1, n.cross(&t1))
}

impl Strand {
    /// One linearly implicit Euler step of `h` seconds with point forces `external` and point `constraints`.
    /// Returns the impulse (N s) each constraint gave the strand over the step (the force is impulse / h; the
    /// obstacle receives the opposite). On failure the state is left unchanged.
    /// Equal to [`Strand::prepare_step`] followed by [`Strand::finish_step`].
    pub fn step_constrained(
        &mut self,
        h: f64,
        external: &[crate::dynamics::PointForce],
        constraints: &[PointConstraint],
        opts: &ConstraintOptions,
    ) -> Result<Vec<Vector3<f64>>> {
        if constraints.is_empty() {
            return self.step(h, external).map(|_| vec![]);
        }
        for c in constraints {
            c.validate()?;
        }
        opts.validate()?;
        self.prepare_step(h, external)?;
        self.finish_step(constraints, opts)
    }

    /// First half of a linearly implicit Euler step of `h` seconds with point forces `external`: evaluates the
    /// dynamics at the current state and solves the velocities without constraints. Afterwards
    /// `self.dynamics.frames` and `self.dynamics.points` hold the segment frames and Gauss points of the
    /// current state (e.g. to sample the centreline for collision detection at no extra cost). Complete the
    /// step with [`Strand::finish_step`]; until then the state is unchanged.
    pub fn prepare_step(&mut self, h: f64, external: &[crate::dynamics::PointForce]) -> Result<()> {
        self.prepared = None;
        if self.integrator != Integrator::LinearlyImplicitEuler {
            return Err(StrandError::InvalidParameter { field: "integrator", reason: "constraints need the linearly implicit Euler integrator".into() });
        }
        self.check_step_input(h, external)?;
        let v = self.linearly_implicit_velocity(h, external)?;
        self.prepared = Some((h, v));
        Ok(())
    }

    /// Second half of the step begun by [`Strand::prepare_step`]: solves the point `constraints` (at the state
    /// the step was prepared at) and advances the state. Returns each constraint's impulse (N s), as
    /// [`Strand::step_constrained`]. An error if no step was prepared; on failure the state is unchanged.
    pub fn finish_step(&mut self, constraints: &[PointConstraint], opts: &ConstraintOptions) -> Result<Vec<Vector3<f64>>> {
        let Some((h, mut v)) = self.prepared.take() else {
            return Err(StrandError::InvalidParameter { field: "finish_step", reason: "no step was prepared (call prepare_step first)".into() });
        };
        if constraints.is_empty() {
            return self.commit_step(h, v).map(|_| vec![]);
        }
        for c in constraints {
            c.validate()?;
        }
        if let Err(e) = opts.validate() {
            self.prepared = Some((h, v));
            return Err(e);
        }
        // Jacobians from the frames and motion subspaces of the step's own sweep (same state).
        let root = self.state.root.clone();
        let mut jac: Vec<Matrix3xX<f64>> = Vec::with_capacity(constraints.len());
        let mut y: Vec<Matrix3xX<f64>> = Vec::with_capacity(constraints.len());
        let mut bias: Vec<Vector3<f64>> = Vec::with_capacity(constraints.len());
        let mut position: Vec<Vector3<f64>> = Vec::with_capacity(constraints.len());
        for c in constraints {
            let (j, x) = self.dynamics.point_jacobian(&self.model, &self.state, c.s);
            bias.push(root.velocity + root.angular_velocity.cross(&(x - root.position)));
            position.push(x);
            let mut yc = Matrix3xX::zeros(self.model.dofs());
            for k in 0..3 {
                let mut col: DVector<f64> = j.row(k).transpose();
                if !self.resolve_step_matrix(&mut col) {
                    return Err(StrandError::NotPositiveDefinite { what: "step matrix" });
                }
                yc.set_row(k, &col.transpose());
            }
            jac.push(j);
            y.push(yc);
        }
        let n = constraints.len();
        // Delassus blocks W[c][d] = J_c Y_d^T (3 x 3).
        let w: Vec<Vec<Matrix3<f64>>> = (0..n).map(|c| (0..n).map(|d| &jac[c] * y[d].transpose()).collect()).collect();
        let u_free: Vec<Vector3<f64>> = (0..n).map(|c| &jac[c] * &v + bias[c]).collect();
        let mut p = vec![Vector3::zeros(); n];
        let beta = opts.error_reduction_rate(h);
        let v_max = opts.max_correction_speed;
        let mix = opts.force_mixing(h);
        // A point that (almost) cannot move, such as the clamped root, is left out: its constraint could only
        // produce an impulse against the root clamp.
        let mobility = |c: usize| w[c][c].trace();
        let max_mobility = (0..n).map(mobility).fold(0.0, f64::max);
        let active: Vec<bool> = (0..n).map(|c| mobility(c).is_finite() && mobility(c) > 1e-9 * max_mobility).collect();
        // What the sweeps need of each contact, fixed over the iterations: tangent basis, regularized normal
        // mobility `W_nn + R` and the inverse of the regularized tangential Delassus block.
        let contact_frames: Vec<Option<(Vector3<f64>, Vector3<f64>, f64, nalgebra::Matrix2<f64>)>> = (0..n)
            .map(|c| match constraints[c].kind {
                ConstraintKind::Contact { normal, .. } => {
                    let (t1, t2) = tangents(&normal);
                    let wnn = (normal.dot(&(w[c][c] * normal)) + mix).max(1e-300);
                    let wt = Matrix3::from_columns(&[t1, t2, normal]).transpose() * w[c][c] * Matrix3::from_columns(&[t1, t2, normal]);
                    let wt2 = nalgebra::Matrix2::new(wt[(0, 0)] + mix, wt[(0, 1)], wt[(1, 0)], wt[(1, 1)] + mix);
                    Some((t1, t2, wnn, wt2.try_inverse().unwrap_or_else(nalgebra::Matrix2::zeros)))
                }
                ConstraintKind::Pin { .. } | ConstraintKind::Drag { .. } => None,
            })
            .collect();
        // Inverses of the pins' regularized Delassus blocks `W + R I` (pseudo-inverses when rigid); the
        // post-stabilization uses the pseudo-inverses of the blocks themselves.
        let is_pin = |c: usize| matches!(constraints[c].kind, ConstraintKind::Pin { .. });
        let is_drag = |c: usize| matches!(constraints[c].kind, ConstraintKind::Drag { .. });
        let pin_projection: Vec<Matrix3<f64>> = (0..n).map(|c| if is_pin(c) || is_drag(c) { pinv3(&w[c][c]) } else { Matrix3::zeros() }).collect();
        let pin_inverse: Vec<Matrix3<f64>> = (0..n)
            .map(|c| match (is_pin(c) || is_drag(c), mix > 0.0) {
                (false, _) => Matrix3::zeros(),
                (true, true) => (w[c][c] + Matrix3::identity() * mix).try_inverse().unwrap_or_else(|| pinv3(&w[c][c])),
                (true, false) => pin_projection[c],
            })
            .collect();
        let capped = |x: Vector3<f64>| if x.norm() > v_max { x * (v_max / x.norm()) } else { x };
        for _ in 0..opts.iterations.max(1) {
            for c in (0..n).filter(|&c| active[c]) {
                let mut u = u_free[c];
                for d in 0..n {
                    u += w[c][d] * p[d];
                }
                let rel = u - constraints[c].velocity;
                match constraints[c].kind {
                    ConstraintKind::Pin { target } => {
                        let want = capped((target - position[c]) * beta);
                        let dp = pin_inverse[c] * (want - rel - p[c] * mix);
                        p[c] += dp;
                    }
                    ConstraintKind::Drag { max_force } => {
                        // Aim for no relative motion, then clamp to the drag's largest impulse.
                        let mut pc = p[c] + pin_inverse[c] * (-rel - p[c] * mix);
                        let limit = max_force * h;
                        if pc.norm() > limit {
                            pc *= limit / pc.norm();
                        }
                        p[c] = pc;
                    }
                    ConstraintKind::Contact { normal, depth, friction } => {
                        let Some((t1, t2, wnn, wt2_inv)) = contact_frames[c] else { continue };
                        let want_n = (beta * depth).min(v_max);
                        let pn_old = p[c].dot(&normal);
                        let mut pn = (pn_old + (want_n - rel.dot(&normal) - mix * pn_old) / wnn).max(0.0);
                        // Tangential: aim for zero slip, then clamp to the cone.
                        let rt = nalgebra::Vector2::new(rel.dot(&t1), rel.dot(&t2));
                        let pt_old = nalgebra::Vector2::new(p[c].dot(&t1), p[c].dot(&t2));
                        let mut pt = pt_old - wt2_inv * (rt + pt_old * mix);
                        let limit = friction * pn;
                        if pt.norm() > limit {
                            pt *= limit / pt.norm();
                        }
                        if !pn.is_finite() {
                            pn = 0.0;
                        }
                        p[c] = normal * pn + t1 * pt.x + t2 * pt.y;
                    }
                }
                if !p[c].iter().all(|x| x.is_finite()) {
                    p[c] = Vector3::zeros();
                }
            }
        }
        for c in 0..n {
            v += y[c].transpose() * p[c];
        }
        let saved = self.state.clone();
        self.commit_step(h, v)?;
        // Post-stabilization of pins (Cline and Pai 2003): project the positions back onto the pins with the
        // same metric, dq = A^-1 J^T lambda with W lambda = error; two Gauss-Seidel passes per projection.
        let pins: Vec<usize> = (0..n).filter(|&c| matches!(constraints[c].kind, ConstraintKind::Pin { .. })).collect();
        for _ in 0..2 {
            if pins.is_empty() {
                break;
            }
            let frames = segment_frames(&self.model, &self.state);
            let mut lambda = vec![Vector3::zeros(); n];
            let error: Vec<Vector3<f64>> = pins
                .iter()
                .map(|&c| match constraints[c].kind {
                    ConstraintKind::Pin { target } => {
                        let e = target - frame_at(&self.model, &self.state.q, &frames, constraints[c].s).position;
                        // At most `v_max h` per step: a pin far from its target is drawn back, not teleported.
                        if e.norm() > v_max * h { e * (v_max * h / e.norm()) } else { e }
                    }
                    ConstraintKind::Contact { .. } | ConstraintKind::Drag { .. } => Vector3::zeros(),
                })
                .collect();
            for _ in 0..opts.iterations.max(1) {
                for (k, &c) in pins.iter().enumerate().filter(|(_, &c)| active[c]) {
                    let mut r = error[k];
                    for &d in &pins {
                        r -= w[c][d] * lambda[d];
                    }
                    lambda[c] += pin_projection[c] * r;
                }
            }
            for &c in &pins {
                self.state.q += y[c].transpose() * lambda[c];
            }
        }
        if !self.state.q.iter().all(|x| x.is_finite()) {
            self.state = saved;
            return Err(StrandError::NonFinite { what: "pin projection", time: self.state.time });
        }
        Ok(p)
    }
}
