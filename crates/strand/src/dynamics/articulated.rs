//! The O(N) solve of the linearly implicit step: `(scale M + stiffness K) x = b` eliminated segment by segment
//! from the tip (articulated-body recursion) with the per-segment sums of the sweep, and the back-substitutions
//! and reduced right-hand sides the constraint solve reuses.

use super::{Dynamics, SegmentSums, Vector6};
use crate::kinematics::Twists;
use crate::model::StrandModel;
use nalgebra::{DVector, Matrix3, Matrix6, SMatrix, SVector, Vector3};

/// Inverse of a symmetric 3x3 matrix, or None unless it is (numerically) positive definite (leading principal
/// minors positive). Cofactors of the matrix itself; if its determinant leaves the range of f64 (a diagonal far
/// above the others, e.g. the geometric stiffness of a huge constraint load), cofactors of the matrix scaled to
/// a unit diagonal (`S A S`, `S = diag(a_ii^-1/2)`; a positive scaling keeps definiteness), unscaled after.
pub(super) fn spd_inverse(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if let Some(inv) = spd_inverse_cofactors(a) {
        return Some(inv);
    }
    if !(a[(0, 0)] > 0.0 && a[(1, 1)] > 0.0 && a[(2, 2)] > 0.0 && a.iter().all(|x| x.is_finite())) {
        return None;
    }
    let s = Vector3::new(a[(0, 0)].sqrt().recip(), a[(1, 1)].sqrt().recip(), a[(2, 2)].sqrt().recip());
    let scaled = Matrix3::from_fn(|i, j| a[(i, j)] * s[i] * s[j]);
    let inv = spd_inverse_cofactors(&scaled)?;
    Some(Matrix3::from_fn(|i, j| inv[(i, j)] * s[i] * s[j]))
}

