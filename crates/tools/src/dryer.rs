//! The hair dryer and the cone of influence it shares with the water sprayer ([`crate::sprayer`]).
//!
//! A [`Cone`] has an apex (the nozzle), an axis, a half-angle and a range. Inside it a metaball-like weight
//! `W(x) = (1 - (d/R)^2)^2 (1 - (theta/alpha)^2)^2` (d the distance to the apex, R the range, theta the angle
//! to the axis, alpha the half-angle) falls smoothly from 1 at the nozzle to 0 on the cone's boundary and is
//! exactly 0 outside, like the paper's metaball fields.
//!
//! The dryer ([`HairDryer`]):
//! - **blows**: the air moves at `u(x) = U W(x) e(x)`, `e` the unit ray from the apex through x. A body with
//!   linear drag coefficient c (N s/m) moving at v feels `c (u - v)`; the still-air part `-c v` is already in
//!   the strand and lattice models, so the dryer adds `F = c u(x)` ([`HairDryer::force`]);
//! - **blows on hair** ([`HairDryer::hair_force`]): the quadratic drag of the jet on a parcel of hair of
//!   total length l, each hair a cylinder of diameter d across the flow: per unit length
//!   `f = 1/2 rho_air C_D d |u| u` with White's correlation for a circular cylinder in cross-flow
//!   `C_D = 1 + 10 Re^(-2/3)`, `Re = |u| d / nu_air`, valid for 1 <= Re <= 2e5 (F. M. White, *Viscous Fluid
//!   Flow*, 2nd ed., McGraw-Hill 1991, eq. 3-225; a 70 um hair in a 10 m/s jet has Re = 47, C_D = 1.77).
//!   Hairs in a dense parcel shelter one another, and the parcel cannot take more than a solid body of its
//!   frontal area A would: `F = F_max (1 - exp(-|F_free|/F_max)) F_free/|F_free|` with `F_free = f l` (the
//!   hairs' drag if each were alone) and `F_max = 1/2 rho_air C_block A |u|^2` (`C_block` = 1, a bluff body's
//!   order of magnitude). This saturation is a modelling choice (smooth, equal to `F_free` for sparse hair), not
//!   a measured law;
//! - **dries**: first-order evaporation `dw/dt = -k(x) w` with `k(x) = k0 W(x)`, integrated exactly over a step
//!   (`w <- w exp(-k dt)`), so a point held still dries as `w0 exp(-k t)` whatever the step.

use crate::wetness::{WetnessError, WetnessField};
use nalgebra::Vector3;

/// A cone of influence (geometry only), SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cone {
    /// Apex (the nozzle), m.
    pub apex: Vector3<f64>,
    /// Axis direction (normalized on use). Default +x.
    pub axis: Vector3<f64>,
    /// Half-angle alpha, rad, in (0, pi/2). Default 0.35 (20 degrees).
    pub half_angle: f64,
    /// Range R: no influence farther than R from the apex, m. Default 0.3.
    pub range: f64,
}

impl Default for Cone {
    fn default() -> Self {
        Self {
            apex: Vector3::zeros(),
            axis: Vector3::x(),
            half_angle: 0.35,
            range: 0.3,
        }
    }
}

impl Cone {
    /// Checks the geometry, naming the first bad field.
    pub fn validate(&self) -> Result<(), WetnessError> {
        let bad = |field: &'static str, reason: String| Err(WetnessError::InvalidParameter { field, reason });
        if !self.apex.iter().all(|x| x.is_finite()) {
            return bad("apex", format!("must be finite, got {:?}", self.apex));
        }
        if !(self.axis.iter().all(|x| x.is_finite()) && self.axis.norm() > 1e-12) {
            return bad("axis", format!("must be a finite non-zero vector, got {:?}", self.axis));
        }
        if !(self.half_angle > 0.0 && self.half_angle < std::f64::consts::FRAC_PI_2) {
            return bad(
                "half_angle",
                format!("must be in (0, pi/2) rad, got {}", self.half_angle),
            );
        }
        if !(self.range.is_finite() && self.range > 0.0) {
            return bad("range", format!("must be > 0 m, got {}", self.range));
        }
        Ok(())
    }

    /// The weight W(x) in [0, 1] (dimensionless) and the unit ray from the apex through `x` (the axis at the
    /// apex itself). W is 0 outside the cone, behind the apex and beyond the range.
    pub fn weight(&self, x: &Vector3<f64>) -> (f64, Vector3<f64>) {
        let axis = self.axis.normalize();
        let r = x - self.apex;
        let d = r.norm();
        if d == 0.0 {
            return (1.0, axis);
        }
        let e = r / d;
        if d >= self.range {
            return (0.0, e);
        }
        let theta = e.dot(&axis).clamp(-1.0, 1.0).acos();
        if theta >= self.half_angle {
            return (0.0, e);
        }
        let a = 1.0 - (d / self.range).powi(2);
        let b = 1.0 - (theta / self.half_angle).powi(2);
        (a * a * b * b, e)
    }
}

