//! The local interaction: a tool touching a patch of strands, one haptic step at a time.
//!
//! Pipeline of [`LocalInteraction::step`]:
//! 1. sample every strand's centreline into straight pieces (two per helical segment) and refit the AABB tree;
//! 2. detect contacts between the tool's swept motion and the pieces ([`crate::contact::detect`]);
//! 3. respond with the chosen [`ForceModel`]: the paper's velocity-proportional force as explicit point
//!    forces, or constraints (non-penetration and Coulomb friction) solved inside each strand's implicit step;
//! 4. the tool receives the exact opposite of what the strands received: force and torque about its origin.
//!
//! A clip ([`LocalInteraction::clip`]) pins strand points to the tool: they follow it (constraint model only).
//! With the constraint model, friction acts on the hair's surface: besides its force it twists the strand (the
//! brush torque), applied at the next step, and the tool feels the opposite torque.

use crate::bvh::{Bvh, Piece};
pub use crate::entanglement::Entanglement;
pub use crate::hair_contact::HairContact;
use crate::hair_contact::HairContactFinder;
use crate::contact::{detect, Contact, DetectReport, ToolPose};
use crate::shape::ToolShape;
use nalgebra::{Matrix3, Vector3};
use strand::constraint::{solve, ConstraintKind, ConstraintLink, ConstraintOptions, ConstraintRows, PointConstraint};
use strand::kinematics::{frame_at, segment_frames};
use strand::{ModelKind, PointForce, Strand, StrandBatch, StrandError};

/// How a contact pushes a strand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ForceModel {
    /// The paper's section 4.3: `F = gain * tdot_perp * w A / l`, with `tdot_perp` the tool's velocity
    /// perpendicular to the strand tangent (m/s), `w = rho g` the specific weight (N/m^3), `A` the section
    /// area (m^2) and `l` the arc length from the root to the contact (m). As published this is not a force
    /// (N/(m s)); `gain` (m s) makes it one. Applied explicitly as a point force.
    Paper {
        /// Gain turning the published expression into newtons, m s. Default 1.
        gain: f64,
    },
    /// Physically consistent: non-penetration and Coulomb friction as constraints in the implicit step.
    Constraint {
        /// Friction coefficient (dimensionless), e.g. from [`strand::HairType::friction_coefficient`].
        friction: f64,
        /// Solver options.
        options: ConstraintOptions,
    },
}

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
    /// prepared step, [`ConstraintRows::mobility`], and the solver's force mixing `R`) along its normal,
    /// `g n n^T`, and the friction's share `mu g (I - n n^T)` across it. Coupling between contacts is left
    /// out, and so are the entanglement drags ([`Entanglement`]: a sliding Coulomb drag does not change with
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

/// Wall-clock time of the phases of one [`LocalInteraction::step`], s.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepTimings {
    /// Every strand's dynamics at the current state and unconstrained velocities (constraint model: the first
    /// half of each step, [`Strand::prepare_step`]), s.
    pub dynamics: f64,
    /// Sampling the centrelines into pieces and refitting the AABB tree, s.
    pub sample: f64,
    /// Contact detection, s.
    pub detect: f64,
    /// Of `detect`: the hair-hair contacts ([`HairContactFinder`]), s.
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
    /// Of `constrained`: the common solve's sweeps alone ([`solve`]), s.
    pub solve: f64,
    /// The most constraint rows of one strand in the common solve.
    pub strand_rows: usize,
    /// Hair-hair links of the common solve (contacts solved for both strands at once).
    pub links: usize,
}

/// How a strand's constrained step stands between the stages of [`LocalInteraction::step`].
enum Solved {
    /// Its rows, at this index of the step's rows, wait for the common solve.
    Rows(usize),
    /// It stepped on its own (its step could not be prepared), with these impulses, N s.
    Stepped(Vec<Vector3<f64>>),
}

/// A strand's constrained step between the stages of [`LocalInteraction::step`]: the tool constraints' levers
/// (m) and contacts (the first `levers.len()` constraints are the tool's), and whether it had constraints.
struct Pending {
    strand: usize,
    /// What each of its constraints is, to warm-start the next step's solve.
    tags: Vec<(WarmTag, f64)>,
    levers: Vec<Vector3<f64>>,
    touching: Vec<Option<Contact>>,
    solved: Solved,
    touched: bool,
}

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

/// Loads per held strand that carry the hold ([`LocalInteraction::hold_distance`]).
pub const HOLD_LOADS: usize = 4;

/// A held strand gets its hold every this many steps, that many times as strong (in turns: strand `k` at the
/// steps where the step count modulo this is `k` modulo this). 4 ms at 1 kHz against the hold's period
/// `2 pi sqrt(hold_distance / |g|)` (0.35 s at the live session's 3 cm), so the impulses act as the steady
/// spring.
pub const HOLD_EVERY: usize = 4;

/// Where the hair volume holds a simulated strand: its place among the unsimulated neighbours (e.g. the
/// groomed strand carried by the global layer's lattice), as points evenly spaced in arc length.
#[derive(Debug, Clone, PartialEq)]
pub struct Hold {
    /// Points from the root (first) to the tip (last) of the uncut strand, evenly spaced in arc length, m
    /// (the strands' frame); at least two.
    pub points: Vec<Vector3<f64>>,
    /// The uncut strand's length the points span, m.
    pub length: f64,
}

impl Hold {
    /// The hold's point at arc length `s` (m; clamped to the points' span), linearly interpolated.
    pub fn at(&self, s: f64) -> Vector3<f64> {
        let n = self.points.len();
        if n < 2 {
            return self.points.first().copied().unwrap_or_else(Vector3::zeros);
        }
        let u = (s / self.length.max(1e-12) * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
        let i = (u.floor() as usize).min(n - 2);
        let f = u - i as f64;
        self.points[i] * (1.0 - f) + self.points[i + 1] * f
    }
}

/// One side of a hair-hair contact: the `pair`-th pair of the step ([`HairContactFinder::contacts`]), at its first
/// strand's point or (`second`) at its second strand's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct HairSide {
    pair: usize,
    second: bool,
    /// The pair's other strand.
    other: usize,
}

/// What a strand's constraint is, to find the same constraint at the next step (with its arc length): a tool
/// contact or drag on a capsule, a pin (its index among the pins), a body contact, a hair-hair contact with another
/// strand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WarmTag {
    Tool(usize),
    Drag(usize),
    Pin(usize),
    Body,
    Hair(usize),
}

