//! One strand's constraint rows in its prepared step (Delassus blocks, contact frames, the per-row update of the
//! projected Gauss-Seidel sweeps), and the small 3 x 3 helpers they use.

use super::{ConstraintKind, PointConstraint};
use nalgebra::{Matrix3, Vector3};

/// Pseudo-inverse of a 3 x 3 Delassus block: directions in which the point cannot move (e.g. along the
/// tangent of a taut, inextensible strand: relative mobility below 1e-4) get no impulse instead of an
/// unbounded one.
pub(super) fn pinv3(w: &Matrix3<f64>) -> Matrix3<f64> {
    let tol = 1e-4 * w.norm();
    w.pseudo_inverse(tol).unwrap_or_else(|_| Matrix3::zeros())
}

/// `w p` for a 3 x 3 block, written out: the same sums in the same order as nalgebra's product (column by
/// column), without its generic loops.
#[inline(always)]
pub(super) fn mul3(w: &Matrix3<f64>, p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        w[(0, 0)] * p.x + w[(0, 1)] * p.y + w[(0, 2)] * p.z,
        w[(1, 0)] * p.x + w[(1, 1)] * p.y + w[(1, 2)] * p.z,
        w[(2, 0)] * p.x + w[(2, 1)] * p.y + w[(2, 2)] * p.z,
    )
}

/// Two unit vectors orthogonal to `n` and to each other.
pub(super) fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let t1 = n.cross(&helper).normalize();
    (t1, n.cross(&t1))
}

/// What the sweeps need of a contact, fixed over the iterations: the tangent basis, the regularized normal
/// mobility `W_nn + R` (m/s per N s) and the inverse of the regularized tangential Delassus block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ContactFrame {
    pub(super) t1: Vector3<f64>,
    pub(super) t2: Vector3<f64>,
    pub(super) wnn: f64,
    pub(super) wt2_inv: nalgebra::Matrix2<f64>,
}

impl ContactFrame {
    /// For a contact along `normal` with the 3 x 3 Delassus block `w` and force mixing `mix`.
    pub(super) fn new(normal: &Vector3<f64>, w: &Matrix3<f64>, mix: f64) -> Self {
        let (t1, t2) = tangents(normal);
        let wnn = (normal.dot(&(w * normal)) + mix).max(1e-300);
        let basis = Matrix3::from_columns(&[t1, t2, *normal]);
        let wt = basis.transpose() * w * basis;
        let wt2 = nalgebra::Matrix2::new(wt[(0, 0)] + mix, wt[(0, 1)], wt[(1, 0)], wt[(1, 1)] + mix);
        Self { t1, t2, wnn, wt2_inv: wt2.try_inverse().unwrap_or_else(nalgebra::Matrix2::zeros) }
    }

