//! Shared helpers of the engine's unit tests.

use crate::scene::{Scene, SceneOptions};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

pub(crate) fn small_scene() -> Arc<Scene> {
    let o = SceneOptions { render_strands: 2000, guides: 60, ..SceneOptions::default() };
    Arc::new(Scene::builtin(&o).unwrap())
}

/// The tool rotation of the tests: x along -x, y along -z (strokes downwards), z along -y (nozzles aim
/// along +y, at the back of the head).
pub(crate) fn test_rot() -> Matrix3<f64> {
    Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)])
}
