//! One helical segment in closed form.
//!
//! A segment has a constant Darboux vector `Omega` written in the material frame at its start
//! (`Omega = (twist, bend, bend2)` along `(n0, n1, n2)`; the reduced model has `bend2 = 0`). After an arc
//! length `sigma` the frame is rotated by `E = exp(sigma [Omega]x)` and the centreline has moved by
//! `p = sigma Jl(sigma Omega) e0`, where `Jl(phi) = int_0^1 exp(t [phi]x) dt` is the left Jacobian of SO(3).
//! Expanded, `p` is the paper's formula of section 4.1 (parallel part, sine part, cosine part).
//!
//! All coefficient functions are written in `u = |phi|^2` with Taylor series below `u = 0.1`, so a straight
//! segment is exact and everything is smooth (also for automatic differentiation) through `Omega = 0`.

use nalgebra::{Matrix3, RealField, Vector3};

/// Below this `u = theta^2` the series forms are used (their truncation error is below 1e-15 relative).
pub(crate) const SERIES_BELOW: f64 = 0.1;

/// The Taylor series (ascending powers of `u`) of the helix coefficients `a`, `b`, `c` and of `db/du`, `dc/du`,
/// used below [`SERIES_BELOW`] by the scalar kinematics and by the lane-wise one (`batch::lanes`).
pub(crate) const SERIES_A: [f64; 6] = [1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0];
pub(crate) const SERIES_B: [f64; 6] = [0.5, -1.0 / 24.0, 1.0 / 720.0, -1.0 / 40320.0, 1.0 / 3628800.0, -1.0 / 479001600.0];
pub(crate) const SERIES_C: [f64; 6] = [1.0 / 6.0, -1.0 / 120.0, 1.0 / 5040.0, -1.0 / 362880.0, 1.0 / 39916800.0, -1.0 / 6227020800.0];
pub(crate) const SERIES_DB: [f64; 5] = [-1.0 / 24.0, 2.0 / 720.0, -3.0 / 40320.0, 4.0 / 3628800.0, -5.0 / 479001600.0];
pub(crate) const SERIES_DC: [f64; 5] = [-1.0 / 120.0, 2.0 / 5040.0, -3.0 / 362880.0, 4.0 / 39916800.0, -5.0 / 6227020800.0];

/// `(a, b, c)` with `a = sin t / t`, `b = (1 - cos t)/t^2`, `c = (t - sin t)/t^3`, `t = sqrt(u)`.
pub fn coefficients<T: RealField + Copy>(u: T) -> (T, T, T) {
    if u < T::from_f64(SERIES_BELOW).unwrap() {
        let f = |x: f64| T::from_f64(x).unwrap();
        let a = f(1.0) - u * (f(1.0 / 6.0) - u * (f(1.0 / 120.0) - u * (f(1.0 / 5040.0) - u * (f(1.0 / 362880.0) - u * f(1.0 / 39916800.0)))));
        let b = f(0.5) - u * (f(1.0 / 24.0) - u * (f(1.0 / 720.0) - u * (f(1.0 / 40320.0) - u * (f(1.0 / 3628800.0) - u * f(1.0 / 479001600.0)))));
        let c = f(1.0 / 6.0) - u * (f(1.0 / 120.0) - u * (f(1.0 / 5040.0) - u * (f(1.0 / 362880.0) - u * (f(1.0 / 39916800.0) - u * f(1.0 / 6227020800.0)))));
        (a, b, c)
    } else {
        let t = u.sqrt();
        let (s, co) = (t.sin(), t.cos());
        (s / t, (T::one() - co) / u, (t - s) / (u * t))
    }
}

