//! The global layer (about 100 Hz): the lattice carrying the whole hairstyle, with the body as a position
//! constraint and the tool as a repelling metaball obstacle; the nozzle tools' jet and wetness
//! ([`nozzle`]); the scissors' cuts of the render strands and the falling cut clusters ([`cut`]).
//!
//! One step of [`GlobalCore::step`], in order:
//! 0. **Head**: the input's head pose (`ToolInput::head`) becomes the lattice's and the body's.
//! 1. **Cuts**: a new scissors close (`ToolInput::cuts` went up) cuts the render strands now, or queues the
//!    cut for a worker thread ([`GlobalCore::defer_cuts`]).
//! 2. **Dryer jet**: the held dryer's drag on the hair each lattice node carries, as external node forces
//!    ([`GlobalCore::blow`]; `tools::dryer::HairDryer::hair_force`, quadratic in the air speed).
//! 3. **Lattice**: the lattice step with a solid tool (clip, scissors: `ToolKind::lattice_obstacle`) as an
//!    obstacle and the jet's forces (`LatticeModel::step_with_forces`). The comb and the brush are none (the
//!    lattice's 5 cm cells cannot resolve their teeth, which the hair passes between), nor are the nozzles
//!    (their tool point is where they aim); the local strands carry their touch.
//! 4. **Body**: nodes that started outside the body are pushed back out of it ([`body`]).
//! 5. **Recovery**: a non-finite lattice is put back to rest (and reported).
//! 6. **Wetness**: the held sprayer or dryer wets or dries the guides in its cone ([`GlobalCore::moisten`]).
//! 7. **Clusters**: the falling cut pieces step.
//! 8. **Snapshot**: the new version is published.

mod body;
pub mod cut;
mod nozzle;

pub use cut::{CutJob, CutReport, CutResult};

use crate::params::{GlobalParams, SessionParams};
use crate::scene::Scene;
use crate::snapshot::LatticeSnapshot;
use crate::tool::{tool_metaballs, ToolInput};
use hairstyle::cut::Blade;
use lattice::cluster::{ClusterParams, ClusterSet};
use lattice::lattice::{LatticeModel, LatticeState, LatticeWorkspace};
use nalgebra::{Isometry3, Point3, Vector3};
use std::sync::Arc;
use std::time::Instant;
use tools::dryer::{HairDrag, HairDryer};
use tools::sprayer::Sprayer;
use tools::wetness::WetnessField;

/// The global layer's state and step, shared by the live thread and [`replay`]: the lattice (with the body
/// as a position constraint and the tool as a repelling metaball obstacle), the dryer's jet on the lattice,
/// the wetness field of the guides (sprayer and dryer), the scissors' cuts of the render strands and the
/// falling cut clusters.
pub struct GlobalCore {
    pub(crate) scene: Arc<Scene>,
    /// The scene's lattice with the obstacle's attraction switched off (the tool repels only).
    pub(crate) model: LatticeModel,
    pub(crate) state: LatticeState,
    /// The lattice step's cached factorisation and scratch (not state).
    pub(crate) workspace: LatticeWorkspace,
    pub(crate) version: u64,
    pub(crate) head: Isometry3<f64>,
    /// Nodes outside the body at rest: only these are pushed out of it.
    pub(crate) outside: Vec<bool>,
    /// The nozzle tools' and the scissors' settings (cone, air speed, rates, blade radius).
    pub(crate) tools: ToolSettings,
    /// Air and hair properties of the jet's drag on the hair (the render hair's diameter).
    pub(crate) drag: HairDrag,
    /// The jet's force on each node in the last step, N (empty: none).
    pub(crate) forces: Vec<Vector3<f64>>,
    /// Magnitude of the total jet force on the lattice in the last step, N.
    pub(crate) blow_force: f64,
    /// Wetness per guide and segment.
    pub(crate) wet: WetnessField,
    /// Kept length of each render strand in vertex units (V - 1: uncut).
    pub(crate) kept_len: Vec<f64>,
    pub(crate) kept: Arc<Vec<u16>>,
    pub(crate) kept_version: u64,
    pub(crate) cuts: u64,
    /// The render hair's linear density, kg/m.
    pub(crate) lambda: f64,
    /// The global step's constants.
    pub(crate) params: GlobalParams,
    /// Each tool's shape (by wire id), built once.
    pub(crate) shapes: Vec<tools::shape::ToolShape>,
    pub(crate) clusters: Vec<ClusterSet>,
    pub(crate) cluster_params: ClusterParams,
    /// The last cut's report.
    pub last_cut: Option<CutReport>,
    pub(crate) deferred: bool,
    pub(crate) pending: Vec<Blade>,
    /// Wetness or cluster updates that failed (state kept).
    pub failed: u64,
}

