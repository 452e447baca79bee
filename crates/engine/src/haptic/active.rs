//! The active set: the guides simulated as local strands near the tool, chosen ahead of its motion, and
//! what happens to a strand when it joins or leaves.
//!
//! Each haptic step ([`HapticCore::update_active`] before the strands' step, [`HapticCore::track_active`]
//! after it):
//! 1. **Choice** (started when the tool has moved `HapticParams::reselect_distance` since the last one): the
//!    guides whose settled shape (through the lattice) comes within `SessionParams::activation_radius` of the
//!    tool's shape on its way over the next `HapticParams::lookahead` s (from the tool to where its velocity
//!    takes it), nearest first, at most `SessionParams::max_chosen`. The scan is spread over
//!    `HapticParams::choice_steps` haptic steps (an equal share of the guides each step, [`Choice`]), so that
//!    no step pays for all of it; the chosen set takes effect when the scan ends: the strands no longer chosen
//!    start relaxing at once, the newly chosen guides are queued.
//! 2. **Joining** guides join from the queue, nearest first, at most `HapticParams::joins_per_step` a step
//!    from the step after the scan ended (a step pays for a few joining strands, not for a whole choice). They
//!    start from their stored shape (groomed, or where they came to rest), at rest, their roots on the head:
//!    no kick. The displacement the viewer shows fades in over `HapticParams::blend_time`.
//! 3. **Leaving** guides (no longer chosen) are still simulated, and the tool may still touch them, until
//!    they are at rest (tip slower than `HapticParams::rest_speed` for `HapticParams::rest_time`) *and* back
//!    in place: every sample within `HapticParams::handover_distance` of where the global layer carries its
//!    guide (the head and the lattice). They fall back by their own dynamics while the tool stays (their rest
//!    shape, the hold of the neighbours), so the hand-over carries at most that distance
//!    ([`HapticCore::handover_max`]). A cut strand (its groom is no longer its shape) is let go once at rest. A
//!    strand not back in place `HapticParams::max_relax_time` after it left is let go wherever it is (an early
//!    hand-over, measured apart: [`HapticCore::early_handovers`]; what holds it off is mostly its contact with
//!    other local strands blown across it). **The hand-over moves nothing drawn**: the strand's shown
//!    displacement from its carried place becomes the guide's offset in the global layer ([`HandedOver`]), which
//!    the hold of the hair volume then brings back by the same hold law (spring and damping) the strand felt.
//!    Let go: velocities zeroed, and a strand whose tip is farther than `HapticParams::rest_distance` from its
//!    groomed tip returns to its groomed shape in the store (what it joins from next time; not drawn). Nothing
//!    stays frozen where the tool left it.
//! 4. When chosen and relaxing strands together exceed `max_active`, relaxing ones are let go, those whose hair
//!    drawn is nearest its place first (the least for the global layer to take over), wherever they are (an early hand-over too): at
//!    most `max_active` strands are simulated (the step's cost is bounded). A strand limit
//!    below it (`Command::LimitStrands`, the live thread's strand budget, `crate::budget`) takes its place: a
//!    new choice takes the same share of it as `max_chosen` of `max_active`, and the relaxing strands beyond
//!    it are let go at once.
//!
//! A membership change moves the strands between the interaction and the guide store (no strand is copied: a
//! joining one is taken out of the store, a leaving one put back; the interaction keeps its workspaces,
//! [`tools::interaction::LocalInteraction::set_strands`]), and never happens while the clip holds a strand.

use super::bounds::{nearer, segment_boxes};
use tools::geometry::Aabb;
pub(crate) use super::bounds::GuideBounds;
use super::strands::{samples_along, samples_and_tip, Sampled};
use super::rest_pieces::RestPieces;
use super::HapticCore;
use tools::geometry::point_segment_distance;
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use strand::Strand;

/// Where a simulated strand is in its life in the active set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Phase {
    /// Chosen near the tool.
    Chosen,
    /// No longer chosen, still simulated until at rest: time since it left and time its tip has been slow, s.
    Relaxing { since: f64, still: f64 },
    /// To be let go at the next step (leaves the simulation, handed over to the global layer: [`HandedOver`]).
    Fading,
}

/// One simulated strand's membership (parallel to `HapticCore::active`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Member {
    pub phase: Phase,
    /// Weight of its displacement in what the viewer shows, in [0, 1].
    pub weight: f64,
    /// Tip position at the last step (head frame), m; None right after joining.
    pub tip: Option<Vector3<f64>>,
    /// Tip speed over the last step, m/s.
    pub tip_speed: f64,
    /// Let go before it was back in place (after `max_relax_time`, or by the strand limit).
    pub early: bool,
    /// Found back in place: its hand-over then ([`HapticCore::handover_jump`] on that step's lattice, the one
    /// its let-go is decided on), m.
    pub in_place: Option<f64>,
}

impl Member {
    fn joining() -> Self {
        Self { phase: Phase::Chosen, weight: 0.0, tip: None, tip_speed: 0.0, early: false, in_place: None }
    }
}

/// A relaxing strand at rest is looked at every this many haptic steps (strand by strand in turns) to see
/// whether it is back in place (`HapticParams::handover_distance`): its samples and its carried place cost a few
/// microseconds, and a strand held off its place (by friction, say) may rest for long.
const PLACE_CHECK_EVERY: usize = 10;

/// A guide handed over to the global layer with the displacement its local strand had from where the global
/// layer carries it (issue 30): the hand-over changes nothing drawn. The global layer then shows the guide at its
/// carried place plus this offset, which the hold of the hair volume brings back by the one hold law
/// (`HapticParams::hold_rates`: the spring and damping per unit mass a local strand feels, each sample a point
/// held by the hair around it; no contact of its own, as the lattice has none), until every sample is within
/// [`HANDED_OVER_GONE`]. Without a hold (`HapticParams::hold_distance` infinite) the offset fades out over
/// `HapticParams::blend_time` instead. No longer simulated (a guide chosen again joins with its offset still
/// relaxing, shown added to its strand's displacement).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct HandedOver {
    pub guide: usize,
    /// Each sample's displacement from where the global layer carries its guide (at the guide's sample arc
    /// lengths), in the head frame (it turns with the head), m.
    pub offset: Vec<Vector3<f64>>,
    /// Its rate of change, head frame, m/s (zero at the hand-over: a strand is let go at rest).
    pub velocity: Vec<Vector3<f64>>,
    /// Weight of the offset shown, in [0, 1]: 1 under a hold; without one it falls to 0 over `blend_time`.
    pub weight: f64,
}

/// A handed-over guide's offset is dropped once every sample is within this of its carried place, m (the change
/// its drop makes in the hair drawn).
pub(crate) const HANDED_OVER_GONE: f64 = 1e-5;

/// A choice of the active set in progress: the tool's way it is made for (from `tool` to `ahead`, m, turned by
/// `rotation`), the next guide to scan and the guides found near so far (distance in m, guide).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Choice {
    tool: Vector3<f64>,
    ahead: Vector3<f64>,
    rotation: Matrix3<f64>,
    next: usize,
    near: Vec<(f64, usize)>,
}

