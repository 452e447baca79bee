//! The scene (model: immutable once built, shared by the threads): head, render hair, guides and lattice.
//! Built from the built-in hairstyle ([`builtin`]) or from a file's curves ([`from_curves`]); where the render
//! strands are now ([`render`]: [`Scene::render_curves`]); the one law of hair carried by the head and the
//! lattice ([`carried`]).

mod builtin;
mod from_curves;
mod render;
#[cfg(test)]
mod loaded_tests;

pub use from_curves::{LoadLimits, LoadReport, MAX_LATTICE_NODES};
pub use render::GuideDisplacements;

use lattice::ffd::FfdLattice;
use lattice::lattice::LatticeModel;
use lattice::metaball::MetaballSet;
use nalgebra::{Isometry3, Point3, Vector3};
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
    /// Follow strands drawn around each strand of a loaded hairstyle (`hairstyle::follow`; `[live.fit]
    /// follow_strands`, the viewer's load bar, `coiffure fit --follow-strands`). Default None: as many as
    /// bring the drawn strands to `render_strands` (none for a file with that many), within
    /// `load.max_strands`.
    pub follow_strands: Option<usize>,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self { render_strands: 100_000, render_vertices: 12, guides: 200, segments: 8, samples: 16, length: 0.2, curliness: 0.0, cell: 0.05, hair_type: "caucasian".into(), seed: 1, load: LoadLimits::default(), follow_strands: None }
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
    /// Length of hair from the root over which the head's hold gives way to the lattice's motion, m
    /// ([`root_hold_weight`]; `HairLatticeParams::root_hold`).
    pub root_hold: f64,
}

impl Scene {
    /// Samples per guide centreline.
    pub fn samples(&self) -> usize {
        self.guides.first().map_or(0, |g| g.reference.len())
    }

    /// Weight of the lattice's motion at each reference sample of guide `g` ([`root_hold_weight`] of its
    /// arc length from the root: the samples are even in arc length over the guide's length).
    pub fn guide_hold_weights(&self, g: usize) -> Vec<f64> {
        let guide = &self.guides[g];
        let n = guide.reference.len();
        (0..n).map(|k| root_hold_weight(k as f64 / (n - 1).max(1) as f64 * guide.model.length, self.root_hold)).collect()
    }

    /// Guide `g`'s reference samples carried by the head at `head` and the lattice `nodes` now, by the one law
    /// of the carried hair ([`carry_strand`]), m (world).
    pub fn guide_points(&self, nodes: &[Point3<f64>], head: &Isometry3<f64>, g: usize) -> Vec<Vector3<f64>> {
        let mut out = Vec::new();
        carry_strand(&self.lattice.ffd, nodes, head, &self.guides[g].reference, &self.guide_hold_weights(g), &mut out);
        out
    }

    /// [`Scene::guide_points`] one at a time, root first ([`CarriedPoints`]), `weights` being
    /// [`Scene::guide_hold_weights`] of guide `g`.
    pub fn guide_points_each<'a>(&'a self, nodes: &'a [Point3<f64>], head: &'a Isometry3<f64>, g: usize, weights: &'a [f64]) -> CarriedPoints<'a> {
        CarriedPoints::new(&self.lattice.ffd, nodes, head, &self.guides[g].reference, weights)
    }
}