impl GlobalCore {
    /// At rest, with the dryer's and sprayer's rates of `params`.
    pub fn new(scene: Arc<Scene>, params: &SessionParams) -> Self {
        let head = Isometry3::identity();
        let mut model = scene.lattice.clone();
        model.params.metaball.attraction_stiffness = 0.0;
        let state = model.rest_state(&head);
        let t = model.params.metaball.threshold;
        let outside = model.rest.iter().map(|p| !scene.head.inside(&(head * p), t)).collect();
        let tools = ToolSettings {
            sprayer: Sprayer { wetting_rate: params.wetting_rate, ..Sprayer::default() },
            dryer: HairDryer { drying_rate: params.drying_rate, ..HairDryer::default() },
            blade_radius: params.global.blade_radius,
        };
        let segs: Vec<usize> = scene.guides.iter().map(|g| g.model.segments).collect();
        let rh = &scene.render;
        let v = rh.vertices_per_strand;
        let g0 = scene.guides.first();
        let lambda = g0.map_or(6.5e-5, |g| g.model.linear_density());
        let drag = g0.map_or_else(HairDrag::default, |g| HairDrag::for_section_area(g.model.section.area()));
        Self {
            model, state, workspace: LatticeWorkspace::default(), version: 0, head, outside, tools, drag, forces: Vec::new(), blow_force: 0.0, wet: WetnessField::dry(&segs),
            kept_len: vec![v.saturating_sub(1) as f64; rh.strands()], kept: Arc::new(vec![v as u16; rh.strands()]), kept_version: 0, cuts: 0,
            lambda, params: params.global, shapes: crate::tool::Tool::ALL.iter().map(|t| t.shape(params.global.nozzle_standoff)).collect(), clusters: Vec::new(), cluster_params: ClusterParams::default(), last_cut: None, deferred: false, pending: Vec::new(), failed: 0, scene,
        }
    }
    /// Back to rest: lattice, wetness, cuts and falling clusters (keeps counting versions and cuts).
    pub fn reset(&mut self) {
        self.state = self.model.rest_state(&self.head);
        self.wet.values.iter_mut().flatten().for_each(|w| *w = 0.0);
        let v = self.scene.render.vertices_per_strand;
        self.kept_len.iter_mut().for_each(|k| *k = v.saturating_sub(1) as f64);
        self.kept = Arc::new(vec![v as u16; self.kept_len.len()]);
        self.kept_version += 1;
        self.clusters.clear();
        self.pending.clear();
    }
    /// Sets every guide segment's wetness to `w` (clamped to [0, 1]; NaN gives 0).
    pub fn set_wetness(&mut self, w: f64) {
        let w = if w.is_finite() { w.clamp(0.0, 1.0) } else { 0.0 };
        self.wet.values.iter_mut().flatten().for_each(|x| *x = w);
    }
    /// The wetness field (per guide and segment).
    pub fn wetness(&self) -> &WetnessField {
        &self.wet
    }
    /// Node positions, m.
    pub fn positions(&self) -> &[Point3<f64>] {
        &self.state.positions
    }
    /// Total mass of the falling clusters, kg.
    pub fn cluster_mass(&self) -> f64 {
        self.clusters.iter().map(|c| c.total_mass()).sum()
    }
    /// Kinetic energy of the falling clusters, J.
    pub fn cluster_energy(&self) -> f64 {
        self.clusters.iter().map(|c| c.kinetic_energy()).sum()
    }
    /// Falling clusters (of all cuts still falling).
    pub fn cluster_count(&self) -> usize {
        self.clusters.iter().map(|c| c.clusters.len()).sum()
    }
    /// Every cut piece's points now (m, head frame), pushed out of the body and above the floor
    /// (`ClusterSet::piece_points`).
    pub fn piece_points(&self) -> Vec<Vec<Point3<f64>>> {
        self.clusters.iter().flat_map(|c| c.piece_points(&self.cluster_params, &self.scene.head)).collect()
    }
    /// Height of the floor the clusters land on, m.
    pub fn floor(&self) -> f64 {
        self.cluster_params.floor
    }
    /// Kept length of each render strand in vertex units (V - 1: uncut).
    pub fn kept_lengths(&self) -> &[f64] {
        &self.kept_len
    }
    /// Linear density of the render hair, kg/m.
    pub fn linear_density(&self) -> f64 {
        self.lambda
    }
    /// The nozzle tools' and the scissors' settings now.
    pub fn tools(&self) -> &ToolSettings {
        &self.tools
    }
    /// Sets the nozzle tools' and the scissors' settings (the cones' axes and apexes are taken from each
    /// step's [`ToolInput`]; their half-angles and ranges, the air speed and the rates from here).
    pub fn set_tools(&mut self, tools: ToolSettings) {
        self.tools = tools;
    }
    /// Sets the height of the floor the falling clusters land on, m (head frame).
    pub fn set_floor(&mut self, z: f64) {
        self.cluster_params.floor = z;
    }
    /// Magnitude of the total jet force on the lattice in the last step, N (0 when the dryer is not blowing).
    pub fn blow_force(&self) -> f64 {
        self.blow_force
    }
    /// The scene this core steps.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }
    /// The head pose now (head frame to world).
    pub fn head_pose(&self) -> Isometry3<f64> {
        self.head
    }
    /// Moves the head to `head` (head frame to world) for the next steps: the lattice's attachment follows
    /// it and the body pushes the nodes out where it now is. A pose with a non-finite part is ignored
    /// (returns false).
    pub fn set_head_pose(&mut self, head: Isometry3<f64>) -> bool {
        let ok = crate::command::is_finite_pose(&head);
        if ok {
            self.head = head;
        }
        ok
    }
    /// The lattice model this core steps (the scene's, with the tool's attraction off).
    pub fn model(&self) -> &LatticeModel {
        &self.model
    }


