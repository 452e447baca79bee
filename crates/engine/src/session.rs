//! The live session: both layers at their own rates on their own threads, coupled both ways.
//!
//! - **Global thread** (about 100 Hz, [`GlobalCore`]): steps the lattice particle system and publishes each
//!   snapshot of its node positions, with a version number, through wait-free triple buffers (one to the
//!   haptic thread, one to the viewer side). The viewer does the FFD of the render strands on the GPU.
//! - **Haptic thread** (1 kHz, [`HapticCore`] inside a [`HapticLoop`]): reads the browser's mouse through a
//!   [`VirtualDevice`], runs the virtual coupling, and steps the *local strands*: the few guide strands
//!   nearest the tool (Super-Helices). Their roots follow the lattice (FFD of the root's rest position, so
//!   head and lattice motion move them); their displacement from their settled reference shape is published
//!   for the viewer, which adds it to the render strands bound to each guide (so what the tool does is seen
//!   on the whole hairstyle). Strand states persist when they leave the active set (styling persists).
//! - Nothing on the haptic path takes a lock: lattice snapshots come in and haptic snapshots go out through
//!   triple buffers, viewer commands through a non-blocking channel.
//!
//! Replay: the haptic step is a pure function of (its state, the device reading, the lattice snapshot it
//! read, the commands applied before it). A [`Record`] keeps, per haptic step, the reading and the lattice
//! version used; [`replay`] re-runs the global and haptic cores in lockstep on one thread and gives the same
//! forces bit for bit.

use crate::record::{Record, StepRecord};
use haptics::backends::{virtual_device, VirtualDevice, VirtualHandle};
use haptics::coupling::{Coupling, CouplingParams};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading};
use haptics::haptic_loop::{HapticLoop, LoopStats};
use lattice::ffd::FfdLattice;
use lattice::lattice::{LatticeModel, LatticeParams, LatticeState};
use lattice::metaball::MetaballSet;
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use strand::{HairType, Strand, StrandModel};
use tools::contact::ToolPose;
use tools::interaction::{ForceModel, LocalInteraction};
use tools::shape::ToolShape;
use triple_buffer::{triple_buffer, Output};

/// Errors of a session.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// A parameter is out of range (names it).
    #[error("invalid session parameter: {0}")]
    Param(String),
    /// Building the scene failed.
    #[error("cannot build the scene: {0}")]
    Scene(String),
    /// A thread could not be started.
    #[error("cannot start the session: {0}")]
    Start(String),
}

// ---------------------------------------------------------------------------------------------------------
// Tools and commands
// ---------------------------------------------------------------------------------------------------------

/// The tools of the toolbar, with their wire ids (docs/protocol.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Tool {
    /// Comb (teeth drawn through the hair).
    Comb = 0,
    /// Brush (bristle pad; twists strands).
    Brush = 1,
    /// Scissors: cuts the strands the blades close on (while the primary button is held).
    Scissors = 2,
    /// Hair dryer: lowers wetness in its cone.
    Dryer = 3,
    /// Water sprayer: raises wetness in its cone.
    Sprayer = 4,
    /// Clip: pins the strand point nearest its jaws while the primary button is held.
    Clip = 5,
}

impl Tool {
    /// All tools in wire order.
    pub const ALL: [Tool; 6] = [Tool::Comb, Tool::Brush, Tool::Scissors, Tool::Dryer, Tool::Sprayer, Tool::Clip];
    /// The tool with wire id `id`, if any.
    pub fn from_id(id: u8) -> Option<Tool> {
        Self::ALL.get(id as usize).copied()
    }
    /// The tool's shape (capsules and spheres, tool frame, m).
    pub fn shape(self) -> ToolShape {
        let builtin = |n: &str| ToolShape::builtin(n).expect("built-in shapes parse (tested in tools)");
        let inline = |t: &str| ToolShape::from_toml(t).expect("inline shapes parse (tested below)");
        match self {
            Tool::Comb => builtin("comb"),
            Tool::Brush => builtin("brush"),
            Tool::Clip => builtin("clip"),
            // Closed blades: two thin capsules along the tool's x axis.
            Tool::Scissors => inline(SCISSORS_TOML),
            // Nozzles: a sphere at the tool origin (it pushes hair like a finger).
            Tool::Dryer => inline(&NOZZLE_TOML.replace("NAME", "dryer")),
            Tool::Sprayer => inline(&NOZZLE_TOML.replace("NAME", "sprayer")),
        }
    }
}

const SCISSORS_TOML: &str = "name = \"scissors\"\nkind = \"scissors\"\n[[capsule]]\na = [-0.04, 0.0, 0.0]\nb = [0.04, 0.0, 0.0]\nradius = 0.0015\n";
const NOZZLE_TOML: &str = "name = \"NAME\"\nkind = \"NAME\"\n[[sphere]]\ncenter = [0.0, 0.0, 0.0]\nradius = 0.012\n";

/// A command from the viewer, applied by the haptic thread before its next step (and recorded).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Select a tool.
    SelectTool(Tool),
    /// Hair type (index into [`HairType::ALL`]), curliness in [0, 1], combing ease in [0, 1].
    SetHair {
        /// Index into [`HairType::ALL`].
        hair_type: u8,
        /// Curliness in [0, 1] (0 straight, 1 tight curls of about 1 cm radius).
        curliness: f64,
        /// Combing ease in [0, 1]: scales the friction coefficient by (1 - 0.8 ease).
        combing_ease: f64,
    },
    /// Put every strand, the lattice, the cuts and the wetness back to the start.
    Reset,
}

// ---------------------------------------------------------------------------------------------------------
// Scene (model: immutable)
// ---------------------------------------------------------------------------------------------------------

/// A triangle mesh for display, f32 (head frame, m).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, m.
    pub positions: Vec<[f32; 3]>,
    /// Triangles (three vertex indices each).
    pub indices: Vec<u32>,
}

