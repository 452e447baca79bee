//! The drag of a comb's tooth through a wisp of entangled fibres (the tress's sub-wisp mechanics).
//!
//! A simulated strand stands for a wisp of many fibres of radius `r_f`, packed in a round section of radius
//! `r_w` (`crate::hair_contact::HairContact`). The fibres of a real tress are not parallel: each is held
//! sideways by its neighbours at entanglement points (crossings) about every `span` metres. A tooth of radius
//! `r_t` passing along the fibres *through* a wisp parts the fibres in its path: each is bent around the tooth
//! between two entanglement points, and presses on the tooth with
//!
//! `N_f = held (48 E I delta / span^3 (1 + mu_ff theta n) (1 + m_h) + w (Z c f_a l_c + 2 pi gamma sqrt(r_f r_t) (1 + c)))`   (N, per parted fibre)
//!
//! - bending: a span of length `span` held at its ends and deflected by `delta` in its middle (a simply
//!   supported beam under a central load, `48 E I / L^3`); `delta = (r_t + r_f) / 2 + kappa span^2 / 8`: the mean
//!   deflection of the fibres in the tooth's path (a fibre `x` off the tooth's axis is pushed `r_t + r_f - |x|`
//!   aside) and, for curled fibres, the sagitta of the curl over the span (**curl interlocking**: a curled fibre
//!   bulges into its neighbours' spans by `kappa span^2 / 8`, and the tooth must bend that bulge out of its way
//!   too); `kappa` is the curl the fibres keep where the tooth meets them: the wisp's current curvature there, at
//!   most its natural (rest) curvature ([`curl_curvature`]). A curl pulled open, by gravity on a hanging tress or
//!   more on a wet one (heavier, bending and torsion moduli 0.4 and 0.1 of dry: `crate::wetness`), interlocks
//!   less: **wet curly hair combs easier** as its curl relaxes. Straight hair (rest curvature 0) has none.
//!   `E I` is the fibre's flexural rigidity at its wetness;
//! - **tangles pushed ahead of the comb** (`1 + mu_ff theta n`, [`Entanglement::pile_factor`]): the tooth turns a
//!   parted fibre by `theta_t = 3 (r_t + r_f) / (2 span)` at the crossings (the end slope of the span it deflects,
//!   [`Entanglement::tooth_turn`]). A crossing the tooth meets with its path between the two fibres cannot be parted:
//!   the comb pushes it down ahead of it with the ones it met before, each a small capstan wrap of the turn
//!   `theta_t` (straight fibres' tangles). Curled fibres cross their neighbours at the end slope `4 h / span` of the
//!   curl's arc of sagitta `h = kappa span^2 / 8`; beyond the tooth's own turn they are hooked by `4 h / span -
//!   theta_t`, so `theta = max(theta_t, 4 h / span - theta_t)`. After combing `travel` metres of the wisp the comb
//!   pushes `n = travel / span` crossings, each a wrap of angle `theta` with the fibre-on-fibre friction `mu_ff` on
//!   the parted fibres' bending load (the crossings carry the bending's reactions; the capillary shares pull along
//!   the fibres). The pile grows towards the tips and leaves with the fibres there (`held`): the tangles "generated
//!   below the comb, which move down with it" and whose cumulative effect at the tips gives the dry end peak
//!   (Y. K. Kamath, TRI-Princeton, "Problems of tangled hair", kamath-consulting.com, 2017: mechanism described, no
//!   figures), curly hair's inter- and intra-fibre entanglements (TRI-Princeton, *Hair Care Product Claims*, ch. 6).
//!   **Wet crossings are zipped shut** ([`Entanglement::zipped`]) where the capillary adhesion over a span beats the
//!   bending that aligns the two fibres, `w c f_a r_f span^2 >= 2 E I theta_t^2` (the elastocapillary coalescence of
//!   wet hair, Bico et al., Nature 432, 690 (2004); the adhesion's energy per unit length `f_a r_f`, the bending's
//!   over a span `2 E I theta_t^2 / span` for the two fibres): a wet tress has no straight-fibre tangles to push (the
//!   measured wet curve has no end peak), only the curls' hooks, which relax with the curl. No constant is fitted:
//!   `theta` is the curl's and the tooth's geometry over the calibrated span, `mu_ff` the fibres' friction
//!   (`crate::hair_contact::HairContact::friction`, with the wetness and the treatment);
//! - **curls hooked into their neighbours** (`1 + m_h`, [`Entanglement::hooked_neighbours`]): a curled parted fibre's
//!   arc, where it turns beyond the tooth's own turn, hooks the fibres beside it, its own wisp's and the
//!   neighbouring wisps' (curly hair's inter-fibre entanglement, TRI-Princeton, *Hair Care Product Claims*, ch. 6):
//!   deflected by the tooth, it drags them with it, each bent over its span as the parted fibre is. The hook is the
//!   sagitta beyond the tooth's deflection of the span's ends, `h_k = max(0, h - 3 (r_t + r_f) / 8)`
//!   ([`Entanglement::hook_depth`]; where `4 h / span` exceeds the tooth's turn, as for the pile's hook angle); the
//!   fibres it holds are those whose centres lie in the region it sweeps, `h_k` wide and `4 r_f` thick (within a
//!   fibre diameter of the curl's plane), at a wisp's areal density `packing / (pi r_f^2)`
//!   (`crate::hair_contact::HairContact::packing`), each pulled by the deflection's component in the curl's plane
//!   (`2 / pi` over the planes' directions): `m_h = 8 packing h_k / (pi^2 r_f) (1 - s_r)`. **Wet, curls zip into
//!   ringlets** ([`Entanglement::ringlet_share`], `s_r`): two wet curled fibres out of phase by `phi` coalesce when
//!   `w c f_a r_f >= E I kappa^2 (1 - cos phi) / 2` (elastocapillary coalescence, Bico et al. 2004), a share
//!   `arccos(1 - 2 X) / pi` of random-phase neighbours, `X = w c f_a r_f / (E I kappa^2)`, all of them from `X = 1`:
//!   a neighbour in the same ringlet lies along the fibre instead of in its hook. Straight and wavy fibres have no
//!   hook (`m_h = 0`: the law before them, to the bit); African hair dry at its natural curl 2.2 hooked neighbours,
//!   none wet once its curl has opened to 90 1/m. Continuous in the curl and the wetness, bounded by the sagitta's
//!   quarter span. No constant: the curl's and the tooth's geometry, the wisps' packing (a model input set before,
//!   not on the combing figures) and the zipping energetics the law already uses;
//! - **capillary adhesion of wet fibres**: wet fibres lying side by side are held together by the menisci
//!   between them, `f_a` per unit length of contact (default `2 gamma`: a meniscus on each side, each pulling
//!   with the surface tension per unit length; the elastocapillary coalescence of wet hair, Bico et al., Nature
//!   432, 690 (2004)); a parted fibre must be pulled off its neighbours over the length `l_c` over which they lie
//!   side by side: the whole span for straight fibres, and for fibres curled with curvature `kappa` the length over
//!   which two touching arcs stay within a fibre radius of each other, `2 sqrt(2 r_f / kappa)` (shorter curls touch
//!   their neighbours at points, so **straight hair combs harder wet, curly hair does not**); **a wet tress
//!   compacts** (TRI-Princeton, ch. 6: straight hair "becomes more volumetrically compact when it is wet and the
//!   surface tension of water causes the hair fibers to stick to one another"; wet fibres coalesce into
//!   close-packed bundles, Bico 2004), so a fibre lies along six neighbours, each pulling with `f_a` along the line
//!   of the two centres: pulled sideways, it is held by `Z = sum max(0, cos phi_i)` of them, `6 / pi` averaged over
//!   the directions of the pull ([`Entanglement::peeled_neighbours`]: 2 pulled away from a neighbour, `sqrt 3`
//!   between two);
//! - the hair surface's **wettability** `c` ([`Entanglement::wettability`]): the capillary forces of water on the
//!   fibre's surface relative to virgin hair's, `cos theta_r / cos theta_r(virgin)` of the receding contact
//!   angles (a meniscus pulled off a surface pulls as the cosine of its contact angle): 1 for virgin hair, 2 for
//!   bleached hair, whose 18-MEA lipid layer is gone (receding angle 3 degrees against 60,
//!   `crate::treatment::Treatment::wettability`). It scales the adhesion between fibres and the fibre's side of
//!   the bridge on the tooth;
//! - capillary bridge on the tooth: the water bridge where a wet fibre crosses the tooth pulls the two
//!   together with `2 pi gamma sqrt(r_f r_t) (cos theta_1 + cos theta_2)` (the meniscus between two crossed
//!   cylinders in contact, as between a sphere of radius `sqrt(r_f r_t)` and a plane; Israelachvili,
//!   *Intermolecular and Surface Forces*, 3rd ed., ch. 17), `gamma` the surface tension of water, scaled by the
//!   wetness `w` in [0, 1]; the tooth's side counts as complete wetting and the fibre's as virgin hair's times the
//!   wettability `c` (so `4 pi gamma sqrt(r_f r_t)` on virgin hair, as the virgin adhesion `f_a`: the virgin
//!   levels are the complete-wetting ones, see [`Entanglement::adhesion`]).
//!
//! Within half a span of the fibre's tip there is no entanglement point below the tooth: the share held
//! (`held`) falls linearly to 0 at the tip (the end slips aside, and at the tip there is no fibre left to part:
//! the wisp's fibres leave the tooth over the last half span, not all in one step).
//!
//! The tooth slides on the parted fibres with the tool-hair Coulomb coefficient `mu`: it feels a drag up to
//! `mu N_f` per parted fibre, against the relative motion. Of a wisp whose centreline is `d` from the tooth's
//! axis, the parted share is the share of the wisp's section within `r_t + r_f` of the axis
//! ([`parted_share`]): it goes smoothly to 0 as the wisp leaves the tooth, so the force has no steps. The
//! drag is a Coulomb force (rate independent), as combing forces of tresses are at 0.1-0.5 m/s. Only a tooth
//! thinner than the wisp parts it ([`Entanglement::parts`]); a thicker body (a comb's spine) presses the fibres it
//! reaches against the others and pushes the wisp as a solid once it reaches its centreline ([`crate::cushion`]).
//!
//! Calibration: `span` is the one number set from a measurement (the dry combing force of a 4.75 g tress of
//! H1, see [`Entanglement::span`]); stiffness, curl, friction, wetness and the tress's size then set every other
//! hair type's and the wet tresses' forces.

