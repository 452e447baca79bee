//! The local force model over the network (UDP protocol version 2, docs/protocol.md): a client that sends its
//! poses as `CFP2` gets each answer as `CFF2`, the version-1 answer followed by the model the server's device
//! loop renders (the hair's reaction linearised about the server's proxy, [`HairReaction`], and the coupling's
//! parameters), in the device frame. The client renders it with the same [`crate::coupling::Coupling`] at its
//! own rate between answers ([`crate::sim`] does), so jitter and a lost answer change nothing its hand feels.
//!
//! Block after the 64 bytes of `CFF1` (little-endian): u32 model number (the physics step that made it; a new
//! number is a new model), u32 reserved (0), f64 validity (s: the physics period; the next model is due then),
//! 3 f64 proxy position `x0` (m), 3 f64 proxy velocity `v0` (m/s), 3 f64 force `f0` (N), 9 f64 stiffness `K`
//! (N/m, row-major), 9 f64 damping `D` (N s/m, row-major), 3 f64 torque (N m), 4 f64 coupling stiffness (N/m),
//! damping (N s/m), damper time (s), proxy mass (kg). 288 bytes: 352 in all.

use crate::coupling::{CouplingParams, HairReaction};
use crate::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};
use triple_buffer::{triple_buffer, Input, Output};

/// Bytes of the model block.
pub const MODEL_BYTES: usize = 288;

/// A local force model as the server's device loop renders it (head frame), fed to a device that forwards it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FedModel {
    /// The physics step that made it.
    pub number: u64,
    /// Its validity: the physics period, s.
    pub valid_for: f64,
    /// The hair's reaction, linearised (head frame).
    pub hair: HairReaction,
    /// The coupling it is rendered with (head frame).
    pub coupling: CouplingParams,
}

/// The device loop's side of a model feed: publishes each new model (wait-free).
pub struct ModelFeed(Input<Option<FedModel>>);

/// The device's side of a model feed: the latest model (wait-free).
pub struct ModelTap(Output<Option<FedModel>>);

/// A connected feed.
pub fn model_feed() -> (ModelFeed, ModelTap) {
    let (i, o) = triple_buffer(&None);
    (ModelFeed(i), ModelTap(o))
}

impl ModelFeed {
    /// Publishes a model (the newest wins).
    pub fn publish(&mut self, m: FedModel) {
        self.0.write(Some(m));
    }
}

impl ModelTap {
    /// The latest model, if any.
    pub fn latest(&mut self) -> Option<FedModel> {
        *self.0.read()
    }
}

/// A model in the device frame, as a version-2 answer carries it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WireModel {
    /// The physics step that made it (low 32 bits).
    pub number: u32,
    /// Validity, s.
    pub valid_for: f64,
    /// The hair's reaction, linearised (device frame).
    pub hair: HairReaction,
    /// The coupling (device frame).
    pub coupling: CouplingParams,
}

impl WireModel {
    /// `m` mapped to the device frame of `ws` (`head = offset + scale device`): positions `(x - offset) /
    /// scale`, velocities `/ scale`, forces and torques unchanged, stiffnesses, dampings and the proxy's mass
    /// times `scale` (the same forces for the same device-frame motion, the port's energy the head frame's over
    /// `scale`).
    pub fn to_device(m: &FedModel, ws: &Workspace) -> Self {
        let s = ws.scale;
        let h = &m.hair;
        let hair = HairReaction {
            force: h.force,
            damping: h.damping * s,
            velocity: h.velocity / s,
            position: (h.position - ws.offset) / s,
            stiffness: h.stiffness * s,
            torque: h.torque,
        };
        let c = &m.coupling;
        let coupling = CouplingParams { stiffness: c.stiffness * s, damping: c.damping * s, damper_time: c.damper_time, proxy_mass: c.proxy_mass * s };
        Self { number: m.number as u32, valid_for: m.valid_for, hair, coupling }
    }

