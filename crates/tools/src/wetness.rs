//! Wetness of hair and what it does to the fibre: mass (water uptake), stiffness (Young's and torsional
//! moduli) and friction. The data and their sources are in `docs/wetness.md`.
//!
//! Wetness `w` is dimensionless in [0, 1]: 0 is hair in equilibrium with ambient air (about 65 % relative
//! humidity, the condition the presets' data were measured at), 1 is a fibre saturated with water carrying the
//! surface water of a towel-dried wet tress. [`WetnessModel`] (immutable) maps a hair type and `w` to the
//! effective material the strand and lattice layers use; [`WetnessField`] (state) holds `w` per guide strand
//! and per segment.
//!
//! Laws (w in [0, 1]):
//! - linear mass (and the effective density, at a fixed section) grows linearly with the water carried:
//!   `m(w) = m_dry (1 + w (uptake + surface))`;
//! - moduli fall geometrically: `E(w) = E_dry r_E^w`, `G(w) = G_dry r_G^w` (log-linear in water content, the
//!   shape of the modulus-humidity curves of keratin fibres; exactly dry at 0 and exactly the wet ratio at 1);
//! - the friction coefficient of the fibre's surface grows linearly: `mu(w) = mu_dry (1 + w (r_mu - 1))`.

use strand::material::Material;
use strand::HairType;

/// What can be wrong with a wetness value or a wetness model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WetnessError {
    /// A wetness value is NaN, infinite or outside [0, 1].
    #[error("{field}: wetness must be a number in [0, 1], got {value}")]
    OutOfRange {
        /// Which value (e.g. "wetness", "wetness[3][2]").
        field: String,
        /// The value given.
        value: f64,
    },
    /// A model parameter is out of its range.
    #[error("{field}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A field's shape does not match the strands it is applied to.
    #[error("wetness field shape: {0}")]
    Shape(String),
}

/// Checks that `w` is a finite number in [0, 1]; names `field` otherwise.
pub fn check_wetness(field: &str, w: f64) -> Result<f64, WetnessError> {
    if w.is_finite() && (0.0..=1.0).contains(&w) {
        Ok(w)
    } else {
        Err(WetnessError::OutOfRange {
            field: field.to_string(),
            value: w,
        })
    }
}

/// How wetness changes a hair fibre (immutable model). Every ratio is "value at w = 1 over value at w = 0".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WetnessModel {
    /// Water absorbed by the fibre at saturation, as a fraction of its dry mass (dimensionless).
    /// Default 0.30 (Robbins 2012: about 30 % of dry weight at saturation / 100 % RH).
    pub water_uptake: f64,
    /// Surface (capillary) water carried by a wet tress at w = 1, fraction of the dry hair mass
    /// (dimensionless). Default 0.5 (a towel-dried tress; an assumption, see docs/wetness.md).
    pub surface_water: f64,
    /// Young's modulus wet / dry (dimensionless, in (0, 1]). Default 0.4 (Robbins: about 1.5-2 GPa in water
    /// against about 4-4.5 GPa at 65 % RH in the Hookean region).
    pub young_ratio: f64,
    /// Torsional (shear) modulus wet / dry (dimensionless, in (0, 1]). Default 0.1 (Bogaty 1967 via Robbins:
    /// the torsional modulus falls about tenfold from 65 % RH to water, far more than the tensile one).
    pub shear_ratio: f64,
    /// Friction coefficient wet / dry (dimensionless, >= 1), tool on hair and hair on hair, of the fibre's surface.
    /// Default 1.5: the low end of the single-fibre wet/dry ratios (1.5-2; friction is higher in water for
    /// virgin, damaged and conditioned hair, Nikogeorgos et al. 2010; docs/wetness.md, docs/treatment.md). Not
    /// fitted to combing: the rest of the wet rise of a straight tress (about 7.5 times the dry force, J. Soc.
    /// Cosmet. Chem. 24, 1973) comes from the capillary adhesion of wet fibres and the bridges on the tooth
    /// (`crate::entanglement`). (It was 6.0 until issue 29, an effective coefficient calibrated on the tresses'
    /// wet/dry ratios.)
    pub friction_ratio: f64,
}

impl Default for WetnessModel {
    fn default() -> Self {
        Self {
            water_uptake: 0.30,
            surface_water: 0.5,
            young_ratio: 0.4,
            shear_ratio: 0.1,
            friction_ratio: 1.5,
        }
    }
}

