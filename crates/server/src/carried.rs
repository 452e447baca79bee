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

/// A request from its JSON body; Err names what is wrong and where (the field's path, e.g. `head_rotation` or
/// `nodes[3]`, and the line and column).
pub fn parse(body: &[u8]) -> Result<CarriedRequest, String> {
    let mut de = serde_json::Deserializer::from_slice(body);
    let req: CarriedRequest = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        if path == "." || path == "?" { format!("not a carried request: {}", e.inner()) } else { format!("not a carried request: {path}: {}", e.inner()) }
    })?;
    de.end().map_err(|e| format!("not a carried request: {e}"))?;
    Ok(req)
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
    for (name, v) in [("head_rotation", &req.head_rotation[..]), ("head_translation", &req.head_translation[..])] {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(format!("{name}: number {i} is not finite"));
        }
    }
    let m = Matrix3::from_row_slice(&req.head_rotation);
    let off = (m.transpose() * m - Matrix3::identity()).abs().max();
    if off > 1e-4 {
        return Err(format!("head_rotation is not a rotation (R^T R differs from I by {off:.2e})"));
    }
    if m.determinant() < 0.0 {
        return Err(format!("head_rotation is not a rotation (a reflection: determinant {:.3})", m.determinant()));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_poses_and_nodes_are_named() {
        // JSON has no NaN or infinity (crates/server/tests/carried.rs: the parser refuses them); a Rust caller can
        // still pass them: each is refused naming the field and the number.
        let scene = Scene::builtin(&engine::scene::SceneOptions { render_strands: 200, ..Default::default() }).unwrap();
        let good = CarriedRequest { nodes: scene.lattice.ffd.rest_positions().iter().flat_map(|p| [p.x, p.y, p.z]).collect(), head_rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], head_translation: [0.0; 3], vertices: vec![0, 3] };
        let at_rest = carried(&scene, &good).unwrap();
        assert_eq!(at_rest.positions.len(), 6);
        for (i, x) in at_rest.positions.iter().enumerate() {
            let want = scene.render.positions[if i < 3 { 0 } else { 3 }][i % 3] as f64;
            assert!((x - want).abs() < 1e-6, "vertex at rest: {x} vs {want}");
        }
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut r = good.clone();
            r.nodes[7] = bad;
            assert_eq!(carried(&scene, &r).unwrap_err(), "nodes: number 7 is not finite");
            let mut r = good.clone();
            r.head_rotation[4] = bad;
            assert_eq!(carried(&scene, &r).unwrap_err(), "head_rotation: number 4 is not finite");
            let mut r = good.clone();
            r.head_translation[2] = bad;
            assert_eq!(carried(&scene, &r).unwrap_err(), "head_translation: number 2 is not finite");
        }
    }
}
