//! Stage 4: the contacts between the tool's swept motion and the strands' pieces ([`crate::contact::detect`]), the
//! hair-hair contacts ([`crate::hair_contact`]) and their pairs of rows.

use super::frame::StepFrame;
use super::warm::HairSide;
use super::{LocalInteraction, StepResult};
use crate::bvh::Piece;
use crate::contact::detect;
use nalgebra::Vector3;
use strand::constraint::{ConstraintKind, PointConstraint};
use strand::StrandError;

impl LocalInteraction {
    /// Stage 4: the tool's contacts with this step's pieces (`frame.contacts`, the detection report in
    /// `frame.result`) and, with hair-hair contact, the strands' contacts with each other as pairs of rows
    /// (`frame.hair_rows`, `frame.hair_slots`). An invalid [`super::HairContact`] is an error (nothing stepped).
    pub(super) fn detect_contacts(&mut self, frame: &mut StepFrame) -> Result<(), StrandError> {
        let (pose, dt, radius, reach) = (frame.pose, frame.dt, frame.radius, frame.reach);
        let t_sample = frame.clock.elapsed().as_secs_f64();
        let mut contacts = std::mem::take(&mut self.ws.contacts);
        contacts.clear();
        let report = detect(&self.shape, &self.pose, &pose, dt, &self.pieces, &self.ws.bvh, reach, &mut contacts);
        // Hair-hair contacts (constraint model): at most `max_per_strand` per strand, deepest first.
        let mut hair_pairs = 0;
        let hair_on = frame.constraint && self.params.hair_contact.is_some();
        if let (Some(hc), true) = (self.params.hair_contact, hair_on) {
            let t_hair = frame.clock.elapsed().as_secs_f64();
            hc.validate()?;
            // The rest pieces aligned with this step's pieces, when the strands, their rest shapes or their pieces
            // (a cut) changed.
            if self.ws.rest_stale || (!self.ws.rest_pieces.is_empty() && self.ws.rest_pieces.len() != self.pieces.len()) {
                self.rebuild_rest_pieces();
            }
            let strands = &self.strands;
            let per_chord = |k: usize| strands[k].dynamics.quadrature_nodes().len() + 1;
            self.ws.hair_finder.detect(&hc, &self.pieces, &self.ws.rest_pieces, per_chord, strands.len(), hc.distance(radius));
            hair_pairs = self.ws.hair_finder.pairs();
            frame.timings.hair_detect = frame.clock.elapsed().as_secs_f64() - t_hair;
        }
        frame.timings.detect = frame.clock.elapsed().as_secs_f64() - t_sample;
        frame.result = StepResult { report, hair_pairs, ..Default::default() };
        frame.contacts = contacts;
        frame.hair_on = hair_on;
        // Hair-hair contacts (constraint model): each pair's two points, solved together below. Only between
        // strands whose step was prepared (the others take a step of their own).
        let mut hair_rows = std::mem::take(&mut self.ws.hair_rows);
        hair_rows.iter_mut().for_each(Vec::clear);
        hair_rows.resize_with(self.strands.len(), Vec::new);
        // Where each pair's two rows went (the first and second strand's): (rows index, constraint index).
        let mut hair_slots = std::mem::take(&mut self.ws.hair_slots);
        hair_slots.clear();
        if hair_on {
            let friction = self.params.hair_contact.map_or(0.0, |hc| hc.friction);
            for (l, pair) in self.ws.hair_finder.contacts().enumerate() {
                let (a, b) = pair.strands;
                if !(self.ws.prepared[a] && self.ws.prepared[b]) {
                    continue;
                }
                let contact = |s: f64, normal: Vector3<f64>| PointConstraint { s, kind: ConstraintKind::Contact { normal, depth: pair.depth, friction }, velocity: Vector3::zeros() };
                hair_rows[a].push((HairSide { pair: l, second: false, other: b }, contact(pair.s.0, pair.normal)));
                hair_rows[b].push((HairSide { pair: l, second: true, other: a }, contact(pair.s.1, -pair.normal)));
                hair_slots.resize(l + 1, [None; 2]);
            }
        }
        frame.hair_rows = hair_rows;
        frame.hair_slots = hair_slots;
        Ok(())
    }

    /// Aligns the strands' rest shapes with this step's pieces into `rest_pieces` (NaN for a strand whose rest
    /// shape is missing or has another number of pieces; empty when no strand has one).
    fn rebuild_rest_pieces(&mut self) {
        self.ws.rest_stale = false;
        self.ws.rest_pieces.clear();
        if self.rest_shapes.iter().all(|r| r.is_empty()) {
            return;
        }
        let nan = Vector3::repeat(f64::NAN);
        let mut i = 0;
        while i < self.pieces.len() {
            let k = self.pieces[i].strand;
            let n = self.pieces[i..].iter().take_while(|p| p.strand == k).count();
            match self.rest_shapes.get(k).filter(|r| r.len() == n) {
                Some(r) => self.ws.rest_pieces.extend_from_slice(r),
                None => self.ws.rest_pieces.extend(self.pieces[i..i + n].iter().map(|p| Piece { a: nan, b: nan, ..*p })),
            }
            i += n;
        }
    }
}
