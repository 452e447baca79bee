//! A patch of strands and a scripted tool, stepped at haptic rate.
//!
//! Pipeline of [`Scenario::run`]:
//! 1. build the patch: roots on a rectangle, small random tilts so that teeth meet hair as in a real tress;
//!    each strand hangs in its static equilibrium under gravity (a tress at rest on the rig, its curls opened by
//!    their weight as far as the wet or dry moduli let them) and stands for `represents` real fibres (from the
//!    tress's mass);
//! 2. wetness and treatment: the strands' material and the friction coefficients (tool-hair and hair-hair) from
//!    [`tools::wetness::WetnessModel`] at `[patch] wetness` and [`tools::treatment::Treatment`] at
//!    `[patch] treatment`, the same law as the live session's; the combing
//!    ease lowers both frictions by [`crate::params::HapticParams::combing_friction`], the live session's law;
//!    the comb drags through the wisps against the fibres it parts ([`tools::entanglement`]);
//! 3. settle the patch under gravity in the [`tools::interaction::LocalInteraction`] (hair-hair contacts on, the
//!    tool held at its path's start);
//! 4. every step move the tool along its path (coming up to speed over `[tool] ease_in`), step the interaction and record the force and torque on the
//!    tool, scaled by the number of real hairs each simulated strand stands for;
//! 5. summarise, with the stroke's quality figures ([`super::output::StrokeMetrics`]) and a combing rig's
//!    ([`super::combing`]: the force by the comb's position from the roots, the combing work, the work in each
//!    fifth of the tress length), for each stroke (`[tool] strokes`, [`super::strokes::StrokeCycle`]) and
//!    for all together.

use super::combing::{CombingFigures, CombingProfile, PerStroke};
use super::output::{ForceStats, ForceTrace, StrokeMetrics};
use super::strokes::StrokeCycle;
use super::{default_dt, ScenarioError};
use crate::params::HapticParams;
use crate::path::{ToolPath, Waypoint};
use nalgebra::Vector3;
use serde::Deserialize;
use strand::constraint::ConstraintOptions;
use strand::statics::{solve_equilibrium, StaticOptions};
use strand::{HairType, ModelKind, RootFrame, Strand, StrandError, StrandModel};
use tools::interaction::{Entanglement, ForceModel, HairContact, LocalInteraction};
use tools::shape::ToolShape;
use tools::treatment::{Contact, Treatment};
use tools::wetness::{check_wetness, WetnessModel};


/// A scenario file's contents (TOML; see docs/scenarios.md).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name (default: the file's stem).
    pub name: Option<String>,
    /// Simulated time after settling, s (default: the path's last time + 0.05 s).
    pub duration: Option<f64>,
    /// Haptic time step, s (default 0.001).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Settling time before the tool moves, s (default 0.5).
    #[serde(default = "default_settle")]
    pub settle: f64,
    /// The strands.
    pub patch: PatchSpec,
    /// The tool and its path.
    pub tool: ToolSpec,
}

fn default_settle() -> f64 {
    0.5
}

