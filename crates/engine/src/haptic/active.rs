//! The active set: the guides simulated as local strands near the tool, chosen ahead of its motion, and
//! what happens to a strand when it joins or leaves.
//!
//! Each haptic step ([`HapticCore::update_active`] before the strands' step, [`HapticCore::track_active`]
//! after it):
//! 1. **Choice** (when the tool has moved `HapticParams::reselect_distance` since the last choice): the guides
//!    whose settled shape (through the lattice) comes within `SessionParams::activation_radius` of the tool's
//!    shape on its way over the next `HapticParams::lookahead` s (from the tool to where its velocity takes
//!    it), nearest first, at most `SessionParams::max_active`.
//! 2. **Joining** guides start from their stored shape (groomed, or where they came to rest), at rest, their
//!    roots on the head: no kick. The displacement the viewer shows fades in over `HapticParams::blend_time`.
//! 3. **Leaving** guides (no longer chosen) are still simulated, and the tool may still touch them, until
//!    they are at rest (tip slower than `HapticParams::rest_speed` for `HapticParams::rest_time`) or
//!    `HapticParams::max_relax_time` has passed. Then their shown displacement fades out over `blend_time`
//!    while they are still stepped, and they are let go: velocities zeroed, and a strand whose tip is farther
//!    than `HapticParams::rest_distance` from its groomed tip returns to its groomed shape (what the viewer
//!    shows of it once faded out). Nothing stays frozen where the tool left it.
//! 4. When chosen and relaxing strands together exceed `max_active`, the relaxing ones that left first are
//!    let go first.
//!
//! A membership change moves the strands between the interaction and the guide store (no copy of the strands
//! that stay), and never happens while the clip holds a strand.

use super::HapticCore;
use crate::scene::ffd_map;
use tools::geometry::point_segment_distance;
use nalgebra::{Matrix3, Point3, Vector3};
use strand::Strand;

/// Where a simulated strand is in its life in the active set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Phase {
    /// Chosen near the tool.
    Chosen,
    /// No longer chosen, still simulated until at rest: time since it left and time its tip has been slow, s.
    Relaxing { since: f64, still: f64 },
    /// Being let go: its shown displacement fades out (still simulated).
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
}

impl Member {
    fn joining() -> Self {
        Self { phase: Phase::Chosen, weight: 0.0, tip: None, tip_speed: 0.0 }
    }
}

/// The tip of a strand, m.
fn tip(s: &Strand) -> Vector3<f64> {
    let frames = strand::kinematics::segment_frames(&s.model, &s.state);
    frames.last().map_or(s.state.root.position, |f| f.position)
}

impl HapticCore {
    /// Copies the active strands' states back into the guide store.
    pub(crate) fn write_back(&mut self) {
        for (slot, &g) in self.active.iter().enumerate() {
            if let Some(s) = self.interaction.strands.get(slot) {
                self.strands[g] = s.clone();
            }
        }
    }

    /// Empties the active set (the strands written back as they are).
    pub(crate) fn clear_active(&mut self) {
        self.active.clear();
        self.members.clear();
        self.last_select = None;
    }

