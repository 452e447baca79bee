//! The immutable model of one strand (MuJoCo's "model" side): geometry, material, rest shape, environment.
//! The mutable side is [`crate::state::StrandState`].

use crate::error::{require_non_negative, require_positive, Result, StrandError};
use crate::material::Material;
use crate::section::CrossSection;
use nalgebra::{DVector, Vector3};
use serde::{Deserialize, Serialize};

/// Which Super-Helix: the paper's reduced model or the full model of Bertails et al. (2006).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Two coordinates per segment: twist (about `n0`) and bend about the major axis `n1` (the paper's model).
    #[default]
    Reduced,
    /// Three coordinates per segment: twist, bend about `n1` and bend about the minor axis `n2`.
    Full,
}

impl ModelKind {
    /// Generalized coordinates per segment: 2 (reduced) or 3 (full).
    pub fn dofs_per_segment(self) -> usize {
        match self {
            ModelKind::Reduced => 2,
            ModelKind::Full => 3,
        }
    }
}

/// Everything about a strand that does not change while it moves. Build it with [`StrandModel::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct StrandModel {
    /// Reduced (2N coordinates) or full (3N) Super-Helix.
    pub kind: ModelKind,
    /// Length L of the strand, m.
    pub length: f64,
    /// Number of helical segments N (equal lengths L/N).
    pub segments: usize,
    /// Elliptical cross-section (semi-major axis along `n1`).
    pub section: CrossSection,
    /// Elastic moduli and density.
    pub material: Material,
    /// Rest Darboux vector of each segment `(twist, bend, bend2)`, rad/m; it gives the natural curl.
    /// `bend2` (about the minor axis) is always 0 for the reduced model.
    pub rest: Vec<Vector3<f64>>,
    /// Gravitational acceleration, m/s^2. Default (0, 0, -9.81).
    pub gravity: Vector3<f64>,
    /// Air drag coefficient nu: drag force per unit length is `-nu rdot`, N s/m^2. Default 1e-5.
    pub air_drag: f64,
    /// Internal (Kelvin-Voigt) damping as a relaxation time tau: dissipation forces are `-tau K qdot`, s.
    /// Default 0.02.
    pub damping: f64,
    /// Gauss-Legendre points per segment for the mass and force integrals. Default 2 (3 changes a
    /// 1 s trajectory by under 1e-8 m, see docs/physics.md).
    pub quadrature_points: usize,
}

/// Default air drag coefficient, N s/m^2 (order of the Stokes drag of a 90 um fibre in still air).
pub const DEFAULT_AIR_DRAG: f64 = 1e-5;
/// Default internal damping relaxation time, s.
pub const DEFAULT_DAMPING: f64 = 0.02;
/// Default Gauss points per segment.
pub const DEFAULT_QUADRATURE_POINTS: usize = 2;

impl StrandModel {
    /// A straight strand at rest (no curl) with default environment; `rest` etc. can be changed after.
    pub fn new(kind: ModelKind, length: f64, segments: usize, section: CrossSection, material: Material) -> Result<Self> {
        let m = Self {
            kind,
            length,
            segments,
            section,
            material,
            rest: vec![Vector3::zeros(); segments],
            gravity: Vector3::new(0.0, 0.0, -9.81),
            air_drag: DEFAULT_AIR_DRAG,
            damping: DEFAULT_DAMPING,
            quadrature_points: DEFAULT_QUADRATURE_POINTS,
        };
        m.validate()?;
        Ok(m)
    }

    /// Sets the same rest twist and bend (rad/m) on every segment (and bend2 for the full model).
    pub fn with_uniform_rest(mut self, twist: f64, bend: f64, bend2: f64) -> Self {
        let b2 = if self.kind == ModelKind::Full { bend2 } else { 0.0 };
        self.rest = vec![Vector3::new(twist, bend, b2); self.segments];
        self
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        require_positive("length", self.length)?;
        if self.segments == 0 || self.segments > 4096 {
            return Err(StrandError::InvalidParameter {
                field: "segments",
                reason: format!("must be between 1 and 4096, got {}", self.segments),
            });
        }
        CrossSection::new(self.section.semi_major, self.section.semi_minor)?;
        self.material.validate()?;
        if self.rest.len() != self.segments {
            return Err(StrandError::InvalidParameter {
                field: "rest_twist",
                reason: format!("needs one value per segment ({}), got {}", self.segments, self.rest.len()),
            });
        }
        for (i, r) in self.rest.iter().enumerate() {
            for (k, field) in [(0, "rest_twist"), (1, "rest_bend"), (2, "rest_bend2")] {
                if !r[k].is_finite() {
                    return Err(StrandError::InvalidParameter { field, reason: format!("segment {i} is {}", r[k]) });
                }
            }
            if self.kind == ModelKind::Reduced && r[2] != 0.0 {
                return Err(StrandError::InvalidParameter {
                    field: "rest_bend2",
                    reason: "the reduced model cannot bend about the minor axis; use model = \"full\"".into(),
                });
            }
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return Err(StrandError::InvalidParameter { field: "gravity", reason: format!("must be finite, got {:?}", self.gravity) });
        }
        require_non_negative("air_drag", self.air_drag)?;
        require_non_negative("damping", self.damping)?;
        if !(1..=16).contains(&self.quadrature_points) {
            return Err(StrandError::InvalidParameter {
                field: "quadrature_points",
                reason: format!("must be between 1 and 16, got {}", self.quadrature_points),
            });
        }
        Ok(())
    }