/// A constraint's impulse at the last step (N s), with what it was and where (arc length, m): the solve of the
/// next step starts from it ([`LocalInteraction::warm_start`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Warm {
    tag: WarmTag,
    s: f64,
    impulse: Vector3<f64>,
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

    /// The hold of the unsimulated neighbours ([`LocalInteraction::hold_distance`]) as loads for this step:
    /// from last step's collision pieces (the strands' points at the start of that step; none right after
    /// the strands changed), each held strand's pieces in [`HOLD_LOADS`] runs along its length, each run one
    /// load at its pieces' mean arc length: the sum of `-k length (midpoint - hold point)` over its pieces.
    /// A strand is held every [`HOLD_EVERY`] steps (strand index modulo, in turns), that many times as
    /// strongly: the same impulse over that time, at a quarter of the cost per step.
    fn hold_strands(&mut self) {
        self.hold_phase = (self.hold_phase + 1) % HOLD_EVERY;
        if !(self.hold_distance > 0.0 && self.hold_distance.is_finite()) || self.rebuild_tree || self.holds.is_empty() {
            return;
        }
        let mut i = 0;
        while i < self.pieces.len() {
            // The pieces are contiguous per strand, in strand order.
            let k = self.pieces[i].strand;
            let end = i + self.pieces[i..].iter().take_while(|p| p.strand == k).count();
            let pieces = i..end;
            i = end;
            if k % HOLD_EVERY != self.hold_phase {
                continue;
            }
            for load in self.hold_loads(k, pieces).into_iter().flatten() {
                // Not finite (never expected): left out.
                self.add_load(k, load);
            }
        }
    }

    /// The hold's [`HOLD_LOADS`] loads on strand `k` (see [`LocalInteraction::hold_strands`]) from its collision
    /// pieces `pieces` (indices into the last step's pieces): forces in N at the runs' mean arc lengths in m,
    /// [`HOLD_EVERY`] times the spring's; None for a run without pieces, or for all if the strand is not held.
    fn hold_loads(&self, k: usize, pieces: std::ops::Range<usize>) -> [Option<PointForce>; HOLD_LOADS] {
        let mut loads = [None; HOLD_LOADS];
        let (Some(Some(hold)), Some(strand)) = (self.holds.get(k), self.strands.get(k)) else { return loads };
        // Spring per unit length, N/m per m, times HOLD_EVERY (this strand's turn stands for that many steps).
        let stiffness = HOLD_EVERY as f64 * strand.model.linear_density() * self.hold_gravity.unwrap_or_else(|| strand.model.gravity.norm()) / self.hold_distance;
        let length = strand.model.length.max(1e-9);
        // Per run along the strand: sum of s x piece length (m^2), of piece lengths (m), of forces (N).
        let mut runs = [(0.0, 0.0, Vector3::zeros()); HOLD_LOADS];
        for p in &self.pieces[pieces] {
            let s = p.s + 0.5 * p.length;
            let run = &mut runs[((s / length * HOLD_LOADS as f64) as usize).min(HOLD_LOADS - 1)];
            run.0 += s * p.length;
            run.1 += p.length;
            run.2 -= (0.5 * (p.a + p.b) - hold.at(s)) * (stiffness * p.length);
        }
        for (load, (sw, w, f)) in loads.iter_mut().zip(runs) {
            if w > 0.0 {
                *load = Some(PointForce::new(sw / w, f));
            }
        }
        loads
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

    /// Largest semi-major axis of the strands, m (the contact distance added to the tool's radius).
    fn hair_radius(strands: &[Strand]) -> f64 {
        strands.iter().map(|s| s.model.section.semi_major).fold(0.0, f64::max)
    }

    /// Radius of the wisp each strand stands for, m: half the hair-hair contact distance, or the fibre's radius
    /// without hair contact.
    fn wisp_radius(&self, fibre_radius: f64) -> f64 {
        self.hair_contact.map_or(fibre_radius, |hc| 0.5 * hc.distance(fibre_radius)).max(fibre_radius)
    }

    /// Distance from a strand's centreline within which the tool's capsules are looked for, m: the wisp's radius
    /// with the entanglement drag, else the fibre's.
    fn reach_radius(&self, fibre_radius: f64) -> f64 {
        if self.entanglement.is_some() && matches!(self.model, ForceModel::Constraint { .. }) {
            self.wisp_radius(fibre_radius)
        } else {
            fibre_radius
        }
    }

    /// Arc lengths (m) at which a strand's centreline is sampled: every segment's start, its Gauss points (as
    /// in the strand's dynamics, so that a step's own sweep gives these points), and the tip.
    fn sample_arc_lengths(strand: &Strand) -> impl Iterator<Item = f64> + '_ {
        let l = strand.model.segment_length();
        let nodes = strand.dynamics.quadrature_nodes();
        (0..strand.model.segments)
            .flat_map(move |i| std::iter::once(i as f64 * l).chain(nodes.iter().map(move |&(sigma, _)| i as f64 * l + sigma)))
            .chain(std::iter::once(strand.model.length))
    }

    /// Centreline pieces of every strand at its current state, computed from its kinematics.
    fn sample(strands: &[Strand]) -> Vec<Piece> {
        let mut pieces = Vec::new();
        for (k, s) in strands.iter().enumerate() {
            Self::sample_strand(k, s, &mut pieces);
        }
        pieces
    }

    /// Appends the pieces of strand `k` at its current state (kinematics evaluated here).
    fn sample_strand(k: usize, strand: &Strand, pieces: &mut Vec<Piece>) {
        let frames = segment_frames(&strand.model, &strand.state);
        let mut last: Option<(f64, Vector3<f64>)> = None;
        for s in Self::sample_arc_lengths(strand) {
            let x = frame_at(&strand.model, &strand.state.q, &frames, s).position;
            if let Some((s0, a)) = last {
                pieces.push(Piece { strand: k, s: s0, length: s - s0, a, b: x });
            }
            last = Some((s, x));
        }
    }

    /// Appends the pieces of strand `k` from the frames and Gauss points of its prepared step's sweep (the same
    /// points as [`LocalInteraction::sample_strand`], without evaluating anything).
    fn sample_strand_from_sweep(k: usize, strand: &Strand, pieces: &mut Vec<Piece>) {
        let dy = &strand.dynamics;
        let q = dy.quadrature_nodes().len();
        let l = strand.model.segment_length();
        let mut s0 = 0.0;
        let mut a = dy.frames[0].position;
        let mut push = |s: f64, x: Vector3<f64>| {
            pieces.push(Piece { strand: k, s: s0, length: s - s0, a, b: x });
            s0 = s;
            a = x;
        };
        for i in 0..strand.model.segments {
            if i > 0 {
                push(i as f64 * l, dy.frames[i].position);
            }
            for (g, &(sigma, _)) in dy.quadrature_nodes().iter().enumerate() {
                push(i as f64 * l + sigma, dy.points[i * q + g]);
            }
        }
        push(strand.model.length, dy.frames[strand.model.segments].position);
    }

    /// Warm start: each constraint of `rows` (what each is and where: `tags`) starts the solve from the impulse of
    /// the same constraint at the last step (`last`): the same kind on the same capsule, pin or other strand, the
    /// nearest in arc length within a quarter of a segment (`segment`, m; each impulse of the last step is used
    /// once). The solve then needs fewer sweeps while the contacts persist.
    /// `used`: workspace (which of `last` are taken), storage kept between calls.
    fn warm_start(last: &[Warm], tags: &[(WarmTag, f64)], segment: f64, used: &mut Vec<bool>, rows: &mut ConstraintRows) {
        if last.is_empty() {
            return;
        }
        used.clear();
        used.resize(last.len(), false);
        let within = 0.25 * segment;
        for (c, &(tag, s)) in tags.iter().enumerate() {
            let best = last.iter().enumerate().filter(|(i, w)| w.tag == tag && !used[*i] && (w.s - s).abs() <= within).min_by(|a, b| (a.1.s - s).abs().total_cmp(&(b.1.s - s).abs()));
            if let Some((i, w)) = best {
                used[i] = true;
                rows.warm_start(c, &w.impulse);
            }
        }
    }

    /// Moves the tool to `pose` over `dt` seconds and steps every strand. On a strand's failure the error is
    /// returned; the other strands have stepped.
    ///
    /// With the constraint model every strand first evaluates its dynamics and unconstrained velocities
    /// ([`Strand::prepare_step`]); the collision pieces are then read from that evaluation's frames and Gauss
    /// points (no kinematics of their own), and strands without contacts only commit their prepared step.
    pub fn step(&mut self, dt: f64, pose: ToolPose) -> Result<StepResult, StrandError> {
        let mut timings = StepTimings::default();
        let clock = std::time::Instant::now();
        let mut first_error = None;
        let constraint = matches!(self.model, ForceModel::Constraint { .. });
        self.hold_strands();
        self.prepared.iter_mut().for_each(|p| *p = false);
        if constraint {
            if self.use_batches {
                self.prepare_batched(dt);
            }
            // A strand that cannot prepare (another integrator, bad input) takes the whole step below instead,
            // which reports its error.
            for (k, strand) in self.strands.iter_mut().enumerate() {
                if self.prepared[k] {
                    continue;
                }
                if strand.integrator == strand::Integrator::LinearlyImplicitEuler && strand.prepare_step(dt, &self.surface_torques[k]).is_ok() {
                    self.prepared[k] = true;
                    self.surface_torques[k].clear();
                }
            }
        }
        let t_dynamics = clock.elapsed().as_secs_f64();
        timings.dynamics = t_dynamics;
        self.pieces.clear();
        for (k, strand) in self.strands.iter().enumerate() {
            if self.prepared[k] {
                Self::sample_strand_from_sweep(k, strand, &mut self.pieces);
            } else {
                Self::sample_strand(k, strand, &mut self.pieces);
            }
        }
        self.tips.clear();
        self.tips.resize(self.strands.len(), Vector3::repeat(f64::NAN));
        for p in &self.pieces {
            // Contiguous per strand, root to tip: the last one written is the tip.
            self.tips[p.strand] = p.b;
        }
        let radius = Self::hair_radius(&self.strands);
        let reach = self.reach_radius(radius);
        if self.pieces.len() == self.bvh.len() && self.bvh.margin() == reach && !self.rebuild_tree {
            self.bvh.refit(&self.pieces);
        } else {
            // A strand changed its number of pieces (cut by the scissors, or replaced), or the reach changed: new
            // tree.
            self.bvh.rebuild(&self.pieces, reach);
            self.rebuild_tree = false;
        }
        let t_sample = clock.elapsed().as_secs_f64();
        timings.sample = t_sample - t_dynamics;
        let mut contacts = std::mem::take(&mut self.contacts);
        contacts.clear();
        let report = detect(&self.shape, &self.pose, &pose, dt, &self.pieces, &self.bvh, reach, &mut contacts);
        // Hair-hair contacts (constraint model): at most `max_per_strand` per strand, deepest first.
        let mut hair_pairs = 0;
        let hair_on = matches!(self.model, ForceModel::Constraint { .. }) && self.hair_contact.is_some();
        if let (Some(hc), true) = (self.hair_contact, hair_on) {
            let t_hair = clock.elapsed().as_secs_f64();
            hc.validate()?;
            // The rest pieces aligned with this step's pieces, when the strands, their rest shapes or their pieces
            // (a cut) changed.
            if self.rest_stale || (!self.rest_pieces.is_empty() && self.rest_pieces.len() != self.pieces.len()) {
                self.rebuild_rest_pieces();
            }
            let strands = &self.strands;
            let per_chord = |k: usize| strands[k].dynamics.quadrature_nodes().len() + 1;
            self.hair_finder.detect(&hc, &self.pieces, &self.rest_pieces, per_chord, strands.len(), hc.distance(radius));
            hair_pairs = self.hair_finder.pairs();
            timings.hair_detect = clock.elapsed().as_secs_f64() - t_hair;
        }
        let t_detect = clock.elapsed().as_secs_f64();
        timings.detect = t_detect - t_sample;
        let mut result = StepResult { report, hair_pairs, ..Default::default() };
        // Where each strand's pieces start (they are contiguous per strand, in strand order).
        let mut first_piece = vec![self.pieces.len(); self.strands.len() + 1];
        for (i, p) in self.pieces.iter().enumerate().rev() {
            first_piece[p.strand] = i;
        }
        for k in (0..self.strands.len()).rev() {
            first_piece[k] = first_piece[k].min(first_piece[k + 1]);
        }
        let entanglement = if constraint { self.entanglement } else { None };
        if let Some(e) = entanglement {
            e.validate()?;
        }
        let wisp_radius = self.wisp_radius(radius);
        // Hair-hair contacts (constraint model): each pair's two points, solved together below. Only between
        // strands whose step was prepared (the others take a step of their own).
        let mut hair_rows = std::mem::take(&mut self.hair_rows);
        hair_rows.iter_mut().for_each(Vec::clear);
        hair_rows.resize_with(self.strands.len(), Vec::new);
        // Where each pair's two rows went (the first and second strand's): (rows index, constraint index).
        let mut hair_slots = std::mem::take(&mut self.hair_slots);
        hair_slots.clear();
        if hair_on {
            let friction = self.hair_contact.map_or(0.0, |hc| hc.friction);
            for (l, pair) in self.hair_finder.contacts().enumerate() {
                let (a, b) = pair.strands;
                if !(self.prepared[a] && self.prepared[b]) {
                    continue;
                }
                let contact = |s: f64, normal: Vector3<f64>| PointConstraint { s, kind: ConstraintKind::Contact { normal, depth: pair.depth, friction }, velocity: Vector3::zeros() };
                hair_rows[a].push((HairSide { pair: l, second: false, other: b }, contact(pair.s.0, pair.normal)));
                hair_rows[b].push((HairSide { pair: l, second: true, other: a }, contact(pair.s.1, -pair.normal)));
                hair_slots.resize(l + 1, [None; 2]);
            }
        }
        // Stage 1, per strand: its constraints (tool contacts and drags, pins, body and hair contacts) and their
        // rows in the prepared step (in the kept workspace `rows[..used]`); the paper's model and unprepared
        // strands step here.
        let mut pending: Vec<Pending> = Vec::new();
        let mut rows = std::mem::take(&mut self.rows);
        let mut used = 0;
        let mut forces: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
        // Per-strand buffers, kept across the strands (no allocation per strand and step).
        let mut mine: Vec<&Contact> = Vec::new();
        let mut resting: Vec<PointConstraint> = Vec::new();
        let mut cons: Vec<PointConstraint> = Vec::new();
        self.piles.resize(self.strands.len(), None);
        for (k, strand) in self.strands.iter_mut().enumerate() {
            let t_strand = clock.elapsed().as_secs_f64();
            // A clip's jaws hold the strands it pins rather than pushing them.
            let held = self.shape.kind == crate::shape::ToolKind::Clip && self.pins.iter().any(|p| p.0 == k);
            mine.clear();
            if !held {
                mine.extend(contacts.iter().filter(|c| c.strand == k));
            }
            let pinned = self.pins.iter().any(|p| p.0 == k);
            // Body contacts (constraint model): sampled points inside the body or within a hair's radius of it.
            resting.clear();
            let t_body = clock.elapsed().as_secs_f64();
            if let (Some((body, threshold)), ForceModel::Constraint { .. }) = (&self.body, &self.model) {
                // Each piece's start, and the strand's last end (a piece's end is the next one's start). The
                // pieces are contiguous per strand, in strand order.
                let pieces = &self.pieces[first_piece[k]..first_piece[k + 1]];
                let points = pieces.iter().enumerate().flat_map(|(i, p)| {
                    let last = i + 1 == pieces.len();
                    std::iter::once((p.s, p.a)).chain(last.then_some((p.s + p.length, p.b)))
                });
                for (s, x) in points {
                    if body.clear_of(&x.into(), *threshold, radius) {
                        continue;
                    }
                    let q = body.push_out(&x.into(), *threshold, radius).coords;
                    let d = q - x;
                    let depth = d.norm();
                    if depth > 0.0 {
                        let kind = ConstraintKind::Contact { normal: d / depth, depth, friction: self.body_friction };
                        resting.push(PointConstraint { s, kind, velocity: Vector3::zeros() });
                    }
                }
            }
            timings.body += clock.elapsed().as_secs_f64() - t_body;
            let touched = !mine.is_empty() || pinned || !resting.is_empty() || !hair_rows[k].is_empty();
            match self.model {
                ForceModel::Paper { gain } => {
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
                    let mut loads = applied.clone();
                    loads.extend(self.surface_torques[k].iter().copied());
                    let r = strand.step(dt, &loads);
                    self.surface_torques[k].clear();
                    if let Err(e) = r {
                        first_error.get_or_insert(e);
                    }
                    forces.extend(applied.iter().zip(&mine).map(|(f, c)| (f.force, c.lever)));
                }
                ForceModel::Constraint { friction, options } => {
                    // Each tool contact found within the wisp's reach: a non-penetration contact where the
                    // capsule touches the centreline's fibre, and (with the entanglement) a drag against the
                    // fibres it parts. `touching[i]`: the contact behind tool constraint i, if a contact.
                    cons.clear();
                    let mut levers: Vec<Vector3<f64>> = Vec::with_capacity(2 * mine.len());
                    let mut touching: Vec<Option<Contact>> = Vec::with_capacity(2 * mine.len());
                    let mut tags: Vec<(WarmTag, f64)> = Vec::with_capacity(2 * mine.len());
                    let r_f = strand.model.section.semi_major;
                    let ei = strand.model.material.young_modulus * strand.model.section.i_soft();
                    let w = self.wetness.get(k).copied().unwrap_or(0.0);
                    // A wisp of many fibres parts around a tooth (the drag) instead of being pushed aside; a thick
                    // capsule (a comb's spine: `Entanglement::parts`) pushes it as a solid at the fibre's radius.
                    let parting = entanglement.is_some() && wisp_radius > radius;
                    let hair_friction = self.hair_contact.map_or(0.0, |hc| hc.friction);
                    // Where the comb entered the wisp: kept while a tooth drags through it, else this step's
                    // shallowest contact.
                    let entry = self.piles[k].take().unwrap_or_else(|| mine.iter().map(|c| c.s).fold(f64::INFINITY, f64::min));
                    for (i, c) in mine.iter().enumerate() {
                        let r_t = self.shape.capsules.get(c.primitive).map_or(0.0, |cap| cap.radius);
                        let parts = parting && entanglement.is_some_and(|e| e.parts(r_t));
                        let fibre_depth = c.depth - (reach - radius);
                        if fibre_depth > 0.0 && !parts {
                            cons.push(PointConstraint { s: c.s, kind: ConstraintKind::Contact { normal: c.normal, depth: fibre_depth, friction }, velocity: c.tool_velocity });
                            levers.push(c.lever);
                            touching.push(Some(**c));
                            tags.push((WarmTag::Tool(c.primitive), c.s));
                        }
                        // One drag per crossing of a capsule and the wisp: the deepest of the strand's contacts
                        // with that capsule (neighbouring pieces near the crossing are found too).
                        let deepest = || mine.iter().enumerate().all(|(j, o)| o.primitive != c.primitive || o.depth < c.depth || (o.depth == c.depth && j >= i));
                        if let (Some(e), true) = (entanglement.filter(|_| parts), deepest()) {
                            let distance = r_t + reach - c.depth;
                            let share = crate::entanglement::parted_share(distance, wisp_radius, r_t + r_f);
                            let curl = crate::entanglement::curl_curvature(strand, c.s);
                            self.piles[k] = Some(entry);
                            let max_force = friction * share * e.parting_load_piled(ei, r_f, r_t, w, strand.model.length - c.s, curl, hair_friction, c.s - entry);
                            if max_force > 0.0 {
                                cons.push(PointConstraint { s: c.s, kind: ConstraintKind::Drag { max_force, slip_speed: e.slip_speed }, velocity: c.tool_velocity });
                                levers.push(c.lever);
                                touching.push(None);
                                tags.push((WarmTag::Drag(c.primitive), c.s));
                            }
                        }
                    }
                    for (i, &(_, s, offset)) in self.pins.iter().enumerate().filter(|p| p.1 .0 == k) {
                        let target = pose.position + pose.rotation * offset;
                        let before = self.pose.position + self.pose.rotation * offset;
                        cons.push(PointConstraint { s, kind: ConstraintKind::Pin { target }, velocity: (target - before) / dt });
                        levers.push(target - pose.position);
                        tags.push((WarmTag::Pin(i), s));
                    }
                    // After the tool's and the pins' constraints: their impulses are not the tool's (the
                    // reactions pair impulses with `levers` and `touching` only).
                    cons.extend(resting.iter().cloned());
                    tags.extend(resting.iter().map(|c| (WarmTag::Body, c.s)));
                    let first_hair = cons.len();
                    cons.extend(hair_rows[k].iter().map(|(_, c)| *c));
                    tags.extend(hair_rows[k].iter().map(|(side, c)| (WarmTag::Hair(side.other), c.s)));
                    let last = std::mem::take(&mut self.warm[k]);
                    let outcome = if self.prepared[k] {
                        // A batched strand with constraints takes over its lane's solver workspace.
                        let handed = match (cons.is_empty(), self.lane_of[k]) {
                            (false, Some((b, j))) => self.batches[b].hand_over(j, strand),
                            _ => Ok(()),
                        };
                        if rows.len() <= used {
                            rows.push(ConstraintRows::default());
                        }
                        handed.and_then(|()| strand.fill_constraint_rows(&cons, &options, &mut rows[used])).map(|()| {
                            for (i, (side, _)) in hair_rows[k].iter().enumerate() {
                                hair_slots[side.pair][side.second as usize] = Some((used, first_hair + i));
                            }
                            used += 1;
                            Solved::Rows(used - 1)
                        })
                    } else {
                        let twisting = std::mem::take(&mut self.surface_torques[k]);
                        strand.step_constrained(dt, &twisting, &cons, &options).map(Solved::Stepped)
                    };
                    if let Ok(Solved::Rows(i)) = &outcome {
                        Self::warm_start(&last, &tags, strand.model.segment_length(), &mut self.warm_used, &mut rows[*i]);
                    }
                    self.warm[k] = last;
                    self.warm[k].clear();
                    match outcome {
                        Ok(solved) => pending.push(Pending { strand: k, tags, levers, touching, solved, touched }),
                        Err(e) => {
                            first_error.get_or_insert(e);
                        }
                    }
                }
            }
            let spent = clock.elapsed().as_secs_f64() - t_strand;
            if touched {
                timings.constrained += spent;
                timings.touched_strands += 1;
            } else {
                timings.free += spent;
            }
        }
        // Stage 2: the constraints of all strands in one projected Gauss-Seidel solve, the hair-hair contacts
        // linking the two strands' rows (both strands' responses in each, no lag of a step).
        if let ForceModel::Constraint { friction, options } = self.model {
            let t_solve = clock.elapsed().as_secs_f64();
            // A pair whose other strand failed to build its rows is no link: the strand that built its rows
            // solves that contact alone, against a still strand.
            let links: Vec<ConstraintLink> = hair_slots
                .iter()
                .filter_map(|pair| match pair {
                    [Some(first), Some(second)] => Some(ConstraintLink { first: *first, second: *second }),
                    _ => None,
                })
                .collect();
            // A linked contact's second row starts from minus its first's (warm starts).
            for link in &links {
                let p = rows[link.first.0].impulses[link.first.1];
                rows[link.second.0].impulses[link.second.1] = -p;
            }
            let t_sweeps = clock.elapsed().as_secs_f64();
            timings.sweeps = solve(&mut rows[..used], &links, &options);
            timings.solve = clock.elapsed().as_secs_f64() - t_sweeps;
            timings.rows = rows[..used].iter().map(ConstraintRows::len).sum();
            timings.strand_rows = rows[..used].iter().map(ConstraintRows::len).max().unwrap_or(0);
            timings.links = links.len();
            timings.constrained += clock.elapsed().as_secs_f64() - t_solve;
            // Stage 3, per strand: apply the impulses and commit the step; the tool feels the tool constraints'.
            let mix = options.force_mixing(dt);
            let beta = options.error_reduction_rate(dt);
            for job in pending {
                let t_strand = clock.elapsed().as_secs_f64();
                let strand = &mut self.strands[job.strand];
                let outcome = match job.solved {
                    Solved::Stepped(p) => Ok((p, vec![0.0; job.touching.len()])),
                    Solved::Rows(i) => {
                        let r = &rows[i];
                        // The tool contacts' mobilities in the prepared step, for the tool's damping.
                        let mobility: Vec<f64> = job.touching.iter().enumerate().map(|(c, t)| t.map_or(0.0, |t| r.mobility(c, &t.normal))).collect();
                        strand.apply_constraints(r, &options).map(|p| (p, mobility))
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
                        for ((impulse, c), w) in p.iter().zip(&job.touching).zip(&mobility) {
                            let Some(c) = c else { continue };
                            if impulse.dot(&c.normal) > 0.0 {
                                let g = 1.0 / (dt * (w + mix));
                                let nn = c.normal * c.normal.transpose();
                                result.damping += nn * g + (Matrix3::identity() - nn) * (friction * g);
                                if beta * c.depth < options.max_correction_speed {
                                    result.stiffness += nn * (beta * g);
                                }
                            }
                            let f = impulse / dt;
                            let tangential = f - c.normal * c.normal.dot(&f);
                            let tau = (-c.normal * r).cross(&tangential);
                            if tau.norm() > 0.0 {
                                self.surface_torques[job.strand].push(PointForce { s: c.s, force: Vector3::zeros(), torque: tau });
                                result.torque -= tau;
                            }
                        }
                        forces.extend(p.iter().zip(&job.levers).map(|(p, l)| (p / dt, *l)));
                    }
                    Err(e) => {
                        first_error.get_or_insert(e);
                    }
                }
                let spent = clock.elapsed().as_secs_f64() - t_strand;
                if job.touched {
                    timings.constrained += spent;
                } else {
                    timings.free += spent;
                }
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;
    use strand::{HairType, ModelKind, RootFrame, StrandModel};

    /// A row of hanging H1 strands along x (roots at z = 0.3), 10 cm long.
    fn patch(n: usize) -> Vec<Strand> {
        let h = HairType::H1;
        let m = StrandModel::new(ModelKind::Reduced, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
        (0..n)
            .map(|i| {
                let root = RootFrame::new(Vector3::new(-0.01 + 0.02 * i as f64 / n.max(2) as f64, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap();
                Strand::new(m.clone(), root).unwrap()
            })
            .collect()
    }

    #[test]
    fn the_hold_pulls_a_strand_towards_its_place_with_its_weight_per_hold_distance() {
        // A straight 10 cm H1 strand hanging at rest, held at its own line shifted by D = (2, -1, 0) mm, hold
        // distance 3 cm, the comb far away. Over HOLD_EVERY steps it gets its hold once: HOLD_LOADS loads
        // summing to HOLD_EVERY k L D with k = lambda |g| / 0.03 (relative error 1e-9: the strand is exactly on
        // its line). Stepped 0.3 s, its tip moves towards D (measured 0.57 mm, along -y: the reduced strand bends
        // about one axis, so it follows the part of D in its bending plane); without a hold it stays on its line.
        let model = ForceModel::Constraint { friction: HairType::H1.friction_coefficient(), options: ConstraintOptions::default() };
        let d = Vector3::new(0.002, -0.001, 0.0);
        let line = |s: f64| Vector3::new(-0.01, 0.0, 0.3 - s);
        let run = |held: bool| {
            let mut it = LocalInteraction::new(patch(1), ToolShape::builtin("comb").unwrap(), comb_at(0.5), model);
            it.step(1e-3, comb_at(0.5)).unwrap();
            if held {
                it.holds = vec![Some(Hold { points: (0..16).map(|i| line(0.1 * i as f64 / 15.0) + d).collect(), length: 0.1 })];
                it.hold_distance = 0.03;
            }
            let (mut total, mut turns) = (Vector3::zeros(), 0);
            for _ in 0..HOLD_EVERY {
                it.surface_torques[0].clear();
                it.hold_strands();
                if !it.surface_torques[0].is_empty() {
                    turns += 1;
                    assert_eq!(it.surface_torques[0].len(), HOLD_LOADS);
                    total += it.surface_torques[0].iter().map(|f| f.force).sum::<Vector3<f64>>();
                }
            }
            it.surface_torques[0].clear();
            for _ in 0..300 {
                it.step(1e-3, comb_at(0.5)).unwrap();
            }
            let tip = strand::kinematics::centerline(&it.strands[0].model, &it.strands[0].state, 2)[1].1 - line(0.1);
            (turns, total, tip, it.strands[0].model.linear_density() * 9.81 / 0.03)
        };
        let (turns, total, tip, k) = run(true);
        let want = d * (HOLD_EVERY as f64 * k * 0.1);
        eprintln!("hold: {turns} turn(s), {total:?} N (want {want:?}); tip moved {tip:?} m");
        assert_eq!(turns, 1, "one turn in HOLD_EVERY steps");
        assert!((total - want).norm() <= 1e-9 * want.norm(), "{total:?} vs {want:?}");
        assert!(tip.dot(&d) > 1e-3 * d.norm() * d.norm() && tip.norm() > 1e-4, "the tip follows the hold: {tip:?}");
        let (turns, _, free_tip, _) = run(false);
        assert_eq!(turns, 0);
        assert!(free_tip.norm() < 1e-9, "not held, the strand stays on its line: {free_tip:?}");
    }

    fn comb_at(y: f64) -> ToolPose {
        // Comb spine along x, teeth pointing down, at mid-height of the strands; stroke along +y. The teeth
        // (every 5 mm from x = -6 cm) are offset 0.4 mm from the strands, so each strand meets a tooth.
        ToolPose { position: Vector3::new(0.0004, y, 0.25), rotation: Matrix3::identity() }
    }

    #[test]
    fn a_comb_stroke_pushes_strands_and_feels_the_reaction() {
        // Drawing the comb through hanging strands at 0.25 m/s: strands are pushed along the stroke, the tool
        // feels a force against its motion, and it equals minus the sum of the contact forces.
        for model in [
            ForceModel::Constraint { friction: HairType::H1.friction_coefficient(), options: ConstraintOptions::default() },
            ForceModel::Paper { gain: 1.0 },
        ] {
            let strands = patch(6);
            let mut it = LocalInteraction::new(strands, ToolShape::builtin("comb").unwrap(), comb_at(-0.01), model);
            let (dt, v) = (1e-3, 0.25);
            let mut y = -0.01;
            let (mut peak, mut contacts) = (0.0f64, 0usize);
            for _ in 0..80 {
                y += v * dt;
                let r = it.step(dt, comb_at(y)).unwrap();
                assert!(r.force.y <= 1e-12, "{model:?}: the hair resists the stroke, got {:?}", r.force);
                peak = peak.max(-r.force.y);
                contacts += r.contacts.len();
            }
            assert!(contacts > 0 && peak > 0.0, "{model:?}: no contact");
            println!("{model:?}: peak stroke force {peak:.3e} N over {contacts} contacts");
            // The strands' tips moved along the stroke.
            let moved = it.strands.iter().map(|s| segment_frames(&s.model, &s.state)[8].position.y).fold(f64::NEG_INFINITY, f64::max);
            assert!(moved > 1e-3, "{model:?}: tips moved {moved}");
        }
    }

    #[test]
    fn the_tip_at_the_last_step_is_the_strands_tip_before_it() {
        // For both contact models (pieces from the prepared sweep, and sampled): after each step of a comb stroke,
        // `tip_at_last_step` is the tip the strand's kinematics give for its state before that step, to 1e-12 m;
        // none before the first step and after new strands are set.
        for model in [
            ForceModel::Constraint { friction: HairType::H1.friction_coefficient(), options: ConstraintOptions::default() },
            ForceModel::Paper { gain: 1.0 },
        ] {
            let mut it = LocalInteraction::new(patch(3), ToolShape::builtin("comb").unwrap(), comb_at(-0.01), model);
            assert_eq!(it.tip_at_last_step(0), None);
            for n in 0..40 {
                let before: Vec<Vector3<f64>> = it.strands.iter().map(|s| segment_frames(&s.model, &s.state).last().unwrap().position).collect();
                it.step(1e-3, comb_at(-0.01 + 2.5e-4 * n as f64)).unwrap();
                for (k, want) in before.iter().enumerate() {
                    let got = it.tip_at_last_step(k).unwrap();
                    assert!((got - want).norm() < 1e-12, "{model:?} step {n} strand {k}: {got:?} vs {want:?}");
                }
            }
            let strands = it.strands.clone();
            it.set_strands(strands, &[Some(0), Some(1), Some(2)]);
            assert_eq!(it.tip_at_last_step(0), None);
        }
    }

    #[test]
    fn batched_steps_give_the_scalar_results() {
        // A comb stroke through 7 reduced strands (batches of 4 and 3 lanes) plus one full-model strand (never
        // batched) and one of 6 segments (its own batch): the force trace and every strand's state with batches
        // equal those without to 1e-9 (relative to the peak force; to 1 + max |q|). Many strands touch the comb,
        // so handed-over lanes with constraints and surface torques are exercised.
        let run = |batches: bool| {
            let mut strands = patch(7);
            let h = HairType::H1;
            let full = StrandModel::new(ModelKind::Full, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
            strands.push(Strand::new(full, RootFrame::new(Vector3::new(0.0095, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap());
            let short = StrandModel::new(ModelKind::Reduced, 0.1, 6, h.section().unwrap(), h.material().unwrap()).unwrap();
            strands.push(Strand::new(short, RootFrame::new(Vector3::new(-0.0095, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap());
            let model = ForceModel::Constraint { friction: h.friction_coefficient(), options: ConstraintOptions::default() };
            let mut it = LocalInteraction::new(strands, ToolShape::builtin("comb").unwrap(), comb_at(-0.01), model);
            it.use_batches = batches;
            let mut trace = Vec::new();
            let mut touched = 0;
            let mut y = -0.01;
            for _ in 0..80 {
                y += 0.25e-3;
                let r = it.step(1e-3, comb_at(y)).unwrap();
                touched += r.timings.touched_strands;
                trace.push((r.force, r.torque));
            }
            (trace, it.strands, touched)
        };
        let (with, strands_with, touched) = run(true);
        let (without, strands_without, _) = run(false);
        assert!(touched > 20, "few contacts ({touched})");
        let peak = without.iter().map(|(f, _)| f.norm()).fold(0.0, f64::max);
        let peak_torque = without.iter().map(|(_, t)| t.norm()).fold(0.0, f64::max);
        assert!(peak > 0.0);
        for (n, (a, b)) in with.iter().zip(&without).enumerate() {
            assert!((a.0 - b.0).norm() <= 1e-9 * peak, "step {n}: force {} vs {}", a.0, b.0);
            assert!((a.1 - b.1).norm() <= 1e-9 * peak_torque.max(1e-30), "step {n}: torque");
        }
        for (k, (a, b)) in strands_with.iter().zip(&strands_without).enumerate() {
            let d = (&a.state.q - &b.state.q).amax() / (1.0 + b.state.q.amax());
            assert!(d <= 1e-9, "strand {k}: q differs by {d:e}");
        }
    }

    #[test]
    fn constraint_contacts_keep_strands_outside_the_teeth() {
        // With the constraint model, after each step no strand piece is deeper inside a tooth than 20 % of the
        // contact distance (tooth radius + hair radius; the stabilization removes half the penetration per
        // step), while strands do lie against the teeth (some piece within 1.2 contact distances).
        use crate::geometry::closest_segment_params;
        let strands = patch(4);
        let friction = HairType::H1.friction_coefficient();
        let comb = ToolShape::builtin("comb").unwrap();
        let mut it = LocalInteraction::new(strands, comb.clone(), comb_at(-0.01), ForceModel::Constraint { friction, options: ConstraintOptions::default() });
        let hair = HairType::H1.major_diameter / 2.0;
        let mut y = -0.01;
        let mut touching = 0;
        for _ in 0..60 {
            y += 0.25e-3;
            it.step(1e-3, comb_at(y)).unwrap();
            let pose = comb_at(y);
            for piece in LocalInteraction::sample(&it.strands) {
                for cap in comb.capsules.iter() {
                    let (a, b) = (pose.apply(&cap.a), pose.apply(&cap.b));
                    let (u, v) = closest_segment_params(&a, &b, &piece.a, &piece.b);
                    let dist = ((a + (b - a) * u) - (piece.a + (piece.b - piece.a) * v)).norm();
                    let reach = cap.radius + hair;
                    assert!(reach - dist < 0.2 * reach, "penetration {} of {reach}", reach - dist);
                    if dist < 1.2 * reach {
                        touching += 1;
                    }
                }
            }
        }
        assert!(touching > 10, "strands never lay against the teeth ({touching})");
    }

    #[test]
    fn a_clip_holds_a_strand_point_and_carries_it() {
        // Close the clip on a hanging strand 5 cm below its root, then swing the tool along an arc of 4.5 cm
        // radius centred 5 mm below the root (0.4 rad in 0.2 s; every point of it is closer to the root than the
        // 5 cm of strand, so the inextensible strand can follow): the clipped point follows the tool within
        // 1e-6 m at every step, and the tool feels the strand's pull.
        let mut strands = patch(1);
        strands.truncate(1);
        let x0 = strands[0].state.root.position.x;
        let pose = |phi: f64| ToolPose { position: Vector3::new(x0, 0.045 * phi.sin(), 0.295 - 0.045 * phi.cos()), rotation: Matrix3::identity() };
        let mut it = LocalInteraction::new(strands, ToolShape::builtin("clip").unwrap(), pose(0.0), ForceModel::Constraint { friction: 0.2, options: ConstraintOptions::default() });
        let (k, s) = it.clip(0.002).expect("a strand within reach");
        assert_eq!(k, 0);
        assert!((s - 0.05).abs() < 1e-6, "clipped at s = {s}");
        let mut felt = 0.0f64;
        for n in 1..=200 {
            let y = 0.4 * n as f64 / 200.0;
            let r = it.step(1e-3, pose(y)).unwrap();
            felt = felt.max(r.force.norm());
            let st = &it.strands[0];
            let p = frame_at(&st.model, &st.state.q, &segment_frames(&st.model, &st.state), s).position;
            assert!((p - pose(y).position).norm() < 1e-6, "step {n}: {}", (p - pose(y).position).norm());
        }
        assert!(felt > 0.0);
        it.release();
        assert!(it.pins.is_empty());
    }

    #[test]
    fn surface_friction_twists_the_strand() {
        // A finger rubbed sideways across a hanging strand near its root. With friction the surface force twists
        // the strand and the tool feels the opposite torque about the strand's axis; without friction there is
        // no such torque (below 1e-20 N m). The effect is small (measured: the section's largest twist grows by
        // about 0.6 %), as a torque arm of one hair radius (46 um) suggests.
        let run = |friction: f64| {
            let h = HairType::H1;
            let m = StrandModel::new(ModelKind::Full, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
            let strands = vec![Strand::new(m, RootFrame::new(Vector3::new(0.0, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap()];
            let x0 = 0.0;
            // The finger lies along +x with its rounded end 0.1 mm into the strand's side 1 cm below the root
            // (where the strand is stiff enough to press back), and slides along y.
            let pose = |y: f64| ToolPose { position: Vector3::new(x0 + 0.0079, y, 0.29), rotation: Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0) };
            let mut it = LocalInteraction::new(strands, ToolShape::builtin("finger").unwrap(), pose(-0.01), ForceModel::Constraint { friction, options: ConstraintOptions::default() });
            let (mut torque, mut twist) = (0.0f64, 0.0f64);
            for n in 1..=100 {
                let r = it.step(1e-3, pose(-0.01 + 0.0002 * n as f64)).unwrap();
                torque = torque.max(r.torque.z.abs());
                // Twist of the section at the contact (the first segment's twist coordinate).
                twist = twist.max(it.strands[0].state.q[0].abs());
            }
            (twist, torque)
        };
        let (with, torque) = run(0.5);
        let (without, no_torque) = run(0.0);
        println!("twist with friction {with:e} (tool torque {torque:e} N m), without {without:e} ({no_torque:e})");
        assert!(torque > 1e-12, "torque {torque}");
        assert!(no_torque < 1e-20, "torque without friction {no_torque}");
        assert!(with > without, "twist with friction {with}, without {without}");
    }

    #[test]
    fn the_reported_damping_predicts_the_force_change_with_tool_speed() {
        // Mid-stroke (0.25 m/s through 6 hanging strands), step two copies of the interaction with the tool 1 %
        // faster and slower along the stroke: the measured -dF_y/dv_y (central difference) is positive and the
        // reported damping D_yy matches it within a factor 2 (D leaves out the coupling between a strand's
        // contacts and takes friction as a share of the normal response; ratios printed, 0.88 at step 50).
        let model = ForceModel::Constraint { friction: HairType::H1.friction_coefficient(), options: ConstraintOptions::default() };
        let mut it = LocalInteraction::new(patch(6), ToolShape::builtin("comb").unwrap(), comb_at(-0.01), model);
        let (dt, v) = (1e-3, 0.25);
        let mut y = -0.01;
        let mut checked = 0;
        for n in 0..80 {
            if n >= 50 && n % 5 == 0 {
                let dv = 0.01 * v;
                let at = |speed: f64| it.clone().step(dt, comb_at(y + speed * dt)).unwrap();
                let (slow, fast, mid) = (at(v - dv), at(v + dv), at(v));
                // A derivative only where the contact set does not change with the speed.
                if mid.contacts.is_empty() || slow.contacts.len() != fast.contacts.len() {
                    println!("step {n}: contacts {} / {} / {}, skipped", slow.contacts.len(), mid.contacts.len(), fast.contacts.len());
                    continue;
                }
                let measured = -(fast.force.y - slow.force.y) / (2.0 * dv);
                let reported = mid.damping[(1, 1)];
                println!("step {n}: -dF/dv = {measured:.4e} N s/m, reported D_yy = {reported:.4e} (ratio {:.2})", reported / measured);
                assert!(mid.damping.symmetric_eigenvalues().iter().all(|&e| e >= -1e-12 * reported));
                assert!(measured > 0.0 && reported >= 0.5 * measured && reported <= 2.0 * measured, "step {n}: {measured} vs {reported}");
                checked += 1;
            }
            y += v * dt;
            it.step(dt, comb_at(y)).unwrap();
        }
        assert!(checked >= 3, "checked {checked} steps");
    }

    #[test]
    fn the_reported_stiffness_predicts_the_force_change_with_tool_depth() {
        // Mid-stroke (0.25 m/s through 6 hanging strands), step two copies of the interaction with the whole
        // step's motion shifted 2 um deeper along the stroke and 2 um back (same velocity): the measured
        // -dF_y/dy (central difference) is matched by the reported stiffness K_yy within a factor 2 where the
        // contact set does not change (K leaves out the coupling between a strand's contacts, as D does; ratios
        // printed, 0.97-0.98 measured), and K is symmetric positive semi-definite.
        let model = ForceModel::Constraint { friction: HairType::H1.friction_coefficient(), options: ConstraintOptions::default() };
        let mut it = LocalInteraction::new(patch(6), ToolShape::builtin("comb").unwrap(), comb_at(-0.01), model);
        let (dt, v) = (1e-3, 0.25);
        let mut y = -0.01;
        let mut checked = 0;
        for n in 0..80 {
            if n >= 50 && n % 5 == 0 {
                let dx = 2e-6;
                let at = |shift: f64| {
                    let mut c = it.clone();
                    c.pose.position.y += shift;
                    c.step(dt, comb_at(y + v * dt + shift)).unwrap()
                };
                let (back, deep, mid) = (at(-dx), at(dx), at(0.0));
                if mid.contacts.is_empty() || back.contacts.len() != deep.contacts.len() || back.contacts.len() != mid.contacts.len() {
                    println!("step {n}: contacts {} / {} / {}, skipped", back.contacts.len(), mid.contacts.len(), deep.contacts.len());
                    continue;
                }
                let measured = -(deep.force.y - back.force.y) / (2.0 * dx);
                let reported = mid.stiffness[(1, 1)];
                println!("step {n}: -dF/dy = {measured:.4e} N/m, reported K_yy = {reported:.4e} (ratio {:.2})", reported / measured);
                assert!(mid.stiffness.symmetric_eigenvalues().iter().all(|&e| e >= -1e-12 * reported.abs().max(1e-30)));
                assert!((mid.stiffness - mid.stiffness.transpose()).amax() <= 1e-12 * reported.abs().max(1e-30));
                assert!(measured > 0.0 && reported >= 0.5 * measured && reported <= 2.0 * measured, "step {n}: {measured} vs {reported}");
                checked += 1;
            }
            y += v * dt;
            it.step(dt, comb_at(y)).unwrap();
        }
        assert!(checked >= 3, "checked {checked} steps");
    }

    #[test]
    fn strands_in_hair_contact_push_each_other() {
        // Two hanging 10 cm H1 strands, roots 3 mm apart along x, each standing for 100 fibres (contact
        // distance 2 r_f sqrt(100 / 0.5) = 1.32 mm). A bar (a capsule of 1 mm radius along y, 5 cm below the
        // roots) moves along +x at 0.05 m/s from just behind the first strand, its centre from -1.1 mm to
        // +1.5 mm: it pushes the first strand to about 2.5 mm but never reaches the second (its surface stops
        // at 2.5 mm). With hair contact the second strand is pushed ahead of the first (its point at the bar's
        // height moves more than 0.5 mm) and the two never come closer than 60 % of the contact distance (the
        // soft contact corrects at most v_max); without it the second stays put (under 0.05 mm).
        let bar = ToolShape::from_toml("name = \"bar\"\nkind = \"finger\"\n[[capsule]]\na = [0.0, -0.005, 0.0]\nb = [0.0, 0.005, 0.0]\nradius = 0.001\n").unwrap();
        let run = |hair: bool| {
            let h = HairType::H1;
            let m = StrandModel::new(ModelKind::Full, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
            let strands: Vec<Strand> = [0.0, 0.003]
                .iter()
                .map(|&x| Strand::new(m.clone(), RootFrame::new(Vector3::new(x, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap())
                .collect();
            let pose = |x: f64| ToolPose { position: Vector3::new(x, 0.0, 0.25), rotation: Matrix3::identity() };
            let model = ForceModel::Constraint { friction: 0.2, options: ConstraintOptions::default() };
            let mut it = LocalInteraction::new(strands, bar.clone(), pose(-0.0011), model);
            let contact = HairContact { fibres: 100.0, ..Default::default() };
            if hair {
                it.hair_contact = Some(contact);
            }
            let distance = contact.distance(h.major_diameter / 2.0);
            let (mut closest, mut pairs) = (f64::INFINITY, 0usize);
            for n in 1..=52 {
                let r = it.step(1e-3, pose(-0.0011 + 5e-5 * n as f64)).unwrap();
                pairs += r.hair_pairs;
                let (a, b) = (LocalInteraction::sample(&it.strands[..1]), LocalInteraction::sample(&it.strands[1..]));
                for pa in &a {
                    for pb in &b {
                        let (u, v) = crate::geometry::closest_segment_params(&pa.a, &pa.b, &pb.a, &pb.b);
                        closest = closest.min(((pa.a + (pa.b - pa.a) * u) - (pb.a + (pb.b - pb.a) * v)).norm());
                    }
                }
            }
            let st = &it.strands[1];
            let moved = frame_at(&st.model, &st.state.q, &segment_frames(&st.model, &st.state), 0.05).position.x - 0.003;
            (moved, closest / distance, pairs)
        };
        let (moved, closest, pairs) = run(true);
        let (moved_off, closest_off, _) = run(false);
        println!("hair contact: second strand moved {moved:.3e} m, closest {closest:.2} contact distances, {pairs} pairs");
        println!("without: second strand moved {moved_off:.3e} m, closest {closest_off:.2}");
        assert!(pairs > 0);
        assert!(moved > 5e-4, "the second strand was not pushed ({moved})");
        assert!(closest > 0.6, "strands came within {closest} contact distances");
        assert!(moved_off.abs() < 5e-5, "without hair contact the second strand moved {moved_off}");
    }

    #[test]
    fn hair_hair_friction_holds_the_neighbour_against_sliding() {
        // Two hanging 10 cm H1 strands, roots 1 mm apart along x, each standing for 100 fibres (contact distance
        // 1.32 mm): they press on each other along x near the roots. A small clip holds the first strand 2 cm below
        // its root and carries it 2 mm along +y (0.01 m/s). Without hair-hair friction the contact's normal, turning
        // as the first strand moves, pushes the second strand aside: its point 1 cm below the root slides along -y
        // (measured 74 um, which must exceed 10 um). With friction 0.5 the contact sticks: the first strand drags
        // the second along +y instead (measured +17 um; the two strands solved together).
        let clip = ToolShape::from_toml("name = \"pin\"\nkind = \"clip\"\n[[capsule]]\na = [0.0, -0.0001, 0.0]\nb = [0.0, 0.0001, 0.0]\nradius = 0.0001\n").unwrap();
        let run = |friction: f64| {
            let h = HairType::H1;
            let m = StrandModel::new(ModelKind::Full, 0.1, 10, h.section().unwrap(), h.material().unwrap()).unwrap();
            let strands: Vec<Strand> = [0.0, 0.001]
                .iter()
                .map(|&x| Strand::new(m.clone(), RootFrame::new(Vector3::new(x, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap())
                .collect();
            let pose = |y: f64| ToolPose { position: Vector3::new(0.0, y, 0.28), rotation: Matrix3::identity() };
            let model = ForceModel::Constraint { friction: 0.0, options: ConstraintOptions::default() };
            let mut it = LocalInteraction::new(strands, clip.clone(), pose(0.0), model);
            it.hair_contact = Some(HairContact { fibres: 100.0, friction, ..Default::default() });
            let (k, _) = it.clip(0.0005).expect("the first strand is within reach");
            assert_eq!(k, 0);
            let mut pairs = 0;
            for n in 1..=200 {
                pairs += it.step(1e-3, pose(1e-5 * n as f64)).unwrap().hair_pairs;
            }
            let st = &it.strands[1];
            (frame_at(&st.model, &st.state.q, &segment_frames(&st.model, &st.state), 0.01).position.y, pairs)
        };
        let (with, pairs) = run(0.5);
        let (without, _) = run(0.0);
        println!("second strand's point 1 cm below the root moved {with:.3e} m along y with friction, {without:.3e} m without ({pairs} pairs)");
        assert!(pairs > 0);
        assert!(without < -1e-5, "without friction the neighbour was not pushed aside: {without}");
        assert!(with > 0.0, "with friction the neighbour was still pushed aside: {with} (without: {without})");
    }
}
