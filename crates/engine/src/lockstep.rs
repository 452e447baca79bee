//! The live session's two cores stepped in lockstep on one thread, deterministic: the one driver of
//! [`crate::replay::replay`] (the recorded schedule) and of the `[live]` scenarios (a fixed schedule: one
//! global step every `haptic_rate / global_rate` haptic steps). The live threads ([`crate::live`]) run the
//! same [`GlobalCore::step`], device steps and physics steps ([`HapticCore::step_rates`]) on their own clocks.

use crate::command::Command;
use crate::error::SessionError;
use crate::global::GlobalCore;
use crate::haptic::HapticCore;
use crate::params::SessionParams;
use crate::record::{Record, StepRecord};
use crate::scene::Scene;
use crate::snapshot::LatticeSnapshot;
use crate::tool::ToolInput;
use haptics::device::{DeviceCommand, DeviceReading};
use std::sync::Arc;
use std::time::Duration;

/// Both cores and the lattice snapshot the haptic core reads.
pub struct Lockstep {
    /// The haptic layer.
    pub haptic: HapticCore,
    /// The global layer.
    pub global: GlobalCore,
    /// The latest lattice snapshot.
    pub lattice: LatticeSnapshot,
    /// Haptic step, s (as the live loop computes it, through `Duration`).
    pub dt: f64,
    /// Global step, s (likewise).
    pub gdt: f64,
    /// A record of the steps (the format of `coiffure serve --record`), if asked for.
    pub record: Option<Record>,
    /// The last physics period's device commands, one per device step, in order.
    pub device_commands: Vec<DeviceCommand>,
}

impl Lockstep {
    /// Both cores at rest on `scene`, the haptic loop at `haptic_rate_hz`.
    pub fn new(scene: Arc<Scene>, params: SessionParams, haptic_rate_hz: f64) -> Result<Self, SessionError> {
        let haptic = HapticCore::new(scene.clone(), params)?;
        let global = GlobalCore::new(scene, &params);
        let lattice = global.snapshot();
        Ok(Self {
            haptic,
            global,
            lattice,
            dt: Duration::from_secs_f64(1.0 / haptic_rate_hz).as_secs_f64(),
            gdt: Duration::from_secs_f64(1.0 / params.global_rate_hz).as_secs_f64(),
            record: None,
            device_commands: Vec::new(),
        })
    }

    /// One global step reading the tool input `input` (what the global thread does each period).
    pub fn global_step(&mut self, input: &ToolInput) -> bool {
        if let Some(r) = self.record.as_mut() {
            r.global_inputs.push(*input);
        }
        let (snap, bad) = self.global.step(self.gdt, input);
        self.lattice = snap;
        bad
    }

    /// One global step reading the haptic core's current tool input.
    pub fn global_step_live(&mut self) -> bool {
        let input = self.haptic.tool_input();
        self.global_step(&input)
    }

    /// One physics period (what the live session's device and physics threads do in one physics period,
    /// [`HapticCore::step_rates`]): one device step per reading of `readings` (the session's
    /// `SessionParams::device_steps`), rendering the model the previous physics step published, then the viewer
    /// `commands` and the physics step with the latest lattice snapshot (recorded if asked for). Returns the
    /// period's last device command.
    pub fn haptic_step(&mut self, commands: &[Command], readings: &[Option<DeviceReading>]) -> DeviceCommand {
        self.haptic_period(commands, readings, 0)
    }

    /// [`Lockstep::haptic_step`] with `carried` device steps before the last one, with the reading before it
    /// ([`StepRecord::carried`], as a live device loop that lost ticks ran them).
    pub fn haptic_period(&mut self, commands: &[Command], readings: &[Option<DeviceReading>], carried: u32) -> DeviceCommand {
        let mut period = std::mem::take(&mut self.device_commands);
        period.clear();
        self.haptic.step_rates(commands, readings, carried, &self.lattice, self.dt, |_, c| period.push(*c));
        let last = period.last().copied().unwrap_or_default();
        self.device_commands = period;
        if let Some(r) = self.record.as_mut() {
            let reading = readings.first().copied().flatten();
            let more_readings = readings.get(1..).unwrap_or_default().to_vec();
            r.steps.push(StepRecord { reading, more_readings, lattice_version: self.lattice.version, commands: commands.to_vec(), force: last.force, carried });
        }
        last
    }

    /// Replays `record` (see [`crate::replay::replay`]): before each recorded haptic step, the global core
    /// is stepped up to the lattice version that step read, with the recorded tool inputs and lattice
    /// resets; then the recorded commands and reading. `each` sees the cores after every global step
    /// (`None`) and after every haptic step (`Some(command)`).
    pub fn replay(&mut self, record: &Record, mut each: impl FnMut(&Lockstep, Option<&DeviceCommand>)) {
        for s in &record.steps {
            while self.lattice.version < s.lattice_version {
                if record.global_resets.contains(&(self.global.version + 1)) {
                    self.global.reset();
                }
                // The tool input that global step read (none in a version-1 record).
                let input = record.global_inputs.get(self.global.version as usize).copied().unwrap_or_default();
                self.global_step(&input);
                each(self, None);
            }
            let cmd = self.haptic_period(&s.commands, &s.readings(), s.carried);
            each(self, Some(&cmd));
        }
    }
}
