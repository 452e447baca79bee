//! `coiffure.hair_types()`: the hair-type presets (`strand::HairType::ALL`) with their derived section,
//! moduli, friction coefficient and rest curl, in SI units.

use crate::errors::strand_err;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The hair-type presets, the paper's Table 1 first, as a list of dicts (SI units).
///
/// Keys: ``name``; ``major_diameter`` (m); ``ellipticity`` (major/minor); ``semi_axes`` ([a, b], m);
/// ``bending_stiffness`` (E I about the major axis, N m^2); ``young_modulus``, ``shear_modulus`` (Pa);
/// ``density`` (kg/m^3); ``linear_density`` (kg/m); ``friction_force`` (measured single-fibre friction, N, or
/// None); ``friction_coefficient`` (Coulomb, against a tool); ``curl_radius``, ``curl_pitch`` (m, or None for
/// straight hair); ``rest_twist``, ``rest_bend`` (rad/m, the natural curl); ``source``.
#[pyfunction]
pub fn hair_types(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    strand::HairType::ALL
        .iter()
        .map(|h| {
            let err = |e| strand_err(h.name, e);
            let section = h.section().map_err(err)?;
            let material = h.material().map_err(err)?;
            let (twist, bend) = h.rest_curvature();
            let d = PyDict::new(py);
            d.set_item("name", h.name)?;
            d.set_item("major_diameter", h.major_diameter)?;
            d.set_item("ellipticity", h.ellipticity)?;
            d.set_item("semi_axes", vec![section.semi_major, section.semi_minor])?;
            d.set_item("bending_stiffness", h.bending_stiffness)?;
            d.set_item("young_modulus", material.young_modulus)?;
            d.set_item("shear_modulus", material.shear_modulus)?;
            d.set_item("density", material.density)?;
            d.set_item("linear_density", material.density * section.area())?;
            d.set_item("friction_force", h.friction_force)?;
            d.set_item("friction_coefficient", h.friction_coefficient())?;
            d.set_item("curl_radius", h.curl_radius)?;
            d.set_item("curl_pitch", h.curl_pitch)?;
            d.set_item("rest_twist", twist)?;
            d.set_item("rest_bend", bend)?;
            d.set_item("source", h.source())?;
            Ok(d)
        })
        .collect()
}
