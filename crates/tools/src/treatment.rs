//! The surface treatment of the hair (virgin, conditioned, bleached once or twice) as a physical input: what
//! each does to the fibre's surface, as friction coefficients of fibre on fibre and of a tool on the fibre, dry
//! and wet, and as the receding contact angle of water on it (its wettability, [`Treatment::wettability`]).
//! Sources, and where a figure is missing and how it was set: `docs/treatment.md`.
//!
//! The model's coefficients keep their own homes (the tool's: `strand::HairType::friction_coefficient`; fibre on
//! fibre: `crate::hair_contact::HairContact::friction`; the rise with wetness: `crate::wetness::WetnessModel`).
//! A treatment multiplies them by its coefficient over the virgin fibre's at the same wetness
//! ([`Treatment::friction_factor`]): virgin hair is exactly the model without a treatment (factor 1, bit-equal).
//! [`Treatment::friction`] is the one friction law with wetness and treatment, for the tress scenarios and the
//! live session alike.

use crate::wetness::{check_wetness, WetnessError, WetnessModel};

/// Which pair of surfaces slides: two fibres, or a tool (comb, brush) on a fibre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Contact {
    /// Fibre on fibre (hair-hair contact, the wisps' friction, the body contact of a strand lying on hair).
    Fibre,
    /// A tool's surface on a fibre (the comb's teeth, the brush's bristles).
    Tool,
}

/// Friction coefficients of one treatment's fibre surface (dimensionless): fibre on fibre and a tool on the
/// fibre, in equilibrium with ambient air (dry, wetness 0) and soaked (wetness 1). Sources in `docs/treatment.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceFriction {
    /// Fibre on fibre, dry.
    pub fibre_dry: f64,
    /// Fibre on fibre, wet.
    pub fibre_wet: f64,
    /// Tool on fibre, dry.
    pub tool_dry: f64,
    /// Tool on fibre, wet.
    pub tool_wet: f64,
}

/// A hair surface treatment. Default [`Treatment::Virgin`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Treatment {
    /// Untreated hair: the cuticle with its covalently bound lipid layer (18-MEA).
    #[default]
    Virgin,
    /// Virgin hair after a rinse-off conditioner (cationic surfactant and fatty alcohol deposited on the cuticle).
    Conditioned,
    /// Bleached once (alkaline hydrogen peroxide): the lipid layer partly removed, a hydrophilic cuticle.
    Bleached,
    /// Bleached twice.
    BleachedTwice,
}

/// Wet rise of the friction of a virgin fibre's surface (wet over dry, dimensionless), the single-fibre
/// figure the treatments' wet coefficients are built on: friction is higher in water (Nikogeorgos et al. 2010);
/// 1.5, the low end of the single-fibre wet/dry ratios of 1.5-2 quoted in `docs/wetness.md` (see
/// `docs/treatment.md` for why no better figure is used). The same figure as `WetnessModel::friction_ratio`'s
/// default (a test holds them equal).
const VIRGIN_WET_RISE: f64 = 1.5;

impl Treatment {
    /// Every treatment, in the order of the viewer's selector.
    pub const ALL: [Treatment; 4] = [Treatment::Virgin, Treatment::Conditioned, Treatment::Bleached, Treatment::BleachedTwice];