/// A hair dryer (immutable parameters; move it by changing `cone.apex` and `cone.axis`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairDryer {
    /// Where it acts. Default [`Cone::default`] (20 degrees, 0.3 m).
    pub cone: Cone,
    /// Air speed U at the nozzle, m/s. Default 10 (hand-held dryers blow at about 5-15 m/s).
    pub air_speed: f64,
    /// Drying rate k0 at the nozzle, 1/s: the first-order evaporation rate that W scales. It stands for the air
    /// temperature and speed together. Default 0.05 (hair in the jet's core dries to 5 % in one minute).
    pub drying_rate: f64,
}

impl Default for HairDryer {
    fn default() -> Self {
        Self {
            cone: Cone::default(),
            air_speed: 10.0,
            drying_rate: 0.05,
        }
    }
}

impl HairDryer {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), WetnessError> {
        self.cone.validate()?;
        for (field, v) in [("air_speed", self.air_speed), ("drying_rate", self.drying_rate)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(WetnessError::InvalidParameter {
                    field,
                    reason: format!("must be >= 0, got {v}"),
                });
            }
        }
        Ok(())
    }

    /// Air velocity of the jet at `x`, m/s (zero outside the cone).
    pub fn air_velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let (w, e) = self.cone.weight(x);
        e * (self.air_speed * w)
    }

    /// Blowing force on a body at `x` with linear drag coefficient `drag` (N s/m; for a strand piece, the
    /// strand's air drag per unit length times the piece's length), N. Zero outside the cone.
    pub fn force(&self, x: &Vector3<f64>, drag: f64) -> Vector3<f64> {
        self.air_velocity(x) * drag
    }

    /// Local first-order drying rate k(x) = k0 W(x), 1/s.
    pub fn rate(&self, x: &Vector3<f64>) -> f64 {
        self.drying_rate * self.cone.weight(x).0
    }

    /// Dries `field` for `dt` seconds: each value `w <- w exp(-k(x) dt)` with x its segment's centre,
    /// `centres[strand][segment]` (m). Returns the total decrease of wetness summed over all values
    /// (dimensionless), for reports.
    pub fn dry(&self, field: &mut WetnessField, centres: &[Vec<Vector3<f64>>], dt: f64) -> Result<f64, WetnessError> {
        self.validate()?;
        check_step(field, centres, dt)?;
        let mut dried = 0.0;
        for (ws, xs) in field.values.iter_mut().zip(centres) {
            for (w, x) in ws.iter_mut().zip(xs) {
                let k = self.rate(x);
                if k > 0.0 {
                    let new = *w * (-k * dt).exp();
                    dried += *w - new;
                    *w = new;
                }
            }
        }
        Ok(dried)
    }
}

/// Air and hair properties for the drag of the jet on hair ([`HairDryer::hair_force`]), SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairDrag {
    /// Air density rho_air, kg/m^3. Default 1.2 (20 C, sea level).
    pub air_density: f64,
    /// Air kinematic viscosity nu_air, m^2/s. Default 1.5e-5 (20 C).
    pub air_kinematic_viscosity: f64,
    /// Hair diameter d, m. Default 7e-5 (a typical European hair; 50-120 um across hair types).
    pub hair_diameter: f64,
    /// Drag coefficient C_block of a parcel of hair at its densest (the saturation of the module docs),
    /// dimensionless. Default 1.0.
    pub block_drag_coefficient: f64,
}

impl Default for HairDrag {
    fn default() -> Self {
        Self {
            air_density: 1.2,
            air_kinematic_viscosity: 1.5e-5,
            hair_diameter: 7e-5,
            block_drag_coefficient: 1.0,
        }
    }
}

impl HairDrag {
    /// The default air with the diameter of a round hair of cross-section area `area` (m^2):
    /// d = 2 sqrt(area / pi), m (an elliptic hair's mean diameter).
    pub fn for_section_area(area: f64) -> Self {
        Self { hair_diameter: 2.0 * (area / std::f64::consts::PI).sqrt(), ..Self::default() }
    }

    /// Checks every field (all > 0 and finite), naming the first bad one.
    pub fn validate(&self) -> Result<(), WetnessError> {
        for (field, v) in [
            ("air_density", self.air_density),
            ("air_kinematic_viscosity", self.air_kinematic_viscosity),
            ("hair_diameter", self.hair_diameter),
            ("block_drag_coefficient", self.block_drag_coefficient),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(WetnessError::InvalidParameter {
                    field,
                    reason: format!("must be > 0, got {v}"),
                });
            }
        }
        Ok(())
    }

    /// White's cross-flow drag coefficient of one hair at air speed `speed` (m/s), dimensionless:
    /// `1 + 10 Re^(-2/3)` with Re clamped to [1, 2e5], the correlation's range.
    pub fn cylinder_drag_coefficient(&self, speed: f64) -> f64 {
        let re = (speed.abs() * self.hair_diameter / self.air_kinematic_viscosity).clamp(1.0, 2e5);
        1.0 + 10.0 * re.powf(-2.0 / 3.0)
    }
}

