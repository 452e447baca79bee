//! Parameters of a live session: [`SessionParams`] (rates, active set, device, tools' rates) with the
//! constants of the haptic step ([`HapticParams`]) and of the global step ([`GlobalParams`]); every field
//! with its meaning, unit and default.

pub use crate::budget::BudgetParams;
use crate::error::SessionError;
use crate::record::params::RecordParams;
use haptics::device::DeviceProfile;
use haptics::target::TargetParams;

/// Where the session's device readings come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InputKind {
    /// A pointer (the browser's mouse): sparse events, interpolated with [`SessionParams::pointer`].
    #[default]
    Pointer,
    /// A haptic device streaming poses (`coiffure serve --device`): followed with
    /// [`SessionParams::device_follow`]; when its stream is lost (no reading) the tool stops and the next
    /// reading re-anchors device, proxy and tool where the device is, at rest.
    Device,
}

/// How the tool follows a streaming device's samples: extrapolated on the device's own clock at the velocity
/// of its time-stamped samples (`haptics::target`, `TargetParams::stream`), so that a device slower than the
/// loop, or jitter in the packets' arrival, gives no velocity steps to the coupling's damper. Interval bounds
/// 0.00025-0.05 s (4 kHz to 20 Hz devices; a gap over 0.05 s restarts at rest), largest speed 5 m/s (the
/// profiles' hand speed), largest acceleration 1000 m/s^2 (follows a hand at 2 m/s sampled at 1 kHz without
/// lag beyond one interval); the running-mean weight 0.2 is a pointer's.
pub const DEVICE_FOLLOW: TargetParams = TargetParams { min_interval: 0.00025, max_interval: 0.05, smoothing: 0.2, max_speed: 5.0, max_acceleration: 1000.0, stream: true };