/// One guide strand: a Super-Helix rooted on the scalp in its groomed state, and that shape.
#[derive(Debug, Clone)]
pub struct Guide {
    /// The strand model (rest coordinates: the sag-free rest of the groomed state).
    pub model: StrandModel,
    /// The groomed state (static equilibrium under gravity), head frame.
    pub state: strand::StrandState,
    /// The groomed centreline, [`Scene::samples`] points from root to tip evenly in arc length, head frame,
    /// m. Displacements are measured from this shape mapped through the lattice.
    pub reference: Vec<Vector3<f64>>,
}

/// Options of the built-in scene. Defaults give the README's default scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneOptions {
    /// Number of render strands. Default 100 000.
    pub render_strands: usize,
    /// Vertices per render strand. Default 12.
    pub render_vertices: usize,
    /// Number of guide strands (candidates for the local layer). Default 200.
    pub guides: usize,
    /// Super-Helix segments per guide. Default 8.
    pub segments: usize,
    /// Centreline samples per guide (the displacement field sent to the viewer). Default 16.
    pub samples: usize,
    /// Hair length, m. Default 0.2.
    pub length: f64,
    /// Curliness in [0, 1]. Default 0.
    pub curliness: f64,
    /// Lattice cell size, m. Default 0.05.
    pub cell: f64,
    /// Hair type (a [`HairType`] name). Default "caucasian".
    pub hair_type: String,
    /// Random seed of the hairstyle. Default 1.
    pub seed: u64,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self { render_strands: 100_000, render_vertices: 12, guides: 200, segments: 8, samples: 16, length: 0.2, curliness: 0.0, cell: 0.05, hair_type: "caucasian".into(), seed: 1 }
    }
}

/// Render strands: rest polylines (head frame, f32) bound to the lattice (by the viewer's FFD) and to guides
/// (vertex j of strand i follows the weighted displacement of its guides at the fraction span_i j/(V-1) of
/// their length).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderHair {
    /// Vertices per strand V (the same for every strand).
    pub vertices_per_strand: usize,
    /// Guides each strand follows.
    pub guides_per_strand: usize,
    /// All vertices, strand after strand, m.
    pub positions: Vec<[f32; 3]>,
    /// Guides of each strand (`guides_per_strand` per strand, nearest first).
    pub guide: Vec<u32>,
    /// Their weights (sum 1 per strand).
    pub weight: Vec<f32>,
    /// Fraction of the guides' length each strand spans.
    pub span: Vec<f32>,
}

impl RenderHair {
    /// Number of strands.
    pub fn strands(&self) -> usize {
        self.span.len()
    }
}

/// The scene: head, hair, guides and lattice. Immutable once built; shared by the threads.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Head, neck and shoulders for collisions (head frame).
    pub head: MetaballSet,
    /// Display mesh of the head and body (head frame).
    pub head_mesh: Mesh,
    /// Render strands.
    pub render: RenderHair,
    /// Guide strands.
    pub guides: Vec<Guide>,
    /// Hair type of the guides.
    pub hair_type: HairType,
    /// The lattice (geometry, masses, stiffeners).
    pub lattice: LatticeModel,
}

impl Scene {
    /// The built-in scene: the built-in head (metaballs and display mesh) and a generated hairstyle
    /// (`hairstyle::Hairstyle::generate`), with the lattice around it.
    pub fn builtin(opts: &SceneOptions) -> Result<Scene, SessionError> {
        if opts.samples < 2 || !(opts.cell > 0.0) {
            return Err(SessionError::Param(format!("samples must be >= 2 and cell > 0 m: {opts:?}")));
        }
        let params = hairstyle::HairstyleParams {
            hair_type: opts.hair_type.clone(),
            length: opts.length,
            curliness: opts.curliness,
            guide_count: opts.guides,
            guide_segments: opts.segments,
            render_count: opts.render_strands,
            render_vertices: opts.render_vertices,
            guide_samples: opts.samples.max(16),
            seed: opts.seed,
            ..Default::default()
        };
        let style = hairstyle::Hairstyle::generate(&params).map_err(|e| SessionError::Scene(e.to_string()))?;
        let hair_type = HairType::by_name(&opts.hair_type).ok_or_else(|| SessionError::Param(format!("unknown hair type {:?}", opts.hair_type)))?;
        let mesh = style.head.mesh();
        let head_mesh = Mesh { positions: mesh.positions, indices: mesh.indices };
        let guides: Vec<Guide> = style
            .guides
            .iter()
            .map(|g| {
                let reference = hairstyle::generate::sample_strand(&g.model, &g.state, opts.samples).into_iter().map(|p| p.coords).collect();
                Guide { model: g.model.clone(), state: g.state.clone(), reference }
            })
            .collect();
        let r = &style.render;
        let render = RenderHair { vertices_per_strand: r.vertices_per_strand, guides_per_strand: r.guides_per_strand, positions: r.positions.clone(), guide: r.guide_indices.clone(), weight: r.guide_weights.clone(), span: r.span.clone() };
        // Lattice around the hair and head.
        let (lo, hi) = style.bounds();
        let rad = style.head.params.head_radius;
        let lo = Point3::new(lo.x.min(-rad), lo.y.min(-rad), lo.z.min(-rad));
        let hi = Point3::new(hi.x.max(rad), hi.y.max(rad), hi.z.max(rad));
        let ffd = FfdLattice::enclosing(lo, hi, opts.cell).map_err(|e| SessionError::Scene(e.to_string()))?;
        let hair_mass: f64 = style.guides.first().map_or(0.0, |g| g.model.mass()) * render.strands() as f64;
        let lattice = lattice_for_hair(ffd, &render.positions, hair_mass.max(1e-6), rad)?;
        Ok(Scene { head: style.head.body.clone(), head_mesh, render, guides, hair_type, lattice })
    }

    /// Samples per guide centreline.
    pub fn samples(&self) -> usize {
        self.guides.first().map_or(0, |g| g.reference.len())
    }
}