/// Weight of the lattice's motion, in [0, 1], at rest arc length `s` (m) from a strand's root, the head
/// holding the first `hold` m (m; 0: none): 0 at the root, rising as the smoothstep 3x^2 - 2x^3 of
/// x = s / hold to 1 at `hold` and beyond (C1, as GLSL's `smoothstep(0, hold, s)`).
pub fn root_hold_weight(s: f64, hold: f64) -> f64 {
    if !(hold > 0.0) {
        return 1.0;
    }
    let x = (s / hold).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Where the global layer puts a rest point `p` (head frame, m) whose lattice weight is `w` ([`root_hold_weight`]
/// of its arc length from its root): `H p + w (FFD(p) - H p)`, H the head pose (head frame to world) and FFD the
/// lattice's map through the nodes `nodes` ([`ffd_map`]), m (world): the head's rigid motion at the root,
/// the lattice's from `Scene::root_hold` on. The lattice at rest (its nodes at H of their rest) gives H p for
/// every w, since the FFD reproduces affine maps. The target of a strand point in [`carry_strand`].
pub fn carried(ffd: &FfdLattice, nodes: &[Point3<f64>], head: &Isometry3<f64>, p: &Vector3<f64>, w: f64) -> Vector3<f64> {
    let rigid = (head * Point3::from(*p)).coords;
    if w <= 0.0 {
        return rigid;
    }
    rigid + (ffd_map(ffd, nodes, p) - rigid) * w
}

/// Follow the leader (Mueller, Kim and Chentanez, "Fast simulation of inextensible hair and fur", VRIPHYS
/// 2012): `points` hold each strand point's target (m, world), root first; the root stays on its target and
/// each next point is put at its rest distance from the previous one (`rest`: the rest points, m), towards its
/// target (along the rest segment turned by the head `head` if the target is on the previous point). The
/// strand then has its rest segment lengths exactly, whatever the targets.
pub fn follow_the_leader(rest: &[Vector3<f64>], head: &Isometry3<f64>, points: &mut [Vector3<f64>]) {
    for k in 1..points.len().min(rest.len()) {
        points[k] = lead(&points[k - 1], &points[k], &rest[k - 1], &rest[k], head);
    }
}

/// One point of [`follow_the_leader`]: the point after `previous` (m, world) towards its `target` (m, world), at
/// the rest distance from `rest_before` to `rest_here` (m, head frame), along that rest segment turned by `head`
/// if the target is on `previous`.
fn lead(previous: &Vector3<f64>, target: &Vector3<f64>, rest_before: &Vector3<f64>, rest_here: &Vector3<f64>, head: &Isometry3<f64>) -> Vector3<f64> {
    let length = (rest_here - rest_before).norm();
    let to = target - previous;
    let dir = if to.norm() > 1e-12 { to / to.norm() } else { (head.rotation * (rest_here - rest_before)).try_normalize(0.0).unwrap_or_else(Vector3::zeros) };
    previous + dir * length
}

/// [`carry_strand`]'s points one at a time, root first: each target ([`carried`]) then its [`follow_the_leader`]
/// point, the same operations on the same numbers (so the same points), for a caller that may stop before the
/// tip (the choice of the local strands passes over the rest of a guide that cannot come near the tool). Point k
/// is within the rest length from sample k to sample j of point j (the segments keep their rest lengths).
pub struct CarriedPoints<'a> {
    ffd: &'a FfdLattice,
    nodes: &'a [Point3<f64>],
    head: &'a Isometry3<f64>,
    rest: &'a [Vector3<f64>],
    weights: &'a [f64],
    next: usize,
    last: Vector3<f64>,
}

impl<'a> CarriedPoints<'a> {
    /// The points of the strand of rest points `rest` (head frame, root first, m) with the lattice weights
    /// `weights`, carried by the head at `head` and the lattice `nodes` ([`carry_strand`]).
    pub fn new(ffd: &'a FfdLattice, nodes: &'a [Point3<f64>], head: &'a Isometry3<f64>, rest: &'a [Vector3<f64>], weights: &'a [f64]) -> Self {
        Self { ffd, nodes, head, rest, weights, next: 0, last: Vector3::zeros() }
    }
}

impl Iterator for CarriedPoints<'_> {
    type Item = Vector3<f64>;

    fn next(&mut self) -> Option<Vector3<f64>> {
        let k = self.next;
        if k >= self.rest.len().min(self.weights.len()) {
            return None;
        }
        let target = carried(self.ffd, self.nodes, self.head, &self.rest[k], self.weights[k]);
        let x = if k == 0 { target } else { lead(&self.last, &target, &self.rest[k - 1], &self.rest[k], self.head) };
        self.next += 1;
        self.last = x;
        Some(x)
    }
}

/// The one law of hair carried by the global layer, for the render strands ([`Scene::render_vertex`], the
/// server's save, the scissors' cut), the guides' references ([`Scene::guide_points`]: what the local strands'
/// displacements are measured from, the choice of the local strands) and the viewer's shader
/// (`web/src/shaders/hairDeform.glsl.ts`): a strand's rest points `rest` (head frame, root first, m) with the
/// lattice's weights `weights` ([`root_hold_weight`]) go to their targets ([`carried`]: the root where the head
/// holds it, the hair beyond the root hold with the lattice), then [`follow_the_leader`] keeps the rest segment
/// lengths. Fills `out` (cleared first) with the points now, m (world).
pub fn carry_strand(ffd: &FfdLattice, nodes: &[Point3<f64>], head: &Isometry3<f64>, rest: &[Vector3<f64>], weights: &[f64], out: &mut Vec<Vector3<f64>>) {
    out.clear();
    out.extend(CarriedPoints::new(ffd, nodes, head, rest, weights));
}

/// FFD of a head-frame point through lattice nodes (clamped to the embedded volume;
/// [`FfdLattice::deform_clamped`]), m; the point itself if the nodes are not the lattice's.
pub fn ffd_map(ffd: &FfdLattice, nodes: &[Point3<f64>], p: &Vector3<f64>) -> Vector3<f64> {
    ffd.deform_clamped(&Point3::from(*p), nodes).unwrap_or(*p)
}
