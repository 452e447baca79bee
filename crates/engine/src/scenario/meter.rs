//! What a live run measures besides the force ([`Meter`]): the hair's displacement against its settled shape,
//! the tool in the hair and moving, the tips' speed, the hand-overs and the hair's depth in the body; and how
//! ([`ContinuityParams`]).

use crate::lockstep::Lockstep;
use crate::scene::Scene;
use nalgebra::{Point3, Vector3};
use std::sync::Arc;

/// How the continuity metrics of a live run are measured ([`LiveSummary`]'s `in_hair_*`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuityParams {
    /// The tool is in the hair in a step when one of its capsules comes within this distance of a guide
    /// point's settled position, m. Default 0.005.
    pub in_hair_distance: f64,
    /// A force above this is felt, N. Default 0.005 (issue 12's acceptance: 5 mN).
    pub force_floor: f64,
    /// The tool moves in a step when faster than this, m/s (the stroke's speed is taken over those steps).
    /// Default 0.01.
    pub moving_speed: f64,
}

impl Default for ContinuityParams {
    fn default() -> Self {
        Self { in_hair_distance: 0.005, force_floor: 0.005, moving_speed: 0.01 }
    }
}

/// Guide point displacements: every guide's samples as the viewer shows them (reference through the
/// lattice, plus the local strand's displacement for the active guides, faded in, and the handed-over guides' offsets), against their
/// settled positions; and, each traced haptic step, whether the tool is in the hair and the simulated
/// strands' fastest tip.
pub(crate) struct Meter {
    scene: Arc<Scene>,
    settled: Vec<Vector3<f64>>,
    params: ContinuityParams,
    /// Largest distance over the run, m.
    pub max: f64,
    /// At the last measure, m.
    pub last: f64,
    /// Largest distance at the measures while the tool is in the hair (the stroke), m.
    pub stroke_max: f64,
    /// Each traced step: the tool in the hair.
    pub in_hair: Vec<bool>,
    /// The tool's path (its proxy's) over the steps with the tool in the hair (a step counts from the
    /// previous step's position), m.
    pub in_hair_path: f64,
    /// Each traced step: the tool in the hair and moving faster than `ContinuityParams::moving_speed` (a
    /// stroke's step); and the tool's path over those steps, m.
    pub moving: Vec<bool>,
    pub moving_path: f64,
    /// The tool's proxy at the last traced step, m.
    last_tool: Option<Vector3<f64>>,
    /// Fastest strand tip over the run, m/s.
    pub max_tip_speed: f64,
    /// The haptic layer's largest hand-over so far (`HapticCore::handover_max`), m.
    pub handover: f64,
    /// Strands let go back in place so far (`HapticCore::handovers`).
    pub handovers: u64,
    /// The largest hand-over of a strand let go before it was back in place (`HapticCore::early_handovers`), m.
    pub early_handover: f64,
    /// How many strands were let go before they were back in place.
    pub early_handovers: u64,
    /// The largest change of any guide point drawn across a hand-over to the global layer, m: a simulated
    /// strand's shown displacement from its carried place (the viewer's snapshot) the step before it was let go,
    /// against the step it was (early hand-overs included).
    pub handover_change: f64,
    /// The simulated guides' shown displacements after the last traced step (guide, per sample, m).
    simulated: Vec<(usize, Vec<Vector3<f64>>)>,
    /// Deepest sampled render vertex inside the body at a measure as the viewer shows it (the lattice's FFD,
    /// then the push-out out of the body, `MetaballSet::push_out` with `PUSH_OUT_SKIN`), m; 0 if none.
    pub max_depth: f64,
    /// The same before the push-out (the FFD alone), m.
    pub max_depth_raw: f64,
}

/// Every this many render strands one is sampled for the depth inside the body ([`Meter::max_depth`]).
const DEPTH_SAMPLE_EVERY: usize = 25;