/// Parameters of a live session. Defaults: the README's `coiffure serve`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionParams {
    /// Physics rate of the haptic layer (the local strands' step, which publishes the local force model), Hz
    /// (at most 4000). Default 1000.
    pub haptic_rate_hz: f64,
    /// Device loop rate, Hz: the coupling renders the local force model at this rate
    /// (`crate::haptic::device_side`), a whole number of device steps per physics step
    /// ([`SessionParams::device_steps`]), at most 10 000. Default 4000 (crisp stiff contact needs 5-10 kHz,
    /// Choi and Tan 2004; 4 kHz is what a loaded 2-core machine sustains, bench/RESULTS.md).
    pub device_rate_hz: f64,
    /// Global (lattice) step rate, Hz. Default 100.
    pub global_rate_hz: f64,
    /// Most guide strands chosen near the tool's path at once (`crate::haptic` active set). Default 48: enough
    /// strands around a comb for a continuous force (issue 12).
    pub max_chosen: usize,
    /// Most guide strands simulated at once: the chosen ones and those still relaxing after they left (the
    /// relaxing ones whose hair drawn is nearest its carried place are let go first beyond it, handed over to the
    /// global layer where they are), >= `max_chosen`. Bounds the haptic
    /// step's cost. Default 56 (64 before the hold of the neighbours, `HapticParams::hold_distance`, made a step
    /// with the comb in the hair dearer; 56 keeps the mean step where 64 had it: docs/physics.md, step costs in
    /// bench/RESULTS.md).
    pub max_active: usize,
    /// A guide joins the active set when its settled shape comes within this distance of the tool's shape
    /// (its capsules) on its way over the next `HapticParams::lookahead` s, m. Default 0.03.
    pub activation_radius: f64,
    /// Device limits. Default: a Phantom Omni (3.3 N, 300 N/s), also for the mouse, whose force is shown.
    pub profile: DeviceProfile,
    /// How the device point follows a pointer's target (the mouse reports at 60-125 Hz): interpolated at the
    /// haptic rate between events. Default `haptics::target::TargetParams::default()` (event-interval bounds 0.004-0.05 s,
    /// running-mean weight 0.2, largest speed 1.5 m/s, largest acceleration 1 m/s^2: a jump of the mouse
    /// target, e.g. when the button presses the tool into the hair, never throws the proxy).
    pub pointer: TargetParams,
    /// Where the device readings come from. Default [`InputKind::Pointer`] (`coiffure serve --device`:
    /// [`InputKind::Device`]).
    pub input: InputKind,
    /// How the tool follows a streaming device ([`InputKind::Device`]). Default [`DEVICE_FOLLOW`].
    pub device_follow: TargetParams,
    /// Haptic steps between two snapshots published for the viewer. Default 5 (200 Hz).
    pub publish_every: u64,
    /// How a recorded session's record is streamed to disk (`crate::record::stream`; recording itself is asked
    /// for by giving `Session::start_recording` a file). Default [`RecordParams::default`].
    pub record: RecordParams,
    /// Sprayer wetting rate s0 at the nozzle (`tools::sprayer::Sprayer`), 1/s. Default 1.
    pub wetting_rate: f64,
    /// Dryer drying rate k0 at the nozzle (`tools::dryer::HairDryer`), 1/s. Default 0.05.
    pub drying_rate: f64,
    /// Real hairs each render strand stands for, dimensionless, > 0. Default 1 (the built-in hairstyle draws
    /// 100 000 render strands, about the number of hairs on a head). Each simulated guide stands for the real
    /// hairs bound to it, `render strands x hairs_per_render_strand / guides` (500 in the built-in scene), and
    /// the local strands' reaction on the tool (force and damping) is multiplied by that number.
    pub hairs_per_render_strand: f64,
    /// Real-time (`SCHED_FIFO`) priority asked for the haptic thread, 1..=99 (`haptics::realtime`), or None
    /// for normal priority. A refusal (no permission) is logged and the loop runs at normal priority.
    /// Default None (`coiffure serve` asks for 10).
    pub haptic_priority: Option<i32>,
    /// Hold every CPU's wake-up latency at 0 while the session runs (`haptics::realtime::hold_cpu_latency`, Linux PM
    /// QoS): idle CPUs poll instead of halting, so that the device loop's timer wakes it on time. A refusal (no
    /// permission) is logged and the session runs without it. Default false (`coiffure serve` holds it unless
    /// `--no-cpu-latency-hold`).
    pub cpu_latency_hold: bool,
    /// Constants of the haptic step. Default [`HapticParams::default`].
    pub haptic: HapticParams,
    /// Constants of the global step. Default [`GlobalParams::default`].
    pub global: GlobalParams,
    /// The live haptic thread's strand budget (`crate::budget`): fewer strands simulated while the steps run
    /// long on this machine. Default [`BudgetParams::default`] (on; headless runs and replays never time
    /// their steps).
    pub budget: BudgetParams,
}

impl Default for SessionParams {
    fn default() -> Self {
        Self { haptic_rate_hz: 1000.0, device_rate_hz: 4000.0, global_rate_hz: 100.0, max_chosen: 48, max_active: 56, activation_radius: 0.03, profile: DeviceProfile::PHANTOM_OMNI, pointer: TargetParams::default(), input: InputKind::Pointer, device_follow: DEVICE_FOLLOW, publish_every: 5, record: RecordParams::default(), wetting_rate: 1.0, drying_rate: 0.05, hairs_per_render_strand: 1.0, haptic_priority: None, cpu_latency_hold: false, haptic: HapticParams::default(), global: GlobalParams::default(), budget: BudgetParams::default() }
    }
}

/// Fastest device loop, Hz (`SessionParams::device_rate_hz`).
pub const MAX_DEVICE_RATE_HZ: f64 = 10_000.0;

