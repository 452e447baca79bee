//! Sampling the strands' centrelines into straight collision pieces (from the prepared step's sweep when there
//! is one), and the radii the contacts use (a fibre's, a wisp's, the reach).

use super::frame::StepFrame;
use super::{ForceModel, LocalInteraction};
use crate::bvh::Piece;
use nalgebra::Vector3;
use strand::kinematics::{frame_at, segment_frames};
use strand::Strand;

impl LocalInteraction {
    /// Largest semi-major axis of the strands, m (the contact distance added to the tool's radius).
    pub(super) fn hair_radius(strands: &[Strand]) -> f64 {
        strands.iter().map(|s| s.model.section.semi_major).fold(0.0, f64::max)
    }

    /// Radius of the wisp each strand stands for, m: half the hair-hair contact distance, or the fibre's radius
    /// without hair contact.
    pub(super) fn wisp_radius(&self, fibre_radius: f64) -> f64 {
        self.params.hair_contact.map_or(fibre_radius, |hc| 0.5 * hc.distance(fibre_radius)).max(fibre_radius)
    }

    /// Distance from a strand's centreline within which the tool's capsules are looked for, m: the wisp's radius
    /// with the entanglement drag, else the fibre's.
    pub(super) fn reach_radius(&self, fibre_radius: f64) -> f64 {
        if self.params.entanglement.is_some() && matches!(self.model, ForceModel::Constraint { .. }) {
            self.wisp_radius(fibre_radius)
        } else {
            fibre_radius
        }
    }

    /// Arc lengths (m) at which a strand's centreline is sampled: every segment's start, its Gauss points (as
    /// in the strand's dynamics, so that a step's own sweep gives these points), and the tip.
    pub(super) fn sample_arc_lengths(strand: &Strand) -> impl Iterator<Item = f64> + '_ {
        let l = strand.model.segment_length();
        let nodes = strand.dynamics.quadrature_nodes();
        (0..strand.model.segments)
            .flat_map(move |i| std::iter::once(i as f64 * l).chain(nodes.iter().map(move |&(sigma, _)| i as f64 * l + sigma)))
            .chain(std::iter::once(strand.model.length))
    }

    /// Centreline pieces of every strand at its current state, computed from its kinematics.
    pub(super) fn sample(strands: &[Strand]) -> Vec<Piece> {
        let mut pieces = Vec::new();
        for (k, s) in strands.iter().enumerate() {
            Self::sample_strand(k, s, &mut pieces);
        }
        pieces
    }

    /// Appends the pieces of strand `k` at its current state (kinematics evaluated here).
    pub(super) fn sample_strand(k: usize, strand: &Strand, pieces: &mut Vec<Piece>) {
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
    pub(super) fn sample_strand_from_sweep(k: usize, strand: &Strand, pieces: &mut Vec<Piece>) {
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

    /// Stage 3: every strand's pieces this step (read from its prepared sweep, else from its kinematics), each
    /// strand's tip, the fibre radius and the tool's reach (`frame.radius`, `frame.reach`), and the tree refitted
    /// (rebuilt when the pieces or the reach changed).
    pub(super) fn sample_pieces(&mut self, frame: &mut StepFrame) {
        self.pieces.clear();
        for (k, strand) in self.strands.iter().enumerate() {
            if self.ws.prepared[k] {
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
        if self.pieces.len() == self.ws.bvh.len() && self.ws.bvh.margin() == reach && !self.ws.rebuild_tree {
            self.ws.bvh.refit(&self.pieces);
        } else {
            // A strand changed its number of pieces (cut by the scissors, or replaced), or the reach changed: new
            // tree.
            self.ws.bvh.rebuild(&self.pieces, reach);
            self.ws.rebuild_tree = false;
        }
        frame.radius = radius;
        frame.reach = reach;
        frame.timings.sample = frame.clock.elapsed().as_secs_f64() - frame.timings.dynamics;
    }
}
