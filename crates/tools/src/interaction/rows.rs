//! Stage 5, per strand: its constraints (tool contacts and, with the entanglement, drags against the parted
//! fibres; clip pins; body contacts; hair-hair contacts) as rows of its prepared step, warm-started from the last
//! step's impulses (`warm.rs`); with the paper's model (`paper.rs`) and for an unprepared strand, the strand
//! steps here.

use super::frame::{Pending, Solved, StepFrame};
use super::warm::WarmTag;
use super::{ForceModel, LocalInteraction, Pile};
use crate::contact::Contact;
use nalgebra::Vector3;
use strand::constraint::{ConstraintKind, ConstraintRows, PointConstraint};
use strand::StrandError;

impl LocalInteraction {
    /// Stage 5: every strand's constraints and rows (the constrained strands' rows in `frame.rows[..frame.used]`, each
    /// waiting in `frame.pending`); the paper's model and unprepared strands step here. An invalid entanglement is an
    /// error (nothing stepped).
    pub(super) fn strand_rows(&mut self, frame: &mut StepFrame) -> Result<(), StrandError> {
        let (constraint, radius, reach, dt, pose) = (frame.constraint, frame.radius, frame.reach, frame.dt, frame.pose);
        // Where each strand's pieces start (they are contiguous per strand, in strand order).
        let mut first_piece = vec![self.pieces.len(); self.strands.len() + 1];
        for (i, p) in self.pieces.iter().enumerate().rev() {
            first_piece[p.strand] = i;
        }
        for k in (0..self.strands.len()).rev() {
            first_piece[k] = first_piece[k].min(first_piece[k + 1]);
        }
        let entanglement = if constraint { self.params.entanglement } else { None };
        if let Some(e) = entanglement {
            e.validate()?;
        }
        let wisp_radius = self.wisp_radius(radius);
        frame.rows = std::mem::take(&mut self.ws.rows);
        frame.used = 0;
        // Per-strand buffers, kept across the strands (no allocation per strand and step).
        let mut mine: Vec<&Contact> = Vec::new();
        let mut resting: Vec<PointConstraint> = Vec::new();
        let mut cons: Vec<PointConstraint> = Vec::new();
        self.piles.resize(self.strands.len(), None);
        // The box the parting teeth fill: a wisp out of every tooth's reach keeps its pile while it passes through.
        let teeth = entanglement.and_then(|e| super::pile::Teeth::new(self.shape.capsules.iter().filter(|c| e.parts(c.radius)), reach));
        for (k, strand) in self.strands.iter_mut().enumerate() {
            let t_strand = frame.clock.elapsed().as_secs_f64();
            // A clip's jaws hold the strands it pins rather than pushing them.
            let held = self.shape.kind == crate::shape::ToolKind::Clip && self.pins.iter().any(|p| p.0 == k);
            mine.clear();
            if !held {
                mine.extend(frame.contacts.iter().filter(|c| c.strand == k));
            }
            let pinned = self.pins.iter().any(|p| p.0 == k);
            // Body contacts (constraint model): sampled points inside the body or within a hair's radius of it.
            resting.clear();
            let t_body = frame.clock.elapsed().as_secs_f64();
            if let (Some((body, threshold)), ForceModel::Constraint { .. }) = (&self.params.body, &self.model) {
                // Each piece's start, and the strand's last end (a piece's end is the next one's start). The
                // pieces are contiguous per strand, in strand order.
                let pieces = &self.pieces[first_piece[k]..first_piece[k + 1]];
                let points = || pieces.iter().enumerate().flat_map(|(i, p)| {
                    let last = i + 1 == pieces.len();
                    std::iter::once((p.s, p.a)).chain(last.then_some((p.s + p.length, p.b)))
                });
                // The first test against the balls that reach the strand's box only (the same answer, fewer terms).
                let (lo, hi) = points().fold((Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY)), |(lo, hi), (_, x)| (lo.inf(&x), hi.sup(&x)));
                body.reaching_into(&lo.into(), &hi.into(), &mut self.ws.near_body);
                for (s, x) in points() {
                    if self.ws.near_body.clear_of(&x.into(), *threshold, radius) {
                        continue;
                    }
                    let q = body.push_out(&x.into(), *threshold, radius).coords;
                    let d = q - x;
                    let depth = d.norm();
                    if depth > 0.0 {
                        let kind = ConstraintKind::Contact { normal: d / depth, depth, friction: self.params.body_friction };
                        resting.push(PointConstraint { s, kind, velocity: Vector3::zeros() });
                    }
                }
            }
            frame.timings.body += frame.clock.elapsed().as_secs_f64() - t_body;
            let touched = !mine.is_empty() || pinned || !resting.is_empty() || !frame.hair_rows[k].is_empty();
            match self.model {
                ForceModel::Paper { gain } => {
                    let (r, applied) = Self::paper_step(strand, gain, &mine, &mut self.surface_torques[k], dt);
                    if let Err(e) = r {
                        frame.first_error.get_or_insert(e);
                    }
                    frame.forces.extend(applied);
                }
                ForceModel::Constraint { friction, options } => {
                    // Each tool contact found within the wisp's reach: a non-penetration contact where the
                    // capsule touches the centreline's fibre, and (with the entanglement) a drag against the
                    // fibres it parts, or the cushion of the fibres a capsule too thick to part them presses.
                    // `touching[i]`: the contact behind tool constraint i, if a contact; `solid[i]`: whether it is
                    // non-penetrating (a cushion clear of the centreline's fibre pushes with its load alone).
                    cons.clear();
                    let mut levers: Vec<Vector3<f64>> = Vec::with_capacity(2 * mine.len());
                    let mut touching: Vec<Option<Contact>> = Vec::with_capacity(2 * mine.len());
                    let mut tags: Vec<(WarmTag, f64)> = Vec::with_capacity(2 * mine.len());
                    let mut solid: Vec<bool> = Vec::with_capacity(2 * mine.len());
                    let r_f = strand.model.section.semi_major;
                    let ei = strand.model.material.young_modulus * strand.model.section.i_soft();
                    let w = self.wetness.get(k).copied().unwrap_or(0.0);
                    // A wisp of many fibres parts around a tooth (the drag) instead of being pushed aside; a thick
                    // capsule (a comb's spine: `Entanglement::parts`) presses the fibres it reaches against the others
                    // (`crate::cushion`) and pushes the wisp as a solid once it reaches the centreline's fibre.
                    let parting = entanglement.is_some() && wisp_radius > radius;
                    let hair_friction = self.params.hair_contact.map_or(0.0, |hc| hc.friction);
                    // The wisps' packing: the density of the neighbours a curled parted fibre hooks.
                    let packing = self.params.hair_contact.unwrap_or_default().packing;
                    // Where the comb's travel along the wisp counts from (`Pile`): kept while the wisp passes
                    // through the comb, else this step's shallowest contact.
                    let span = entanglement.map_or(0.0, |e| e.span);
                    let pieces = &self.pieces[first_piece[k]..first_piece[k + 1]];
                    let threaded = || teeth.is_some_and(|t| t.thread(&pose, pieces));
                    let entry = Pile::entry(&mut self.piles[k], mine.iter().map(|c| c.s), span, threaded);
                    for (i, c) in mine.iter().enumerate() {
                        let r_t = self.shape.capsules.get(c.primitive).map_or(0.0, |cap| cap.radius);
                        let parts = parting && entanglement.is_some_and(|e| e.parts(r_t));
                        let fibre_depth = c.depth - (reach - radius);
                        let cushion = match entanglement {
                            Some(e) if parting && !parts => {
                                let gap = reach - c.depth;
                                Some((crate::cushion::cushion_load(&e, ei, r_f, wisp_radius, gap), crate::cushion::cushion_stiffness(&e, ei, r_f, wisp_radius, gap)))
                            }
                            _ => None,
                        };
                        if let Some((load, stiffness)) = cushion.filter(|&(l, k)| l > 0.0 || k > 0.0 || fibre_depth > 0.0) {
                            cons.push(PointConstraint { s: c.s, kind: ConstraintKind::Cushion { normal: c.normal, depth: fibre_depth, friction, load, stiffness }, velocity: c.tool_velocity });
                            levers.push(c.lever);
                            touching.push(Some(**c));
                            solid.push(fibre_depth > 0.0);
                            tags.push((WarmTag::Tool(c.primitive), c.s));
                        } else if fibre_depth > 0.0 && !parts && cushion.is_none() {
                            cons.push(PointConstraint { s: c.s, kind: ConstraintKind::Contact { normal: c.normal, depth: fibre_depth, friction }, velocity: c.tool_velocity });
                            levers.push(c.lever);
                            touching.push(Some(**c));
                            solid.push(true);
                            tags.push((WarmTag::Tool(c.primitive), c.s));
                        }
                        // One drag per crossing of a capsule and the wisp: the deepest of the strand's contacts
                        // with that capsule (neighbouring pieces near the crossing are found too).
                        let deepest = || mine.iter().enumerate().all(|(j, o)| o.primitive != c.primitive || o.depth < c.depth || (o.depth == c.depth && j >= i));
                        if let (Some(e), true) = (entanglement.filter(|_| parts), deepest()) {
                            let distance = r_t + reach - c.depth;
                            let share = crate::entanglement::parted_share(distance, wisp_radius, r_t + r_f);
                            let curl = crate::entanglement::curl_curvature(strand, c.s);
                            Pile::reach(&mut self.piles[k], entry, c.s);
                            let max_force = friction * share * e.parting_load_piled(ei, r_f, r_t, w, strand.model.length - c.s, curl, hair_friction, c.s - entry, packing);
                            if max_force > 0.0 {
                                cons.push(PointConstraint { s: c.s, kind: ConstraintKind::Drag { max_force, slip_speed: e.slip_speed }, velocity: c.tool_velocity });
                                levers.push(c.lever);
                                touching.push(None);
                                solid.push(false);
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
                    cons.extend(frame.hair_rows[k].iter().map(|(_, c)| *c));
                    tags.extend(frame.hair_rows[k].iter().map(|(side, c)| (WarmTag::Hair(side.other), c.s)));
                    let last = std::mem::take(&mut self.warm[k]);
                    let outcome = if self.ws.prepared[k] {
                        // A batched strand with constraints takes over its lane's solver workspace.
                        let handed = match (cons.is_empty(), self.ws.lane_of[k]) {
                            (false, Some((b, j))) => self.ws.batches[b].hand_over(j, strand),
                            _ => Ok(()),
                        };
                        if frame.rows.len() <= frame.used {
                            frame.rows.push(ConstraintRows::default());
                        }
                        handed.and_then(|()| strand.fill_constraint_rows(&cons, &options, &mut frame.rows[frame.used])).map(|()| {
                            for (i, (side, _)) in frame.hair_rows[k].iter().enumerate() {
                                frame.hair_slots[side.pair][side.second as usize] = Some((frame.used, first_hair + i));
                            }
                            frame.used += 1;
                            Solved::Rows(frame.used - 1)
                        })
                    } else {
                        let twisting = std::mem::take(&mut self.surface_torques[k]);
                        strand.step_constrained(dt, &twisting, &cons, &options).map(Solved::Stepped)
                    };
                    if let Ok(Solved::Rows(i)) = &outcome {
                        Self::warm_start(&last, &tags, strand.model.segment_length(), &mut self.ws.warm_used, &mut frame.rows[*i]);
                    }
                    self.warm[k] = last;
                    self.warm[k].clear();
                    match outcome {
                        Ok(solved) => frame.pending.push(Pending { strand: k, tags, levers, touching, solid, solved, touched }),
                        Err(e) => {
                            frame.first_error.get_or_insert(e);
                        }
                    }
                }
            }
            let spent = frame.clock.elapsed().as_secs_f64() - t_strand;
            if touched {
                frame.timings.constrained += spent;
                frame.timings.touched_strands += 1;
            } else {
                frame.timings.free += spent;
            }
        }
        Ok(())
    }
}