impl Meter {
    pub(crate) fn new(scene: &Arc<Scene>) -> Self {
        Self { scene: scene.clone(), settled: Vec::new(), params: ContinuityParams::default(), max: 0.0, last: 0.0, stroke_max: 0.0, in_hair: Vec::new(), in_hair_path: 0.0, moving: Vec::new(), moving_path: 0.0, last_tool: None, max_tip_speed: 0.0, handover: 0.0, handovers: 0, early_handover: 0.0, early_handovers: 0, handover_change: 0.0, simulated: Vec::new(), max_depth: 0.0, max_depth_raw: 0.0 }
    }
    /// Guide points as shown, in the head frame (relative to the head), m.
    pub(crate) fn points(&self, ls: &Lockstep) -> Vec<Vector3<f64>> {
        let s = &self.scene;
        let n = s.samples();
        let head = ls.lattice.head;
        let inv = head.inverse();
        let mut pts: Vec<Vector3<f64>> = (0..s.guides.len()).flat_map(|g| s.guide_points(&ls.lattice.positions, &head, g)).collect();
        let mut snap = crate::snapshot::HapticSnapshot::default();
        ls.haptic.snapshot(&ls.lattice, ls.dt, &mut snap);
        for (a, &g) in snap.active.iter().enumerate() {
            for k in 0..n {
                pts[g as usize * n + k] += snap.displacement[a * n + k];
            }
        }
        pts.iter().map(|p| (inv * Point3::from(*p)).coords).collect()
    }
    /// Deepest sampled render vertex inside the body now (head frame; carried by the head and the lattice,
    /// `Scene::render_vertex`), as shown (after the viewer's push-out) and before it, m (0: none).
    pub(crate) fn depth(&self, ls: &Lockstep) -> (f64, f64) {
        let s = &self.scene;
        let t = s.lattice.params.metaball.threshold;
        let head = ls.lattice.head;
        let inv = head.inverse();
        let depth = |x: &Point3<f64>| {
            let (f, g) = s.head.field_and_gradient(x);
            let gn = g.norm();
            if f > t && gn > 0.0 { (f - t) / gn } else { 0.0 }
        };
        let (mut shown, mut raw) = (0.0f64, 0.0f64);
        for strand in (0..s.render.strands()).step_by(DEPTH_SAMPLE_EVERY) {
            for p in s.render_strand(&ls.lattice.positions, &head, strand) {
                let x = inv * Point3::from(p);
                raw = raw.max(depth(&x));
                shown = shown.max(depth(&s.head.push_out(&x, t, lattice::metaball::PUSH_OUT_SKIN)));
            }
        }
        (shown, raw)
    }
    pub(crate) fn settle(&mut self, ls: &Lockstep) {
        self.settled = self.points(ls);
    }
    /// A force above this is felt, N.
    pub(crate) fn force_floor(&self) -> f64 {
        self.params.force_floor
    }
    pub(crate) fn measure(&mut self, ls: &Lockstep) {
        if self.settled.is_empty() {
            return;
        }
        let d = self.points(ls).iter().zip(&self.settled).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        self.max = self.max.max(d);
        let (shown, raw) = self.depth(ls);
        self.max_depth = self.max_depth.max(shown);
        self.max_depth_raw = self.max_depth_raw.max(raw);
        if self.in_hair.last() == Some(&true) {
            self.stroke_max = self.stroke_max.max(d);
        }
        self.last = d;
    }
    /// After each traced haptic step: the tool in the hair (a capsule of its shape within `in_hair_distance`
    /// of a settled guide point), the fastest strand tip.
    pub(crate) fn step(&mut self, ls: &Lockstep) {
        let input = ls.haptic.tool_input();
        let shape = &ls.haptic.model.shapes[input.tool as usize];
        let reach = shape.capsules.iter().flat_map(|c| [Vector3::from(c.a).norm(), Vector3::from(c.b).norm()].map(|r| r + c.radius)).fold(0.0, f64::max) + self.params.in_hair_distance;
        let inside = input.present && self.settled.iter().any(|p| {
            let d = p - input.position;
            if d.norm() > reach {
                return false;
            }
            let q = input.rotation.transpose() * d;
            shape.capsules.iter().any(|c| tools::geometry::point_segment_distance(&q, &Vector3::from(c.a), &Vector3::from(c.b)) - c.radius < self.params.in_hair_distance)
        });
        self.in_hair.push(inside);
        let mut moving = false;
        if let (true, Some(last)) = (inside, self.last_tool) {
            let step = (input.position - last).norm();
            self.in_hair_path += step;
            if step > self.params.moving_speed * ls.dt {
                moving = true;
                self.moving_path += step;
            }
        }
        self.moving.push(moving);
        self.last_tool = input.present.then_some(input.position);
        self.max_tip_speed = self.max_tip_speed.max(ls.haptic.max_tip_speed());
        self.handover = ls.haptic.handover_max();
        self.handovers = ls.haptic.handovers();
        (self.early_handover, self.early_handovers) = ls.haptic.early_handovers();
        self.hand_overs(ls);
    }
    /// The hand-overs of the last step: the change of each guide point drawn of the guides that were simulated
    /// after the step before and no longer are ([`Meter::handover_change`]); then the simulated guides' shown
    /// displacements now. A snapshot is taken only while strands are simulated.
    fn hand_overs(&mut self, ls: &Lockstep) {
        let simulated = ls.haptic.active();
        if simulated.is_empty() && self.simulated.is_empty() {
            return;
        }
        let n = self.scene.samples();
        let mut snap = crate::snapshot::HapticSnapshot::default();
        ls.haptic.snapshot(&ls.lattice, ls.dt, &mut snap);
        let shown = |g: usize| snap.active.iter().position(|&a| a as usize == g).map(|i| &snap.displacement[i * n..(i + 1) * n]);
        for (g, before) in &self.simulated {
            if ls.haptic.active().contains(g) {
                continue;
            }
            let zeros = vec![Vector3::zeros(); n];
            let now = shown(*g).unwrap_or(&zeros);
            let change = before.iter().zip(now).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            self.handover_change = self.handover_change.max(change);
        }
        self.simulated = simulated.iter().filter_map(|&g| shown(g).map(|d| (g, d.to_vec()))).collect();
    }
}
