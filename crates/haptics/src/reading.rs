//! What a haptic device reports (pose, buttons: [`DeviceReading`]) and what it accepts (force, torque:
//! [`DeviceCommand`]).

use nalgebra::{Matrix3, Vector3};

/// One reading of a device: end-effector pose and buttons, at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceReading {
    /// Time of the reading, s.
    pub time: f64,
    /// End-effector position in the simulation's frame, m.
    pub position: Vector3<f64>,
    /// End-effector orientation (tool frame to world).
    pub rotation: Matrix3<f64>,
    /// Button bits (bit 0: primary).
    pub buttons: u32,
}

/// What the simulation sends back to the device.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DeviceCommand {
    /// Force on the user's hand, N.
    pub force: Vector3<f64>,
    /// Torque on the user's hand, N m.
    pub torque: Vector3<f64>,
}
