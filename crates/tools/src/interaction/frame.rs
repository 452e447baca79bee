//! What the stages of [`LocalInteraction::step`](super::LocalInteraction::step) hand each other: [`StepFrame`], and
//! each constrained strand's step waiting between its rows and its commit ([`Pending`]).

use super::warm::{HairSide, WarmTag};
use super::{StepResult, StepTimings};
use crate::contact::{Contact, ToolPose};
use nalgebra::Vector3;
use strand::constraint::{ConstraintRows, PointConstraint};
use strand::StrandError;

/// What one step's stages hand each other: the step's inputs, its clock and timings, the buffers taken from
/// the interaction's workspaces for the step (given back at its end, storage kept) and the result being built.
pub(super) struct StepFrame {
    /// The step's length, s.
    pub dt: f64,
    /// The tool's pose at the step's end.
    pub pose: ToolPose,
    /// Whether the contact model is the constraint model.
    pub constraint: bool,
    /// The step's wall clock, for `timings`.
    pub clock: std::time::Instant,
    pub timings: StepTimings,
    /// The first strand error of the step (the other strands step on).
    pub first_error: Option<StrandError>,
    /// Largest fibre radius of the strands, m, and the distance from a centreline the tool is looked for within
    /// (`LocalInteraction::reach_radius`), m (stage 3).
    pub radius: f64,
    pub reach: f64,
    /// The tool's contacts with the pieces (stage 4).
    pub contacts: Vec<Contact>,
    /// Hair-hair contact is on (constraint model with `LocalInteraction::hair_contact`).
    pub hair_on: bool,
    /// Each strand's hair-hair contacts with the pair side each stands for, and per pair where its two rows went
    /// (rows index, constraint index) (stages 4-5).
    pub hair_rows: Vec<Vec<(HairSide, PointConstraint)>>,
    pub hair_slots: Vec<[Option<(usize, usize)>; 2]>,
    /// The constrained strands' rows (the first `used` in use) and each strand's step waiting for the solve
    /// (stage 5).
    pub rows: Vec<ConstraintRows>,
    pub used: usize,
    pub pending: Vec<Pending>,
    /// Forces on the strands (N) with their levers about the tool's origin (m), for the reaction (stages 5, 7).
    pub forces: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// The step's result, built along the stages.
    pub result: StepResult,
}

/// How a strand's constrained step stands between the stages of [`LocalInteraction::step`](super::LocalInteraction::step).
pub(super) enum Solved {
    /// Its rows, at this index of the step's rows, wait for the common solve.
    Rows(usize),
    /// It stepped on its own (its step could not be prepared), with these impulses, N s.
    Stepped(Vec<Vector3<f64>>),
}

/// A strand's constrained step between the stages of [`LocalInteraction::step`](super::LocalInteraction::step): the tool constraints' levers
/// (m) and contacts (the first `levers.len()` constraints are the tool's), and whether it had constraints.
pub(super) struct Pending {
    pub strand: usize,
    /// What each of its constraints is, to warm-start the next step's solve.
    pub tags: Vec<(WarmTag, f64)>,
    pub levers: Vec<Vector3<f64>>,
    pub touching: Vec<Option<Contact>>,
    /// Per tool constraint: whether it is a non-penetrating contact (its compliance enters the reaction's damping
    /// and stiffness; a spine's cushion clear of the centreline's fibre pushes with its load alone).
    pub solid: Vec<bool>,
    pub solved: Solved,
    pub touched: bool,
}