/// A lattice model whose node masses share `hair_mass` (kg) by the render vertices each node's cell holds
/// (plus a floor of 2 % of the mean), attached fully near the head and more loosely further out.
fn lattice_for_hair(ffd: FfdLattice, positions: &[[f32; 3]], hair_mass: f64, r: f64) -> Result<LatticeModel, SessionError> {
    let n = ffd.node_count();
    let mut count = vec![0.0f64; n];
    for p in positions {
        let q = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let s = (q - ffd.origin) / ffd.h;
        let (i, j, k) = (s.x.round() as usize, s.y.round() as usize, s.z.round() as usize);
        if i < ffd.nx && j < ffd.ny && k < ffd.nz {
            count[ffd.index(i, j, k)] += 1.0;
        }
    }
    let total: f64 = count.iter().sum::<f64>().max(1.0);
    let mean = hair_mass / n as f64;
    let masses: Vec<f64> = count.iter().map(|c| hair_mass * c / total + 0.02 * mean).collect();
    let rest = ffd.rest_positions();
    let attachment: Vec<f64> = rest.iter().map(|p| {
        let d = (p.coords.norm() - r).max(0.0);
        (1.0 - d / (3.0 * r)).clamp(0.35, 1.0)
    }).collect();
    LatticeModel::new(ffd, masses, attachment, LatticeParams::default()).map_err(|e| SessionError::Scene(e.to_string()))
}

// ---------------------------------------------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------------------------------------------

/// Parameters of a live session. Defaults: the README's `coiffure serve`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionParams {
    /// Haptic loop rate, Hz (at most 4000). Default 1000.
    pub haptic_rate_hz: f64,
    /// Global (lattice) step rate, Hz. Default 100.
    pub global_rate_hz: f64,
    /// Most guide strands simulated at once near the tool. Default 12.
    pub max_active: usize,
    /// A guide joins the active set when its settled shape comes within this distance of the tool, m.
    /// Default 0.05.
    pub activation_radius: f64,
    /// Device limits. Default: a Phantom Omni (3.3 N, 300 N/s), also for the mouse, whose force is shown.
    pub profile: DeviceProfile,
    /// Largest speed at which the device point follows the mouse target, m/s (the mouse jumps between events;
    /// the device moves there smoothly). Default 1.0.
    pub follow_speed: f64,
    /// Haptic steps between two snapshots published for the viewer. Default 5 (200 Hz).
    pub publish_every: u64,
    /// Keep a record of the device input for replay. Default false.
    pub record: bool,
    /// Wetness change per second for the dryer (-) and sprayer (+) in their cone, 1/s. Default 0.5.
    pub wetting_rate: f64,
    /// Hairs each simulated guide stands for in the force on the tool (a wisp): the local strands' reaction
    /// is multiplied by it. Dimensionless, >= 1. Default 20.
    pub wisp: f64,
}

impl Default for SessionParams {
    fn default() -> Self {
        Self { haptic_rate_hz: 1000.0, global_rate_hz: 100.0, max_active: 12, activation_radius: 0.05, profile: DeviceProfile::PHANTOM_OMNI, follow_speed: 1.0, publish_every: 5, record: false, wetting_rate: 0.5, wisp: 20.0 }
    }
}

impl SessionParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), SessionError> {
        let p = |m: String| Err(SessionError::Param(m));
        if !(self.haptic_rate_hz > 0.0 && self.haptic_rate_hz <= haptics::haptic_loop::MAX_RATE_HZ) {
            return p(format!("haptic_rate_hz must be in (0, 4000], got {}", self.haptic_rate_hz));
        }
        if !(self.global_rate_hz > 0.0 && self.global_rate_hz <= 1000.0) {
            return p(format!("global_rate_hz must be in (0, 1000], got {}", self.global_rate_hz));
        }
        if self.max_active == 0 {
            return p("max_active must be > 0".into());
        }
        if !(self.activation_radius > 0.0 && self.follow_speed > 0.0 && self.wetting_rate >= 0.0) {
            return p(format!("activation_radius, follow_speed must be > 0 and wetting_rate >= 0: {self:?}"));
        }
        if !(self.wisp >= 1.0 && self.wisp.is_finite()) {
            return p(format!("wisp must be >= 1, got {}", self.wisp));
        }
        if self.publish_every == 0 {
            return p("publish_every must be > 0".into());
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------------------
// Snapshots exchanged between threads
// ---------------------------------------------------------------------------------------------------------

/// A lattice snapshot: node positions (world, m) and the global step that produced it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LatticeSnapshot {
    /// Global steps done (0: the rest state).
    pub version: u64,
    /// Node positions, m.
    pub positions: Vec<Point3<f64>>,
    /// Wall time of the step, s (information).
    pub step_seconds: f64,
}

/// What the haptic thread publishes for the viewer.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HapticSnapshot {
    /// Haptic steps done.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Selected tool (wire id).
    pub tool: u8,
    /// Tool proxy pose (what touches the hair).
    pub tool_position: Vector3<f64>,
    /// Tool rotation (tool frame to world).
    pub tool_rotation: Matrix3<f64>,
    /// Device point (where the mouse put the device), m.
    pub device_position: Vector3<f64>,
    /// Force on the user's hand, N.
    pub force: Vector3<f64>,
    /// Contacts in the last step.
    pub contacts: u32,
    /// Active guides (indices into the scene's guides).
    pub active: Vec<u32>,
    /// Displacement of each active guide's samples from its reference mapped through the lattice, m
    /// (active.len() * samples entries).
    pub displacement: Vec<Vector3<f64>>,
    /// Wetness in [0, 1] per guide.
    pub wetness: Vec<f32>,
    /// Kept length fraction in [0, 1] per guide (1: uncut).
    pub cut: Vec<f32>,
    /// Lattice version the last step used.
    pub lattice_version: u64,
}

