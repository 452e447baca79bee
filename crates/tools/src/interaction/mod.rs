//! The local interaction: a tool touching a patch of strands, one haptic step at a time.
//!
//! Stages of [`LocalInteraction::step`] (`step.rs`: the list; `frame.rs`: what the stages hand each other),
//! each in its own file:
//! 1. **Hold** (`hold.rs`): the hair volume's pull towards each held strand's place, in turns.
//! 2. **Dynamics** (`prepare.rs`, constraint model): every strand's free step is prepared
//!    ([`strand::Strand::prepare_step`]), batched strands together ([`strand::StrandBatch`]).
//! 3. **Sample** (`sample.rs`): every strand's centreline as straight pieces (two per helical segment, read from
//!    the prepared sweep), and the AABB tree refitted.
//! 4. **Detect** (`detect.rs`): contacts between the tool's swept motion and the pieces
//!    ([`crate::contact::detect`]), and the hair-hair contacts ([`crate::hair_contact`]) as pairs of rows.
//! 5. **Rows** (`rows.rs`), per strand: its constraints (tool contacts and, with the entanglement, drags against
//!    the parted fibres; clip pins; body contacts; hair-hair contacts) as rows of its prepared step, warm-started
//!    from the last step's impulses (`warm.rs`); with the paper's [`ForceModel`] (`paper.rs`) the strand steps
//!    here with the explicit point forces.
//! 6. **Solve** (`solve.rs`): all strands' rows in one projected Gauss-Seidel solve
//!    ([`strand::constraint::solve`]), a hair-hair contact linking its two strands' rows.
//! 7. **Commit** (`commit.rs`), per strand: the impulses applied and the step committed; the tool contacts'
//!    compliance gives the reaction's damping and stiffness ([`StepResult`]), surface friction the brush torque
//!    (applied at the next step).
//! 8. **Reaction** (`step.rs`): the tool receives the exact opposite of what the strands received: force and
//!    torque about its origin.
//!
//! A clip ([`LocalInteraction::clip`]) pins strand points to the tool: they follow it (constraint model only).
//! Other files: `model.rs` (the force model), `result.rs` (what a step gives), this file (the interaction's
//! settings, state and workspaces, and their changes between steps).

mod commit;
mod detect;
mod frame;
mod hold;
mod model;
mod params;
mod paper;
mod pile;
mod prepare;
mod result;
mod rows;
mod sample;
mod solve;
mod step;
mod warm;
mod workspace;

pub use crate::entanglement::Entanglement;
pub use crate::hair_contact::HairContact;
pub use hold::{hold_rate, Hold, HOLD_EVERY, HOLD_LOADS};
pub use model::ForceModel;
use pile::Pile;
pub use params::InteractionParams;
pub use result::{StepResult, StepTimings};

use crate::bvh::Piece;
use crate::contact::ToolPose;
use crate::shape::ToolShape;
use nalgebra::Vector3;
use strand::{PointForce, Strand};
use warm::{Warm, WarmTag};
use workspace::Workspace;

/// A patch of strands, a tool, and the contact between them.
#[derive(Debug, Clone)]
pub struct LocalInteraction {
    /// The strands near the tool.
    pub strands: Vec<Strand>,
    /// The tool's shape.
    pub shape: ToolShape,
    /// The tool's pose at the end of the last step.
    pub pose: ToolPose,
    /// Contact response.
    pub model: ForceModel,
    /// Strand points held by the tool (a clip): (strand, arc length in m, offset in the tool frame in m).
    pub pins: Vec<(usize, f64, Vector3<f64>)>,
    /// Settings: the body, its friction, the hold, hair-hair contact, the entanglement, the batching
    /// ([`InteractionParams`]; the caller sets them between steps).
    pub params: InteractionParams,
    /// Where the hair volume holds each strand ([`Hold`]; one entry per strand, None: not held). The caller
    /// keeps it up to date; [`LocalInteraction::set_strands`] carries each strand's over (None for a new
    /// one). Default empty.
    pub holds: Vec<Option<Hold>>,
    /// Which strands get their hold this step ([`HOLD_EVERY`]).
    hold_phase: usize,
    /// Wetness of each strand (dimensionless, 0..1; missing entries are dry), for the capillary share of the
    /// entanglement drag. The strands' material and the friction take wetness through
    /// [`crate::wetness::WetnessModel`] where they are built. Default empty (dry).
    pub wetness: Vec<f64>,
    /// Each strand's rest shape for hair-hair contact, as centreline pieces (empty: none), set by
    /// [`LocalInteraction::set_rest_shape`]: wisps closer than the contact distance at rest touch only closer
    /// than their rest distance ([`HairContactFinder::detect`]).
    rest_shapes: Vec<Vec<Piece>>,
    /// Loads applied to each strand at the next step: twisting torques from last step's surface friction
    /// and the loads given to [`LocalInteraction::add_load`].
    surface_torques: Vec<Vec<PointForce>>,
    pieces: Vec<Piece>,
    /// Each strand's tip at the start of the last step (its last piece's end), m; NaN before its first step.
    tips: Vec<Vector3<f64>>,
    /// Each strand's constraint impulses of the last step: the next solve starts from them
    /// ([`LocalInteraction::warm_start`]).
    warm: Vec<Vec<Warm>>,
    /// Each strand's pile of tangles pushed ahead of the comb ([`Pile`]: where the comb entered the wisp and the
    /// farthest a tooth has dragged through it since; None before any drag): the crossings the comb pushes ahead are
    /// those it met since ([`Entanglement::pile_factor`]).
    piles: Vec<Option<Pile>>,
    /// Buffers and caches of the step ([`workspace`]).
    ws: Workspace,
}