    /// Writes the block (`MODEL_BYTES`) at the start of `b`.
    pub fn encode_into(&self, b: &mut [u8]) {
        let mut at = 0;
        let mut put = |bytes: &[u8]| {
            b[at..at + bytes.len()].copy_from_slice(bytes);
            at += bytes.len();
        };
        put(&self.number.to_le_bytes());
        put(&0u32.to_le_bytes());
        let h = &self.hair;
        let c = &self.coupling;
        let mut values: Vec<f64> = Vec::with_capacity(35);
        values.push(self.valid_for);
        values.extend(h.position.iter().chain(h.velocity.iter()).chain(h.force.iter()));
        values.extend((0..9).map(|k| h.stiffness[(k / 3, k % 3)]));
        values.extend((0..9).map(|k| h.damping[(k / 3, k % 3)]));
        values.extend(h.torque.iter());
        values.extend([c.stiffness, c.damping, c.damper_time, c.proxy_mass]);
        for v in values {
            put(&v.to_le_bytes());
        }
    }

    /// Reads a block (`MODEL_BYTES` at the start of `b`).
    pub fn decode(b: &[u8]) -> Self {
        let f = |i: usize| f64::from_le_bytes(b[8 + 8 * i..16 + 8 * i].try_into().unwrap());
        let v = |i: usize| Vector3::new(f(i), f(i + 1), f(i + 2));
        let m = |i: usize| Matrix3::from_fn(|r, c| f(i + 3 * r + c));
        let hair = HairReaction { position: v(1), velocity: v(4), force: v(7), stiffness: m(10), damping: m(19), torque: v(28) };
        let coupling = CouplingParams { stiffness: f(31), damping: f(32), damper_time: f(33), proxy_mass: f(34) };
        Self { number: u32::from_le_bytes(b[0..4].try_into().unwrap()), valid_for: f(0), hair, coupling }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_survives_the_wire_and_the_device_frame_keeps_forces_and_energy() {
        // A model with every field distinct round-trips exactly; mapped to a device frame of scale 2, the force
        // it gives a device-frame state equals the head-frame force at the mapped state (1e-12 N), and the
        // power f . v of the device frame is the head frame's over the scale.
        let hair = HairReaction {
            force: Vector3::new(0.1, -0.2, 0.3),
            damping: Matrix3::new(2.0, 0.1, 0.0, 0.1, 3.0, 0.2, 0.0, 0.2, 4.0),
            velocity: Vector3::new(0.01, 0.02, -0.03),
            position: Vector3::new(0.0, -0.11, 0.02),
            stiffness: Matrix3::new(50.0, 1.0, 2.0, 1.0, 60.0, 3.0, 2.0, 3.0, 70.0),
            torque: Vector3::new(1e-3, -2e-3, 3e-3),
        };
        let fed = FedModel { number: 7, valid_for: 1e-3, hair, coupling: CouplingParams { stiffness: 500.0, damping: 10.0, damper_time: 0.003, proxy_mass: 0.05 } };
        let ws = Workspace { scale: 2.0, offset: Vector3::new(0.0, -0.13, 0.0) };
        let wire = WireModel::to_device(&fed, &ws);
        let mut b = [0u8; MODEL_BYTES];
        wire.encode_into(&mut b);
        assert_eq!(WireModel::decode(&b), wire);
        let (xd, vd) = (Vector3::new(0.01, 0.02, 0.005), Vector3::new(0.05, -0.02, 0.01));
        let (xh, vh) = (ws.offset + xd * ws.scale, vd * ws.scale);
        let fd = wire.hair.force_at(&xd, &vd);
        let fh = hair.force_at(&xh, &vh);
        assert!((fd - fh).norm() < 1e-12, "{fd:?} vs {fh:?}");
        assert!((fd.dot(&vd) - fh.dot(&vh) / ws.scale).abs() < 1e-15);
    }
}
