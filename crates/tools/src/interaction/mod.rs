//! The local interaction: a tool touching a patch of strands, one haptic step at a time.
//!
//! Stages of [`LocalInteraction::step`] (`step.rs`), in order:
//! 1. **Hold** (`hold.rs`): the hair volume's pull towards each held strand's place, in turns.
//! 2. **Dynamics** (constraint model): every strand's free step is prepared ([`strand::Strand::prepare_step`]),
//!    batched strands together ([`strand::StrandBatch`]).
//! 3. **Sample** (`sample.rs`): every strand's centreline as straight pieces (two per helical segment, read from
//!    the prepared sweep), and the AABB tree refitted.
//! 4. **Detect**: contacts between the tool's swept motion and the pieces ([`crate::contact::detect`]), and the
//!    hair-hair contacts ([`crate::hair_contact`]).
//! 5. **Rows**, per strand: its constraints (tool contacts and, with the entanglement, drags against the
//!    parted fibres; clip pins; body contacts; hair-hair contacts) as rows of its prepared step, warm-started
//!    from the last step's impulses (`warm.rs`); with the paper's [`ForceModel`] the strand steps here with
//!    the explicit point forces.
//! 6. **Solve**: all strands' rows in one projected Gauss-Seidel solve ([`strand::constraint::solve`]), a
//!    hair-hair contact linking its two strands' rows.
//! 7. **Commit**, per strand: the impulses applied and the step committed; the tool contacts' compliance gives
//!    the reaction's damping and stiffness ([`StepResult`]), surface friction the brush torque (applied at the
//!    next step).
//! 8. **Reaction**: the tool receives the exact opposite of what the strands received: force and torque about
//!    its origin.
//!
//! A clip ([`LocalInteraction::clip`]) pins strand points to the tool: they follow it (constraint model only).
//! Files: `model.rs` (the force model), `result.rs` (what a step gives), `hold.rs`, `sample.rs`, `warm.rs`,
//! `step.rs` (the stages), this file (the interaction's state and its changes between steps).

mod hold;
mod model;
mod result;
mod sample;
mod step;
mod warm;

pub use crate::entanglement::Entanglement;
pub use crate::hair_contact::HairContact;
pub use hold::{hold_rate, Hold, HOLD_EVERY, HOLD_LOADS};
pub use model::ForceModel;
pub use result::{StepResult, StepTimings};