impl HairDryer {
    /// Drag of the jet on a parcel of hair at `x` (m): `hair_length` (m) of hair in all, presenting at most
    /// `frontal_area` (m^2) to the flow (e.g. a lattice cell's face, h^2), N. The rule is in the module docs
    /// (White's cylinder drag per hair, saturating at a solid body's drag). The hair's own velocity is
    /// neglected beside the air's (centimetres per second against metres per second). Zero outside the cone
    /// or for no hair.
    ///
    /// Errors: bad `drag` fields, or a negative or non-finite length or area.
    pub fn hair_force(
        &self,
        x: &Vector3<f64>,
        hair_length: f64,
        frontal_area: f64,
        drag: &HairDrag,
    ) -> Result<Vector3<f64>, WetnessError> {
        drag.validate()?;
        for (field, v) in [("hair_length", hair_length), ("frontal_area", frontal_area)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(WetnessError::InvalidParameter {
                    field,
                    reason: format!("must be >= 0 and finite, got {v}"),
                });
            }
        }
        let u = self.air_velocity(x);
        let speed = u.norm();
        if speed == 0.0 || hair_length == 0.0 || frontal_area == 0.0 {
            return Ok(Vector3::zeros());
        }
        let q = 0.5 * drag.air_density * speed * speed; // dynamic pressure, Pa
        let free = q * drag.cylinder_drag_coefficient(speed) * drag.hair_diameter * hair_length;
        let max = q * drag.block_drag_coefficient * frontal_area;
        let f = max * (-(-free / max).exp_m1());
        Ok(u * (f / speed))
    }
}

