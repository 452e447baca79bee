//! The strand spec: a plain, serde-readable description of one strand (the `coiffure strand --spec` file).
//! Reading the file is the caller's business; this module turns its contents into a model and a root.
//!
//! Fields (SI units; see docs/strand-spec.md):
//! `model` ("reduced" | "full", default "reduced"), `length` (m), `segments`, either `hair_type` (a preset
//! name) or `semi_axes = [a, b]` (m), `young_modulus` (Pa), `shear_modulus` (Pa), `density` (kg/m^3),
//! `rest_twist`, `rest_bend`, `rest_bend2` (rad/m, a number or one per segment), `root_position` (m),
//! `root_tangent`, `root_major_axis`, `gravity` (m/s^2), `air_drag` (N s/m^2), `damping` (s),
//! `quadrature_points`.

use crate::error::{Result, StrandError};
use crate::hair_type::HairType;
use crate::material::Material;
use crate::model::{ModelKind, StrandModel, DEFAULT_AIR_DRAG, DEFAULT_DAMPING, DEFAULT_QUADRATURE_POINTS};
use crate::state::RootFrame;
use nalgebra::Vector3;
use serde::Deserialize;

/// A number for every segment, or one value for all.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum PerSegment {
    /// The same value on every segment.
    Uniform(f64),
    /// One value per segment (must have `segments` entries).
    Each(Vec<f64>),
}

impl PerSegment {
    fn expand(&self, field: &'static str, n: usize) -> Result<Vec<f64>> {
        match self {
            PerSegment::Uniform(v) => Ok(vec![*v; n]),
            PerSegment::Each(v) if v.len() == n => Ok(v.clone()),
            PerSegment::Each(v) => Err(StrandError::InvalidParameter {
                field,
                reason: format!("needs one value per segment ({n}) or a single number, got {} values", v.len()),
            }),
        }
    }
}

/// Contents of a strand spec file. Every field but `length` and `segments` has a default.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrandSpec {
    /// "reduced" (default) or "full".
    #[serde(default)]
    pub model: ModelKind,
    /// Strand length, m.
    pub length: f64,
    /// Number of helical segments.
    pub segments: usize,
    /// A hair-type preset (`H1`, `H2`, `GA1`, `GC3`, `asian`, `caucasian`, `african`); gives the section,
    /// moduli, density and natural curl unless those fields are given too. Default when no `semi_axes`: H1.
    pub hair_type: Option<String>,
    /// Semi-axes `[a, b]` of the elliptical section, m (a along the major axis).
    pub semi_axes: Option<[f64; 2]>,
    /// Young's modulus, Pa (default: from the hair type, else 3.9e9).
    pub young_modulus: Option<f64>,
    /// Shear modulus, Pa (default: from the hair type, else 0.9e9).
    pub shear_modulus: Option<f64>,
    /// Density, kg/m^3 (default 1300).
    pub density: Option<f64>,
    /// Rest twist, rad/m (default: the hair type's curl, else 0).
    pub rest_twist: Option<PerSegment>,
    /// Rest bend about the major axis, rad/m (default: the hair type's curl, else 0).
    pub rest_bend: Option<PerSegment>,
    /// Rest bend about the minor axis, rad/m (full model only; default 0).
    pub rest_bend2: Option<PerSegment>,
    /// Root position, m (default origin).
    #[serde(default)]
    pub root_position: [f64; 3],
    /// Root tangent (default straight down, [0, 0, -1]).
    pub root_tangent: Option<[f64; 3]>,
    /// Direction of the section's major axis at the root (default [1, 0, 0]).
    pub root_major_axis: Option<[f64; 3]>,
    /// Gravity, m/s^2 (default [0, 0, -9.81]).
    pub gravity: Option<[f64; 3]>,
    /// Air drag coefficient, N s/m^2 (default 1e-5).
    pub air_drag: Option<f64>,
    /// Internal damping relaxation time, s (default 0.02).
    pub damping: Option<f64>,
    /// Gauss points per segment (default 2).
    pub quadrature_points: Option<usize>,
}

impl StrandSpec {
    /// Builds and validates the model and the root frame; errors name the offending field.
    pub fn build(&self) -> Result<(StrandModel, RootFrame)> {
        let preset = match (&self.hair_type, self.semi_axes) {
            (Some(name), _) => Some(HairType::by_name(name).ok_or_else(|| StrandError::InvalidParameter {
                field: "hair_type",
                reason: format!(
                    "unknown hair type {name:?}; known: {}",
                    HairType::ALL.iter().map(|h| h.name).collect::<Vec<_>>().join(", ")
                ),
            })?),
            (None, Some(_)) => None,
            (None, None) => Some(HairType::H1),
        };
        let section = match (self.semi_axes, preset) {
            (Some([a, b]), _) => crate::section::CrossSection::new(a, b)?,
            (None, Some(h)) => h.section()?,
            (None, None) => unreachable!("a preset is chosen when semi_axes is absent"),
        };
        let base = match preset {
            Some(h) => h.material()?,
            None => Material::default(),
        };
        let material = Material {
            young_modulus: self.young_modulus.unwrap_or(base.young_modulus),
            shear_modulus: self.shear_modulus.unwrap_or(base.shear_modulus),
            density: self.density.unwrap_or(base.density),
        };
        if self.segments == 0 {
            return Err(StrandError::InvalidParameter { field: "segments", reason: "must be at least 1, got 0".into() });
        }
        let mut model = StrandModel::new(self.model, self.length, self.segments, section, material)?;
        let (curl_twist, curl_bend) = preset.map(|h| h.rest_curvature()).unwrap_or((0.0, 0.0));
        let n = self.segments;
        let twist = self.rest_twist.clone().unwrap_or(PerSegment::Uniform(curl_twist)).expand("rest_twist", n)?;
        let bend = self.rest_bend.clone().unwrap_or(PerSegment::Uniform(curl_bend)).expand("rest_bend", n)?;
        let bend2 = self.rest_bend2.clone().unwrap_or(PerSegment::Uniform(0.0)).expand("rest_bend2", n)?;
        model.rest = (0..n).map(|i| Vector3::new(twist[i], bend[i], bend2[i])).collect();
        if let Some(g) = self.gravity {
            model.gravity = Vector3::from(g);
        }
        model.air_drag = self.air_drag.unwrap_or(DEFAULT_AIR_DRAG);
        model.damping = self.damping.unwrap_or(DEFAULT_DAMPING);
        model.quadrature_points = self.quadrature_points.unwrap_or(DEFAULT_QUADRATURE_POINTS);
        model.validate()?;
        let root = RootFrame::new(
            Vector3::from(self.root_position),
            Vector3::from(self.root_tangent.unwrap_or([0.0, 0.0, -1.0])),
            Vector3::from(self.root_major_axis.unwrap_or([1.0, 0.0, 0.0])),
        )?;
        Ok((model, root))
    }
}