    /// One global step of `dt` s with the tool `input`; returns the new snapshot. A non-finite lattice is
    /// detected and put back to rest (reported by the flag).
    pub fn step(&mut self, dt: f64, input: &ToolInput) -> (LatticeSnapshot, bool) {
        let t0 = Instant::now();
        if input.head != self.head {
            self.set_head_pose(input.head);
        }
        if input.cuts > self.cuts {
            self.cuts = input.cuts;
            if input.present {
                let blade = input.blade(self.tools.blade_radius);
                if self.deferred {
                    self.pending.push(blade);
                } else {
                    self.cut(&blade);
                }
            }
        }
        self.blow(input);
        let shape = &self.shapes[input.tool as usize];
        let obstacle = (input.present && shape.kind.lattice_obstacle()).then(|| tool_metaballs(shape, &input.position, &input.rotation, &self.params));
        if self.model.step_with_forces(&mut self.state, &mut self.workspace, dt, &self.head, obstacle.as_ref(), &self.forces).is_err() {
            // A non-finite jet force (never expected): the step without it, counted.
            self.failed += 1;
            self.model.step(&mut self.state, &mut self.workspace, dt, &self.head, obstacle.as_ref());
        }
        self.push_out_of_body();
        let bad = self.state.positions.iter().any(|p| !p.coords.iter().all(|x| x.is_finite()));
        if bad {
            self.state = self.model.rest_state(&self.head);
        }
        self.moisten(input, dt);
        for c in self.clusters.iter_mut() {
            if c.step(&self.cluster_params, &self.scene.head, dt).is_err() {
                self.failed += 1;
            }
        }
        self.version += 1;
        let mut snap = self.snapshot();
        snap.step_seconds = t0.elapsed().as_secs_f64();
        (snap, bad)
    }

