//! Parameters of hairstyle generation ([`HairstyleParams`]): every field with its meaning, unit and default.

use crate::error::GenerateError;
use crate::head::HeadParams;
use nalgebra::Vector3;
use strand::HairType;

/// Parameters of hairstyle generation. Every length in m.
#[derive(Debug, Clone, PartialEq)]
pub struct HairstyleParams {
    /// Hair type preset of the strand crate ([`HairType::by_name`]): fibre section, stiffness,
    /// density. Default "caucasian".
    pub hair_type: String,
    /// Hair length (arc length of a strand), m. Default 0.2 m.
    pub length: f64,
    /// Curliness in [0, 1] (see the module docs for the map to rest twist and bend). Default 0.
    pub curliness: f64,
    /// Number of guide strands (Super-Helices). Default 300.
    pub guide_count: usize,
    /// Helical segments per guide. Default 12.
    pub guide_segments: usize,
    /// Number of render strands. Default 100,000.
    pub render_count: usize,
    /// Vertices per render strand (root included), >= 2. Default 32.
    pub render_vertices: usize,
    /// Guides each render strand follows, 1 to 8. Default 3.
    pub guides_per_render: usize,
    /// Centreline samples per guide used to interpolate render strands, >= 2. Default 64.
    pub guide_samples: usize,
    /// Relative random shortening of render strands: length in [(1 - j) L, L]. Default 0.1.
    pub length_jitter: f64,
    /// Arc length over which a guide turns from the scalp normal to the scalp's tangent, m.
    /// Default 0.015 m (the hair stands about 1 cm off the scalp).
    pub lift: f64,
    /// Extra gap between the wrapped hair layer and the head, m. Default 0.003 m.
    pub clearance: f64,
    /// Direction (head frame, any length) from the head centre to the point hair is combed away
    /// from: a guide at p leaves the scalp along the projection of (p - |p| d) onto the scalp, so
    /// hair flows away from that point over the head. Default (0, 0.6, 0.8): 53 deg above the
    /// front, so that the sides and the back are combed down and back. Roots towards the face are
    /// combed along [`HairstyleParams::fringe_flow`] instead (blended over [`crate::groom::FLOW_FRONT_BLEND`]).
    pub flow: Vector3<f64>,
    /// Direction (head frame, any length) the front of the scalp is combed towards, for roots on
    /// the right (x >= 0; mirrored in x on the left): a centre parting, the fringe combed to the
    /// sides so that it frames the face instead of hanging over it (roots between the hairline and
    /// the `flow` point would otherwise be combed forwards, over the eyes). A root whose direction
    /// from the head centre has the forward (+y) component c is combed along
    /// `lerp(away from flow, fringe_flow, w)` with w = smoothstep([`crate::groom::FLOW_FRONT_BLEND`], c): w = 0 on
    /// the back half and the sides (the back hair is groomed by `flow` alone), 1 at the forehead.
    /// Default Some((1, -0.3, 0)): sideways and a little back. None: the front is combed away from
    /// `flow` like the rest of the scalp (the fringe falls over the face).
    pub fringe_flow: Option<Vector3<f64>>,
    /// Angle by which the hanging part of a guide leans outwards from the steepest descent,
    /// radians; increased in 5 degree steps (up to 50 degrees more) for a guide that would
    /// otherwise pass through the body. Default 5 deg.
    pub hang_tilt: f64,
    /// Largest curl radius drawn on render strands, m. Default 0.015 m.
    pub max_curl_amplitude: f64,
    /// Random seed; the same seed gives the same hairstyle. Default 1.
    pub seed: u64,
    /// The head.
    pub head: HeadParams,
}

impl Default for HairstyleParams {
    fn default() -> Self {
        Self {
            hair_type: "caucasian".into(),
            length: 0.2,
            curliness: 0.0,
            guide_count: 300,
            guide_segments: 12,
            render_count: 100_000,
            render_vertices: 32,
            guides_per_render: 3,
            guide_samples: 64,
            length_jitter: 0.1,
            lift: 0.015,
            clearance: 0.003,
            flow: Vector3::new(0.0, 0.6, 0.8),
            fringe_flow: Some(Vector3::new(1.0, -0.3, 0.0)),
            hang_tilt: 5f64.to_radians(),
            max_curl_amplitude: 0.015,
            seed: 1,
            head: HeadParams::default(),
        }
    }
}