    /// Generalized coordinates per segment (2 or 3).
    pub fn dofs_per_segment(&self) -> usize {
        self.kind.dofs_per_segment()
    }

    /// Total number of generalized coordinates, 2N or 3N.
    pub fn dofs(&self) -> usize {
        self.segments * self.dofs_per_segment()
    }

    /// Length of one segment L/N, m.
    pub fn segment_length(&self) -> f64 {
        self.length / self.segments as f64
    }

    /// Mass per unit length rho A, kg/m.
    pub fn linear_density(&self) -> f64 {
        self.material.density * self.section.area()
    }

    /// Total mass, kg.
    pub fn mass(&self) -> f64 {
        self.linear_density() * self.length
    }

    /// Stiffness per unit length of each Darboux component `(G J, E I_soft, E I_stiff)`, N m^2.
    pub fn rigidities(&self) -> Vector3<f64> {
        Vector3::new(
            self.material.shear_modulus * self.section.torsion_constant(),
            self.material.young_modulus * self.section.i_soft(),
            self.material.young_modulus * self.section.i_stiff(),
        )
    }

    /// Diagonal of the stiffness matrix K (`l_Q` times the rigidity of each coordinate), N m.
    pub fn stiffness(&self) -> DVector<f64> {
        let d = self.dofs_per_segment();
        let r = self.rigidities() * self.segment_length();
        DVector::from_fn(self.dofs(), |i, _| r[i % d])
    }

    /// Rest coordinates `q_rest` (2N or 3N), rad/m.
    pub fn rest_coordinates(&self) -> DVector<f64> {
        let d = self.dofs_per_segment();
        DVector::from_fn(self.dofs(), |i, _| self.rest[i / d][i % d])
    }

    /// Replaces the rest shape from a coordinate vector (2N or 3N), rad/m.
    pub fn set_rest_coordinates(&mut self, q_rest: &DVector<f64>) {
        let d = self.dofs_per_segment();
        for (i, r) in self.rest.iter_mut().enumerate() {
            for k in 0..d {
                r[k] = q_rest[i * d + k];
            }
        }
    }

    /// Rotary inertia per unit length about `(n0, n1, n2)`: `rho (I_polar, I_soft, I_stiff)`, kg m.
    pub fn rotary_inertia(&self) -> Vector3<f64> {
        let rho = self.material.density;
        Vector3::new(rho * self.section.i_polar(), rho * self.section.i_soft(), rho * self.section.i_stiff())
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton iteration on the Legendre polynomial).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else if n == 1 { x } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pm) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out.reverse();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // n points integrate degree 2n-1 exactly; check x^(2n-2) and the weights' sum (1e-13).
        for n in 1..=8 {
            let gl = gauss_legendre(n);
            let sum: f64 = gl.iter().map(|(_, w)| w).sum();
            assert!((sum - 2.0).abs() < 1e-13, "n={n}");
            let deg = 2 * n - 2;
            let integral: f64 = gl.iter().map(|(x, w)| w * x.powi(deg as i32)).sum();
            assert!((integral - 2.0 / (deg as f64 + 1.0)).abs() < 1e-13, "n={n}");
        }
    }

    #[test]
    fn bad_models_name_the_field() {
        let s = CrossSection::new(40e-6, 30e-6).unwrap();
        let m = Material::default();
        let err = |r: Result<StrandModel>| match r {
            Err(StrandError::InvalidParameter { field, .. }) => field,
            other => panic!("expected an error, got {other:?}"),
        };
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.0, 4, s, m)), "length");
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, -0.1, 4, s, m)), "length");
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.1, 0, s, m)), "segments");
        let bad = Material { young_modulus: f64::NAN, ..m };
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.1, 4, s, bad)), "young_modulus");
        let bad = Material { shear_modulus: -1.0, ..m };
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.1, 4, s, bad)), "shear_modulus");
        let bad = Material { density: 0.0, ..m };
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.1, 4, s, bad)), "density");
        let zero = CrossSection { semi_major: 0.0, semi_minor: 0.0 };
        assert_eq!(err(StrandModel::new(ModelKind::Reduced, 0.1, 4, zero, m)), "semi_axes");
    }
}