use crate::bvh::{Bvh, Piece};
use crate::contact::{Contact, ToolPose};
use crate::hair_contact::HairContactFinder;
use crate::shape::ToolShape;
use nalgebra::Vector3;
use strand::constraint::{ConstraintRows, PointConstraint};
use strand::{ModelKind, PointForce, Strand, StrandBatch};
use warm::{HairSide, Warm, WarmTag};

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
    /// Constraint model: prepare the steps of reduced strands four at a time ([`StrandBatch`], SIMD lanes)
    /// instead of one by one. Same results to round-off; default true.
    pub use_batches: bool,
    /// Constraint model: the body the strands rest on (the head, neck and shoulders as metaballs, world
    /// frame) and its iso-surface threshold. Each strand's sampled points that are inside it, or within a
    /// hair's radius of its surface, get a contact pushing them out with Coulomb friction
    /// `body_friction` (the tool does not feel it). Default None (no body).
    pub body: Option<(lattice::metaball::MetaballSet, f64)>,
    /// Where the hair volume holds each strand ([`Hold`]; one entry per strand, None: not held). The caller
    /// keeps it up to date; [`LocalInteraction::set_strands`] carries each strand's over (None for a new
    /// one). Default empty.
    pub holds: Vec<Option<Hold>>,
    /// The hold's displacement scale, m: the unsimulated neighbours pull a held strand back towards its place
    /// with a spring per unit length that carries the strand's own weight at this displacement,
    /// `k = lambda |g| / hold_distance` (N/m per m of strand), applied explicitly at [`HOLD_LOADS`] points per
    /// strand. Infinite: no hold. Default infinite.
    pub hold_distance: f64,
    /// The gravity |g| the hold's spring is scaled with, m/s^2; None: each strand model's own. A caller whose
    /// strands carry no weight of their own (the hair volume carries it, e.g. the live session's local strands,
    /// whose models have no gravity) gives the scene's. Default None.
    pub hold_gravity: Option<f64>,
    /// Which strands get their hold this step ([`HOLD_EVERY`]).
    hold_phase: usize,
    /// Constraint model: Coulomb friction coefficient of the body contacts (dimensionless, >= 0): a strand
    /// lies on the scalp and on the hair beneath it, and without friction a strand resting on the curved
    /// head is free to slide round it. Default 0 (frictionless).
    pub body_friction: f64,
    /// Constraint model: contact and friction between the simulated strands ([`HairContact`]). Default None
    /// (strands pass through each other).
    pub hair_contact: Option<HairContact>,
    /// Constraint model: the drag of the tool's capsules through the wisps they pass through, against the
    /// fibres they part ([`Entanglement`]; the wisp's radius is [`HairContact`]'s, the fibre's without hair
    /// contact). Default None (a tool touches a strand only at the fibre's radius).
    pub entanglement: Option<Entanglement>,
    /// Wetness of each strand (dimensionless, 0..1; missing entries are dry), for the capillary share of the
    /// entanglement drag. The strands' material and the friction take wetness through
    /// [`crate::wetness::WetnessModel`] where they are built. Default empty (dry).
    pub wetness: Vec<f64>,
    /// Workspace: hair-hair contact detection ([`crate::hair_contact`]).
    hair_finder: HairContactFinder,
    /// Each strand's rest shape for hair-hair contact, as centreline pieces (empty: none), set by
    /// [`LocalInteraction::set_rest_shape`]: wisps closer than the contact distance at rest touch only closer
    /// than their rest distance ([`HairContactFinder::detect`]).
    rest_shapes: Vec<Vec<Piece>>,
    /// Workspace: the rest pieces aligned with `pieces` (NaN where a strand has none; empty when no strand has a
    /// rest shape), rebuilt only when the strands, their rest shapes or their number of pieces change.
    rest_pieces: Vec<Piece>,
    /// `rest_pieces` must be rebuilt (strands or rest shapes changed).
    rest_stale: bool,
    /// Workspaces of the batches, and each strand's (batch, lane) this step.
    batches: Vec<StrandBatch>,
    lane_of: Vec<Option<(usize, usize)>>,
    /// Loads applied to each strand at the next step: twisting torques from last step's surface friction
    /// and the loads given to [`LocalInteraction::add_load`].
    surface_torques: Vec<Vec<PointForce>>,
    pieces: Vec<Piece>,
    /// Each strand's tip at the start of the last step (its last piece's end), m; NaN before its first step.
    tips: Vec<Vector3<f64>>,
    bvh: Bvh,
    /// Build the tree anew at the next step rather than refit it.
    rebuild_tree: bool,
    /// Workspace: which strands' steps were prepared this step.
    prepared: Vec<bool>,
    /// Workspace: contacts of this step.
    contacts: Vec<Contact>,
    /// Workspace: each strand's hair-hair contacts this step, with the pair side each stands for.
    hair_rows: Vec<Vec<(HairSide, PointConstraint)>>,
    /// Workspace: per hair-hair pair, where its first and second strand's rows went (rows index, constraint
    /// index).
    hair_slots: Vec<[Option<(usize, usize)>; 2]>,
    /// Workspace: the constrained strands' rows of this step (the first ones in use), storage kept.
    rows: Vec<ConstraintRows>,
    /// Each strand's constraint impulses of the last step: the next solve starts from them
    /// ([`LocalInteraction::warm_start`]).
    warm: Vec<Vec<Warm>>,
    /// Workspace of [`LocalInteraction::warm_start`]: which of a strand's last impulses are taken.
    warm_used: Vec<bool>,
    /// Each strand's arc length (m) at which the comb entered the wisp, while a tooth drags through it (None when
    /// none does): the crossings the comb pushes ahead are those it met since ([`Entanglement::pile_factor`]). A
    /// wisp that leaves every tooth leaves its pile behind.
    piles: Vec<Option<f64>>,
}

