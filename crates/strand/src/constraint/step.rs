//! The constrained step of one strand: prepare (the free step), build the rows, apply the solved impulses and
//! project onto the pins.

use super::rows::{pinv3, ConstraintRows, ContactFrame, Rule};
use super::solve::solve;
use super::{ConstraintKind, ConstraintOptions, PointConstraint};
use crate::error::{Result, StrandError};
use crate::integrator::{Integrator, Strand};
use crate::kinematics::{frame_at, segment_frames};
use nalgebra::{Matrix3, Vector3};

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
    /// Equal to [`Strand::constraint_rows`], [`solve`](super::solve) for this strand alone and [`Strand::apply_constraints`].
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
    /// blocks and the unconstrained point velocities), for [`solve`](super::solve); the step stays prepared. Errors if no
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
                ConstraintKind::Contact { .. } | ConstraintKind::Cushion { .. } | ConstraintKind::Drag { .. } => Vector3::zeros(),
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
            // The pseudo-inverse (an SVD) only where it is used: a drag's inverse with force mixing is the
            // regularized block's (the same numbers, no SVD thrown away).
            let inverse = |projection: Option<Matrix3<f64>>| if mix > 0.0 { (w + Matrix3::identity() * mix).try_inverse().unwrap_or_else(|| pinv3(&w)) } else { projection.unwrap_or_else(|| pinv3(&w)) };
            rows.rule.push(match pc.kind {
                ConstraintKind::Contact { normal, .. } | ConstraintKind::Cushion { normal, .. } => Rule::Contact(ContactFrame::new(&normal, &w, mix)),
                ConstraintKind::Pin { .. } => {
                    let projection = pinv3(&w);
                    Rule::Pin { inverse: inverse(Some(projection)), projection }
                }
                ConstraintKind::Drag { .. } => {
                    let (axes, mobilities) = super::slide::eigenbasis(&w);
                    Rule::Drag { inverse: inverse(None), axes, mobilities }
                }
            });
        }
        rows.impulses.resize(n, Vector3::zeros());
        Ok(())
    }

    /// Completes the prepared step with the impulses [`solve`](super::solve) found for `rows` (built by this strand's
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
        // The loads the constraints applied, for the next step's geometric stiffness.
        for (c, p) in constraints.iter().zip(&rows.impulses) {
            if p.x != 0.0 || p.y != 0.0 || p.z != 0.0 {
                self.constraint_loads.push((c.s, p / h));
            }
        }
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
                    ConstraintKind::Contact { .. } | ConstraintKind::Cushion { .. } | ConstraintKind::Drag { .. } => Vector3::zeros(),
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
