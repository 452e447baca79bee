//! Parameters of a live session.

use crate::error::SessionError;
use haptics::device::DeviceProfile;

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
    /// Largest speed at which the device point follows the mouse target, m/s (the mouse jumps between events;
    /// the device moves there smoothly). Default 1.0.
    pub follow_speed: f64,
    /// Haptic steps between two snapshots published for the viewer. Default 5 (200 Hz).
    pub publish_every: u64,
    /// Keep a record of the device input for replay. Default false.
    pub record: bool,
    /// Sprayer wetting rate s0 at the nozzle (`tools::sprayer::Sprayer`), 1/s. Default 1.
    pub wetting_rate: f64,
    /// Dryer drying rate k0 at the nozzle (`tools::dryer::HairDryer`), 1/s. Default 0.05.
    pub drying_rate: f64,
    /// Hairs each simulated guide stands for in the force on the tool (a wisp): the local strands' reaction
    /// is multiplied by it. Dimensionless, >= 1. Default 20.
    pub wisp: f64,
    /// Real-time (`SCHED_FIFO`) priority asked for the haptic thread, 1..=99 (`haptics::realtime`), or None
    /// for normal priority. A refusal (no permission) is logged and the loop runs at normal priority.
    /// Default None (`coiffure serve` asks for 10).
    pub haptic_priority: Option<i32>,
}

impl Default for SessionParams {
    fn default() -> Self {
        Self { haptic_rate_hz: 1000.0, global_rate_hz: 100.0, max_active: 12, activation_radius: 0.05, profile: DeviceProfile::PHANTOM_OMNI, follow_speed: 1.0, publish_every: 5, record: false, wetting_rate: 1.0, drying_rate: 0.05, wisp: 20.0, haptic_priority: None }
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
        if !(self.activation_radius > 0.0 && self.follow_speed > 0.0 && self.wetting_rate >= 0.0 && self.drying_rate >= 0.0 && self.wetting_rate.is_finite() && self.drying_rate.is_finite()) {
            return p(format!("activation_radius, follow_speed must be > 0 and wetting_rate, drying_rate finite and >= 0: {self:?}"));
        }
        if !(self.wisp >= 1.0 && self.wisp.is_finite()) {
            return p(format!("wisp must be >= 1, got {}", self.wisp));
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
