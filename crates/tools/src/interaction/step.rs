//! The interaction step: its stages in order (see the module documentation of `interaction`).

use super::warm::{HairSide, Warm, WarmTag};
use super::{ForceModel, LocalInteraction, StepResult, StepTimings};
use crate::contact::{detect, Contact, ToolPose};
use nalgebra::{Matrix3, Vector3};
use strand::constraint::{solve, ConstraintKind, ConstraintLink, ConstraintRows, PointConstraint};
use strand::kinematics::{frame_at, segment_frames};
use strand::{PointForce, StrandError};

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

impl LocalInteraction {
    /// Moves the tool to `pose` over `dt` seconds and steps every strand. On a strand's failure the error is
    /// returned; the other strands have stepped.
    ///
    /// With the constraint model every strand first evaluates its dynamics and unconstrained velocities
    /// ([`Strand::prepare_step`](strand::Strand::prepare_step)); the collision pieces are then read from that evaluation's frames and Gauss
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
