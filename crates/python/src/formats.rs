//! Hair files (`hairstyle::formats`: `.hair`, `.data`, `.tfx`, `.usda`, chosen by extension), as flat arrays:
//! all points `(P, 3)` float32 and the point count of each strand. `coiffure.read_hair` / `write_hair` split
//! and join them in Python (numpy views, no copies per strand).

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;
use hairstyle::formats::{read_file, write_file, FormatError, HairCurves};

/// A format error as a Python exception: malformed data (with the byte offset or line) and unknown extensions
/// are `ValueError`; I/O failures are `OSError` (`FileNotFoundError` for a missing file).
fn format_err(e: FormatError) -> PyErr {
    match e {
        FormatError::Io { path, source } => {
            let msg = format!("{}: {source}", path.display());
            match source.kind() {
                std::io::ErrorKind::NotFound => pyo3::exceptions::PyFileNotFoundError::new_err(msg),
                std::io::ErrorKind::PermissionDenied => pyo3::exceptions::PyPermissionError::new_err(msg),
                _ => PyOSError::new_err(msg),
            }
        }
        other => PyValueError::new_err(other.to_string()),
    }
}

/// Reads a hair file: (points (P, 3) float32 in file units, counts (S,) int64 points per strand).
#[pyfunction]
pub fn read_hair_flat<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyArray1<i64>>)> {
    let curves = py.detach(|| read_file(&path)).map_err(|e| match e {
        FormatError::Io { .. } | FormatError::UnknownExtension(_) => format_err(e),
        other => PyValueError::new_err(format!("{}: {other}", path.display())),
    })?;
    let counts: Vec<i64> = curves.strands.iter().map(|s| s.len() as i64).collect();
    let flat: Vec<f32> = curves.strands.iter().flatten().flat_map(|p| *p).collect();
    let points = Array2::from_shape_vec((flat.len() / 3, 3), flat).expect("3 values per point");
    Ok((points.into_pyarray(py), counts.into_pyarray(py)))
}

/// Writes a hair file from flat points (P, 3) float32 and counts (S,) per strand; nothing is written on error.
#[pyfunction]
pub fn write_hair_flat(py: Python<'_>, path: PathBuf, points: PyReadonlyArray2<'_, f32>, counts: PyReadonlyArray1<'_, i64>) -> PyResult<()> {
    let pts = points.as_array();
    if pts.ncols() != 3 {
        return Err(PyValueError::new_err(format!("points must have shape (P, 3), got {:?}", pts.shape())));
    }
    let counts = counts.as_array();
    let total: i64 = counts.iter().sum();
    if counts.iter().any(|&c| c < 0) || total as usize != pts.nrows() {
        return Err(PyValueError::new_err(format!("strand point counts (sum {total}) do not match the {} points", pts.nrows())));
    }
    if let Some(i) = pts.iter().position(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!("point {} is not finite", i / 3)));
    }
    let mut strands = Vec::with_capacity(counts.len());
    let mut at = 0usize;
    for &c in counts.iter() {
        let c = c as usize;
        strands.push((at..at + c).map(|i| [pts[(i, 0)], pts[(i, 1)], pts[(i, 2)]]).collect::<Vec<_>>());
        at += c;
    }
    let curves = HairCurves::from_strands(strands);
    py.detach(|| write_file(&path, &curves)).map_err(|e| match e {
        FormatError::Io { .. } | FormatError::UnknownExtension(_) => format_err(e),
        other => PyValueError::new_err(format!("{}: {other}", path.display())),
    })
}
