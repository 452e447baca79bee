//! Parameters of a streamed record ([`RecordParams`]).

use crate::error::SessionError;

/// Parameters of a streamed record (`SessionParams::record`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordParams {
    /// Longest time between two chunks written and synced to disk, s, in (0, 10]: if the server dies, at most
    /// about this much of the session is lost. Default 0.5.
    pub flush_interval: f64,
    /// Capacity of each queue to the writer thread, s of steps at the loop's rate, >= 2 flush intervals: how
    /// long the writer may be held up (a slow disk) before a step finds its queue full. Default 10 (about
    /// 2 MB at 1 kHz).
    pub queue_seconds: f64,
}

impl Default for RecordParams {
    fn default() -> Self {
        Self { flush_interval: 0.5, queue_seconds: 10.0 }
    }
}

impl RecordParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        if !(self.flush_interval > 0.0 && self.flush_interval <= 10.0) {
            return Err(SessionError::Param(format!("record.flush_interval must be in (0, 10] s, got {}", self.flush_interval)));
        }
        if !(self.queue_seconds >= 2.0 * self.flush_interval && self.queue_seconds <= 600.0) {
            return Err(SessionError::Param(format!("record.queue_seconds must be in [2 x flush_interval, 600] s, got {}", self.queue_seconds)));
        }
        Ok(())
    }

    /// Queue capacity for a loop at `rate_hz`, steps.
    pub(crate) fn capacity(&self, rate_hz: f64) -> usize {
        (self.queue_seconds * rate_hz).ceil().max(16.0) as usize
    }
}
