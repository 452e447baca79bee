//! `coiffure.run_scenario`: any scenario kind (patch, global, `[live]`) through the engine's one in-memory
//! entry point (`engine::scenario::run`), the code `coiffure run` calls; the output handed over as numpy
//! arrays and the summary as a dict (the `summary.json` contents). Files only when `out` is given, written by
//! the same engine serialisers as the CLI's.

use crate::convert::Source;
use crate::errors::SimulationError;
use engine::scenario::{ScenarioError, ScenarioFile, ScenarioOutput};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How often the caller looks for Ctrl-C (or a set `cancel` event) while the scenario runs.
const POLL: Duration = Duration::from_millis(50);

fn scenario_err(e: ScenarioError) -> PyErr {
    match e {
        ScenarioError::Invalid(m) => PyValueError::new_err(format!("invalid scenario: {m}")),
        other => SimulationError::new_err(other.to_string()),
    }
}

/// Columns `(T, 3)` from three equal-length vectors.
fn columns3<'py>(py: Python<'py>, x: &[f64], y: &[f64], z: &[f64]) -> Bound<'py, PyArray2<f64>> {
    let n = x.len();
    Array2::from_shape_fn((n, 3), |(i, k)| [x[i], y[i], z[i]][k]).into_pyarray(py)
}

/// A JSON value as a Python value (the `summary.json` contents as a dict).
fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => pyo3::types::PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => PyList::new(py, a.iter().map(|x| json_to_py(py, x)).collect::<PyResult<Vec<_>>>()?)?.into_any(),
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// Strands of a hair file's curves as a list of (n_i, 3) float32 arrays.
fn curves_to_py<'py>(py: Python<'py>, c: &hairstyle::HairCurves) -> PyResult<Bound<'py, PyList>> {
    let arrays: Vec<Bound<'py, PyArray2<f32>>> = c
        .strands
        .iter()
        .map(|s| Array2::from_shape_fn((s.len(), 3), |(i, k)| s[i][k]).into_pyarray(py))
        .collect();
    PyList::new(py, arrays)
}

/// The output as the dict `run_scenario` returns.
fn output_to_py<'py>(py: Python<'py>, name: &str, out: &ScenarioOutput) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let f = &out.force;
    d.set_item("kind", out.kind)?;
    d.set_item("name", name)?;
    d.set_item("t", f.t.clone().into_pyarray(py))?;
    d.set_item("force", columns3(py, &f.fx, &f.fy, &f.fz))?;
    d.set_item("torque", columns3(py, &f.tx, &f.ty, &f.tz))?;
    let contacts: Vec<i64> = f.contacts.iter().map(|&c| c as i64).collect();
    d.set_item("contacts", contacts.into_pyarray(py))?;
    d.set_item("tool", columns3(py, &f.tool_x, &f.tool_y, &f.tool_z))?;
    d.set_item("summary", json_to_py(py, &engine::scenario::summary_json(out))?)?;
    d.set_item("wall_time", out.wall_time_s)?;
    if !out.global_rows.is_empty() {
        let rows = &out.global_rows;
        let g = PyDict::new(py);
        let col = |get: &dyn Fn(&engine::scenario::GlobalRow) -> f64| -> Bound<'py, PyArray1<f64>> { rows.iter().map(get).collect::<Vec<_>>().into_pyarray(py) };
        g.set_item("t", col(&|r| r.t))?;
        let w: Vec<f64> = rows.iter().flat_map(|r| r.wetness).collect();
        g.set_item("wetness", Array2::from_shape_vec((rows.len(), 3), w).expect("3 per row").into_pyarray(py))?;
        g.set_item("guides_in_cone", rows.iter().map(|r| r.in_cone as i64).collect::<Vec<_>>().into_pyarray(py))?;
        g.set_item("blow_force", col(&|r| r.blow_force))?;
        g.set_item("cluster_energy", col(&|r| r.cluster_energy))?;
        g.set_item("mean_tip_z", col(&|r| r.mean_tip_z))?;
        d.set_item("global", g)?;
    }
    if !out.profile.is_empty() {
        let p = &out.profile;
        let c = PyDict::new(py);
        c.set_item("stroke", p.stroke.iter().map(|&s| s as i64).collect::<Vec<_>>().into_pyarray(py))?;
        c.set_item("t", p.t.clone().into_pyarray(py))?;
        c.set_item("position_m", p.position_m.clone().into_pyarray(py))?;
        c.set_item("force_n", p.force_n.clone().into_pyarray(py))?;
        d.set_item("profile", c)?;
    }
    if let Some((style, pieces)) = &out.hair {
        d.set_item("hairstyle", curves_to_py(py, style)?)?;
        d.set_item("pieces", curves_to_py(py, pieces)?)?;
    }
    Ok(d)
}

/// Runs `file` on a worker thread while this thread (GIL released) looks for Ctrl-C or a set `cancel` event
/// every [`POLL`]. On an interruption the call returns at once with the exception; the abandoned run ends on
/// its own in the background and its result is dropped.
fn run_interruptible(py: Python<'_>, file: ScenarioFile, dir: PathBuf, cancel: Option<Py<PyAny>>) -> PyResult<ScenarioOutput> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("coiffure-scenario".into())
        .spawn(move || {
            let _ = tx.send(engine::scenario::run_in(&file, &dir));
        })
        .map_err(|e| PyOSError::new_err(format!("cannot start the scenario thread: {e}")))?;
    py.detach(move || loop {
        match rx.recv_timeout(POLL) {
            Ok(result) => return result.map_err(scenario_err),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return Err(SimulationError::new_err("the scenario thread panicked")),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                let stop = Python::attach(|py| -> PyResult<()> {
                    py.check_signals()?;
                    if let Some(c) = &cancel {
                        if c.bind(py).call_method0("is_set")?.is_truthy()? {
                            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err("cancelled"));
                        }
                    }
                    Ok(())
                });
                stop?;
            }
        }
    })
}

/// Runs a scenario (dict or TOML path) in memory; see `coiffure.run_scenario`.
#[pyfunction]
#[pyo3(signature = (scenario, out = None, base_dir = None, cancel = None))]
pub fn run_scenario<'py>(py: Python<'py>, scenario: &Bound<'py, PyAny>, out: Option<PathBuf>, base_dir: Option<PathBuf>, cancel: Option<Py<PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    let source = Source::from_py(scenario, "scenario")?;
    let text = source.text()?;
    let file = ScenarioFile::from_toml(&text).map_err(|e| match source.path() {
        Some(p) => PyValueError::new_err(format!("malformed scenario {}: {e}", p.display())),
        None => scenario_err(e),
    })?;
    let dir = match source.path() {
        Some(p) => p.parent().map(Path::to_path_buf).unwrap_or_default(),
        None => base_dir.unwrap_or_default(),
    };
    let stem = source.path().and_then(|p| p.file_stem()).and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let name = file.name().map(str::to_string).unwrap_or(stem);
    let output = run_interruptible(py, file.clone(), dir, cancel)?;
    if let Some(out_dir) = out {
        py.detach(|| engine::scenario::write_output(&file, &output, &name, &out_dir)).map_err(|e| PyOSError::new_err(format!("cannot write {}: {e}", out_dir.display())))?;
    }
    output_to_py(py, &name, &output)
}