impl SessionParams {
    /// Device steps per physics step: `device_rate_hz / haptic_rate_hz` (a whole number, >= 1).
    pub fn device_steps(&self) -> usize {
        ((self.device_rate_hz / self.haptic_rate_hz).round() as usize).max(1)
    }

    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        let p = |m: String| Err(SessionError::Param(m));
        if !(self.haptic_rate_hz > 0.0 && self.haptic_rate_hz <= haptics::haptic_loop::MAX_RATE_HZ) {
            return p(format!("haptic_rate_hz must be in (0, 4000], got {}", self.haptic_rate_hz));
        }
        let n = self.device_rate_hz / self.haptic_rate_hz;
        if !(self.device_rate_hz <= MAX_DEVICE_RATE_HZ && n >= 1.0 - 1e-9 && (n - n.round()).abs() <= 1e-9 * n) {
            return p(format!("device_rate_hz must be a whole multiple of haptic_rate_hz ({} Hz) up to {MAX_DEVICE_RATE_HZ} Hz, got {}", self.haptic_rate_hz, self.device_rate_hz));
        }
        if !(self.global_rate_hz > 0.0 && self.global_rate_hz <= 1000.0) {
            return p(format!("global_rate_hz must be in (0, 1000], got {}", self.global_rate_hz));
        }
        if self.max_chosen == 0 || self.max_active < self.max_chosen {
            return p(format!("max_chosen must be > 0 and max_active >= max_chosen, got {} and {}", self.max_chosen, self.max_active));
        }
        if !(self.activation_radius > 0.0 && self.wetting_rate >= 0.0 && self.drying_rate >= 0.0 && self.wetting_rate.is_finite() && self.drying_rate.is_finite()) {
            return p(format!("activation_radius must be > 0 and wetting_rate, drying_rate finite and >= 0: {self:?}"));
        }
        for (k, t) in [("pointer", &self.pointer), ("device_follow", &self.device_follow)] {
            if !(t.min_interval > 0.0 && t.max_interval >= t.min_interval && t.max_interval.is_finite() && t.smoothing > 0.0 && t.smoothing <= 1.0 && t.max_speed > 0.0 && t.max_speed.is_finite() && t.max_acceleration > 0.0 && t.max_acceleration.is_finite()) {
                return p(format!("{k}: need 0 < min_interval <= max_interval (finite), smoothing in (0, 1], max_speed and max_acceleration > 0 finite, got {t:?}"));
            }
        }
        if !(self.hairs_per_render_strand > 0.0 && self.hairs_per_render_strand.is_finite()) {
            return p(format!("hairs_per_render_strand must be finite and > 0, got {}", self.hairs_per_render_strand));
        }
        if self.publish_every == 0 {
            return p("publish_every must be > 0".into());
        }
        if let Some(prio) = self.haptic_priority.filter(|x| !haptics::realtime::PRIORITY_RANGE.contains(x)) {
            return p(format!("haptic_priority must be in 1..=99, got {prio}"));
        }
        self.haptic.validate()?;
        self.budget.validate()?;
        self.record.validate()?;
        self.global.validate()
    }
}