impl LocalInteraction {
    /// Sets up the interaction with the tool at `pose`.
    pub fn new(strands: Vec<Strand>, shape: ToolShape, pose: ToolPose, model: ForceModel) -> Self {
        let pieces = Self::sample(&strands);
        let margin = Self::hair_radius(&strands);
        let bvh = Bvh::build(&pieces, margin);
        let surface_torques = vec![Vec::new(); strands.len()];
        let prepared = vec![false; strands.len()];
        let lane_of = vec![None; strands.len()];
        let strands_len = strands.len();
        Self {
            strands,
            shape,
            pose,
            model,
            pins: Vec::new(),
            use_batches: true,
            body: None,
            body_friction: 0.0,
            holds: Vec::new(),
            hold_distance: f64::INFINITY,
            hold_gravity: None,
            hold_phase: 0,
            hair_contact: None,
            entanglement: None,
            wetness: Vec::new(),
            hair_finder: HairContactFinder::new(),
            rest_shapes: vec![Vec::new(); strands_len],
            rest_pieces: Vec::new(),
            tips: Vec::new(),
            rest_stale: false,
            batches: Vec::new(),
            lane_of,
            surface_torques,
            pieces,
            bvh,
            rebuild_tree: false,
            prepared,
            contacts: Vec::new(),
            hair_rows: Vec::new(),
            hair_slots: Vec::new(),
            rows: Vec::new(),
            warm: vec![Vec::new(); strands_len],
            warm_used: Vec::new(),
            piles: vec![None; strands_len],
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
        self.rest_stale = true;
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
        self.prepared.clear();
        self.prepared.resize(strands.len(), false);
        self.lane_of.clear();
        self.lane_of.resize(strands.len(), None);
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
        self.rebuild_tree = true;
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
            self.rest_stale = true;
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
        self.rest_stale = true;
        true
    }

    /// Aligns the strands' rest shapes with this step's pieces into `rest_pieces` (NaN for a strand whose rest
    /// shape is missing or has another number of pieces; empty when no strand has one).
    fn rebuild_rest_pieces(&mut self) {
        self.rest_stale = false;
        self.rest_pieces.clear();
        if self.rest_shapes.iter().all(|r| r.is_empty()) {
            return;
        }
        let nan = Vector3::repeat(f64::NAN);
        let mut i = 0;
        while i < self.pieces.len() {
            let k = self.pieces[i].strand;
            let n = self.pieces[i..].iter().take_while(|p| p.strand == k).count();
            match self.rest_shapes.get(k).filter(|r| r.len() == n) {
                Some(r) => self.rest_pieces.extend_from_slice(r),
                None => self.rest_pieces.extend(self.pieces[i..i + n].iter().map(|p| Piece { a: nan, b: nan, ..*p })),
            }
            i += n;
        }
    }

    /// Prepares the steps of the reduced, linearly implicit strands in batches of four strands of equal size
    /// ([`StrandBatch::prepare`]); marks them prepared and remembers their lanes. Strands left out (another
    /// model or integrator, a lane that failed) are prepared one by one afterwards.
    fn prepare_batched(&mut self, dt: f64) {
        self.lane_of.clear();
        self.lane_of.resize(self.strands.len(), None);
        let mut groups: Vec<((usize, usize), Vec<usize>)> = Vec::new();
        for (k, s) in self.strands.iter().enumerate() {
            // A strand that carries the last step's constraint loads takes their geometric stiffness in its own
            // (scalar) step.
            if s.model.kind != ModelKind::Reduced || s.integrator != strand::Integrator::LinearlyImplicitEuler || !s.constraint_loads.is_empty() {
                continue;
            }
            let key = (s.model.segments, s.dynamics.quadrature_nodes().len());
            match groups.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.push(k),
                None => groups.push((key, vec![k])),
            }
        }
        let mut b = 0;
        for (key, members) in groups {
            for chunk in members.chunks(strand::batch::LANES) {
                if self.batches.len() <= b {
                    self.batches.push(StrandBatch::new(key.0, key.1));
                } else if !self.batches[b].accepts(&self.strands[chunk[0]]) {
                    self.batches[b] = StrandBatch::new(key.0, key.1);
                }
                let ext: Vec<&[PointForce]> = chunk.iter().map(|&k| self.surface_torques[k].as_slice()).collect();
                let mut refs: Vec<&mut Strand> = self.strands.iter_mut().enumerate().filter(|(k, _)| chunk.contains(k)).map(|(_, s)| s).collect();
                // A lane that fails is left unprepared; its strand's own step reports the error below.
                let _ = self.batches[b].prepare(dt, &mut refs, &ext);
                for (j, &k) in chunk.iter().enumerate() {
                    if self.strands[k].has_prepared_step() {
                        self.prepared[k] = true;
                        self.lane_of[k] = Some((b, j));
                        self.surface_torques[k].clear();
                    }
                }
                b += 1;
            }
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
