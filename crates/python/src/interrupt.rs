//! Ctrl-C during long runs: the GIL is released while Rust steps, and every [`CHECK_EVERY`] steps the loop
//! briefly takes it back to let Python look at its pending signals. A `KeyboardInterrupt` (or any exception a
//! signal handler raises) stops the loop after the step in progress and is raised by the binding.

use pyo3::prelude::*;

/// Steps between two looks at Python's signals (at 1 ms steps, a few milliseconds of a strand's work).
pub const CHECK_EVERY: u64 = 64;

/// Looks at pending signals from inside a `Python::detach` section; the exception of a signal handler, if any.
pub fn pending() -> Option<PyErr> {
    Python::attach(|py| py.check_signals().err())
}

/// Counts steps and looks at the signals every [`CHECK_EVERY`] of them; keeps the first exception.
#[derive(Default)]
pub struct Watch {
    steps: u64,
    /// The exception raised by a signal handler (KeyboardInterrupt for Ctrl-C), once seen.
    pub error: Option<PyErr>,
}

impl Watch {
    /// Call after every step: true when the run must stop.
    pub fn stop(&mut self) -> bool {
        if self.error.is_some() {
            return true;
        }
        self.steps += 1;
        if self.steps % CHECK_EVERY == 0 {
            self.error = pending();
        }
        self.error.is_some()
    }
}