use strand::StrandError;

/// The entanglement of the fibres in a wisp and the capillary adhesion of wet fibres: what a tooth passing
/// through a wisp pulls against (see the module documentation for the law).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entanglement {
    /// Free length of a fibre between the entanglement points that hold it sideways in the tress, m.
    /// Default 7.3 mm: calibrated on the H1 tress scenario (`examples/scenarios/comb-h1.toml`: 4.75 g, 24 wisps of
    /// 20 cm, combed at 0.25 m/s; the mean over six tress layouts at the shipped 1 ms step) against the measured
    /// dry force (J. Soc. Cosmet. Chem. 24, 1973, Table I: 12-13 gf, i.e. 0.12 N), the one number fitted; refitted
    /// to the same figure once the sliding drag (`strand::constraint::slide`) made the force converge in the time
    /// step (6.6 mm before, docs/combing.md "Inputs"); the bending share goes as `span^-3`.
    /// A few millimetres
    /// between crossings is what a combed, nearly aligned tress shows (fibres cross their neighbours at small
    /// angles). Other hair types' spans scale with the fibre's size: [`Entanglement::for_hair`].
    pub span: f64,
    /// Surface tension of the water on wet fibres, N/m. Default 0.072 (water at 25 C).
    pub surface_tension: f64,
    /// Capillary adhesion of two wet fibres lying side by side, per unit length of contact at wetness 1, N/m.
    /// Default 0.144 = 2 x 0.072: the meniscus on each side of the contact pulls with the surface tension per
    /// unit length (complete wetting; Bico et al., Nature 432, 690 (2004): wet hair coalesces under an
    /// adhesion of the order of the surface tension per unit length).
    pub adhesion: f64,
    /// The hair surface's capillary forces relative to virgin hair's, dimensionless: `cos theta_r / cos
    /// theta_r(virgin)` of water's receding contact angles on the two surfaces
    /// ([`crate::treatment::Treatment::wettability`]: 1 for virgin and conditioned hair, 2.0 for bleached hair).
    /// Scales the adhesion between wet fibres and the fibre's side of the bridge on the tooth. Default 1 (virgin
    /// hair).
    ///
    /// Only the ratio to virgin hair is taken from the contact angles: the virgin levels (`adhesion`, the
    /// bridge's) stay the complete-wetting estimates. With virgin hair's measured receding angle (60 degrees,
    /// cos 0.5) in them as well, the capillary terms would halve and the straight presets' wet/dry peak ratio
    /// fall far below the 7-8 measured (docs/combing.md gives the ratios): the meniscus at the contact lines is not all
    /// of the wet adhesion (the Laplace pressure of the water held between the fibres adds to it; not modelled).
    pub wettability: f64,
    /// The neighbours a parted wet fibre is pulled off, dimensionless: the adhesion between fibres `f_a` counts this
    /// many times. Default `6 / pi` (1.91): in a close-packed wet bundle (wet fibres coalesce, Bico et al., Nature
    /// 432, 690 (2004); a wet tress compacts, TRI-Princeton, *Hair Care Product Claims*, ch. 6) a fibre has six
    /// neighbours, each meniscus pulling along the line of the two centres; pulled sideways in a direction at
    /// `phi_i` from each, the fibre is held by `sum max(0, cos phi_i)` of them (2 pulled away from one neighbour,
    /// `sqrt 3` between two), `6 / pi` over the directions of the pull (the wisps' bundles lie at any angle to the
    /// tooth). Geometry, not fitted; 1 is the law before (one neighbour).
    pub peeled_neighbours: f64,
    /// Relative speed of the tooth through the wisp at and above which the drag reaches its full Coulomb force,
    /// m/s (`strand::constraint::ConstraintKind::Drag::slip_speed`); below it the drag grows with the speed (a
    /// regularised Coulomb drag: a wisp at rest on a still tooth creeps through it instead of hanging on it, and
    /// the force comes up continuously as the comb starts). Default 0.05: half the slowest combing speed of the
    /// validated range (0.1-0.5 m/s, over which tress combing forces are rate independent), a model choice.
    pub slip_speed: f64,
}

impl Default for Entanglement {
    fn default() -> Self {
        Self { span: 7.3e-3, surface_tension: 0.072, adhesion: 2.0 * 0.072, wettability: 1.0, peeled_neighbours: 6.0 / std::f64::consts::PI, slip_speed: 0.05 }
    }
}

impl Entanglement {
    /// The law for fibres of the hair type `hair`: the defaults, with the span between entanglement points scaled
    /// with the fibre's size ([`Entanglement::span_for`]).
    pub fn for_hair(hair: &strand::HairType) -> Self {
        let d = Self::default();
        Self { span: Self::span_for(d.span, hair), ..d }
    }

