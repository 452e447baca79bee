//! Shared helpers of the engine's unit tests.

use crate::scene::{Scene, SceneOptions};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// The options of [`small_scene`].
pub(crate) fn small_scene_options() -> SceneOptions {
    SceneOptions { render_strands: 2000, guides: 60, ..SceneOptions::default() }
}

pub(crate) fn small_scene() -> Arc<Scene> {
    Arc::new(Scene::builtin(&small_scene_options()).unwrap())
}

/// The tool rotation of the tests: x along -x, y along -z (strokes downwards), z along -y (nozzles aim
/// along +y, at the back of the head).
pub(crate) fn test_rot() -> Matrix3<f64> {
    Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)])
}

/// A `[live]` comb stroke on [`small_scene`]'s hairstyle: settle 0.2 s, then the comb drawn 7 cm down the back
/// of the head in 0.7 s, pressed at the end; 0.8 s in all.
pub(crate) const LIVE_COMB: &str = r#"
        settle = 0.2
        duration = 0.8
        [live]
        render_strands = 2000
        guides = 60
        [tool]
        shape = "comb"
        path = [ { t = 0.0, position = [0.0, -0.118, 0.05], rotation = [0.0, 2.2214415, -2.2214415] },
                 { t = 0.7, position = [0.0, -0.118, -0.02], rotation = [0.0, 2.2214415, -2.2214415], pressed = true } ]
    "#;

/// A record file for a test (in the temporary folder, named after the test and this process): its path, and
/// the target to record a session with `params` on [`small_scene`] to.
pub(crate) fn record_file(name: &str, params: &crate::params::SessionParams) -> (std::path::PathBuf, crate::record::RecordTarget) {
    let path = std::env::temp_dir().join(format!("coiffure-test-{}-{name}.rec", std::process::id()));
    let sink = Box::new(crate::record::RecordFile::create(&path).expect("a record file in the temporary folder"));
    let settings = Some(crate::record::RecordSettings::of(&small_scene_options(), params));
    (path, crate::record::RecordTarget { sink, settings })
}

/// The record written to `path` by a session that ended, read whole (the file is removed).
pub(crate) fn read_record(path: &std::path::Path) -> crate::record::Record {
    let bytes = std::fs::read(path).expect("the record file");
    let _ = std::fs::remove_file(path);
    crate::record::Record::from_bytes(&bytes).expect("a whole record")
}