// ---------------------------------------------------------------------------------------------------------
// Global core
// ---------------------------------------------------------------------------------------------------------

/// The global layer's state and step, shared by the live thread and [`replay`].
pub struct GlobalCore {
    scene: Arc<Scene>,
    state: LatticeState,
    version: u64,
    head: Isometry3<f64>,
}

impl GlobalCore {
    /// At rest.
    pub fn new(scene: Arc<Scene>) -> Self {
        let head = Isometry3::identity();
        let state = scene.lattice.rest_state(&head);
        Self { scene, state, version: 0, head }
    }
    /// Back to rest (keeps counting versions).
    pub fn reset(&mut self) {
        self.state = self.scene.lattice.rest_state(&self.head);
    }
    /// One lattice step of `dt` s; returns the new snapshot. A non-finite result is detected and the lattice
    /// put back to rest (reported by `recovered`).
    pub fn step(&mut self, dt: f64) -> (LatticeSnapshot, bool) {
        let t0 = Instant::now();
        self.scene.lattice.step(&mut self.state, dt, &self.head, None);
        let bad = self.state.positions.iter().any(|p| !p.coords.iter().all(|x| x.is_finite()));
        if bad {
            self.reset();
        }
        self.version += 1;
        (LatticeSnapshot { version: self.version, positions: self.state.positions.clone(), step_seconds: t0.elapsed().as_secs_f64() }, bad)
    }
    /// The current snapshot.
    pub fn snapshot(&self) -> LatticeSnapshot {
        LatticeSnapshot { version: self.version, positions: self.state.positions.clone(), step_seconds: 0.0 }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Haptic core
// ---------------------------------------------------------------------------------------------------------

/// The haptic layer's state and step (coupling, local strands, wetness, cuts), shared by the live thread
/// and [`replay`].
pub struct HapticCore {
    scene: Arc<Scene>,
    params: SessionParams,
    tool: Tool,
    hair_type: HairType,
    curliness: f64,
    combing_ease: f64,
    coupling: Coupling,
    /// Device point following the mouse target at limited speed, m.
    device: Option<Vector3<f64>>,
    /// Every guide's strand (inactive ones keep their last state).
    strands: Vec<Strand>,
    /// Active guides and their interaction (strands inside are clones, written back on a change).
    active: Vec<usize>,
    interaction: LocalInteraction,
    hair_force: Vector3<f64>,
    wetness: Vec<f32>,
    cut: Vec<f32>,
    step: u64,
    last_contacts: u32,
    last_select: Option<Vector3<f64>>,
    clipped: bool,
    /// Rejected device readings (NaN, teleport).
    pub rejected: u64,
    /// Strand steps that failed (state kept).
    pub failed: u64,
}

impl HapticCore {
    /// At rest with the comb selected.
    pub fn new(scene: Arc<Scene>, params: SessionParams) -> Result<Self, SessionError> {
        params.validate()?;
        let h = scene.hair_type;
        let strands = Self::build_strands(&scene, &h, 0.0)?;
        let start = Vector3::new(0.0, -0.25, 0.0);
        let coupling = Coupling::new(params.profile, CouplingParams::for_profile(&params.profile), start);
        let pose = ToolPose { position: start, rotation: Matrix3::identity() };
        let n = scene.guides.len();
        let interaction = LocalInteraction::new(Vec::new(), Tool::Comb.shape(), pose, Self::force_model(&h, 0.0));
        Ok(Self {
            scene, params, tool: Tool::Comb, hair_type: h, curliness: 0.0, combing_ease: 0.0, coupling, device: None, strands, active: Vec::new(), interaction,
            hair_force: Vector3::zeros(), wetness: vec![0.0; n], cut: vec![1.0; n], step: 0, last_contacts: 0, last_select: None, clipped: false, rejected: 0, failed: 0,
        })
    }

    /// Every guide's strand in its groomed state, with the hair type's section and material and the
    /// curliness (in [0, 1], [`hairstyle::Curl`]) added to the rest twist and bend.
    fn build_strands(scene: &Scene, h: &HairType, curliness: f64) -> Result<Vec<Strand>, SessionError> {
        let err = |e: strand::StrandError| SessionError::Scene(e.to_string());
        let curl = hairstyle::Curl::from_curliness(curliness.clamp(0.0, 1.0)).map_err(|e| SessionError::Scene(e.to_string()))?;
        scene.guides.iter().map(|g| {
            let mut m = g.model.clone();
            if *h != scene.hair_type {
                m.section = h.section().map_err(err)?;
                m.material = h.material().map_err(err)?;
            }
            if let Some(c) = curl.as_ref() {
                let mut q = m.rest_coordinates();
                for i in 0..m.segments {
                    q[2 * i] += c.twist;
                    q[2 * i + 1] += c.bend;
                }
                m.set_rest_coordinates(&q);
            }
            m.air_drag = m.air_drag.max(2e-5);
            let mut s = Strand::new(m, g.state.root.clone()).map_err(err)?;
            s.state.q.copy_from(&g.state.q);
            Ok(s)
        }).collect()
    }

    fn force_model(h: &HairType, ease: f64) -> ForceModel {
        ForceModel::Constraint { friction: h.friction_coefficient() * (1.0 - 0.8 * ease.clamp(0.0, 1.0)), options: Default::default() }
    }

    /// Applies a viewer command.
    pub fn apply(&mut self, c: &Command) {
        match *c {
            Command::SelectTool(t) => {
                self.write_back();
                self.tool = t;
                self.active.clear();
                self.last_select = None;
                self.clipped = false;
                self.interaction = LocalInteraction::new(Vec::new(), t.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease));
            }
            Command::SetHair { hair_type, curliness, combing_ease } => {
                let h = HairType::ALL.get(hair_type as usize).copied().unwrap_or(self.hair_type);
                let (c, e) = (if curliness.is_finite() { curliness.clamp(0.0, 1.0) } else { 0.0 }, if combing_ease.is_finite() { combing_ease.clamp(0.0, 1.0) } else { 0.0 });
                if h != self.hair_type || c != self.curliness {
                    if let Ok(s) = Self::build_strands(&self.scene, &h, c) {
                        self.strands = s;
                        self.active.clear();
                    }
                }
                self.hair_type = h;
                self.curliness = c;
                self.combing_ease = e;
                self.last_select = None;
                self.interaction = LocalInteraction::new(Vec::new(), self.tool.shape(), self.interaction.pose, Self::force_model(&h, e));
            }
            Command::Reset => {
                if let Ok(s) = Self::build_strands(&self.scene, &self.hair_type, self.curliness) {
                    self.strands = s;
                }
                self.active.clear();
                self.last_select = None;
                self.clipped = false;
                self.interaction = LocalInteraction::new(Vec::new(), self.tool.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease));
                self.wetness.iter_mut().for_each(|w| *w = 0.0);
                self.cut.iter_mut().for_each(|c| *c = 1.0);
            }
        }
    }

