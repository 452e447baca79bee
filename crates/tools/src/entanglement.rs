//! The drag of a comb's tooth through a wisp of entangled fibres (the tress's sub-wisp mechanics).
//!
//! A simulated strand stands for a wisp of many fibres of radius `r_f`, packed in a round section of radius
//! `r_w` (`crate::hair_contact::HairContact`). The fibres of a real tress are not parallel: each is held
//! sideways by its neighbours at entanglement points (crossings) about every `span` metres. A tooth of radius
//! `r_t` passing along the fibres *through* a wisp parts the fibres in its path: each is bent around the tooth
//! between two entanglement points, and presses on the tooth with
//!
//! `N_f = 48 E I delta / span^3 + w 4 pi gamma sqrt(r_f r_t)`   (N, per parted fibre)
//!
//! - bending: a span of length `span` held at its ends and deflected by `delta` in its middle (a simply
//!   supported beam under a central load, `48 E I / L^3`); `delta = (r_t + r_f) / 2`, the mean deflection of
//!   the fibres in the tooth's path (a fibre `x` off the tooth's axis is pushed `r_t + r_f - |x|` aside);
//!   `E I` is the fibre's flexural rigidity at its wetness (wet fibres are softer, `crate::wetness`);
//! - capillary adhesion of wet fibres: the water bridge where a wet fibre crosses the tooth pulls the two
//!   together with `4 pi gamma sqrt(r_f r_t)` (the meniscus between two crossed cylinders in contact, as
//!   between a sphere of radius `sqrt(r_f r_t)` and a plane, complete wetting; Israelachvili, *Intermolecular
//!   and Surface Forces*, 3rd ed., ch. 17), `gamma` the surface tension of water, scaled by the wetness `w`
//!   in [0, 1].
//!
//! Within half a span of the fibre's tip there is no entanglement point below the tooth: the bending share
//! falls linearly to 0 at the tip (the end slips aside).
//!
//! The tooth slides on the parted fibres with the tool-hair Coulomb coefficient `mu`: it feels a drag up to
//! `mu N_f` per parted fibre, against the relative motion. Of a wisp whose centreline is `d` from the tooth's
//! axis, the parted share is the share of the wisp's section within `r_t + r_f` of the axis
//! ([`parted_share`]): it goes smoothly to 0 as the wisp leaves the tooth, so the force has no steps. The
//! drag is a Coulomb force (rate independent), as combing forces of tresses are at 0.1-0.5 m/s.
//!
//! Calibration: `span` is the one number set from a measurement (the dry combing force of a 4.75 g tress,
//! see [`Entanglement::span`]); stiffness, friction, wetness and the tress's size then set every other
//! hair type's and the wet tresses' forces.

use strand::StrandError;

/// The entanglement of the fibres in a wisp and the capillary adhesion of wet fibres: what a tooth passing
/// through a wisp pulls against (see the module documentation for the law).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entanglement {
    /// Free length of a fibre between the entanglement points that hold it sideways in the tress, m.
    /// Default 6.6 mm: calibrated on the H1 tress scenario (`examples/scenarios/comb-h1.toml`: 4.75 g, 24 wisps of
    /// 20 cm, combed at 0.25 m/s) against the measured dry force (J. Soc. Cosmet. Chem. 24, 1973, Table I:
    /// 12-13 gf, i.e. 0.12 N; here 0.089 N peak, 0.066 N median, chosen at the low side so that the stiffest
    /// type, H2, stays inside the acceptance's 0.24 N); the bending share goes as `span^-3`. A few millimetres
    /// between crossings is what a combed, nearly aligned tress shows (fibres cross their neighbours at small
    /// angles).
    pub span: f64,
    /// Surface tension of the water on wet fibres, N/m. Default 0.072 (water at 25 C).
    pub surface_tension: f64,
}

impl Default for Entanglement {
    fn default() -> Self {
        Self { span: 6.6e-3, surface_tension: 0.072 }
    }
}

impl Entanglement {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), StrandError> {
        let bad = |field: &'static str, reason: String| Err(StrandError::InvalidParameter { field, reason });
        if !(self.span.is_finite() && self.span > 0.0) {
            return bad("entanglement.span", format!("must be > 0 m, got {}", self.span));
        }
        if !(self.surface_tension.is_finite() && self.surface_tension >= 0.0) {
            return bad("entanglement.surface_tension", format!("must be >= 0 N/m, got {}", self.surface_tension));
        }
        Ok(())
    }

    /// Normal load one parted fibre puts on a tooth, N: `48 E I delta / span^3 + w 4 pi gamma sqrt(r_f r_t)`, for a fibre of
    /// flexural rigidity `ei` (N m^2) and radius `fibre_radius` (m), a tooth of radius `tooth_radius` (m) and
    /// wetness `wetness` (0..1; clamped), `free_length` (m) from the tooth to the fibre's tip. Within half a span
    /// of the tip the fibre is not held below the tooth (its end slips aside): the bending share falls linearly
    /// to 0 at the tip, `min(1, 2 free_length / span)`.
    pub fn parting_load(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64, free_length: f64) -> f64 {
        let delta = 0.5 * (tooth_radius + fibre_radius);
        let bridge = 4.0 * std::f64::consts::PI * self.surface_tension * (fibre_radius * tooth_radius).sqrt();
        let held = (2.0 * free_length.max(0.0) / self.span).min(1.0);
        held * 48.0 * ei * delta / self.span.powi(3) + wetness.clamp(0.0, 1.0) * bridge
    }

    /// Lateral stiffness of one fibre of flexural rigidity `ei` (N m^2) pressed at a point, N/m: held sideways by
    /// its neighbours every `span`, it bends over one span as a simply supported beam under a central load,
    /// `48 E I / span^3`. The bending share of [`Entanglement::parting_load`] is this times the deflection; the live
    /// session takes it as the stiffest any constraint on a simulated fibre may be (`ConstraintOptions::max_stiffness`):
    /// a tooth or a neighbour pressing a fibre meets that span's bending, not the rigid segments of the model beyond.
    /// (`parting_load` keeps its own order of the operations: the tress scenarios' forces are calibrated on it
    /// and move at round-off; `stiffness * delta` instead lowered H2's wet/dry peak ratio from above 4 to 3.94.)
    pub fn fibre_stiffness(&self, ei: f64) -> f64 {
        48.0 * ei / self.span.powi(3)
    }
}

