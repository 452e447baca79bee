//! Errors of the live session (parameters, scene building, threads).

/// Errors of a session.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// A parameter is out of range (names it).
    #[error("invalid session parameter: {0}")]
    Param(String),
    /// Building the scene failed.
    #[error("cannot build the scene: {0}")]
    Scene(String),
    /// A thread could not be started.
    #[error("cannot start the session: {0}")]
    Start(String),
}