    /// The guides whose settled shapes (through the lattice `nodes`) come within the activation radius of the
    /// tool's shape (its capsules, turned by `rotation`) anywhere on its way from `tool` to `ahead` (m; checked
    /// at both ends and midway), nearest first, at most `max_active`. The shape, not the tool's point: a
    /// comb's outer teeth are 6.5 cm from it, and a strand chosen only once a tooth is inside it is kicked.
    pub(crate) fn choose(&self, tool: &Vector3<f64>, ahead: &Vector3<f64>, rotation: &Matrix3<f64>, nodes: &[Point3<f64>]) -> Vec<usize> {
        let r = self.params.activation_radius;
        let shape = &self.shapes[self.tool as usize];
        let caps: Vec<(Vector3<f64>, Vector3<f64>, f64)> = shape.capsules.iter().map(|c| (Vector3::from(c.a), Vector3::from(c.b), c.radius)).collect();
        let reach = caps.iter().map(|(a, b, rad)| a.norm().max(b.norm()) + rad).fold(0.0, f64::max);
        let poses = [*tool, (tool + ahead) * 0.5, *ahead];
        let mut near: Vec<(f64, usize)> = Vec::new();
        for (g, guide) in self.scene.guides.iter().enumerate() {
            let mut d = f64::INFINITY;
            for p in &guide.reference {
                let x = ffd_map(&self.scene.lattice.ffd, nodes, p);
                // Cheap rejection by the shape's bounding sphere swept along the way.
                if point_segment_distance(&x, tool, ahead) - reach >= r.min(d) {
                    continue;
                }
                for c in &poses {
                    let q = rotation.transpose() * (x - c);
                    for (a, b, rad) in &caps {
                        d = d.min(point_segment_distance(&q, a, b) - rad);
                    }
                }
            }
            if d < r {
                near.push((d, g));
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        near.iter().take(self.params.max_active).map(|x| x.1).collect()
    }

    /// Stage 3 of the step: the choice when the tool (the proxy at `proxy`, m, moving at `velocity`, m/s) has
    /// moved far enough, and the membership changes (joining, let-go strands leaving the simulation). Never
    /// while the clip holds a strand.
    pub(crate) fn update_active(&mut self, proxy: &Vector3<f64>, velocity: &Vector3<f64>, rotation: &Matrix3<f64>, nodes: &[Point3<f64>]) {
        if self.clipped || nodes.len() != self.scene.lattice.node_count() {
            return;
        }
        let moved = self.last_select.map_or(true, |p| (p - proxy).norm() > self.params.haptic.reselect_distance);
        let mut guides = self.active.clone();
        let mut members = self.members.clone();
        if moved {
            let ahead = proxy + velocity * self.params.haptic.lookahead;
            let chosen = self.choose(proxy, &ahead, rotation, nodes);
            for (g, m) in guides.iter().zip(members.iter_mut()) {
                if chosen.contains(g) {
                    m.phase = Phase::Chosen;
                } else if m.phase == Phase::Chosen {
                    m.phase = Phase::Relaxing { since: 0.0, still: 0.0 };
                }
            }
            for &g in &chosen {
                if !guides.contains(&g) {
                    guides.push(g);
                    members.push(Member::joining());
                }
            }
            // Over capacity: the relaxing strands that left first are let go first.
            let mut over = guides.len().saturating_sub(self.params.max_active);
            let mut relaxing: Vec<(f64, usize)> = members.iter().enumerate().filter_map(|(i, m)| match m.phase {
                Phase::Relaxing { since, .. } => Some((since, i)),
                _ => None,
            }).collect();
            relaxing.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            for (_, i) in relaxing {
                if over == 0 {
                    break;
                }
                members[i].phase = Phase::Fading;
                over -= 1;
            }
            self.last_select = Some(*proxy);
        }
        // Let-go strands whose display has faded out leave the simulation.
        let mut k = 0;
        while k < guides.len() {
            if members[k].phase == Phase::Fading && members[k].weight <= 0.0 {
                guides.remove(k);
                members.remove(k);
            } else {
                k += 1;
            }
        }
        if guides != self.active {
            self.rebuild(guides, members);
        } else {
            self.members = members;
        }
    }

    /// Moves the strands to the new membership `guides` (`members` parallel): the staying strands move over,
    /// the joining ones come from the store at rest, the leaving ones go back to the store let go.
    fn rebuild(&mut self, guides: Vec<usize>, members: Vec<Member>) {
        let old_guides = std::mem::take(&mut self.active);
        let mut old: Vec<Option<Strand>> = std::mem::take(&mut self.interaction.strands).into_iter().map(Some).collect();
        let mut strands = Vec::with_capacity(guides.len());
        for &g in &guides {
            let s = match old_guides.iter().position(|&o| o == g) {
                Some(i) => old[i].take().expect("each old strand is taken once"),
                None => self.joining(g),
            };
            strands.push(s);
        }
        for (i, s) in old.into_iter().enumerate() {
            if let Some(s) = s {
                let g = old_guides[i];
                self.strands[g] = self.let_go(g, s);
            }
        }
        self.active = guides;
        self.members = members;
        self.renew_interaction(strands);
        self.wet_version = u64::MAX;
    }

    /// Guide `g`'s stored strand ready to join: at rest (zero velocities), its root on the head at rest.
    fn joining(&self, g: usize) -> Strand {
        let mut s = self.strands[g].clone();
        s.state.qdot.fill(0.0);
        let root = &mut s.state.root;
        root.position = self.scene.guides[g].state.root.position;
        root.velocity = Vector3::zeros();
        root.angular_velocity = Vector3::zeros();
        root.acceleration = Vector3::zeros();
        s
    }

    /// A strand of guide `g` leaving the simulation: velocities zeroed; back to its groomed shape if its tip is
    /// farther than `rest_distance` from the groomed tip (an uncut strand; a cut one keeps its shape).
    fn let_go(&self, g: usize, mut s: Strand) -> Strand {
        s.state.qdot.fill(0.0);
        let guide = &self.scene.guides[g];
        let uncut = s.state.q.len() == guide.state.q.len() && (s.model.length - guide.model.length).abs() < 1e-12;
        if uncut {
            let groomed = guide.reference.last().copied().unwrap_or(guide.state.root.position);
            if (tip(&s) - groomed).norm() > self.params.haptic.rest_distance {
                s.state.q.copy_from(&guide.state.q);
            }
        }
        s
    }

    /// Stage 8 of the step: each simulated strand's tip speed over the step `dt` (s), the leaving strands'
    /// rest, and the display weights (fading in and out over `blend_time`).
    pub(crate) fn track_active(&mut self, dt: f64) {
        let h = self.params.haptic;
        let fade = dt / h.blend_time;
        self.max_tip_speed = 0.0;
        for (m, s) in self.members.iter_mut().zip(&self.interaction.strands) {
            let x = tip(s);
            m.tip_speed = m.tip.map_or(0.0, |p| (x - p).norm() / dt);
            m.tip = Some(x);
            if m.tip_speed.is_finite() {
                self.max_tip_speed = self.max_tip_speed.max(m.tip_speed);
            }
            match m.phase {
                Phase::Chosen => m.weight = (m.weight + fade).min(1.0),
                Phase::Relaxing { since, still } => {
                    let (since, still) = (since + dt, if m.tip_speed < h.rest_speed { still + dt } else { 0.0 });
                    m.weight = (m.weight + fade).min(1.0);
                    m.phase = if still >= h.rest_time || since >= h.max_relax_time { Phase::Fading } else { Phase::Relaxing { since, still } };
                }
                Phase::Fading => m.weight = (m.weight - fade).max(0.0),
            }
        }
    }

    /// The active strands' roots move with the head, which is rigid (at the pose `HapticCore::head`): each
    /// root is held at its guide's root on the scalp, moving and turning with the head. Not with the lattice: the tool's own
    /// repelling obstacle deforms the lattice, and roots following it sank into the head and were kicked out.
    pub(crate) fn roots_follow(&mut self, dt: f64) {
        let head = self.head;
        for (slot, &g) in self.active.iter().enumerate() {
            let groomed = &self.scene.guides[g].state.root;
            let target = head * nalgebra::Point3::from(groomed.position);
            let turn = head.rotation.to_rotation_matrix().into_inner() * groomed.rotation;
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
