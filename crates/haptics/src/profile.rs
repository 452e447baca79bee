//! Limits of force-feedback devices ([`DeviceProfile`]): force, torque, their rates, stiffness, speed, the
//! mechanism's mass and damping, and the workspace; the profiles of the devices the project supports.

/// Limits of a force-feedback device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceProfile {
    /// Name.
    pub name: &'static str,
    /// Largest force the device may be asked for, N.
    pub max_force: f64,
    /// Largest change of force per second, N/s (limits buzz and kicks).
    pub max_force_rate: f64,
    /// Largest torque the device may be asked for, N m (magnitude); 0 for a 3-DOF device, which renders the
    /// force only.
    pub max_torque: f64,
    /// Largest change of torque per second, N m/s: `max_force_rate * max_torque / max_force` (the torque
    /// reaches its limit as fast as the force does); 0 for a 3-DOF device.
    pub max_torque_rate: f64,
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
    /// workspace, about 45 g apparent mass at the stylus. 3-DOF force output: no torque.
    pub const PHANTOM_OMNI: DeviceProfile = DeviceProfile { name: "Phantom Omni", max_force: 3.3, max_force_rate: 300.0, max_torque: 0.0, max_torque_rate: 0.0, max_stiffness: 1000.0, max_speed: 5.0, mass: 0.045, damping: 0.05, workspace: [0.16, 0.07, 0.12] };
    /// Phantom Desktop: 7.9 N peak, about 1.9 N/mm, 160 x 130 x 130 mm, about 75 g at the stylus. 3-DOF force
    /// output: no torque.
    pub const PHANTOM_DESKTOP: DeviceProfile = DeviceProfile { name: "Phantom Desktop", max_force: 7.9, max_force_rate: 600.0, max_torque: 0.0, max_torque_rate: 0.0, max_stiffness: 1860.0, max_speed: 5.0, mass: 0.075, damping: 0.05, workspace: [0.16, 0.13, 0.13] };
    /// Force Dimension omega.3: 12 N, about 14.5 N/mm, a 160 mm x 110 mm workspace, about 200 g at the handle.
    /// 3-DOF: no torque (nor rotation sensing).
    pub const OMEGA3: DeviceProfile = DeviceProfile { name: "omega.3", max_force: 12.0, max_force_rate: 2000.0, max_torque: 0.0, max_torque_rate: 0.0, max_stiffness: 14500.0, max_speed: 5.0, mass: 0.2, damping: 0.1, workspace: [0.16, 0.16, 0.11] };
    /// 3D Systems Phantom Premium 1.5 6-DOF (high force): 6-DOF force and torque output. Datasheet: 8.5 N peak
    /// force (1.4 N continuous), torque 515 mN m peak and 188 mN m continuous about the stylus' pitch and yaw
    /// axes (170 / 48 mN m about its roll), 3.5 N/mm stiffness, 381 x 267 x 191 mm (wide x high x deep),
    /// under 136 g apparent mass at the tip. The torque limit is the continuous 0.188 N m, the figure
    /// CHAI3D 3.3 gives the device (`cPhantomDevice`, "PHANTOM Premium 1.5 6DOF": 8.5 N, 0.188 N m). Force rate
    /// 700 N/s (full force in 12 ms, as the Omni's and Desktop's 11-13 ms).
    pub const PHANTOM_PREMIUM_6DOF: DeviceProfile = DeviceProfile { name: "Phantom Premium 1.5 6-DOF", max_force: 8.5, max_force_rate: 700.0, max_torque: 0.188, max_torque_rate: 700.0 * 0.188 / 8.5, max_stiffness: 3500.0, max_speed: 5.0, mass: 0.136, damping: 0.05, workspace: [0.381, 0.191, 0.267] };
    /// A mouse in the browser (no force output; the force is only shown).
    pub const MOUSE: DeviceProfile = DeviceProfile { name: "mouse", max_force: 10.0, max_force_rate: 1e4, max_torque: 0.0, max_torque_rate: 0.0, max_stiffness: 1000.0, max_speed: 20.0, mass: 0.0, damping: 0.0, workspace: [0.0; 3] };

    /// Looks a profile up by a short name ("omni", "desktop", "omega3", "premium6" / "phantom-premium-6dof",
    /// "mouse") or its own name.
    pub fn by_name(name: &str) -> Option<DeviceProfile> {
        match name.to_ascii_lowercase().as_str() {
            "omni" | "phantom-omni" | "touch" | "phantom omni" => Some(Self::PHANTOM_OMNI),
            "desktop" | "phantom-desktop" | "phantom desktop" => Some(Self::PHANTOM_DESKTOP),
            "omega3" | "omega.3" => Some(Self::OMEGA3),
            "premium6" | "phantom-premium-6dof" | "phantom premium 1.5 6-dof" => Some(Self::PHANTOM_PREMIUM_6DOF),
            "mouse" => Some(Self::MOUSE),
            _ => None,
        }
    }
}