    /// Copies the active strands' states back into the guide set.
    fn write_back(&mut self) {
        for (slot, &g) in self.active.iter().enumerate() {
            if let Some(s) = self.interaction.strands.get(slot) {
                self.strands[g] = s.clone();
            }
        }
    }

    /// Chooses the guides nearest to the tool (their settled shapes through the lattice) as the active set.
    fn select(&mut self, tool: &Vector3<f64>, nodes: &[Point3<f64>]) {
        let r = self.params.activation_radius;
        let mut near: Vec<(f64, usize)> = Vec::new();
        for (g, guide) in self.scene.guides.iter().enumerate() {
            let d = guide.reference.iter().map(|p| (ffd_map(&self.scene.lattice.ffd, nodes, p) - tool).norm()).fold(f64::INFINITY, f64::min);
            if d < r {
                near.push((d, g));
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut chosen: Vec<usize> = near.iter().take(self.params.max_active).map(|x| x.1).collect();
        chosen.sort_unstable();
        if chosen != self.active {
            self.write_back();
            self.active = chosen;
            let strands = self.active.iter().map(|&g| self.strands[g].clone()).collect();
            self.interaction = LocalInteraction::new(strands, self.tool.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease));
        }
        self.last_select = Some(*tool);
    }

    /// One haptic step of `dt` s with the device's latest `reading` (the mouse target) and the lattice
    /// snapshot `lattice`. Returns the command for the device.
    pub fn step(&mut self, reading: Option<DeviceReading>, lattice: &LatticeSnapshot, dt: f64) -> DeviceCommand {
        self.step += 1;
        let Some(r) = reading else { return DeviceCommand::default() };
        // The device point follows the mouse target at a bounded speed.
        let target = r.position;
        if !target.iter().all(|x| x.is_finite()) {
            self.rejected += 1;
            return DeviceCommand::default();
        }
        if self.device.is_none() {
            // First reading: device, proxy and tool start where the mouse is, at rest.
            self.coupling = Coupling::new(self.params.profile, CouplingParams::for_profile(&self.params.profile), target);
            self.interaction.pose = ToolPose { position: target, rotation: r.rotation };
        }
        let dev = self.device.get_or_insert(target);
        let d = target - *dev;
        let max = self.params.follow_speed * dt;
        *dev += if d.norm() > max { d * (max / d.norm()) } else { d };
        let reading = DeviceReading { position: *dev, ..r };
        let force = match self.coupling.update(&reading, dt, &self.hair_force) {
            Ok(f) => f,
            Err(_) => {
                self.rejected += 1;
                self.hair_force = Vector3::zeros();
                return DeviceCommand::default();
            }
        };
        let proxy = self.coupling.proxy;
        let nodes = &lattice.positions;
        // Re-select the active set when the tool has moved 1 cm (never while the clip holds a strand).
        let moved = self.last_select.map_or(true, |p| (p - proxy).norm() > 0.01);
        if moved && !self.clipped && nodes.len() == self.scene.lattice.node_count() {
            self.select(&proxy, nodes);
        }
        // Roots follow the lattice.
        if nodes.len() == self.scene.lattice.node_count() {
            for (slot, &g) in self.active.iter().enumerate() {
                let target = ffd_map(&self.scene.lattice.ffd, nodes, &self.scene.guides[g].state.root.position);
                let root = &mut self.interaction.strands[slot].state.root;
                root.velocity = (target - root.position) / dt;
                root.acceleration = Vector3::zeros();
            }
        }
        // Clip: the primary button closes it.
        let pressed = r.buttons & 1 != 0;
        if self.tool == Tool::Clip {
            if pressed && !self.clipped {
                self.clipped = self.interaction.clip(0.01).is_some();
            } else if !pressed && self.clipped {
                self.interaction.release();
                self.clipped = false;
            }
        }
        let pose = ToolPose { position: proxy, rotation: r.rotation };
        match self.interaction.step(dt, pose) {
            Ok(res) => {
                self.hair_force = res.force * self.params.wisp;
                self.last_contacts = res.contacts.len() as u32;
                if self.tool == Tool::Scissors && pressed {
                    for c in &res.contacts {
                        let g = self.active[c.strand];
                        let frac = (c.s / self.interaction.strands[c.strand].model.length) as f32;
                        self.cut[g] = self.cut[g].min(frac.clamp(0.05, 1.0));
                    }
                }
            }
            Err(_) => {
                self.failed += 1;
                self.hair_force = Vector3::zeros();
                self.last_contacts = 0;
            }
        }
        // Wetness: the sprayer raises and the dryer lowers it for guides whose roots' region (within 6 cm of
        // the nozzle's aim point, 5 cm ahead along the tool's -z) is in the cone, while the button is held.
        if pressed && matches!(self.tool, Tool::Dryer | Tool::Sprayer) {
            let aim = proxy - r.rotation.column(2).into_owned() * 0.05;
            let sign = if self.tool == Tool::Sprayer { 1.0 } else { -1.0 };
            for (g, guide) in self.scene.guides.iter().enumerate() {
                let near = guide.reference.iter().any(|p| (ffd_map(&self.scene.lattice.ffd, nodes, p) - aim).norm() < 0.06);
                if near {
                    self.wetness[g] = (self.wetness[g] + (sign * self.params.wetting_rate * dt) as f32).clamp(0.0, 1.0);
                }
            }
        }
        DeviceCommand { force, torque: Vector3::zeros() }
    }

    /// Fills `out` with what the viewer needs.
    pub fn snapshot(&self, lattice: &LatticeSnapshot, dt: f64, out: &mut HapticSnapshot) {
        out.step = self.step;
        out.time = self.step as f64 * dt;
        out.tool = self.tool as u8;
        out.tool_position = self.coupling.proxy;
        out.tool_rotation = self.interaction.pose.rotation;
        out.device_position = self.device.unwrap_or(self.coupling.proxy);
        out.force = self.coupling.force;
        out.contacts = self.last_contacts;
        out.lattice_version = lattice.version;
        out.active.clear();
        out.displacement.clear();
        let ok = lattice.positions.len() == self.scene.lattice.node_count();
        let samples = self.scene.samples();
        for (slot, &g) in self.active.iter().enumerate() {
            out.active.push(g as u32);
            let s = &self.interaction.strands[slot];
            let pts = centreline(s, samples);
            for (k, p) in pts.into_iter().enumerate() {
                let reference = self.scene.guides[g].reference[k];
                let base = if ok { ffd_map(&self.scene.lattice.ffd, &lattice.positions, &reference) } else { reference };
                let d = p - base;
                // Keep the viewer's displacement sane even if a strand misbehaves.
                out.displacement.push(if d.iter().all(|x| x.is_finite()) && d.norm() < 0.5 { d } else { Vector3::zeros() });
            }
        }
        out.wetness.clone_from(&self.wetness);
        out.cut.clone_from(&self.cut);
    }

    /// Force last sent to the device, N.
    pub fn force(&self) -> Vector3<f64> {
        self.coupling.force
    }
    /// Guide indices currently simulated.
    pub fn active(&self) -> &[usize] {
        &self.active
    }
    /// Wetness per guide.
    pub fn wetness(&self) -> &[f32] {
        &self.wetness
    }
    /// Kept length fraction per guide.
    pub fn cut(&self) -> &[f32] {
        &self.cut
    }
}

/// `samples` centreline points of a strand evenly in arc length, root to tip, m.
fn centreline(s: &Strand, samples: usize) -> Vec<Vector3<f64>> {
    hairstyle::generate::sample_strand(&s.model, &s.state, samples).into_iter().map(|p| p.coords).collect()
}

/// FFD of a head-frame point through lattice nodes (clamped to the embedded volume), m.
pub fn ffd_map(ffd: &FfdLattice, nodes: &[Point3<f64>], p: &Vector3<f64>) -> Vector3<f64> {
    match ffd.weights_clamped(&Point3::from(*p)) {
        Ok((idx, w)) => idx.iter().zip(w.iter()).fold(Vector3::zeros(), |a, (&i, &w)| a + nodes[i].coords * w),
        Err(_) => *p,
    }
}

// ---------------------------------------------------------------------------------------------------------
// The live session
// ---------------------------------------------------------------------------------------------------------

/// The viewer side's handles: device input, commands, and the latest snapshots.
pub struct SessionIo {
    /// Push mouse readings here (the haptic thread reads the newest).
    pub device: VirtualHandle,
    /// Viewer commands, applied by the haptic thread before its next step.
    pub commands: Sender<Command>,
    /// Latest lattice snapshot.
    pub lattice: Output<LatticeSnapshot>,
    /// Latest haptic snapshot.
    pub haptic: Output<HapticSnapshot>,
}

/// What a stopped session returns.
#[derive(Debug)]
pub struct SessionReport {
    /// Haptic loop timing.
    pub haptic: LoopStats,
    /// Global steps done.
    pub global_steps: u64,
    /// Mean global step wall time, s.
    pub global_step_mean: f64,
    /// Times the lattice was found non-finite and reset.
    pub global_recoveries: u64,
    /// The record, if asked for.
    pub record: Option<Record>,
}

/// A running session: a global thread and a haptic loop thread.
pub struct Session {
    scene: Arc<Scene>,
    params: SessionParams,
    stop: Arc<AtomicBool>,
    reset_epoch: Arc<AtomicU64>,
    global: Option<JoinHandle<(u64, f64, u64, Vec<u64>)>>,
    haptic: Option<HapticLoop<VirtualDevice>>,
    record: Arc<std::sync::Mutex<Option<Record>>>,
}

impl Session {
    /// Starts both threads on `scene`.
    pub fn start(scene: Arc<Scene>, params: SessionParams) -> Result<(Session, SessionIo), SessionError> {
        params.validate()?;
        let mut core = HapticCore::new(scene.clone(), params)?;
        let mut global = GlobalCore::new(scene.clone());
        let rest = global.snapshot();
        let (mut lat_h_in, mut lat_h_out) = triple_buffer(&rest);
        let (mut lat_v_in, lat_v_out) = triple_buffer(&rest);
        let mut first = HapticSnapshot::default();
        let dt = 1.0 / params.haptic_rate_hz;
        core.snapshot(&rest, dt, &mut first);
        let (mut hap_in, hap_out) = triple_buffer(&first);
        let (cmd_tx, cmd_rx): (Sender<Command>, Receiver<Command>) = channel();
        let (dev, handle) = virtual_device();
        let stop = Arc::new(AtomicBool::new(false));
        let reset_epoch = Arc::new(AtomicU64::new(0));

        // Global thread.
        let (stop_g, epoch_g) = (stop.clone(), reset_epoch.clone());
        let period = Duration::from_secs_f64(1.0 / params.global_rate_hz);
        let gdt = period.as_secs_f64();
        let global_thread = std::thread::Builder::new().name("coiffure-global".into()).spawn(move || {
            let (mut steps, mut busy, mut recov) = (0u64, 0.0f64, 0u64);
            let mut resets = Vec::new();
            let mut seen_epoch = 0;
            let start = Instant::now();
            while !stop_g.load(Ordering::Relaxed) {
                let e = epoch_g.load(Ordering::Acquire);
                if e != seen_epoch {
                    seen_epoch = e;
                    global.reset();
                    resets.push(global.version + 1);
                }
                let (snap, bad) = global.step(gdt);
                busy += snap.step_seconds;
                recov += bad as u64;
                steps += 1;
                lat_h_in.write(snap.clone());
                lat_v_in.write(snap);
                let next = start + period * steps as u32;
                let now = Instant::now();
                if next > now {
                    std::thread::sleep(next - now);
                }
            }
            (steps, busy / steps.max(1) as f64, recov, resets)
        }).map_err(|e| SessionError::Start(e.to_string()))?;

        // Haptic thread.
        let record = Arc::new(std::sync::Mutex::new(params.record.then(|| Record::new(params.haptic_rate_hz))));
        let mut recorder = params.record.then(|| Recorder { local: Vec::with_capacity(4096), shared: record.clone() });
        let epoch_h = reset_epoch.clone();
        let publish_every = params.publish_every;
        let step = move |reading: Option<DeviceReading>, _t: f64, dt: f64| -> DeviceCommand {
            let mut cmds = Vec::new();
            while let Ok(c) = cmd_rx.try_recv() {
                if c == Command::Reset {
                    epoch_h.fetch_add(1, Ordering::Release);
                }
                core.apply(&c);
                cmds.push(c);
            }
            let lattice = lat_h_out.read();
            let cmd = core.step(reading, lattice, dt);
            if let Some(r) = recorder.as_mut() {
                r.local.push(StepRecord { reading, lattice_version: lattice.version, commands: cmds, force: cmd.force });
                if r.local.len() >= 1000 {
                    r.flush(false);
                }
            }
            if core.step % publish_every == 0 {
                let mut out = hap_in.input_buffer_mut();
                core.snapshot(lattice, dt, &mut out);
                hap_in.publish();
            }
            cmd
        };
        let haptic = HapticLoop::spawn(params.haptic_rate_hz, dev, step, None).map_err(SessionError::Start)?;
        let session = Session { scene, params, stop, reset_epoch, global: Some(global_thread), haptic: Some(haptic), record };
        Ok((session, SessionIo { device: handle, commands: cmd_tx, lattice: lat_v_out, haptic: hap_out }))
    }

