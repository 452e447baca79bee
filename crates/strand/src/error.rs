//! Errors of the strand crate. Every variant names the offending field or quantity.

use thiserror::Error;

/// Something wrong with a strand's parameters or with a step of its simulation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StrandError {
    /// A parameter is out of range; `field` is its name as written in a strand spec file.
    #[error("invalid `{field}`: {reason}")]
    InvalidParameter {
        /// Name of the field, e.g. `length` or `semi_axes`.
        field: &'static str,
        /// What is wrong with it, with the value given.
        reason: String,
    },
    /// The state became non-finite (NaN or infinity) during a step; the previous state was kept.
    #[error("simulation produced a non-finite {what} at t = {time} s; the step was rejected and the previous state kept")]
    NonFinite {
        /// Which quantity was non-finite (e.g. "velocity").
        what: &'static str,
        /// Simulation time at the start of the rejected step, in s.
        time: f64,
    },
    /// A linear system that must be positive definite was not (e.g. the implicit step matrix).
    #[error("matrix `{what}` is not positive definite")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// An iterative solver (Newton, implicit midpoint) did not converge.
    #[error("{solver} did not converge in {iterations} iterations (last residual {residual:e})")]
    NoConvergence {
        /// Which solver.
        solver: &'static str,
        /// Iterations spent.
        iterations: usize,
        /// Norm of the last residual or update.
        residual: f64,
    },
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, StrandError>;

/// Check that `value` is finite and strictly positive, naming `field` otherwise.
pub(crate) fn require_positive(field: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(StrandError::InvalidParameter {
            field,
            reason: format!("must be a finite positive number, got {value}"),
        })
    }
}

/// Check that `value` is finite and not negative, naming `field` otherwise.
pub(crate) fn require_non_negative(field: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(StrandError::InvalidParameter {
            field,
            reason: format!("must be a finite number >= 0, got {value}"),
        })
    }
}
