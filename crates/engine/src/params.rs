//! Parameters of a live session.

use crate::error::SessionError;
use haptics::device::DeviceProfile;
use haptics::target::TargetParams;

/// Parameters of a live session. Defaults: the README's `coiffure serve`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionParams {
    /// Haptic loop rate, Hz (at most 4000). Default 1000.
    pub haptic_rate_hz: f64,
    /// Global (lattice) step rate, Hz. Default 100.
    pub global_rate_hz: f64,
    /// Most guide strands simulated at once near the tool. Default 12.
    pub max_active: usize,
    /// A guide joins the active set when its settled shape comes within this distance of the tool, m.
    /// Default 0.05.
    pub activation_radius: f64,
    /// Device limits. Default: a Phantom Omni (3.3 N, 300 N/s), also for the mouse, whose force is shown.
    pub profile: DeviceProfile,
    /// How the device point follows a pointer's target (the mouse reports at 60-125 Hz): interpolated at the
    /// haptic rate between events (`haptics::target::TargetParams`: event-interval bounds 0.004-0.05 s,
    /// running-mean weight 0.2, largest speed 1.5 m/s). A real device's reading passes through it unchanged
    /// when it reports every step.
    pub pointer: TargetParams,
    /// Haptic steps between two snapshots published for the viewer. Default 5 (200 Hz).
    pub publish_every: u64,
    /// Keep a record of the device input for replay. Default false.
    pub record: bool,
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
}

impl Default for SessionParams {
    fn default() -> Self {
        Self { haptic_rate_hz: 1000.0, global_rate_hz: 100.0, max_active: 12, activation_radius: 0.05, profile: DeviceProfile::PHANTOM_OMNI, pointer: TargetParams { min_interval: 0.004, max_interval: 0.05, smoothing: 0.2, max_speed: 1.5 }, publish_every: 5, record: false, wetting_rate: 1.0, drying_rate: 0.05, hairs_per_render_strand: 1.0, haptic_priority: None }
    }
}

impl SessionParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        let p = |m: String| Err(SessionError::Param(m));
        if !(self.haptic_rate_hz > 0.0 && self.haptic_rate_hz <= haptics::haptic_loop::MAX_RATE_HZ) {
            return p(format!("haptic_rate_hz must be in (0, 4000], got {}", self.haptic_rate_hz));
        }
        if !(self.global_rate_hz > 0.0 && self.global_rate_hz <= 1000.0) {
            return p(format!("global_rate_hz must be in (0, 1000], got {}", self.global_rate_hz));
        }
        if self.max_active == 0 {
            return p("max_active must be > 0".into());
        }
        if !(self.activation_radius > 0.0 && self.wetting_rate >= 0.0 && self.drying_rate >= 0.0 && self.wetting_rate.is_finite() && self.drying_rate.is_finite()) {
            return p(format!("activation_radius must be > 0 and wetting_rate, drying_rate finite and >= 0: {self:?}"));
        }
        let t = &self.pointer;
        if !(t.min_interval > 0.0 && t.max_interval >= t.min_interval && t.max_interval.is_finite() && t.smoothing > 0.0 && t.smoothing <= 1.0 && t.max_speed > 0.0 && t.max_speed.is_finite()) {
            return p(format!("pointer: need 0 < min_interval <= max_interval (finite), smoothing in (0, 1], max_speed > 0 finite, got {t:?}"));
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
        Ok(())
    }
}
