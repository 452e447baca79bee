//! The scene (model: immutable once built, shared by the threads): head, render hair, guides and lattice.
//! Built from the built-in hairstyle ([`builtin`]) or from a file's curves ([`from_curves`]); where the render
//! strands are now ([`render`]: [`Scene::render_curves`]).

mod builtin;
mod from_curves;
mod render;

pub use from_curves::{LoadLimits, MAX_LATTICE_NODES};
pub use render::GuideDisplacements;

use lattice::ffd::FfdLattice;
use lattice::lattice::LatticeModel;
use lattice::metaball::MetaballSet;
use nalgebra::{Point3, Vector3};
use strand::{HairType, StrandModel};

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
    /// Whether the groomed state is a stable equilibrium of the sag-free model under gravity (the hairstyle
    /// generator's statics flag, `hairstyle::Guide::stable`).
    pub stable: bool,
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
    /// Bounds on a loaded hairstyle ([`Scene::from_curves`], `coiffure serve`'s LOAD). Default [`LoadLimits::default`].
    pub load: LoadLimits,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self { render_strands: 100_000, render_vertices: 12, guides: 200, segments: 8, samples: 16, length: 0.2, curliness: 0.0, cell: 0.05, hair_type: "caucasian".into(), seed: 1, load: LoadLimits::default() }
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
    /// Samples per guide centreline.
    pub fn samples(&self) -> usize {
        self.guides.first().map_or(0, |g| g.reference.len())
    }
}

/// FFD of a head-frame point through lattice nodes (clamped to the embedded volume;
/// [`FfdLattice::deform_clamped`]), m; the point itself if the nodes are not the lattice's.
pub fn ffd_map(ffd: &FfdLattice, nodes: &[Point3<f64>], p: &Vector3<f64>) -> Vector3<f64> {
    ffd.deform_clamped(&Point3::from(*p), nodes).unwrap_or(*p)
}
