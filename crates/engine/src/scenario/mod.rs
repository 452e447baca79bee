//! Headless scenarios (`coiffure run`), the research instrument:
//! - [`patch`]: a patch of strands of one hair type, a tool and its scripted path, stepped at haptic rate;
//!   the result is the force trace the tool (the hand) feels and a summary.
//! - [`global`]: a generated hairstyle on the built-in head and timed actions of the scissors, the hair
//!   dryer and the water sprayer ([`actions`]).

pub mod actions;
pub mod global;
pub mod patch;

pub use actions::{Action, ConeAction, ConePose, CutAction};
pub use global::{GlobalOutput, GlobalRow, GlobalScenario, GlobalSummary, HairstyleSpec};
pub use patch::{PatchSpec, Scenario, Summary, ToolSpec, TraceRow};

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
}

pub(crate) fn default_dt() -> f64 {
    1e-3
}