/// A patch (tress) of hanging strands.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchSpec {
    /// Hair type preset (default "H1").
    #[serde(default = "default_hair")]
    pub hair_type: String,
    /// "full" (default) or "reduced". Contact scenarios default to the full model: pushed sideways, the reduced
    /// model can only escape by twisting, whose tiny rotary inertia makes the contact response violent
    /// (see docs/physics.md, limits).
    #[serde(default = "default_model")]
    pub model: ModelKind,
    /// Number of simulated strands (default 16).
    #[serde(default = "default_strands")]
    pub strands: usize,
    /// Strand length, m (default 0.2).
    #[serde(default = "default_length")]
    pub length: f64,
    /// Segments per strand (default 12).
    #[serde(default = "default_segments")]
    pub segments: usize,
    /// Centre of the root rectangle, m (default [0, 0, 0.3]); strands hang down (-z).
    #[serde(default = "default_root")]
    pub root: [f64; 3],
    /// Extent of the root rectangle along x and y, m (default [0.01, 0.004]).
    #[serde(default = "default_extent")]
    pub extent: [f64; 2],
    /// Standard deviation of the random tilt of the root tangents, rad (default 0.05).
    #[serde(default = "default_tilt")]
    pub tilt: f64,
    /// Seed of the random layout (default 1): where the wisps are rooted, how their roots are tilted, and how each
    /// wisp's section is turned about its root tangent ([`Scenario::build_patch`]).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Real hairs each simulated strand stands for: forces are multiplied by it (default 1).
    #[serde(default = "default_represents")]
    pub represents: f64,
    /// Or: mass of the real (dry) tress, kg; sets `represents` to tress_mass / (strands x dry strand mass).
    pub tress_mass: Option<f64>,
    /// Wetness of the tress, 0 (dry, in equilibrium with ambient air) to 1 (towel-dried wet), dimensionless
    /// (default 0). Sets the strands' material and the friction through `tools::wetness::WetnessModel`.
    #[serde(default)]
    pub wetness: f64,
    /// Surface treatment of the hair: "virgin" (default), "conditioned", "bleached" or "bleached-twice"; scales
    /// the tool-hair and hair-hair friction, dry and wet, and wet, the capillary forces of the entanglement drag by
    /// its wettability (`tools::treatment::Treatment`, docs/treatment.md).
    #[serde(default)]
    pub treatment: Treatment,
    /// Contact and friction between the simulated strands, each a wisp of `represents` fibres
    /// (`tools::hair_contact`; default true).
    #[serde(default = "default_true")]
    pub hair_contact: bool,
    /// Packing fraction of the fibres in a wisp (dimensionless, (0, 1]; default `HairContact`'s, 0.5): sets
    /// the wisps' radius, hence the contact distance between strands.
    pub packing: Option<f64>,
    /// Dry fibre-fibre friction coefficient (dimensionless; default `HairContact`'s, 0.25).
    pub hair_friction: Option<f64>,
    /// The drag of the tool through the wisps, against the fibres it parts (`tools::entanglement`; default
    /// true).
    #[serde(default = "default_true")]
    pub entanglement: bool,
    /// Free length of a fibre between its entanglement points, m (default: `Entanglement::for_hair`'s for the hair
    /// type, 7.3 mm for H1 scaled with the fibre's size).
    pub entanglement_span: Option<f64>,
}

fn default_true() -> bool {
    true
}

fn default_hair() -> String {
    "H1".into()
}
fn default_model() -> ModelKind {
    ModelKind::Full
}
fn default_strands() -> usize {
    16
}
fn default_length() -> f64 {
    0.2
}
fn default_segments() -> usize {
    12
}
fn default_root() -> [f64; 3] {
    [0.0, 0.0, 0.3]
}
fn default_extent() -> [f64; 2] {
    [0.01, 0.004]
}
fn default_tilt() -> f64 {
    0.05
}
fn default_seed() -> u64 {
    1
}
fn default_represents() -> f64 {
    1.0
}