/// The tip of a strand, m.
fn tip(s: &Strand) -> Vector3<f64> {
    let frames = strand::kinematics::segment_frames(&s.model, &s.state);
    frames.last().map_or(s.state.root.position, |f| f.position)
}

/// Stages 3-4 and 8's state: which guides are simulated, their strands, the choice in progress and the
/// hand-overs to the global layer.
#[derive(Debug, Clone)]
pub(crate) struct ActiveSet {
    /// Every guide's strand while it is not simulated (it keeps its last state there); None while it is: the
    /// interaction has it (moved, not copied: a copy of a strand's workspaces was most of a joining step).
    pub strands: Vec<Option<Strand>>,
    /// Simulated guides, in the interaction's order (their strands live in the interaction meanwhile and
    /// move back to `strands` when they leave or the set is cleared), and each one's membership.
    pub active: Vec<usize>,
    pub members: Vec<Member>,
    /// Guides handed over to the global layer whose displacement from their carried place is still relaxing
    /// (no longer simulated, or simulated again with it; [`HandedOver`]).
    pub handed: Vec<HandedOver>,
    /// The choice of the active set in progress, if any (spread over steps).
    pub choice: Option<Choice>,
    /// Guides the last finished choice chose that have yet to join, nearest first (they join
    /// `HapticParams::joins_per_step` at a time).
    pub queued: Vec<usize>,
    /// The most strands simulated now ([`Command::LimitStrands`](crate::command::Command::LimitStrands), the live
    /// thread's strand budget), in 1..=`SessionParams::max_active`; `max_active` unless limited.
    pub strand_limit: usize,
    /// Where the tool was at the last choice (None: choose again).
    pub last_select: Option<Vector3<f64>>,
    /// Fastest tip of the simulated strands over the last step, m/s.
    pub max_tip_speed: f64,
    /// The largest hand-over to the global layer so far: a let-go strand's largest shown displacement from its
    /// place carried by the global layer when it leaves the simulation (what the hand-over carries into the
    /// global layer, which the hold then brings back; [`HandedOver`]), m.
    pub handover_max: f64,
    /// Strands let go so far back in place (handed over to the global layer).
    pub handovers: u64,
    /// The same for the strands let go before they were back in place (after `HapticParams::max_relax_time`,
    /// or by the strand limit): the largest hand-over, m, and how many.
    pub early_handover_max: f64,
    pub early_handovers: u64,
    /// Each guide's groomed rest pieces for the hair-hair contacts, kept from its first join on ([`RestPieces`]):
    /// at most one entry per guide (a few kB each: about 200 guides, under a megabyte).
    pub rest_pieces: Vec<Option<RestPieces>>,
}

impl ActiveSet {
    /// Every guide's strand in the store, none simulated, at most `strand_limit` at once.
    pub fn new(strands: Vec<Strand>, strand_limit: usize) -> Self {
        Self { strands: strands.into_iter().map(Some).collect(), active: Vec::new(), members: Vec::new(), handed: Vec::new(), choice: None, queued: Vec::new(), strand_limit, last_select: None, max_tip_speed: 0.0, handover_max: 0.0, handovers: 0, early_handover_max: 0.0, early_handovers: 0, rest_pieces: Vec::new() }
    }
}

impl HapticCore {
    /// Empties the active set: its strands are handed over to the global layer where they are
    /// ([`HapticCore::hand_over`]: the hair drawn does not move; counted as early hand-overs) and go back to the
    /// guide store let go (the interaction keeps none); forgets any choice in progress.
    pub(crate) fn clear_active(&mut self) {
        let strands = std::mem::take(&mut self.interaction.strands);
        let guides = std::mem::take(&mut self.set.active);
        let members = std::mem::take(&mut self.set.members);
        for (i, (s, g)) in strands.into_iter().zip(guides).enumerate() {
            let member = members.get(i).map(|m| Member { early: true, ..*m });
            self.hand_over(g, s, member, None);
        }
        self.interaction.set_strands(Vec::new(), &[]);
        self.set.choice = None;
        self.set.queued.clear();
        self.set.last_select = None;
    }

    /// The guides whose settled shapes (through the lattice `nodes`) come within the activation radius of the
    /// tool's shape (its capsules, turned by `rotation`) anywhere on its way from `tool` to `ahead` (m; checked
    /// at both ends and midway), nearest first, at most `max_chosen`. The shape, not the tool's point: a
    /// comb's outer teeth are 6.5 cm from it, and a strand chosen only once a tooth is inside it is kicked.
    /// All at once ([`HapticCore::update_active`] spreads the same scan over steps).
    #[cfg(test)]
    pub(crate) fn choose(&self, tool: &Vector3<f64>, ahead: &Vector3<f64>, rotation: &Matrix3<f64>, nodes: &[Point3<f64>], head: &Isometry3<f64>) -> Vec<usize> {
        let mut c = Choice { tool: *tool, ahead: *ahead, rotation: *rotation, next: 0, near: Vec::new() };
        self.scan(&mut c, self.model.scene.guides.len(), nodes, head);
        self.chosen(c)
    }

    /// What of the tool the choice looks near (tool frame: capsules' ends and radius, m): its shape's capsules;
    /// a blowing nozzle's jet instead (dryer, sprayer with the button held at the last step: its axis from the
    /// nozzle, `GlobalParams::nozzle_standoff` behind the tool point along +z, over its cone's range along -z,
    /// `tools::dryer::Cone::range`), so that the strands the jet blows are simulated, not those near the nozzle
    /// or the aim point. A nozzle that does not blow touches the hair only with its body.
    fn reach(&self) -> Vec<(Vector3<f64>, Vector3<f64>, f64)> {
        if self.actions.was_pressed && matches!(self.tool, crate::tool::Tool::Dryer | crate::tool::Tool::Sprayer) {
            let back = self.model.params.global.nozzle_standoff;
            let range = if self.tool == crate::tool::Tool::Dryer { tools::dryer::HairDryer::default().cone.range } else { tools::sprayer::Sprayer::default().cone.range };
            return vec![(Vector3::new(0.0, 0.0, back), Vector3::new(0.0, 0.0, back - range), 0.0)];
        }
        self.model.shapes[self.tool as usize].capsules.iter().map(|c| (Vector3::from(c.a), Vector3::from(c.b), c.radius)).collect()
    }

