//! The interaction step as its list of stages (see the module documentation of `interaction`), each stage in
//! its own file, and what the stages hand each other ([`StepFrame`]).

use super::rows::Pending;
use super::warm::HairSide;
use super::{ForceModel, LocalInteraction, StepResult, StepTimings};
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

impl LocalInteraction {
    /// Moves the tool to `pose` over `dt` seconds and steps every strand. On a strand's failure the error is
    /// returned; the other strands have stepped.
    ///
    /// With the constraint model every strand first evaluates its dynamics and unconstrained velocities
    /// ([`Strand::prepare_step`](strand::Strand::prepare_step)); the collision pieces are then read from that evaluation's frames and Gauss
    /// points (no kinematics of their own), and strands without contacts only commit their prepared step.
    pub fn step(&mut self, dt: f64, pose: ToolPose) -> Result<StepResult, StrandError> {
        let mut frame = StepFrame {
            dt,
            pose,
            constraint: matches!(self.model, ForceModel::Constraint { .. }),
            clock: std::time::Instant::now(),
            timings: StepTimings::default(),
            first_error: None,
            radius: 0.0,
            reach: 0.0,
            contacts: Vec::new(),
            hair_on: false,
            hair_rows: Vec::new(),
            hair_slots: Vec::new(),
            rows: Vec::new(),
            used: 0,
            pending: Vec::new(),
            forces: Vec::new(),
            result: StepResult::default(),
        };
        // 1. Hold (`hold.rs`).
        self.hold_strands();
        // 2. Dynamics (`prepare.rs`).
        self.prepare_strands(&mut frame);
        // 3. Sample (`sample.rs`).
        self.sample_pieces(&mut frame);
        // 4. Detect (`detect.rs`).
        self.detect_contacts(&mut frame)?;
        // 5. Rows, per strand (`rows.rs`; the paper's model steps its strands here, `paper.rs`).
        self.strand_rows(&mut frame)?;
        if let ForceModel::Constraint { friction, options } = self.model {
            // 6. Solve (`solve.rs`).
            self.solve_rows(&mut frame, &options);
            // 7. Commit, per strand (`commit.rs`).
            self.commit_strands(&mut frame, friction, &options);
        }
        // 8. Reaction.
        self.react(frame)
    }

    /// Stage 8: the tool receives the exact opposite of what the strands received (force, and torque about its
    /// origin); the buffers go back to the workspaces; the tool is at the step's pose.
    fn react(&mut self, frame: StepFrame) -> Result<StepResult, StrandError> {
        let StepFrame { pose, timings, first_error, contacts, hair_rows, hair_slots, rows, forces, mut result, .. } = frame;
        self.rows = rows;
        self.hair_rows = hair_rows;
        self.hair_slots = hair_slots;
        for (f, lever) in forces {
            result.force -= f;
            result.torque -= lever.cross(&f);
        }
        self.pose = pose;
        result.contacts = contacts.clone();
        self.contacts = contacts;
        result.timings = timings;
        match first_error {
            Some(e) => Err(e),
            None => Ok(result),
        }
    }
}