/// Derivatives `(db/du, dc/du)` of the coefficients `b` and `c` of [`coefficients`].
pub fn coefficient_derivatives<T: RealField + Copy>(u: T) -> (T, T) {
    let f = |x: f64| T::from_f64(x).unwrap();
    if u < f(SERIES_BELOW) {
        let db = f(-1.0 / 24.0) + u * (f(2.0 / 720.0) - u * (f(3.0 / 40320.0) - u * (f(4.0 / 3628800.0) - u * f(5.0 / 479001600.0))));
        let dc = f(-1.0 / 120.0) + u * (f(2.0 / 5040.0) - u * (f(3.0 / 362880.0) - u * (f(4.0 / 39916800.0) - u * f(5.0 / 6227020800.0))));
        (db, dc)
    } else {
        let t = u.sqrt();
        let (s, co) = (t.sin(), t.cos());
        let db = (t * s - (T::one() - co) * f(2.0)) / (u * u * f(2.0));
        let dc = (t * (T::one() - co) - (t - s) * f(3.0)) / (u * u * t * f(2.0));
        (db, dc)
    }
}

/// Rotation `E = exp(sigma [Omega]x)` and displacement `p = sigma Jl(sigma Omega) e0` of a segment after arc
/// length `sigma` (m), both in the segment's start frame. `omega` in rad/m.
pub fn segment_transform<T: RealField + Copy>(omega: &Vector3<T>, sigma: f64) -> (Matrix3<T>, Vector3<T>) {
    let s = T::from_f64(sigma).unwrap();
    let phi = omega * s;
    let (a, b, c) = coefficients(phi.norm_squared());
    let k = phi.cross_matrix();
    let k2 = k * k;
    let e = Matrix3::identity() + k * a + k2 * b;
    let e0 = Vector3::x();
    let p = (e0 + k.column(0) * b + k2.column(0) * c) * s;
    (e, p)
}

/// Derivatives of a segment's transform with respect to the Darboux components, in the start frame.
///
/// Column `k` of `angular` is the rotation vector `w_k` with `dE/dOmega_k = [w_k]x E`, and column `k` of
/// `linear` is `dp/dOmega_k`, both after arc length `sigma` (units: m rad per (rad/m), and m^2).
/// Generic so that dual numbers give their rates of change along a direction (used for the velocity-product
/// terms of the dynamics).
pub fn segment_derivatives<T: RealField + Copy>(omega: &Vector3<T>, sigma: f64) -> (Matrix3<T>, Matrix3<T>) {
    let sg = T::from_f64(sigma).unwrap();
    let two = T::from_f64(2.0).unwrap();
    let phi = omega * sg;
    let u = phi.norm_squared();
    let (_, b, c) = coefficients(u);
    let (db, dc) = coefficient_derivatives(u);
    let e0: Vector3<T> = Vector3::x();
    let pe = phi.cross(&e0);
    let ppe = phi.cross(&pe);
    let mut angular = Matrix3::zeros();
    let mut linear = Matrix3::zeros();
    for k in 0..3 {
        let ek: Vector3<T> = Vector3::ith(k, T::one());
        let pk = phi.cross(&ek);
        angular.set_column(k, &((ek + pk * b + phi.cross(&pk) * c) * sg));
        let eke0 = ek.cross(&e0);
        let d = pe * (two * phi[k] * db) + eke0 * b + ppe * (two * phi[k] * dc) + (ek.cross(&pe) + phi.cross(&eke0)) * c;
        linear.set_column(k, &(d * (sg * sg)));
    }
    (angular, linear)
}

/// Everything the dynamics needs about a point at arc length `sigma` of a segment whose Darboux vector
/// `omega` changes at the rate `rate` (rad/(m s)); all in the segment's start frame. See [`segment_kinematics`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentPoint {
    /// Rotation `E` of the frame (as in [`segment_transform`]).
    pub rotation: Matrix3<f64>,
    /// Displacement `p` of the centreline, m.
    pub offset: Vector3<f64>,
    /// `dE/dOmega` as rotation vectors, one column per Darboux component (as in [`segment_derivatives`]).
    pub angular: Matrix3<f64>,
    /// `dp/dOmega`, one column per Darboux component, m^2.
    pub linear: Matrix3<f64>,
    /// `(d/dt angular) rate` at fixed `rate` (the velocity-product angular acceleration), rad/s^2.
    pub angular_bias: Vector3<f64>,
    /// `(d/dt linear) rate` at fixed `rate` (the velocity-product acceleration), m/s^2.
    pub linear_bias: Vector3<f64>,
}