/// The tool of a scenario.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// Built-in shape name ("comb", "brush", "finger", "clip") or a shape file path relative to the scenario.
    pub shape: String,
    /// "constraint" (default) or "paper".
    #[serde(default = "default_force_model")]
    pub force_model: String,
    /// Gain of the paper's force model, m s (default 1).
    #[serde(default = "default_gain")]
    pub gain: f64,
    /// Dry tool-hair friction coefficient (default: the hair type's).
    pub friction: Option<f64>,
    /// Combing ease in [0, 1] (default 0): lowers the tool-hair and hair-hair friction as the live session's
    /// slider does ([`HapticParams::combing_friction`]).
    #[serde(default)]
    pub combing_ease: f64,
    /// Time the tool takes to come up to its path's speed from rest, s (default 0.04): the path's clock runs as
    /// `t^2 / (2 T)` for the first `T` seconds (uniform acceleration), then `t - T / 2`, so the path ends `T / 2`
    /// later. A rig's drive or a hand starts a stroke from rest (at 0.25 m/s, 0.04 s is 6 m/s^2); a tool thrown
    /// to speed in one step jerks every fibre it holds at once. 0: the path as written.
    #[serde(default = "default_ease_in")]
    pub ease_in: f64,
    /// Waypoints (time from the end of settling, s).
    #[serde(default)]
    pub path: Vec<Waypoint>,
    /// Or a CSV file `t,x,y,z[,rx,ry,rz]` relative to the scenario.
    pub path_file: Option<String>,
    /// Strokes: the path is played this many times, the tool returning to its start out of the hair between
    /// them ([`StrokeCycle`]; default 1, at most [`StrokeCycle::MAX_STROKES`]).
    #[serde(default = "default_strokes")]
    pub strokes: u32,
}

fn default_strokes() -> u32 {
    1
}

fn default_ease_in() -> f64 {
    0.04
}

/// The path's clock at time `t` (s) for a tool coming up to speed over `ease_in` s ([`ToolSpec::ease_in`]).
pub fn eased_time(t: f64, ease_in: f64) -> f64 {
    if ease_in <= 0.0 {
        t
    } else if t < ease_in {
        t * t / (2.0 * ease_in)
    } else {
        t - 0.5 * ease_in
    }
}

fn default_force_model() -> String {
    "constraint".into()
}
fn default_gain() -> f64 {
    1.0
}

/// One row of the force trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Time since the tool started, s.
    pub t: f64,
    /// Force on the tool, N (scaled by `represents`).
    pub force: Vector3<f64>,
    /// Torque on the tool about its origin, N m (scaled).
    pub torque: Vector3<f64>,
    /// Contacts this step.
    pub contacts: usize,
    /// Tool position, m.
    pub tool: Vector3<f64>,
    /// The stroke the tool is in (from 1; 0 while it returns between strokes).
    pub stroke: u32,
}

/// Summary of a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Largest force magnitude, N.
    pub peak_force_n: f64,
    /// Mean force magnitude over the steps with contact, N.
    pub mean_force_n: f64,
    /// Work done by the hand against the hair, `-sum F . dx`, J.
    pub work_j: f64,
    /// Steps with at least one contact.
    pub contact_steps: usize,
    /// Steps.
    pub steps: usize,
    /// Mass of the real tress represented, kg.
    pub tress_mass_kg: f64,
    /// Real hairs per simulated strand (the force scale).
    pub represents: f64,
    /// Wetness of the tress (dimensionless, 0..1).
    pub wetness: f64,
    /// Surface treatment of the hair.
    pub treatment: Treatment,
    /// Tool-hair friction coefficient used (after wetness, treatment and combing ease).
    pub tool_friction: f64,
    /// Hair-hair friction coefficient used (0 without hair contact).
    pub hair_friction: f64,
    /// Hair-hair contact distance between two strands' centrelines, m (0 without hair contact).
    pub hair_contact_distance_m: f64,
    /// The stroke's quality figures (peak, median, 90th percentile, continuity, largest step change), from the
    /// first to the last step with contact (all strokes).
    pub stroke: StrokeMetrics,
    /// The combing rig's figures of all the strokes together (work, peak, mean, fifths; serialised flat).
    #[serde(flatten)]
    pub combing: CombingFigures,
    /// Strokes played.
    pub strokes: u32,
    /// The combing rig's figures of each stroke.
    pub per_stroke: PerStroke,
    /// Strand-steps in which a strand's velocities were scaled down by the strand safety net (summed over the
    /// strands; not the device clamp, see `LiveSummary::clamp_steps`).
    pub strand_clamped_steps: u64,
    /// Wall time of the run, s (set by [`super::run_patch`]; 0 from [`Scenario::run`]).
    pub wall_time_s: f64,
}

