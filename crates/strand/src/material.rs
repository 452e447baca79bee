//! Elastic material of a hair fibre (keratin).

use crate::error::{require_positive, Result};
use serde::{Deserialize, Serialize};

/// Linear elastic material, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus E, Pa. Default 3.9e9 (dry human hair, Robbins 2002).
    pub young_modulus: f64,
    /// Shear modulus G, Pa. Default 0.9e9 (torsional modulus of dry hair, Robbins 2002).
    pub shear_modulus: f64,
    /// Mass density, kg/m^3. Default 1300 (keratin fibre, Robbins 2002).
    pub density: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self { young_modulus: 3.9e9, shear_modulus: 0.9e9, density: 1300.0 }
    }
}

impl Material {
    /// Checks that every modulus and the density are finite and positive, naming the field otherwise.
    pub fn validate(&self) -> Result<()> {
        require_positive("young_modulus", self.young_modulus)?;
        require_positive("shear_modulus", self.shear_modulus)?;
        require_positive("density", self.density)
    }
}