/// The coefficients `a, b, c, db/du, dc/du` of [`coefficients`] and [`coefficient_derivatives`] at `u`, and
/// the time derivatives of `b, c, db/du, dc/du` when `u` changes at the rate `u_dot` (forward-mode dual
/// numbers; one sine and cosine shared by all of them). Returns `[a, b, c, db, dc, b_dot, c_dot, db_dot, dc_dot]`.
#[inline]
fn coefficients_with_rates(u: f64, u_dot: f64) -> [f64; 9] {
    use num_dual::Dual64;
    let ud = Dual64::new(u, u_dot);
    let (b, c, db, dc, a) = if u < SERIES_BELOW {
        // The Taylor series of `coefficients` and `coefficient_derivatives` (ascending powers of u), with
        // their u-derivatives by Horner's scheme in plain floating point.
        let horner = |k: &[f64]| {
            let (mut p, mut dp) = (k[k.len() - 1], 0.0);
            for &c in k[..k.len() - 1].iter().rev() {
                dp = dp * u + p;
                p = p * u + c;
            }
            Dual64::new(p, dp * u_dot)
        };
        (horner(&SERIES_B), horner(&SERIES_C), horner(&SERIES_DB), horner(&SERIES_DC), horner(&SERIES_A).re)
    } else {
        // The closed forms of `coefficients` and `coefficient_derivatives`, with one sin/cos for all.
        let t = num_dual::DualNum::sqrt(&ud);
        let (s, co) = num_dual::DualNum::sin_cos(&t);
        let one_minus_cos = -co + 1.0;
        let b = one_minus_cos / ud;
        let c = (t - s) / (ud * t);
        let db = (t * s - one_minus_cos * 2.0) / (ud * ud * 2.0);
        let dc = (t * one_minus_cos - (t - s) * 3.0) / (ud * ud * t * 2.0);
        (b, c, db, dc, s.re / t.re)
    };
    [a, b.re, c.re, db.re, dc.re, b.eps, c.eps, db.eps, dc.eps]
}

