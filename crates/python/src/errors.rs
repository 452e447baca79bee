//! Python exceptions for the crates' errors: bad input is a `ValueError` naming what is wrong; a simulation
//! that fails (non-finite state, solver not converging) is a `coiffure.SimulationError` (a `RuntimeError`).

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::PyErr;
use strand::StrandError;

create_exception!(
    coiffure,
    SimulationError,
    PyRuntimeError,
    "A simulation failed (non-finite state, a solver that did not converge); the message says when and why."
);

/// A strand error as a Python exception: invalid parameters are `ValueError`, the rest `SimulationError`.
pub fn strand_err(context: &str, e: StrandError) -> PyErr {
    let msg = if context.is_empty() { e.to_string() } else { format!("{context}: {e}") };
    match e {
        StrandError::InvalidParameter { .. } => PyValueError::new_err(msg),
        _ => SimulationError::new_err(msg),
    }
}
