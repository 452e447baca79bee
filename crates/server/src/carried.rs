//! `POST /debug/carried`: where the engine's one law of the carried hair (`Scene::render_vertex`, the render
//! strands carried by the head and the lattice, `engine::scene::carry_strand`) puts the render vertices a caller
//! names, for a lattice and a head pose the caller gives. The viewer computes the same law on the GPU
//! (web/src/carriedHair.ts); its browser test reads back the lattice, the head pose and the carried vertices of
//! one frame and asks this for the same vertices on that state (web/test/viewer.test.mjs), point by point.
//! Read-only: nothing of the session changes. docs/protocol.md, "Debug endpoint".

use engine::scene::{GuideDisplacements, Scene};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Most vertices one request may name (a request is computed on a blocking thread, about 1 us a vertex).
pub const MAX_VERTICES: usize = 200_000;

/// A request: the lattice and the head pose the vertices are carried by, and which vertices.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarriedRequest {
    /// Lattice node positions (world, m), x, y, z per node in the lattice's order (node (i, j, k) at
    /// i + nx (j + ny k), as the FRAME message carries them).
    pub nodes: Vec<f64>,
    /// The head pose's rotation (head frame to world), row-major 3 x 3 (a rotation to 1e-4).
    pub head_rotation: [f64; 9],
    /// The head pose's translation (world), m.
    pub head_translation: [f64; 3],
    /// Render vertices, each `strand * vertices_per_strand + j` (the viewer's texel index).
    pub vertices: Vec<u32>,
}

/// The answer: each requested vertex carried (world, m), x, y, z per vertex in the request's order.
#[derive(Debug, Clone, Serialize)]
pub struct CarriedAnswer {
    /// The requested vertices carried (world, m): x, y, z per vertex, in the request's order.
    pub positions: Vec<f64>,
}

/// The requested vertices of `scene`'s render strands where `Scene::render_vertex` puts them on the request's
/// lattice and head pose, without local strands' displacements (those are added after the carry, as the viewer
/// adds them after its carried texture). Err names what is wrong with the request.
pub fn carried(scene: &Scene, req: &CarriedRequest) -> Result<CarriedAnswer, String> {
    let count = scene.lattice.node_count();
    if req.nodes.len() != 3 * count {
        return Err(format!("nodes: {} numbers, the scene's lattice has {count} nodes ({} numbers)", req.nodes.len(), 3 * count));
    }
    if let Some(i) = req.nodes.iter().position(|x| !x.is_finite()) {
        return Err(format!("nodes: number {i} is not finite"));
    }
    if !req.head_rotation.iter().chain(&req.head_translation).all(|x| x.is_finite()) {
        return Err("head_rotation and head_translation must be finite".into());
    }
    let m = Matrix3::from_row_slice(&req.head_rotation);
    let off = (m.transpose() * m - Matrix3::identity()).abs().max();
    if off > 1e-4 || m.determinant() < 0.0 {
        return Err(format!("head_rotation is not a rotation (R^T R differs from I by {off:.2e})"));
    }
    if req.vertices.len() > MAX_VERTICES {
        return Err(format!("vertices: {} asked, at most {MAX_VERTICES}", req.vertices.len()));
    }
    let nv = scene.render.vertices_per_strand;
    let total = scene.render.strands() * nv;
    if let Some(v) = req.vertices.iter().find(|&&v| v as usize >= total) {
        return Err(format!("vertices: {v} is not a render vertex (the scene has {total})"));
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&m));
    let head = Isometry3::from_parts(Translation3::from(Vector3::from(req.head_translation)), rotation);
    let nodes: Vec<Point3<f64>> = req.nodes.chunks_exact(3).map(|p| Point3::new(p[0], p[1], p[2])).collect();
    let none = GuideDisplacements::default();
    let mut positions = Vec::with_capacity(3 * req.vertices.len());
    for &v in &req.vertices {
        let (i, j) = (v as usize / nv, v as usize % nv);
        positions.extend_from_slice(scene.render_vertex(&nodes, &head, &none, i, j).as_slice());
    }
    Ok(CarriedAnswer { positions })
}
