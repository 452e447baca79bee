//! Python values to TOML values, so that a dict given to `Strand.from_spec` or `run_scenario` is read by the
//! same serde code (same keys, defaults and error messages) as the TOML files of the command line.
//!
//! `None` in a dict means "key absent" (the default applies); numpy scalars and arrays are taken through
//! `.tolist()`; paths (`os.PathLike`) become strings.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::PathBuf;

/// A TOML value for a Python value; `at` names the key for errors. `None` gives `Ok(None)`.
pub fn to_toml(obj: &Bound<'_, PyAny>, at: &str) -> PyResult<Option<toml::Value>> {
    if obj.is_none() {
        return Ok(None);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Some(toml::Value::Boolean(obj.extract()?)));
    }
    if obj.is_instance_of::<PyInt>() {
        let v: i64 = obj.extract().map_err(|_| PyValueError::new_err(format!("{at}: integer out of range")))?;
        return Ok(Some(toml::Value::Integer(v)));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Some(toml::Value::Float(obj.extract()?)));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Some(toml::Value::String(obj.extract()?)));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return Ok(Some(toml::Value::Table(to_table(d, at)?)));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut out = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            let key = format!("{at}[{i}]");
            match to_toml(&item?, &key)? {
                Some(v) => out.push(v),
                None => return Err(PyValueError::new_err(format!("{key}: None is not allowed in a list"))),
            }
        }
        return Ok(Some(toml::Value::Array(out)));
    }
    // numpy scalars and arrays.
    if obj.hasattr("tolist")? {
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return to_toml(&plain, at);
        }
    }
    // pathlib.Path and other path-like objects.
    if obj.hasattr("__fspath__")? {
        let s: String = obj.call_method0("__fspath__")?.extract()?;
        return Ok(Some(toml::Value::String(s)));
    }
    let ty = obj.get_type().name()?.to_string();
    Err(PyTypeError::new_err(format!("{at}: cannot use a {ty} value (expected a number, string, bool, list or dict)")))
}

/// A TOML table for a Python dict (keys must be strings; `None` values are left out).
pub fn to_table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k.extract().map_err(|_| PyTypeError::new_err(format!("{at}: keys must be strings, got {k}")))?;
        let path = if at.is_empty() { key.clone() } else { format!("{at}.{key}") };
        if let Some(v) = to_toml(&v, &path)? {
            t.insert(key, v);
        }
    }
    Ok(t)
}

/// A text file's contents; `FileNotFoundError` / `OSError` naming `what` and the path.
pub fn read_text(path: &std::path::Path, what: &str) -> PyResult<String> {
    std::fs::read_to_string(path).map_err(|e| {
        let msg = format!("cannot read {what} {}: {e}", path.display());
        match e.kind() {
            std::io::ErrorKind::NotFound => pyo3::exceptions::PyFileNotFoundError::new_err(msg),
            _ => pyo3::exceptions::PyOSError::new_err(msg),
        }
    })
}

/// Where a spec or scenario came from: a file (its text and path) or a dict (as a TOML table).
pub enum Source {
    /// A TOML file's text and its path.
    File { text: String, path: PathBuf },
    /// A dict, converted.
    Dict(toml::Table),
}

impl Source {
    /// A dict, or a path (`str` or `os.PathLike`) to a TOML file; `what` names the kind of file for errors.
    pub fn from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Source> {
        if let Ok(d) = obj.cast::<PyDict>() {
            return Ok(Source::Dict(to_table(d, "")?));
        }
        let path: PathBuf = obj
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{what}: expected a dict or a path to a TOML file, got {}", obj.get_type().name().map(|n| n.to_string()).unwrap_or_default())))?;
        let text = read_text(&path, what)?;
        Ok(Source::File { text, path })
    }

    /// Deserializes the contents as `T`, with the CLI's error message (`malformed <what> <file>: ...`).
    pub fn parse<T: serde::de::DeserializeOwned>(&self, what: &str) -> PyResult<T> {
        match self {
            Source::File { text, path } => {
                toml::from_str(text).map_err(|e| PyValueError::new_err(format!("malformed {what} {}: {e}", path.display())))
            }
            Source::Dict(t) => toml::Value::Table(t.clone()).try_into().map_err(|e| PyValueError::new_err(format!("malformed {what} (dict): {e}"))),
        }
    }

    /// The TOML text: the file's, or the dict written as TOML.
    pub fn text(&self) -> PyResult<String> {
        match self {
            Source::File { text, .. } => Ok(text.clone()),
            Source::Dict(t) => toml::to_string(t).map_err(|e| PyValueError::new_err(format!("cannot write the dict as TOML: {e}"))),
        }
    }

    /// The file's path, if any.
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            Source::File { path, .. } => Some(path),
            Source::Dict(_) => None,
        }
    }
}

/// A TOML value as a Python value (tables are dicts, arrays lists, datetimes strings).
pub fn to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => PyString::new(py, s).into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => PyFloat::new(py, *f).into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        toml::Value::Array(a) => PyList::new(py, a.iter().map(|x| to_py(py, x)).collect::<PyResult<Vec<_>>>()?)?.into_any(),
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// Reads a TOML file (a strand spec or a scenario) into a dict; `ValueError` with the line for bad TOML.
#[pyfunction]
pub fn load_toml(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let text = read_text(&path, "file")?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| PyValueError::new_err(format!("malformed TOML {}: {e}", path.display())))?;
    to_py(py, &toml::Value::Table(table))
}
