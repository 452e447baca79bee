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
use lattice::cluster::{ClusterParams, ClusterSet, CutPiece};
use lattice::metaball::{Metaball, MetaballSet};
use hairstyle::cut::{cut_guide, cut_polylines, polyline_length, Blade};
use tools::dryer::{Cone, HairDryer};
use tools::sprayer::Sprayer;
use tools::wetness::{WetnessField, WetnessModel};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use strand::{HairType, PointForce, Strand, StrandModel};
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
    /// The built-in head and guides of `opts` carrying the render strands of `curves` instead of generated
    /// ones (positions in m in the head frame, root first, as the viewer saves them; at most
    /// 10,000,000 strands): each strand resampled to `opts.render_vertices` points evenly along its
    /// length, bound to the guides whose roots are nearest its root (inverse-distance weights), spanning
    /// its length over the nearest guide's length (capped at 1), and a lattice enclosing them all whose
    /// node masses come from the strands (the guides' linear density times their lengths).
    /// Errors name the bad strand (empty, non-finite point) or parameter.
    pub fn from_curves(curves: &hairstyle::HairCurves, opts: &SceneOptions) -> Result<Scene, SessionError> {
        let bad = |m: String| SessionError::Scene(m);
        if curves.strands.is_empty() || curves.strands.len() > 10_000_000 {
            return Err(bad(format!("a hairstyle needs 1 to 10,000,000 strands, got {}", curves.strands.len())));
        }
        for (i, st) in curves.strands.iter().enumerate() {
            if st.is_empty() {
                return Err(bad(format!("strand {i} has no point")));
            }
            if let Some(j) = st.iter().position(|p| !p.iter().all(|x| x.is_finite() && x.abs() < 100.0)) {
                return Err(bad(format!("strand {i} point {j} is not finite or is over 100 m away: {:?}", st[j])));
            }
        }
        let base = Scene::builtin(&SceneOptions { render_strands: 1, ..opts.clone() })?;
        let v = opts.render_vertices;
        let curves = hairstyle::formats::tfx::resample(&hairstyle::HairCurves::from_strands(curves.strands.clone()), v).map_err(|e| bad(e.to_string()))?;
        let k = base.render.guides_per_strand.min(base.guides.len()).max(1);
        let roots: Vec<Vector3<f64>> = base.guides.iter().map(|g| g.state.root.position).collect();
        let density = base.guides.first().map_or(0.0, |g| g.model.mass() / g.model.length);
        let n = curves.strands.len();
        let (mut positions, mut guide, mut weight, mut span) = (Vec::with_capacity(n * v), Vec::with_capacity(n * k), Vec::with_capacity(n * k), Vec::with_capacity(n));
        let mut hair_mass = 0.0;
        for st in &curves.strands {
            let root = Vector3::new(st[0][0] as f64, st[0][1] as f64, st[0][2] as f64);
            let mut near: Vec<(f64, usize)> = roots.iter().enumerate().map(|(g, r)| ((r - root).norm(), g)).collect();
            near.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            near.truncate(k);
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            let w: Vec<f64> = near.iter().map(|(d, _)| 1.0 / (d + 1e-3)).collect();
            let sum: f64 = w.iter().sum();
            guide.extend(near.iter().map(|&(_, g)| g as u32));
            weight.extend(w.iter().map(|x| (x / sum) as f32));
            let length: f64 = st.windows(2).map(|p| (0..3).map(|a| ((p[1][a] - p[0][a]) as f64).powi(2)).sum::<f64>().sqrt()).sum();
            span.push((length / base.guides[near[0].1].model.length).min(1.0) as f32);
            hair_mass += density * length;
            positions.extend_from_slice(st);
        }
        let render = RenderHair { vertices_per_strand: v, guides_per_strand: k, positions, guide, weight, span };
        // The lattice encloses the strands and what the built-in one enclosed (head, guides).
        let (mut lo, mut hi) = (Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY), Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY));
        let base_points = base.lattice.rest.iter().copied();
        let hair_points = render.positions.iter().map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        for p in base_points.chain(hair_points) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let ffd = FfdLattice::enclosing(lo, hi, opts.cell).map_err(|e| bad(e.to_string()))?;
        if ffd.node_count() > 200_000 {
            return Err(bad(format!("the strands span {:?} to {:?} m: a lattice of {} nodes at {} m cells is too large", lo, hi, ffd.node_count(), opts.cell)));
        }
        let radius = hairstyle::HeadParams::default().head_radius;
        let lattice = lattice_for_hair(ffd, &render.positions, hair_mass.max(1e-6), radius)?;
        Ok(Scene { head: base.head, head_mesh: base.head_mesh, render, guides: base.guides, hair_type: base.hair_type, lattice })
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
    /// Sprayer wetting rate s0 at the nozzle (`tools::sprayer::Sprayer`), 1/s. Default 1.
    pub wetting_rate: f64,
    /// Dryer drying rate k0 at the nozzle (`tools::dryer::HairDryer`), 1/s. Default 0.05.
    pub drying_rate: f64,
    /// Hairs each simulated guide stands for in the force on the tool (a wisp): the local strands' reaction
    /// is multiplied by it. Dimensionless, >= 1. Default 20.
    pub wisp: f64,
    /// Real-time (`SCHED_FIFO`) priority asked for the haptic thread, 1..=99 (`haptics::realtime`), or None
    /// for normal priority. A refusal (no permission) is logged and the loop runs at normal priority.
    /// Default None (`coiffure serve` asks for 10).
    pub haptic_priority: Option<i32>,
}

