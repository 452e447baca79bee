//! What one interaction step produced: the tool's force and torque, their linearisation, the contacts and where the
//! step's time went.

use crate::contact::{Contact, DetectReport};
use nalgebra::{Matrix3, Vector3};

/// What one interaction step produced.
#[derive(Debug, Clone, Default)]
pub struct StepResult {
    /// Force on the tool, N (the opposite of the sum of the forces on the strands).
    pub force: Vector3<f64>,
    /// Torque on the tool about its origin, N m.
    pub torque: Vector3<f64>,
    /// Linearisation of `force` in the tool's velocity (constraint model): the effective damping
    /// `D = -dF/dv`, N s/m, symmetric positive semi-definite. Each pressing contact (normal impulse > 0)
    /// adds its compliant response `g = 1 / (h (W_nn + R))` (the strand point's mobility `W_nn` in the
    /// prepared step, [`ConstraintRows::mobility`](strand::constraint::ConstraintRows::mobility), and the solver's force mixing `R`) along its normal,
    /// `g n n^T`, and the friction's share `mu g (I - n n^T)` across it. Coupling between contacts is left
    /// out, and so are the entanglement drags ([`Entanglement`](crate::entanglement::Entanglement): a sliding Coulomb drag does not change with
    /// the speed). Zero with the paper's model. Used to couple the tool proxy implicitly
    /// (`haptics::coupling::HairReaction`).
    pub damping: Matrix3<f64>,
    /// Linearisation of `force` in the tool's position (constraint model): the effective stiffness
    /// `K = -dF/dx`, N/m, symmetric positive semi-definite. A pressing contact asks its strand point to leave
    /// the tool at `beta` times its depth (`ConstraintOptions::error_reduction_rate`) while that stays below
    /// `max_correction_speed`: a tool `dx` deeper asks `beta dx` more speed, which its compliant response turns
    /// into `g beta dx` more force along the normal; so each such contact adds `beta g n n^T`. Zero with the
    /// paper's model. With `damping`, the local force model the device loop renders between steps
    /// (`haptics::coupling::HairReaction`).
    pub stiffness: Matrix3<f64>,
    /// Contacts found this step.
    pub contacts: Vec<Contact>,
    /// Detection details (sub-steps, too-fast flag).
    pub report: DetectReport,
    /// Hair-hair contacts found this step (pairs of strand chords closer than the contact distance, before
    /// each strand keeps its deepest; see [`crate::hair_contact`]).
    pub hair_pairs: usize,
    /// Where the step's time went (wall clock).
    pub timings: StepTimings,
}

/// Wall-clock time of the phases of one [`LocalInteraction::step`](super::LocalInteraction::step), s.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepTimings {
    /// Every strand's dynamics at the current state and unconstrained velocities (constraint model: the first
    /// half of each step, [`Strand::prepare_step`](strand::Strand::prepare_step)), s.
    pub dynamics: f64,
    /// Sampling the centrelines into pieces and refitting the AABB tree, s.
    pub sample: f64,
    /// Contact detection, s.
    pub detect: f64,
    /// Of `detect`: the hair-hair contacts ([`HairContactFinder`](crate::hair_contact::HairContactFinder)), s.
    pub hair_detect: f64,
    /// Strands with contacts: constraint assembly, projected Gauss-Seidel and commit (paper model: the strand
    /// steps with contact forces), s.
    pub constrained: f64,
    /// Strands without contacts: commit of the prepared step (paper model: their whole step), s.
    pub free: f64,
    /// Strands that had contacts this step.
    pub touched_strands: usize,
    /// Of `constrained` and `free`: finding the strands' body contacts, s.
    pub body: f64,
    /// Projected Gauss-Seidel sweeps of the common solve (0 without constraints).
    pub sweeps: usize,
    /// Constraint rows of the common solve (tool, pins, body and both sides of the hair-hair contacts).
    pub rows: usize,
    /// Of `constrained`: the common solve's sweeps alone ([`solve`](strand::constraint::solve)), s.
    pub solve: f64,
    /// The most constraint rows of one strand in the common solve.
    pub strand_rows: usize,
    /// Hair-hair links of the common solve (contacts solved for both strands at once).
    pub links: usize,
}