/// Where the stream of the wisps' section orientations starts for a layout's seed: the seed xor this (an odd
/// 64-bit constant, PCG's multiplier), so that the roots and tilts drawn from the seed's own stream stay the
/// layouts they were.
const ORIENTATION_STREAM: u64 = 0x5851_F42D_4C95_7F2D;

/// splitmix64: a small deterministic generator for the patch layout.
fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E3779B97F4A7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

impl Scenario {
    /// Checks the values, naming the first bad key.
    pub fn validate(&self) -> Result<HairType, ScenarioError> {
        let bad = |m: String| Err(ScenarioError::Invalid(m));
        if !(self.dt.is_finite() && self.dt > 0.0 && self.dt <= 0.01) {
            return bad(format!("dt must be in (0, 0.01] s, got {}", self.dt));
        }
        if !(self.settle.is_finite() && self.settle >= 0.0) {
            return bad(format!("settle must be >= 0 s, got {}", self.settle));
        }
        if let Some(d) = self.duration {
            if !(d.is_finite() && d > 0.0 && d < 3600.0) {
                return bad(format!("duration must be in (0, 3600) s, got {d}"));
            }
        }
        let p = &self.patch;
        let hair = HairType::by_name(&p.hair_type).ok_or_else(|| ScenarioError::Invalid(format!("patch.hair_type: unknown {:?}", p.hair_type)))?;
        if p.strands == 0 || p.strands > 4096 {
            return bad(format!("patch.strands must be 1..4096, got {}", p.strands));
        }
        if !(p.tilt.is_finite() && p.tilt >= 0.0 && p.tilt < 1.0) {
            return bad(format!("patch.tilt must be in [0, 1) rad, got {}", p.tilt));
        }
        if !(p.represents.is_finite() && p.represents > 0.0) {
            return bad(format!("patch.represents must be > 0, got {}", p.represents));
        }
        if let Some(m) = p.tress_mass {
            if !(m.is_finite() && m > 0.0) {
                return bad(format!("patch.tress_mass must be > 0 kg, got {m}"));
            }
            if p.represents != 1.0 {
                return bad("give patch.represents or patch.tress_mass, not both".into());
            }
        }
        check_wetness("patch.wetness", p.wetness).map_err(|e| ScenarioError::Invalid(e.to_string()))?;
        check_wetness("tool.combing_ease", self.tool.combing_ease).map_err(|e| ScenarioError::Invalid(e.to_string().replace("wetness must be", "must be")))?;
        if let Some(k) = p.packing {
            if !(k.is_finite() && k > 0.0 && k <= 1.0) {
                return bad(format!("patch.packing must be in (0, 1], got {k}"));
            }
        }
        if let Some(l) = p.entanglement_span {
            if !(l.is_finite() && l > 0.0) {
                return bad(format!("patch.entanglement_span must be > 0 m, got {l}"));
            }
        }
        if let Some(mu) = p.hair_friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return bad(format!("patch.hair_friction must be >= 0, got {mu}"));
            }
        }
        if !p.root.iter().chain(p.extent.iter()).all(|x| x.is_finite()) || p.extent.iter().any(|x| *x < 0.0) {
            return bad("patch.root and patch.extent must be finite (extent >= 0)".into());
        }
        match self.tool.force_model.as_str() {
            "constraint" | "paper" => {}
            other => return bad(format!("tool.force_model must be \"constraint\" or \"paper\", got {other:?}")),
        }
        if !(self.tool.ease_in.is_finite() && (0.0..=1.0).contains(&self.tool.ease_in)) {
            return bad(format!("tool.ease_in must be in [0, 1] s, got {}", self.tool.ease_in));
        }
        if !(self.tool.gain.is_finite() && self.tool.gain >= 0.0) {
            return bad(format!("tool.gain must be >= 0, got {}", self.tool.gain));
        }
        if let Some(mu) = self.tool.friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return bad(format!("tool.friction must be >= 0, got {mu}"));
            }
        }
        if !(1..=StrokeCycle::MAX_STROKES).contains(&self.tool.strokes) {
            return bad(format!("tool.strokes must be 1..={}, got {}", StrokeCycle::MAX_STROKES, self.tool.strokes));
        }
        Ok(hair)
    }

    /// The strands of the patch, hanging at rest: each in its stable static equilibrium under gravity
    /// (`strand::statics::solve_equilibrium`), with the material of the tress's wetness (a wet curl hangs
    /// longer: its bending and torsion moduli are lower and it is heavier, `tools::wetness`).
    ///
    /// Each wisp's material frame is turned about its root tangent by its own angle, uniform in [0, 2 pi), drawn
    /// from a second stream of the layout's seed ([`ORIENTATION_STREAM`]): the fibres of a real tress lie with
    /// their elliptical sections turned every way about their axes, and a wavy or curly wisp's rest shape (a helix
    /// of the preset's curvature and twist in the material frame) then waves in its own plane and phase. With one
    /// frame for all (the major axis towards +x, before 2026-11-30) every wavy wisp waved in one plane and phase
    /// and the whole tress leaned one way (docs/combing.md, "Why caucasian's force halves").
    pub fn build_patch(&self) -> Result<Vec<Strand>, ScenarioError> {
        let hair = self.validate()?;
        let p = &self.patch;
        let inv = |e: StrandError| ScenarioError::Invalid(format!("patch: {e}"));
        let (tw, bd) = hair.rest_curvature();
        let wet = WetnessModel::default().hair(&hair, p.wetness).map_err(|e| ScenarioError::Invalid(format!("patch: {e}")))?;
        let model = StrandModel::new(p.model, p.length, p.segments, hair.section().map_err(inv)?, wet.material())
            .map_err(inv)?
            .with_uniform_rest(tw, bd, 0.0);
        let mut rng = p.seed;
        let mut spin = p.seed ^ ORIENTATION_STREAM;
        (0..p.strands)
            .map(|_| {
                let x = p.root[0] + (splitmix(&mut rng) - 0.5) * p.extent[0];
                let y = p.root[1] + (splitmix(&mut rng) - 0.5) * p.extent[1];
                let ang = 2.0 * std::f64::consts::PI * splitmix(&mut rng);
                let tilt = p.tilt * (-2.0 * splitmix(&mut rng).max(1e-300).ln()).sqrt() * 0.5f64.sqrt();
                let tangent = Vector3::new(tilt * ang.cos(), tilt * ang.sin(), -1.0);
                let turn = 2.0 * std::f64::consts::PI * splitmix(&mut spin);
                let n1 = (Vector3::x() - tangent * tangent.dot(&Vector3::x()) / tangent.norm_squared()).normalize();
                let n2 = tangent.normalize().cross(&n1);
                let root = RootFrame::new(Vector3::new(x, y, p.root[2]), tangent, n1 * turn.cos() + n2 * turn.sin()).map_err(inv)?;
                let mut strand = Strand::new(model.clone(), root).map_err(inv)?;
                // Hanging at rest: the stable static equilibrium under gravity of the wisp's model at its wetness
                // (moduli and mass), as a tress hangs on a rig before the comb comes; its natural shape if the
                // solve finds none (then the settle takes it down).
                if let Ok(eq) = solve_equilibrium(&strand.model, &strand.state, &[], &StaticOptions::default()) {
                    if eq.stable {
                        strand.state.q = eq.q;
                    }
                }
                Ok(strand)
            })
            .collect()
    }

    /// The tool's path played `[tool] strokes` times, with the returns between strokes.
    pub fn stroke_cycle(&self, shape: &ToolShape, path: &ToolPath) -> Result<StrokeCycle, ScenarioError> {
        let p = &self.patch;
        StrokeCycle::new(path.clone(), self.tool.strokes, [p.root[0], p.root[1]], StrokeCycle::clearance(shape, p.extent)).map_err(ScenarioError::Invalid)
    }

    /// The comb's position from the roots along the tress (m) when the tool is at `tool`: the strands hang
    /// down (-z) from the roots' height.
    pub fn position_along(&self, tool: &Vector3<f64>) -> f64 {
        self.patch.root[2] - tool.z
    }

    /// A combing rig's recording of `rows` (a run's trace): the steps of each stroke, the comb's position from
    /// the roots and the force's magnitude.
    pub fn profile(&self, rows: &[TraceRow]) -> CombingProfile {
        let mut out = CombingProfile::default();
        for r in rows.iter().filter(|r| r.stroke > 0) {
            out.push(r.stroke, r.t, self.position_along(&r.tool), r.force.norm());
        }
        out
    }

    /// Runs the scenario with the tool's shape and path (loaded by the caller). Deterministic.
    pub fn run(&self, shape: ToolShape, path: &ToolPath) -> Result<(Vec<TraceRow>, Summary), ScenarioError> {
        let hair = self.validate()?;
        let strands = self.build_patch()?;
        let cycle = self.stroke_cycle(&shape, path)?;
        let p = &self.patch;
        let wet_model = WetnessModel::default();
        let wet_error = |e: tools::wetness::WetnessError| ScenarioError::Invalid(format!("patch: {e}"));
        // Fibres each strand stands for, from the dry mass (water adds mass, not fibres).
        let mass_factor = wet_model.mass_factor(p.wetness).map_err(wet_error)?;
        let dry_mass = strands.iter().map(|s| s.model.mass()).sum::<f64>() / mass_factor;
        let k = match p.tress_mass {
            Some(m) => m / dry_mass,
            None => p.represents,
        };
        let tress_mass = dry_mass * k;
        // Frictions: wetness and treatment, then combing ease (the live session's laws).
        let ease = HapticParams::default();
        let tool_dry = self.tool.friction.unwrap_or(hair.friction_coefficient());
        let tool_friction = ease.combing_friction(p.treatment.friction(&wet_model, Contact::Tool, tool_dry, p.wetness).map_err(wet_error)?, self.tool.combing_ease);
        let model = match self.tool.force_model.as_str() {
            "paper" => ForceModel::Paper { gain: self.tool.gain },
            _ => ForceModel::Constraint { friction: tool_friction, options: ConstraintOptions::default() },
        };
        let mut it = LocalInteraction::new(strands, shape, path.pose(0.0), model);
        let mut hair_friction = 0.0;
        let mut hair_contact_distance = 0.0;
        if p.hair_contact {
            let d = HairContact::default();
            let dry = p.hair_friction.unwrap_or(d.friction);
            hair_friction = ease.combing_friction(p.treatment.friction(&wet_model, Contact::Fibre, dry, p.wetness).map_err(wet_error)?, self.tool.combing_ease);
            let hc = HairContact { fibres: k.max(1.0), packing: p.packing.unwrap_or(d.packing), friction: hair_friction, ..d };
            hair_contact_distance = hc.distance(hair.major_diameter / 2.0);
            it.params.hair_contact = Some(hc);
        }
        if p.entanglement {
            // The span between entanglement points scaled with the fibre's size (`Entanglement::for_hair`) unless
            // given; the treatment's wettability: its capillary forces over virgin hair's (`Treatment::wettability`).
            let d = Entanglement::for_hair(&hair);
            it.params.entanglement = Some(Entanglement { span: p.entanglement_span.unwrap_or(d.span), wettability: p.treatment.wettability(), ..d });
            it.wetness = vec![p.wetness; it.strands.len()];
        }
        // Settle under gravity (and the strands' contacts), the tool held at its start.
        let settle_steps = (self.settle / self.dt).round() as usize;
        for n in 0..settle_steps {
            it.step(self.dt, path.pose(0.0)).map_err(|e| ScenarioError::Simulation { time: -self.settle + n as f64 * self.dt, source: e })?;
        }
        let ease = self.tool.ease_in;
        let duration = self.duration.unwrap_or(cycle.end_time() + 0.5 * ease + 0.05);
        let steps = (duration / self.dt).round() as usize;
        let mut rows = Vec::with_capacity(steps);
        let mut work = 0.0;
        let mut last = path.pose(0.0).position;
        for n in 1..=steps {
            let t = n as f64 * self.dt;
            let (pose, stroke) = cycle.pose(eased_time(t, ease));
            let r = it.step(self.dt, pose).map_err(|e| ScenarioError::Simulation { time: t, source: e })?;
            let force = r.force * k;
            work -= force.dot(&(pose.position - last));
            last = pose.position;
            rows.push(TraceRow { t, force, torque: r.torque * k, contacts: r.contacts.len(), tool: pose.position, stroke });
        }
        let mut trace = ForceTrace::default();
        for r in &rows {
            trace.push(r.t, &r.force, &r.torque, r.contacts as u32, &r.tool);
        }
        let stats = ForceStats::of(rows.iter().map(|r| (r.force.norm(), r.contacts > 0)), f64::INFINITY);
        let strokes = self.profile(&rows).strokes(p.length);
        let summary = Summary {
            peak_force_n: stats.peak,
            mean_force_n: stats.mean_in_contact,
            work_j: work,
            contact_steps: stats.contact_steps,
            steps,
            tress_mass_kg: tress_mass,
            represents: k,
            wetness: p.wetness,
            treatment: p.treatment,
            tool_friction,
            hair_friction,
            hair_contact_distance_m: hair_contact_distance,
            stroke: StrokeMetrics::of(&trace),
            combing: CombingFigures::total(&strokes),
            strokes: self.tool.strokes,
            per_stroke: PerStroke::of(&strokes),
            strand_clamped_steps: it.strands.iter().map(|s| s.clamped_steps).sum(),
            wall_time_s: 0.0,
        };
        Ok((rows, summary))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENARIO: &str = r#"
        dt = 0.001
        settle = 0.1
        [patch]
        hair_type = "GC3"
        strands = 6
        length = 0.1
        segments = 8
        [tool]
        shape = "comb"
        path = [ { t = 0.0, position = [0.0, -0.012, 0.29], rotation = [1.5707963, 0.0, 0.0] },
                 { t = 0.2, position = [0.0, -0.012, 0.24], rotation = [1.5707963, 0.0, 0.0] } ]
    "#;

    fn parse(text: &str) -> (Scenario, ToolPath) {
        let s: Scenario = toml_from_str(text);
        let p = ToolPath::new(s.tool.path.clone()).unwrap();
        (s, p)
    }

    fn toml_from_str(text: &str) -> Scenario {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn a_scripted_stroke_is_deterministic() {
        let (s, p) = parse(SCENARIO);
        let a = s.run(ToolShape::builtin("comb").unwrap(), &p).unwrap();
        let b = s.run(ToolShape::builtin("comb").unwrap(), &p).unwrap();
        assert_eq!(a.0, b.0, "same trace twice, to the bit");
        assert!(a.1.contact_steps > 0, "the comb met the hair");
        assert!(a.1.peak_force_n > 0.0);
        assert_eq!(a.1.steps, 270, "0.2 s of path, 0.02 s later for the ease-in, and 0.05 s");
    }

    #[test]
    fn the_treatment_key_sets_both_frictions_by_the_one_law() {
        // `[patch] treatment` goes through `Treatment::friction` for the tool (the hair type's coefficient) and
        // for hair on hair (HairContact's 0.25), dry and wet; virgin is the default and the untreated law; a bad
        // name is refused naming the key's value.
        use super::super::run::{run, ScenarioFile, ScenarioSummary};
        let model = WetnessModel::default();
        let mu = HairType::GC3.friction_coefficient();
        for (name, t) in [("virgin", Treatment::Virgin), ("conditioned", Treatment::Conditioned), ("bleached", Treatment::Bleached), ("bleached-twice", Treatment::BleachedTwice)] {
            for w in [0.0, 1.0] {
                let text = SCENARIO.replace("segments = 8", &format!("segments = 8\nwetness = {w}\ntreatment = \"{name}\""));
                let ScenarioSummary::Patch(s) = run(&ScenarioFile::from_toml(&text).unwrap()).unwrap().summary else { panic!("not a patch summary") };
                assert_eq!(s.treatment, t);
                assert_eq!(s.tool_friction, t.friction(&model, Contact::Tool, mu, w).unwrap(), "{name} {w}");
                assert_eq!(s.hair_friction, t.friction(&model, Contact::Fibre, 0.25, w).unwrap(), "{name} {w}");
            }
        }
        let (s, _) = parse(SCENARIO);
        assert_eq!(s.patch.treatment, Treatment::Virgin);
        let e = ScenarioFile::from_toml(&SCENARIO.replace("segments = 8", "segments = 8\ntreatment = \"permed\"")).unwrap_err().to_string();
        assert!(e.contains("permed") && e.contains("bleached-twice"), "{e}");
    }

    #[test]
    fn a_wavy_tress_hangs_centred_under_its_roots() {
        // Each wisp's section is turned about its root tangent by its own angle (`build_patch`), so the wisps of a
        // wavy tress wave in their own planes and phases: hanging at rest, each wisp's lower half leans off its root
        // by the wave (caucasian: curl radius 4.4 cm, pitch 15 cm), every way, and the tress's mean stays near
        // under the roots. One frame for all made every wisp lean the same way (the mean lean as large as each
        // wisp's: the tress leaned 11 mm at 16 cm, out of the comb's teeth). Six layouts of the suite's tress.
        for seed in 1..=6 {
            let (mut s, _) = parse(SCENARIO);
            s.patch = PatchSpec { hair_type: "caucasian".into(), strands: 24, length: 0.2, segments: 12, extent: [0.012, 0.004], seed, ..s.patch };
            let strands = s.build_patch().unwrap();
            // Each wisp's horizontal offset from its root averaged over the lower half of its length, m.
            let leans: Vec<Vector3<f64>> = strands
                .iter()
                .map(|st| {
                    let c = strand::kinematics::centerline(&st.model, &st.state, 21);
                    let lower = &c[10..];
                    let mean = lower.iter().map(|(_, x)| x - c[0].1).sum::<Vector3<f64>>() / lower.len() as f64;
                    Vector3::new(mean.x, mean.y, 0.0)
                })
                .collect();
            let each = leans.iter().map(|v| v.norm()).sum::<f64>() / leans.len() as f64;
            let tress = (leans.iter().sum::<Vector3<f64>>() / leans.len() as f64).norm();
            assert!(each > 5e-3, "layout {seed}: the wave leans each wisp off its root ({:.1} mm)", each * 1e3);
            assert!(tress < 0.5 * each, "layout {seed}: the tress leans {:.1} mm, its wisps {:.1} mm each", tress * 1e3, each * 1e3);
        }
    }

    #[test]
    fn bad_values_are_named() {
        let (mut s, _) = parse(SCENARIO);
        s.patch.hair_type = "yeti".into();
        assert!(s.validate().unwrap_err().to_string().contains("patch.hair_type"));
        let (mut s, _) = parse(SCENARIO);
        s.tool.force_model = "magic".into();
        assert!(s.validate().unwrap_err().to_string().contains("tool.force_model"));
        let (mut s, _) = parse(SCENARIO);
        s.dt = f64::NAN;
        assert!(s.validate().unwrap_err().to_string().contains("dt"));
    }
}
