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
use nalgebra::{Matrix3, Vector3};

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
    /// whose parted fibres press on it with a load of their own: `tools::entanglement`). Regularised below
    /// `slip_speed`: the largest force is `max_force min(1, |u| / slip_speed)`, with `u` the point's velocity
    /// relative to the constraint's without the drag's own impulse (what the rest of the step gives it), so a
    /// point the drag would hold at rest creeps instead, and the force comes up continuously as the relative
    /// motion starts (no jump from holding to sliding). 0: plain Coulomb.
    Drag {
        /// Largest force, N (>= 0).
        max_force: f64,
        /// Relative speed at and above which the drag may reach `max_force`, m/s (>= 0; 0: always).
        slip_speed: f64,
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
    /// Most projected Gauss-Seidel sweeps per solve. Default 10: the local interaction starts each solve from the
    /// last step's impulses ([`ConstraintRows::warm_start`]), so the sweeps of successive steps add up while the
    /// contacts persist (with hair-hair contacts the linked solve seldom reaches `tolerance`; 30 cold sweeps a
    /// step cost a third of the haptic step, bench/HISTORY.md).
    pub iterations: usize,
    /// The sweeps of a group of strands (one strand, or strands linked by contacts with each other) stop early
    /// once a whole sweep changed none of the group's impulses by more than `tolerance` times its largest
    /// impulse (dimensionless, >= 0; 0 always runs `iterations` sweeps). Default 1e-6.
    pub tolerance: f64,
}

impl Default for ConstraintOptions {
    fn default() -> Self {
        Self { time_constant: 0.004, damping_ratio: 1.0, max_correction_speed: 0.05, max_stiffness: 100.0, iterations: 10, tolerance: 1e-6 }
    }
}