/// Constants of the haptic layer's step (`crate::haptic`), each with its meaning, unit and default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HapticParams {
    /// Runaway guard: a tool proxy farther than this from the device point (or non-finite) is put back on
    /// the device at rest with zero force, and counted (`HapticCore::runaways`), m. Far more than the
    /// coupling ever stretches in use (the proxy held on the scalp while the pointer's target is at the
    /// head's centre: 9 cm); the audit saw proxies at 65 km and 1e38 m. Default 0.2.
    pub max_proxy_lag: f64,
    /// The active set is chosen again when the tool has moved this far since the last choice, m.
    /// Default 0.01.
    pub reselect_distance: f64,
    /// Haptic steps one choice of the active set is spread over (each step scans an equal share of the guides,
    /// so that no step pays for the whole scan; `crate::haptic` active set), >= 1. Default 10 (10 ms at 1 kHz,
    /// far less than `lookahead`).
    pub choice_steps: usize,
    /// Most guides that join the active set in one haptic step: the guides a finished choice adds join in
    /// turns, nearest first, from the step after the scan ended (a joining strand's set-up is paid in the step
    /// it joins; a choice adds up to `max_chosen`), >= 1. Default 4 (48 guides join within 12 ms, far less than
    /// `lookahead`).
    pub joins_per_step: usize,
    /// The clip pins the strand point nearest its jaws if it is within this distance, m. Default 0.01.
    pub clip_reach: f64,
    /// Displacements of the local strands from their references larger than this are not sent to the
    /// viewer (zero instead: a misbehaving strand must not throw the hairstyle across the scene), m.
    /// Default 0.5.
    pub max_displacement: f64,
    /// Air drag per unit length of the simulated strands (and of the hair the lattice carries), N s/m^2;
    /// the strands' own value is raised to it. Default 2e-5, twice `strand::DEFAULT_AIR_DRAG`: the local
    /// strands stand for wisps whose hairs shield each other less than they drag together, and the extra
    /// drag damps the strands the tool throws about.
    pub min_air_drag: f64,
    /// How much the combing-ease slider lowers the friction: friction = mu (1 - reduction x ease),
    /// ease in [0, 1] ([`combing_friction`]). Dimensionless in [0, 1). Default 0.8.
    pub combing_ease_reduction: f64,
    /// Pieces of each simulated strand the dryer's air drag is applied to (at their midpoints). Default 8.
    pub dryer_pieces: usize,
    /// The held scissors cut again each time they have moved this far, m. Default 0.02.
    pub snip_distance: f64,
    /// Collision pieces of a guide cut by the scissors (`hairstyle::cut::cut_guide`). Default 4.
    pub cut_pieces: usize,
    /// Where the tool waits before the first device reading (head frame), m. Default (0, -0.25, 0).
    pub start: [f64; 3],
    /// The active set is chosen around the tool's path over the next `lookahead` s (its position and
    /// velocity now), so that strands join before the tool reaches them, s. Default 0.1.
    pub lookahead: f64,
    /// A strand that left the active set is still simulated until its tip has moved slower than this for
    /// `rest_time`, m/s. Default 0.02.
    pub rest_speed: f64,
    /// How long a leaving strand's tip must stay slower than `rest_speed` to count as at rest, s.
    /// Default 0.2.
    pub rest_time: f64,
    /// A leaving strand is let go (handed over to the global layer, which carries its displacement from where the
    /// head and the lattice carry its guide and brings it back by the hold: `HapticCore::handed`) once at rest and
    /// with every sample within this distance of that carried place, so that what the global layer takes over is
    /// at most this: the strand falls back by its own dynamics (its rest shape, the hold of the neighbours), m. Default
    /// 0.002: under the width of the wisp a guide stands for (twice the wisp's radius, the hair-hair contact
    /// distance `HairContact::distance`: 2.5 mm for 500 Caucasian fibres), so the guide drawn stays inside its
    /// own wisp across the hand-over. A strand not back in place within `max_relax_time` is let go all the same
    /// (an early hand-over, measured apart: `HapticCore::early_handovers`).
    pub handover_distance: f64,
    /// A leaving strand not back in place (`handover_distance`) this long after it left is let go wherever it
    /// is (an early hand-over: the global layer takes its displacement over, the hair drawn does not move, and
    /// the hold brings it back in about 0.3 s), s. Default 1.5: within issue 30's 2.3 s after a dryer stops. A
    /// critically damped hold brings most strands
    /// back within `handover_distance` well before; what is still off then is mostly held by its contact with
    /// other local strands (wisps blown across each other: issue 30, docs/scenarios.md). How many strands go
    /// early and how far off, at this and at 0.6 s: bench/RESULTS.md, the hand-over rows.
    pub max_relax_time: f64,
    /// A strand let go whose tip is farther than this from its groomed tip returns to its groomed shape in the
    /// store (what it joins from next time; the hair drawn is the global layer's), m. Default 0.005.
    pub rest_distance: f64,
    /// The displacement shown of a strand fades in over this time when it joins the active set, s (and, with
    /// no hold, `hold_distance` infinite, a handed-over guide's displacement fades out over it). Default 0.3.
    pub blend_time: f64,
    /// The ends of the tool's capsules stay this far outside the body (head, neck, shoulders), m: the teeth
    /// ride on the hair near the scalp and never reach the roots. Default 0.004.
    pub body_clearance: f64,
    /// Share of the rest shape a wet set holds once dry (`strand::styling::SetModel::hydrogen_share`),
    /// dimensionless in [0, 1]. Default 0.8.
    pub hydrogen_share: f64,
    /// The local strands touch each other (contact and Coulomb friction, `tools::hair_contact`; each guide a
    /// wisp of the real hairs it stands for, `HapticCore::hair_contact`; each contact solved for both strands
    /// together). Default true (since every groomed guide is a stable equilibrium, issue 12; what the `[live]`
    /// acceptance stroke, live-comb.toml, gives with it: docs/scenarios.md, "The live comb stroke", and
    /// bench/RESULTS.md).
    pub hair_contact: bool,
    /// Guides that overlap in the groom keep that overlap: two local strands closer than their contact
    /// distance in their groomed shapes touch only closer than their groomed distance (`tools::hair_contact`'s
    /// rest shapes, set when a strand joins the simulation). The groomed guides are independent curves and
    /// some pairs of the built-in groom lie closer than the contact distance; pushed apart they moved guides by
    /// centimetres with a dryer held still beside the hair (issue 12; bench/RESULTS.md, the dryer-held-still
    /// row). Default true.
    pub groomed_overlap: bool,
    /// The tool drags through the local strands against the fibres it parts (`tools::entanglement`, the tress
    /// scenarios' law: bending of the parted fibres and, wet, the water bridges on the tooth; each guide's
    /// drag times the real hairs it stands for). Default true: the `[live]` strokes meet issue 12's acceptance
    /// with it on caucasian and African hair (strokes towards the roots within the bound of a drag, the comb's
    /// travel: a tooth drawn towards the roots drags the parted fibres up with it, as backcombing does); its cost in
    /// the device loop, with the strand budget's `late_steps`: bench/RESULTS.md. False: the tool meets the strands
    /// by contact and friction only (issue 12's law).
    pub entanglement: bool,
    /// The hold of the unsimulated neighbours on each local strand (`tools::interaction::LocalInteraction::
    /// hold_distance`): a spring per unit length towards the strand's place in the hair volume (its groom
    /// carried by the lattice) that carries the strand's own weight at this displacement, m; infinite: none.
    /// A simulated guide has one fibre's mechanics, and groomed along the curved head it is only a local
    /// equilibrium: pushed far enough by a slow comb it rolled round the side of the head (the replayed record
    /// of issue 12's failing browser stroke), where real hair is held by the hair around it. A whole guide 3 cm
    /// out of place is pulled back by its weight (1.4e-5 N for 25 cm), below the tool's push on it (~1e-4 N).
    /// What that record gives with and without the hold: docs/physics.md.
    /// Default 0.03.
    /// The hold also **carries the strand's weight** at its place, as the sag-free lattice's pre-stressed springs
    /// carry the global layer's (docs/global.md): the local strands' models have no gravity of their own and their
    /// rest shape is their groomed shape (`HapticCore::build_strands`; with no hold, infinite, they keep their own
    /// weight and the sag-free rest). A single fibre's sag-free rest instead
    /// stored a root curvature of up to 200 rad/m (the gravity moment of 20 cm of hair over the crown, about
    /// 1e-6 N m, over EI, about 5e-9 N m^2): a second, flipped equilibrium, where guides blown over their own
    /// roots came to rest 2-7 cm off their place (issue 30).
    pub hold_distance: f64,
    /// Damping ratio of the hold (dimensionless; 1: critical): the hair volume damps a local strand's return to
    /// its place as a linear drag `2 zeta sqrt(|g| / hold_distance)` times its linear density (N s/m^2) added to
    /// its air drag (on its absolute velocity, as the lattice's attachment damping). Default 1: between the
    /// lattice's stiffeners (0.5) and attachment (1.5) (`HairLatticeParams`); the strands come back within
    /// `handover_distance` in about 0.3 s (at 0.1, the air's drag alone, they still swung after
    /// `max_relax_time`).
    pub hold_damping: f64,
    /// Surface treatment of the hair (`tools::treatment::Treatment`: virgin, conditioned, bleached, bleached
    /// twice): scales the tool's and the fibres' friction, dry and wet, by the one friction law
    /// (`Treatment::friction`), and with `entanglement` the drag's capillary forces by its wettability
    /// (`Treatment::wettability`), as `[patch] treatment` does in the tress scenarios. Default virgin.
    pub treatment: tools::treatment::Treatment,
}

