//! Headless scenarios (`coiffure run`), the research instrument:
//! - [`patch`]: a patch of strands of one hair type, a tool and its scripted path, stepped at haptic rate;
//!   the result is the force trace the tool (the hand) feels and a summary.
//! - [`global`]: a generated hairstyle on the built-in head and timed actions of the scissors, the hair
//!   dryer and the water sprayer ([`actions`]).
//! - [`live`]: the live session's own cores driven headless, the tool moved as a device would move it.
//!
//! [`run`] runs any kind into memory ([`ScenarioOutput`]); [`files`] reads a scenario's tool files
//! ([`run_in`]) and writes the outputs ([`write_output`]), for the CLI and the Python binding alike.
//! [`schema`]: the one summary schema of every kind (each key's unit, by its suffix or the unitless list).

pub mod actions;
pub mod combing;
pub mod criteria;
pub mod files;
pub mod global;
pub mod live;
pub mod meter;
pub mod output;
pub mod patch;
pub mod run;
pub mod schema;
pub mod strokes;

pub use actions::{Action, ConeAction, ConePose, CutAction};
pub use combing::{fifths, CombingFigures, CombingProfile, Fifths, PerStroke};
pub use files::{load_tool, read_path_csv, run_in, summary_json, write_device_force, write_output, write_replay};
pub use global::{GlobalOutput, GlobalRow, GlobalScenario, GlobalSummary, HairstyleSpec};
pub use live::{LiveScenario, LiveSpec, LiveTool, LiveWaypoint};
pub use output::{ForceStats, ForceTrace, LiveSummary};
pub use patch::{PatchSpec, Scenario, Summary, ToolSpec, TraceRow};
pub use run::{run, run_patch, ScenarioFile, ScenarioOutput, ScenarioSummary};
pub use strokes::StrokeCycle;

use strand::StrandError;


/// Why a scenario could not run.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// A value out of range; names the key.
    #[error("invalid scenario: {0}")]
    Invalid(String),
    /// The simulation failed.
    #[error("simulation failed at t = {time} s: {source}")]
    Simulation {
        /// Time since the tool started, s.
        time: f64,
        /// What failed.
        source: StrandError,
    },
    /// A file the scenario reads or writes (tool shape or path, outputs): names the file.
    #[error("{}: {message}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        message: String,
    },
}

pub(crate) fn default_dt() -> f64 {
    1e-3
}

#[cfg(test)]
mod loaded_comb_tests;