impl LocalInteraction {
    /// Sets up the interaction with the tool at `pose`.
    pub fn new(strands: Vec<Strand>, shape: ToolShape, pose: ToolPose, model: ForceModel) -> Self {
        let pieces = Self::sample(&strands);
        let margin = Self::hair_radius(&strands);
        let n = strands.len();
        Self {
            ws: Workspace::new(n, &pieces, margin),
            strands,
            shape,
            pose,
            model,
            pins: Vec::new(),
            params: InteractionParams::default(),
            holds: Vec::new(),
            hold_phase: 0,
            wetness: Vec::new(),
            rest_shapes: vec![Vec::new(); n],
            tips: Vec::new(),
            surface_torques: vec![Vec::new(); n],
            pieces,
            warm: vec![Vec::new(); n],
            piles: vec![None; n],
        }
    }

    /// Replaces the strands by `strands`, keeping the workspaces (the batches' solver storage, the contact
    /// buffers): strand `i` of the new set was strand `from[i]` of the old one (its pending surface torques and
    /// loads and its wetness move with it), or is new (`None`, dry). The pins are released (they name old strands). The collision
    /// tree is rebuilt at the next step. Cheaper than a new interaction when a few strands join or leave.
    pub fn set_strands(&mut self, strands: Vec<Strand>, from: &[Option<usize>]) {
        let mut old = std::mem::take(&mut self.surface_torques);
        self.surface_torques = (0..strands.len()).map(|i| match from.get(i).copied().flatten() {
            Some(j) if j < old.len() => std::mem::take(&mut old[j]),
            _ => Vec::new(),
        }).collect();
        if !self.wetness.is_empty() {
            let wet = std::mem::take(&mut self.wetness);
            self.wetness = (0..strands.len()).map(|i| from.get(i).copied().flatten().and_then(|j| wet.get(j).copied()).unwrap_or(0.0)).collect();
        }
        let mut rest = std::mem::take(&mut self.rest_shapes);
        self.rest_shapes = (0..strands.len()).map(|i| match from.get(i).copied().flatten() {
            Some(j) if j < rest.len() => {
                let mut r = std::mem::take(&mut rest[j]);
                r.iter_mut().for_each(|p| p.strand = i);
                r
            }
            _ => Vec::new(),
        }).collect();
        self.ws.rest_stale = true;
        // The last impulses move with their strands; a hair-hair contact's other strand is renamed (dropped if it left).
        let mut new_index = vec![None; self.warm.len()];
        for (i, f) in from.iter().enumerate().take(strands.len()) {
            if let Some(j) = *f {
                if let Some(slot) = new_index.get_mut(j) {
                    *slot = Some(i);
                }
            }
        }
        let piles = std::mem::take(&mut self.piles);
        self.piles = (0..strands.len()).map(|i| match from.get(i).copied().flatten() {
            Some(j) if j < piles.len() => piles[j],
            _ => None,
        }).collect();
        let mut warm = std::mem::take(&mut self.warm);
        self.warm = (0..strands.len()).map(|i| match from.get(i).copied().flatten() {
            Some(j) if j < warm.len() => {
                let mut w = std::mem::take(&mut warm[j]);
                w.retain_mut(|x| match x.tag {
                    WarmTag::Hair(o) => match new_index.get(o).copied().flatten() {
                        Some(n) => {
                            x.tag = WarmTag::Hair(n);
                            true
                        }
                        None => false,
                    },
                    _ => true,
                });
                w
            }
            _ => Vec::new(),
        }).collect();
        self.ws.prepared.clear();
        self.ws.prepared.resize(strands.len(), false);
        self.ws.lane_of.clear();
        self.ws.lane_of.resize(strands.len(), None);
        self.pins.clear();
        let mut holds = std::mem::take(&mut self.holds);
        self.holds = (0..strands.len()).map(|i| match from.get(i).copied().flatten() {
            Some(j) if j < holds.len() => holds[j].take(),
            _ => None,
        }).collect();
        self.strands = strands;
        self.tips.clear();
        // The collision tree is built anew at the next step (`Bvh::rebuild`, about the cost of a refit); the
        // hair-hair sweep's order is re-sorted from the last one.
        self.ws.rebuild_tree = true;
    }

