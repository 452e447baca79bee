//! # Coiffure engine
//!
//! Runs the simulation in time. No file or network I/O here: the server reads and writes files.
//!
//! The live session, room by room:
//! - [`scene`]: the immutable model (head, render hair, guides, lattice), built-in or from a file's curves;
//! - [`tool`]: the toolbar's tools, what the global layer reads of the tool ([`tool::ToolInput`]);
//! - [`command`]: viewer commands; [`params`]: the session's parameters; [`snapshot`]: what the threads
//!   exchange;
//! - [`global`]: the global layer's core (lattice, nozzles, cuts), [`haptic`]: the haptic layer's core
//!   (coupling, active set, local strands, tool actions);
//! - [`live`]: the threads and their triple buffers ([`device_loop`]: the device loop at the device's rate and
//!   the haptic physics, on the lockstep schedule); [`record`] and [`replay`]: deterministic replay;
//!   [`lockstep`]: both cores on one thread (replay and `[live]` scenarios).
//!
//! [`session`] gathers the live session's public names. Headless: [`scenario`]: a tool scripted through a
//! patch of strands; the live [`global::GlobalCore`] driven by a script of tool inputs (`[[action]]`); the
//! live cores driven by device inputs in lockstep (`[live]`); with tool paths from [`path`]. One engine:
//! the headless doors run the live session's own cores (tests check them against the live ones to the bit).

pub mod budget;
pub mod command;
pub mod device_loop;
pub mod error;
pub mod global;
pub mod haptic;
pub mod live;
pub mod lockstep;
pub mod params;
pub mod path;
pub mod record;
pub mod replay;
pub mod scenario;
pub mod scene;
pub mod session;
pub mod snapshot;
pub mod tool;

#[cfg(test)]
pub(crate) mod testing;