impl ConstraintOptions {
    /// The solver before compliance was introduced: rigid constraints (no force mixing, no speed cap) removing
    /// half of a position error per step of `h` seconds. Kept to show what the bounds change.
    pub fn rigid(h: f64) -> Self {
        // beta = omega / (2 zeta + h omega) = 0.5 / h  <=>  omega = 2 zeta / h  <=>  tau = h / (2 zeta^2).
        Self { time_constant: 0.5 * h, damping_ratio: 1.0, max_correction_speed: f64::INFINITY, max_stiffness: f64::INFINITY, iterations: 30, tolerance: 1e-6 }
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
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad("tolerance", format!("must be finite and >= 0, got {}", self.tolerance));
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
            ConstraintKind::Drag { max_force, slip_speed } => {
                if !(max_force.is_finite() && max_force >= 0.0) {
                    return bad("drag force must be finite and >= 0");
                }
                if !(slip_speed.is_finite() && slip_speed >= 0.0) {
                    return bad("drag slip speed must be finite and >= 0");
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

/// `w p` for a 3 x 3 block, written out: the same sums in the same order as nalgebra's product (column by
/// column), without its generic loops.
#[inline(always)]
fn mul3(w: &Matrix3<f64>, p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        w[(0, 0)] * p.x + w[(0, 1)] * p.y + w[(0, 2)] * p.z,
        w[(1, 0)] * p.x + w[(1, 1)] * p.y + w[(1, 2)] * p.z,
        w[(2, 0)] * p.x + w[(2, 1)] * p.y + w[(2, 2)] * p.z,
    )
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
    /// Equal to [`Strand::constraint_rows`], [`solve`] for this strand alone and [`Strand::apply_constraints`].
    pub fn finish_step(&mut self, constraints: &[PointConstraint], opts: &ConstraintOptions) -> Result<Vec<Vector3<f64>>> {
        if self.prepared.is_none() {
            return Err(StrandError::InvalidParameter { field: "finish_step", reason: "no step was prepared (call prepare_step first)".into() });
        }
        if constraints.is_empty() {
            let (h, v) = self.prepared.take().expect("checked above");
            return self.commit_step(h, v).map(|_| vec![]);
        }
        let mut rows = self.constraint_rows(constraints, opts)?;
        let _ = solve(std::slice::from_mut(&mut rows), &[], opts);
        self.apply_constraints(rows, opts)
    }

    /// The rows of `constraints` in the prepared step (Jacobians, their responses `Y = A^-1 J^T`, the Delassus
    /// blocks and the unconstrained point velocities), for [`solve`]; the step stays prepared. Errors if no
    /// step was prepared, a constraint or `opts` is invalid, or the step matrix fails.
    pub fn constraint_rows(&mut self, constraints: &[PointConstraint], opts: &ConstraintOptions) -> Result<ConstraintRows> {
        let mut rows = ConstraintRows::default();
        self.fill_constraint_rows(constraints, opts, &mut rows)?;
        Ok(rows)
    }

    /// [`Strand::constraint_rows`] into `rows`, reusing its storage (no allocation once it has grown): for a
    /// workspace kept across steps. On error `rows` is left empty.
    pub fn fill_constraint_rows(&mut self, constraints: &[PointConstraint], opts: &ConstraintOptions, rows: &mut ConstraintRows) -> Result<()> {
        rows.clear();
        let Some((h, _)) = self.prepared.as_ref() else {
            return Err(StrandError::InvalidParameter { field: "constraint_rows", reason: "no step was prepared (call prepare_step first)".into() });
        };
        let h = *h;
        for c in constraints {
            c.validate()?;
        }
        opts.validate()?;
        let root = self.state.root.clone();
        let n = constraints.len();
        let dofs = self.model.dofs();
        let d_seg = self.model.dofs_per_segment();
        let size = 3 * dofs;
        rows.h = h;
        rows.dofs = dofs;
        rows.constraints.extend_from_slice(constraints);
        rows.jac.resize(size, 0.0);
        rows.reduced.resize(n * size, 0.0);
        rows.pivoted.resize(n * size, 0.0);
        for (c, pc) in constraints.iter().enumerate() {
            let jac = &mut rows.jac[..];
            let (x, span) = self.dynamics.point_jacobian_into(&self.model, &self.state, pc.s, jac);
            let bias = root.velocity + root.angular_velocity.cross(&(x - root.position));
            let (lc, dlc) = (&mut rows.reduced[c * size..(c + 1) * size], &mut rows.pivoted[c * size..(c + 1) * size]);
            if !self.dynamics.reduce_articulated3(&self.model, jac, span / d_seg, lc, dlc) {
                rows.clear();
                return Err(StrandError::NotPositiveDefinite { what: "step matrix" });
            }
            // J v over the Jacobian's nonzero columns (the others add exact zeros).
            let v = &self.prepared.as_ref().expect("checked above").1;
            let mut u = Vector3::zeros();
            for (m, col) in jac[..3 * span].chunks_exact(3).enumerate() {
                u += Vector3::new(col[0], col[1], col[2]) * v[m];
            }
            rows.u_free.push(u + bias);
            rows.span.push(span);
            rows.pin_error.push(match pc.kind {
                ConstraintKind::Pin { target } => target - x,
                ConstraintKind::Contact { .. } | ConstraintKind::Drag { .. } => Vector3::zeros(),
            });
        }
        // Delassus blocks W[c][d] = J_c A^-1 J_d^T = sum_m (L^-1 J_c^T)[m] (D^-1 L^-1 J_d^T)[m]^T (3 x 3), over the
        // columns both reduced right-hand sides have (beyond a point's segment its own are zero). W is
        // symmetric, so only c <= d is computed.
        rows.w.resize(n * n, Matrix3::zeros());
        for c in 0..n {
            let lc = &rows.reduced[c * size..(c + 1) * size];
            for d in c..n {
                let common = 3 * rows.span[c].min(rows.span[d]);
                let dlc = &rows.pivoted[d * size..d * size + common];
                // The outer products summed entry by entry (the same sums in the same order as nalgebra's
                // `block += a * b^T`, without its generic loops).
                let mut b = [[0.0f64; 3]; 3];
                for (jm, ym) in lc[..common].chunks_exact(3).zip(dlc.chunks_exact(3)) {
                    for (row, &j) in b.iter_mut().zip(jm) {
                        row[0] += j * ym[0];
                        row[1] += j * ym[1];
                        row[2] += j * ym[2];
                    }
                }
                let block = Matrix3::new(b[0][0], b[0][1], b[0][2], b[1][0], b[1][1], b[1][2], b[2][0], b[2][1], b[2][2]);
                rows.w[c * n + d] = block;
                rows.w[d * n + c] = block.transpose();
            }
        }
        let mix = opts.force_mixing(h);
        // A point that (almost) cannot move, such as the clamped root, is left out: its constraint could only
        // produce an impulse against the root clamp.
        let mobility = |c: usize| rows.w[c * n + c].trace();
        let max_mobility = (0..n).map(mobility).fold(0.0, f64::max);
        for c in 0..n {
            let active = mobility(c).is_finite() && mobility(c) > 1e-9 * max_mobility;
            rows.active.push(active);
        }
        // What the sweeps need of each constraint, fixed over the iterations: for a contact its tangent basis,
        // regularized normal mobility `W_nn + R` and the inverse of the regularized tangential Delassus block;
        // for a pin or drag the inverse of its regularized Delassus block `W + R I` (pseudo-inverse when rigid),
        // and for a pin the pseudo-inverse of the block itself (the post-stabilization's).
        for (c, pc) in constraints.iter().enumerate() {
            let w = rows.w[c * n + c];
            let inverse = |projection: Matrix3<f64>| if mix > 0.0 { (w + Matrix3::identity() * mix).try_inverse().unwrap_or_else(|| pinv3(&w)) } else { projection };
            rows.rule.push(match pc.kind {
                ConstraintKind::Contact { normal, .. } => Rule::Contact(ContactFrame::new(&normal, &w, mix)),
                ConstraintKind::Pin { .. } => {
                    let projection = pinv3(&w);
                    Rule::Pin { inverse: inverse(projection), projection }
                }
                ConstraintKind::Drag { .. } => Rule::Drag { inverse: inverse(pinv3(&w)) },
            });
        }
        rows.impulses.resize(n, Vector3::zeros());
        Ok(())
    }

    /// Completes the prepared step with the impulses [`solve`] found for `rows` (built by this strand's
    /// [`Strand::constraint_rows`] in this step, given by value or by reference): the velocities take `Y^T p`,
    /// the state advances, and the positions are projected back onto the pins. Returns each constraint's
    /// impulse (N s). On failure the state is unchanged.
    pub fn apply_constraints(&mut self, rows: impl std::borrow::Borrow<ConstraintRows>, opts: &ConstraintOptions) -> Result<Vec<Vector3<f64>>> {
        let rows = rows.borrow();
        let Some((h, mut v)) = self.prepared.take() else {
            return Err(StrandError::InvalidParameter { field: "apply_constraints", reason: "no step was prepared (call prepare_step first)".into() });
        };
        let n = rows.len();
        if rows.dofs != v.len() || (rows.h - h).abs() > 1e-15 * h {
            self.prepared = Some((h, v));
            return Err(StrandError::InvalidParameter { field: "apply_constraints", reason: "the rows were not built for this strand's prepared step".into() });
        }
        // The velocity change of all the impulses at once: A^-1 J^T p (one articulated solve per strand).
        if !self.add_response(rows, &rows.impulses, v.as_mut_slice()) {
            self.prepared = Some((h, v));
            return Err(StrandError::NonFinite { what: "constraint response", time: self.state.time });
        }
        let constraints = &rows.constraints;
        // Post-stabilization of pins (Cline and Pai 2003): project the positions back onto the pins with the
        // same metric, dq = A^-1 J^T lambda with W lambda = error; two Gauss-Seidel passes per projection. The
        // state before the step is kept to restore it if the projection fails (commit_step checks its own).
        let pins: Vec<usize> = (0..n).filter(|&c| matches!(constraints[c].kind, ConstraintKind::Pin { .. })).collect();
        let saved = (!pins.is_empty()).then(|| self.state.clone());
        self.commit_step(h, v)?;
        let v_max = opts.max_correction_speed;
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
                for (k, &c) in pins.iter().enumerate().filter(|(_, &c)| rows.active[c]) {
                    let Rule::Pin { projection, .. } = rows.rule[c] else { continue };
                    let mut r = error[k];
                    for &d in &pins {
                        r -= rows.w[c * n + d] * lambda[d];
                    }
                    lambda[c] += projection * r;
                }
            }
            let mut q = std::mem::replace(&mut self.state.q, nalgebra::DVector::zeros(0));
            let finite = self.add_response(rows, &lambda, q.as_mut_slice());
            self.state.q = q;
            if !finite {
                break;
            }
        }
        if let Some(saved) = saved.filter(|_| !self.state.q.iter().all(|x| x.is_finite())) {
            self.state = saved;
            return Err(StrandError::NonFinite { what: "pin projection", time: self.state.time });
        }
        Ok(rows.impulses.clone())
    }
}

impl Strand {
    /// Adds `A^-1 J^T p` (the generalized response to the impulses `p`, one per constraint of `rows`, N s) to
    /// `out` (dofs), with the step matrix of the prepared step: the rows' reduced right-hand sides summed
    /// (`L^-1 J^T p`), then one back-substitution for all of them. False if
    /// the response is not finite (`out` unchanged).
    fn add_response(&mut self, rows: &ConstraintRows, p: &[Vector3<f64>], out: &mut [f64]) -> bool {
        let mut g = std::mem::replace(&mut self.rhs, nalgebra::DVector::zeros(0));
        if g.len() != rows.dofs {
            g = nalgebra::DVector::zeros(rows.dofs);
        }
        g.fill(0.0);
        let mut any = false;
        for (c, p) in p.iter().enumerate().take(rows.len()) {
            if p.x == 0.0 && p.y == 0.0 && p.z == 0.0 {
                continue;
            }
            any = true;
            // The reduced right-hand side of J_c^T p (linear in p): L^-1 J_c^T p.
            let reduced = &rows.reduced[c * 3 * rows.dofs..c * 3 * rows.dofs + 3 * rows.span[c]];
            for (o, l) in g.iter_mut().zip(reduced.chunks_exact(3)) {
                *o += l[0] * p.x + l[1] * p.y + l[2] * p.z;
            }
        }
        let ok = !any || self.dynamics.back_substitute1(&self.model, g.as_mut_slice());
        if ok && any {
            for (o, x) in out.iter_mut().zip(g.iter()) {
                *o += x;
            }
        }
        self.rhs = g;
        ok
    }
}

/// What the sweeps need of a contact, fixed over the iterations: the tangent basis, the regularized normal
/// mobility `W_nn + R` (m/s per N s) and the inverse of the regularized tangential Delassus block.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ContactFrame {
    t1: Vector3<f64>,
    t2: Vector3<f64>,
    wnn: f64,
    wt2_inv: nalgebra::Matrix2<f64>,
}