    /// The name used in scenario files and the viewer: "virgin", "conditioned", "bleached", "bleached-twice".
    pub fn name(self) -> &'static str {
        match self {
            Treatment::Virgin => "virgin",
            Treatment::Conditioned => "conditioned",
            Treatment::Bleached => "bleached",
            Treatment::BleachedTwice => "bleached-twice",
        }
    }

    /// The treatment's wire id (viewer protocol, records): its index in [`Treatment::ALL`].
    pub fn id(self) -> u8 {
        Self::ALL.iter().position(|&t| t == self).expect("every treatment is in ALL") as u8
    }

    /// The treatment of wire id `id` ([`Treatment::id`]), if there is one.
    pub fn from_id(id: u8) -> Option<Self> {
        Self::ALL.get(id as usize).copied()
    }

    /// The treatment named `name` (as [`Treatment::name`]), or an error listing the names.
    pub fn by_name(name: &str) -> Result<Self, String> {
        Self::ALL.into_iter().find(|t| t.name() == name).ok_or_else(|| {
            format!("unknown treatment {name:?} (one of {})", Self::ALL.map(|t| format!("{:?}", t.name())).join(", "))
        })
    }

    /// The treatment's surface friction (see `docs/treatment.md` for each figure's source):
    /// - virgin: fibre on fibre 0.13 dry (Fair and Gupta 1988, twist method, brown and blond virgin hair
    ///   0.130 and 0.132), tool on fibre 0.2 dry (`strand::HairType::friction_coefficient`'s reference);
    ///   wet, both times 1.5 ([`VIRGIN_WET_RISE`]);
    /// - conditioned: dry 0.8 of virgin's (0.104 and 0.16; [`CONDITIONED_DRY`]), wet no higher than dry (the
    ///   conditioner film lubricates in water: recalled, see `docs/treatment.md`);
    /// - bleached: fibre on fibre 0.195 dry (Fair and Gupta: 0.196 and 0.194), 1.5 times virgin's, the same
    ///   factor on the tool and wet;
    /// - bleached twice: one more bleach's increment, 0.26 (2 times virgin's; no fibre measurement found).
    pub fn surface(self) -> SurfaceFriction {
        let virgin = SurfaceFriction { fibre_dry: 0.13, fibre_wet: 0.13 * VIRGIN_WET_RISE, tool_dry: 0.2, tool_wet: 0.2 * VIRGIN_WET_RISE };
        let scaled = |dry: f64, wet: f64| SurfaceFriction { fibre_dry: virgin.fibre_dry * dry, fibre_wet: virgin.fibre_wet * wet, tool_dry: virgin.tool_dry * dry, tool_wet: virgin.tool_wet * wet };
        match self {
            Treatment::Virgin => virgin,
            // Dry: the read probe-on-fibre ratio; wet: the conditioned surface's dry coefficient (no rise in water).
            Treatment::Conditioned => scaled(CONDITIONED_DRY, CONDITIONED_DRY / VIRGIN_WET_RISE),
            Treatment::Bleached => scaled(1.5, 1.5),
            Treatment::BleachedTwice => scaled(2.0, 2.0),
        }
    }

    /// This treatment's coefficient of `contact` over the virgin fibre's at wetness `w` (in [0, 1], clamped;
    /// NaN counts as 0), dimensionless: the dry and the wet ratios interpolated linearly in `w`. Exactly 1 for
    /// virgin hair.
    pub fn friction_factor(self, contact: Contact, w: f64) -> f64 {
        if self == Treatment::Virgin {
            return 1.0;
        }
        let w = if w.is_finite() { w.clamp(0.0, 1.0) } else { 0.0 };
        let (t, v) = (self.surface(), Treatment::Virgin.surface());
        let (dry, wet) = match contact {
            Contact::Fibre => (t.fibre_dry / v.fibre_dry, t.fibre_wet / v.fibre_wet),
            Contact::Tool => (t.tool_dry / v.tool_dry, t.tool_wet / v.tool_wet),
        };
        dry + w * (wet - dry)
    }

    /// The one friction law with wetness and treatment: the Coulomb coefficient of `contact` at wetness `w` for
    /// a contact whose dry coefficient on virgin hair is `dry` (dimensionless): the wetness model's
    /// `model.friction(dry, w)` times [`Treatment::friction_factor`]. Bad wetness is named.
    pub fn friction(self, model: &WetnessModel, contact: Contact, dry: f64, w: f64) -> Result<f64, WetnessError> {
        let w = check_wetness("wetness", w)?;
        Ok(model.friction(dry, w)? * self.friction_factor(contact, w))
    }
}

