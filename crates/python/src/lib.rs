//! The native part of the `coiffure` Python package (`coiffure._coiffure`).
//!
//! Thin bindings over the same Rust code as the `coiffure` command line: [`strand`] (one Super-Helix from a
//! strand spec), [`hair_types`] (the presets), [`formats`] (hair files), [`scenario`] (headless scenarios).
//! Conversions between Python values and the spec/scenario structures are in [`convert`]; long loops release
//! the GIL and look for Ctrl-C between steps ([`interrupt`]). The pure-Python part (`python/coiffure/`) adds
//! the sweep (in-process threads or Ray) and the typed wrappers; the stubs are in `_coiffure.pyi`.

use pyo3::prelude::*;

mod convert;
mod errors;
mod formats;
mod hair_types;
mod interrupt;
mod scenario;
mod strand;

/// The module `coiffure._coiffure`.
#[pymodule]
fn _coiffure(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("SimulationError", m.py().get_type::<errors::SimulationError>())?;
    m.add_class::<strand::PyStrand>()?;
    m.add_function(wrap_pyfunction!(hair_types::hair_types, m)?)?;
    m.add_function(wrap_pyfunction!(convert::load_toml, m)?)?;
    m.add_function(wrap_pyfunction!(formats::read_hair_flat, m)?)?;
    m.add_function(wrap_pyfunction!(formats::write_hair_flat, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::run_scenario, m)?)?;
    Ok(())
}
