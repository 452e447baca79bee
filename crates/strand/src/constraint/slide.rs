//! A sliding drag's impulse: Coulomb's law at its bound, the force against the relative motion it leaves (the
//! principle of maximum dissipation), whatever the point's mobility in each direction.
//!
//! A drag row whose impulse to stop the relative motion, `-(W + R I)^-1 u0` (`W` the point's Delassus block, `R`
//! the force mixing, `u0` the point's velocity relative to the obstacle without this row's impulse), exceeds the
//! bound `b` slides. Shortening that impulse to `b` would keep its direction, which the block's anisotropy turns
//! towards the directions in which the point hardly moves (along a taut, inextensible strand the block is four
//! orders of magnitude stiffer than across it): the force would then not oppose the sliding velocity, and its part
//! across the strand, the part that carries a wisp sideways with a tooth, would depend on how the step's size sets
//! `W` against `R`. The impulse at the bound that opposes the relative velocity after the step is
//! `p = -(W + lambda I)^-1 u0` with `lambda >= R` such that `|p| = b`: then `u0 + W p + R p = -(lambda - R) p`, the
//! velocity left (with the mixing's compliance, as the row aims for below its bound) is along `-p`. `|p|` falls
//! monotonically with `lambda`, so `lambda` is one root in a bracket (the trust-region subproblem's secular
//! equation, solved in `W`'s eigenbasis by safeguarded Newton steps on `1 / |p| - 1 / b`).

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// `W`'s eigenbasis (columns) and its eigenvalues (m/s per N s, negative round-off set to 0), for [`sliding`].
pub(super) fn eigenbasis(w: &Matrix3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let sym = (w + w.transpose()) * 0.5;
    let e = SymmetricEigen::new(sym);
    (e.eigenvectors, e.eigenvalues.map(|x| x.max(0.0)))
}

/// The impulse of norm `bound` (N s, > 0) opposing the relative velocity it leaves: `-(W + lambda I)^-1 u0` with
/// `lambda >= mix` and `|p| = bound`, `W = axes diag(mobilities) axes^T`, `u0` the relative velocity without the
/// row's impulse (m/s). Call it where the unbounded impulse `-(W + mix I)^-1 u0` is longer than `bound`; if it is
/// not (round-off), the unbounded impulse is returned, shortened to `bound` at most.
pub(super) fn sliding(axes: &Matrix3<f64>, mobilities: &Vector3<f64>, mix: f64, u0: &Vector3<f64>, bound: f64) -> Vector3<f64> {
    let c = axes.transpose() * u0;
    let at = |lambda: f64| Vector3::new(c.x / (mobilities.x + lambda), c.y / (mobilities.y + lambda), c.z / (mobilities.z + lambda));
    let speed = u0.norm();
    if !(bound > 0.0) || !(speed > 0.0) {
        return Vector3::zeros();
    }
    // |p(lambda)| <= |u0| / lambda (the mobilities are >= 0): the root lies in [mix, |u0| / bound].
    let (mut lo, mut hi) = (mix.max(0.0), speed / bound);
    if hi <= lo {
        return -shorten(axes * at(lo), bound);
    }
    let mut lambda = lo;
    for _ in 0..100 {
        let q = at(lambda);
        let n = q.norm();
        if !n.is_finite() || !(lambda > 0.0 || n > 0.0) {
            lambda = if lo > 0.0 { (lo * hi).sqrt() } else { 0.5 * hi };
            continue;
        }
        if (n - bound).abs() <= 1e-13 * bound {
            break;
        }
        if n > bound {
            lo = lambda;
        } else {
            hi = lambda;
        }
        // Newton on phi = 1 / |p| - 1 / b (concave and increasing in lambda): phi' = sum c_i^2 / (w_i + l)^3 / |p|^3.
        let slope = Vector3::new(q.x * q.x / (mobilities.x + lambda), q.y * q.y / (mobilities.y + lambda), q.z * q.z / (mobilities.z + lambda)).sum() / (n * n * n);
        let step = (1.0 / n - 1.0 / bound) / slope;
        let next = lambda - step;
        lambda = if slope > 0.0 && next > lo && next < hi { next } else { 0.5 * (lo + hi) };
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    -shorten(axes * at(lambda), bound)
}

/// `x` scaled to norm `limit` if longer; exactly `limit` long if within round-off of it.
fn shorten(x: Vector3<f64>, limit: f64) -> Vector3<f64> {
    let n = x.norm();
    if n > limit * (1.0 - 1e-12) && n > 0.0 { x * (limit / n) } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sliding_impulse_opposes_the_velocity_it_leaves() {
        // An anisotropic block (a point that moves 1e4 times more easily across a strand than along it), a relative
        // velocity mostly along the stiff direction, bounds from just below the unbounded impulse to far below:
        // the impulse is exactly the bound long, and the velocity it leaves with the mixing's compliance,
        // u0 + (W + R) p, is along -p (1e-9 rad); the plain shortening of the unbounded impulse is not (it points
        // along the stiff direction).
        let w = Matrix3::from_diagonal(&Vector3::new(3.0e6, 2.0e6, 3.0e2));
        let turn = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.7).into_inner();
        let w = turn * w * turn.transpose();
        let (axes, mobilities) = eigenbasis(&w);
        let mix = 1.0e4;
        let u0 = turn * Vector3::new(0.01, -0.004, -0.25);
        let free = -(w + Matrix3::identity() * mix).try_inverse().unwrap() * u0;
        for share in [0.99, 0.5, 1e-2, 1e-4, 1e-8] {
            let bound = share * free.norm();
            let p = sliding(&axes, &mobilities, mix, &u0, bound);
            let left = u0 + (w + Matrix3::identity() * mix) * p;
            let angle = (-p).angle(&left);
            assert!((p.norm() - bound).abs() <= 1e-12 * bound, "norm {} against {bound}", p.norm());
            assert!(angle < 1e-9, "share {share}: angle {angle} rad between -p and the velocity left");
            let plain = free * (bound / free.norm());
            let plain_left = u0 + (w + Matrix3::identity() * mix) * plain;
            if share <= 0.5 {
                assert!((-plain).angle(&plain_left) > 1e-3, "the plain shortening opposes the motion too");
            }
        }
    }
}