impl ContactFrame {
    /// For a contact along `normal` with the 3 x 3 Delassus block `w` and force mixing `mix`.
    fn new(normal: &Vector3<f64>, w: &Matrix3<f64>, mix: f64) -> Self {
        let (t1, t2) = tangents(normal);
        let wnn = (normal.dot(&(w * normal)) + mix).max(1e-300);
        let basis = Matrix3::from_columns(&[t1, t2, *normal]);
        let wt = basis.transpose() * w * basis;
        let wt2 = nalgebra::Matrix2::new(wt[(0, 0)] + mix, wt[(0, 1)], wt[(1, 0)], wt[(1, 1)] + mix);
        Self { t1, t2, wnn, wt2_inv: wt2.try_inverse().unwrap_or_else(nalgebra::Matrix2::zeros) }
    }

    /// The contact's new impulse from its old one `p_old` and the relative velocity `rel` of the point to the
    /// obstacle (both without this iteration's update): normal impulse `>= 0` aiming at the separation speed
    /// `want_n`, tangential impulse aiming at no slip, clamped to the Coulomb cone of `friction`.
    fn update(&self, normal: &Vector3<f64>, friction: f64, want_n: f64, rel: &Vector3<f64>, p_old: &Vector3<f64>, mix: f64) -> Vector3<f64> {
        let pn_old = p_old.dot(normal);
        let mut pn = (pn_old + (want_n - rel.dot(normal) - mix * pn_old) / self.wnn).max(0.0);
        let rt = nalgebra::Vector2::new(rel.dot(&self.t1), rel.dot(&self.t2));
        let pt_old = nalgebra::Vector2::new(p_old.dot(&self.t1), p_old.dot(&self.t2));
        let mut pt = pt_old - self.wt2_inv * (rt + pt_old * mix);
        let limit = friction * pn;
        if pt.norm() > limit {
            pt *= limit / pt.norm();
        }
        if !pn.is_finite() {
            pn = 0.0;
        }
        normal * pn + self.t1 * pt.x + self.t2 * pt.y
    }
}