    /// The current snapshot.
    pub fn snapshot(&self) -> LatticeSnapshot {
        let wetness = (0..self.wet.values.len()).map(|g| self.wet.strand_mean(g) as f32).collect();
        let chains = self.clusters.iter().flat_map(|c| c.clusters.iter()).flat_map(|c| c.guides.iter())
            .map(|ch| ch.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect()).collect();
        LatticeSnapshot { version: self.version, positions: self.state.positions.clone(), step_seconds: 0.0, wetness, kept_version: self.kept_version, kept: self.kept.clone(), chains, head: self.head }
    }

    /// Guide segment centres now (on the guides' references carried by the head and the lattice,
    /// `Scene::guide_points`), m.
    pub(crate) fn centres_now(&self) -> Vec<Vec<Vector3<f64>>> {
        (0..self.scene.guides.len()).map(|g| segment_centres(&self.scene.guide_points(&self.state.positions, &self.head, g), self.scene.guides[g].model.segments)).collect()
    }
}

/// The centres of `n` even segments of the polyline of even samples `r` (linear between samples), m.
fn segment_centres(r: &[Vector3<f64>], n: usize) -> Vec<Vector3<f64>> {
    (0..n).map(|k| strand::samples::lerp(r, (k as f64 + 0.5) / n as f64)).collect()
}