impl Default for SessionParams {
    fn default() -> Self {
        Self { haptic_rate_hz: 1000.0, global_rate_hz: 100.0, max_active: 12, activation_radius: 0.05, profile: DeviceProfile::PHANTOM_OMNI, follow_speed: 1.0, publish_every: 5, record: false, wetting_rate: 1.0, drying_rate: 0.05, wisp: 20.0, haptic_priority: None }
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
        if !(self.activation_radius > 0.0 && self.follow_speed > 0.0 && self.wetting_rate >= 0.0 && self.drying_rate >= 0.0 && self.wetting_rate.is_finite() && self.drying_rate.is_finite()) {
            return p(format!("activation_radius, follow_speed must be > 0 and wetting_rate, drying_rate finite and >= 0: {self:?}"));
        }
        if !(self.wisp >= 1.0 && self.wisp.is_finite()) {
            return p(format!("wisp must be >= 1, got {}", self.wisp));
        }
        if self.publish_every == 0 {
            return p("publish_every must be > 0".into());
        }
        if let Some(prio) = self.haptic_priority.filter(|x| !haptics::realtime::PRIORITY_RANGE.contains(x)) {
            return p(format!("haptic_priority must be in 1..=99, got {prio}"));
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
    /// Mean wetness in [0, 1] of each guide (over its segments' `WetnessField` values).
    pub wetness: Vec<f32>,
    /// Changes of `kept` so far (scissors cuts and resets): the viewer re-reads `kept` when it changes.
    pub kept_version: u64,
    /// Points kept of each render strand (vertices 0..kept stay on the head; V: uncut).
    pub kept: Arc<Vec<u16>>,
    /// The falling cut clusters' chains: node positions (world, m), one list per chain.
    pub chains: Vec<Vec<[f32; 3]>>,
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
    /// Lattice version the last step used.
    pub lattice_version: u64,
}

// ---------------------------------------------------------------------------------------------------------
// Global core
// ---------------------------------------------------------------------------------------------------------

/// What the global layer reads of the tool each step: published by the haptic thread after every haptic
/// step, kept in the record for replay ([`Record::global_inputs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolInput {
    /// Selected tool.
    pub tool: Tool,
    /// False until the device gave a reading (the tool then acts on nothing).
    pub present: bool,
    /// Tool proxy position (world, m).
    pub position: Vector3<f64>,
    /// Tool rotation (tool frame to world).
    pub rotation: Matrix3<f64>,
    /// Primary button held (dryer blowing, sprayer spraying).
    pub pressed: bool,
    /// Scissors closes so far: the global layer cuts the render strands once per increment, with the blade
    /// of [`ToolInput::blade`].
    pub cuts: u64,
}

impl Default for ToolInput {
    fn default() -> Self {
        Self { tool: Tool::Comb, present: false, position: Vector3::zeros(), rotation: Matrix3::identity(), pressed: false, cuts: 0 }
    }
}

/// `it` with the scene's body (head, neck, shoulders; the live head frame is the world frame) for its strands
/// to rest on.
fn resting_on(scene: &Scene, mut it: LocalInteraction) -> LocalInteraction {
    it.body = Some((scene.head.clone(), scene.lattice.params.metaball.threshold));
    it
}

/// Pieces of each simulated strand the dryer's air drag is applied to (at their midpoints).
const DRYER_PIECES: usize = 8;
/// Distance from the tool point back to the dryer's or sprayer's nozzle, m.
pub const NOZZLE_STANDOFF: f64 = 0.15;
/// Radius of the disk the scissors' blades sweep when they close, m (about the blades' length).
pub const BLADE_RADIUS: f64 = 0.04;
/// Distance the held scissors move between two cuts, m.
pub const SNIP_DISTANCE: f64 = 0.02;
/// Most falling pieces made of one cut: more are sampled evenly, their masses scaled to keep the total.
pub const MAX_PIECES_PER_CUT: usize = 256;
/// Most cuts whose clusters fall at once (the oldest is dropped).
const MAX_CLUSTER_SETS: usize = 8;

impl ToolInput {
    /// The scissors' cutting disk: centred on the proxy, in the plane normal to the tool's y axis (the
    /// stroke direction), radius [`BLADE_RADIUS`].
    pub fn blade(&self) -> Blade {
        let n = self.rotation.column(1).into_owned();
        Blade { point: self.position.into(), normal: n.into(), radius: BLADE_RADIUS }
    }
    /// The nozzle's cone (dryer, sprayer): axis along the tool's -z, apex [`NOZZLE_STANDOFF`] back from the
    /// proxy along +z (the viewer puts the tool where the mouse points on the hair: the nozzle aims there
    /// from a hand's distance, as a dryer or a sprayer is held).
    fn cone(&self, mut cone: Cone) -> Cone {
        cone.apex = self.position + self.rotation.column(2).into_owned() * NOZZLE_STANDOFF;
        cone.axis = -self.rotation.column(2).into_owned();
        cone
    }
}

/// What one scissors cut of the render strands did (masses in kg, by the render hair's linear density).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutReport {
    /// Render strands cut.
    pub strands: usize,
    /// Mass of those strands before the cut (their hair on the head), kg.
    pub mass_before: f64,
    /// Mass they keep on the head, kg (from the kept lengths the session stores).
    pub mass_kept: f64,
    /// Mass of the pieces cut off, kg.
    pub mass_pieces: f64,
    /// Mass handed to the falling clusters (all pieces, or a sample scaled to the same total), kg.
    pub mass_clusters: f64,
    /// Pieces turned into falling chains (at most [`MAX_PIECES_PER_CUT`]).
    pub pieces: usize,
    /// Wall time of the cut, s (information).
    pub seconds: f64,
}