    /// Strand `k`'s tip at the start of the last step (read from that step's collision pieces, no kinematics of
    /// its own), m; None before the strand's first step (or when `k` is out of range).
    pub fn tip_at_last_step(&self, k: usize) -> Option<Vector3<f64>> {
        self.tips.get(k).copied().filter(|x| x.x.is_finite())
    }

    /// Gives strand `k` its rest shape for hair-hair contact: `rest`'s centreline (the same model and
    /// segments as strand `k`; e.g. its groomed state), so that wisps overlapping at rest keep that overlap
    /// rather than being pushed apart ([`HairContactFinder::detect`]). Kept while the strand stays
    /// ([`LocalInteraction::set_strands`] carries it over); a strand whose pieces no longer match (cut) has none.
    pub fn set_rest_shape(&mut self, k: usize, rest: &Strand) {
        if let Some(r) = self.rest_shapes.get_mut(k) {
            r.clear();
            Self::sample_strand(k, rest, r);
            self.ws.rest_stale = true;
        }
    }

    /// As [`LocalInteraction::set_rest_shape`], the rest shape being strand `k` itself in the state `state`
    /// (its coordinates and root; e.g. its groomed state), without copying the strand. False (and nothing
    /// changed) when `state` has another number of coordinates than strand `k` (a cut strand).
    pub fn set_rest_state(&mut self, k: usize, state: &strand::StrandState) -> bool {
        let (Some(s), Some(r)) = (self.strands.get_mut(k), self.rest_shapes.get_mut(k)) else { return false };
        if s.state.q.len() != state.q.len() {
            return false;
        }
        let own = std::mem::replace(&mut s.state, state.clone());
        r.clear();
        Self::sample_strand(k, s, r);
        s.state = own;
        self.ws.rest_stale = true;
        true
    }

    /// Strand `k`'s rest shape for hair-hair contact, as set ([`LocalInteraction::set_rest_state`]; empty if none).
    pub fn rest_shape(&self, k: usize) -> &[Piece] {
        self.rest_shapes.get(k).map_or(&[], |r| r.as_slice())
    }

    /// Gives strand `k` the rest shape `pieces` (as [`LocalInteraction::rest_shape`] returned it for a strand of the
    /// same guide, model and segments: a copy, renamed strand `k`), without evaluating its kinematics again.
    pub fn set_rest_pieces(&mut self, k: usize, pieces: &[Piece]) {
        if let Some(r) = self.rest_shapes.get_mut(k) {
            r.clear();
            r.extend(pieces.iter().map(|p| Piece { strand: k, ..*p }));
            self.ws.rest_stale = true;
        }
    }

    /// Adds a point load (force in N, torque in N m, at arc length `load.s` m) on strand `strand` for the
    /// next step only, e.g. the air of a hair dryer. False (and nothing added) if there is no such strand
    /// or the load is not finite.
    pub fn add_load(&mut self, strand: usize, load: PointForce) -> bool {
        let finite = load.s.is_finite() && load.force.iter().chain(load.torque.iter()).all(|x| x.is_finite());
        match self.surface_torques.get_mut(strand) {
            Some(loads) if finite => {
                loads.push(load);
                true
            }
            _ => false,
        }
    }

    /// Closes a clip: pins the strand point nearest to the tool origin, if one is within `reach` (m); it then
    /// moves with the tool (the paper's "interactively define a fixed strand's position"). Returns the pinned
    /// (strand, arc length) or None.
    pub fn clip(&mut self, reach: f64) -> Option<(usize, f64)> {
        let origin = self.pose.position;
        let mut best: Option<(f64, usize, f64, Vector3<f64>)> = None;
        for p in Self::sample(&self.strands) {
            let t = crate::geometry::closest_point_param(&origin, &p.a, &p.b);
            let x = p.a + (p.b - p.a) * t;
            let d = (x - origin).norm();
            if d <= reach && best.map_or(true, |b| d < b.0) {
                best = Some((d, p.strand, p.s + t * p.length, x));
            }
        }
        let (_, k, s, x) = best?;
        let offset = self.pose.rotation.transpose() * (x - self.pose.position);
        self.pins.push((k, s, offset));
        Some((k, s))
    }

    /// Opens the clip: releases every pinned point.
    pub fn release(&mut self) {
        self.pins.clear();
    }

}

#[cfg(test)]
mod tests;