/// The effective properties of a fibre at some wetness, for the strand and lattice layers (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WetMaterial {
    /// Wetness this was computed for, in [0, 1].
    pub wetness: f64,
    /// Effective Young's modulus E, Pa.
    pub young_modulus: f64,
    /// Effective shear (torsional) modulus G, Pa.
    pub shear_modulus: f64,
    /// Effective density (dry section, wet mass), kg/m^3.
    pub density: f64,
    /// Mass per unit length including water, kg/m.
    pub linear_density: f64,
    /// Tool-hair Coulomb friction coefficient (dimensionless).
    pub friction: f64,
}

impl WetMaterial {
    /// As a strand [`Material`] (moduli and density).
    pub fn material(&self) -> Material {
        Material {
            young_modulus: self.young_modulus,
            shear_modulus: self.shear_modulus,
            density: self.density,
        }
    }
}

impl WetnessModel {
    /// Checks every parameter, naming the first bad one.
    pub fn validate(&self) -> Result<(), WetnessError> {
        let bad = |field: &'static str, reason: String| Err(WetnessError::InvalidParameter { field, reason });
        for (field, v) in [
            ("water_uptake", self.water_uptake),
            ("surface_water", self.surface_water),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(field, format!("must be >= 0, got {v}"));
            }
        }
        for (field, v) in [("young_ratio", self.young_ratio), ("shear_ratio", self.shear_ratio)] {
            if !(v.is_finite() && v > 0.0 && v <= 1.0) {
                return bad(field, format!("must be in (0, 1], got {v}"));
            }
        }
        if !(self.friction_ratio.is_finite() && self.friction_ratio >= 1.0) {
            return bad("friction_ratio", format!("must be >= 1, got {}", self.friction_ratio));
        }
        Ok(())
    }

    /// Mass multiplier `m(w) / m_dry = 1 + w (uptake + surface)` (dimensionless).
    pub fn mass_factor(&self, w: f64) -> Result<f64, WetnessError> {
        let w = check_wetness("wetness", w)?;
        Ok(1.0 + w * (self.water_uptake + self.surface_water))
    }

    /// Coulomb friction coefficient at wetness `w` of a contact whose dry coefficient is `dry` (dimensionless):
    /// `dry (1 + w (friction_ratio - 1))`. The one wetness law of friction, for the tool on hair and for hair on
    /// hair (`crate::hair_contact::HairContact::friction`) alike: both are keratin cuticle surfaces, and the
    /// ratio is measured on combing, where fibre-fibre friction dominates (docs/wetness.md).
    pub fn friction(&self, dry: f64, w: f64) -> Result<f64, WetnessError> {
        self.validate()?;
        let w = check_wetness("wetness", w)?;
        Ok(dry * (1.0 + w * (self.friction_ratio - 1.0)))
    }

    /// Effective material of `dry` (moduli in Pa, density in kg/m^3) at wetness `w`; the friction coefficient
    /// `dry_friction` (dimensionless) is scaled too, and `area` (m^2) gives the linear density.
    pub fn wet(&self, dry: &Material, dry_friction: f64, area: f64, w: f64) -> Result<WetMaterial, WetnessError> {
        self.validate()?;
        let w = check_wetness("wetness", w)?;
        let density = dry.density * (1.0 + w * (self.water_uptake + self.surface_water));
        Ok(WetMaterial {
            wetness: w,
            young_modulus: dry.young_modulus * self.young_ratio.powf(w),
            shear_modulus: dry.shear_modulus * self.shear_ratio.powf(w),
            density,
            linear_density: density * area,
            friction: self.friction(dry_friction, w)?,
        })
    }

    /// Effective material of a hair type preset at wetness `w`.
    pub fn hair(&self, hair: &HairType, w: f64) -> Result<WetMaterial, WetnessError> {
        let shape = |e: strand::StrandError| WetnessError::InvalidParameter {
            field: "hair_type",
            reason: e.to_string(),
        };
        let dry = hair.material().map_err(shape)?;
        let area = hair.section().map_err(shape)?.area();
        self.wet(&dry, hair.friction_coefficient(), area, w)
    }
}

/// Wetness state of a set of strands: one value in [0, 1] per strand and per segment (for guide strands, the
/// Super-Helix segments; values are uniform along a segment). Render strands take the value of their guide.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WetnessField {
    /// `values[strand][segment]`, dimensionless in [0, 1].
    pub values: Vec<Vec<f64>>,
}

impl WetnessField {
    /// A field of `segments[i]` values for strand i, all equal to `w` (checked).
    pub fn uniform(segments: &[usize], w: f64) -> Result<Self, WetnessError> {
        let w = check_wetness("wetness", w)?;
        Ok(Self {
            values: segments.iter().map(|&n| vec![w; n]).collect(),
        })
    }