impl Default for HapticParams {
    fn default() -> Self {
        Self { max_proxy_lag: 0.2, reselect_distance: 0.01, choice_steps: 10, joins_per_step: 4, clip_reach: 0.01, max_displacement: 0.5, min_air_drag: 2e-5, combing_ease_reduction: 0.8, dryer_pieces: 8, snip_distance: 0.02, cut_pieces: 4, start: [0.0, -0.25, 0.0], lookahead: 0.1, rest_speed: 0.02, rest_time: 0.2, handover_distance: 0.002, max_relax_time: 1.5, rest_distance: 0.005, blend_time: 0.3, body_clearance: 0.004, hydrogen_share: 0.8, hair_contact: true, groomed_overlap: true, entanglement: true, hold_distance: 0.03, hold_damping: 1.0, treatment: tools::treatment::Treatment::Virgin }
    }
}

impl HapticParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        let p = |m: String| Err(SessionError::Param(m));
        for (k, v) in [("max_proxy_lag", self.max_proxy_lag), ("reselect_distance", self.reselect_distance), ("clip_reach", self.clip_reach), ("max_displacement", self.max_displacement), ("snip_distance", self.snip_distance), ("rest_distance", self.rest_distance), ("handover_distance", self.handover_distance)] {
            if !(v > 0.0 && v.is_finite()) {
                return p(format!("haptic.{k} must be > 0 m, got {v}"));
            }
        }
        if !(self.body_clearance >= 0.0 && self.body_clearance.is_finite()) {
            return p(format!("haptic.body_clearance must be >= 0 m, got {}", self.body_clearance));
        }
        for (k, v) in [("lookahead", self.lookahead), ("rest_time", self.rest_time)] {
            if !(v >= 0.0 && v.is_finite()) {
                return p(format!("haptic.{k} must be >= 0 s, got {v}"));
            }
        }
        for (k, v) in [("max_relax_time", self.max_relax_time), ("blend_time", self.blend_time)] {
            if !(v > 0.0 && v.is_finite()) {
                return p(format!("haptic.{k} must be > 0 s, got {v}"));
            }
        }
        if !(self.hold_distance > 0.0) {
            return p(format!("haptic.hold_distance must be > 0 m (infinite: no hold), got {}", self.hold_distance));
        }
        if !(self.hold_damping >= 0.0 && self.hold_damping.is_finite()) {
            return p(format!("haptic.hold_damping must be a finite damping ratio >= 0, got {}", self.hold_damping));
        }
        if !(self.rest_speed > 0.0 && self.rest_speed.is_finite()) {
            return p(format!("haptic.rest_speed must be > 0 m/s, got {}", self.rest_speed));
        }
        if !(self.min_air_drag >= 0.0 && self.min_air_drag.is_finite()) {
            return p(format!("haptic.min_air_drag must be >= 0 N s/m^2, got {}", self.min_air_drag));
        }
        if !(0.0..1.0).contains(&self.combing_ease_reduction) {
            return p(format!("haptic.combing_ease_reduction must be in [0, 1), got {}", self.combing_ease_reduction));
        }
        if self.dryer_pieces == 0 || self.cut_pieces == 0 || self.choice_steps == 0 || self.joins_per_step == 0 {
            return p(format!("haptic.dryer_pieces, haptic.cut_pieces, haptic.choice_steps and haptic.joins_per_step must be > 0, got {}, {}, {}, {}", self.dryer_pieces, self.cut_pieces, self.choice_steps, self.joins_per_step));
        }
        if !(0.0..=1.0).contains(&self.hydrogen_share) {
            return p(format!("haptic.hydrogen_share must be in [0, 1], got {}", self.hydrogen_share));
        }
        if !self.start.iter().all(|x| x.is_finite()) {
            return p(format!("haptic.start must be finite, got {:?}", self.start));
        }
        Ok(())
    }

    /// The hold of the hair volume per unit mass of hair at gravity `g` (m/s^2): its stiffness
    /// `omega^2 = |g| / hold_distance` (1/s^2) and its damping `2 hold_damping omega` (1/s); (0, 0) without a hold
    /// (`hold_distance` infinite). The one hold law (`tools::interaction::hold_rate`)'s rates: a local strand's hold (`LocalInteraction::holds`, its
    /// spring `omega^2` times the linear density per unit length) and damping (added to its air drag), and the
    /// relaxation of a handed-over guide's displacement in the global layer (`HapticCore::handed`).
    pub fn hold_rates(&self, g: f64) -> (f64, f64) {
        let k = tools::interaction::hold_rate(g, self.hold_distance);
        (k, 2.0 * self.hold_damping * k.sqrt())
    }

    /// The tool's friction coefficient on hair of friction `mu` at combing ease `ease` (clamped to [0, 1];
    /// NaN counts as 0): mu (1 - `combing_ease_reduction` ease). The one combing-ease law.
    pub fn combing_friction(&self, mu: f64, ease: f64) -> f64 {
        let e = if ease.is_finite() { ease.clamp(0.0, 1.0) } else { 0.0 };
        mu * (1.0 - self.combing_ease_reduction * e)
    }
}