/// Conditioned over virgin hair's dry friction (dimensionless), a tool on the fibre and (for want of a figure) fibre
/// on fibre: 0.8, the median of the three ratios read, 0.77, 0.80 and 0.93 (a probe slid over single dry fibres, Kato
/// Tech KES-SE, shampooed hair against the same after a rinse-off treatment or conditioner; a testing laboratory's
/// published results, `docs/treatment.md`, "Conditioned hair: figures read"). Not set from a combing figure.
pub const CONDITIONED_DRY: f64 = 0.8;

/// Receding contact angle of water on untreated (virgin) hair, rad: 60.0 +- 9.0 degrees (Tanamachi et al., J.
/// Cosmet. Sci. 61, 147-160 (2010), Table III, Wilhelmy method, with the scales). The 18-MEA lipid layer keeps
/// virgin hair's receding angle high.
const VIRGIN_RECEDING_ANGLE: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// Receding contact angle of water on hair whose 18-MEA layer is removed, rad: 3.2 +- 5.5 degrees (Tanamachi et
/// al. 2010, Table III: 18-MEA removed by potassium t-butoxide; the receding angle falls linearly with the
/// surface's 18-MEA, to this at none).
const STRIPPED_RECEDING_ANGLE: f64 = 3.2 * std::f64::consts::PI / 180.0;

impl Treatment {
    /// Receding contact angle of water on the fibre's surface, rad (sources in `docs/treatment.md`):
    /// - virgin and conditioned: 60 degrees (Tanamachi et al. 2010, untreated hair; no figure read for a
    ///   conditioned virgin fibre, whose cationic film is hydrophobic too: taken as virgin's);
    /// - bleached once or twice: 3.2 degrees, the fibre without its 18-MEA layer (Tanamachi et al. 2010), which
    ///   alkaline peroxide removes (`docs/treatment.md`: one bleach may leave some of it, Nikogeorgos et al. 2010,
    ///   so this is the bleached-once fibre's lower bound).
    ///
    /// The receding angle is the one of a meniscus pulled off the surface, as when a comb parts wet fibres.
    pub fn receding_contact_angle(self) -> f64 {
        match self {
            Treatment::Virgin | Treatment::Conditioned => VIRGIN_RECEDING_ANGLE,
            Treatment::Bleached | Treatment::BleachedTwice => STRIPPED_RECEDING_ANGLE,
        }
    }

    /// The capillary forces of water on this treatment's fibre surface over the virgin fibre's (dimensionless):
    /// `cos theta_r / cos theta_r(virgin)` of the receding contact angles ([`Treatment::receding_contact_angle`]),
    /// the capillary pull of a meniscus on a surface going as the cosine of its contact angle (Young; Israelachvili,
    /// *Intermolecular and Surface Forces*, 3rd ed., ch. 17). Exactly 1 for virgin (and conditioned) hair; 2.0 for
    /// bleached hair. `tools::entanglement::Entanglement::wettability` takes it.
    pub fn wettability(self) -> f64 {
        if self.receding_contact_angle() == VIRGIN_RECEDING_ANGLE {
            return 1.0;
        }
        self.receding_contact_angle().cos() / VIRGIN_RECEDING_ANGLE.cos()
    }
}

