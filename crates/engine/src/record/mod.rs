//! Records of live sessions: per haptic step, the device reading, the lattice version it used, the viewer
//! commands applied before it and the force sent back; plus the global steps at which the lattice was reset.
//! [`crate::replay::replay`] reproduces the force trace from a record.
//!
//! File format ([`format`]) (little-endian, f64 kept exactly): magic `CFREC1\0\0`, f64 haptic rate (Hz), u64 number of
//! resets then each u64 global version, u64 number of steps, then per step: u8 has-reading; if 1: f64 time,
//! 3 f64 position (m), 9 f64 rotation (column-major), u32 buttons; u64 lattice version; 3 f64 force (N);
//! u8 number of commands, each: u8 kind (0 tool: u8 id; 1 hair: u8 type, f64 curliness, f64 ease; 2 reset;
//! 3 head: 3 f64 position (m), 3 f64 rotation vector (rad); 4 strand limit: u32). A step with several device
//! steps (`SessionParams::device_steps`) writes has-reading 2, then u8 count of device steps and each one's
//! reading as above (u8 has-reading 0 or 1, and if 1 the reading).
//!
//! Version 2 (magic `CFREC2\0\0`, written now) adds the tool input of every global step right after the
//! resets: u64 number of global steps, then per step: u8 tool id, u8 flags (bit 0 present, bit 1 primary
//! button held), 3 f64 position (m), 9 f64 rotation (column-major), u64 scissors closes so far. The rest is
//! as in version 1. Version-1 files still load (no global inputs: their global steps had no tool).

mod format;

use crate::command::Command;
use crate::tool::ToolInput;
use haptics::device::DeviceReading;
use nalgebra::Vector3;

/// One haptic step as recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct StepRecord {
    /// The device reading the step received (None: no input yet); with several device steps per physics
    /// step (`SessionParams::device_steps`), the reading of the period's first device step.
    pub reading: Option<DeviceReading>,
    /// The readings of the period's further device steps, in order (empty at one device step per physics
    /// step).
    pub more_readings: Vec<Option<DeviceReading>>,
    /// Version of the lattice snapshot the step read.
    pub lattice_version: u64,
    /// Viewer commands applied just before the step.
    pub commands: Vec<Command>,
    /// Force sent to the device, N (by the period's last device step).
    pub force: Vector3<f64>,
}

impl StepRecord {
    /// Every device step's reading of the period, in order.
    pub fn readings(&self) -> Vec<Option<DeviceReading>> {
        std::iter::once(self.reading).chain(self.more_readings.iter().copied()).collect()
    }
}

/// A recorded session.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// Haptic rate, Hz.
    pub rate_hz: f64,
    /// Global versions produced right after a lattice reset.
    pub global_resets: Vec<u64>,
    /// The tool input each global step read (entry v - 1 for the step producing version v).
    pub global_inputs: Vec<ToolInput>,
    /// Every haptic step, in order.
    pub steps: Vec<StepRecord>,
}

/// Errors reading a record.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RecordError {
    /// The bytes end early or hold a bad value; names the byte offset.
    #[error("bad session record at byte {offset}: {what}")]
    Bad {
        /// Byte offset.
        offset: usize,
        /// What is wrong.
        what: String,
    },
}

impl Record {
    /// An empty record at `rate_hz`.
    pub fn new(rate_hz: f64) -> Self {
        Self { rate_hz, global_resets: Vec::new(), global_inputs: Vec::new(), steps: Vec::new() }
    }

    /// The forces in order, N.
    pub fn forces(&self) -> Vec<Vector3<f64>> {
        self.steps.iter().map(|s| s.force).collect()
    }
}