/// Checks a time step and that `centres` has one point per value of `field`.
pub(crate) fn check_step(field: &WetnessField, centres: &[Vec<Vector3<f64>>], dt: f64) -> Result<(), WetnessError> {
    if !(dt.is_finite() && dt >= 0.0) {
        return Err(WetnessError::InvalidParameter {
            field: "dt",
            reason: format!("must be >= 0 s, got {dt}"),
        });
    }
    let n: Vec<usize> = centres.iter().map(Vec::len).collect();
    field.check_shape(&n)?;
    if centres.iter().flatten().any(|x| !x.iter().all(|c| c.is_finite())) {
        return Err(WetnessError::InvalidParameter {
            field: "centres",
            reason: "segment centres must be finite".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dryer() -> HairDryer {
        HairDryer {
            cone: Cone {
                apex: Vector3::new(0.1, 0.2, 0.3),
                axis: Vector3::new(0.0, 0.0, -2.0),
                half_angle: 0.4,
                range: 0.25,
            },
            ..Default::default()
        }
    }

    #[test]
    fn drying_at_a_fixed_point_is_exponential() {
        // A point on the axis 0.1 m from the nozzle: W = (1 - 0.16)^2, k = k0 W. Any step gives exp(-k t)
        // to rounding (1e-12 relative); after 60 s at 10 ms steps and in one 60 s step.
        let d = dryer();
        let x = d.cone.apex + Vector3::new(0.0, 0.0, -0.1);
        let k = d.drying_rate * (1.0f64 - 0.16).powi(2);
        assert!((d.rate(&x) - k).abs() < 1e-15);
        let mut f = WetnessField::uniform(&[1], 0.9).unwrap();
        let centres = vec![vec![x]];
        for _ in 0..6000 {
            d.dry(&mut f, &centres, 0.01).unwrap();
        }
        let exact = 0.9 * (-k * 60.0).exp();
        assert!(
            (f.values[0][0] - exact).abs() < 1e-12 * exact,
            "{} vs {exact}",
            f.values[0][0]
        );
        let mut g = WetnessField::uniform(&[1], 0.9).unwrap();
        d.dry(&mut g, &centres, 60.0).unwrap();
        assert!((g.values[0][0] - exact).abs() < 1e-12 * exact);
    }

    #[test]
    fn nothing_outside_the_cone() {
        let d = dryer();
        let a = d.cone.apex;
        let outside = [
            a + Vector3::new(0.0, 0.0, 0.05),                    // behind the nozzle
            a + Vector3::new(0.0, 0.0, -0.26),                   // beyond the range
            a + Vector3::new(0.1 * 0.43f64.tan(), 0.0, -0.1),    // just outside the half-angle
            a + Vector3::new(0.0, -0.05 * 0.41f64.tan(), -0.05), // idem, other side
        ];
        for x in outside {
            assert_eq!(d.force(&x, 1e-5), Vector3::zeros(), "{x:?}");
            assert_eq!(d.rate(&x), 0.0);
        }
        let mut f = WetnessField::uniform(&[4], 0.7).unwrap();
        d.dry(&mut f, &[outside.to_vec()], 10.0).unwrap();
        assert!(f.values[0].iter().all(|&w| w == 0.7));
    }

    #[test]
    fn on_the_axis_the_force_is_along_the_axis() {
        let d = dryer();
        let axis = d.cone.axis.normalize();
        for s in [0.0, 0.01, 0.1, 0.2, 0.249] {
            let x = d.cone.apex + axis * s;
            let f = d.force(&x, 2e-5);
            let w = (1.0 - (s / 0.25f64).powi(2)).powi(2);
            let expected = axis * (2e-5 * d.air_speed * w);
            assert!(
                (f - expected).norm() <= 1e-15 * expected.norm().max(1e-300),
                "s = {s}: {f:?}"
            );
        }
        // Off the axis, inside: the force points away from the nozzle and is weaker than on the axis.
        let x = d.cone.apex + Vector3::new(0.02, 0.0, -0.1);
        let f = d.force(&x, 2e-5);
        assert!(
            f.dot(&(x - d.cone.apex)) > 0.0 && f.norm() < d.force(&(d.cone.apex - Vector3::z() * 0.1), 2e-5).norm()
        );
    }

    #[test]
    fn bad_input_is_named() {
        let mut d = dryer();
        d.cone.half_angle = 2.0;
        assert!(d.validate().unwrap_err().to_string().contains("half_angle"));
        let d = dryer();
        let mut f = WetnessField::dry(&[2]);
        assert!(d.dry(&mut f, &[vec![Vector3::zeros()]], 0.1).is_err(), "shape mismatch");
        assert!(d
            .dry(&mut f, &[vec![Vector3::zeros(); 2]], f64::NAN)
            .unwrap_err()
            .to_string()
            .contains("dt"));
    }

    /// White's correlation at hand-computed points, and the drag rule: on the axis 0.1 m from the nozzle
    /// (W = (1 - 0.16)^2 = 0.7056 with range 0.25 m) u = 7.056 m/s, Re = 7.056 x 7e-5 / 1.5e-5 = 32.93,
    /// C_D = 1 + 10 x 32.93^(-2/3) = 1.9734; 1 cm of hair alone: F = 0.5 x 1.2 x 7.056^2 x 1.9734 x 7e-5 x 0.01
    /// = 4.1265e-5 N (to 1e-3 relative, the hand arithmetic's rounding), along the axis; a huge parcel
    /// saturates at 0.5 rho u^2 A; twice the hair never gives more than twice the force.
    #[test]
    fn hair_drag_follows_white_and_saturates() {
        let drag = HairDrag::default();
        assert!((drag.cylinder_drag_coefficient(1000.0 * 1.5e-5 / 7e-5) - (1.0 + 10.0 * 1000f64.powf(-2.0 / 3.0))).abs() < 1e-12);
        assert_eq!(drag.cylinder_drag_coefficient(0.0), 11.0); // Re clamped to 1
        let d = dryer();
        let axis = d.cone.axis.normalize();
        let x = d.cone.apex + 0.1 * axis;
        let f = d.hair_force(&x, 0.01, 1.0, &drag).unwrap();
        assert!((f.norm() - 4.1265e-5).abs() < 1e-3 * 4.1265e-5, "{}", f.norm());
        assert!((f.normalize() - axis).norm() < 1e-12);
        let a = 4e-4;
        let big = d.hair_force(&x, 1e4, a, &drag).unwrap();
        let cap = 0.5 * 1.2 * 7.056f64.powi(2) * a;
        assert!((big.norm() - cap).abs() < 1e-9 * cap);
        for l in [0.1, 1.0, 10.0] {
            let f1 = d.hair_force(&x, l, a, &drag).unwrap().norm();
            let f2 = d.hair_force(&x, 2.0 * l, a, &drag).unwrap().norm();
            assert!(f2 > f1 && f2 <= 2.0 * f1 * (1.0 + 1e-12));
        }
        assert_eq!(d.hair_force(&(d.cone.apex - axis * 0.05), 1.0, a, &drag).unwrap(), Vector3::zeros());
        assert!(d.hair_force(&x, -1.0, a, &drag).unwrap_err().to_string().contains("hair_length"));
        let bad = HairDrag { hair_diameter: 0.0, ..drag };
        assert!(d.hair_force(&x, 1.0, a, &bad).unwrap_err().to_string().contains("hair_diameter"));
    }
}