impl std::fmt::Display for Treatment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn virgin_is_exactly_the_untreated_model() {
        let m = WetnessModel::default();
        for w in [0.0, 0.3, 1.0] {
            for c in [Contact::Fibre, Contact::Tool] {
                assert_eq!(Treatment::Virgin.friction_factor(c, w), 1.0);
                assert_eq!(Treatment::Virgin.friction(&m, c, 0.25, w).unwrap(), m.friction(0.25, w).unwrap());
            }
        }
    }

    #[test]
    fn the_treatments_take_their_sources_figures() {
        // Fair and Gupta 1988 (twist method): virgin 0.13, bleached once 0.195 fibre on fibre, dry.
        let v = Treatment::Virgin.surface();
        let b = Treatment::Bleached.surface();
        assert!((v.fibre_dry - 0.13).abs() < 1e-12 && (b.fibre_dry - 0.195).abs() < 1e-12);
        assert!((Treatment::BleachedTwice.surface().fibre_dry - 0.26).abs() < 1e-12);
        // Conditioned: the read 0.8 of virgin's dry; wet no higher than its own dry coefficient.
        let c = Treatment::Conditioned.surface();
        assert!((c.fibre_dry / v.fibre_dry - 0.8).abs() < 1e-12 && (c.tool_dry / v.tool_dry - 0.8).abs() < 1e-12);
        assert!((c.fibre_wet - c.fibre_dry).abs() < 1e-12 && (c.tool_wet - c.tool_dry).abs() < 1e-12);
        // Wet is rougher than dry for every surface but the conditioned one.
        for t in [Treatment::Virgin, Treatment::Bleached, Treatment::BleachedTwice] {
            let s = t.surface();
            assert!(s.fibre_wet > s.fibre_dry && s.tool_wet > s.tool_dry, "{t}");
        }
        // The factors: dry at 0, wet at 1, linear between.
        let f = |t: Treatment, w| t.friction_factor(Contact::Fibre, w);
        assert!((f(Treatment::Bleached, 0.0) - 1.5).abs() < 1e-12 && (f(Treatment::Bleached, 1.0) - 1.5).abs() < 1e-12);
        // Conditioned wet: 0.8 over virgin's wet rise (1.5).
        assert!((f(Treatment::Conditioned, 0.0) - 0.8).abs() < 1e-12);
        assert!((f(Treatment::Conditioned, 1.0) - 0.8 / 1.5).abs() < 1e-12);
        assert!((f(Treatment::Conditioned, 0.5) - 0.5 * (0.8 + 0.8 / 1.5)).abs() < 1e-12);
        // Ordering: conditioned < virgin < bleached < bleached twice, dry and wet, both contacts.
        for w in [0.0, 1.0] {
            for c in [Contact::Fibre, Contact::Tool] {
                let order: Vec<f64> = [Treatment::Conditioned, Treatment::Virgin, Treatment::Bleached, Treatment::BleachedTwice].iter().map(|t| t.friction_factor(c, w)).collect();
                assert!(order.windows(2).all(|p| p[0] < p[1]), "{order:?}");
            }
        }
    }

    #[test]
    fn the_wettability_is_the_cosine_of_the_receding_angle_over_virgins() {
        // Tanamachi et al. 2010, Table III: 60.0 degrees untreated, 3.2 degrees without 18-MEA; cos 60 = 0.5, cos 3.2 =
        // 0.99844 (by hand): bleached hair's capillary forces 1.9969 times virgin's.
        assert_eq!(Treatment::Virgin.wettability(), 1.0);
        assert_eq!(Treatment::Conditioned.wettability(), 1.0);
        assert!((Treatment::Virgin.receding_contact_angle().to_degrees() - 60.0).abs() < 1e-12);
        for t in [Treatment::Bleached, Treatment::BleachedTwice] {
            assert!((t.receding_contact_angle().to_degrees() - 3.2).abs() < 1e-12);
            assert!((t.wettability() - 1.99688).abs() < 1e-5, "{}", t.wettability());
        }
    }

    #[test]
    fn the_virgin_wet_rise_is_the_wetness_models() {
        assert_eq!(VIRGIN_WET_RISE, WetnessModel::default().friction_ratio);
    }

    #[test]
    fn names_round_trip_and_bad_ones_are_named() {
        for t in Treatment::ALL {
            assert_eq!(Treatment::by_name(t.name()).unwrap(), t);
            let toml_text = format!("t = {:?}", t.name());
            #[derive(serde::Deserialize)]
            struct Wrap {
                t: Treatment,
            }
            assert_eq!(toml::from_str::<Wrap>(&toml_text).unwrap().t, t);
        }
        let e = Treatment::by_name("permed").unwrap_err();
        assert!(e.contains("permed") && e.contains("bleached-twice"), "{e}");
        assert!(Treatment::Bleached.friction(&WetnessModel::default(), Contact::Tool, 0.2, f64::NAN).is_err());
    }
}
