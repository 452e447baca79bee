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
const SERIES_BELOW: f64 = 0.1;

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
pub fn coefficient_derivatives(u: f64) -> (f64, f64) {
    if u < SERIES_BELOW {
        let db = -1.0 / 24.0 + u * (2.0 / 720.0 - u * (3.0 / 40320.0 - u * (4.0 / 3628800.0 - u * 5.0 / 479001600.0)));
        let dc = -1.0 / 120.0 + u * (2.0 / 5040.0 - u * (3.0 / 362880.0 - u * (4.0 / 39916800.0 - u * 5.0 / 6227020800.0)));
        (db, dc)
    } else {
        let t = u.sqrt();
        let (s, co) = (t.sin(), t.cos());
        let db = (t * s - 2.0 * (1.0 - co)) / (2.0 * u * u);
        let dc = (t * (1.0 - co) - 3.0 * (t - s)) / (2.0 * u * u * t);
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
pub fn segment_derivatives(omega: &Vector3<f64>, sigma: f64) -> (Matrix3<f64>, Matrix3<f64>) {
    let phi = omega * sigma;
    let u = phi.norm_squared();
    let (_, b, c) = coefficients(u);
    let (db, dc) = coefficient_derivatives(u);
    let e0 = Vector3::x();
    let pe = phi.cross(&e0);
    let ppe = phi.cross(&pe);
    let mut angular = Matrix3::zeros();
    let mut linear = Matrix3::zeros();
    for k in 0..3 {
        let ek = Vector3::ith(k, 1.0);
        let pk = phi.cross(&ek);
        angular.set_column(k, &((ek + pk * b + phi.cross(&pk) * c) * sigma));
        let d = pe * (2.0 * phi[k] * db)
            + ek.cross(&e0) * b
            + ppe * (2.0 * phi[k] * dc)
            + (ek.cross(&pe) + phi.cross(&ek.cross(&e0))) * c;
        linear.set_column(k, &(d * (sigma * sigma)));
    }
    (angular, linear)
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
        let d_below = coefficient_derivatives(SERIES_BELOW * (1.0 - 1e-12));
        let d_above = coefficient_derivatives(SERIES_BELOW * (1.0 + 1e-12));
        assert!((d_below.0 - d_above.0).abs() < 1e-12);
        assert!((d_below.1 - d_above.1).abs() < 1e-12);
    }

    #[test]
    fn derivatives_match_automatic_differentiation() {
        // Forward-mode dual numbers differentiate the closed form exactly; agreement to 1e-12 (relative).
        for omega in [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1e-3, 2e-3, 0.0), Vector3::new(30.0, 80.0, -10.0), Vector3::new(-300.0, 25.0, 90.0)] {
            let sigma = 0.013;
            let (ang, lin) = segment_derivatives(&omega, sigma);
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
}
