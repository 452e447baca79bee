//! Elliptical cross-section of a hair fibre and its geometric moments.
//!
//! The section has semi-major axis `a` (along the material frame's `n1`) and semi-minor axis `b`
//! (along `n2`), `a >= b > 0`. Bending "about the major axis" rotates the section about `n1`; the
//! fibre then curves towards `n2` and resists with the small moment `I_soft = pi a b^3 / 4`.

use crate::error::{require_positive, Result, StrandError};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Elliptical cross-section, semi-axes in m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CrossSection {
    /// Semi-major axis `a`, m (along `n1`). Human hair: about 35-60 um.
    pub semi_major: f64,
    /// Semi-minor axis `b`, m (along `n2`), `b <= a`.
    pub semi_minor: f64,
}

impl CrossSection {
    /// Section from its semi-axes in m (`a >= b > 0`).
    pub fn new(semi_major: f64, semi_minor: f64) -> Result<Self> {
        require_positive("semi_axes", semi_major)?;
        require_positive("semi_axes", semi_minor)?;
        if semi_minor > semi_major {
            return Err(StrandError::InvalidParameter {
                field: "semi_axes",
                reason: format!(
                    "the first (major, along root_major_axis) must be >= the second, got [{semi_major}, {semi_minor}]"
                ),
            });
        }
        Ok(Self { semi_major, semi_minor })
    }

    /// Section from the major-axis diameter in m and the ellipticity (major/minor ratio, >= 1),
    /// as hair science reports them (e.g. Table 1 of the paper).
    pub fn from_diameter(major_diameter: f64, ellipticity: f64) -> Result<Self> {
        require_positive("diameter", major_diameter)?;
        if !(ellipticity.is_finite() && ellipticity >= 1.0) {
            return Err(StrandError::InvalidParameter {
                field: "ellipticity",
                reason: format!("must be a finite number >= 1, got {ellipticity}"),
            });
        }
        Self::new(major_diameter / 2.0, major_diameter / 2.0 / ellipticity)
    }

    /// Ellipticity a/b (1 for a circle).
    pub fn ellipticity(&self) -> f64 {
        self.semi_major / self.semi_minor
    }

    /// Area `pi a b`, m^2.
    pub fn area(&self) -> f64 {
        PI * self.semi_major * self.semi_minor
    }

    /// Second moment about the major axis `n1`, `pi a b^3 / 4`, m^4 (the soft bending direction).
    pub fn i_soft(&self) -> f64 {
        PI * self.semi_major * self.semi_minor.powi(3) / 4.0
    }

    /// Second moment about the minor axis `n2`, `pi a^3 b / 4`, m^4 (the stiff bending direction).
    pub fn i_stiff(&self) -> f64 {
        PI * self.semi_major.powi(3) * self.semi_minor / 4.0
    }

    /// Polar second moment `I_soft + I_stiff`, m^4 (rotary inertia about the tangent).
    pub fn i_polar(&self) -> f64 {
        self.i_soft() + self.i_stiff()
    }

    /// Saint-Venant torsion constant of an ellipse `pi a^3 b^3 / (a^2 + b^2)`, m^4.
    pub fn torsion_constant(&self) -> f64 {
        let (a, b) = (self.semi_major, self.semi_minor);
        PI * a.powi(3) * b.powi(3) / (a * a + b * b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_moments_match_textbook() {
        // A circle of radius r: I = pi r^4/4, J = pi r^4/2 (torsion constant equals the polar moment).
        let r = 40e-6;
        let s = CrossSection::new(r, r).unwrap();
        let i = PI * r.powi(4) / 4.0;
        assert!((s.i_soft() - i).abs() < 1e-12 * i);
        assert!((s.i_stiff() - i).abs() < 1e-12 * i);
        assert!((s.torsion_constant() - 2.0 * i).abs() < 1e-12 * i);
    }

    #[test]
    fn ellipse_soft_axis_is_softer() {
        let s = CrossSection::from_diameter(93.1e-6, 1.36).unwrap();
        assert!((s.ellipticity() - 1.36).abs() < 1e-12);
        assert!(s.i_soft() < s.i_stiff());
        // Torsion constant of an ellipse is below its polar moment.
        assert!(s.torsion_constant() < s.i_polar());
    }

    #[test]
    fn bad_sections_name_the_field() {
        for (a, b) in [(0.0, 1e-6), (1e-6, -1.0), (f64::NAN, 1e-6), (1e-6, 2e-6)] {
            match CrossSection::new(a, b) {
                Err(StrandError::InvalidParameter { field, .. }) => assert_eq!(field, "semi_axes"),
                other => panic!("expected an error naming semi_axes, got {other:?}"),
            }
        }
        assert!(matches!(
            CrossSection::from_diameter(90e-6, 0.5),
            Err(StrandError::InvalidParameter { field: "ellipticity", .. })
        ));
    }
}
