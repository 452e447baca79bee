//! The map from a device's workspace to the head frame (docs/protocol.md, "Workspace mapping").
//!
//! A device reports its end-effector in its own frame (m, origin at the workspace's centre, axes as the head
//! frame's seen from behind the head: x to the user's right, y away from the user, z up). Coiffure places the
//! tool at `head = offset + scale * device`; rotations are not changed. Forces go back unchanged (N): the
//! hand then feels the coupling stiffness times `scale`, which must stay within the device's
//! `max_stiffness`, and the energy the port exchanges is the head frame's divided by `scale` (passivity is
//! kept).

use crate::coupling::CouplingParams;
use crate::profile::DeviceProfile;
use crate::reading::DeviceReading;
use nalgebra::Vector3;

/// Default scale, dimensionless: a Phantom Omni's 16 x 7 x 12 cm workspace covers 32 x 14 x 24 cm of the
/// back of the head (the coupling's default stiffness, half the device's limit, may be doubled).
pub const DEFAULT_SCALE: f64 = 2.0;
/// Default head-frame point of the workspace's centre, m: 13 cm behind the head's centre, on the back hair.
pub const DEFAULT_OFFSET: [f64; 3] = [0.0, -0.13, 0.0];

/// Workspace mapping: `head = offset + scale * device`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workspace {
    /// Head-frame metres per device metre, > 0. Default [`DEFAULT_SCALE`].
    pub scale: f64,
    /// Head-frame position of the device's origin, m. Default [`DEFAULT_OFFSET`].
    pub offset: Vector3<f64>,
}

impl Workspace {
    /// The default mapping for `profile`: the workspace's centre on the back hair, scaled by 2 (at most what
    /// keeps the felt stiffness within the device's limit).
    pub fn for_profile(profile: &DeviceProfile) -> Self {
        let k = CouplingParams::for_profile(profile).stiffness;
        let scale = if k > 0.0 { DEFAULT_SCALE.min(profile.max_stiffness / k) } else { DEFAULT_SCALE };
        Self { scale, offset: Vector3::from(DEFAULT_OFFSET) }
    }

    /// Parses `"SCALE,X,Y,Z"` (dimensionless, m) or `"SCALE"` (the default offset) and checks it against
    /// `profile`: the scale must be finite and > 0 and keep the felt stiffness (`scale` times the coupling
    /// stiffness) within the device's `max_stiffness`.
    pub fn parse(text: &str, profile: &DeviceProfile) -> Result<Self, String> {
        let parts: Result<Vec<f64>, _> = text.split(',').map(|x| x.trim().parse::<f64>()).collect();
        let v = parts.map_err(|e| format!("device workspace {text:?}: expected SCALE or SCALE,X,Y,Z (numbers): {e}"))?;
        let w = match v.as_slice() {
            [s] => Self { scale: *s, offset: Vector3::from(DEFAULT_OFFSET) },
            [s, x, y, z] => Self { scale: *s, offset: Vector3::new(*x, *y, *z) },
            _ => return Err(format!("device workspace {text:?}: expected SCALE or SCALE,X,Y,Z, got {} numbers", v.len())),
        };
        w.check(profile)?;
        Ok(w)
    }

    /// Checks the mapping against `profile` (see [`Workspace::parse`]).
    pub fn check(&self, profile: &DeviceProfile) -> Result<(), String> {
        if !(self.scale.is_finite() && self.scale > 0.0) || !self.offset.iter().all(|x| x.is_finite()) {
            return Err(format!("device workspace: the scale must be finite and > 0 and the offset finite, got scale {} offset {:?}", self.scale, self.offset.as_slice()));
        }
        let k = CouplingParams::for_profile(profile).stiffness;
        if self.scale * k > profile.max_stiffness * (1.0 + 1e-9) {
            return Err(format!(
                "device workspace: scale {} makes the hand feel {:.0} N/m (scale x coupling stiffness {:.0} N/m), above the {}'s {:.0} N/m; use a scale <= {:.3}",
                self.scale, self.scale * k, k, profile.name, profile.max_stiffness, profile.max_stiffness / k
            ));
        }
        Ok(())
    }

    /// A device-frame reading in the head frame (position mapped, the rest unchanged).
    pub fn to_head(&self, r: &DeviceReading) -> DeviceReading {
        DeviceReading { position: self.offset + r.position * self.scale, ..*r }
    }

    /// A head-frame position in the device frame, m.
    pub fn to_device(&self, head: &Vector3<f64>) -> Vector3<f64> {
        (head - self.offset) / self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    #[test]
    fn maps_both_ways_and_refuses_what_the_device_cannot_render() {
        let p = DeviceProfile::PHANTOM_OMNI;
        let w = Workspace::for_profile(&p);
        assert_eq!(w.scale, 2.0);
        // The Omni's workspace corners land around the back of the head: x within +-16 cm, y from -20 to -6 cm.
        let r = DeviceReading { time: 0.0, position: Vector3::new(0.08, 0.035, -0.06), rotation: Matrix3::identity(), buttons: 1 };
        let h = w.to_head(&r);
        assert!((h.position - Vector3::new(0.16, -0.06, -0.12)).norm() < 1e-15);
        assert!((w.to_device(&h.position) - r.position).norm() < 1e-15);
        assert_eq!(h.buttons, 1);
        let parsed = Workspace::parse("1.5, 0, -0.1, 0.02", &p).unwrap();
        assert_eq!(parsed, Workspace { scale: 1.5, offset: Vector3::new(0.0, -0.1, 0.02) });
        assert_eq!(Workspace::parse("1", &p).unwrap().offset, Vector3::from(DEFAULT_OFFSET));
        // Scale 3 would make the Omni render 1500 N/m > 1000 N/m.
        assert!(Workspace::parse("3", &p).unwrap_err().contains("1000 N/m"));
        assert!(Workspace::parse("0", &p).is_err());
        assert!(Workspace::parse("nan,0,0,0", &p).is_err());
        assert!(Workspace::parse("1,2", &p).unwrap_err().contains("SCALE"));
        assert!(Workspace::parse("x", &p).is_err());
    }
}