/// Share (0..1) of a wisp's fibres, uniform over a disc of radius `wisp_radius` (m), whose centres lie within
/// `half_width` (m) of a line `distance` (m) from the disc's centre: the fibres in a tooth's path (half width
/// `r_t + r_f`). Exactly 1 for a wisp no wider than the path centred on it, 0 beyond `wisp_radius + half_width`.
pub fn parted_share(distance: f64, wisp_radius: f64, half_width: f64) -> f64 {
    let r = wisp_radius.max(1e-300);
    // Area of the disc on the side x' <= x of a chord at x (m^2).
    let below = |x: f64| {
        let x = x.clamp(-r, r);
        r * r * (std::f64::consts::FRAC_PI_2 + (x / r).asin()) + x * (r * r - x * x).max(0.0).sqrt()
    };
    let d = distance.abs();
    ((below(d + half_width) - below(d - half_width)) / (std::f64::consts::PI * r * r)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parted_share_is_the_area_of_the_band() {
        // Against a numerical integration of the disc (a 2000 x 2000 grid, 1e-3 absolute): a band through the
        // centre, off centre, past the edge, and the limits (1 for a band wider than the wisp, 0 beyond reach).
        let (r, b) = (0.8e-3, 0.65e-3);
        for d in [0.0, 0.3e-3, 0.9e-3, 1.4e-3, 1.5e-3] {
            let n = 2000;
            let mut inside = 0usize;
            let mut total = 0usize;
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = (-r + 2.0 * r * (i as f64 + 0.5) / n as f64, -r + 2.0 * r * (j as f64 + 0.5) / n as f64);
                    if x * x + y * y <= r * r {
                        total += 1;
                        if (x - d).abs() <= b {
                            inside += 1;
                        }
                    }
                }
            }
            let want = inside as f64 / total as f64;
            let got = parted_share(d, r, b);
            assert!((got - want).abs() < 1e-3, "d = {d}: {got} vs {want}");
        }
        assert!((parted_share(0.0, 0.5e-3, 0.6e-3) - 1.0).abs() < 1e-12);
        assert_eq!(parted_share(1.46e-3, 0.8e-3, 0.65e-3), 0.0);
    }

    #[test]
    fn the_parting_load_is_the_beam_and_the_menisci() {
        // A span of 8 mm of H1 fibre (EI 7.59e-9 N m^2) around a 0.6 mm tooth (fibre radius 46.55 um): the central
        // load of a simply supported beam deflected by (r_t + r_f) / 2, 48 EI delta / L^3 = 0.230 mN; wet, plus
        // the crossed-cylinder meniscus 4 pi gamma sqrt(r_f r_t) = 0.151 mN (figures by hand, 1e-3 relative).
        let e = Entanglement { span: 8e-3, ..Default::default() };
        let (ei, rf, rt) = (7.59e-9, 46.55e-6, 0.6e-3);
        let beam = e.parting_load(ei, rf, rt, 0.0, 0.1);
        assert!((beam - 0.2300e-3).abs() < 1e-3 * 0.23e-3, "{beam}");
        let wet = e.parting_load(0.4 * ei, rf, rt, 1.0, 0.1);
        assert!((wet - (0.4 * beam + 0.1511e-3)).abs() < 1e-3 * 0.15e-3, "{wet}");
        // At the tip only the meniscus is left; half a span from it, half the beam.
        assert!((e.parting_load(ei, rf, rt, 1.0, 0.0) - 0.1511e-3).abs() < 1e-3 * 0.15e-3);
        assert!((e.parting_load(ei, rf, rt, 0.0, 0.25 * e.span) - 0.5 * beam).abs() < 1e-12 * beam);
        // The fibre's lateral stiffness over one span: 48 EI / L^3 = 0.7116 N/m (by hand), the beam's load per metre of deflection.
        assert!((e.fibre_stiffness(ei) - 0.71156).abs() < 1e-4, "{}", e.fibre_stiffness(ei));
        assert!((e.fibre_stiffness(ei) * 0.5 * (rf + rt) - beam).abs() < 1e-12 * beam);
        assert!(Entanglement { span: 0.0, ..e }.validate().unwrap_err().to_string().contains("entanglement.span"));
        assert!(Entanglement { surface_tension: f64::NAN, ..e }.validate().is_err());
    }
}
