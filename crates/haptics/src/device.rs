//! Haptic devices: what they report (pose, buttons) and what they accept (force, torque), and their limits.

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

/// A device driven at the haptic rate.
pub trait HapticDevice: Send {
    /// The latest reading, or `None` when the device has no new data (scripted path ended, connection lost).
    fn read(&mut self, time: f64) -> Option<DeviceReading>;
    /// Sends a force and torque to the device.
    fn write(&mut self, command: &DeviceCommand);
}

/// A boxed device is a device (the live session holds the mouse's or a UDP device behind one type).
impl<T: HapticDevice + ?Sized> HapticDevice for Box<T> {
    fn read(&mut self, time: f64) -> Option<DeviceReading> {
        (**self).read(time)
    }
    fn write(&mut self, command: &DeviceCommand) {
        (**self).write(command)
    }
}

/// Limits of a force-feedback device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceProfile {
    /// Name.
    pub name: &'static str,
    /// Largest force the device may be asked for, N.
    pub max_force: f64,
    /// Largest change of force per second, N/s (limits buzz and kicks).
    pub max_force_rate: f64,
    /// Largest stable rendering stiffness, N/m; the virtual coupling stays below it.
    pub max_stiffness: f64,
    /// Largest believable hand speed, m/s; faster input is treated as a teleport (a glitch).
    pub max_speed: f64,
    /// Apparent mass of the end-effector at the handle, kg (`coiffure device-sim`'s device dynamics).
    pub mass: f64,
    /// Viscous friction of the mechanism at the handle, N s/m (`coiffure device-sim`).
    pub damping: f64,
    /// Size of the usable workspace along x, y, z (device frame: x right, y away from the user, z up), m.
    pub workspace: [f64; 3],
}

impl DeviceProfile {
    /// 3D Systems (SensAble) Phantom Omni / Touch: 3.3 N peak, about 1 N/mm stiffness, 160 x 120 x 70 mm
    /// workspace, about 45 g apparent mass at the stylus.
    pub const PHANTOM_OMNI: DeviceProfile = DeviceProfile { name: "Phantom Omni", max_force: 3.3, max_force_rate: 300.0, max_stiffness: 1000.0, max_speed: 5.0, mass: 0.045, damping: 0.05, workspace: [0.16, 0.07, 0.12] };
    /// Phantom Desktop: 7.9 N peak, about 1.9 N/mm, 160 x 130 x 130 mm, about 75 g at the stylus.
    pub const PHANTOM_DESKTOP: DeviceProfile = DeviceProfile { name: "Phantom Desktop", max_force: 7.9, max_force_rate: 600.0, max_stiffness: 1860.0, max_speed: 5.0, mass: 0.075, damping: 0.05, workspace: [0.16, 0.13, 0.13] };
    /// Force Dimension omega.3: 12 N, about 14.5 N/mm, a 160 mm x 110 mm workspace, about 200 g at the handle.
    pub const OMEGA3: DeviceProfile = DeviceProfile { name: "omega.3", max_force: 12.0, max_force_rate: 2000.0, max_stiffness: 14500.0, max_speed: 5.0, mass: 0.2, damping: 0.1, workspace: [0.16, 0.16, 0.11] };
    /// A mouse in the browser (no force output; the force is only shown).
    pub const MOUSE: DeviceProfile = DeviceProfile { name: "mouse", max_force: 10.0, max_force_rate: 1e4, max_stiffness: 1000.0, max_speed: 20.0, mass: 0.0, damping: 0.0, workspace: [0.0; 3] };

    /// Looks a profile up by a short name ("omni", "desktop", "omega3", "mouse") or its own name.
    pub fn by_name(name: &str) -> Option<DeviceProfile> {
        match name.to_ascii_lowercase().as_str() {
            "omni" | "phantom-omni" | "touch" | "phantom omni" => Some(Self::PHANTOM_OMNI),
            "desktop" | "phantom-desktop" | "phantom desktop" => Some(Self::PHANTOM_DESKTOP),
            "omega3" | "omega.3" => Some(Self::OMEGA3),
            "mouse" => Some(Self::MOUSE),
            _ => None,
        }
    }
}