    /// The span between a fibre's entanglement points for the hair type `hair`, m: `span_h1` (the span calibrated on
    /// H1, [`Entanglement::span`]) times the fibre's size over H1's, the size of an elliptical section of
    /// semi-axes `a`, `b` being `a b / (a + b)` (its area over its half perimeter, to first order in the
    /// ellipticity). In a mass of fibres at a given packing fraction, the mean length between a fibre's contacts
    /// with its neighbours goes as the fibres' cross-section over their width (Komori and Makishima, "Number of
    /// fiber-to-fiber contacts in general fiber assemblies", Textile Research Journal 47, 13-17, 1977): thicker
    /// fibres cross fewer neighbours per unit length. No constant: H1's ratio is 1 exactly, so it keeps
    /// `span_h1` to the bit (the other presets' spans: docs/combing.md). A section that cannot be built keeps
    /// `span_h1`. Lengths in m.
    pub fn span_for(span_h1: f64, hair: &strand::HairType) -> f64 {
        let size = |h: &strand::HairType| h.section().map(|c| c.semi_major * c.semi_minor / (c.semi_major + c.semi_minor));
        match (size(hair), size(&strand::HairType::H1)) {
            (Ok(s), Ok(s1)) if s > 0.0 && s1 > 0.0 => span_h1 * (s / s1),
            _ => span_h1,
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), StrandError> {
        let bad = |field: &'static str, reason: String| Err(StrandError::InvalidParameter { field, reason });
        if !(self.span.is_finite() && self.span > 0.0) {
            return bad("entanglement.span", format!("must be > 0 m, got {}", self.span));
        }
        if !(self.surface_tension.is_finite() && self.surface_tension >= 0.0) {
            return bad("entanglement.surface_tension", format!("must be >= 0 N/m, got {}", self.surface_tension));
        }
        if !(self.adhesion.is_finite() && self.adhesion >= 0.0) {
            return bad("entanglement.adhesion", format!("must be >= 0 N/m, got {}", self.adhesion));
        }
        if !(self.wettability.is_finite() && self.wettability >= 0.0) {
            return bad("entanglement.wettability", format!("must be >= 0, got {}", self.wettability));
        }
        if !(self.peeled_neighbours.is_finite() && self.peeled_neighbours >= 0.0) {
            return bad("entanglement.peeled_neighbours", format!("must be >= 0, got {}", self.peeled_neighbours));
        }
        if !(self.slip_speed.is_finite() && self.slip_speed >= 0.0) {
            return bad("entanglement.slip_speed", format!("must be >= 0 m/s, got {}", self.slip_speed));
        }
        Ok(())
    }

    /// Normal load one parted fibre puts on a tooth, N (the module's law): for a fibre of flexural rigidity `ei`
    /// (N m^2) and radius `fibre_radius` (m), a tooth of radius `tooth_radius` (m), wetness `wetness` (0..1;
    /// clamped), `free_length` (m) from the tooth to the fibre's tip and the curl `curvature` (1/m, from
    /// [`curl_curvature`]; 0 for straight fibres) the fibres keep at the tooth. Within half a span of the tip the
    /// fibre is not held below the tooth (its end slips aside): the load falls linearly to 0 at the tip,
    /// `min(1, 2 free_length / span)`. Without the pile and the hooked neighbours
    /// ([`Entanglement::parting_load_piled`]).
    pub fn parting_load(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64, free_length: f64, curvature: f64) -> f64 {
        self.parting_load_piled(ei, fibre_radius, tooth_radius, wetness, free_length, curvature, 0.0, 0.0, 0.0)
    }

    /// The curl's hook depth over a span, m: the sagitta ([`Entanglement::sagitta`]) beyond the tooth's own
    /// deflection of the span's ends, `max(0, h - 3 (r_t + r_f) / 8)` (radii in m, the curvature in 1/m): where the
    /// end slope of the curl's arc, `4 h / span`, exceeds the tooth's turn `3 (r_t + r_f) / (2 span)`
    /// ([`Entanglement::tooth_turn`]), the part of the bulge the tooth's deflection does not take out. 0 for straight
    /// and wavy fibres (a 4.4 cm wave over 5.6 mm: 68 um against 240 um), continuous in the curvature.
    pub fn hook_depth(&self, fibre_radius: f64, tooth_radius: f64, curvature: f64) -> f64 {
        (self.sagitta(curvature) - 0.375 * (tooth_radius + fibre_radius)).max(0.0)
    }

    /// Share (0..1) of a curled fibre's neighbours zipped along it by the water (the module's law, **ringlets**): two
    /// wet fibres of curvature `kappa` lying side by side out of phase by `phi` zip into one ringlet when the capillary
    /// adhesion's energy per unit length beats the bending that brings the two curls into phase,
    /// `w c f_a r_f >= E I kappa^2 (1 - cos phi) / 2` (elastocapillary coalescence, Bico et al., Nature 432, 690
    /// (2004), as [`Entanglement::zipped`] for straight crossings); over neighbours of uniformly random phase the
    /// share is `arccos(1 - 2 X) / pi`, `X = w c f_a r_f / (E I kappa^2)`, 1 from `X = 1`. Dry (w = 0): 0;
    /// continuous in the wetness and the curvature. Flexural rigidity `ei` in N m^2 at the wetness, radius in m,
    /// curvature in 1/m.
    pub fn ringlet_share(&self, ei: f64, fibre_radius: f64, wetness: f64, curvature: f64) -> f64 {
        let w = if wetness.is_finite() { wetness.clamp(0.0, 1.0) } else { 0.0 };
        let kappa = if curvature.is_finite() { curvature.abs() } else { 0.0 };
        let adhesion = w * self.wettability * self.adhesion * fibre_radius;
        let bending = ei * kappa * kappa;
        if adhesion <= 0.0 {
            return 0.0;
        }
        if bending.is_nan() || bending <= 0.0 || adhesion >= bending {
            return 1.0;
        }
        (1.0 - 2.0 * adhesion / bending).clamp(-1.0, 1.0).acos() / std::f64::consts::PI
    }

    /// The neighbours a parted curled fibre drags with it through its hooks, dimensionless (the module's law,
    /// **inter-wisp hooking**): the fibres around it, at the areal density `packing / (pi r_f^2)` of a wisp's
    /// section (`crate::hair_contact::HairContact::packing`, the same wisps), whose centres lie within the region
    /// the curl's hook sweeps beside its chord, the hook depth `h_k` ([`Entanglement::hook_depth`]) wide and `4 r_f`
    /// thick (a neighbour within a fibre diameter of the curl's plane touches the arc), each pulled by the component
    /// of the tooth's deflection in the curl's plane (`2 / pi` averaged over the planes' directions), less the
    /// share zipped into the same ringlet when wet ([`Entanglement::ringlet_share`]):
    /// `m = 8 packing h_k / (pi^2 r_f) (1 - ringlet_share)`. 0 for straight and wavy hair; African hair dry at its
    /// natural curl 2.2 with the default packing 0.5; bounded by the sagitta's quarter span.
    pub fn hooked_neighbours(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64, curvature: f64, packing: f64) -> f64 {
        let phi = if packing.is_finite() { packing.clamp(0.0, 1.0) } else { 0.0 };
        let depth = self.hook_depth(fibre_radius, tooth_radius, curvature);
        if depth <= 0.0 || phi <= 0.0 || fibre_radius.is_nan() || fibre_radius <= 0.0 {
            return 0.0;
        }
        let pi2 = std::f64::consts::PI * std::f64::consts::PI;
        8.0 * phi * depth / (pi2 * fibre_radius) * (1.0 - self.ringlet_share(ei, fibre_radius, wetness, curvature))
    }

    /// Deflection of a parted fibre's span at the tooth, m: `(r_t + r_f) / 2` and the curl's sagitta
    /// ([`Entanglement::sagitta`]).
    pub fn deflection(&self, fibre_radius: f64, tooth_radius: f64, curvature: f64) -> f64 {
        0.5 * (tooth_radius + fibre_radius) + self.sagitta(curvature)
    }

    /// The curl's sagitta over a span, m: `kappa span^2 / 8` for the curvature `curvature` (1/m), at most a quarter
    /// span (the beam law's reach).
    pub fn sagitta(&self, curvature: f64) -> f64 {
        let kappa = if curvature.is_finite() { curvature.abs() } else { 0.0 };
        (kappa * self.span * self.span / 8.0).min(0.25 * self.span)
    }

    /// The turn the tooth gives a parted fibre at the crossings that hold it, rad: `3 (r_t + r_f) / (2 span)`, the
    /// end slope `3 delta / span` of a span deflected by `delta = (r_t + r_f) / 2` in its middle (radii in m).
    pub fn tooth_turn(&self, fibre_radius: f64, tooth_radius: f64) -> f64 {
        1.5 * (tooth_radius + fibre_radius) / self.span
    }

    /// The zipping ratio of wet crossings, dimensionless (the module's law): the capillary adhesion between two
    /// fibres over a span, `w c f_a r_f span` (its energy per unit length `f_a r_f`, at wetness `w` and the
    /// wettability `c`), over the bending that aligns two fibres crossing at the tooth's turn `theta_t`
    /// ([`Entanglement::tooth_turn`]), `2 E I theta_t^2 / span` (the elastocapillary coalescence of wet hair, Bico et
    /// al., Nature 432, 690 (2004)):
    /// `w c f_a r_f span^2 / (2 E I theta_t^2)`. At 1 or more the crossings zip shut ([`Entanglement::zipped`]).
    /// For a fibre of flexural rigidity `ei` (N m^2) and radius `fibre_radius` (m) on a tooth of radius
    /// `tooth_radius` (m), at `wetness` (0..1, clamped; not finite counts as dry). 0 dry; infinite for a wet fibre
    /// without flexural rigidity (`ei <= 0`). It grows with the wetness (the adhesion grows and, with the wet
    /// modulus, the fibre softens; test `every_presets_crossings_zip_shut_wet_and_never_dry` gives the presets'
    /// margins).
    pub fn zipping_ratio(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64) -> f64 {
        let w = if wetness.is_finite() { wetness.clamp(0.0, 1.0) } else { 0.0 };
        if w <= 0.0 {
            return 0.0;
        }
        let theta = self.tooth_turn(fibre_radius, tooth_radius);
        let bending = 2.0 * ei * theta * theta;
        if bending <= 0.0 {
            return f64::INFINITY;
        }
        w * self.wettability * self.adhesion * fibre_radius * self.span * self.span / bending
    }

    /// Whether wet crossings are zipped shut (the module's law): the zipping ratio
    /// ([`Entanglement::zipping_ratio`], adhesion over bending) at least 1. Same arguments. Dry fibres are never
    /// zipped. The same decision as comparing the adhesion with the bending directly: a correctly rounded quotient
    /// of two positive numbers is at least 1 exactly when the numerator is at least the denominator.
    pub fn zipped(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64) -> bool {
        self.zipping_ratio(ei, fibre_radius, tooth_radius, wetness) >= 1.0
    }

    /// The tangles' pile-up factor on the parted fibres' bending load, dimensionless (the module's law):
    /// `1 + mu_ff theta n`, with `n = travel / span` the crossings the comb has met over `travel` (m) along the
    /// wisp since it entered it, which it pushes ahead, `mu_ff` (`hair_friction`) the fibre-on-fibre friction
    /// coefficient (each crossing pushed along is a small capstan wrap of angle `theta`) and `theta` the angle of the
    /// wrap: the tooth's turn `theta_t` ([`Entanglement::tooth_turn`]; none where the crossings are `zipped`, wet:
    /// [`Entanglement::zipped`]) or, if larger, the angle by which curled fibres hook into each other beyond it,
    /// `(4 h - 3 (r_t + r_f) / 2) / span`, the end slope of the curl's arc of sagitta `h` over a span
    /// ([`Entanglement::sagitta`]) beyond the tooth's turn. Straight and wavy fibres (a 4.4 cm wave turns 0.08 rad over
    /// the span, a 0.6 mm tooth 0.15 rad) pile at the tooth's turn dry and nothing wet; tight curls (African hair:
    /// 0.37 rad) pile at their hook's angle, dry and wet.
    pub fn pile_factor(&self, hair_friction: f64, fibre_radius: f64, tooth_radius: f64, curvature: f64, travel: f64, zipped: bool) -> f64 {
        let mu = if hair_friction.is_finite() { hair_friction.max(0.0) } else { 0.0 };
        let n = if travel.is_finite() { travel.abs() / self.span } else { 0.0 };
        let turn = self.tooth_turn(fibre_radius, tooth_radius);
        // The hook's angle: the end slope of the curl's arc beyond the tooth's turn, `4 h_k / span` with `h_k`
        // [`Entanglement::hook_depth`]. Written in this order, not through `hook_depth`: the two differ in the last
        // bit, and a wet African tress's six-layout peak moves by a few per cent with it (the anchors' round-off sensitivity,
        // docs/combing.md).
        let hook = (4.0 * self.sagitta(curvature) / self.span - turn).max(0.0);
        let theta = if zipped { hook } else { hook.max(turn) };
        1.0 + mu * theta * n
    }

    /// [`Entanglement::parting_load`] with the crossings the tooth pushes ahead (the tangle pile-up,
    /// [`Entanglement::pile_factor`], zipped shut when wet: [`Entanglement::zipped`]): the bending share times
    /// `1 + mu_ff theta travel / span`, for the fibre-on-fibre friction `hair_friction` and the tooth's `travel` (m)
    /// along the wisp since it entered it, and the curled neighbours hooked into the fibre dragged with it, times
    /// `1 + m_h` ([`Entanglement::hooked_neighbours`], at the wisps' packing fraction `packing`; 0 for no hooks). The
    /// capillary shares are neither piled nor hooked: they pull fibres off their neighbours along their length, not
    /// at the crossings.
    #[allow(clippy::too_many_arguments)]
    pub fn parting_load_piled(&self, ei: f64, fibre_radius: f64, tooth_radius: f64, wetness: f64, free_length: f64, curvature: f64, hair_friction: f64, travel: f64, packing: f64) -> f64 {
        let kappa = if curvature.is_finite() { curvature.abs() } else { 0.0 };
        let w = if wetness.is_finite() { wetness.clamp(0.0, 1.0) } else { 0.0 };
        let delta = self.deflection(fibre_radius, tooth_radius, kappa);
        let pile = self.pile_factor(hair_friction, fibre_radius, tooth_radius, kappa, travel, self.zipped(ei, fibre_radius, tooth_radius, w));
        let c = self.wettability;
        let bridge = 4.0 * std::f64::consts::PI * self.surface_tension * (fibre_radius * tooth_radius).sqrt() * (0.5 * (1.0 + c));
        let adhesion = self.peeled_neighbours * self.adhesion * self.contact_length(fibre_radius, kappa) * c;
        let held = (2.0 * free_length.max(0.0) / self.span).min(1.0);
        let hooked = self.hooked_neighbours(ei, fibre_radius, tooth_radius, w, kappa, packing);
        held * (48.0 * ei * delta / self.span.powi(3) * pile * (1.0 + hooked) + w * (adhesion + bridge))
    }

    /// Length over which a fibre of radius `fibre_radius` (m) curled with curvature `curvature` (1/m) lies side
    /// by side with its neighbours within one span, m: `min(span, 2 sqrt(2 r_f / kappa))` (two touching arcs of
    /// curvature kappa stay within `r_f` of each other over that length); the span for straight fibres.
    pub fn contact_length(&self, fibre_radius: f64, curvature: f64) -> f64 {
        let kappa = if curvature.is_finite() { curvature.abs() } else { 0.0 };
        if kappa * self.span * self.span <= 8.0 * fibre_radius {
            return self.span;
        }
        (2.0 * (2.0 * fibre_radius / kappa).sqrt()).min(self.span)
    }

    /// Whether a tooth of radius `tooth_radius` (m) passes through the fibres, parting them (the beam law above):
    /// a tooth whose diameter is at most half a span, so that the parted fibres' deflection stays small against
    /// the span they bend over (a comb's teeth, 1.2 mm, a brush's bristles). A thicker body (a comb's 6 mm spine,
    /// a finger) is not passed through: it presses the wisp's fibres it reaches ([`crate::cushion`]) and pushes the
    /// wisp aside as a solid once it reaches the centreline.
    pub fn parts(&self, tooth_radius: f64) -> bool {
        4.0 * tooth_radius <= self.span
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

/// The curl a wisp's fibres keep at arc length `s` (m) of `strand`, 1/m: the centreline's current curvature there
/// (`sqrt(kappa_1^2 + kappa_2^2)` of the Super-Helix segment; the reduced model's one bend), at most its rest
/// (natural) curvature: a curl pulled open counts as far as it is open, a wisp bent further than its natural curl
/// (around the tooth itself) does not count as curlier. 0 for straight hair.
pub fn curl_curvature(strand: &strand::Strand, s: f64) -> f64 {
    let m = &strand.model;
    let d = m.dofs_per_segment();
    if m.segments == 0 || !s.is_finite() {
        return 0.0;
    }
    let i = ((s / m.segment_length()).max(0.0) as usize).min(m.segments - 1);
    let q = &strand.state.q;
    let now = (1..d).map(|k| q.get(i * d + k).copied().unwrap_or(0.0).powi(2)).sum::<f64>().sqrt();
    let rest = m.rest.get(i).map_or(0.0, |r| (1..d).map(|k| r[k] * r[k]).sum::<f64>().sqrt());
    if now.is_finite() { now.min(rest) } else { 0.0 }
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
    #[test]
    fn the_span_goes_as_the_fibres_size() {
        // H1 keeps the calibrated span to the bit; every other preset's is 6.6 mm times a b / (a + b) over H1's, the
        // semi-axes written out from the presets' diameters and ellipticities (1e-12); African hair, the thinnest
        // minor axis, has the shortest span and asian hair, the thickest and roundest, the longest.
        let d = Entanglement::default();
        assert_eq!(Entanglement::for_hair(&strand::HairType::H1).span, d.span);
        let size = |dia: f64, e: f64| {
            let (a, b) = (dia / 2.0, dia / 2.0 / e);
            a * b / (a + b)
        };
        let h1 = size(93.1e-6, 1.36);
        for (name, dia, e) in [("H2", 96.1e-6, 1.33), ("GA1", 89.5e-6, 1.45), ("GC3", 89.3e-6, 1.42), ("asian", 100e-6, 1.2), ("caucasian", 80e-6, 1.4), ("african", 85e-6, 1.9)] {
            let hair = strand::HairType::by_name(name).unwrap();
            let span = Entanglement::for_hair(&hair).span;
            let expected = 7.3e-3 * size(dia, e) / h1;
            assert!((span - expected).abs() <= 1e-12 * expected, "{name}: {span} vs {expected}");
        }
        let spans: Vec<f64> = strand::HairType::ALL.iter().map(|h| Entanglement::for_hair(h).span).collect();
        let min = spans.iter().copied().fold(f64::INFINITY, f64::min);
        let max = spans.iter().copied().fold(0.0, f64::max);
        assert_eq!(min, Entanglement::for_hair(&strand::HairType::by_name("african").unwrap()).span);
        assert_eq!(max, Entanglement::for_hair(&strand::HairType::by_name("asian").unwrap()).span);
    }

    use super::*;

    #[test]
    fn curled_fibres_interlock_dry_and_lie_apart_wet() {
        // A span of 6.6 mm (the default before 2026-11-30), an African fibre (EI 1.46e-9 N m^2, r_f 42.5 um) on a 0.6 mm tooth.
        let e = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let (ei, rf, rt) = (1.46e-9, 42.5e-6, 0.6e-3);
        let span3 = e.span.powi(3);
        // Curl interlocking: the deflection grows by the curl's sagitta kappa span^2 / 8 (156 1/m: 0.849 mm).
        let dry_straight = e.parting_load(ei, rf, rt, 0.0, 0.1, 0.0);
        let dry_curled = e.parting_load(ei, rf, rt, 0.0, 0.1, 156.0);
        let sagitta = 156.0 * e.span * e.span / 8.0;
        assert!((dry_curled - dry_straight - 48.0 * ei * sagitta / span3).abs() < 1e-12, "{dry_curled} {dry_straight}");
        assert!(dry_curled > 3.0 * dry_straight);
        // The sagitta is capped at a quarter span.
        assert_eq!(e.parting_load(ei, rf, rt, 0.0, 0.1, 1e6), e.parting_load(ei, rf, rt, 0.0, 0.1, 8.0 / e.span));
        // Contact length: the span for straight fibres, 2 sqrt(2 r_f / kappa) for curled ones (1.476 mm at 156 1/m),
        // continuous where they meet (kappa span^2 = 8 r_f).
        assert_eq!(e.contact_length(rf, 0.0), e.span);
        assert!((e.contact_length(rf, 156.0) - 2.0 * (2.0 * rf / 156.0f64).sqrt()).abs() < 1e-15);
        let k0 = 8.0 * rf / (e.span * e.span);
        assert!((e.contact_length(rf, k0 * (1.0 + 1e-9)) - e.span).abs() < 1e-9 * e.span);
        // Wet adhesion, per fibre: the straight fibre's 0.144 N/m from 6 / pi neighbours over the span, the curled
        // one's over its contact.
        let wet = |kappa: f64| e.parting_load(ei, rf, rt, 1.0, 0.1, kappa) - e.parting_load(ei, rf, rt, 0.0, 0.1, kappa);
        let bridge = 4.0 * std::f64::consts::PI * 0.072 * (rf * rt).sqrt();
        let z = 6.0 / std::f64::consts::PI;
        assert!((wet(0.0) - (z * 0.144 * e.span + bridge)).abs() < 1e-12);
        assert!((wet(156.0) - (z * 0.144 * e.contact_length(rf, 156.0) + bridge)).abs() < 1e-12);
        assert!(wet(156.0) < 0.5 * wet(0.0));
        // Teeth part the wisp, a comb's 3 mm spine does not (diameter above half a span).
        assert!(e.parts(0.6e-3) && !e.parts(3e-3));
    }

    #[test]
    fn interlocked_curls_pile_up_ahead_of_the_comb() {
        // A span of 6.6 mm (the default before 2026-11-30), an African fibre (EI 1.46e-9 N m^2, r_f 42.5 um, curl 156 1/m) on a 0.6 mm tooth,
        // fibre-on-fibre friction 0.25, 10 cm combed: sagitta 0.8494 mm, theta = (4 h - 1.5 (r_t + r_f)) / span =
        // (3.3977 - 0.9638) mm / 6.6 mm = 0.3688 rad, 15.15 crossings pushed ahead: 1 + 0.25 x 0.3688 x 15.15 = 2.397
        // (by hand, 1e-3).
        let e = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let (ei, rf, rt, mu) = (1.46e-9, 42.5e-6, 0.6e-3, 0.25);
        let f = e.pile_factor(mu, rf, rt, 156.0, 0.1, false);
        assert!((f - 2.397).abs() < 1e-3, "{f}");
        // The curls' hooks are not zipped shut wet: the same pile.
        assert_eq!(e.pile_factor(mu, rf, rt, 156.0, 0.1, true), f);
        // Linear in the travel and the friction; no friction or no travel: none, exactly.
        assert!((e.pile_factor(mu, rf, rt, 156.0, 0.05, false) - 1.0 - 0.5 * (f - 1.0)).abs() < 1e-12);
        assert!((e.pile_factor(2.0 * mu, rf, rt, 156.0, 0.1, false) - 1.0 - 2.0 * (f - 1.0)).abs() < 1e-12);
        assert_eq!(e.pile_factor(0.0, rf, rt, 156.0, 0.1, false), 1.0);
        assert_eq!(e.pile_factor(mu, rf, rt, 156.0, 0.0, false), 1.0);
        // Caucasian waves (radius 4.4 cm, 22.7 1/m) cross at 0.075 rad, below the tooth's own turn ((0.6 + 0.04) mm x
        // 1.5 / 6.6 mm = 0.1455 rad): piled at the tooth's turn as straight fibres are, 1 + 0.25 x 0.1455 x 0.2 / 6.6 mm
        // = 2.102 (by hand, 1e-3); zipped shut (wet), none.
        let wave = e.pile_factor(mu, 40e-6, rt, 22.7, 0.2, false);
        assert!((wave - 2.102).abs() < 1e-3, "{wave}");
        assert_eq!(wave, e.pile_factor(mu, 40e-6, rt, 0.0, 0.2, false));
        assert_eq!(e.pile_factor(mu, 40e-6, rt, 22.7, 0.2, true), 1.0);
        // The angle is bounded with the sagitta (a quarter span: theta at most 1 - 0.146 rad); bad inputs pile nothing.
        assert!((e.pile_factor(mu, rf, rt, 1e9, e.span, false) - (1.0 + mu * (1.0 - 1.5 * (rt + rf) / e.span))).abs() < 1e-12);
        assert_eq!(e.pile_factor(f64::NAN, rf, rt, 156.0, 0.1, false), 1.0);
        assert_eq!(e.pile_factor(mu, rf, rt, 156.0, f64::INFINITY, false), 1.0);
        // The pile multiplies the bending share only: no travel is the law without it, bit for bit; wet, the
        // capillary shares are added unpiled.
        for w in [0.0, 1.0] {
            assert_eq!(e.parting_load_piled(ei, rf, rt, w, 0.1, 156.0, mu, 0.0, 0.0), e.parting_load(ei, rf, rt, w, 0.1, 156.0));
            let beam = e.parting_load(ei, rf, rt, 0.0, 0.1, 156.0);
            let wet = e.parting_load(ei, rf, rt, w, 0.1, 156.0) - beam;
            let piled = e.parting_load_piled(ei, rf, rt, w, 0.1, 156.0, mu, 0.1, 0.0);
            assert!((piled - (beam * f + wet)).abs() < 1e-12 * piled, "w = {w}: {piled}");
        }
        // Near the tip the pile leaves with the fibres (the held share): a quarter span from it, half.
        let half = e.parting_load_piled(ei, rf, rt, 0.0, 0.25 * e.span, 156.0, mu, 0.1, 0.0);
        assert!((half - 0.5 * e.parting_load_piled(ei, rf, rt, 0.0, 0.1, 156.0, mu, 0.1, 0.0)).abs() < 1e-12 * half);
    }

    #[test]
    fn curled_fibres_hook_their_neighbours_dry_and_zip_into_ringlets_wet() {
        // A span of 6.6 mm (the default before 2026-11-30), an African fibre (EI 1.46e-9 N m^2 dry, 0.4 of it wet; r_f 42.5 um, curl 156 1/m)
        // on a 0.6 mm tooth, packing 0.5: sagitta 0.84942 mm, hook depth 0.84942 - 0.375 x 0.6425 = 0.60848 mm,
        // hooked neighbours dry 8 x 0.5 x 0.60848 mm / (pi^2 x 42.5 um) = 5.8026 (by hand, 1e-4).
        let e = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let (ei, rf, rt, phi) = (1.46e-9, 42.5e-6, 0.6e-3, 0.5);
        assert!((e.hook_depth(rf, rt, 156.0) - 0.60848e-3).abs() < 1e-8, "{}", e.hook_depth(rf, rt, 156.0));
        let dry = e.hooked_neighbours(ei, rf, rt, 0.0, 156.0, phi);
        assert!((dry - 5.8026).abs() < 1e-4, "{dry}");
        // Linear in the packing; none without neighbours or without a hook (straight, or a curl whose end slope the
        // tooth's turn takes out: kappa <= 3 (r_t + r_f) / span^2 = 44.25 1/m), and continuous there.
        assert!((e.hooked_neighbours(ei, rf, rt, 0.0, 156.0, 0.25) - 0.5 * dry).abs() < 1e-12);
        assert_eq!(e.hooked_neighbours(ei, rf, rt, 0.0, 156.0, 0.0), 0.0);
        assert_eq!(e.hooked_neighbours(ei, rf, rt, 0.0, 0.0, phi), 0.0);
        let k0 = 3.0 * (rt + rf) / (e.span * e.span);
        assert!((k0 - 44.25).abs() < 0.01, "{k0}");
        assert_eq!(e.hooked_neighbours(ei, rf, rt, 0.0, 0.999 * k0, phi), 0.0);
        assert!(e.hooked_neighbours(ei, rf, rt, 0.0, 1.001 * k0, phi) < 1e-2);
        // Wet at the natural curl: X = 0.144 N/m x 42.5 um / (0.584e-9 N m^2 x 156^2) = 0.43062, a share
        // arccos(1 - 2 X) / pi = 0.45569 of the neighbours zipped into the same ringlet (by hand, 1e-5); dry none.
        let z = e.ringlet_share(0.4 * ei, rf, 1.0, 156.0);
        assert!((z - 0.45569).abs() < 1e-5, "{z}");
        assert_eq!(e.ringlet_share(0.4 * ei, rf, 0.0, 156.0), 0.0);
        assert!((e.hooked_neighbours(0.4 * ei, rf, rt, 1.0, 156.0, phi) - (1.0 - z) * e.hooked_neighbours(0.4 * ei, rf, rt, 0.0, 156.0, phi)).abs() < 1e-12);
        // The curl pulled open to 90 1/m wet (X = 1.29): every neighbour zipped, no hook left; bleached hair (twice the
        // wettability) zips at half the wetness.
        assert_eq!(e.ringlet_share(0.4 * ei, rf, 1.0, 90.0), 1.0);
        assert_eq!(e.hooked_neighbours(0.4 * ei, rf, rt, 1.0, 90.0, phi), 0.0);
        let bleached = Entanglement { wettability: 2.0, ..e };
        assert!((bleached.ringlet_share(0.4 * ei, rf, 0.5, 156.0) - z).abs() < 1e-12);
        // Continuous and monotone: the share grows with the wetness from 0 and falls with the curl; the hooks fall with
        // the wetness; no step over a fine scan of the wetness and of the curvature (the largest jump between
        // neighbouring points of the scan is a few per cent of the range).
        let (mut last_z, mut last_m) = (0.0, dry);
        for k in 1..=1000 {
            let w = k as f64 / 1000.0;
            let ei_w = ei * (1.0 - 0.6 * w);
            let (zw, mw) = (e.ringlet_share(ei_w, rf, w, 156.0), e.hooked_neighbours(ei_w, rf, rt, w, 156.0, phi));
            assert!(zw >= last_z && zw - last_z < 0.05, "w {w}: {zw} after {last_z}");
            assert!(mw <= last_m + 1e-12 && last_m - mw < 0.05 * dry, "w {w}: {mw} after {last_m}");
            (last_z, last_m) = (zw, mw);
        }
        let mut last = 0.0;
        for k in 0..=2000 {
            let kappa = 0.2 * k as f64;
            for (w, ei_w) in [(0.0, ei), (1.0, 0.4 * ei)] {
                let m = e.hooked_neighbours(ei_w, rf, rt, w, kappa, phi);
                assert!(m.is_finite() && m >= 0.0 && m <= 8.0 * phi * 0.25 * e.span / (std::f64::consts::PI.powi(2) * rf), "kappa {kappa} w {w}: {m}");
                if w == 0.0 {
                    assert!(m >= last && m - last < 0.02, "kappa {kappa}: {m} after {last}");
                    last = m;
                }
            }
        }
        // The load: the bending share (piled) carried by the parted fibre and its hooked neighbours, the capillary
        // shares as before; packing 0 is the law before, bit for bit.
        let mu = 0.25;
        for w in [0.0, 0.5, 1.0] {
            let ei_w = ei * (1.0 - 0.6 * w);
            let before = e.parting_load_piled(ei_w, rf, rt, w, 0.1, 156.0, mu, 0.05, 0.0);
            let beam = e.parting_load_piled(ei_w, rf, rt, 0.0, 0.1, 156.0, mu, 0.05, 0.0);
            let m = e.hooked_neighbours(ei_w, rf, rt, w, 156.0, phi);
            let now = e.parting_load_piled(ei_w, rf, rt, w, 0.1, 156.0, mu, 0.05, phi);
            assert!((now - (before + m * beam)).abs() < 1e-12 * now, "w {w}: {now} vs {before} + {m} x {beam}");
        }
        assert!(e.parting_load_piled(ei, rf, rt, 0.0, 0.1, 156.0, mu, 0.05, phi) > 6.0 * e.parting_load_piled(ei, rf, rt, 0.0, 0.1, 156.0, mu, 0.05, 0.0));
    }

    #[test]
    fn no_preset_but_african_hair_hooks_its_neighbours() {
        // Every preset at its natural curl (the largest the law takes), every treatment, dry and wet, on the built-in
        // comb's and brush's thinnest teeth, with the preset's own span: the straight presets and caucasian's 4.4 cm
        // waves have no hook (the law before, to the bit); African hair does, dry.
        use crate::shape::ToolShape;
        use crate::treatment::Treatment;
        use crate::wetness::WetnessModel;
        let teeth = [ToolShape::builtin("comb").unwrap().min_radius(), ToolShape::builtin("brush").unwrap().min_radius()];
        let wet_model = WetnessModel::default();
        for hair in strand::HairType::ALL {
            let section = hair.section().unwrap();
            let rf = section.semi_major;
            let kappa = hair.rest_curvature().1;
            for t in Treatment::ALL {
                let e = Entanglement { wettability: t.wettability(), ..Entanglement::for_hair(&hair) };
                for rt in teeth {
                    for w in [0.0, 0.5, 1.0] {
                        let ei = wet_model.hair(&hair, w).unwrap().young_modulus * section.i_soft();
                        let m = e.hooked_neighbours(ei, rf, rt, w, kappa, 0.5);
                        if hair.name == "african" && w == 0.0 {
                            assert!(m > 1.0, "{} dry: {m}", hair.name);
                        } else if hair.name != "african" {
                            assert_eq!(m, 0.0, "{} {} w {w} r_t {rt}", hair.name, t.name());
                            assert_eq!(e.parting_load_piled(ei, rf, rt, w, 0.1, kappa, 0.25, 0.05, 0.5), e.parting_load_piled(ei, rf, rt, w, 0.1, kappa, 0.25, 0.05, 0.0));
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn straight_tangles_pile_dry_and_zip_shut_wet() {
        // H1 (EI 7.59e-9 N m^2 dry, 0.4 of it wet; r_f 46.55 um) on a 0.6 mm tooth, a span of 6.6 mm (the default before 2026-11-30): the
        // tooth's turn 1.5 x 0.64655 mm / 6.6 mm = 0.14694 rad. Zipping, wet: 0.144 N/m x 46.55 um x (6.6 mm)^2 =
        // 2.9200e-10 J against 2 x 3.036e-9 x 0.14694^2 = 1.3110e-10 J: 2.23 times (by hand); dry never.
        let e = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let (ei, rf, rt, mu) = (7.59e-9, 46.55e-6, 0.6e-3, 0.2);
        assert!((e.tooth_turn(rf, rt) - 0.14694).abs() < 1e-5, "{}", e.tooth_turn(rf, rt));
        assert!(e.zipped(0.4 * ei, rf, rt, 1.0));
        assert!(!e.zipped(ei, rf, rt, 0.0) && !e.zipped(0.4 * ei, rf, rt, 0.0));
        // The margin: at 2.23 the crossings zip at w >= 1 / 2.23 = 0.448 (with the wet stiffness), a stiffer fibre
        // (EI x 2.3) not at all; bleached hair (wettability 2) at half the wetness.
        assert!(e.zipped(0.4 * ei, rf, rt, 0.46) && !e.zipped(0.4 * ei, rf, rt, 0.43));
        assert!(!e.zipped(2.3 * 0.4 * ei, rf, rt, 1.0));
        let bleached = Entanglement { wettability: 2.0, ..e };
        assert!(bleached.zipped(0.4 * ei, rf, rt, 0.23) && !bleached.zipped(0.4 * ei, rf, rt, 0.21));
        // Dry, a straight fibre combed 10 cm pushes 15.15 crossings, each a wrap of 0.14694 rad: the bending share
        // times 1 + 0.2 x 0.14694 x 15.15 = 1.4453 (by hand, 1e-4); wet (zipped), the law without the pile.
        let dry = e.parting_load_piled(ei, rf, rt, 0.0, 0.15, 0.0, mu, 0.1, 0.0);
        assert!((dry / e.parting_load(ei, rf, rt, 0.0, 0.15, 0.0) - 1.4453).abs() < 1e-4, "{dry}");
        assert_eq!(e.parting_load_piled(0.4 * ei, rf, rt, 1.0, 0.15, 0.0, mu, 0.1, 0.0), e.parting_load(0.4 * ei, rf, rt, 1.0, 0.15, 0.0));
        // Partly wet and not zipped: the pile is back.
        assert!(e.parting_load_piled(0.4 * ei, rf, rt, 0.3, 0.15, 0.0, mu, 0.1, 0.0) > e.parting_load(0.4 * ei, rf, rt, 0.3, 0.15, 0.0));
    }

    #[test]
    fn every_presets_crossings_zip_shut_wet_and_never_dry() {
        // One case by hand: H1 wet (E I 0.4 x 7.59e-9 = 3.036e-9 N m^2, r_f 46.55 um) on the 0.6 mm tooth, the
        // a span of 6.6 mm: theta_t = 1.5 x 0.64655 mm / 6.6 mm = 0.146943 rad; adhesion over a span
        // 0.144 N/m x 46.55 um x (6.6 mm)^2 = 2.91991e-10 J, bending 2 x 3.036e-9 x 0.146943^2 = 1.31108e-10 J:
        // ratio 2.2271 fully wet, 1.1135 half wet (by hand, 1e-4); dry 0.
        let h1 = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let (ei_h1, rf_h1, rt_h1) = (0.4 * 7.59e-9, 46.55e-6, 0.6e-3);
        assert!((h1.zipping_ratio(ei_h1, rf_h1, rt_h1, 1.0) - 2.2271).abs() < 1e-4, "{}", h1.zipping_ratio(ei_h1, rf_h1, rt_h1, 1.0));
        assert!((h1.zipping_ratio(ei_h1, rf_h1, rt_h1, 0.5) - 1.1135).abs() < 1e-4, "{}", h1.zipping_ratio(ei_h1, rf_h1, rt_h1, 0.5));
        assert_eq!(h1.zipping_ratio(ei_h1, rf_h1, rt_h1, 0.0), 0.0);
        // Every hair preset, every treatment (its wettability), the built-in comb's and brush's thinnest teeth and a
        // range of wetness, with the preset's own span, fibre radius and flexural rigidity at the wetness
        // (`WetnessModel::hair`, E I = E(w) I_soft, as the local strands take it): dry, the ratio is 0 and nothing
        // is zipped; the ratio grows with the wetness (the adhesion grows and the fibre softens), so once zipped a
        // fibre stays zipped when wetter; fully wet on the comb's tooth every preset is zipped, ratio >= 1 (the
        // module's law: a wet tress has no straight-fibre tangles). `zipped` is the ratio at least 1. The margins
        // over the family are printed.
        use crate::shape::ToolShape;
        use crate::treatment::Treatment;
        use crate::wetness::WetnessModel;
        let teeth = [("comb", ToolShape::builtin("comb").unwrap().min_radius()), ("brush", ToolShape::builtin("brush").unwrap().min_radius())];
        let wet_model = WetnessModel::default();
        let (mut lowest_wet_comb, mut highest_wet_comb) = (f64::INFINITY, 0.0f64);
        for hair in strand::HairType::ALL {
            let section = hair.section().unwrap();
            let rf = section.semi_major;
            for t in Treatment::ALL {
                let e = Entanglement { wettability: t.wettability(), ..Entanglement::for_hair(&hair) };
                for (tool, rt) in teeth {
                    let mut last = 0.0;
                    for k in 0..=20 {
                        let w = k as f64 / 20.0;
                        let ei = wet_model.hair(&hair, w).unwrap().young_modulus * section.i_soft();
                        let ratio = e.zipping_ratio(ei, rf, rt, w);
                        let case = format!("{} {} {tool} w {w}: ratio {ratio}", hair.name, t.name());
                        assert!(ratio.is_finite() && ratio >= 0.0, "{case}");
                        assert_eq!(e.zipped(ei, rf, rt, w), ratio >= 1.0, "{case}");
                        assert!(ratio >= last, "{case}: below the drier {last}");
                        last = ratio;
                        if w == 0.0 {
                            assert_eq!(ratio, 0.0, "{case}: dry");
                            assert!(!e.zipped(ei, rf, rt, w), "{case}: zipped dry");
                        }
                        if w == 1.0 && tool == "comb" {
                            assert!(ratio >= 1.0 && e.zipped(ei, rf, rt, w), "{case}: not zipped wet on the comb");
                            if t == Treatment::Virgin {
                                lowest_wet_comb = lowest_wet_comb.min(ratio);
                                highest_wet_comb = highest_wet_comb.max(ratio);
                            }
                        }
                    }
                }
            }
        }
        println!("virgin hair fully wet on the comb's tooth: adhesion over bending {lowest_wet_comb:.2}-{highest_wet_comb:.2} over the presets");
    }

    #[test]
    fn a_wet_fibre_is_pulled_off_six_over_pi_neighbours() {
        // Six close-packed neighbours, each meniscus pulling along the line of the centres: pulled in direction psi,
        // the fibre is held by sum max(0, cos(phi_i - psi)); averaged over psi (a fine quadrature), 6 / pi; 2 pulled
        // away from one neighbour, sqrt 3 between two.
        let held = |psi: f64| (0..6).map(|i| (i as f64 * std::f64::consts::FRAC_PI_3 - psi).cos().max(0.0)).sum::<f64>();
        let n = 100_000;
        let mean = (0..n).map(|k| held(2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n as f64)).sum::<f64>() / n as f64;
        let e = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        assert!((mean - e.peeled_neighbours).abs() < 1e-8, "{mean} vs {}", e.peeled_neighbours);
        assert!((held(0.0) - 2.0).abs() < 1e-12 && (held(std::f64::consts::FRAC_PI_6) - 3f64.sqrt()).abs() < 1e-12);
        // The adhesion between fibres counts that many times; the bridge on the tooth and the dry load do not move.
        let (ei, rf, rt) = (7.59e-9, 46.55e-6, 0.6e-3);
        let one = Entanglement { peeled_neighbours: 1.0, ..e };
        let share = |e: &Entanglement| e.parting_load(0.4 * ei, rf, rt, 1.0, 0.1, 0.0) - e.parting_load(0.4 * ei, rf, rt, 0.0, 0.1, 0.0);
        assert!((share(&e) - share(&one) - (e.peeled_neighbours - 1.0) * 0.144 * e.span).abs() < 1e-15);
        assert_eq!(e.parting_load(ei, rf, rt, 0.0, 0.1, 0.0), one.parting_load(ei, rf, rt, 0.0, 0.1, 0.0));
        assert!(Entanglement { peeled_neighbours: -1.0, ..e }.validate().unwrap_err().to_string().contains("entanglement.peeled_neighbours"));
    }

    #[test]
    fn the_curl_is_the_wisps_current_curvature_at_most_its_natural_one() {
        use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};
        let h = HairType::AFRICAN;
        let (tw, bd) = h.rest_curvature();
        let m = StrandModel::new(ModelKind::Full, 0.1, 5, h.section().unwrap(), h.material().unwrap()).unwrap().with_uniform_rest(tw, bd, 0.0);
        let mut s = Strand::new(m, RootFrame::new(nalgebra::Vector3::zeros(), -nalgebra::Vector3::z(), nalgebra::Vector3::x()).unwrap()).unwrap();
        // At rest in its natural shape: the natural curl (the bend; the twist is no curvature of the centreline).
        s.state.q.copy_from(&s.model.rest_coordinates());
        assert!((curl_curvature(&s, 0.05) - bd).abs() < 1e-12);
        // Pulled half open in segment 2: half; bent further than its curl: the natural curl.
        s.state.q[3 * 2 + 1] = 0.5 * bd;
        assert!((curl_curvature(&s, 0.05) - 0.5 * bd).abs() < 1e-12);
        s.state.q[3 * 2 + 1] = 3.0 * bd;
        assert!((curl_curvature(&s, 0.05) - bd).abs() < 1e-12);
        // Straight hair: none, whatever its bend.
        let hs = HairType::H1;
        let ms = StrandModel::new(ModelKind::Full, 0.1, 5, hs.section().unwrap(), hs.material().unwrap()).unwrap();
        let mut st = Strand::new(ms, RootFrame::new(nalgebra::Vector3::zeros(), -nalgebra::Vector3::z(), nalgebra::Vector3::x()).unwrap()).unwrap();
        st.state.q[4] = 50.0;
        assert_eq!(curl_curvature(&st, 0.03), 0.0);
    }

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
    fn the_wettability_scales_the_menisci_and_nothing_else() {
        // Bleached hair (wettability 2): the adhesion between fibres doubles, the bridge on the tooth becomes
        // 2 pi gamma sqrt(r_f r_t) (2 + 1) (its fibre side doubled, the tooth's unchanged); dry, nothing changes.
        let (ei, rf, rt) = (7.59e-9, 46.55e-6, 0.6e-3);
        let v = Entanglement { span: 6.6e-3, ..Entanglement::default() };
        let b = Entanglement { wettability: 2.0, ..v };
        assert_eq!(b.parting_load(ei, rf, rt, 0.0, 0.1, 0.0), v.parting_load(ei, rf, rt, 0.0, 0.1, 0.0));
        let beam = v.parting_load(0.4 * ei, rf, rt, 0.0, 0.1, 0.0);
        let bridge = 2.0 * std::f64::consts::PI * 0.072 * (rf * rt).sqrt();
        for (e, c) in [(v, 1.0), (b, 2.0)] {
            for kappa in [0.0, 156.0] {
                // The wet share: the load wet less the same fibre's load dry.
                let want = e.peeled_neighbours * c * 0.144 * e.contact_length(rf, kappa) + bridge * (1.0 + c);
                let got = e.parting_load(0.4 * ei, rf, rt, 1.0, 0.1, kappa) - e.parting_load(0.4 * ei, rf, rt, 0.0, 0.1, kappa);
                assert!((got - want).abs() < 1e-12, "c = {c}, kappa = {kappa}: {got} vs {want}");
            }
        }
        // Virgin hair's load is the complete-wetting law, 4 pi gamma sqrt(r_f r_t) on the tooth.
        assert!((v.parting_load(0.4 * ei, rf, rt, 1.0, 0.1, 0.0) - (beam + v.peeled_neighbours * 0.144 * v.span + 2.0 * bridge)).abs() < 1e-15);
    }

    #[test]
    fn the_parting_load_is_the_beam_and_the_menisci() {
        // A span of 8 mm of H1 fibre (EI 7.59e-9 N m^2) around a 0.6 mm tooth (fibre radius 46.55 um): the central
        // load of a simply supported beam deflected by (r_t + r_f) / 2, 48 EI delta / L^3 = 0.230 mN; wet, plus
        // the crossed-cylinder meniscus 4 pi gamma sqrt(r_f r_t) = 0.151 mN (figures by hand, 1e-3 relative).
        let e = Entanglement { span: 8e-3, ..Default::default() };
        let (ei, rf, rt) = (7.59e-9, 46.55e-6, 0.6e-3);
        let beam = e.parting_load(ei, rf, rt, 0.0, 0.1, 0.0);
        assert!((beam - 0.2300e-3).abs() < 1e-3 * 0.23e-3, "{beam}");
        let wet = e.parting_load(0.4 * ei, rf, rt, 1.0, 0.1, 0.0);
        // Wet and straight: the softer beam, the adhesion to the 6 / pi neighbours over the whole span (0.144 N/m x
        // 8 mm x 1.9099 = 2.2002 mN) and the bridge on the tooth.
        assert!((wet - (0.4 * beam + 2.2002e-3 + 0.1511e-3)).abs() < 1e-3 * 0.15e-3, "{wet}");
        // At the tip nothing is left; a quarter span from it, half of everything.
        assert_eq!(e.parting_load(ei, rf, rt, 1.0, 0.0, 0.0), 0.0);
        assert!((e.parting_load(0.4 * ei, rf, rt, 1.0, 0.25 * e.span, 0.0) - 0.5 * wet).abs() < 1e-12 * wet);
        assert!((e.parting_load(ei, rf, rt, 0.0, 0.25 * e.span, 0.0) - 0.5 * beam).abs() < 1e-12 * beam);
        // The fibre's lateral stiffness over one span: 48 EI / L^3 = 0.7116 N/m (by hand), the beam's load per metre of deflection.
        assert!((e.fibre_stiffness(ei) - 0.71156).abs() < 1e-4, "{}", e.fibre_stiffness(ei));
        assert!((e.fibre_stiffness(ei) * 0.5 * (rf + rt) - beam).abs() < 1e-12 * beam);
        assert!(Entanglement { span: 0.0, ..e }.validate().unwrap_err().to_string().contains("entanglement.span"));
        assert!(Entanglement { adhesion: -1.0, ..e }.validate().unwrap_err().to_string().contains("entanglement.adhesion"));
        assert!(Entanglement { slip_speed: f64::NAN, ..e }.validate().unwrap_err().to_string().contains("entanglement.slip_speed"));
        assert!(Entanglement { wettability: -0.5, ..e }.validate().unwrap_err().to_string().contains("entanglement.wettability"));
        assert!(Entanglement { surface_tension: f64::NAN, ..e }.validate().is_err());
    }
}
