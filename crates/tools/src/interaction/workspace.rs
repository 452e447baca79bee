//! The local interaction's workspace: buffers kept between steps for their storage (no allocation per step) and
//! caches rebuilt when what they stand for changes. Nothing in it is a result: a step's outcome does not depend
//! on what it held before, except through the caches' own invalidation.

use super::warm::HairSide;
use crate::bvh::{Bvh, Piece};
use crate::contact::Contact;
use crate::hair_contact::HairContactFinder;
use strand::constraint::{ConstraintRows, PointConstraint};
use strand::StrandBatch;

/// Buffers and caches of a [`super::LocalInteraction`]'s step.
#[derive(Debug, Clone)]
pub(super) struct Workspace {
    /// Hair-hair contact detection ([`crate::hair_contact`]).
    pub hair_finder: HairContactFinder,
    /// The rest pieces aligned with the step's pieces (NaN where a strand has none; empty when no strand has a
    /// rest shape), rebuilt only when the strands, their rest shapes or their number of pieces change.
    pub rest_pieces: Vec<Piece>,
    /// `rest_pieces` must be rebuilt (strands or rest shapes changed).
    pub rest_stale: bool,
    /// The batches' solver storage, and each strand's (batch, lane) this step.
    pub batches: Vec<StrandBatch>,
    pub lane_of: Vec<Option<(usize, usize)>>,
    /// The AABB tree over the pieces (refitted each step), and whether to build it anew at the next step.
    pub bvh: Bvh,
    pub rebuild_tree: bool,
    /// Which strands' steps were prepared this step.
    pub prepared: Vec<bool>,
    /// The contacts of this step.
    pub contacts: Vec<Contact>,
    /// Each strand's hair-hair contacts this step, with the pair side each stands for.
    pub hair_rows: Vec<Vec<(HairSide, PointConstraint)>>,
    /// Per hair-hair pair, where its first and second strand's rows went (rows index, constraint index).
    pub hair_slots: Vec<[Option<(usize, usize)>; 2]>,
    /// The constrained strands' rows of this step (the first ones in use), storage kept.
    pub rows: Vec<ConstraintRows>,
    /// Of [`super::LocalInteraction::warm_start`]: which of a strand's last impulses are taken.
    pub warm_used: Vec<bool>,
    /// The body's balls that reach the strand whose body contacts are being found
    /// ([`lattice::metaball::MetaballSet::reaching_into`]).
    pub near_body: lattice::metaball::MetaballSet,
}

impl Workspace {
    /// An empty workspace for `strands` strands whose pieces are `pieces` (the tree built over them with the
    /// margin `margin`, m).
    pub fn new(strands: usize, pieces: &[Piece], margin: f64) -> Self {
        Self {
            hair_finder: HairContactFinder::new(),
            rest_pieces: Vec::new(),
            rest_stale: false,
            batches: Vec::new(),
            lane_of: vec![None; strands],
            bvh: Bvh::build(pieces, margin),
            rebuild_tree: false,
            prepared: vec![false; strands],
            contacts: Vec::new(),
            hair_rows: Vec::new(),
            hair_slots: Vec::new(),
            rows: Vec::new(),
            warm_used: Vec::new(),
            near_body: lattice::metaball::MetaballSet::default(),
        }
    }
}
