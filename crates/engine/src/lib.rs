//! # Coiffure engine
//!
//! Runs the simulation in time. Today: headless scenarios ([`scenario`]), a scripted tool drawn through a
//! patch of strands at haptic rate, producing a force trace. (Threads, the global layer and live sessions come
//! with later issues.) No file or network I/O here: the server reads and writes files.

pub mod path;
pub mod scenario;