impl HairstyleParams {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), GenerateError> {
        if HairType::by_name(&self.hair_type).is_none() {
            let names: Vec<&str> = HairType::ALL.iter().map(|h| h.name).collect();
            let reason = format!(
                "unknown preset {:?}; known: {}",
                self.hair_type,
                names.join(", ")
            );
            return Err(GenerateError::InvalidParameter {
                field: "hair_type",
                reason,
            });
        }
        // Each rule: (holds, field, what the field must be, the value given).
        let rules: [(bool, &'static str, &str, String); 15] = [
            (
                self.length > 0.0 && self.length <= 2.0,
                "length",
                "in (0, 2] m",
                format!("{}", self.length),
            ),
            (
                (0.0..=1.0).contains(&self.curliness),
                "curliness",
                "in [0, 1]",
                format!("{}", self.curliness),
            ),
            (
                (1..=100_000).contains(&self.guide_count),
                "guide_count",
                "in 1..=100000",
                format!("{}", self.guide_count),
            ),
            (
                (1..=256).contains(&self.guide_segments),
                "guide_segments",
                "in 1..=256",
                format!("{}", self.guide_segments),
            ),
            (
                self.render_count <= 10_000_000,
                "render_count",
                "at most 10,000,000",
                format!("{}", self.render_count),
            ),
            (
                (2..=1024).contains(&self.render_vertices),
                "render_vertices",
                "in 2..=1024",
                format!("{}", self.render_vertices),
            ),
            (
                (1..=8).contains(&self.guides_per_render)
                    && self.guides_per_render <= self.guide_count,
                "guides_per_render",
                "in 1..=8 and at most guide_count",
                format!("{}", self.guides_per_render),
            ),
            (
                (2..=4096).contains(&self.guide_samples),
                "guide_samples",
                "in 2..=4096",
                format!("{}", self.guide_samples),
            ),
            (
                (0.0..1.0).contains(&self.length_jitter),
                "length_jitter",
                "in [0, 1)",
                format!("{}", self.length_jitter),
            ),
            (
                self.lift > 0.0 && self.lift.is_finite(),
                "lift",
                "> 0 m",
                format!("{}", self.lift),
            ),
            (
                self.clearance >= 0.0 && self.clearance.is_finite(),
                "clearance",
                ">= 0 m",
                format!("{}", self.clearance),
            ),
            (
                self.flow.iter().all(|x| x.is_finite()) && self.flow.norm() > 0.0,
                "flow",
                "a finite non-zero vector",
                format!("{:?}", self.flow),
            ),
            (
                self.fringe_flow.is_none_or(|f| f.iter().all(|x| x.is_finite()) && f.norm() > 0.0),
                "fringe_flow",
                "a finite non-zero vector",
                format!("{:?}", self.fringe_flow),
            ),
            (
                self.hang_tilt.abs() <= std::f64::consts::FRAC_PI_2,
                "hang_tilt",
                "in [-pi/2, pi/2] rad",
                format!("{}", self.hang_tilt),
            ),
            (
                self.max_curl_amplitude >= 0.0 && self.max_curl_amplitude.is_finite(),
                "max_curl_amplitude",
                ">= 0 m",
                format!("{}", self.max_curl_amplitude),
            ),
        ];
        if let Some((_, field, rule, got)) = rules.into_iter().find(|r| !r.0) {
            return Err(GenerateError::InvalidParameter {
                field,
                reason: format!("must be {rule}, got {got}"),
            });
        }
        self.head.validate()?;
        Ok(())
    }

    /// The hair type preset.
    pub fn hair(&self) -> Result<HairType, GenerateError> {
        self.validate()?;
        Ok(HairType::by_name(&self.hair_type).expect("validated"))
    }
}