/// What the sweeps need of one constraint besides its Delassus blocks, fixed over the iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rule {
    /// A contact's tangent basis and regularized mobilities.
    Contact(ContactFrame),
    /// A pin: the inverse of its regularized Delassus block `W + R I` (m/s per N s, inverted) and the
    /// pseudo-inverse of `W` itself (the post-stabilization's).
    Pin { inverse: Matrix3<f64>, projection: Matrix3<f64> },
    /// A drag: the inverse of its regularized Delassus block.
    Drag { inverse: Matrix3<f64> },
}

/// One strand's constraints in its prepared step, as the projected Gauss-Seidel sweeps of [`solve`] need them:
/// built by [`Strand::constraint_rows`] (or into a kept workspace by [`Strand::fill_constraint_rows`]), applied
/// by [`Strand::apply_constraints`].
#[derive(Debug, Clone, Default)]
pub struct ConstraintRows {
    /// The step's time step, s.
    h: f64,
    /// The strand's degrees of freedom.
    dofs: usize,
    constraints: Vec<PointConstraint>,
    /// Workspace: one point's Jacobian `J_c` (3 x dofs, column-major, m per rad/m) while its row is built.
    jac: Vec<f64>,
    /// Per constraint: the number of leading columns of its Jacobian that can be nonzero (the dofs of the
    /// segments from the root to its point's).
    span: Vec<usize>,
    /// Per constraint, at `c * 3 dofs`: its reduced right-hand sides `L^-1 J_c^T` (3 x dofs, column-major; the
    /// first `span[c]` columns can be nonzero) in the elimination `A = L D L^T` of the step matrix
    /// ([`crate::dynamics::Dynamics::reduce_articulated3`]).
    reduced: Vec<f64>,
    /// Per constraint, at `c * 3 dofs`: `D^-1 L^-1 J_c^T`, the same layout.
    pivoted: Vec<f64>,
    /// Delassus blocks `W[c][d]` at `c * n + d`, m/s per N s.
    w: Vec<Matrix3<f64>>,
    /// Unconstrained point velocities, m/s.
    u_free: Vec<Vector3<f64>>,
    /// Per constraint: a pin's position error (target minus point, m) at the prepared state; zero for the
    /// other kinds.
    pin_error: Vec<Vector3<f64>>,
    /// Constraints the sweeps update (their point can move).
    active: Vec<bool>,
    rule: Vec<Rule>,
    /// Impulse of each constraint on the strand over the step, N s (zero until [`solve`]).
    pub impulses: Vec<Vector3<f64>>,
}