/// The nozzle tools' and the scissors' settings the global layer uses (what a viewer's settings or a
/// scenario's action sets; the pose comes with each step's [`ToolInput`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolSettings {
    /// The hair dryer: cone half-angle (rad) and range (m), air speed (m/s), drying rate (1/s). Default
    /// `HairDryer::default()` with `SessionParams::drying_rate`.
    pub dryer: HairDryer,
    /// The water sprayer: cone half-angle (rad) and range (m), wetting rate (1/s). Default
    /// `Sprayer::default()` with `SessionParams::wetting_rate`.
    pub sprayer: Sprayer,
    /// Radius of the disk the scissors' blades sweep, m. Default `GlobalParams::blade_radius` (0.04).
    pub blade_radius: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ffd_map;
    use crate::testing::{small_scene, test_rot};
    use crate::tool::Tool;

    #[test]
    fn a_solid_tool_pushes_the_lattice_and_does_not_drag_it() {
        // Two lattices side by side, one with a clip (a solid tool) held still in the hair behind the head, on a
        // lattice node. Relative to the free one: every node inside the clip's surface at the free position (its
        // metaball field >= 0.25) ends where the clip's field is lower (pushed out, never pulled in); the whole
        // lattice moves less than 5 cm (the node the clip sits on leaves its surface, 2.2 cm from the jaws:
        // measured 3.8 cm; the lost helper's attraction dragged hair 0.37 m); and 2 s after the clip leaves, the
        // largest difference is under a fifth of what it was (the hair goes back).
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut free, mut pushed) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        // On the lattice node nearest a point behind the head (the clip is smaller than a cell).
        let behind = Vector3::new(0.0, -0.13, 0.0);
        let tool = free.positions().iter().map(|x| x.coords).min_by(|a, b| (a - behind).norm().total_cmp(&(b - behind).norm())).unwrap();
        let input = ToolInput { tool: Tool::Clip, present: true, position: tool, rotation: test_rot(), pressed: false, cuts: 0, ..ToolInput::default() };
        let balls = tool_metaballs(&Tool::Clip.shape(0.15), &tool, &test_rot(), &GlobalParams::default());
        for _ in 0..30 {
            free.step(0.01, &ToolInput::default());
            pushed.step(0.01, &input);
        }
        let (mut touched, mut most) = (0, 0.0f64);
        for (a, b) in pushed.positions().iter().zip(free.positions()) {
            most = most.max((a - b).norm());
            let (fa, fb) = (balls.field(a), balls.field(b));
            if fb >= 0.25 {
                touched += 1;
                assert!(fa < fb, "a touched node is pushed out of the clip: field {fb} -> {fa}");
            }
        }
        eprintln!("{touched} nodes touched, largest difference {most} m");
        assert!(touched >= 1 && most > 2e-3, "the clip pushes the hair: {touched} nodes, {most} m");
        assert!(most < 0.05, "no drag: {most} m");
        for _ in 0..200 {
            free.step(0.01, &ToolInput::default());
            pushed.step(0.01, &ToolInput::default());
        }
        let after = pushed.positions().iter().zip(free.positions()).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        eprintln!("largest difference {after} m 2 s after the clip left");
        assert!(after < 0.2 * most, "the hair goes back: {after} m vs {most} m");
    }

    #[test]
    fn a_comb_passes_through_the_hair_volume() {
        // Issue 12: a comb drawn slowly (2 cm/s, 10 cm down the back of the head) leaves the lattice where a free
        // one is, to 1e-12 m (bit for bit in fact): its teeth are no obstacle (as one, with a 2 cm margin, the failing browser
        // stroke's comb at 1.8 mm/s ploughed the hair volume 8.4 cm ahead of it).
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut free, mut combed) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        for n in 0..500 {
            let input = ToolInput { tool: Tool::Comb, present: true, position: Vector3::new(0.0, -0.12, 0.04 - 0.02 * n as f64 * 0.01), rotation: test_rot(), ..ToolInput::default() };
            free.step(0.01, &ToolInput::default());
            combed.step(0.01, &input);
        }
        let ploughed = combed.positions().iter().zip(free.positions()).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        assert!(ploughed < 1e-12, "the comb's teeth are no obstacle: {ploughed} m");
    }

    #[test]
    fn the_hairstyle_keeps_its_groomed_shape_at_rest() {
        // Issue 14: at rest, 5 s after the start, no render vertex (the lattice's FFD of every render strand's
        // rest vertex) has moved more than 2 mm from the groomed shape: the soft lattice is sag-free.
        let scene = small_scene();
        let mut core = GlobalCore::new(scene.clone(), &SessionParams::default());
        for _ in 0..500 {
            core.step(0.01, &ToolInput::default());
        }
        let worst = scene.render.positions.iter().map(|p| {
            let q = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            (ffd_map(&scene.lattice.ffd, core.positions(), &q) - q).norm()
        }).fold(0.0, f64::max);
        eprintln!("largest render-vertex drift after 5 s at rest: {worst:.2e} m");
        assert!(worst <= 2e-3, "{worst} m");
    }

    #[test]
    fn the_dryer_jet_moves_the_soft_lattice_and_it_falls_back() {
        // The same dryer held at the side of the hair in two sessions, blowing in one of them for 2 s: the jet
        // moves the lattice by >= 5 mm more than the nozzle's presence alone, and 4.3 s after it stops the two
        // lattices are within 1 mm of each other. Measured 2026-11-24 with the stable grooms (issue 12; the side
        // hair hangs further out, nearer the nozzle): largest difference 6.5 cm, then 3.9 mm 2.3 s after,
        // 1.5 mm 3.3 s after, 0.58 mm 4.3 s after, 4e-6 m 8.3 s after (it falls back; time constant ~0.8 s).
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut blown, mut held) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        let rot = nalgebra::Rotation3::new(Vector3::new(2.2214415, 0.0, 2.2214415)).into_inner();
        let mut input = ToolInput { tool: Tool::Dryer, present: true, position: Vector3::new(0.13, 0.0, 0.0), rotation: rot, pressed: true, cuts: 0, ..ToolInput::default() };
        let gap = |a: &GlobalCore, b: &GlobalCore| a.positions().iter().zip(b.positions()).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
        let mut most = 0.0f64;
        for k in 0..630 {
            input.pressed = k < 200;
            blown.step(0.01, &input);
            held.step(0.01, &ToolInput { pressed: false, ..input });
            most = most.max(gap(&blown, &held));
        }
        let after = gap(&blown, &held);
        eprintln!("jet: largest difference {most:.4} m, 4.3 s after {after:.2e} m");
        assert!(most >= 5e-3, "the jet moves the lattice: {most} m");
        assert!(after <= 1e-3, "it falls back: {after} m");
    }
}