/// The lattice around the live hair (`Scene::builtin`, `Scene::from_curves`): soft, sag-free, its springs
/// proportional to the hair it carries.
///
/// Each render strand is one hair, so the lattice carries the real hair's mass, and its springs stand for
/// the hair's collective resistance, which grows with the number of hairs: every stiffness and damping is
/// given per kilogram of the mean node mass m (the hair's mass over the nodes), k = rate x m, so the motion
/// (sag before compensation, swing, settling) does not depend on how many strands are drawn. The rest is
/// made sag-free (`lattice::sag_free`): the groomed shape is the equilibrium under gravity, with the weight
/// carried by pre-stressed springs. The rates were chosen by measurement (`cargo run --release -p
/// coiffure-engine --example global_motion`, docs/global.md "A soft lattice"): about 170 times softer than
/// `LatticeParams::default` for the 20k-strand scene, so that a dryer, a comb and a head turn move the
/// hairstyle by centimetres, with damping that settles it in about 2 s without oscillating. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairLatticeParams {
    /// Stiffness of each 26-neighbour stiffener per kg of mean node mass, N/m/kg = 1/s^2. Default 3600.
    pub stiffener_rate: f64,
    /// Damping of each stiffener per kg of mean node mass, 1/s. Default 60.
    pub stiffener_damping_rate: f64,
    /// Stiffness of each bending stiffener (second neighbours) per kg of mean node mass, 1/s^2. Default 900.
    pub bending_rate: f64,
    /// Damping of each bending stiffener per kg of mean node mass, 1/s. Default 15.
    pub bending_damping_rate: f64,
    /// Stiffness of a fully attached node's spring to the head per kg of mean node mass, 1/s^2. Default 900.
    pub attachment_rate: f64,
    /// Damping of a fully attached node per kg of mean node mass (on its absolute velocity: it also stands
    /// for the air's drag on the hair), 1/s. Default 90.
    pub attachment_damping_rate: f64,
    /// Attachment weight of the nodes farthest from the head (dimensionless, [0, 1]): the weight falls from 1
    /// on the body over three head radii to this. Default 0.03 (the hair's own springs, not the head, hold
    /// the far hair).
    pub min_attachment: f64,
    /// Make the rest sag-free. Default true.
    pub sag_free: bool,
    /// Length of hair from the root that the head holds (`Scene::root_hold`, the law `scene::carried`), m:
    /// along it the carried hair goes from the head's rigid motion at the root to the lattice's motion
    /// (`scene::root_hold_weight`, a smoothstep), so that roots stay on the scalp whatever the lattice does.
    /// The scale on which a root's clamp dominates a hair's shape: the elastogravity length
    /// (EI / (lambda g))^(1/3) (Goldstein, Warren and Ball, Phys. Rev. Lett. 108, 078101, 2012: "Shape of a
    /// ponytail") is 4.0 cm for the caucasian preset (EI 2.9e-9 N m^2, 4.7 mg/m), and a dryer's 8 m/s jet (about
    /// 5e-3 N per metre of hair) bends a clamped hair by its own length at (8 EI / q)^(1/3) = 1.7 cm from the
    /// root. Default 0.03 (between the two).
    pub root_hold: f64,
}