impl ConstraintRows {
    /// Number of constraints.
    pub fn len(&self) -> usize {
        self.constraints.len()
    }

    /// Whether there are no constraints.
    pub fn is_empty(&self) -> bool {
        self.constraints.is_empty()
    }

    /// Empties the rows, keeping their storage.
    fn clear(&mut self) {
        self.constraints.clear();
        self.span.clear();
        self.w.clear();
        self.u_free.clear();
        self.pin_error.clear();
        self.active.clear();
        self.rule.clear();
        self.impulses.clear();
    }

    /// Mobility of constraint `c`'s point along the unit `direction` in the prepared step: `n^T W_cc n`, m/s per
    /// N s (the velocity change of the point along `direction` per unit impulse along it).
    pub fn mobility(&self, c: usize, direction: &Vector3<f64>) -> f64 {
        direction.dot(&(self.w[c * self.len() + c] * direction))
    }

    /// Starts the solve of row `c` from the impulse `p` (N s; e.g. the same contact's impulse at the last step)
    /// instead of zero, projected onto what the row allows now: a contact's normal part >= 0 and its tangential part
    /// within the Coulomb cone (its current normal and friction), a drag's within its largest force. Ignored for a
    /// row the solve skips (no mobility), a non-finite `p` or a missing row. Call after the rows are built
    /// ([`Strand::fill_constraint_rows`]) and before [`solve`]; a linked contact's second row must hold minus
    /// the first's.
    pub fn warm_start(&mut self, c: usize, p: &Vector3<f64>) {
        if c >= self.len() || !self.active[c] || !p.iter().all(|x| x.is_finite()) {
            return;
        }
        self.impulses[c] = match self.constraints[c].kind {
            ConstraintKind::Contact { normal, friction, .. } => {
                let pn = p.dot(&normal).max(0.0);
                normal * pn + clamp_norm(p - normal * p.dot(&normal), friction * pn)
            }
            ConstraintKind::Drag { max_force, .. } => clamp_norm(*p, max_force * self.h),
            ConstraintKind::Pin { .. } => *p,
        };
    }