/// The global layer's state and step, shared by the live thread and [`replay`]: the lattice (with the body
/// as a position constraint and the tool as a repelling metaball obstacle), the dryer's jet on the lattice,
/// the wetness field of the guides (sprayer and dryer), the scissors' cuts of the render strands and the
/// falling cut clusters.
pub struct GlobalCore {
    scene: Arc<Scene>,
    /// The scene's lattice with the obstacle's attraction switched off (the tool repels only).
    model: LatticeModel,
    state: LatticeState,
    version: u64,
    head: Isometry3<f64>,
    /// Nodes outside the body at rest: only these are pushed out of it.
    outside: Vec<bool>,
    sprayer: Sprayer,
    dryer: HairDryer,
    /// Wetness per guide and segment.
    wet: WetnessField,
    /// Rest (head-frame) centres of each guide's segments, m.
    centres: Vec<Vec<Vector3<f64>>>,
    /// Kept length of each render strand in vertex units (V - 1: uncut).
    kept_len: Vec<f64>,
    kept: Arc<Vec<u16>>,
    kept_version: u64,
    cuts: u64,
    /// The render hair's linear density, kg/m.
    lambda: f64,
    /// Air drag per unit length of a hair, N s/m^2.
    air_drag: f64,
    clusters: Vec<ClusterSet>,
    cluster_params: ClusterParams,
    /// The last cut's report.
    pub last_cut: Option<CutReport>,
    deferred: bool,
    pending: Vec<Blade>,
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
        let sprayer = Sprayer { wetting_rate: params.wetting_rate, ..Sprayer::default() };
        let dryer = HairDryer { drying_rate: params.drying_rate, ..HairDryer::default() };
        let segs: Vec<usize> = scene.guides.iter().map(|g| g.model.segments).collect();
        let centres = scene.guides.iter().map(|g| {
            let n = g.model.segments;
            let r = &g.reference;
            (0..n).map(|k| {
                let u = (k as f64 + 0.5) / n as f64 * (r.len() - 1) as f64;
                let (i, f) = ((u.floor() as usize).min(r.len() - 2), u - u.floor().min((r.len() - 2) as f64));
                r[i] * (1.0 - f) + r[i + 1] * f
            }).collect()
        }).collect();
        let rh = &scene.render;
        let v = rh.vertices_per_strand;
        let g0 = scene.guides.first();
        let lambda = g0.map_or(6.5e-5, |g| g.model.linear_density());
        let air_drag = g0.map_or(2e-5, |g| g.model.air_drag.max(2e-5));
        Self {
            model, state, version: 0, head, outside, sprayer, dryer, wet: WetnessField::dry(&segs), centres,
            kept_len: vec![v.saturating_sub(1) as f64; rh.strands()], kept: Arc::new(vec![v as u16; rh.strands()]), kept_version: 0, cuts: 0,
            lambda, air_drag, clusters: Vec::new(), cluster_params: ClusterParams::default(), last_cut: None, deferred: false, pending: Vec::new(), failed: 0, scene,
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

    /// One global step of `dt` s with the tool `input`; returns the new snapshot. A non-finite lattice is
    /// detected and put back to rest (reported by the flag).
    pub fn step(&mut self, dt: f64, input: &ToolInput) -> (LatticeSnapshot, bool) {
        let t0 = Instant::now();
        if input.cuts > self.cuts {
            self.cuts = input.cuts;
            if input.present {
                if self.deferred {
                    self.pending.push(input.blade());
                } else {
                    self.cut(&input.blade());
                }
            }
        }
        let nozzle = input.present && input.pressed;
        // Dryer jet on the lattice nodes, as a velocity change dv = F dt / m with F the jet's drag on the
        // hair a node stands for (m / lambda metres of it). (It can move to `LatticeModel::step_with_forces`.)
        if nozzle && input.tool == Tool::Dryer {
            let d = HairDryer { cone: input.cone(self.dryer.cone), ..self.dryer };
            for (i, x) in self.state.positions.iter().enumerate() {
                let m = self.model.masses[i];
                let f = d.force(&x.coords, self.air_drag * m / self.lambda);
                self.state.velocities[i] += f * (dt / m);
            }
        }
        let obstacle = input.present.then(|| tool_metaballs(&input.tool.shape(), &input.position, &input.rotation));
        self.model.step(&mut self.state, dt, &self.head, obstacle.as_ref());
        self.push_out_of_body();
        let bad = self.state.positions.iter().any(|p| !p.coords.iter().all(|x| x.is_finite()));
        if bad {
            self.state = self.model.rest_state(&self.head);
        }
        // Wetness: sprayer and dryer in their cones, at the guides' segment centres through the lattice.
        if nozzle && matches!(input.tool, Tool::Dryer | Tool::Sprayer) {
            let centres = self.centres_now();
            let r = if input.tool == Tool::Sprayer {
                Sprayer { cone: input.cone(self.sprayer.cone), ..self.sprayer }.spray(&mut self.wet, &centres, dt)
            } else {
                HairDryer { cone: input.cone(self.dryer.cone), ..self.dryer }.dry(&mut self.wet, &centres, dt)
            };
            self.failed += r.is_err() as u64;
        }
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
        LatticeSnapshot { version: self.version, positions: self.state.positions.clone(), step_seconds: 0.0, wetness, kept_version: self.kept_version, kept: self.kept.clone(), chains }
    }

    /// Guide segment centres now (rest centres through the lattice), m.
    fn centres_now(&self) -> Vec<Vec<Vector3<f64>>> {
        let (f, n) = (&self.model.ffd, &self.state.positions);
        self.centres.iter().map(|c| c.iter().map(|p| ffd_map(f, n, p)).collect()).collect()
    }

    /// Pushes nodes that started outside the body back onto its surface (a position correction along the
    /// field gradient, a few Newton steps) and removes their inward velocity.
    fn push_out_of_body(&mut self) {
        let t = self.model.params.metaball.threshold;
        let body = &self.scene.head;
        for i in 0..self.state.positions.len() {
            if !self.outside[i] {
                continue;
            }
            let mut x = self.head.inverse() * self.state.positions[i];
            let mut moved = false;
            for _ in 0..4 {
                let (f, g) = body.field_and_gradient(&x);
                let gg = g.norm_squared();
                if f <= t || !(gg > 1e-12) {
                    break;
                }
                x -= g * ((f - t) / gg * 1.05);
                moved = true;
            }
            if moved {
                let n = -(self.head * body.gradient(&x)).normalize();
                self.state.positions[i] = self.head * x;
                let v = &mut self.state.velocities[i];
                let vn = v.dot(&n);
                if vn < 0.0 {
                    *v -= n * vn;
                }
            }
        }
    }

    /// Cuts the render strands crossing `blade` (their current shape: rest positions through the lattice)
    /// and turns the pieces into falling clusters, at once (`self.cut_job(blade).run()` then
    /// [`GlobalCore::apply_cut`]).
    pub fn cut(&mut self, blade: &Blade) -> CutReport {
        let job = self.cut_job(blade);
        let r = job.run();
        self.apply_cut(r).unwrap_or_default()
    }

    /// What a cut needs of the current state, copied so that another thread can compute it
    /// ([`CutJob::run`]) while this core keeps stepping.
    pub fn cut_job(&self, blade: &Blade) -> CutJob {
        CutJob { scene: self.scene.clone(), nodes: self.state.positions.clone(), head: self.head, kept_len: self.kept_len.clone(), kept_version: self.kept_version, lambda: self.lambda, blade: *blade }
    }

    /// Applies a computed cut: shortens the strands and adds the falling clusters. None (and nothing done)
    /// if the strands changed since the job was taken (a reset meanwhile).
    pub fn apply_cut(&mut self, r: CutResult) -> Option<CutReport> {
        if r.kept_version != self.kept_version {
            return None;
        }
        let t0 = Instant::now();
        let mut rep = r.report;
        let v = self.scene.render.vertices_per_strand;
        let mut kept = (*self.kept).clone();
        for &(i, k) in &r.changes {
            self.kept_len[i] = k;
            kept[i] = ((k + 0.5).floor() as usize + 1).min(v) as u16;
        }
        self.kept = Arc::new(kept);
        self.kept_version += 1;
        if !r.pieces.is_empty() {
            match ClusterSet::new(&r.pieces, &self.cluster_params) {
                Ok(set) => {
                    rep.mass_clusters = set.total_mass();
                    rep.pieces = r.pieces.len();
                    if self.clusters.len() >= MAX_CLUSTER_SETS {
                        self.clusters.remove(0);
                    }
                    self.clusters.push(set);
                }
                Err(_) => self.failed += 1,
            }
        }
        rep.seconds += t0.elapsed().as_secs_f64();
        self.last_cut = Some(rep);
        Some(rep)
    }

    /// Cuts the global steps were asked for but left to the caller (see [`GlobalCore::defer_cuts`]).
    pub fn take_pending_cut(&mut self) -> Option<Blade> {
        if self.pending.is_empty() { None } else { Some(self.pending.remove(0)) }
    }

    /// With `true`, [`GlobalCore::step`] queues the scissors' cuts ([`GlobalCore::take_pending_cut`]) instead
    /// of making them: the live session computes them on a worker thread and applies them when done.
    pub fn defer_cuts(&mut self, on: bool) {
        self.deferred = on;
    }

    /// Version of the kept points (changes with every cut and reset).
    pub fn kept_version(&self) -> u64 {
        self.kept_version
    }
}

/// The inputs of one scissors cut of the render strands (see [`GlobalCore::cut_job`]).
pub struct CutJob {
    scene: Arc<Scene>,
    nodes: Vec<Point3<f64>>,
    head: Isometry3<f64>,
    kept_len: Vec<f64>,
    kept_version: u64,
    lambda: f64,
    blade: Blade,
}

/// A computed cut, to apply with [`GlobalCore::apply_cut`].
pub struct CutResult {
    kept_version: u64,
    /// New kept length (vertex units) of each strand cut.
    changes: Vec<(usize, f64)>,
    /// The pieces for the falling clusters (at most [`MAX_PIECES_PER_CUT`]).
    pieces: Vec<CutPiece>,
    report: CutReport,
}

impl CutJob {
    /// Computes the cut: each kept strand (rest positions through the lattice) is cut at its first crossing
    /// of the blade's disk (`hairstyle::cut::cut_polylines`). Strands that cannot reach the blade are skipped
    /// without mapping them. At most [`MAX_PIECES_PER_CUT`] pieces are kept for the clusters, sampled
    /// evenly, their masses scaled so that they carry all the mass cut off.
    pub fn run(&self) -> CutResult {
        let t0 = Instant::now();
        let mut rep = CutReport::default();
        let mut out = CutResult { kept_version: self.kept_version, changes: Vec::new(), pieces: Vec::new(), report: rep };
        let blade = &self.blade;
        if blade.validate().is_err() {
            return out;
        }
        let rh = &self.scene.render;
        let v = rh.vertices_per_strand;
        let (f, nodes) = (&self.scene.lattice.ffd, &self.nodes);
        let c = Vector3::from(blade.point);
        let vert = |i: usize, j: usize| Vector3::from(rh.positions[i * v + j]).cast::<f64>();
        // Polyline of strand i as kept now, through the lattice.
        let line = |i: usize, k: f64| -> Vec<[f64; 3]> {
            let whole = (k.floor() as usize).min(v - 1);
            let mut out: Vec<[f64; 3]> = (0..=whole).map(|j| ffd_map(f, nodes, &vert(i, j)).into()).collect();
            let frac = k - whole as f64;
            if frac > 0.0 && whole + 1 < v {
                // The cut end on the straight segment between the mapped vertices (where the cut was made).
                let (a, b) = (Vector3::from(out[whole]), ffd_map(f, nodes, &vert(i, whole + 1)));
                out.push((a * (1.0 - frac) + b * frac).into());
            }
            out
        };
        let mut idx = Vec::new();
        let mut lines = Vec::new();
        // The FFD moves no point farther than the farthest node moved (its weights are a convex combination):
        // a strand whose rest vertices all stay farther than that from the blade's plane on one side, or from
        // the disk, cannot cross it, and is skipped without mapping it through the lattice.
        let reach = nodes.iter().zip(&self.scene.lattice.rest).map(|(x, r)| (x - self.head * r).norm()).fold(0.0, f64::max) + 1e-9;
        let n = Vector3::from(blade.normal).normalize();
        for i in 0..rh.strands() {
            let k = self.kept_len[i];
            if !(k > 0.0) {
                continue;
            }
            let last = (k.ceil() as usize).min(v - 1);
            let (mut above, mut below, mut near, mut seg) = (false, false, f64::INFINITY, 0.0f64);
            for j in 0..=last {
                let r = vert(i, j);
                let d = n.dot(&(r - c));
                above |= d > -reach;
                below |= d < reach;
                near = near.min((r - c).norm());
                if j > 0 {
                    seg = seg.max((r - vert(i, j - 1)).norm());
                }
            }
            if !(above && below) || near > blade.radius + reach + seg {
                continue;
            }
            let l = line(i, k);
            // A crossing at the very end (the strand's cut end lies on this blade) leaves nothing to cut.
            let rest = |(j, _, x): (usize, f64, Vector3<f64>)| (Vector3::from(l[j + 1]) - x).norm() + polyline_length(&l[j + 1..]);
            if blade.first_crossing(&l).is_some_and(|c| rest(c) > 1e-6) {
                idx.push(i);
                lines.push(l);
            }
        }
        let before: Vec<Vec<[f64; 3]>> = lines.clone();
        let Ok(pieces) = cut_polylines(&mut lines, self.lambda, blade) else { return out };
        for p in &pieces {
            let i = idx[p.source];
            let orig = &before[p.source];
            let Some((j, t, _)) = blade.first_crossing(orig) else { continue };
            // Segment j of the polyline is vertex segment j, except a partial last one (from an earlier cut).
            let k_old = self.kept_len[i];
            let whole = k_old.floor() as usize;
            let k_new = (if j >= whole { whole as f64 + (k_old - whole as f64) * t } else { j as f64 + t }).min(k_old);
            out.changes.push((i, k_new));
            rep.strands += 1;
            rep.mass_before += self.lambda * polyline_length(orig);
            rep.mass_kept += self.lambda * polyline_length(&line(i, k_new));
            rep.mass_pieces += p.mass;
        }
        // Falling clusters: at most MAX_PIECES_PER_CUT pieces, sampled evenly, masses scaled to the total.
        let every = pieces.len().div_ceil(MAX_PIECES_PER_CUT).max(1);
        let chosen: Vec<&hairstyle::cut::Piece> = pieces.iter().step_by(every).filter(|p| p.points.len() >= 2).collect();
        let chosen_mass: f64 = chosen.iter().map(|p| p.mass).sum();
        if chosen_mass > 0.0 {
            let scale = rep.mass_pieces / chosen_mass;
            out.pieces = chosen.iter().map(|p| CutPiece { points: p.points.iter().map(|x| Point3::from(*x)).collect(), mass: p.mass * scale }).collect();
        }
        rep.seconds = t0.elapsed().as_secs_f64();
        out.report = rep;
        out
    }
}

/// The tool as a metaball set (world frame): balls along each capsule, spaced at half their radius, whose
/// iso-surface (at the default threshold, 0.707 R for a lone ball) lies 2 cm outside the capsule, so the
/// 5 cm lattice feels it.
pub fn tool_metaballs(shape: &ToolShape, position: &Vector3<f64>, rotation: &Matrix3<f64>) -> MetaballSet {
    let mut balls = Vec::new();
    for c in &shape.capsules {
        let r = (c.radius + 0.02) / 0.707;
        let (a, b) = (rotation * Vector3::from(c.a) + position, rotation * Vector3::from(c.b) + position);
        let n = (((b - a).norm() / (0.5 * r)).ceil() as usize).clamp(1, 64);
        for k in 0..=n {
            let p = a + (b - a) * (k as f64 / n as f64);
            balls.push(Metaball::new(Point3::from(p), r));
        }
    }
    MetaballSet::new(balls)
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
    /// Wetness of each guide as last read from the lattice snapshot, and the version it came from
    /// (u64::MAX: apply again).
    wetness: Vec<f32>,
    wet_version: u64,
    wet_model: WetnessModel,
    /// Scissors closes so far, and whether the primary button was held in the last step.
    cuts: u64,
    was_pressed: bool,
    last_cut_at: Option<Vector3<f64>>,
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
        let interaction = resting_on(&scene, LocalInteraction::new(Vec::new(), Tool::Comb.shape(), pose, Self::force_model(&h, 0.0)));
        Ok(Self {
            scene, params, tool: Tool::Comb, hair_type: h, curliness: 0.0, combing_ease: 0.0, coupling, device: None, strands, active: Vec::new(), interaction,
            hair_force: Vector3::zeros(), wetness: vec![0.0; n], wet_version: u64::MAX, wet_model: WetnessModel::default(), cuts: 0, was_pressed: false, last_cut_at: None, step: 0, last_contacts: 0, last_select: None, clipped: false, rejected: 0, failed: 0,
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
        self.wet_version = u64::MAX;
        match *c {
            Command::SelectTool(t) => {
                self.write_back();
                self.tool = t;
                self.active.clear();
                self.last_select = None;
                self.clipped = false;
                self.interaction = resting_on(&self.scene, LocalInteraction::new(Vec::new(), t.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease)));
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
                self.interaction = resting_on(&self.scene, LocalInteraction::new(Vec::new(), self.tool.shape(), self.interaction.pose, Self::force_model(&h, e)));
            }
            Command::Reset => {
                if let Ok(s) = Self::build_strands(&self.scene, &self.hair_type, self.curliness) {
                    self.strands = s;
                }
                self.active.clear();
                self.last_select = None;
                self.clipped = false;
                self.interaction = resting_on(&self.scene, LocalInteraction::new(Vec::new(), self.tool.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease)));
                self.wet_version = u64::MAX;
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
            self.interaction = resting_on(&self.scene, LocalInteraction::new(strands, self.tool.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease)));
            self.wet_version = u64::MAX;
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
        self.apply_wetness(lattice);
        // Clip: the primary button closes it.
        let pressed = r.buttons & 1 != 0;
        // Scissors: closing the blades (the button going down) cuts the active guides where the blades are,
        // and again each time the held scissors have moved SNIP_DISTANCE (dragging cuts along the path); the
        // global layer cuts the render strands when it sees the count go up (`ToolInput::cuts`).
        let snip = self.tool == Tool::Scissors && pressed && (!self.was_pressed || self.last_cut_at.is_none_or(|p| (p - proxy).norm() > SNIP_DISTANCE));
        if !pressed {
            self.last_cut_at = None;
        }
        if snip {
            self.cuts += 1;
            self.last_cut_at = Some(proxy);
            let blade = ToolInput { position: proxy, rotation: r.rotation, ..Default::default() }.blade();
            for (slot, &g) in self.active.iter().enumerate() {
                let s = &self.interaction.strands[slot];
                if let Ok(Some((m, st, _piece))) = cut_guide(&s.model, &s.state, &blade, 4, g) {
                    if let Ok(mut ns) = Strand::new(m, st.root.clone()) {
                        ns.state = st;
                        ns.integrator = s.integrator;
                        self.interaction.strands[slot] = ns;
                    }
                }
            }
        }
        self.was_pressed = pressed;
        if self.tool == Tool::Clip {
            if pressed && !self.clipped {
                self.clipped = self.interaction.clip(0.01).is_some();
            } else if !pressed && self.clipped {
                self.interaction.release();
                self.clipped = false;
            }
        }
        // The dryer's jet blows on the simulated strands near the tool too: linear air drag on each of
        // DRYER_PIECES pieces per strand (as `GlobalCore` blows on the lattice), held over the step.
        if self.tool == Tool::Dryer && pressed {
            let jet = HairDryer { cone: ToolInput { position: proxy, rotation: r.rotation, ..Default::default() }.cone(HairDryer::default().cone), ..HairDryer::default() };
            for slot in 0..self.interaction.strands.len() {
                let s = &self.interaction.strands[slot];
                let piece = s.model.length / DRYER_PIECES as f64;
                let line = strand::kinematics::centerline(&s.model, &s.state, DRYER_PIECES + 1);
                let loads: Vec<PointForce> = line
                    .windows(2)
                    .map(|w| PointForce::new(0.5 * (w[0].0 + w[1].0), jet.force(&(0.5 * (w[0].1 + w[1].1)), s.model.air_drag * piece)))
                    .filter(|f| f.force != Vector3::zeros())
                    .collect();
                for f in loads {
                    self.interaction.add_load(slot, f);
                }
            }
        }
        let pose = ToolPose { position: proxy, rotation: r.rotation };
        match self.interaction.step(dt, pose) {
            Ok(res) => {
                self.hair_force = res.force * self.params.wisp;
                self.last_contacts = res.contacts.len() as u32;
            }
            Err(_) => {
                self.failed += 1;
                self.hair_force = Vector3::zeros();
                self.last_contacts = 0;
            }
        }
        DeviceCommand { force, torque: Vector3::zeros() }
    }

    /// The wetness model's material and friction for the active strands, from the guides' wetness in the
    /// lattice snapshot (once per lattice version, and after the active set changes): a wet strand is
    /// heavier, softer, and the tool's friction grows (`tools::wetness::WetnessModel`). The friction of the
    /// interaction follows the active guides' mean wetness.
    fn apply_wetness(&mut self, lattice: &LatticeSnapshot) {
        if lattice.version == self.wet_version || lattice.wetness.len() != self.wetness.len() {
            return;
        }
        self.wet_version = lattice.version;
        self.wetness.copy_from_slice(&lattice.wetness);
        let h = self.hair_type;
        let (Ok(dry), Ok(section)) = (h.material(), h.section()) else { return };
        let mut mean = 0.0;
        for (slot, &g) in self.active.iter().enumerate() {
            let w = self.wetness[g] as f64;
            mean += w / self.active.len() as f64;
            if let Ok(m) = self.wet_model.wet(&dry, h.friction_coefficient(), section.area(), w) {
                self.interaction.strands[slot].model.material = m.material();
            }
        }
        if let Ok(m) = self.wet_model.wet(&dry, h.friction_coefficient(), section.area(), mean) {
            self.interaction.model = ForceModel::Constraint { friction: m.friction * (1.0 - 0.8 * self.combing_ease), options: Default::default() };
        }
    }

    /// What the global layer needs of the tool now.
    pub fn tool_input(&self) -> ToolInput {
        ToolInput { tool: self.tool, present: self.device.is_some(), position: self.coupling.proxy, rotation: self.interaction.pose.rotation, pressed: self.was_pressed, cuts: self.cuts }
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
            let pts = samples_along(s, self.scene.guides[g].model.length, samples);
            for (k, p) in pts.into_iter().enumerate() {
                let reference = self.scene.guides[g].reference[k];
                let base = if ok { ffd_map(&self.scene.lattice.ffd, &lattice.positions, &reference) } else { reference };
                let d = p - base;
                // Keep the viewer's displacement sane even if a strand misbehaves.
                out.displacement.push(if d.iter().all(|x| x.is_finite()) && d.norm() < 0.5 { d } else { Vector3::zeros() });
            }
        }
    }

