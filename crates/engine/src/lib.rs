//! # Coiffure engine
//!
//! Runs the simulation in time: headless scenarios ([`scenario`]), a scripted tool drawn through a patch of
//! strands at haptic rate producing a force trace, and live local sessions ([`local_session`]) where a device
//! drives the tool in the fixed-rate haptic loop thread. (The global layer and the coupled session come with
//! later issues.) No file or network I/O here: the server reads and writes files.

pub mod local_session;
pub mod path;
pub mod scenario;
pub mod record;
pub mod session;
