//! Hair-type presets: the four fibres of the paper's Table 1 and typical Asian, Caucasian and African hair.
//!
//! Sources:
//! - Table 1 of Bonanni, Montagnol, Magnenat-Thalmann (2008), itself from Wortmann and Schwan-Jonczyk (2006),
//!   "Investigating hair properties relevant for hair handle": major-axis diameter, ellipticity, bending
//!   stiffness and single-fibre frictional force of hair types H1, H2, GA1 and GC3. The bending stiffness is
//!   printed as "10^-9 Nm"; it is the flexural rigidity E I in N m^2 (H1: 7.59e-9 N m^2). The Young modulus
//!   of a preset is E = EI / I_soft of its own section, so the preset reproduces the measured EI exactly.
//! - Ethnic hair: ellipticity Asian 1.2, Caucasian 1.4, African about 1.9 and major-axis diameters from
//!   Franbourg et al. (2003), "Current research on ethnic hair", J. Am. Acad. Dermatol. 48(6) S115-119;
//!   curl radii from Loussouarn et al. (2007), "Worldwide diversity of hair curliness", Int. J. Dermatol. 46
//!   (natural curl radius 0.6 to 16 cm, mean 4.4 cm; straight Asian hair beyond that range).
//!   These are typical values of wide distributions, not measurements of one fibre.
//! - Moduli not in those sources: E = 3.9 GPa, G = 0.9 GPa, density 1300 kg/m^3 (Robbins 2002).

use crate::error::Result;
use crate::material::Material;
use crate::section::CrossSection;
use serde::{Deserialize, Serialize};

/// A named hair type with its fibre geometry, stiffness, friction and natural curl.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HairType {
    /// Short name as used in spec files (`"H1"`, `"caucasian"`, ...).
    pub name: &'static str,
    /// Major-axis diameter, m.
    pub major_diameter: f64,
    /// Ellipticity, major/minor axis ratio (>= 1).
    pub ellipticity: f64,
    /// Flexural rigidity about the major axis E I_soft, N m^2.
    pub bending_stiffness: f64,
    /// Shear modulus G, Pa.
    pub shear_modulus: f64,
    /// Density, kg/m^3.
    pub density: f64,
    /// Single-fibre frictional force measured by Wortmann and Schwan-Jonczyk, N (None where not reported).
    pub friction_force: Option<f64>,
    /// Natural curl radius, m (None: straight hair).
    pub curl_radius: Option<f64>,
    /// Natural curl pitch (length of one helix turn along its axis), m (None: straight hair).
    pub curl_pitch: Option<f64>,
}

const G_HAIR: f64 = 0.9e9;
const RHO_HAIR: f64 = 1300.0;
const E_HAIR: f64 = 3.9e9;

/// Flexural rigidity E I_soft of a section with the default Young modulus, N m^2.
const fn ei_default(d: f64, e: f64) -> f64 {
    let a = d / 2.0;
    let b = a / e;
    E_HAIR * std::f64::consts::PI * a * b * b * b / 4.0
}

impl HairType {
    /// H1 of Table 1 (41 % positive handle ratings): 93.1 um, ellipticity 1.36, EI 7.59e-9 N m^2, 0.64 cN.
    pub const H1: HairType = HairType {
        name: "H1",
        major_diameter: 93.1e-6,
        ellipticity: 1.36,
        bending_stiffness: 7.59e-9,
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: Some(0.64e-2),
        curl_radius: None,
        curl_pitch: None,
    };
    /// H2 of Table 1 (69 %): 96.1 um, ellipticity 1.33, EI 9.25e-9 N m^2, friction not reported.
    pub const H2: HairType = HairType {
        name: "H2",
        major_diameter: 96.1e-6,
        ellipticity: 1.33,
        bending_stiffness: 9.25e-9,
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: None,
        curl_radius: None,
        curl_pitch: None,
    };
    /// GA1 of Table 1 (94 %): 89.5 um, ellipticity 1.45, EI 5.23e-9 N m^2, 0.65 cN.
    pub const GA1: HairType = HairType {
        name: "GA1",
        major_diameter: 89.5e-6,
        ellipticity: 1.45,
        bending_stiffness: 5.23e-9,
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: Some(0.65e-2),
        curl_radius: None,
        curl_pitch: None,
    };
    /// GC3 of Table 1 (94 %): 89.3 um, ellipticity 1.42, EI 5.66e-9 N m^2, 0.79 cN.
    pub const GC3: HairType = HairType {
        name: "GC3",
        major_diameter: 89.3e-6,
        ellipticity: 1.42,
        bending_stiffness: 5.66e-9,
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: Some(0.79e-2),
        curl_radius: None,
        curl_pitch: None,
    };
    /// Typical Asian hair: thick (100 um), nearly round (1.2), straight.
    pub const ASIAN: HairType = HairType {
        name: "asian",
        major_diameter: 100e-6,
        ellipticity: 1.2,
        bending_stiffness: ei_default(100e-6, 1.2),
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: None,
        curl_radius: None,
        curl_pitch: None,
    };
    /// Typical Caucasian hair: 80 um, ellipticity 1.4, wavy with the mean natural curl radius 4.4 cm.
    pub const CAUCASIAN: HairType = HairType {
        name: "caucasian",
        major_diameter: 80e-6,
        ellipticity: 1.4,
        bending_stiffness: ei_default(80e-6, 1.4),
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: None,
        curl_radius: Some(0.044),
        curl_pitch: Some(0.15),
    };
    /// Typical African hair: 85 um, ellipticity 1.9, tightly curled (curl radius 0.6 cm, pitch 1 cm).
    pub const AFRICAN: HairType = HairType {
        name: "african",
        major_diameter: 85e-6,
        ellipticity: 1.9,
        bending_stiffness: ei_default(85e-6, 1.9),
        shear_modulus: G_HAIR,
        density: RHO_HAIR,
        friction_force: None,
        curl_radius: Some(0.006),
        curl_pitch: Some(0.01),
    };