    /// Scans the next `count` guides of the choice `c` (see [`HapticCore::choose`]), their references carried
    /// by the lattice `nodes` and the head at `head`.
    fn scan(&self, c: &mut Choice, count: usize, nodes: &[Point3<f64>], head: &Isometry3<f64>) {
        let r = self.model.params.activation_radius;
        let caps = self.reach();
        let reach = caps.iter().map(|(a, b, rad)| a.norm().max(b.norm()) + rad).fold(0.0, f64::max);
        // The shape's box in its own frame: a point farther than d from it is farther than d from every capsule.
        let shape = caps.iter().fold(Aabb::empty(), |u, (a, b, rad)| u.merge(&Aabb::of_segment(a, b, *rad)));
        // Each capsule's segment's box: a point farther than d + rad from it is farther than d from the capsule.
        let boxes = segment_boxes(&caps);
        let (tool, ahead, rotation) = (c.tool, c.ahead, c.rotation);
        let poses = [tool, (tool + ahead) * 0.5, ahead];
        // The viewer's cache serves the guides it holds if its bases are for these nodes and this head (it is not
        // moved to them here: what the step measures against the nodes last seen stays so).
        let mut cache = self.shown.references.borrow_mut();
        let cached = nodes.len() == self.model.scene.lattice.node_count() && cache.is_for(nodes, head);
        let end = (c.next + count).min(self.model.scene.guides.len());
        for g in c.next..end {
            // The guide's ball farther than the radius from the swept shape: none of its samples is nearer.
            let centre = (head * Point3::from(self.model.bounds.centres[g])).coords;
            if point_segment_distance(&centre, &tool, &ahead) - reach - self.model.bounds.radii[g] >= r {
                continue;
            }
            let mut d = f64::INFINITY;
            // One carried sample k at x; true once the rest of the guide cannot come nearer.
            let mut visit = |k: usize, x: &Vector3<f64>| {
                // Cheap rejection by the shape's bounding sphere swept along the way; the samples after this one
                // lie within `beyond` of it: if they are all as far, none is carried (the same choice).
                let limit = r.min(d);
                let far = point_segment_distance(x, &tool, &ahead) - reach;
                if far - self.model.bounds.beyond[g].get(k).copied().unwrap_or(f64::INFINITY) >= limit {
                    return true;
                }
                if far >= limit {
                    return false;
                }
                for o in &poses {
                    let q = rotation.transpose() * (x - o);
                    if shape.distance_to(&q) >= r.min(d) {
                        continue;
                    }
                    d = nearer(&q, &caps, &boxes, d);
                }
                false
            };
            // A guide the viewer's cache holds (a simulated or handed-over one) has its carried samples there, the
            // same numbers (`reference::ReferenceCache::held_bases`), mapped once per lattice for the hold and the viewer.
            if let Some(bases) = cached.then(|| cache.held_bases(&self.model.scene, g)).flatten() {
                for (k, x) in bases.iter().enumerate() {
                    if visit(k, x) {
                        break;
                    }
                }
            } else {
                let weights = self.model.scene.guide_hold_weights(g);
                for (k, x) in self.model.scene.guide_points_each(nodes, head, g, &weights).enumerate() {
                    if visit(k, &x) {
                        break;
                    }
                }
            }
            if d < r {
                c.near.push((d, g));
            }
        }
        c.next = end;
    }

    /// The chosen guides of a finished scan: nearest first, at most [`HapticCore::chosen_limit`].
    fn chosen(&self, mut c: Choice) -> Vec<usize> {
        c.near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        c.near.iter().take(self.chosen_limit()).map(|x| x.1).collect()
    }

    /// The most guides a choice takes: `max_chosen`, or under a strand limit ([`HapticCore::strand_limit`])
    /// the same share of it as `max_chosen` of `max_active` (room is left for relaxing strands), at least 1.
    pub(crate) fn chosen_limit(&self) -> usize {
        let (chosen, active) = (self.model.params.max_chosen, self.model.params.max_active.max(1));
        if self.set.strand_limit >= active {
            return chosen;
        }
        (self.set.strand_limit * chosen / active).clamp(1, chosen)
    }

    /// Stage 3 of the step: the choice (started when the tool, the proxy at `proxy`, m, moving at `velocity`,
    /// m/s, has moved far enough; one share of its scan per step) and the membership changes (joining, let-go
    /// strands leaving the simulation). Never while the clip holds a strand.
    pub(crate) fn update_active(&mut self, proxy: &Vector3<f64>, velocity: &Vector3<f64>, rotation: &Matrix3<f64>, nodes: &[Point3<f64>], head: &Isometry3<f64>) {
        if self.actions.clipped || nodes.len() != self.model.scene.lattice.node_count() {
            return;
        }
        let moved = self.set.last_select.map_or(true, |p| (p - proxy).norm() > self.model.params.haptic.reselect_distance);
        if self.set.choice.is_none() && moved {
            let ahead = proxy + velocity * self.model.params.haptic.lookahead;
            self.set.choice = Some(Choice { tool: *proxy, ahead, rotation: *rotation, next: 0, near: Vec::new() });
            self.set.last_select = Some(*proxy);
        }
        let mut guides = self.set.active.clone();
        let mut members = self.set.members.clone();
        // Queued guides join (before any scan, so a step never pays for the scan's end and joins).
        if !self.set.queued.is_empty() {
            self.admit(&mut guides, &mut members);
        } else if let Some(mut c) = self.set.choice.take() {
            let clock = std::time::Instant::now();
            let n = self.model.scene.guides.len();
            let share = n.div_ceil(self.model.params.haptic.choice_steps.max(1));
            self.scan(&mut c, share, nodes, head);
            let chosen = if c.next >= n { Some(self.chosen(c)) } else {
                self.set.choice = Some(c);
                None
            };
            self.stats.timings.choose = clock.elapsed().as_secs_f64();
            if let Some(chosen) = chosen {
                self.join(&chosen, &guides, &mut members);
            }
        }
        // Beyond the strand limit relaxing strands are let go, those nearest their place first (after a lowered
        // limit, also when no guide joins); their samples, taken to rank them, serve their hand-over.
        let sampled = self.let_go_beyond(self.set.strand_limit, &mut members);
        // (The simulated strands' members come first, in order: what the rebuild measures of a leaving one.)
        for (m, new) in self.set.members.iter_mut().zip(&members) {
            m.early = new.early;
        }
        // Let-go strands leave the simulation.
        let mut k = 0;
        while k < guides.len() {
            if members[k].phase == Phase::Fading {
                guides.remove(k);
                members.remove(k);
            } else {
                k += 1;
            }
        }
        if guides != self.set.active {
            let clock = std::time::Instant::now();
            self.rebuild(guides, members, sampled);
            self.stats.timings.rebuild = clock.elapsed().as_secs_f64();
        } else {
            self.set.members = members;
        }
    }

    /// The membership after a choice: the `chosen` guides that are simulated (`guides`, `members` parallel)
    /// become (or stay) Chosen, the others that were start relaxing, and the chosen ones not simulated yet are
    /// queued to join, nearest first ([`HapticCore::admit`]).
    fn join(&mut self, chosen: &[usize], guides: &[usize], members: &mut [Member]) {
        for (g, m) in guides.iter().zip(members.iter_mut()) {
            if chosen.contains(g) {
                m.phase = Phase::Chosen;
                m.early = false;
                m.in_place = None;
            } else if m.phase == Phase::Chosen {
                m.phase = Phase::Relaxing { since: 0.0, still: 0.0 };
            }
        }
        self.set.queued.clear();
        self.set.queued.extend(chosen.iter().rev().filter(|g| !guides.contains(g)));
    }

