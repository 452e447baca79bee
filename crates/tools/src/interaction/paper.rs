//! The paper's contact model (its section 4.3, [`super::ForceModel::Paper`]): each tool contact pushes its strand across
//! itself with a force proportional to the tool's velocity across the strand, applied explicitly as a point
//! force in the strand's own step.

use super::LocalInteraction;
use crate::contact::Contact;
use nalgebra::Vector3;
use strand::kinematics::{frame_at, segment_frames};
use strand::{PointForce, Strand, StrandError};

impl LocalInteraction {
    /// Steps `strand` for `dt` s with the paper's force of each of its tool contacts `mine` ([`super::ForceModel::Paper`]
    /// with `gain`, m s) and its other loads for this step `loads` (taken: cleared). Returns the step's outcome
    /// and each contact's force on the strand (N) with its lever about the tool's origin (m), for the reaction.
    pub(super) fn paper_step(strand: &mut Strand, gain: f64, mine: &[&Contact], loads: &mut Vec<PointForce>, dt: f64) -> (Result<(), StrandError>, Vec<(Vector3<f64>, Vector3<f64>)>) {
        let w = strand.model.material.density * strand.model.gravity.norm();
        let area = strand.model.section.area();
        let applied: Vec<PointForce> = if mine.is_empty() {
            Vec::new()
        } else {
            let frames = segment_frames(&strand.model, &strand.state);
            mine.iter()
                .map(|c| {
                    let tangent = frame_at(&strand.model, &strand.state.q, &frames, c.s).rotation.column(0).into_owned();
                    let perp = c.tool_velocity - tangent * tangent.dot(&c.tool_velocity);
                    let l = c.s.max(1e-3 * strand.model.length);
                    PointForce::new(c.s, perp * (gain * w * area / l))
                })
                .collect()
        };
        // The contact forces first (their reactions are read below), then the strand's other loads.
        let mut all = applied.clone();
        all.extend(loads.iter().copied());
        let r = strand.step(dt, &all);
        loads.clear();
        (r.map(|_| ()), applied.iter().zip(mine).map(|(f, c)| (f.force, c.lever)).collect())
    }
}