/// [`spd_inverse`] by cofactors alone.
pub(super) fn spd_inverse_cofactors(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let c00 = a[(1, 1)] * a[(2, 2)] - a[(1, 2)] * a[(2, 1)];
    let c01 = a[(1, 2)] * a[(2, 0)] - a[(1, 0)] * a[(2, 2)];
    let c02 = a[(1, 0)] * a[(2, 1)] - a[(1, 1)] * a[(2, 0)];
    let det = a[(0, 0)] * c00 + a[(0, 1)] * c01 + a[(0, 2)] * c02;
    let minor2 = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
    if !(a[(0, 0)] > 0.0 && minor2 > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let c11 = a[(0, 0)] * a[(2, 2)] - a[(0, 2)] * a[(2, 0)];
    let c12 = a[(0, 1)] * a[(2, 0)] - a[(0, 0)] * a[(2, 1)];
    let inv = 1.0 / det;
    Some(Matrix3::new(c00, c01, c02, c01, c11, c12, c02, c12, minor2) * inv)
}

/// One tip-to-root step of [`Dynamics::solve_articulated`] for a segment with `D` coordinates: updates the
/// articulated inertia `ia` and bias `pa` and returns `(U, D^-1, c)` padded to 3 columns (zeros beyond `D`).
pub(super) fn eliminate<const D: usize>(
    ia: &mut Matrix6<f64>,
    pa: &mut Vector6,
    motion: &Twists,
    sums: &SegmentSums,
    scale: f64,
    rig: &Vector3<f64>,
    geometric: &[f64],
    b: &[f64],
) -> Option<(Twists, Matrix3<f64>, Vector3<f64>)> {
    let s = motion.fixed_columns::<D>(0);
    let ia_s = *ia * s;
    let u = sums.f_own.fixed_columns::<D>(0) * scale + ia_s;
    // D = scale M_own + S^T I^A S + stiffness K, padded with 1 on unused diagonal entries.
    let mut dm = Matrix3::identity();
    let mut c = Vector3::zeros();
    let s_pa = s.tr_mul(pa);
    for k in 0..D {
        for j in 0..D {
            dm[(j, k)] = sums.m_own[(j, k)] * scale + s.column(j).dot(&ia_s.column(k));
        }
        dm[(k, k)] += rig[k] + geometric[k];
        c[k] = -s_pa[k] - b[k];
    }
    let dinv = spd_inverse(&dm)?;
    let dinv_d = dinv.fixed_view::<D, D>(0, 0);
    let u_dinv = u * dinv_d;
    *ia += sums.inertia.matrix() * scale - u_dinv * u.transpose();
    *pa += u_dinv * c.fixed_rows::<D>(0);
    let mut u_pad = Twists::zeros();
    u_pad.fixed_columns_mut::<D>(0).copy_from(&u);
    Some((u_pad, dinv, c))
}


impl Dynamics {
    /// Solves `(scale M + stiffness K) x = b` in place in O(N), where `M` is the mass matrix at the state of
    /// the last [`Dynamics::sweep`] with sums (not assembled) and `K` the diagonal elastic stiffness.
    /// Returns false if the matrix is not (numerically) positive definite.
    ///
    /// Articulated-body recursion (Featherstone; Bertails 2009, "Linear time super-helices"): `x` minimizes
    /// `x^T A x / 2 - b^T x`, where `x^T M x` is the kinetic form `sum_points V^T I V` of the twists that `x`
    /// gives the points. Eliminating the segments from the tip, the minimum over segments `Q+1..` for a twist
    /// `V` of the frame at the end of segment `Q` is `V^T I^A_Q+1 V / 2 - V^T p^A_Q+1` (+ const), with
    /// `U = scale F_own + I^A S`, `D = scale M_own + S^T I^A S + stiffness K_Q`, `c = -S^T p^A - b_Q`,
    /// `I^A_Q = scale I_own + I^A_Q+1 - U D^-1 U^T`, `p^A_Q = p^A_Q+1 + U D^-1 c`; then from the root (`V = 0`),
    /// `x_Q = -D^-1 (U^T V + c)` and `V += S_Q x_Q`.
    ///
    /// `geometric_scale` (s^2) multiplies [`Dynamics::geometric`], added to the diagonal of `K`'s term.
    pub(crate) fn solve_articulated(&mut self, model: &StrandModel, scale: f64, stiffness: f64, geometric_scale: f64, b: &mut DVector<f64>) -> bool {
        let d = model.dofs_per_segment();
        let n = model.segments;
        let rig = model.rigidities() * (model.segment_length() * stiffness);
        let mut ia = Matrix6::zeros();
        let mut pa = Vector6::zeros();
        let mut geo = [0.0; 3];
        for i in (0..n).rev() {
            let bi = &b.as_slice()[i * d..(i + 1) * d];
            for k in 0..d {
                geo[k] = geometric_scale * self.geometric[i * d + k];
            }
            let step = if d == 2 {
                eliminate::<2>(&mut ia, &mut pa, &self.motion[i], &self.sums[i], scale, &rig, &geo, bi)
            } else {
                eliminate::<3>(&mut ia, &mut pa, &self.motion[i], &self.sums[i], scale, &rig, &geo, bi)
            };
            let Some(step) = step else { return false };
            self.articulated[i] = step;
        }
        self.back_substitute(d, b)
    }

    /// Root-to-tip back-substitution of the articulated solve: `x_Q = -D^-1 (U^T V + c)`, `V += S_Q x_Q`.
    fn back_substitute(&self, d: usize, b: &mut DVector<f64>) -> bool {
        let mut v = Vector6::zeros();
        for (i, (u, dinv, c)) in self.articulated.iter().enumerate() {
            let x = -(dinv * (u.tr_mul(&v) + c));
            for k in 0..d {
                b[i * d + k] = x[k];
            }
            v += self.motion[i] * x;
        }
        b.iter().all(|x| x.is_finite())
    }

    /// The root-to-tip half of an articulated solve alone (the elimination of the last
    /// [`Dynamics::solve_articulated`]): `b` (dofs) holds reduced right-hand sides
    /// `c = L^-1 b'` (e.g. sums of [`Dynamics::reduce_articulated3`]'s columns, weighted by impulses: the reduction
    /// is linear) and becomes `A^-1 b'`. False if a value is not finite.
    pub(crate) fn back_substitute1(&self, model: &StrandModel, b: &mut [f64]) -> bool {
        if model.dofs_per_segment() == 2 {
            self.back_substitute_d::<2>(model, b)
        } else {
            self.back_substitute_d::<3>(model, b)
        }
    }

    /// [`Dynamics::back_substitute1`] for `D` coordinates per segment.
    fn back_substitute_d<const D: usize>(&self, model: &StrandModel, b: &mut [f64]) -> bool {
        let mut v = Vector6::zeros();
        for i in 0..model.segments {
            let (u, dinv, _) = &self.articulated[i];
            let c = SVector::<f64, D>::from_fn(|k, _| b[i * D + k]);
            let x = -(dinv.fixed_view::<D, D>(0, 0) * (u.fixed_columns::<D>(0).tr_mul(&v) + c));
            b[i * D..(i + 1) * D].copy_from_slice(x.as_slice());
            v += self.motion[i].fixed_columns::<D>(0) * x;
        }
        b[..model.segments * D].iter().all(|x| x.is_finite())
    }

    /// Solves the system of the last [`Dynamics::solve_articulated`] for another right-hand side `b` (dofs) in
    /// place, reusing its elimination: [`Dynamics::reduce_articulated3`] (first column) then
    /// [`Dynamics::back_substitute1`], as the constraint solver applies its impulses.
    #[cfg(test)]
    pub(crate) fn resolve_articulated1(&mut self, model: &StrandModel, b: &mut [f64]) -> bool {
        let n = b.len();
        let mut three = vec![0.0; 3 * n];
        for (t, x) in three.chunks_exact_mut(3).zip(b.iter()) {
            t[0] = *x;
        }
        let (mut c, mut e) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        let ok = self.reduce_articulated3(model, &three, model.segments, &mut c, &mut e);
        for (x, t) in b.iter_mut().zip(c.chunks_exact(3)) {
            *x = t[0];
        }
        ok && self.back_substitute1(model, b)
    }

    /// The tip-to-root half of an articulated solve alone (reusing the elimination of the last
    /// [`Dynamics::solve_articulated`]: its articulated inertias and pivots), for three right-hand sides, for the quadratic form of `A^-1`: with
    /// the elimination `A = L D L^T` of the last [`Dynamics::solve_articulated`] (the pivots `D_Q` of each
    /// segment), the reduced right-hand sides `c = L^-1 b` give `b1^T A^-1 b2 = sum_Q c1_Q^T D_Q^-1 c2_Q`. For
    /// the three right-hand sides `b` (3 x dofs, column-major, only the first `used` segments' columns nonzero,
    /// e.g. a point's Jacobian: the segments from the root to its own) writes `c` into `c_out` and `D^-1 c` into `e_out` (3 x (used
    /// D), column-major, the same layout as `b`; `c` is zero beyond `used`). So the Delassus block of two points
    /// is `W_12 = J_1 A^-1 J_2^T = sum_m c1[m] e2[m]^T` over the columns both have: no back-substitution over the
    /// whole strand per point. False if a value is not finite.
    pub(crate) fn reduce_articulated3(&self, model: &StrandModel, b: &[f64], used: usize, c_out: &mut [f64], e_out: &mut [f64]) -> bool {
        if model.dofs_per_segment() == 2 {
            self.reduce_articulated_d::<2>(model, b, used, c_out, e_out)
        } else {
            self.reduce_articulated_d::<3>(model, b, used, c_out, e_out)
        }
    }

    /// [`Dynamics::reduce_articulated3`] for `D` coordinates per segment.
    fn reduce_articulated_d<const D: usize>(&self, model: &StrandModel, b: &[f64], used: usize, c_out: &mut [f64], e_out: &mut [f64]) -> bool {
        let used = used.min(model.segments);
        let mut pa = SMatrix::<f64, 6, 3>::zeros();
        let mut finite = true;
        for i in (0..used).rev() {
            let s = self.motion[i].fixed_columns::<D>(0);
            let s_pa = s.tr_mul(&pa);
            let (u, dinv, _) = &self.articulated[i];
            let mut c = SMatrix::<f64, D, 3>::zeros();
            for k in 0..D {
                for r in 0..3 {
                    c[(k, r)] = -s_pa[(k, r)] - b[3 * (i * D + k) + r];
                }
            }
            let e = dinv.fixed_view::<D, D>(0, 0) * c;
            pa += u.fixed_columns::<D>(0) * e;
            for k in 0..D {
                for r in 0..3 {
                    c_out[3 * (i * D + k) + r] = c[(k, r)];
                    e_out[3 * (i * D + k) + r] = e[(k, r)];
                }
            }
            finite &= e.iter().all(|x| x.is_finite());
        }
        finite
    }
}