impl Default for HairLatticeParams {
    fn default() -> Self {
        Self { stiffener_rate: 3600.0, stiffener_damping_rate: 60.0, bending_rate: 900.0, bending_damping_rate: 15.0, attachment_rate: 900.0, attachment_damping_rate: 90.0, min_attachment: 0.03, sag_free: true, root_hold: 0.03 }
    }
}

impl HairLatticeParams {
    /// The lattice parameters (the other fields `LatticeParams::default`'s) for a mean node mass `mean_mass`, kg.
    pub fn lattice(&self, mean_mass: f64) -> lattice::lattice::LatticeParams {
        let m = mean_mass;
        lattice::lattice::LatticeParams {
            stiffener_stiffness: self.stiffener_rate * m,
            stiffener_damping: self.stiffener_damping_rate * m,
            bending_stiffness: self.bending_rate * m,
            bending_damping: self.bending_damping_rate * m,
            attachment_stiffness: self.attachment_rate * m,
            attachment_damping: self.attachment_damping_rate * m,
            ..Default::default()
        }
    }
}

/// Constants of the global layer's step (`crate::global`) and of the tools as the global layer sees them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalParams {
    /// Distance from the tool point back to the dryer's or sprayer's nozzle, m (the viewer puts the tool
    /// where the mouse points on the hair: the nozzle aims there from a hand's distance). Default 0.15.
    pub nozzle_standoff: f64,
    /// Radius of the disk the scissors' blades sweep when they close, m (about the blades' length).
    /// Default 0.04.
    pub blade_radius: f64,
    /// Most falling pieces made of one cut: more are sampled evenly, their masses scaled to keep the total.
    /// Default 256.
    pub max_pieces_per_cut: usize,
    /// Most cuts whose clusters fall at once (the oldest is dropped). Default 8.
    pub max_cluster_sets: usize,
    /// The tool as a lattice obstacle: its metaballs' iso-surface lies this far outside each capsule, m
    /// (so that the lattice, 5 cm cells, feels it). Default 0.02.
    pub obstacle_margin: f64,
    /// Metaballs along each capsule are spaced at this fraction of their radius. Default 0.5.
    pub obstacle_spacing: f64,
    /// Most metaballs along one capsule, minus one. Default 64.
    pub obstacle_max_balls: usize,
}

impl Default for GlobalParams {
    fn default() -> Self {
        Self { nozzle_standoff: 0.15, blade_radius: 0.04, max_pieces_per_cut: 256, max_cluster_sets: 8, obstacle_margin: 0.02, obstacle_spacing: 0.5, obstacle_max_balls: 64 }
    }
}

impl GlobalParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        let p = |m: String| Err(SessionError::Param(m));
        for (k, v) in [("nozzle_standoff", self.nozzle_standoff), ("blade_radius", self.blade_radius), ("obstacle_margin", self.obstacle_margin), ("obstacle_spacing", self.obstacle_spacing)] {
            if !(v > 0.0 && v.is_finite()) {
                return p(format!("global.{k} must be > 0, got {v}"));
            }
        }
        if self.max_pieces_per_cut == 0 || self.max_cluster_sets == 0 || self.obstacle_max_balls == 0 {
            return p("global.max_pieces_per_cut, max_cluster_sets and obstacle_max_balls must be > 0".into());
        }
        Ok(())
    }
}
