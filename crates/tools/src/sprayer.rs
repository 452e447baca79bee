//! The water sprayer: a cone of influence ([`crate::dryer::Cone`]) that raises wetness.
//!
//! Law: `dw/dt = s(x) (1 - w)` with `s(x) = s0 W(x)` (W the cone's weight): wetness approaches saturation
//! exponentially, integrated exactly over a step (`1 - w <- (1 - w) exp(-s dt)`), so w stays in [0, 1] and a
//! point held still follows `1 - (1 - w0) exp(-s t)` whatever the step.

use crate::dryer::{check_step, Cone};
use crate::wetness::{WetnessError, WetnessField};
use nalgebra::Vector3;

/// A water sprayer (immutable parameters; move it by changing `cone`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sprayer {
    /// Where it acts. Default: a 25-degree cone of 0.4 m range along +x.
    pub cone: Cone,
    /// Wetting rate s0 at the nozzle, 1/s. Default 1 (a few seconds of spray soak the hair in the core).
    pub wetting_rate: f64,
}

impl Default for Sprayer {
    fn default() -> Self {
        Self {
            cone: Cone {
                half_angle: 0.44,
                range: 0.4,
                ..Cone::default()
            },
            wetting_rate: 1.0,
        }
    }
}

impl Sprayer {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), WetnessError> {
        self.cone.validate()?;
        if !(self.wetting_rate.is_finite() && self.wetting_rate >= 0.0) {
            return Err(WetnessError::InvalidParameter {
                field: "wetting_rate",
                reason: format!("must be >= 0, got {}", self.wetting_rate),
            });
        }
        Ok(())
    }

    /// Local wetting rate s(x) = s0 W(x), 1/s.
    pub fn rate(&self, x: &Vector3<f64>) -> f64 {
        self.wetting_rate * self.cone.weight(x).0
    }

    /// Sprays `field` for `dt` seconds, each value at its segment centre `centres[strand][segment]` (m).
    /// Returns the total increase of wetness summed over all values (dimensionless).
    pub fn spray(&self, field: &mut WetnessField, centres: &[Vec<Vector3<f64>>], dt: f64) -> Result<f64, WetnessError> {
        self.validate()?;
        check_step(field, centres, dt)?;
        let mut added = 0.0;
        for (ws, xs) in field.values.iter_mut().zip(centres) {
            for (w, x) in ws.iter_mut().zip(xs) {
                let s = self.rate(x);
                if s > 0.0 {
                    let new = (1.0 - (1.0 - *w) * (-s * dt).exp()).clamp(0.0, 1.0);
                    added += new - *w;
                    *w = new;
                }
            }
        }
        Ok(added)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spraying_approaches_saturation_exponentially_and_only_inside() {
        let sp = Sprayer {
            cone: Cone {
                apex: Vector3::zeros(),
                axis: Vector3::y(),
                half_angle: 0.3,
                range: 0.5,
            },
            wetting_rate: 0.8,
        };
        let inside = Vector3::new(0.0, 0.2, 0.0);
        let outside = Vector3::new(0.0, -0.2, 0.0);
        let s = 0.8 * (1.0f64 - 0.16).powi(2);
        let mut f = WetnessField::uniform(&[2], 0.1).unwrap();
        let centres = vec![vec![inside, outside]];
        for _ in 0..500 {
            sp.spray(&mut f, &centres, 0.01).unwrap();
            assert!(f.values[0][0] <= 1.0);
        }
        let exact = 1.0 - 0.9 * (-s * 5.0f64).exp();
        assert!((f.values[0][0] - exact).abs() < 1e-12, "{} vs {exact}", f.values[0][0]);
        assert_eq!(f.values[0][1], 0.1, "outside the cone nothing changes");
    }
}