    /// The next `HapticParams::joins_per_step` queued guides join (a handed-over guide is simulated again from
    /// its stored state, its offset still relaxing); beyond the strand limit, relaxing strands make room ([`HapticCore::let_go_beyond`]).
    fn admit(&mut self, guides: &mut Vec<usize>, members: &mut Vec<Member>) {
        for _ in 0..self.model.params.haptic.joins_per_step {
            let Some(g) = self.set.queued.pop() else { break };
            if !guides.contains(&g) {
                guides.push(g);
                members.push(Member::joining());
            }
        }
    }

    /// While more than `limit` strands (`max_active`, or the strand limit) would stay simulated, relaxing ones are
    /// let go (marked Fading): those whose hair drawn is nearest its carried place first (the least for the
    /// global layer to take over and bring back; [`HapticCore::shown_offset`]), then those that left first. Chosen strands are never let go here: a
    /// choice takes at most [`HapticCore::chosen_limit`] <= `limit`. Returns the let-go strands' samples (by slot).
    fn let_go_beyond(&self, limit: usize, members: &mut [Member]) -> Vec<(usize, Sampled)> {
        let mut over = members.iter().filter(|m| m.phase != Phase::Fading).count().saturating_sub(limit);
        if over == 0 {
            return Vec::new();
        }
        // A slot not simulated yet has no samples: last in the order (infinitely far), let go without them.
        let mut relaxing: Vec<(f64, f64, usize, Option<Sampled>)> = members.iter().enumerate().filter_map(|(i, m)| match m.phase {
            Phase::Relaxing { since, .. } => Some(match self.shown_offset(i) {
                Some((offset, sampled)) => (offset, since, i, Some(sampled)),
                None => (f64::INFINITY, since, i, None),
            }),
            _ => None,
        }).collect();
        relaxing.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.total_cmp(&a.1)).then(a.2.cmp(&b.2)));
        let mut gone = Vec::with_capacity(over);
        for (_, _, i, sampled) in relaxing {
            if over == 0 {
                break;
            }
            members[i].phase = Phase::Fading;
            members[i].early = true;
            over -= 1;
            gone.extend(sampled.map(|x| (i, x)));
        }
        gone
    }

    /// How far the hair drawn for simulated strand `slot` is from where the global layer carries its guide (at the
    /// nodes last seen, the hold's cache), m: what its hand-over would move it by, with the samples it is measured
    /// at; None for a slot not simulated yet.
    fn shown_offset(&self, slot: usize) -> Option<(f64, Sampled)> {
        let (Some(&g), Some(s)) = (self.set.active.get(slot), self.interaction.strands.get(slot)) else { return None };
        let weight = self.set.members.get(slot).map_or(1.0, |m| m.weight);
        let guide = &self.model.scene.guides[g];
        let sampled = samples_and_tip(s, guide.model.length, self.model.scene.samples());
        let mut cache = self.shown.references.borrow_mut();
        let ok = cache.has_nodes(self.model.scene.lattice.node_count());
        let offset = sampled.points.iter().zip(cache.bases(&self.model.scene, g, ok)).map(|(p, b)| (p - b).norm() * weight).fold(0.0, f64::max);
        Some((offset, sampled))
    }

    /// Moves the strands to the new membership `guides` (`members` parallel): the staying strands move over,
    /// the joining ones come from the store at rest, the leaving ones are handed over to the global layer
    /// ([`HapticCore::hand_over`], with their `sampled` samples by slot where this step took them) and go back to the
    /// store let go.
    fn rebuild(&mut self, guides: Vec<usize>, members: Vec<Member>, mut sampled: Vec<(usize, Sampled)>) {
        let old_guides = std::mem::take(&mut self.set.active);
        let old_members = std::mem::take(&mut self.set.members);
        let mut old: Vec<Option<Strand>> = std::mem::take(&mut self.interaction.strands).into_iter().map(Some).collect();
        let mut strands = Vec::with_capacity(guides.len());
        let mut from = Vec::with_capacity(guides.len());
        let (mut kept, mut kept_members) = (Vec::with_capacity(guides.len()), Vec::with_capacity(guides.len()));
        for (&g, m) in guides.iter().zip(members) {
            let i = old_guides.iter().position(|&o| o == g);
            // A guide whose strand is in neither place is left out (none is: each is in the store or simulated,
            // `every_guide_strand_is_in_the_store_or_simulated_never_both_nor_lost`).
            let Some(s) = (match i {
                Some(i) => old[i].take(),
                None => self.joining(g),
            }) else { continue };
            strands.push(s);
            from.push(i);
            kept.push(g);
            kept_members.push(m);
        }
        let (guides, members) = (kept, kept_members);
        for (i, s) in old.into_iter().enumerate() {
            if let Some(s) = s {
                let taken = sampled.iter().position(|x| x.0 == i).map(|j| sampled.swap_remove(j).1);
                self.hand_over(old_guides[i], s, old_members.get(i).copied(), taken);
            }
        }
        self.set.active = guides;
        self.set.members = members;
        self.interaction.set_strands(strands, &from);
        // Joining strands: their groomed shapes as the hair-hair contacts' rest (`HapticParams::groomed_overlap`;
        // none for a cut strand: other segments than the groom's).
        if self.model.params.haptic.groomed_overlap {
            for (i, &g) in self.set.active.iter().enumerate() {
                let guide = &self.model.scene.guides[g];
                let uncut = (self.interaction.strands[i].model.length - guide.model.length).abs() <= 1e-12;
                if from[i].is_none() && uncut {
                    // Computed at the guide's first join, kept for its next ones (`ActiveSet::rest_pieces`).
                    RestPieces::give(&mut self.set.rest_pieces, g, &mut self.interaction, i, &guide.state);
                }
            }
        }
        self.wet.version = u64::MAX;
    }

    /// Hands the simulated strand `s` of guide `g` (its membership `m`; None: never shown) over to the global
    /// layer: its shown displacement from where the global layer carries its guide (at the nodes last seen) becomes
    /// the guide's offset there ([`HandedOver`], added to what it still carried), so the hair drawn does not move;
    /// the hold then brings it back. Counted: what the hand-over carries over, the largest sample's (for a strand
    /// found back in place, as measured then, [`Member::in_place`]), apart for early hand-overs. The strand goes
    /// back to the store let go ([`HapticCore::let_go`]). `sampled`: the strand's samples and tip as it is, if this
    /// step already took them (else taken here).
    fn hand_over(&mut self, g: usize, s: Strand, m: Option<Member>, sampled: Option<Sampled>) {
        let weight = m.map_or(0.0, |m| m.weight);
        let early = m.is_some_and(|m| m.early);
        let tip = sampled.as_ref().map(|x| x.tip);
        if weight > 0.0 {
            let pts = sampled.map_or_else(|| samples_along(&s, self.model.scene.guides[g].model.length, self.model.scene.samples()), |x| x.points);
            let mut cache = self.shown.references.borrow_mut();
            let ok = cache.has_nodes(self.model.scene.lattice.node_count());
            let to_head = cache.head().rotation.inverse();
            let shown: Vec<Vector3<f64>> = pts.iter().zip(cache.bases(&self.model.scene, g, ok)).map(|(p, b)| self.shown((p - b) * weight)).collect();
            drop(cache);
            let carried = m.and_then(|m| m.in_place).filter(|_| !early).unwrap_or_else(|| shown.iter().map(|d| d.norm()).fold(0.0, f64::max));
            if early {
                self.set.early_handover_max = self.set.early_handover_max.max(carried);
                self.set.early_handovers += 1;
            } else {
                self.set.handover_max = self.set.handover_max.max(carried);
                self.set.handovers += 1;
            }
            let offset = shown.iter().map(|d| to_head * d);
            match self.set.handed.iter_mut().find(|h| h.guide == g) {
                Some(h) => {
                    for (a, d) in h.offset.iter_mut().zip(offset) {
                        *a = *a * h.weight + d;
                    }
                    h.velocity.iter_mut().for_each(|v| *v *= h.weight);
                    h.weight = 1.0;
                }
                None => {
                    let offset: Vec<Vector3<f64>> = offset.collect();
                    let velocity = vec![Vector3::zeros(); offset.len()];
                    self.set.handed.push(HandedOver { guide: g, offset, velocity, weight: 1.0 });
                }
            }
        }
        self.set.strands[g] = Some(self.let_go(g, s, tip));
    }

    /// Stage 8's relaxation of the handed-over guides' offsets over a step `dt` (s) by the hold's law
    /// ([`HandedOver`]): per sample `x'' = -omega^2 x - c x'` with `(omega^2, c)` = `HapticParams::hold_rates` at
    /// the scene's gravity, linearly implicit Euler (the local strands' integrator; stable for every step); without
    /// a hold the weight falls by `dt / blend_time`. Offsets within [`HANDED_OVER_GONE`] are dropped.
    fn relax_handed(&mut self, dt: f64) {
        let g = self.model.scene.guides.first().map_or(0.0, |g| g.model.gravity.norm());
        let (k, c) = self.model.params.haptic.hold_rates(g);
        let fade = dt / self.model.params.haptic.blend_time;
        for h in &mut self.set.handed {
            if k > 0.0 {
                for (x, v) in h.offset.iter_mut().zip(&mut h.velocity) {
                    *v = (*v - *x * (dt * k)) / (1.0 + dt * c + dt * dt * k);
                    *x += *v * dt;
                }
            } else {
                h.weight -= fade;
            }
        }
        self.set.handed.retain(|h| h.weight > 0.0 && h.offset.iter().any(|x| x.norm() * h.weight > HANDED_OVER_GONE));
    }

    /// Guide `g`'s stored strand, taken from the store, ready to join: at rest (zero velocities), its root on
    /// the head at rest. None if the store does not have it.
    fn joining(&mut self, g: usize) -> Option<Strand> {
        let mut s = self.set.strands.get_mut(g)?.take()?;
        s.state.qdot.fill(0.0);
        let root = &mut s.state.root;
        root.position = self.model.scene.guides[g].state.root.position;
        root.velocity = Vector3::zeros();
        root.angular_velocity = Vector3::zeros();
        root.acceleration = Vector3::zeros();
        Some(s)
    }

    /// A strand of guide `g` leaving the simulation: velocities zeroed; back to its groomed shape if its tip is
    /// farther than `rest_distance` from the groomed tip (an uncut strand; a cut one keeps its shape). `at`: its tip,
    /// if known.
    fn let_go(&self, g: usize, mut s: Strand, at: Option<Vector3<f64>>) -> Strand {
        s.state.qdot.fill(0.0);
        let guide = &self.model.scene.guides[g];
        let uncut = s.state.q.len() == guide.state.q.len() && (s.model.length - guide.model.length).abs() < 1e-12;
        if uncut {
            let groomed = guide.reference.last().copied().unwrap_or(guide.state.root.position);
            if (at.unwrap_or_else(|| tip(&s)) - groomed).norm() > self.model.params.haptic.rest_distance {
                s.state.q.copy_from(&guide.state.q);
            }
        }
        s
    }

    /// Stage 8 of the step: each simulated strand's tip speed over a step `dt` (s; the step before this one:
    /// the tips at the start of each step, read from the interaction's collision pieces, one step behind), the
    /// leaving strands' rest, and the display weights (fading in, and the let-go strands' out, over
    /// `blend_time`).
    pub(crate) fn track_active(&mut self, dt: f64, lattice: &crate::snapshot::LatticeSnapshot) {
        let h = self.model.params.haptic;
        let fade = dt / h.blend_time;
        self.set.max_tip_speed = 0.0;
        let mut resting = Vec::new();
        for (k, (m, s)) in self.set.members.iter_mut().zip(&self.interaction.strands).enumerate() {
            let x = self.interaction.tip_at_last_step(k).unwrap_or_else(|| tip(s));
            m.tip_speed = m.tip.map_or(0.0, |p| (x - p).norm() / dt);
            m.tip = Some(x);
            if m.tip_speed.is_finite() {
                self.set.max_tip_speed = self.set.max_tip_speed.max(m.tip_speed);
            }
            match m.phase {
                Phase::Chosen => m.weight = (m.weight + fade).min(1.0),
                Phase::Relaxing { since, still } => {
                    let (since, still) = (since + dt, if m.tip_speed < h.rest_speed { still + dt } else { 0.0 });
                    m.weight = (m.weight + fade).min(1.0);
                    m.phase = Phase::Relaxing { since, still };
                    if since >= h.max_relax_time {
                        m.phase = Phase::Fading;
                        m.early = true;
                    } else if still >= h.rest_time && (self.step as usize + k) % PLACE_CHECK_EVERY == 0 {
                        // At rest: whether it is back in place is looked at every `PLACE_CHECK_EVERY` steps (in turns).
                        resting.push(k);
                    }
                }
                Phase::Fading => {}
            }
        }
        for k in resting {
            let jump = self.handover_jump(k, lattice);
            if jump <= h.handover_distance {
                self.set.members[k].phase = Phase::Fading;
                self.set.members[k].in_place = Some(jump);
            }
        }
        self.relax_handed(dt);
    }

    /// How far the hair drawn for simulated strand `slot` would move if it were handed over to the global layer
    /// now: its largest shown displacement from where the head and the lattice of this step (`lattice`) carry
    /// its guide (`Scene::guide_points`), m; 0 for a cut strand (its shape is no longer its guide's: it is let go
    /// once at rest).
    fn handover_jump(&self, slot: usize, lattice: &crate::snapshot::LatticeSnapshot) -> f64 {
        let (g, s) = (self.set.active[slot], &self.interaction.strands[slot]);
        let guide = &self.model.scene.guides[g];
        if s.model.length < guide.model.length - 1e-12 || lattice.positions.len() != self.model.scene.lattice.node_count() {
            return 0.0;
        }
        let weight = self.set.members.get(slot).map_or(1.0, |m| m.weight);
        let pts = samples_along(s, guide.model.length, self.model.scene.samples());
        pts.iter().zip(self.model.scene.guide_points(&lattice.positions, &lattice.head, g)).map(|(p, b)| (p - b).norm() * weight).fold(0.0, f64::max)
    }

    /// The active strands' roots move with the head, which is rigid (at the pose `HapticCore::head`): each
    /// root is held at its guide's root on the scalp, moving and turning with the head. Not with the lattice: the tool's own
    /// repelling obstacle deforms the lattice, and roots following it sank into the head and were kicked out.
    pub(crate) fn roots_follow(&mut self, dt: f64) {
        let head = self.head;
        let head_rotation = head.rotation.to_rotation_matrix().into_inner();
        for (slot, &g) in self.set.active.iter().enumerate() {
            let groomed = &self.model.scene.guides[g].state.root;
            let target = head * nalgebra::Point3::from(groomed.position);
            let turn = head_rotation * groomed.rotation;
            let root = &mut self.interaction.strands[slot].state.root;
            // A root that is elsewhere (a state from before, or a head that moved) is brought back over one
            // step, turning with the head.
            root.velocity = (target.coords - root.position) / dt;
            let spin = nalgebra::Rotation3::from_matrix_unchecked(turn * root.rotation.transpose()).scaled_axis();
            root.angular_velocity = if spin.iter().all(|x| x.is_finite()) { spin / dt } else { Vector3::zeros() };
            root.acceleration = Vector3::zeros();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::GlobalCore;
    use crate::params::SessionParams;
    use crate::testing::{small_scene, test_rot};
    use haptics::device::DeviceReading;

    /// The tests' fixture: the small scene, the default parameters, a haptic core on them and the lattice's
    /// snapshot at rest.
    fn core_at_rest() -> (std::sync::Arc<crate::scene::Scene>, SessionParams, HapticCore, crate::snapshot::LatticeSnapshot) {
        let scene = small_scene();
        let params = SessionParams::default();
        let core = HapticCore::new(scene.clone(), params).unwrap();
        let snap = GlobalCore::new(scene.clone(), &params).snapshot();
        (scene, params, core, snap)
    }

    #[test]
    fn the_choice_spread_over_steps_is_the_whole_scan() {
        // The comb held still in the hair at the back of the head: after `choice_steps` steps the scan has found
        // exactly the guides the whole scan at once chooses (same set, nearest first), and none has joined
        // before (the scan is spread: the set is empty until then). They then join `joins_per_step` a step,
        // nearest first, until all have. At most `max_active` are simulated.
        let (_, params, mut core, snap) = core_at_rest();
        let at = Vector3::new(0.0, -0.118, 0.0);
        let reading = DeviceReading { time: 0.0, position: at, rotation: test_rot(), buttons: 0 };
        let steps = params.haptic.choice_steps;
        let mut way = None;
        // The first step's device step anchors the tool; its physics step sees no device yet (the physics runs
        // with the proxy's state at its period's start).
        core.step(Some(reading), &snap, 1e-3);
        for n in 0..steps {
            assert!(core.active().is_empty(), "chosen after {n} steps");
            core.step(Some(reading), &snap, 1e-3);
            // The way the choice is made for: the proxy (kept out of the body) and where its velocity takes it.
            // (The proxy's state this step's physics used: the device side's at the step's start.)
            if core.proxy.present {
                way.get_or_insert((core.proxy.position, core.proxy.position + core.proxy.velocity * params.haptic.lookahead));
            }
        }
        let (from, to) = way.unwrap();
        let want = core.choose(&from, &to, &test_rot(), &snap.positions, &snap.head);
        let per = params.haptic.joins_per_step;
        assert!(want.len() > per, "the comb is in the hair, more guides than join in one step: {want:?}");
        assert!(core.active().is_empty(), "nothing joins on the step the scan ends");
        for k in 1..=want.len().div_ceil(per) {
            core.step(Some(reading), &snap, 1e-3);
            assert_eq!(core.active(), &want[..(k * per).min(want.len())], "after {k} joining steps");
        }
        assert!(core.active().len() <= params.max_active);
    }

    #[test]
    fn every_guide_strand_is_in_the_store_or_simulated_never_both_nor_lost() {
        // A comb stroke down through the hair (strands join and leave), then each command that empties the
        // active set: after every step and command, each guide's strand is in exactly one place (the store
        // while it is not simulated, the interaction while it is), and a strand that left is in the store let
        // go (finite coordinates, at rest).
        use crate::command::Command;
        let (scene, _, mut core, snap) = core_at_rest();
        let n = scene.guides.len();
        let check = |core: &HapticCore, when: &str| {
            assert_eq!(core.interaction.strands.len(), core.active().len(), "{when}");
            for g in 0..n {
                assert_ne!(core.set.strands[g].is_some(), core.active().contains(&g), "guide {g} {when}");
            }
        };
        let (mut joined, mut left) = (0, 0);
        for k in 0..1500 {
            let before: Vec<usize> = core.active().to_vec();
            let z = 0.03 - 0.1 * (k as f64 / 1500.0);
            let reading = DeviceReading { time: k as f64 * 1e-3, position: Vector3::new(0.0, -0.118, z), rotation: test_rot(), buttons: 0 };
            core.step(Some(reading), &snap, 1e-3);
            check(&core, &format!("after step {k}"));
            joined += core.active().iter().filter(|g| !before.contains(g)).count();
            for &g in before.iter().filter(|g| !core.active().contains(g)) {
                left += 1;
                // Let go where it was (or back to its groom if far from it), at rest.
                let s = core.set.strands[g].as_ref().unwrap();
                assert!(s.state.q.iter().all(|x| x.is_finite()) && s.state.qdot.iter().all(|&v| v == 0.0), "guide {g} let go at rest");
            }
        }
        assert!(joined > 8 && left > 0, "strands joined ({joined}) and left ({left}) during the stroke");
        assert!(!core.active().is_empty(), "the comb ends in the hair");
        for (c, name) in [(Command::SelectTool(crate::tool::Tool::Brush), "select"), (Command::SetHair { hair_type: 1, curliness: 0.0, combing_ease: 0.0 }, "set hair"), (Command::Reset, "reset")] {
            for k in 0..300 {
                let reading = DeviceReading { time: k as f64 * 1e-3, position: Vector3::new(0.0, -0.118, -0.02), rotation: test_rot(), buttons: 0 };
                core.step(Some(reading), &snap, 1e-3);
            }
            assert!(!core.active().is_empty(), "in the hair before {name}");
            core.apply(&c);
            assert!(core.active().is_empty(), "{name} empties the active set");
            check(&core, name);
        }
    }

    #[test]
    fn a_strand_limit_bounds_the_simulated_strands_within_a_choice_and_lifting_it_restores_them() {
        // A comb stroke down the back hair with the default limits (48 chosen, 56 simulated). Halfway, the
        // strand budget's command limits the strands to 20: within a new choice (`choice_steps`) plus the
        // joins it needs, at most 20 are simulated, every step after, and the choice takes 20 x 48 / 56 = 17;
        // no strand is lost (each guide's strand in the store or simulated). Lifted back to 56 the stroke
        // simulates more than 20 again. Without any limit the same stroke simulates more than 20 at that point
        // (the limit, not the hair, made the difference).
        use crate::command::Command;
        let scene = small_scene();
        let params = SessionParams::default();
        let snap = GlobalCore::new(scene.clone(), &params).snapshot();
        let reading = |k: usize| {
            let z = 0.03 - 0.1 * (k as f64 / 2400.0);
            DeviceReading { time: k as f64 * 1e-3, position: Vector3::new(0.0, -0.118, z), rotation: test_rot(), buttons: 0 }
        };
        let mut free = HapticCore::new(scene.clone(), params).unwrap();
        let mut core = HapticCore::new(scene.clone(), params).unwrap();
        let settle = params.haptic.choice_steps + 2 * params.max_active.div_ceil(params.haptic.joins_per_step);
        let (mut most_free, mut most_limited, mut most_after) = (0, 0, 0);
        for k in 0..2400 {
            if k == 800 {
                core.apply(&Command::LimitStrands(20));
                assert_eq!(core.strand_limit(), 20);
                assert_eq!(core.chosen_limit(), 17);
            }
            if k == 1600 {
                core.apply(&Command::LimitStrands(1000));
                assert_eq!(core.strand_limit(), params.max_active, "clamped to max_active");
            }
            free.step(Some(reading(k)), &snap, 1e-3);
            core.step(Some(reading(k)), &snap, 1e-3);
            for g in 0..scene.guides.len() {
                assert_ne!(core.set.strands[g].is_some(), core.active().contains(&g), "guide {g} after step {k}");
            }
            if (800 + settle..1600).contains(&k) {
                assert!(core.active().len() <= 20, "{} simulated at step {k}", core.active().len());
                most_limited = most_limited.max(core.active().len());
                most_free = most_free.max(free.active().len());
            }
            if k >= 1600 + settle {
                most_after = most_after.max(core.active().len());
            }
        }
        assert!(most_free > 20, "without a limit the stroke simulates {most_free}");
        assert!(most_limited >= 10, "the limited stroke still simulates strands: {most_limited}");
        assert!(most_after > 20, "lifted, the stroke simulates {most_after}");
    }

    #[test]
    fn a_hand_over_carries_the_strands_displacement_and_the_hold_brings_it_back() {
        // Issue 30. A comb stroke down the back hair; halfway the strand limit drops to 2, so the relaxing strands
        // are let go wherever they are (early hand-overs); later the brush is taken, which hands over every
        // simulated strand at once. Every step, each leaving guide's shown displacement from
        // its carried place (the viewer's snapshot) is compared with the next step's: a guide let go keeps what was
        // drawn, up to one step of the hold's motion (asserted under 0.1 mm), while what the hand-overs carried over
        // is far larger (asserted over 2 mm: the check can fail). Dropping the offsets instead (the hand-over before
        // issue 30, without its display fade) moves the hair drawn by all of it. Then, the comb taken away, every
        // offset is brought back by the hold (all within 1 mm 1.5 s after; the law itself:
        // `a_handed_over_offset_follows_the_holds_critically_damped_return`).
        use crate::command::Command;
        let scene = small_scene();
        let params = SessionParams::default();
        let snap = GlobalCore::new(scene.clone(), &params).snapshot();
        let n = scene.samples();
        let reading = |k: usize, present: bool| {
            let z = 0.03 - 0.1 * (k as f64 / 1500.0);
            present.then(|| DeviceReading { time: k as f64 * 1e-3, position: Vector3::new(0.0, -0.118, z), rotation: test_rot(), buttons: 0 })
        };
        let shown = |core: &HapticCore| {
            let mut hs = crate::snapshot::HapticSnapshot::default();
            core.snapshot(&snap, 1e-3, &mut hs);
            hs.active.iter().enumerate().map(|(i, &g)| (g as usize, hs.displacement[i * n..(i + 1) * n].to_vec())).collect::<Vec<_>>()
        };
        let mut core = HapticCore::new(scene.clone(), params).unwrap();
        let (mut change, mut events): (f64, usize) = (0.0, 0);
        for k in 0..3000 {
            if k == 900 {
                core.apply(&Command::LimitStrands(2));
            }
            let leaving: Vec<usize> = core.active().to_vec();
            let before = shown(&core);
            if k == 1200 {
                // Another tool taken in the middle of the stroke: its strands are handed over where they are.
                assert!(!core.active().is_empty(), "strands simulated when the brush is taken");
                core.apply(&Command::SelectTool(crate::tool::Tool::Brush));
            }
            core.step(reading(k, k < 1500), &snap, 1e-3);
            let after = shown(&core);
            for g in leaving.iter().filter(|g| !core.active().contains(g)) {
                let was = &before.iter().find(|e| e.0 == *g).unwrap().1;
                let now = after.iter().find(|e| e.0 == *g).map(|e| e.1.clone()).unwrap_or(vec![Vector3::zeros(); n]);
                change = change.max(was.iter().zip(&now).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max));
                events += 1;
            }
        }
        let (carried, early) = core.early_handovers();
        eprintln!("{events} hand-overs ({early} early, carrying up to {:.2} mm): the hair drawn moved by {:.4} mm at most", carried * 1e3, change * 1e3);
        assert!(events > 5 && early > 0 && carried > 2e-3, "early hand-overs carrying {carried} m");
        assert!(change < 1e-4, "a hand-over moved the hair drawn by {change} m");
        let left = core.set.handed.iter().flat_map(|h| h.offset.iter().map(|x| x.norm() * h.weight)).fold(0.0, f64::max);
        eprintln!("1.5 s after the comb: {} strands simulated, {} offsets left, the largest {:.4} mm", core.active().len(), core.set.handed.len(), left * 1e3);
        assert!(left < 1e-3, "an offset of {left} m left 1.5 s after the comb");
    }

    #[test]
    fn a_handed_over_offset_follows_the_holds_critically_damped_return() {
        // The hold's law on a handed-over guide's offset (`HapticParams::hold_rates`: omega^2 = |g| / hold_distance,
        // damping 2 zeta omega; critical by default): from x0 at rest, x(t) = x0 (1 + omega t) e^(-omega t). The
        // linearly implicit Euler steps at 1 ms stay within 2 % of x0 of it (its error is first order in omega dt =
        // 0.018), it never overshoots, and the offset is dropped once under 10 um.
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let g = scene.guides[0].model.gravity.norm();
        let omega = (g / core.model.params.haptic.hold_distance).sqrt();
        let x0 = Vector3::new(0.02, -0.01, 0.005);
        core.set.handed.push(HandedOver { guide: 3, offset: vec![x0; scene.samples()], velocity: vec![Vector3::zeros(); scene.samples()], weight: 1.0 });
        let mut worst: f64 = 0.0;
        for k in 1..=2000 {
            core.relax_handed(1e-3);
            let t = k as f64 * 1e-3;
            let want = x0 * (1.0 + omega * t) * (-omega * t).exp();
            match core.set.handed.first() {
                Some(h) => {
                    worst = worst.max((h.offset[0] - want).norm() / x0.norm());
                    assert!(h.offset[0].dot(&x0) > 0.0, "overshoot at {t} s");
                }
                None => {
                    assert!(want.norm() < 2e-5, "dropped at {t} s with {} m left", want.norm());
                    break;
                }
            }
        }
        eprintln!("omega {omega:.2} 1/s: largest error {:.3} % of x0", worst * 100.0);
        assert!(worst < 0.02, "off the analytic return by {worst} of x0");
        assert!(core.set.handed.is_empty(), "dropped within 2 s");
    }

    #[test]
    fn the_guide_balls_hold_every_mapped_sample_and_the_scan_chooses_the_same_guides() {
        // Lattice nodes moved by a smooth field (up to ~1 cm), the head still or turned and moved: every guide
        // sample carried by them lies in its guide's ball (its length about its root) and every later sample within
        // the rest length beyond it, and a choice made with the balls and the early stop along a guide is the choice
        // made sample by sample (both disabled), for tools all over the head.
        let scene = small_scene();
        let params = SessionParams::default();
        let mut core = HapticCore::new(scene.clone(), params).unwrap();
        let rest = scene.lattice.ffd.rest_positions();
        let mut compared = 0;
        for (a, turn) in [(0.0, 0.0), (4e-3, 0.0), (-9e-3, 0.0), (4e-3, 0.3)] {
            let head = Isometry3::new(Vector3::new(0.0, 0.005, -0.01) * turn, Vector3::new(0.0, 0.2, 1.0) * turn);
            let nodes: Vec<Point3<f64>> = rest.iter().map(|p| head * p + Vector3::new(a * (7.0 * p.y).sin(), a * (5.0 * p.z).cos(), -a * p.x)).collect();
            for g in 0..scene.guides.len() {
                let centre = (head * Point3::from(core.model.bounds.centres[g])).coords;
                let points = scene.guide_points(&nodes, &head, g);
                for (j, x) in points.iter().enumerate() {
                    assert!((x - centre).norm() <= core.model.bounds.radii[g], "guide {g}, a {a}");
                    // Every later sample within the rest length beyond this one.
                    let beyond = core.model.bounds.beyond[g][j];
                    assert!(points[j..].iter().all(|y| (y - x).norm() <= beyond), "guide {g}, sample {j}, a {a}");
                }
                // One at a time, the same numbers.
                let weights = scene.guide_hold_weights(g);
                assert_eq!(scene.guide_points_each(&nodes, &head, g, &weights).collect::<Vec<_>>(), points, "guide {g}");
            }
            for k in 0..12 {
                let angle = k as f64 * 0.52;
                let tool = Vector3::new(0.11 * angle.sin(), -0.11 * angle.cos(), 0.04 - 0.01 * k as f64);
                let ahead = tool + Vector3::new(0.0, 0.0, -0.015);
                let with = core.choose(&tool, &ahead, &test_rot(), &nodes, &head);
                let radii = std::mem::replace(&mut core.model.bounds.radii, vec![f64::INFINITY; scene.guides.len()]);
                let beyond = std::mem::replace(&mut core.model.bounds.beyond, vec![Vec::new(); scene.guides.len()]);
                let without = core.choose(&tool, &ahead, &test_rot(), &nodes, &head);
                core.model.bounds.radii = radii;
                core.model.bounds.beyond = beyond;
                assert_eq!(with, without, "tool at {tool:?}, a {a}");
                compared += with.len();
            }
        }
        assert!(compared > 20, "the tools met guides: {compared}");
    }

    #[test]
    fn the_scan_reads_the_cached_guides_samples_as_it_would_carry_them() {
        // The comb held in the hair: once guides are simulated the viewer's cache holds their carried samples; a scan
        // reading them finds the same guides at the same distances (exactly) as one carrying every sample itself.
        let (scene, _, mut core, snap) = core_at_rest();
        let at = Vector3::new(0.0, -0.118, 0.0);
        let reading = DeviceReading { time: 0.0, position: at, rotation: test_rot(), buttons: 0 };
        for _ in 0..40 {
            core.step(Some(reading), &snap, 1e-3);
            core.stage_snapshot(&snap);
        }
        let scan = |core: &HapticCore| {
            let mut c = Choice { tool: at, ahead: at + Vector3::new(0.0, 0.0, -0.015), rotation: test_rot(), next: 0, near: Vec::new() };
            core.scan(&mut c, scene.guides.len(), &snap.positions, &snap.head);
            c.near
        };
        let held = core.active().iter().filter(|&&g| core.shown.references.borrow().holds(g)).count();
        assert!(held > 3 && core.shown.references.borrow().is_for(&snap.positions, &snap.head), "{held} guides cached");
        let with = scan(&core);
        *core.shown.references.borrow_mut() = Default::default();
        let without = scan(&core);
        assert!(with.len() > 3, "found {}", with.len());
        assert_eq!(with, without);
    }

    #[test]
    fn the_capsules_passed_over_change_no_distance() {
        // `nearer` against the least over every capsule of the comb, bit for bit, at points all around it (inside
        // the capsules too) and from every starting distance the scan may hold (none yet, the activation radius,
        // near, inside a capsule).
        let core = HapticCore::new(small_scene(), SessionParams::default()).unwrap();
        let caps = core.reach();
        let boxes = segment_boxes(&caps);
        let union = boxes.iter().fold(tools::geometry::Aabb::empty(), |u, b| u.merge(b));
        let (lo, hi) = (union.min, union.max);
        let (mut passed, mut n) = (0, 0);
        for i in 0..=24 {
            for j in 0..=24 {
                for k in 0..=24 {
                    let t = Vector3::new(i as f64, j as f64, k as f64) / 24.0;
                    let q = (lo - Vector3::repeat(0.03)) + (hi - lo + Vector3::repeat(0.06)).component_mul(&t);
                    for d0 in [f64::INFINITY, 0.03, 0.004, 1e-4, -3e-4] {
                        let all = caps.iter().fold(d0, |d, (a, b, rad)| d.min(point_segment_distance(&q, a, b) - rad));
                        assert_eq!(nearer(&q, &caps, &boxes, d0).to_bits(), all.to_bits(), "at {q:?} from {d0}");
                        passed += caps.iter().zip(&boxes).filter(|((_, _, rad), bx)| bx.distance_to(&q) - rad > all + 1e-12).count();
                        n += caps.len();
                    }
                }
            }
        }
        assert!(caps.len() > 20 && passed > n / 2, "the comb's capsules, most passed over: {passed} of {n}");
    }
}