    /// Velocity of constraint `c`'s point with the current impulses, m/s.
    fn velocity(&self, c: usize) -> Vector3<f64> {
        let n = self.len();
        let mut u = self.u_free[c];
        // A zero impulse (a separating contact) would add exact zeros.
        for (w, p) in self.w[c * n..(c + 1) * n].iter().zip(&self.impulses) {
            if p.x != 0.0 || p.y != 0.0 || p.z != 0.0 {
                u += mul3(w, p);
            }
        }
        u
    }

    /// One Gauss-Seidel update of constraint `c` against its own obstacle.
    fn update(&mut self, c: usize, beta: f64, v_max: f64, mix: f64) {
        let rel = self.velocity(c) - self.constraints[c].velocity;
        let capped = |x: Vector3<f64>| if x.norm() > v_max { x * (v_max / x.norm()) } else { x };
        let p = self.impulses[c];
        let new = match self.constraints[c].kind {
            ConstraintKind::Pin { .. } => {
                let Rule::Pin { inverse, .. } = self.rule[c] else { return };
                let want = capped(self.pin_error[c] * beta);
                p + inverse * (want - rel - p * mix)
            }
            ConstraintKind::Drag { max_force, slip_speed } => {
                let Rule::Drag { inverse } = self.rule[c] else { return };
                // Aim for no relative motion, then clamp to the drag's largest impulse, regularised by the relative
                // speed the point would have without this drag.
                let share = if slip_speed > 0.0 {
                    let own = mul3(&self.w[c * self.len() + c], &p);
                    ((rel - own).norm() / slip_speed).min(1.0)
                } else {
                    1.0
                };
                clamp_norm(p + inverse * (-rel - p * mix), max_force * self.h * share)
            }
            ConstraintKind::Contact { normal, depth, friction } => {
                let Rule::Contact(frame) = self.rule[c] else { return };
                frame.update(&normal, friction, (beta * depth).min(v_max), &rel, &p, mix)
            }
        };
        self.impulses[c] = if new.iter().all(|x| x.is_finite()) { new } else { Vector3::zeros() };
    }
}

/// `x` shortened to length `limit` if it is longer (an impulse clamped to its largest value, N s).
fn clamp_norm(x: Vector3<f64>, limit: f64) -> Vector3<f64> {
    let n = x.norm();
    if n > limit { x * (limit / n) } else { x }
}

/// Two strands' constraints that are one contact (two strands touching): the `first` row's constraint, a
/// [`ConstraintKind::Contact`] whose normal points from the second strand's point towards the first's, is
/// solved for both points (relative velocity, the sum of both mobilities), and the `second` row takes the
/// opposite impulse (its own kind is not used). Each index is (position of the strand's rows in the slice given
/// to [`solve`], constraint index in those rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConstraintLink {
    /// The first strand's rows and constraint.
    pub first: (usize, usize),
    /// The second strand's rows and constraint.
    pub second: (usize, usize),
}