    /// Force last sent to the device, N.
    pub fn force(&self) -> Vector3<f64> {
        self.coupling.force
    }
    /// Guide indices currently simulated.
    pub fn active(&self) -> &[usize] {
        &self.active
    }
    /// Wetness per guide as last read from the lattice snapshot.
    pub fn wetness(&self) -> &[f32] {
        &self.wetness
    }
    /// Length of each active strand, m (shorter than its guide's once cut).
    pub fn active_lengths(&self) -> Vec<f64> {
        self.interaction.strands.iter().map(|s| s.model.length).collect()
    }
}

/// `samples` centreline points of a strand evenly in arc length, root to tip, m.
fn centreline(s: &Strand, samples: usize) -> Vec<Vector3<f64>> {
    hairstyle::generate::sample_strand(&s.model, &s.state, samples).into_iter().map(|p| p.coords).collect()
}

/// `samples` centreline points of a strand at the arc lengths of its uncut guide (`length`, m, evenly from root
/// to tip); past the end of a cut strand, its tip. Equal to [`centreline`] for an uncut strand.
fn samples_along(s: &Strand, length: f64, samples: usize) -> Vec<Vector3<f64>> {
    if s.model.length >= length - 1e-12 {
        return centreline(s, samples);
    }
    let frames = strand::kinematics::segment_frames(&s.model, &s.state);
    (0..samples).map(|k| {
        let at = (k as f64 / (samples - 1).max(1) as f64 * length).min(s.model.length);
        strand::kinematics::frame_at(&s.model, &s.state.q, &frames, at).position
    }).collect()
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
    global: Option<JoinHandle<GlobalRun>>,
    haptic: Option<HapticLoop<VirtualDevice>>,
    record: Arc<std::sync::Mutex<Option<Record>>>,
}