    /// The scene.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The parameters.
    pub fn params(&self) -> &SessionParams {
        &self.params
    }

    /// Stops both threads and returns timing and the record.
    pub fn stop(mut self) -> SessionReport {
        let _ = self.reset_epoch.load(Ordering::Relaxed);
        let (haptic, _dev) = self.haptic.take().expect("running").stop();
        self.stop.store(true, Ordering::Relaxed);
        let (global_steps, global_step_mean, global_recoveries, resets) = self.global.take().expect("running").join().expect("the global thread panicked");
        let mut record = self.record.lock().map(|mut g| g.take()).unwrap_or(None);
        if let Some(r) = record.as_mut() {
            r.global_resets = resets;
        }
        SessionReport { haptic, global_steps, global_step_mean, global_recoveries, record }
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.haptic.take() {
            let _ = h.stop();
        }
        if let Some(g) = self.global.take() {
            let _ = g.join();
        }
    }
}

/// Collects step records on the haptic thread and hands them over in batches: the lock is only tried on
/// the haptic path (never waited on); the last batch is handed over when the loop ends (on drop).
struct Recorder {
    local: Vec<StepRecord>,
    shared: Arc<std::sync::Mutex<Option<Record>>>,
}

impl Recorder {
    fn flush(&mut self, wait: bool) {
        let guard = if wait { self.shared.lock().ok() } else { self.shared.try_lock().ok() };
        if let Some(mut g) = guard {
            if let Some(r) = g.as_mut() {
                r.steps.append(&mut self.local);
            }
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.flush(true);
    }
}

/// Re-runs a recorded session in lockstep on this thread: the global core is stepped up to the lattice
/// version each haptic step used (applying the recorded lattice resets), the recorded commands are applied,
/// and the haptic core steps with the recorded reading. Returns the force of every step.
pub fn replay(scene: Arc<Scene>, params: SessionParams, record: &Record) -> Result<Vec<Vector3<f64>>, SessionError> {
    let mut core = HapticCore::new(scene.clone(), params)?;
    let mut global = GlobalCore::new(scene);
    let mut snap = global.snapshot();
    // The same step lengths as the live threads (which go through Duration).
    let gdt = Duration::from_secs_f64(1.0 / params.global_rate_hz).as_secs_f64();
    let dt = Duration::from_secs_f64(1.0 / record.rate_hz).as_secs_f64();
    let mut out = Vec::with_capacity(record.steps.len());
    for s in &record.steps {
        while snap.version < s.lattice_version {
            if record.global_resets.contains(&(global.version + 1)) {
                global.reset();
            }
            snap = global.step(gdt).0;
        }
        for c in &s.commands {
            core.apply(c);
        }
        out.push(core.step(s.reading, &snap, dt).force);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_scene() -> Arc<Scene> {
        let o = SceneOptions { render_strands: 2000, guides: 60, ..SceneOptions::default() };
        Arc::new(Scene::builtin(&o).unwrap())
    }

    #[test]
    fn inline_tool_shapes_parse() {
        for t in Tool::ALL {
            assert!(!t.shape().capsules.is_empty(), "{t:?}");
        }
        assert_eq!(Tool::from_id(5), Some(Tool::Clip));
        assert_eq!(Tool::from_id(6), None);
    }

    #[test]
    fn builtin_scene_is_inside_the_lattice_and_guides_start_at_their_reference() {
        // Every render vertex is inside the lattice's embedded volume, so the viewer's FFD reproduces it at
        // rest (to 1e-9 m in f64); each guide's strand starts exactly on its reference centreline.
        let s = small_scene();
        let f = &s.lattice.ffd;
        for p in &s.render.positions {
            let q = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            assert!(f.weights(&Point3::from(q)).is_ok(), "{q:?} outside the lattice");
            let back = ffd_map(f, &s.lattice.rest, &q);
            assert!((back - q).norm() < 1e-9, "FFD at rest reproduces the point: {back:?} vs {q:?}");
        }
        assert_eq!(s.render.positions.len(), 2000 * 12);
        assert_eq!(s.render.guide.len(), 2000 * s.render.guides_per_strand);
        assert!(s.render.guide.iter().all(|&g| (g as usize) < s.guides.len()));
        assert!(s.guides.iter().all(|g| g.reference.len() == 16));
        let strands = HapticCore::build_strands(&s, &s.hair_type, 0.0).unwrap();
        for (st, g) in strands.iter().zip(&s.guides) {
            for (a, b) in centreline(st, 16).iter().zip(&g.reference) {
                assert!((a - b).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn combing_through_the_guides_gives_force_and_moves_them() {
        // Headless: the comb is dragged down the back of the head through the hair (0.1 m/s), stepping the
        // haptic core at 1 kHz on the rest lattice. The hand feels a force, the active guides leave their
        // reference shape, and nothing is rejected.
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let snap = GlobalCore::new(scene).snapshot();
        let rot = Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)]);
        let mut peak: f64 = 0.0;
        let mut moved: f64 = 0.0;
        let mut hs = HapticSnapshot::default();
        for n in 0..1500 {
            let t = n as f64 * 1e-3;
            let p = Vector3::new(0.0, -0.118, 0.05 - 0.1 * t);
            let c = core.step(Some(DeviceReading { time: t, position: p, rotation: rot, buttons: 0 }), &snap, 1e-3);
            peak = peak.max(c.force.norm());
            if n % 50 == 0 {
                core.snapshot(&snap, 1e-3, &mut hs);
                moved = moved.max(hs.displacement.iter().map(|d| d.norm()).fold(0.0, f64::max));
            }
        }
        assert_eq!(core.rejected, 0);
        eprintln!("peak force {peak} N, largest displacement {moved} m");
        assert!(peak > 1e-3, "peak force {peak} N");
        assert!(peak <= 3.3 + 1e-12, "within the Omni's clamp: {peak} N");
        assert!(moved > 1e-3, "largest guide displacement {moved} m");
    }

    #[test]
    fn a_recorded_live_session_replays_to_the_same_forces() {
        // A live session (both threads, real time) is driven through the virtual device by this thread: a
        // comb stroke down the back of the head at 0.1 m/s, a switch to the brush and a reset on the way.
        // Its record (through the file format) replayed in lockstep on one thread gives every haptic
        // step's force again within 1e-9 N (in fact bit for bit), although the live threads' timing
        // was whatever the machine gave them.
        let scene = small_scene();
        let params = SessionParams { record: true, ..SessionParams::default() };
        let (session, mut io) = Session::start(scene.clone(), params).unwrap();
        let rot = Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)]);
        // The path follows the haptic thread's own step count (published every 5 steps), so the test does
        // not depend on how fast this machine runs the threads.
        let (mut brush, mut reset) = (false, false);
        loop {
            let step = io.haptic.read().step;
            if step >= 1500 {
                break;
            }
            let t = step as f64 * 1e-3;
            io.device.push(DeviceReading { time: t, position: Vector3::new(0.0, -0.118, 0.05 - 0.1 * t), rotation: rot, buttons: 0 });
            if step > 700 && !brush {
                io.commands.send(Command::SelectTool(Tool::Brush)).unwrap();
                brush = true;
            }
            if step > 1100 && !reset {
                io.commands.send(Command::Reset).unwrap();
                reset = true;
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        let report = session.stop();
        eprintln!("live: {:?}, global steps {}", report.haptic, report.global_steps);
        let rec = report.record.expect("recorded");
        assert!(rec.steps.len() >= 1500, "{} steps", rec.steps.len());
        assert_eq!(rec.global_resets.len(), 1, "one lattice reset recorded");
        assert_eq!(rec.steps.iter().map(|s| s.commands.len()).sum::<usize>(), 2);
        let peak = rec.steps.iter().map(|s| s.force.norm()).fold(0.0, f64::max);
        assert!(peak > 1e-4, "the stroke was felt: peak {peak} N");
        let back = Record::from_bytes(&rec.to_bytes()).unwrap();
        assert_eq!(back, rec);
        let forces = replay(scene, params, &back).unwrap();
        assert_eq!(forces.len(), rec.steps.len());
        let worst = forces.iter().zip(&rec.steps).map(|(f, s)| (f - s.force).norm()).fold(0.0, f64::max);
        eprintln!("replayed {} steps, peak {peak} N, largest difference {worst} N", forces.len());
        assert!(worst <= 1e-9, "largest force difference {worst} N");
    }

    #[test]
    fn damaged_records_are_refused_with_the_offset() {
        let mut r = Record::new(1000.0);
        r.steps.push(crate::record::StepRecord { reading: None, lattice_version: 3, commands: vec![Command::Reset], force: Vector3::new(1.0, 2.0, 3.0) });
        let b = r.to_bytes();
        assert_eq!(Record::from_bytes(&b).unwrap(), r);
        for n in 0..b.len() {
            assert!(Record::from_bytes(&b[..n]).is_err(), "prefix of {n} bytes");
        }
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(matches!(Record::from_bytes(&bad), Err(crate::record::RecordError::Bad { offset: 0, .. })));
    }
}