    /// Every preset, Table 1 first.
    pub const ALL: [HairType; 7] = [
        Self::H1,
        Self::H2,
        Self::GA1,
        Self::GC3,
        Self::ASIAN,
        Self::CAUCASIAN,
        Self::AFRICAN,
    ];

    /// Looks a preset up by name, ignoring case (`"h1"`, `"GC3"`, `"African"`).
    pub fn by_name(name: &str) -> Option<HairType> {
        Self::ALL.into_iter().find(|h| h.name.eq_ignore_ascii_case(name))
    }

    /// Where the preset's figures come from (a short citation).
    pub fn source(&self) -> &'static str {
        match self.name {
            "H1" | "H2" | "GA1" | "GC3" => {
                "Table 1 of Bonanni, Montagnol, Magnenat-Thalmann (2008), from Wortmann and Schwan-Jonczyk (2006), \
                 \"Investigating hair properties relevant for hair handle\"; G and density from Robbins (2002)"
            }
            _ => {
                "typical values: Franbourg et al. (2003), \"Current research on ethnic hair\" (diameter, ellipticity); \
                 Loussouarn et al. (2007), \"Worldwide diversity of hair curliness\" (curl); E, G and density from Robbins (2002)"
            }
        }
    }

    /// Coulomb friction coefficient of the fibre against a tool (dimensionless). The single-fibre frictional
    /// forces of Table 1 (0.64-0.79 cN) come from a test whose normal load the paper does not give, so they are
    /// used as relative values: mu = 0.2 x (friction force / 0.7 cN), 0.2 being a typical dry hair-on-comb
    /// coefficient (Robbins 2002 reports 0.1-0.3). Types without a measurement get 0.2.
    pub fn friction_coefficient(&self) -> f64 {
        match self.friction_force {
            Some(f) => 0.2 * f / 0.7e-2,
            None => 0.2,
        }
    }

    /// The fibre's elliptical cross-section.
    pub fn section(&self) -> Result<CrossSection> {
        CrossSection::from_diameter(self.major_diameter, self.ellipticity)
    }

    /// The fibre's material; E is chosen so that E I_soft equals the preset's bending stiffness.
    pub fn material(&self) -> Result<Material> {
        let e = self.bending_stiffness / self.section()?.i_soft();
        Ok(Material { young_modulus: e, shear_modulus: self.shear_modulus, density: self.density })
    }

    /// Rest (twist, bend) in rad/m that give the natural curl as a helix of the preset's radius and pitch:
    /// with c = pitch / (2 pi), bend = R / (R^2 + c^2) and twist = c / (R^2 + c^2). Straight hair: (0, 0).
    pub fn rest_curvature(&self) -> (f64, f64) {
        match (self.curl_radius, self.curl_pitch) {
            (Some(r), Some(p)) => {
                let c = p / (2.0 * std::f64::consts::PI);
                let d = r * r + c * c;
                (c / d, r / d)
            }
            _ => (0.0, 0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_reproduce_table_1_bending_stiffness() {
        for h in HairType::ALL {
            let ei = h.material().unwrap().young_modulus * h.section().unwrap().i_soft();
            assert!((ei - h.bending_stiffness).abs() < 1e-12 * h.bending_stiffness, "{}", h.name);
        }
        // Effective Young moduli of the Table 1 fibres fall in the measured range of hair (2-7 GPa).
        for h in [HairType::H1, HairType::H2, HairType::GA1, HairType::GC3] {
            let e = h.material().unwrap().young_modulus;
            assert!((2e9..7e9).contains(&e), "{}: E = {e}", h.name);
        }
    }

    #[test]
    fn curl_gives_the_helix_radius_back() {
        let h = HairType::AFRICAN;
        let (tau, kappa) = h.rest_curvature();
        let w2 = tau * tau + kappa * kappa;
        assert!((kappa / w2 - 0.006).abs() < 1e-12);
        assert!((2.0 * std::f64::consts::PI * tau / w2 - 0.01).abs() < 1e-12);
        assert_eq!(HairType::ASIAN.rest_curvature(), (0.0, 0.0));
    }

    #[test]
    fn lookup_by_name() {
        assert_eq!(HairType::by_name("gc3").unwrap().name, "GC3");
        assert!(HairType::by_name("nonexistent").is_none());
    }
}
