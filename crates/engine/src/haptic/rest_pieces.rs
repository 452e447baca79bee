//! Each guide's groomed rest pieces for the hair-hair contacts (`HapticParams::groomed_overlap`), kept from its first
//! join of the active set for its next ones: a joining strand's rest shape costs an evaluation of its groomed
//! kinematics, and the joining steps are most of the live physics step's slowest (issue 31, bench/HISTORY.md).

use nalgebra::{DVector, Matrix3, Vector3};
use strand::{Strand, StrandState};
use tools::interaction::LocalInteraction;

/// A guide's groomed rest pieces, as `LocalInteraction::set_rest_state` computed them at its first join, with what
/// they were computed from: the guide's groomed coordinates and root, and its strand's geometry (kind, length,
/// segments, Gauss points). A guide joining again with all of these the same takes them as they are (the same
/// bits), without its kinematics.
#[derive(Debug, Clone)]
pub(crate) struct RestPieces {
    q: DVector<f64>,
    root: (Vector3<f64>, Matrix3<f64>),
    geometry: (strand::ModelKind, f64, usize),
    nodes: Vec<(f64, f64)>,
    pieces: Vec<tools::bvh::Piece>,
}

impl RestPieces {
    /// Whether these were computed from the groomed `state` for strand `s`'s geometry.
    fn matches(&self, state: &StrandState, s: &Strand) -> bool {
        self.geometry == (s.model.kind, s.model.length, s.model.segments) && self.root == (state.root.position, state.root.rotation) && self.q == state.q && self.nodes.as_slice() == s.dynamics.quadrature_nodes()
    }

    /// Gives the interaction's strand `i`, guide `g` joining with groomed `state`, its rest shape: the pieces kept in
    /// `kept` (one entry per guide at most) if they were computed from the same, else computed and kept. In the test
    /// profile a kept shape is checked against a fresh evaluation, bit for bit.
    pub fn give(kept: &mut Vec<Option<RestPieces>>, g: usize, interaction: &mut LocalInteraction, i: usize, state: &StrandState) {
        let s = &interaction.strands[i];
        match kept.get(g).and_then(Option::as_ref).filter(|r| r.matches(state, s)) {
            Some(r) => {
                interaction.set_rest_pieces(i, &r.pieces);
                if cfg!(debug_assertions) {
                    let shape = interaction.rest_shape(i).to_vec();
                    interaction.set_rest_state(i, state);
                    assert!(shape == interaction.rest_shape(i), "guide {g}'s kept rest pieces are the ones its groomed state gives, bit for bit");
                }
            }
            None => {
                let (geometry, nodes) = ((s.model.kind, s.model.length, s.model.segments), s.dynamics.quadrature_nodes().to_vec());
                if interaction.set_rest_state(i, state) {
                    if kept.len() <= g {
                        kept.resize(g + 1, None);
                    }
                    let (q, root, pieces) = (state.q.clone(), (state.root.position, state.root.rotation), interaction.rest_shape(i).to_vec());
                    kept[g] = Some(RestPieces { q, root, geometry, nodes, pieces });
                }
            }
        }
    }
}