/// Transform, derivatives and velocity-product terms of a segment point in one pass (one set of
/// trigonometric functions, evaluated in forward-mode dual numbers of `u = |sigma omega|^2` along time).
/// Equal to [`segment_transform`], [`segment_derivatives`] and their directional derivatives along `rate`.
/// The matrices are written out with `[phi]x^2 = phi phi^T - |phi|^2 1` and `e0 = x` (no 3x3 products).
#[inline]
pub fn segment_kinematics(omega: &Vector3<f64>, rate: &Vector3<f64>, sigma: f64) -> SegmentPoint {
    let phi = omega * sigma;
    let phi_dot = rate * sigma;
    let nu = rate;
    let u = phi.norm_squared();
    let pn = phi.dot(nu);
    let u_dot = 2.0 * sigma * pn;
    let [a, b, c, db, dc, b_dot, c_dot, db_dot, dc_dot] = coefficients_with_rates(u, u_dot);
    let (p0, p1, p2) = (phi.x, phi.y, phi.z);
    let e0 = Vector3::x();
    // phi x e0 and phi x (phi x e0) = p0 phi - u e0.
    let pe = Vector3::new(0.0, p2, -p1);
    let ppe = Vector3::new(p0 * p0 - u, p0 * p1, p0 * p2);
    let pp = phi * phi.transpose();
    let k = Matrix3::new(0.0, -p2, p1, p2, 0.0, -p0, -p1, p0, 0.0);
    // E = 1 + a K + b K^2 and angular = sigma (1 + b K + c K^2), with K^2 = phi phi^T - u 1.
    let mut rotation = k * a + pp * b;
    let diag = 1.0 - b * u;
    rotation[(0, 0)] += diag;
    rotation[(1, 1)] += diag;
    rotation[(2, 2)] += diag;
    let mut angular = k * b + pp * c;
    let diag = 1.0 - c * u;
    angular[(0, 0)] += diag;
    angular[(1, 1)] += diag;
    angular[(2, 2)] += diag;
    angular *= sigma;
    let offset = (e0 + pe * b + ppe * c) * sigma;
    // linear = sigma^2 [2 db pe phi^T + 2 dc ppe phi^T - b [e0]x - c ([pe]x + K [e0]x)], where
    // [pe]x + K [e0]x = [[0, 2 p1, 2 p2], [-p1, -p0, 0], [-p2, 0, -p0]].
    let g = pe * (2.0 * db) + ppe * (2.0 * dc);
    let mut linear = g * phi.transpose();
    let m = Matrix3::new(0.0, 2.0 * p1, 2.0 * p2, -p1, -p0, 0.0, -p2, 0.0, -p0);
    linear -= m * c;
    linear[(2, 1)] -= b;
    linear[(1, 2)] += b;
    linear *= sigma * sigma;
    let pnu = phi.cross(nu);
    let angular_bias = (pnu * b_dot + phi.cross(&pnu) * c_dot + nu.cross(&pnu) * (c * sigma)) * sigma;
    let p_dot = sigma * nu.norm_squared();
    let nue = Vector3::new(0.0, nu.z, -nu.y);
    let pde = Vector3::new(0.0, phi_dot.z, -phi_dot.y);
    let linear_bias = (pe * (2.0 * (db_dot * pn + db * p_dot))
        + pde * (2.0 * db * pn)
        + nue * b_dot
        + ppe * (2.0 * (dc_dot * pn + dc * p_dot))
        + (phi_dot.cross(&pe) + phi.cross(&pde)) * (2.0 * dc * pn)
        + (nu.cross(&pe) + phi.cross(&nue)) * c_dot
        + nu.cross(&nue) * (2.0 * c * sigma))
        * (sigma * sigma);
    SegmentPoint { rotation, offset, angular, linear, angular_bias, linear_bias }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{Dual64, DualNum};

    fn paper_formula(omega: &Vector3<f64>, sigma: f64) -> Vector3<f64> {
        // Section 4.1 of the paper, in the start frame where n0 = e0.
        let w = omega.norm();
        let om = omega / w;
        let e0 = Vector3::x();
        let par = om * om.dot(&e0);
        let perp = e0 - par;
        par * sigma + perp * ((sigma * w).sin() / w) + om.cross(&perp) * ((1.0 - (sigma * w).cos()) / w)
    }

    #[test]
    fn transform_matches_the_papers_helix_formula() {
        // Tolerance 1e-15 m on a 1 cm segment: both are closed forms of the same helix.
        for omega in [Vector3::new(30.0, 80.0, 0.0), Vector3::new(-5.0, 200.0, 40.0), Vector3::new(1e3, 1.0, 0.0)] {
            let (_, p) = segment_transform(&omega, 0.01);
            assert!((p - paper_formula(&omega, 0.01)).norm() < 1e-15, "{omega:?}");
        }
    }

    #[test]
    fn rotation_is_orthonormal_and_straight_limit_is_exact() {
        let (e, p) = segment_transform(&Vector3::new(0.0, 0.0, 0.0), 0.02);
        assert_eq!(e, Matrix3::identity());
        assert_eq!(p, Vector3::new(0.02, 0.0, 0.0));
        let (e, _) = segment_transform::<f64>(&Vector3::new(3.0, 70.0, -20.0), 0.05);
        assert!((e.transpose() * e - Matrix3::identity()).norm() < 1e-14);
        assert!((e.determinant() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn series_and_closed_forms_agree_at_the_switch() {
        // Both branches evaluated just across u = 0.1 agree to 1e-13 (they are the same functions).
        let below = coefficients(SERIES_BELOW * (1.0 - 1e-12));
        let above = coefficients(SERIES_BELOW * (1.0 + 1e-12));
        assert!((below.0 - above.0).abs() < 1e-13);
        assert!((below.1 - above.1).abs() < 1e-13);
        assert!((below.2 - above.2).abs() < 1e-13);
        let d_below = coefficient_derivatives::<f64>(SERIES_BELOW * (1.0 - 1e-12));
        let d_above = coefficient_derivatives::<f64>(SERIES_BELOW * (1.0 + 1e-12));
        assert!((d_below.0 - d_above.0).abs() < 1e-12);
        assert!((d_below.1 - d_above.1).abs() < 1e-12);
    }

    #[test]
    fn derivatives_match_automatic_differentiation() {
        // Forward-mode dual numbers differentiate the closed form exactly; agreement to 1e-12 (relative).
        for omega in [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1e-3, 2e-3, 0.0), Vector3::new(30.0, 80.0, -10.0), Vector3::new(-300.0, 25.0, 90.0)] {
            let sigma = 0.013;
            let (ang, lin) = segment_derivatives::<f64>(&omega, sigma);
            for k in 0..3 {
                let om: Vector3<Dual64> = Vector3::from_fn(|i, _| {
                    let x = Dual64::from_re(omega[i]);
                    if i == k { x.derivative() } else { x }
                });
                let (e, p) = segment_transform(&om, sigma);
                let dp = p.map(|x| x.eps);
                let de = e.map(|x| x.eps);
                let e_re = e.map(|x| x.re());
                let w = de * e_re.transpose(); // [w]x
                let w = Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
                let scale = 1.0 + dp.norm();
                assert!((lin.column(k) - dp).norm() < 1e-12 * scale, "linear k={k} omega={omega:?}");
                assert!((ang.column(k) - w).norm() < 1e-12 * (1.0 + w.norm()), "angular k={k}");
            }
        }
    }

    #[test]
    fn fused_kinematics_match_the_separate_functions() {
        // segment_kinematics = transform + derivatives + their directional derivatives along the rate
        // (computed here with dual numbers through the generic functions): 1e-12 relative.
        for (omega, rate) in [
            (Vector3::new(0.0, 0.0, 0.0), Vector3::new(3.0, -2.0, 1.0)),
            (Vector3::new(1e-3, 2e-3, 0.0), Vector3::new(50.0, 10.0, 0.0)),
            (Vector3::new(30.0, 80.0, -10.0), Vector3::new(-40.0, 7.0, 20.0)),
            (Vector3::new(-300.0, 25.0, 90.0), Vector3::new(100.0, 300.0, -50.0)),
        ] {
            let sigma = 0.013;
            let f = segment_kinematics(&omega, &rate, sigma);
            let (e, p) = segment_transform(&omega, sigma);
            let (ang, lin) = segment_derivatives::<f64>(&omega, sigma);
            assert!((f.rotation - e).norm() < 1e-14 && (f.offset - p).norm() < 1e-15);
            assert!((f.angular - ang).norm() < 1e-12 * (1.0 + ang.norm()));
            assert!((f.linear - lin).norm() < 1e-12 * (1.0 + lin.norm()));
            let dual: Vector3<Dual64> = Vector3::from_fn(|k, _| Dual64::new(omega[k], rate[k]));
            let (da, dl) = segment_derivatives(&dual, sigma);
            let ab = da.map(|x| x.eps) * rate;
            let lb = dl.map(|x| x.eps) * rate;
            assert!((f.angular_bias - ab).norm() < 1e-12 * (1.0 + ab.norm()), "{} vs {}", f.angular_bias, ab);
            assert!((f.linear_bias - lb).norm() < 1e-12 * (1.0 + lb.norm()), "{} vs {}", f.linear_bias, lb);
        }
    }
}
