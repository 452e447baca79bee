//! One door for every scenario kind: parse a scenario's TOML ([`ScenarioFile::from_toml`]) and run it into
//! memory ([`run`]): the CLI writes the [`ScenarioOutput`] to files, the Python binding hands it over.

use super::global::{GlobalRow, GlobalScenario, GlobalSummary};
use super::live::LiveScenario;
use super::combing::CombingProfile;
use super::output::{ForceTrace, LiveSummary};
use super::patch::{Scenario, Summary};
use super::ScenarioError;
use crate::path::ToolPath;
use serde::Serialize;
use tools::shape::ToolShape;

/// A scenario of any kind.
#[derive(Debug, Clone)]
pub enum ScenarioFile {
    /// A patch of strands and a scripted tool (`[patch]`).
    Patch(Scenario),
    /// Global tools on a generated hairstyle (`[[action]]`, `[hairstyle]`).
    Global(GlobalScenario),
    /// The live session's cores driven headless (`[live]`).
    Live(LiveScenario),
}

impl ScenarioFile {
    /// Parses a scenario's TOML; its kind is told by its tables (`[live]`; `[[action]]` or `[hairstyle]`;
    /// else a patch scenario). Errors name the bad key.
    pub fn from_toml(text: &str) -> Result<Self, ScenarioError> {
        let bad = |e: toml::de::Error| ScenarioError::Invalid(e.to_string());
        let table: toml::Table = toml::from_str(text).map_err(bad)?;
        Ok(if table.contains_key("live") {
            ScenarioFile::Live(toml::from_str(text).map_err(bad)?)
        } else if table.contains_key("action") || table.contains_key("hairstyle") {
            ScenarioFile::Global(toml::from_str(text).map_err(bad)?)
        } else {
            ScenarioFile::Patch(toml::from_str(text).map_err(bad)?)
        })
    }

    /// The scenario's `name`, if it gives one.
    pub fn name(&self) -> Option<&str> {
        match self {
            ScenarioFile::Patch(s) => s.name.as_deref(),
            ScenarioFile::Global(s) => s.name.as_deref(),
            ScenarioFile::Live(s) => s.name.as_deref(),
        }
    }

    /// The kind: "patch", "global" or "live".
    pub fn kind(&self) -> &'static str {
        match self {
            ScenarioFile::Patch(_) => "patch",
            ScenarioFile::Global(_) => "global",
            ScenarioFile::Live(_) => "live",
        }
    }
}

/// The summary of a run, by kind.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ScenarioSummary {
    /// A patch scenario's.
    Patch(Summary),
    /// A global scenario's.
    Global(GlobalSummary),
    /// A live scenario's (or a replayed record's).
    Live(LiveSummary),
}

/// Everything a scenario run produces, in memory.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioOutput {
    /// "patch", "global", "live" or "replay".
    pub kind: &'static str,
    /// The force trace (patch and live scenarios; empty for global ones).
    pub force: ForceTrace,
    /// The global scenario's rows (every `global_dt`; empty for the other kinds).
    pub global_rows: Vec<GlobalRow>,
    /// A combing rig's recording: the force by the comb's position from the roots, stroke by stroke (patch
    /// scenarios; empty for the other kinds).
    pub profile: CombingProfile,
    /// The summary.
    pub summary: ScenarioSummary,
    /// The global scenario's final hairstyle and cut pieces (not serialised).
    #[serde(skip)]
    pub hair: Option<(hairstyle::HairCurves, hairstyle::HairCurves)>,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
}

/// Runs a scenario of any kind. A patch scenario's tool must be built in and its path inline (the CLI
/// loads shape and path files and calls [`run_patch`]).
pub fn run(file: &ScenarioFile) -> Result<ScenarioOutput, ScenarioError> {
    match file {
        ScenarioFile::Patch(s) => {
            let shape = ToolShape::builtin(&s.tool.shape).map_err(|_| ScenarioError::Invalid(format!("tool.shape {:?} is not a built-in shape (a shape file is loaded by the caller: run_patch)", s.tool.shape)))?;
            if s.tool.path_file.is_some() {
                return Err(ScenarioError::Invalid("tool.path_file is read by the caller (run_patch); give tool.path inline".into()));
            }
            let path = ToolPath::new(s.tool.path.clone()).map_err(|e| ScenarioError::Invalid(format!("tool.path: {e}")))?;
            run_patch(s, shape, &path)
        }
        ScenarioFile::Global(s) => {
            let t0 = std::time::Instant::now();
            let out = s.run()?;
            let mut summary = out.summary;
            let wall = t0.elapsed().as_secs_f64();
            summary.wall_time_s = wall;
            Ok(ScenarioOutput { kind: "global", force: ForceTrace::default(), global_rows: out.rows, profile: CombingProfile::default(), summary: ScenarioSummary::Global(summary), hair: Some((out.hairstyle, out.pieces)), wall_time_s: wall })
        }
        ScenarioFile::Live(s) => run_live_on(s, std::sync::Arc::new(s.scene_in(std::path::Path::new("."))?)),
    }
}

/// Runs a live scenario on `scene` (from [`LiveScenario::scene_in`]) into a [`ScenarioOutput`].
pub fn run_live_on(s: &LiveScenario, scene: std::sync::Arc<crate::scene::Scene>) -> Result<ScenarioOutput, ScenarioError> {
    let (force, summary) = s.run_on(scene)?;
    let wall = summary.wall_time_s;
    Ok(ScenarioOutput { kind: "live", force, global_rows: Vec::new(), profile: CombingProfile::default(), summary: ScenarioSummary::Live(summary), hair: None, wall_time_s: wall })
}

/// Runs a patch scenario with its tool `shape` and `path` (loaded by the caller).
pub fn run_patch(s: &Scenario, shape: ToolShape, path: &ToolPath) -> Result<ScenarioOutput, ScenarioError> {
    let t0 = std::time::Instant::now();
    let (rows, mut summary) = s.run(shape, path)?;
    let wall = t0.elapsed().as_secs_f64();
    summary.wall_time_s = wall;
    let mut force = ForceTrace::default();
    for r in &rows {
        force.push(r.t, &r.force, &r.torque, r.contacts as u32, &r.tool);
    }
    let profile = s.profile(&rows);
    Ok(ScenarioOutput { kind: "patch", force, global_rows: Vec::new(), profile, summary: ScenarioSummary::Patch(summary), hair: None, wall_time_s: wall })
}