/// Solves the constraints of one or several strands' prepared steps together by projected Gauss-Seidel sweeps
/// (at most `opts.iterations`, fewer once converged to `opts.tolerance`), the law of the module documentation;
/// `links` couple rows of different strands (their contacts with each other), so that both strands' responses
/// enter each such contact in the same sweep (implicitly, with no lag of a step). Each group of strands linked
/// directly or through others (an unlinked strand alone) is solved as it would be alone: its sweeps stop when
/// its own impulses converged. A link naming a
/// missing row, a row of its own strand, a row already linked or a first row that is not a contact is ignored.
/// The impulses are left in each [`ConstraintRows::impulses`]; the sweeps start from the impulses the rows hold
/// (zero, or a warm start: [`ConstraintRows::warm_start`]). Returns the number of sweeps run.
pub fn solve(rows: &mut [ConstraintRows], links: &[ConstraintLink], opts: &ConstraintOptions) -> usize {
    let Some(h) = rows.first().map(|r| r.h) else { return 0 };
    let beta = opts.error_reduction_rate(h);
    let v_max = opts.max_correction_speed;
    let mix = opts.force_mixing(h);
    // Each row's role: 0 its own, 1 + l the first row of link l, usize::MAX the second row of a link.
    const SECOND: usize = usize::MAX;
    let mut role: Vec<Vec<usize>> = rows.iter().map(|r| vec![0; r.len()]).collect();
    let mut frames: Vec<Option<ContactFrame>> = vec![None; links.len()];
    for (l, link) in links.iter().enumerate() {
        let ((a, i), (b, j)) = (link.first, link.second);
        let fits = |(s, c): (usize, usize)| s < rows.len() && c < rows[s].len() && role[s][c] == 0;
        if a == b || !fits(link.first) || !fits(link.second) {
            continue;
        }
        let ConstraintKind::Contact { normal, .. } = rows[a].constraints[i].kind else { continue };
        let w = rows[a].w[i * rows[a].len() + i] + rows[b].w[j * rows[b].len() + j];
        if !(rows[a].active[i] || rows[b].active[j]) || !(w.trace() > 0.0) {
            continue;
        }
        frames[l] = Some(ContactFrame::new(&normal, &w, mix));
        role[a][i] = 1 + l;
        role[b][j] = SECOND;
    }
    // Strands linked by contacts, directly or through others, form a group; each group stops sweeping once a
    // whole sweep changed none of its impulses by more than `tolerance` times its largest one (a strand without
    // links is a group of its own, and stops as it would alone).
    let group = groups(rows.len(), links.iter().enumerate().filter(|(l, _)| frames[*l].is_some()).map(|(_, k)| (k.first.0, k.second.0)));
    let mut done = vec![false; rows.len()];
    // Per group: the largest impulse and the largest change of one in this sweep, N s.
    let mut sizes = vec![(0.0f64, 0.0f64); rows.len()];
    let mut sweeps = 0;
    for _ in 0..opts.iterations.max(1) {
        sweeps += 1;
        sizes.fill((0.0, 0.0));
        for s in 0..rows.len() {
            if done[group[s]] {
                continue;
            }
            let (mut own_largest, mut own_change) = (0.0f64, 0.0f64);
            for c in 0..rows[s].len() {
                let before = rows[s].impulses[c];
                match role[s][c] {
                    0 if rows[s].active[c] => rows[s].update(c, beta, v_max, mix),
                    0 | SECOND => continue,
                    r => {
                        let l = r - 1;
                        let ((a, i), (b, j)) = (links[l].first, links[l].second);
                        let (Some(frame), ConstraintKind::Contact { normal, depth, friction }) = (frames[l], rows[a].constraints[i].kind) else { continue };
                        let rel = rows[a].velocity(i) - rows[b].velocity(j);
                        let p = frame.update(&normal, friction, (beta * depth).min(v_max), &rel, &rows[a].impulses[i], mix);
                        let p = if p.iter().all(|x| x.is_finite()) { p } else { Vector3::zeros() };
                        rows[a].impulses[i] = p;
                        rows[b].impulses[j] = -p;
                    }
                }
                // Squared norms: the square root of the largest equals the largest square root.
                own_largest = own_largest.max(rows[s].impulses[c].norm_squared());
                own_change = own_change.max((rows[s].impulses[c] - before).norm_squared());
            }
            let size = &mut sizes[group[s]];
            *size = (size.0.max(own_largest), size.1.max(own_change));
        }
        let mut all = true;
        for g in 0..rows.len() {
            if group[g] == g && !done[g] {
                let (largest, change) = (sizes[g].0.sqrt(), sizes[g].1.sqrt());
                done[g] = change <= opts.tolerance * largest;
                all &= done[g];
            }
        }
        if all {
            break;
        }
    }
    sweeps
}

/// The group of each of `n` strands joined by the `pairs` (strand indices; out-of-range ones ignored): the
/// smallest strand index of its group, so a group's representative is the strand whose group is itself.
fn groups(n: usize, pairs: impl Iterator<Item = (usize, usize)>) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for (a, b) in pairs.filter(|&(a, b)| a < n && b < n) {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[ra.max(rb)] = ra.min(rb);
    }
    (0..n).map(|x| find(&mut parent, x)).collect()
}

#[cfg(test)]
mod tests {
    use super::groups;

    #[test]
    fn strands_joined_directly_or_through_others_form_one_group() {
        // 0-3 and 3-5 join 0, 3, 5; 4-2 joins 2 and 4; 1 and 6 stay alone; an out-of-range pair is ignored.
        let pairs = [(0, 3), (4, 2), (5, 3), (7, 1), (2, 4)];
        assert_eq!(groups(7, pairs.into_iter()), vec![0, 1, 2, 0, 2, 0, 6]);
        assert_eq!(groups(3, std::iter::empty()), vec![0, 1, 2]);
    }
}
