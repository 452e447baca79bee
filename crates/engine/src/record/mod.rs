//! Records of live sessions: per haptic step, the device reading, the lattice version it used, the viewer
//! commands applied before it and the force sent back; per global step, the tool input it read and whether the
//! lattice was reset before it. [`crate::replay::replay`] reproduces the force trace from a record.
//!
//! A live session streams its record to disk as it runs ([`stream`]): the file is created when recording
//! starts and grows by self-checking chunks, so that a file cut at any byte (the server killed, the disk full,
//! the power cut) reads up to its last whole chunk ([`Record::read`] says where and why it stopped).
//!
//! File format, version 3 ([`format`], [`chunk`]; little-endian, every f64 kept exactly):
//! - magic `CFREC4\0\0` (8 bytes), then chunks;
//! - a chunk: u32 payload length L (bytes, at most [`chunk::MAX_PAYLOAD`]), u32 CRC-32 (IEEE) of the payload,
//!   then the L payload bytes, whose first byte is the chunk's kind:
//!   - 0 **header** (the first chunk, once): f64 haptic rate (Hz), u32 byte length n, n bytes of UTF-8 TOML text:
//!     the session's settings ([`RecordSettings`]; empty when not given);
//!   - 1 **steps**: u64 index of its first global step, u32 number of global steps G, G global steps; u64 index
//!     of its first haptic step, u32 number of haptic steps H, H haptic steps. Every haptic step reads a
//!     lattice version no later than the global steps written so far (the version v is produced by global step
//!     v - 1), so any prefix of whole chunks replays;
//!   - 2 **end** (last, written when recording ends in order): u64 global steps, u64 haptic steps in the file,
//!     u8 0 (the session ended) or 1 (recording stopped before the session ended), u16 byte length n, n bytes
//!     of UTF-8 text saying why it stopped (empty when it did not).
//! - a global step: u8 tool id, u8 flags (bit 0 tool present, bit 1 primary button held, bit 2 the head pose
//!   follows, bit 3 the lattice was reset before this step), 3 f64 position (m), 9 f64 rotation
//!   (column-major), u64 scissors closes so far, and with bit 2 the head pose (3 f64 translation (m), unit
//!   quaternion i j k w);
//! - a haptic step: u8 has-reading; if 1: f64 time (s), 3 f64 position (m), 9 f64 rotation (column-major), u32
//!   buttons; u64 lattice version; 3 f64 force (N); u8 number of commands, each: u8 kind (0 tool: u8 id; 1 hair:
//!   u8 type, f64 curliness, f64 ease; 2 reset; 3 head: 3 f64 position (m), 3 f64 rotation vector (rad); 4
//!   strand limit: u32; 5 treatment: u8 id). A haptic step with several device steps
//!   (`SessionParams::device_steps`) writes has-reading 2, then u8 count of device steps and each one's reading
//!   as above (u8 has-reading 0 or 1, and if 1 the reading). A haptic step whose period ran device steps beyond
//!   its readings ([`StepRecord::carried`]) writes has-reading 3, the count and the readings as after 2 (at
//!   least one), then u32 carried steps (at least 1); records written before it have none and read as they did.
//!
//! Older versions are refused with an error naming their version: a record replays bit for bit only on the code
//! that wrote it. `CFREC1`, `CFREC2`: one block written at a clean exit, before records were streamed; `CFREC3`:
//! streamed, but one device step per haptic step (before the device loop ran at its own rate, issue 31).

pub mod chunk;
mod format;
pub mod params;
pub mod settings;
pub mod stream;

use crate::command::Command;
use crate::tool::ToolInput;
use haptics::device::DeviceReading;
use nalgebra::Vector3;

pub use settings::RecordSettings;
pub use stream::{GlobalSender, RecordFile, RecordParams, RecordReport, RecordSink, RecordStatus, RecordTarget, RecordWriter, StepSender};

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
    /// Device steps the period ran before its last one beyond its readings, with the reading before the last (0:
    /// none): the device loop lost more ticks than the period had room for
    /// ([`crate::device_loop::MAX_PERIOD_STEPS`]) and ran the rest there
    /// ([`crate::haptic::DeviceSide::step_after`]), so the replay runs them so.
    pub carried: u32,
}

impl StepRecord {
    /// Every device step's reading of the period, in order.
    pub fn readings(&self) -> Vec<Option<DeviceReading>> {
        std::iter::once(self.reading).chain(self.more_readings.iter().copied()).collect()
    }
}

/// One global step as recorded: the tool input it read and whether the lattice was reset just before it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalRecord {
    /// The lattice was reset before this step (a RESET command).
    pub reset: bool,
    /// The tool input the step read.
    pub input: ToolInput,
}

/// A recorded session.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// Haptic rate, Hz.
    pub rate_hz: f64,
    /// The session's scene and settings, if the record says (`coiffure serve`'s do).
    pub settings: Option<RecordSettings>,
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

/// Where and why reading a record stopped before its end chunk.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// Byte offset of the first byte not read (the end of the last whole chunk).
    pub offset: usize,
    /// The file's length, bytes.
    pub file_bytes: usize,
    /// Why reading stopped there.
    pub why: String,
}

/// How a record read ends.
#[derive(Debug, Clone, PartialEq)]
pub enum Ending {
    /// The end chunk is there: the session ended and every step is in the file.
    Complete,
    /// The end chunk says recording stopped before the session ended (why); every step up to then is there.
    Stopped(String),
    /// No end chunk: the file was cut (the server died, or the disk filled); read up to its last whole chunk.
    Cut(Cut),
}

/// A record read from a file, whole or up to where it was cut.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadRecord {
    /// The steps read.
    pub record: Record,
    /// How the file ends.
    pub ending: Ending,
}

impl Record {
    /// An empty record at `rate_hz`.
    pub fn new(rate_hz: f64) -> Self {
        Self { rate_hz, settings: None, global_resets: Vec::new(), global_inputs: Vec::new(), steps: Vec::new() }
    }

    /// The forces in order, N.
    pub fn forces(&self) -> Vec<Vector3<f64>> {
        self.steps.iter().map(|s| s.force).collect()
    }

    /// Length of the recorded session, s (haptic steps over the haptic rate).
    pub fn seconds(&self) -> f64 {
        self.steps.len() as f64 / self.rate_hz
    }

    /// The device steps that read each device pose sent at the times `sent` (s, the poses' time stamps, in
    /// order), as (haptic step, device step within it): the first device step whose reading is that pose or a
    /// later one (a device step reads the newest pose that arrived and answers the poses it read with its
    /// force; the older ones of that step got its force too). None for a pose after the last reading.
    pub fn steps_reading(&self, sent: &[f64]) -> Vec<Option<(usize, usize)>> {
        let read: Vec<(f64, (usize, usize))> = self
            .steps
            .iter()
            .enumerate()
            .flat_map(|(i, s)| s.readings().into_iter().enumerate().filter_map(move |(j, r)| r.map(|r| (r.time, (i, j)))))
            .collect();
        sent.iter().map(|&t| read.get(read.partition_point(|&(rt, _)| rt < t)).map(|&(_, i)| i)).collect()
    }

    /// The global steps as recorded (reset flag and tool input).
    pub fn global_steps(&self) -> impl Iterator<Item = GlobalRecord> + '_ {
        self.global_inputs.iter().enumerate().map(|(i, &input)| GlobalRecord { reset: self.global_resets.contains(&(i as u64 + 1)), input })
    }
}
