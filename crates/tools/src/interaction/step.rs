//! The interaction step as its list of stages (see the module documentation of `interaction`), each stage in
//! its own file; what they hand each other is in `frame.rs`.

use super::frame::StepFrame;
use super::{ForceModel, LocalInteraction, StepResult, StepTimings};
use crate::contact::ToolPose;
use strand::StrandError;

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
        self.ws.rows = rows;
        self.ws.hair_rows = hair_rows;
        self.ws.hair_slots = hair_slots;
        for (f, lever) in forces {
            result.force -= f;
            result.torque -= lever.cross(&f);
        }
        self.pose = pose;
        result.contacts = contacts.clone();
        self.ws.contacts = contacts;
        result.timings = timings;
        match first_error {
            Some(e) => Err(e),
            None => Ok(result),
        }
    }
}