    /// The contact's new impulse from its old one `p_old` and the relative velocity `rel` of the point to the
    /// obstacle (both without this iteration's update): normal impulse `>= least` aiming at the separation speed
    /// `want_n`, tangential impulse aiming at no slip, clamped to the Coulomb cone of `friction`.
    /// The normal impulse (N s, >= 0) of a layer pushing with `load` (N) at the step's start and growing by
    /// `stiffness` (N/m) as the obstacle comes closer, taken at the step's end (an implicit spring): `p = h load + h^2
    /// stiffness (v_obstacle - u) . n` with `u` the point's velocity after the step, `rel` its relative velocity with
    /// the impulses `p_old` (this row's included) and the point's normal mobility `wnn - mix`, so
    /// `p (1 + h^2 k W_nn) = h load - h^2 k (rel . n - W_nn p_old . n)`. `h load` exactly for a stiffness of 0.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spring(&self, normal: &Vector3<f64>, load: f64, stiffness: f64, h: f64, rel: &Vector3<f64>, p_old: &Vector3<f64>, mix: f64) -> f64 {
        if stiffness <= 0.0 {
            return h * load;
        }
        let w = (self.wnn - mix).max(0.0);
        let hk = h * h * stiffness;
        let p = (h * load - hk * (rel.dot(normal) - w * p_old.dot(normal))) / (1.0 + hk * w);
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// `least`: the smallest normal impulse, N s (0 for a plain contact; a cushion's load times the step; with
    /// `want_n` minus infinity the normal impulse is `least`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn update(&self, normal: &Vector3<f64>, friction: f64, want_n: f64, rel: &Vector3<f64>, p_old: &Vector3<f64>, mix: f64, least: f64) -> Vector3<f64> {
        let pn_old = p_old.dot(normal);
        let mut pn = (pn_old + (want_n - rel.dot(normal) - mix * pn_old) / self.wnn).max(least);
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
pub(super) enum Rule {
    /// A contact's tangent basis and regularized mobilities.
    Contact(ContactFrame),
    /// A pin: the inverse of its regularized Delassus block `W + R I` (m/s per N s, inverted) and the
    /// pseudo-inverse of `W` itself (the post-stabilization's).
    Pin { inverse: Matrix3<f64>, projection: Matrix3<f64> },
    /// A drag: the inverse of its regularized Delassus block, and the block's eigenbasis and eigenvalues (the
    /// sliding impulse's, `super::slide`).
    Drag { inverse: Matrix3<f64>, axes: Matrix3<f64>, mobilities: Vector3<f64> },
}

/// One strand's constraints in its prepared step, as the projected Gauss-Seidel sweeps of [`solve`](super::solve) need them:
/// built by [`Strand::constraint_rows`](crate::integrator::Strand::constraint_rows) (or into a kept workspace by [`Strand::fill_constraint_rows`](crate::integrator::Strand::fill_constraint_rows)), applied
/// by [`Strand::apply_constraints`](crate::integrator::Strand::apply_constraints).
#[derive(Debug, Clone, Default)]
pub struct ConstraintRows {
    /// The step's time step, s.
    pub(super) h: f64,
    /// The strand's degrees of freedom.
    pub(super) dofs: usize,
    pub(super) constraints: Vec<PointConstraint>,
    /// Workspace: one point's Jacobian `J_c` (3 x dofs, column-major, m per rad/m) while its row is built.
    pub(super) jac: Vec<f64>,
    /// Per constraint: the number of leading columns of its Jacobian that can be nonzero (the dofs of the
    /// segments from the root to its point's).
    pub(super) span: Vec<usize>,
    /// Per constraint, at `c * 3 dofs`: its reduced right-hand sides `L^-1 J_c^T` (3 x dofs, column-major; the
    /// first `span[c]` columns can be nonzero) in the elimination `A = L D L^T` of the step matrix
    /// ([`crate::dynamics::Dynamics::reduce_articulated3`]).
    pub(super) reduced: Vec<f64>,
    /// Per constraint, at `c * 3 dofs`: `D^-1 L^-1 J_c^T`, the same layout.
    pub(super) pivoted: Vec<f64>,
    /// Delassus blocks `W[c][d]` at `c * n + d`, m/s per N s.
    pub(super) w: Vec<Matrix3<f64>>,
    /// Unconstrained point velocities, m/s.
    pub(super) u_free: Vec<Vector3<f64>>,
    /// Per constraint: a pin's position error (target minus point, m) at the prepared state; zero for the
    /// other kinds.
    pub(super) pin_error: Vec<Vector3<f64>>,
    /// Constraints the sweeps update (their point can move).
    pub(super) active: Vec<bool>,
    pub(super) rule: Vec<Rule>,
    /// Impulse of each constraint on the strand over the step, N s (zero until [`solve`](super::solve)).
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
    pub(super) fn clear(&mut self) {
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
    /// within the Coulomb cone (its current normal and friction; a cushion's too: the solve then keeps its normal
    /// part at least the layer's load, `ContactFrame::spring`), a drag's within its largest force. Ignored for a
    /// row the solve skips (no mobility), a non-finite `p` or a missing row. Call after the rows are built
    /// ([`Strand::fill_constraint_rows`](crate::integrator::Strand::fill_constraint_rows)) and before [`solve`](super::solve); a linked contact's second row must hold minus
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
            ConstraintKind::Cushion { normal, friction, .. } => {
                let pn = p.dot(&normal).max(0.0);
                normal * pn + clamp_norm(p - normal * p.dot(&normal), friction * pn)
            }
            ConstraintKind::Drag { max_force, .. } => clamp_norm(*p, max_force * self.h),
            ConstraintKind::Pin { .. } => *p,
        };
    }

    /// Velocity of constraint `c`'s point with the current impulses, m/s.
    pub(super) fn velocity(&self, c: usize) -> Vector3<f64> {
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
    pub(super) fn update(&mut self, c: usize, beta: f64, v_max: f64, mix: f64) {
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
                let Rule::Drag { inverse, axes, mobilities } = self.rule[c] else { return };
                // Aim for no relative motion; beyond the drag's largest impulse (regularised by the relative speed
                // the point would have without this drag) slide: the impulse at the bound that opposes the relative
                // velocity it leaves (`super::slide`), not the aim shortened.
                let own = mul3(&self.w[c * self.len() + c], &p);
                let share = if slip_speed > 0.0 { ((rel - own).norm() / slip_speed).min(1.0) } else { 1.0 };
                let bound = max_force * self.h * share;
                let aim = p + inverse * (-rel - p * mix);
                if aim.norm() > bound {
                    super::slide::sliding(&axes, &mobilities, mix, &(rel - own), bound)
                } else {
                    aim
                }
            }
            ConstraintKind::Contact { normal, depth, friction } => {
                let Rule::Contact(frame) = self.rule[c] else { return };
                frame.update(&normal, friction, (beta * depth).min(v_max), &rel, &p, mix, 0.0)
            }
            ConstraintKind::Cushion { normal, depth, friction, load, stiffness } => {
                let Rule::Contact(frame) = self.rule[c] else { return };
                // Clear of the obstacle the point takes the layer's load alone; packed against it, the contact's
                // non-penetration too.
                let least = frame.spring(&normal, load, stiffness, self.h, &rel, &p, mix);
                let want = if depth > 0.0 { (beta * depth).min(v_max) } else { f64::NEG_INFINITY };
                frame.update(&normal, friction, want, &rel, &p, mix, least)
            }
        };
        self.impulses[c] = if new.iter().all(|x| x.is_finite()) { new } else { Vector3::zeros() };
    }
}

/// `x` shortened to length `limit` if it is longer (an impulse clamped to its largest value, N s).
pub(super) fn clamp_norm(x: Vector3<f64>, limit: f64) -> Vector3<f64> {
    let n = x.norm();
    if n > limit { x * (limit / n) } else { x }
}