impl Session {
    /// Starts both threads on `scene`.
    pub fn start(scene: Arc<Scene>, params: SessionParams) -> Result<(Session, SessionIo), SessionError> {
        params.validate()?;
        let mut core = HapticCore::new(scene.clone(), params)?;
        let mut global = GlobalCore::new(scene.clone(), &params);
        let rest = global.snapshot();
        let (mut tool_in, mut tool_out) = triple_buffer(&ToolInput::default());
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
        let recording = params.record;
        global.defer_cuts(true);
        let global_thread = std::thread::Builder::new().name("coiffure-global".into()).spawn(move || {
            let (mut steps, mut busy, mut recov) = (0u64, 0.0f64, 0u64);
            // Scissors cuts run on a worker thread (one at a time) and are swapped in when done, so a cut of
            // 100k strands does not stall the lattice. (The haptic forces do not depend on them.)
            let mut cutting: Option<JoinHandle<CutResult>> = None;
            let mut resets = Vec::new();
            let mut inputs = Vec::new();
            let mut seen_epoch = 0;
            let start = Instant::now();
            while !stop_g.load(Ordering::Relaxed) {
                let e = epoch_g.load(Ordering::Acquire);
                if e != seen_epoch {
                    seen_epoch = e;
                    global.reset();
                    resets.push(global.version + 1);
                }
                let input = *tool_out.read();
                if recording {
                    inputs.push(input);
                }
                let (mut snap, bad) = global.step(gdt, &input);
                if cutting.as_ref().is_some_and(|h| h.is_finished()) {
                    if let Some(Ok(r)) = cutting.take().map(|h| h.join()) {
                        if global.apply_cut(r).is_some() {
                            let secs = snap.step_seconds;
                            snap = global.snapshot();
                            snap.step_seconds = secs;
                        }
                    }
                }
                if cutting.is_none() {
                    if let Some(b) = global.take_pending_cut() {
                        let job = global.cut_job(&b);
                        cutting = std::thread::Builder::new().name("coiffure-cut".into()).spawn(move || job.run()).ok();
                    }
                }
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
            GlobalRun { steps, mean: busy / steps.max(1) as f64, recoveries: recov, resets, inputs }
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
            tool_in.write(core.tool_input());
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
        let on_refused = |why: String| tracing::warn!("haptic thread: {why}");
        let haptic = HapticLoop::spawn_with_priority(params.haptic_rate_hz, dev, step, None, params.haptic_priority, on_refused)
            .map_err(SessionError::Start)?;
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
        let g = self.global.take().expect("running").join().expect("the global thread panicked");
        let mut record = self.record.lock().map(|mut g| g.take()).unwrap_or(None);
        if let Some(r) = record.as_mut() {
            r.global_resets = g.resets;
            r.global_inputs = g.inputs;
        }
        SessionReport { haptic, global_steps: g.steps, global_step_mean: g.mean, global_recoveries: g.recoveries, record }
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

/// What the global thread returns when it ends.
struct GlobalRun {
    steps: u64,
    mean: f64,
    recoveries: u64,
    resets: Vec<u64>,
    inputs: Vec<ToolInput>,
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
/// the global steps read the recorded tool inputs (dryer jet, sprayer and dryer wetness, scissors cuts, the tool
/// pushing the lattice), and the haptic core steps with the recorded reading. Returns the force of every step.
pub fn replay(scene: Arc<Scene>, params: SessionParams, record: &Record) -> Result<Vec<Vector3<f64>>, SessionError> {
    let mut core = HapticCore::new(scene.clone(), params)?;
    let mut global = GlobalCore::new(scene, &params);
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
            // The tool input that global step read (none in a version-1 record).
            let input = record.global_inputs.get(global.version as usize).copied().unwrap_or_default();
            snap = global.step(gdt, &input).0;
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
        let snap = GlobalCore::new(scene, &SessionParams::default()).snapshot();
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
        // comb stroke down the back of the head at 0.1 m/s, then the sprayer held on the hair, then the
        // scissors closed once, and a reset on the way. Its record (through the file format, version 2 with
        // the global steps' tool inputs) replayed in lockstep on one thread gives every haptic step's force
        // again within 1e-9 N (in fact bit for bit), although the live threads' timing was whatever the
        // machine gave them.
        let scene = small_scene();
        let params = SessionParams { record: true, ..SessionParams::default() };
        let (session, mut io) = Session::start(scene.clone(), params).unwrap();
        let rot = test_rot();
        // The path follows the haptic thread's own step count (published every 5 steps), so the test does
        // not depend on how fast this machine runs the threads.
        let (mut sprayer, mut scissors, mut reset) = (false, false, false);
        loop {
            let step = io.haptic.read().step;
            if step >= 1800 {
                break;
            }
            let t = step as f64 * 1e-3;
            let z = 0.05 - 0.1 * t.min(1.0);
            let buttons = ((700..1000).contains(&step) || (1200..1300).contains(&step)) as u32;
            io.device.push(DeviceReading { time: t, position: Vector3::new(0.0, -0.118, z), rotation: rot, buttons });
            if step > 650 && !sprayer {
                io.commands.send(Command::SelectTool(Tool::Sprayer)).unwrap();
                sprayer = true;
            }
            if step > 1100 && !scissors {
                io.commands.send(Command::SelectTool(Tool::Scissors)).unwrap();
                scissors = true;
            }
            if step > 1500 && !reset {
                io.commands.send(Command::Reset).unwrap();
                reset = true;
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        let report = session.stop();
        eprintln!("live: {:?}, global steps {}", report.haptic, report.global_steps);
        let rec = report.record.expect("recorded");
        assert!(rec.steps.len() >= 1800, "{} steps", rec.steps.len());
        assert_eq!(rec.global_resets.len(), 1, "one lattice reset recorded");
        assert_eq!(rec.steps.iter().map(|s| s.commands.len()).sum::<usize>(), 3);
        assert_eq!(rec.global_inputs.len() as u64, report.global_steps);
        assert!(rec.global_inputs.iter().any(|g| g.tool == Tool::Sprayer && g.pressed), "the sprayer sprayed");
        assert_eq!(rec.global_inputs.last().map(|g| g.cuts), Some(1), "one scissors close");
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

    /// The tool rotation of the tests: x along -x, y along -z (strokes downwards), z along -y (nozzles aim
    /// along +y, at the back of the head).
    fn test_rot() -> Matrix3<f64> {
        Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)])
    }

    #[test]
    fn sprayer_raises_and_dryer_lowers_wetness_in_the_cone_only() {
        // The nozzle 0.35 m behind the head (0.15 m behind the tool point) aims at it (+y). Every guide segment whose centre is in the cone
        // at the end gets wetter (sprayer) or drier (dryer); every segment outside the cone widened by
        // 0.15 rad keeps its wetness exactly (the lattice moves a little meanwhile, hence the margin).
        let scene = small_scene();
        let params = SessionParams::default();
        let spray = ToolInput { tool: Tool::Sprayer, present: true, position: Vector3::new(0.0, -0.2, 0.0), rotation: test_rot(), pressed: true, cuts: 0 };
        for (tool, start) in [(Tool::Sprayer, 0.0), (Tool::Dryer, 0.5)] {
            let mut g = GlobalCore::new(scene.clone(), &params);
            g.set_wetness(start);
            let input = ToolInput { tool, ..spray };
            for _ in 0..100 {
                g.step(0.01, &input);
            }
            let cone = input.cone(if tool == Tool::Sprayer { Sprayer::default().cone } else { HairDryer::default().cone });
            let wide = Cone { half_angle: cone.half_angle + 0.15, range: cone.range + 0.02, ..cone };
            let (mut inside, mut outside) = (0, 0);
            for (gi, cs) in g.centres_now().iter().enumerate() {
                for (k, x) in cs.iter().enumerate() {
                    let w = g.wetness().values[gi][k];
                    if cone.weight(x).0 > 0.05 {
                        inside += 1;
                        if tool == Tool::Sprayer {
                            assert!(w > start + 1e-3, "sprayed segment {gi}/{k}: {w}");
                        } else {
                            assert!(w < start - 1e-4, "dried segment {gi}/{k}: {w}");
                        }
                    } else if wide.weight(x).0 == 0.0 {
                        outside += 1;
                        assert_eq!(w, start, "segment {gi}/{k} outside the cone changed");
                    }
                }
            }
            let snap = g.snapshot();
            let mean = snap.wetness.iter().map(|&w| w as f64).sum::<f64>() / snap.wetness.len() as f64;
            eprintln!("{tool:?}: {inside} segments in the cone, {outside} outside; mean guide wetness {start} -> {mean}");
            assert!(inside >= 5 && outside >= 20, "{inside} in, {outside} out");
            assert!(if tool == Tool::Sprayer { mean > start } else { mean < start });
        }
    }

    /// Peak and mean force (N) of a comb stroke down the back of the head, 0.1 m/s for 1.5 s at depth y (m),
    /// with every guide at wetness w; the first 0.2 s (the coupling's start) are left out.
    fn comb_stroke(scene: &Arc<Scene>, w: f64, y: f64) -> (f64, f64) {
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        g.set_wetness(w);
        let snap = g.snapshot();
        let (mut peak, mut sum): (f64, f64) = (0.0, 0.0);
        for n in 0..1500 {
            let t = n as f64 * 1e-3;
            let p = Vector3::new(0.0, y, 0.05 - 0.1 * t);
            let c = core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3);
            if n >= 200 {
                peak = peak.max(c.force.norm());
                sum += c.force.norm() / 1300.0;
            }
        }
        (peak, sum)
    }

    #[test]
    fn the_dryer_blows_the_simulated_strands_along_its_jet() {
        // The dryer held still 15 cm behind the hair at the back of the head (its jet along the tool's -z,
        // here +y), blowing or not for 0.6 s. The jet's air drag (DEFAULT_AIR_DRAG x 10 m/s in the jet's
        // core, about the weight of a hair per metre) pushes the simulated strands along the jet: their
        // tips' mean displacement along +y against the still run is over 5 mm, and nothing goes non-finite.
        let scene = small_scene();
        let run = |blow: bool| {
            let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
            core.apply(&Command::SelectTool(Tool::Dryer));
            let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
            for n in 0..600 {
                let p = Vector3::new(0.0, -0.118, 0.0);
                core.step(Some(DeviceReading { time: n as f64 * 1e-3, position: p, rotation: test_rot(), buttons: blow as u32 }), &snap, 1e-3);
            }
            let tips: Vec<Vector3<f64>> = core.interaction.strands.iter().map(|s| strand::kinematics::centerline(&s.model, &s.state, 2)[1].1).collect();
            (core.active.clone(), tips)
        };
        let ((still_active, still), (blown_active, blown)) = (run(false), run(true));
        assert_eq!(still_active, blown_active, "the same strands near the tool");
        assert!(!still.is_empty());
        let along: Vec<f64> = still.iter().zip(&blown).map(|(a, b)| (b - a).y).collect();
        let mean = along.iter().sum::<f64>() / along.len() as f64;
        eprintln!("dryer: tips moved along the jet by {along:?} m (mean {mean} m)");
        assert!(blown.iter().all(|t| t.iter().all(|x| x.is_finite())));
        assert!(mean > 5e-3, "mean tip displacement along the jet {mean} m");
    }

    #[test]
    fn a_scene_carries_the_render_strands_of_a_file() {
        // The built-in scene's own render strands, written as curves (what the viewer's Save gives, 3 of
        // them reversed into odd shapes), make a scene: same strand count, each strand keeps its root and tip
        // (1e-6 m), is bound to its nearest guides with weights summing to 1 (1e-6), and a live session runs
        // on it with finite lattice positions. Empty files and non-finite points are refused by name.
        let opts = SceneOptions { render_strands: 500, guides: 40, ..SceneOptions::default() };
        let built = Scene::builtin(&opts).unwrap();
        let v = built.render.vertices_per_strand;
        let mut strands: Vec<Vec<[f32; 3]>> = built.render.positions.chunks(v).map(|c| c.to_vec()).collect();
        strands[0].truncate(3);
        strands[1].push([0.0, -0.3, -0.3]);
        strands[2] = vec![strands[2][0]];
        let scene = Scene::from_curves(&hairstyle::HairCurves::from_strands(strands.clone()), &opts).unwrap();
        assert_eq!(scene.render.strands(), strands.len());
        assert_eq!(scene.render.vertices_per_strand, opts.render_vertices);
        let k = scene.render.guides_per_strand;
        for (i, st) in strands.iter().enumerate() {
            let got = &scene.render.positions[i * opts.render_vertices..(i + 1) * opts.render_vertices];
            let d = |a: [f32; 3], b: [f32; 3]| (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f32>().sqrt();
            assert!(d(got[0], st[0]) < 1e-6 && d(got[got.len() - 1], st[st.len() - 1]) < 1e-6, "strand {i} ends");
            let w: f32 = scene.render.weight[i * k..(i + 1) * k].iter().sum();
            assert!((w - 1.0).abs() < 1e-6, "strand {i} weights sum to {w}");
            let root = Vector3::new(st[0][0] as f64, st[0][1] as f64, st[0][2] as f64);
            let nearest = (0..scene.guides.len()).min_by(|&a, &b| (scene.guides[a].state.root.position - root).norm().total_cmp(&(scene.guides[b].state.root.position - root).norm())).unwrap();
            assert_eq!(scene.render.guide[i * k] as usize, nearest, "strand {i} follows its nearest guide first");
        }
        let scene = Arc::new(scene);
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        for _ in 0..20 {
            g.step(0.01, &ToolInput::default());
        }
        assert!(g.positions().iter().all(|p| p.coords.iter().all(|x| x.is_finite())));
        let empty = Scene::from_curves(&hairstyle::HairCurves::from_strands(vec![]), &opts).unwrap_err().to_string();
        assert!(empty.contains("1 to 10,000,000 strands"), "{empty}");
        let mut nan = strands;
        nan[7][1][2] = f32::NAN;
        let e = Scene::from_curves(&hairstyle::HairCurves::from_strands(nan), &opts).unwrap_err().to_string();
        assert!(e.contains("strand 7 point 1"), "{e}");
    }

    #[test]
    fn the_simulated_strands_rest_on_the_head_when_the_comb_presses_them() {
        // The comb pushed from the hair at the back of the head 6 cm towards the head's centre over 0.6 s,
        // then held. The simulated strands' centrelines (64 samples each) then lie no deeper than 2 mm inside
        // the body (depth to the surface; the contacts hold the collision pieces' ends, and the centreline may
        // dip between them: 1.3 mm measured); without the body contact the same push drives them 14.8 mm deep,
        // so the check can fail (asserted > 5 mm).
        let scene = small_scene();
        let deepest = |body: bool| {
            let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
            let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
            let mut worst: f64 = 0.0;
            for n in 0..900 {
                let t = n as f64 * 1e-3;
                let p = Vector3::new(0.0, -0.13 + 0.06 * (t / 0.6).min(1.0), 0.0);
                core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3);
                if !body {
                    core.interaction.body = None;
                }
                if n % 100 == 99 {
                    let t = scene.lattice.params.metaball.threshold;
                    for s in &core.interaction.strands {
                        for (_, x) in strand::kinematics::centerline(&s.model, &s.state, 64) {
                            let q = scene.head.push_out(&x.into(), t, 0.0).coords;
                            worst = worst.max((q - x).norm());
                        }
                    }
                }
            }
            worst
        };
        let (with, without) = (deepest(true), deepest(false));
        eprintln!("deepest centreline point inside the body: {with} m with the body contact, {without} m without");
        assert!(with <= 2e-3, "{with} m inside the body");
        assert!(without > 5e-3, "without the body contact the check must be able to fail: {without} m");
    }

    #[test]
    fn the_comb_feels_heavier_through_wet_hair() {
        // Wet hair (WetnessModel: heavier, softer, 7.5 x the friction) resists the same stroke more.
        let scene = small_scene();
        let (dry, wet) = (comb_stroke(&scene, 0.0, -0.118), comb_stroke(&scene, 1.0, -0.118));
        eprintln!("comb force dry: peak {} N, mean {} N; wet: peak {} N, mean {} N", dry.0, dry.1, wet.0, wet.1);
        assert!(dry.0 > 1e-4, "the dry stroke is felt: {} N", dry.0);
        assert!(wet.0 > 2.0 * dry.0, "peak wet {} N vs dry {} N", wet.0, dry.0);
        assert!(wet.1 > dry.1, "mean wet {} N vs dry {} N", wet.1, dry.1);
    }

    #[test]
    fn scissors_shorten_the_render_strands_and_the_pieces_fall_to_rest() {
        // A horizontal cut through the hair at the back of the head. Mass: for the cut strands, the pieces'
        // mass plus the mass kept on the head (from the kept lengths the session stores) equals the mass
        // before, to 1e-9 relative; the falling clusters carry the pieces' mass (1e-9 relative). Then the
        // clusters fall: after 4 s they are at rest (kinetic energy < 1e-7 J) and above the floor.
        // The lattice is deformed first (the comb held in the hair for 0.2 s), so the cut is of the FFD's shape.
        let scene = small_scene();
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        let comb = ToolInput { tool: Tool::Comb, present: true, position: Vector3::new(0.0, -0.13, 0.0), rotation: test_rot(), pressed: false, cuts: 0 };
        for _ in 0..20 {
            g.step(0.01, &comb);
        }
        let v = scene.render.vertices_per_strand;
        let blade = Blade { point: [0.0, -0.12, -0.05], normal: [0.0, 0.0, 1.0], radius: 0.08 };
        let rep = g.cut(&blade);
        eprintln!("{rep:?}");
        assert!(rep.strands > 50, "{} strands cut", rep.strands);
        assert!(((rep.mass_kept + rep.mass_pieces) - rep.mass_before).abs() <= 1e-9 * rep.mass_before, "{rep:?}");
        assert!((rep.mass_clusters - rep.mass_pieces).abs() <= 1e-9 * rep.mass_pieces, "{rep:?}");
        assert!(rep.pieces > 0 && rep.pieces <= MAX_PIECES_PER_CUT);
        let snap = g.snapshot();
        assert_eq!(g.kept_lengths().iter().filter(|&&k| k < (v - 1) as f64).count(), rep.strands);
        assert!(snap.kept.iter().filter(|&&k| (k as usize) < v).count() > rep.strands / 2);
        assert!(g.kept_lengths().iter().all(|&k| k >= 0.0 && k <= (v - 1) as f64));
        assert!(!snap.chains.is_empty());
        // A second cut at the same place cuts nothing more; a cut higher up cuts the same strands again.
        assert_eq!(g.cut(&blade).strands, 0);
        let mass0 = g.cluster_mass();
        for _ in 0..400 {
            g.step(0.01, &ToolInput::default());
        }
        let e = g.cluster_energy();
        let low = g.snapshot().chains.iter().flatten().map(|p| p[2] as f64).fold(f64::INFINITY, f64::min);
        eprintln!("after 4 s: cluster energy {e} J, lowest point {low} m (floor {} m)", g.floor());
        assert!((g.cluster_mass() - mass0).abs() <= 1e-12 * mass0);
        assert!(e < 1e-7, "clusters at rest: {e} J");
        assert!(low >= g.floor() - 1e-6, "above the floor: {low}");
    }

    #[test]
    fn a_cut_on_a_worker_gives_the_same_strands_as_at_once() {
        // The live session defers cuts to a worker thread: the same blade gives the same kept lengths; a reset
        // between taking the job and applying it drops the result.
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut now, mut later) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        later.defer_cuts(true);
        let input = ToolInput { tool: Tool::Scissors, present: true, position: Vector3::new(0.0, -0.12, -0.05), rotation: test_rot(), pressed: true, cuts: 1 };
        now.step(0.01, &ToolInput { cuts: 0, ..input });
        later.step(0.01, &input);
        let v0 = later.kept_version();
        let blade = later.take_pending_cut().expect("queued");
        now.cut(&blade);
        assert!(later.take_pending_cut().is_none());
        let job = later.cut_job(&blade);
        let r = std::thread::spawn(move || job.run()).join().unwrap();
        let rep = later.apply_cut(r).expect("applied");
        assert_eq!(later.kept_version(), v0 + 1);
        assert!(rep.strands > 50);
        assert!(now.kept_lengths() == later.kept_lengths(), "the same kept lengths");
        let job = later.cut_job(&Blade { point: [0.0, -0.12, -0.02], ..blade });
        later.reset();
        assert!(later.apply_cut(job.run()).is_none(), "a reset drops the pending cut");
    }

    #[test]
    fn lattice_nodes_thrown_at_the_head_stay_outside_the_body() {
        // Every node that starts outside the body is thrown at the head's centre at 10 m/s: after each step,
        // none of them is inside the body (metaball field above the threshold by more than 1e-9). The same
        // throw without the push-out does put nodes inside (so the test can fail).
        let scene = small_scene();
        let run = |push: bool| -> (usize, f64) {
            let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
            let t = g.model.params.metaball.threshold;
            let outside = g.outside.clone();
            for (i, x) in g.state.positions.clone().iter().enumerate() {
                if outside[i] && x.coords.norm() > 1e-9 {
                    g.state.velocities[i] = -x.coords.normalize() * 10.0;
                }
            }
            if !push {
                g.outside.iter_mut().for_each(|o| *o = false);
            }
            let mut worst = f64::NEG_INFINITY;
            for _ in 0..20 {
                g.step(0.01, &ToolInput::default());
                for (i, x) in g.state.positions.iter().enumerate() {
                    if outside[i] {
                        worst = worst.max(scene.head.field(x) - t);
                    }
                }
            }
            (outside.iter().filter(|&&o| o).count(), worst)
        };
        let ((outside, worst), (_, without)) = (run(true), run(false));
        eprintln!("{outside} nodes outside the body at rest; largest field above the surface {worst} (without the push-out {without})");
        assert!(outside > 100);
        assert!(without > 1e-4, "the throw reaches the body: {without}");
        assert!(worst <= 1e-9, "a node went into the body: field {worst} above the threshold");
    }

    /// Pushes one mouse reading every 5 ms for each k of `ks` (position in m and buttons from `at(k)`,
    /// the tests' tool rotation, time 5 ms k) into a live session, waiting 5 ms between readings.
    fn hold(io: &mut SessionIo, ks: std::ops::Range<usize>, at: impl Fn(usize) -> (Vector3<f64>, u32)) {
        for k in ks {
            let (position, buttons) = at(k);
            io.device.push(DeviceReading { time: k as f64 * 0.005, position, rotation: test_rot(), buttons });
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn after_a_scissors_drag_the_session_takes_the_next_tool() {
        // The browser's sequence: the scissors closed and dragged across the back of the head (a cut every
        // 2 cm, on the worker thread), released, then the sprayer selected and held. The haptic thread must
        // still take commands: its snapshot reports the sprayer and the sprayer wets the guides.
        let scene = small_scene();
        let (session, mut io) = Session::start(scene.clone(), SessionParams::default()).unwrap();
        io.commands.send(Command::SelectTool(Tool::Scissors)).unwrap();
        hold(&mut io, 0..300, |k| (Vector3::new(0.05 - 0.1 * (k as f64 / 300.0), -0.1, -0.06), (k < 280) as u32));
        let cuts = io.lattice.read().kept_version;
        io.commands.send(Command::SelectTool(Tool::Sprayer)).unwrap();
        hold(&mut io, 300..700, |_| (Vector3::new(0.0, -0.1, 0.0), 1));
        let h = io.haptic.read().clone();
        let l = io.lattice.read().clone();
        let sum = l.wetness.iter().sum::<f32>();
        eprintln!("kept version after the scissors {cuts}; tool {} step {} wetness summed over guides {sum}", h.tool, h.step);
        let report = session.stop();
        assert!(cuts > 0, "the scissors cut");
        assert_eq!(h.tool, Tool::Sprayer as u8, "the haptic thread took the sprayer");
        assert!(h.step > 3000, "the haptic loop kept running: {} steps", h.step);
        assert!(sum > 0.1, "wetness summed over the guides {sum}");
        assert!(report.haptic.steps > 3000);
    }

    #[test]
    fn the_live_sprayer_wets_the_guides() {
        // A live session: the sprayer held (button down) at the back of the head for 2 s wets the guides the
        // lattice snapshot reports.
        let scene = small_scene();
        let (session, mut io) = Session::start(scene.clone(), SessionParams::default()).unwrap();
        io.commands.send(Command::SelectTool(Tool::Sprayer)).unwrap();
        hold(&mut io, 0..400, |_| (Vector3::new(0.0, -0.1, 0.0), 1));
        let h = io.haptic.read().clone();
        let l = io.lattice.read().clone();
        let sum = l.wetness.iter().sum::<f32>();
        eprintln!("tool {} step {} version {} wetness summed over guides {sum}", h.tool, h.step, l.version);
        session.stop();
        assert_eq!(h.tool, Tool::Sprayer as u8);
        assert!(sum > 0.1, "wetness summed over the guides {sum}");
    }

    #[test]
    fn the_tool_pushes_the_lattice_and_does_not_drag_it() {
        // Two lattices side by side, one with the comb held still in the hair behind the head. Relative to
        // the free one: every node the comb touches (its metaball field at the free position >= 0.1, the
        // surface being at 0.25) ends where the comb's field is lower (pushed out, never pulled in); the
        // whole lattice moves less than 3 cm (the lost helper's attraction dragged hair 0.37 m); and once
        // the comb leaves, the hair goes back.
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut free, mut pushed) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        let tool = Vector3::new(0.0, -0.13, 0.0);
        let input = ToolInput { tool: Tool::Comb, present: true, position: tool, rotation: test_rot(), pressed: false, cuts: 0 };
        let balls = tool_metaballs(&Tool::Comb.shape(), &tool, &test_rot());
        for _ in 0..30 {
            free.step(0.01, &ToolInput::default());
            pushed.step(0.01, &input);
        }
        let (mut touched, mut most) = (0, 0.0f64);
        for (a, b) in pushed.positions().iter().zip(free.positions()) {
            most = most.max((a - b).norm());
            let (fa, fb) = (balls.field(a), balls.field(b));
            if fb >= 0.1 {
                touched += 1;
                assert!(fa < fb, "a touched node is pushed out of the comb: field {fb} -> {fa}");
            }
        }
        eprintln!("{touched} nodes touched, largest difference {most} m");
        assert!(touched >= 1 && most > 2e-3, "the comb pushes the hair: {touched} nodes, {most} m");
        assert!(most < 0.03, "no drag: {most} m");
        for _ in 0..200 {
            free.step(0.01, &ToolInput::default());
            pushed.step(0.01, &ToolInput::default());
        }
        let after = pushed.positions().iter().zip(free.positions()).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        eprintln!("largest difference {after} m 2 s after the comb left");
        assert!(after < 0.2 * most, "the hair goes back: {after} m vs {most} m");
    }

    #[test]
    fn closing_the_scissors_cuts_the_active_guides_and_counts_the_cut() {
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        core.apply(&Command::SelectTool(Tool::Scissors));
        let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
        let p = Vector3::new(0.0, -0.118, -0.03);
        for n in 0..200 {
            let buttons = (n >= 100) as u32;
            core.step(Some(DeviceReading { time: n as f64 * 1e-3, position: p, rotation: test_rot(), buttons }), &snap, 1e-3);
        }
        assert_eq!(core.tool_input().cuts, 1);
        let lens = core.active_lengths();
        let full = scene.guides[0].model.length;
        eprintln!("active lengths after the cut {lens:?} (guides {full} m)");
        assert!(!lens.is_empty() && lens.iter().any(|&l| l < full - 1e-3), "{lens:?}");
        let mut hs = HapticSnapshot::default();
        core.snapshot(&snap, 1e-3, &mut hs);
        assert_eq!(hs.displacement.len(), hs.active.len() * scene.samples());
        assert!(hs.displacement.iter().all(|d| d.norm() < 0.5));
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
        // A version-1 file (no global inputs: magic CFREC1 and no count after the resets) still loads.
        let mut v1 = b"CFREC1\0\0".to_vec();
        v1.extend_from_slice(&b[8..24 + 8 * r.global_resets.len()]);
        v1.extend_from_slice(&b[32 + 8 * r.global_resets.len()..]);
        assert_eq!(Record::from_bytes(&v1).unwrap(), r);
        r.global_inputs.push(ToolInput { tool: Tool::Scissors, present: true, pressed: true, cuts: 3, ..ToolInput::default() });
        let b = r.to_bytes();
        assert_eq!(Record::from_bytes(&b).unwrap(), r);
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(matches!(Record::from_bytes(&bad), Err(crate::record::RecordError::Bad { offset: 0, .. })));
    }
}
