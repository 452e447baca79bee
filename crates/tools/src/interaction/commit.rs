//! Stage 7, per strand: the solved impulses applied and the step committed; the tool contacts' compliance gives the
//! reaction's damping and stiffness ([`super::StepResult`]), surface friction the brush torque (applied at the
//! next step).

use super::frame::{Solved, StepFrame};
use super::warm::Warm;
use super::LocalInteraction;
use nalgebra::{Matrix3, Vector3};
use strand::constraint::ConstraintOptions;
use strand::PointForce;

impl LocalInteraction {
    /// Stage 7: commits every strand waiting in `frame.pending` with the solver `options` and the tool's friction
    /// coefficient `friction`, adding its tool constraints' forces to `frame.forces` and their linearisation and
    /// torques to `frame.result`.
    pub(super) fn commit_strands(&mut self, frame: &mut StepFrame, friction: f64, options: &ConstraintOptions) {
        let dt = frame.dt;
        let mix = options.force_mixing(dt);
        let beta = options.error_reduction_rate(dt);
        for job in std::mem::take(&mut frame.pending) {
            let t_strand = frame.clock.elapsed().as_secs_f64();
            let strand = &mut self.strands[job.strand];
            let outcome = match job.solved {
                Solved::Stepped(p) => Ok((p, vec![0.0; job.touching.len()])),
                Solved::Rows(i) => {
                    let r = &frame.rows[i];
                    // The tool contacts' mobilities in the prepared step, for the tool's damping.
                    let mobility: Vec<f64> = job.touching.iter().enumerate().map(|(c, t)| t.map_or(0.0, |t| r.mobility(c, &t.normal))).collect();
                    strand.apply_constraints(r, options).map(|p| (p, mobility))
                }
            };
            if let Ok((p, _)) = &outcome {
                let warm = &mut self.warm[job.strand];
                warm.clear();
                warm.extend(job.tags.iter().zip(p).map(|(&(tag, s), &impulse)| Warm { tag, s, impulse }));
            }
            match outcome {
                Ok((p, mobility)) => {
                    // Friction acts on the hair's surface, a radius away from the centreline towards the tool:
                    // it also twists the strand (brush torque). Applied at the next step; the tool feels the
                    // opposite torque now.
                    let r = strand.model.section.semi_major;
                    for (((impulse, c), w), &solid) in p.iter().zip(&job.touching).zip(&mobility).zip(&job.solid) {
                        let Some(c) = c else { continue };
                        if solid && impulse.dot(&c.normal) > 0.0 {
                            let g = 1.0 / (dt * (w + mix));
                            let nn = c.normal * c.normal.transpose();
                            frame.result.damping += nn * g + (Matrix3::identity() - nn) * (friction * g);
                            if beta * c.depth < options.max_correction_speed {
                                frame.result.stiffness += nn * (beta * g);
                            }
                        }
                        let f = impulse / dt;
                        let tangential = f - c.normal * c.normal.dot(&f);
                        let tau = (-c.normal * r).cross(&tangential);
                        if tau.norm() > 0.0 {
                            self.surface_torques[job.strand].push(PointForce { s: c.s, force: Vector3::zeros(), torque: tau });
                            frame.result.torque -= tau;
                        }
                    }
                    frame.forces.extend(p.iter().zip(&job.levers).map(|(p, l)| (p / dt, *l)));
                }
                Err(e) => {
                    frame.first_error.get_or_insert(e);
                }
            }
            let spent = frame.clock.elapsed().as_secs_f64() - t_strand;
            if job.touched {
                frame.timings.constrained += spent;
            } else {
                frame.timings.free += spent;
            }
        }
    }
}