    /// Dry everywhere.
    pub fn dry(segments: &[usize]) -> Self {
        Self {
            values: segments.iter().map(|&n| vec![0.0; n]).collect(),
        }
    }

    /// Sets one value, rejecting NaN and values outside [0, 1].
    pub fn set(&mut self, strand: usize, segment: usize, w: f64) -> Result<(), WetnessError> {
        let field = format!("wetness[{strand}][{segment}]");
        let w = check_wetness(&field, w)?;
        let slot = self
            .values
            .get_mut(strand)
            .and_then(|s| s.get_mut(segment))
            .ok_or_else(|| WetnessError::Shape(format!("{field} does not exist")))?;
        *slot = w;
        Ok(())
    }

    /// Mean wetness over all values (0 for an empty field).
    pub fn mean(&self) -> f64 {
        let (sum, n) = self
            .values
            .iter()
            .flatten()
            .fold((0.0, 0usize), |(s, n), w| (s + w, n + 1));
        if n == 0 {
            0.0
        } else {
            sum / n as f64
        }
    }

    /// Mean wetness of one strand (its segments are of equal length).
    pub fn strand_mean(&self, strand: usize) -> f64 {
        let v = &self.values[strand];
        if v.is_empty() {
            0.0
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    }

    /// Checks that the field has `segments[i]` values for strand i and every value is in [0, 1].
    pub fn check_shape(&self, segments: &[usize]) -> Result<(), WetnessError> {
        if self.values.len() != segments.len() {
            return Err(WetnessError::Shape(format!(
                "{} strands in the field, {} given",
                self.values.len(),
                segments.len()
            )));
        }
        for (i, (v, &n)) in self.values.iter().zip(segments).enumerate() {
            if v.len() != n {
                return Err(WetnessError::Shape(format!(
                    "strand {i}: {} values for {n} segments",
                    v.len()
                )));
            }
            for (j, &w) in v.iter().enumerate() {
                check_wetness(&format!("wetness[{i}][{j}]"), w)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dry_is_exactly_the_dry_material_and_wet_the_documented_values() {
        let m = WetnessModel::default();
        for h in HairType::ALL {
            let dry = h.material().unwrap();
            let area = h.section().unwrap().area();
            let d = m.hair(&h, 0.0).unwrap();
            assert_eq!(d.material(), dry, "{}", h.name);
            assert_eq!(d.friction, h.friction_coefficient());
            assert_eq!(d.linear_density, dry.density * area);
            let w = m.hair(&h, 1.0).unwrap();
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
            assert!(rel(w.young_modulus, 0.4 * dry.young_modulus) < 1e-15);
            assert!(rel(w.shear_modulus, 0.1 * dry.shear_modulus) < 1e-15);
            assert!(rel(w.density, 1.8 * dry.density) < 1e-15);
            assert!(rel(w.friction, 1.5 * h.friction_coefficient()) < 1e-15);
        }
    }

    #[test]
    fn monotonic_in_between() {
        let m = WetnessModel::default();
        let h = HairType::H1;
        let mut last = m.hair(&h, 0.0).unwrap();
        for i in 1..=100 {
            let c = m.hair(&h, i as f64 / 100.0).unwrap();
            assert!(c.young_modulus < last.young_modulus);
            assert!(c.shear_modulus < last.shear_modulus);
            assert!(c.density > last.density && c.linear_density > last.linear_density);
            assert!(c.friction > last.friction);
            last = c;
        }
    }

    #[test]
    fn bad_wetness_is_rejected_with_its_name() {
        let m = WetnessModel::default();
        for w in [f64::NAN, -0.01, 1.01, f64::INFINITY] {
            let e = m.hair(&HairType::H1, w).unwrap_err();
            assert!(e.to_string().contains("wetness"), "{e}");
        }
        let mut f = WetnessField::dry(&[3, 2]);
        assert!(f.set(1, 1, f64::NAN).unwrap_err().to_string().contains("wetness[1][1]"));
        assert!(f.set(2, 0, 0.5).is_err());
        f.set(1, 1, 1.0).unwrap();
        assert_eq!(f.mean(), 0.2);
        let bad = WetnessModel {
            shear_ratio: 0.0,
            ..Default::default()
        };
        assert!(bad
            .hair(&HairType::H1, 0.5)
            .unwrap_err()
            .to_string()
            .contains("shear_ratio"));
        let bad = WetnessModel {
            friction_ratio: f64::NAN,
            ..Default::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("friction_ratio"));
    }
}
