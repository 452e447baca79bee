//! A similarity transform (scale, rotation, translation): the fit's map from file to head frame.

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
}
