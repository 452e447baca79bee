//! Least-squares similarity transform between paired point sets (Umeyama 1991).

use nalgebra::{Matrix3, Point3, Vector3};

/// x -> scale * rotation * x + translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    /// Scale factor (dimensionless, or m per file unit).
    pub scale: f64,
    /// Proper rotation (det +1).
    pub rotation: Matrix3<f64>,
    /// Translation, m.
    pub translation: Vector3<f64>,
}

impl Similarity {
    /// The identity.
    pub fn identity() -> Self {
        Self { scale: 1.0, rotation: Matrix3::identity(), translation: Vector3::zeros() }
    }

    /// Applies the transform to `p`.
    pub fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.scale * (self.rotation * p.coords) + self.translation)
    }

    /// `self` after `first`: x -> self(first(x)).
    pub fn after(&self, first: &Similarity) -> Similarity {
        Similarity {
            scale: self.scale * first.scale,
            rotation: self.rotation * first.rotation,
            translation: self.scale * (self.rotation * first.translation) + self.translation,
        }
    }

    /// The similarity minimising sum |s R a_i + t - b_i|^2 over pairs (a_i, b_i), with the scale
    /// clamped to `scale_range` (the translation then re-solved for the clamped scale). None for
    /// fewer than 3 pairs or a degenerate (collinear) set.
    pub fn fit(a: &[Point3<f64>], b: &[Point3<f64>], scale_range: (f64, f64)) -> Option<Similarity> {
        let n = a.len();
        if n < 3 || b.len() != n {
            return None;
        }
        let ma = a.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n as f64;
        let mb = b.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n as f64;
        let mut cov = Matrix3::zeros();
        let mut var_a = 0.0;
        for (p, q) in a.iter().zip(b) {
            let (da, db) = (p.coords - ma, q.coords - mb);
            cov += db * da.transpose();
            var_a += da.norm_squared();
        }
        cov /= n as f64;
        var_a /= n as f64;
        if var_a <= 0.0 {
            return None;
        }
        let svd = cov.svd(true, true);
        let (u, v_t) = (svd.u?, svd.v_t?);
        let mut s = Matrix3::identity();
        if (u.determinant() * v_t.determinant()) < 0.0 {
            s[(2, 2)] = -1.0;
        }
        let rotation = u * s * v_t;
        let d = svd.singular_values;
        let trace = d[0] * s[(0, 0)] + d[1] * s[(1, 1)] + d[2] * s[(2, 2)];
        let scale = (trace / var_a).clamp(scale_range.0, scale_range.1);
        if !(scale.is_finite() && scale > 0.0) || !rotation.iter().all(|x| x.is_finite()) {
            return None;
        }
        Some(Similarity { scale, rotation, translation: mb - scale * (rotation * ma) })
    }
}
