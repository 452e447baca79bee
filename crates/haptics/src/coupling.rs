//! Virtual coupling between the device and the tool proxy, with force and force-rate clamps, a time-domain
//! passivity observer and controller (Hannaford and Ryu 2002) and input checks.
//!
//! Per haptic step ([`Coupling::update`]):
//! 1. check the reading: non-finite values or a jump faster than the profile's `max_speed` are rejected
//!    (zero force, an [`InputError`] returned, the last good pose kept);
//! 2. the proxy (a light rigid body of mass `proxy_mass`) is pulled towards the device by a spring-damper
//!    (stiffness `stiffness`, below the device's limit) and pushed by the hair's reaction; semi-implicit Euler;
//! 3. the device force is minus the coupling force, its rate of change clamped to the profile; then the
//!    passivity controller adds just enough damping to keep the energy the device port has absorbed from the
//!    user non-negative (stability first: this damping may exceed the rate limit); then the magnitude is
//!    clamped to the profile (scaling a force down keeps the step passive).

use crate::device::{DeviceProfile, DeviceReading};
use nalgebra::Vector3;
use thiserror::Error;

/// Why a device reading was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InputError {
    /// NaN or infinite position or time.
    #[error("non-finite device reading at t = {time} s")]
    NonFinite {
        /// Simulation time, s.
        time: f64,
    },
    /// The device moved faster than its profile allows (a glitch or a teleport).
    #[error("device jumped {distance} m in {dt} s (more than {max_speed} m/s)")]
    Teleport {
        /// Distance jumped, m.
        distance: f64,
        /// Time step, s.
        dt: f64,
        /// The profile's limit, m/s.
        max_speed: f64,
    },
}

/// Parameters of the coupling. Defaults suit a 1 kHz loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingParams {
    /// Coupling stiffness, N/m. Default: half the device's `max_stiffness`.
    pub stiffness: f64,
    /// Coupling damping, N s/m. Default: critical damping of the proxy, `2 sqrt(k m)`.
    pub damping: f64,
    /// Mass of the tool proxy, kg. Default 0.05.
    pub proxy_mass: f64,
}

impl CouplingParams {
    /// Defaults for a device profile.
    pub fn for_profile(p: &DeviceProfile) -> Self {
        let k = 0.5 * p.max_stiffness;
        let m = 0.05;
        Self { stiffness: k, damping: 2.0 * (k * m).sqrt(), proxy_mass: m }
    }
}

/// State of the coupling between one device and one tool proxy.
#[derive(Debug, Clone)]
pub struct Coupling {
    /// Device limits.
    pub profile: DeviceProfile,
    /// Spring-damper and proxy parameters.
    pub params: CouplingParams,
    /// Tool proxy position, m.
    pub proxy: Vector3<f64>,
    /// Tool proxy velocity, m/s.
    pub proxy_velocity: Vector3<f64>,
    /// Last accepted device position, m.
    pub device: Vector3<f64>,
    /// Device velocity (finite difference), m/s.
    pub device_velocity: Vector3<f64>,
    /// Force last sent to the device, N.
    pub force: Vector3<f64>,
    /// Passivity observer: energy absorbed from the user through the device port, J (kept >= 0).
    pub energy: f64,
    /// Steps in which the passivity controller acted.
    pub passivity_activations: u64,
    /// Steps in which a clamp (force or rate) acted.
    pub clamp_activations: u64,
    last_time: Option<f64>,
}

impl Coupling {
    /// A coupling at rest with proxy and device at `position` (m).
    pub fn new(profile: DeviceProfile, params: CouplingParams, position: Vector3<f64>) -> Self {
        Self {
            profile,
            params,
            proxy: position,
            proxy_velocity: Vector3::zeros(),
            device: position,
            device_velocity: Vector3::zeros(),
            force: Vector3::zeros(),
            energy: 0.0,
            passivity_activations: 0,
            clamp_activations: 0,
            last_time: None,
        }
    }

    /// One haptic step of `dt` seconds with a device reading and the hair's reaction on the tool proxy
    /// (`hair_force`, N). Returns the force to send to the device (N), or an error (and zero force) for a bad
    /// reading; the proxy then holds still.
    pub fn update(&mut self, reading: &DeviceReading, dt: f64, hair_force: &Vector3<f64>) -> Result<Vector3<f64>, InputError> {
        let finite = reading.time.is_finite() && reading.position.iter().all(|x| x.is_finite()) && reading.rotation.iter().all(|x| x.is_finite());
        if !finite || !dt.is_finite() || dt <= 0.0 {
            self.reject();
            return Err(InputError::NonFinite { time: reading.time });
        }
        let jump = (reading.position - self.device).norm();
        if self.last_time.is_some() && jump > self.profile.max_speed * dt {
            self.reject();
            return Err(InputError::Teleport { distance: jump, dt, max_speed: self.profile.max_speed });
        }
        self.device_velocity = if self.last_time.is_some() { (reading.position - self.device) / dt } else { Vector3::zeros() };
        self.device = reading.position;
        self.last_time = Some(reading.time);
        let hair = if hair_force.iter().all(|x| x.is_finite()) { *hair_force } else { Vector3::zeros() };

        // Proxy dynamics (semi-implicit: the coupling spring and damper are taken at the new proxy state).
        let (k, b, m) = (self.params.stiffness, self.params.damping, self.params.proxy_mass);
        let x_rel = self.device - self.proxy;
        // m dv = (k (x_rel - dt v_new) + b (v_dev - v_new) + hair) dt, solved for v_new.
        let v_new = (self.proxy_velocity * m + (x_rel * k + self.device_velocity * b + hair) * dt) / (m + b * dt + k * dt * dt);
        self.proxy_velocity = v_new;
        self.proxy += v_new * dt;
        let coupling = (self.device - self.proxy) * k + (self.device_velocity - self.proxy_velocity) * b;

        // Device force: minus the coupling force, rate-limited.
        let mut f = -coupling;
        let mut clamped = false;
        let max_step = self.profile.max_force_rate * dt;
        let df = f - self.force;
        if df.norm() > max_step {
            f = self.force + df * (max_step / df.norm());
            clamped = true;
        }
        // Passivity: the energy the port absorbs from the hand is -f . v dt (f on the hand, v of the hand).
        // If the sum would go negative, add damping alpha (N s/m) along v so that it stays at zero.
        let v = self.device_velocity;
        let de = -f.dot(&v) * dt;
        if self.energy + de < 0.0 && v.norm_squared() > 0.0 {
            let alpha = -(self.energy + de) / (v.norm_squared() * dt);
            f -= v * alpha;
            self.passivity_activations += 1;
        }
        // Magnitude clamp (scaling the force down keeps the step passive).
        if f.norm() > self.profile.max_force {
            f *= self.profile.max_force / f.norm();
            clamped = true;
        }
        if clamped {
            self.clamp_activations += 1;
        }
        self.energy -= f.dot(&v) * dt;
        self.force = f;
        Ok(f)
    }

    fn reject(&mut self) {
        self.force = Vector3::zeros();
        self.proxy_velocity = Vector3::zeros();
        self.device_velocity = Vector3::zeros();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn reading(t: f64, x: Vector3<f64>) -> DeviceReading {
        DeviceReading { time: t, position: x, rotation: Matrix3::identity(), buttons: 0 }
    }

    /// A hard wall at z = 0 acting on the proxy: a penalty 20 kN/m, far stiffer than the coupling.
    fn wall(proxy: &Vector3<f64>) -> Vector3<f64> {
        if proxy.z < 0.0 { Vector3::new(0.0, 0.0, -20000.0 * proxy.z) } else { Vector3::zeros() }
    }

    #[test]
    fn hard_fast_contact_stays_passive_and_clamped() {
        // The hand drives the device into a hard wall at 0.5 m/s and out again, repeatedly, at 1 kHz.
        // Passivity: the energy absorbed from the user never goes negative. Clamps: |F| <= max force and
        // |dF| <= max rate * dt at every step. (Tolerance 1e-12 for round-off.)
        for profile in [DeviceProfile::PHANTOM_OMNI, DeviceProfile::PHANTOM_DESKTOP, DeviceProfile::OMEGA3] {
            let mut c = Coupling::new(profile, CouplingParams::for_profile(&profile), Vector3::new(0.0, 0.0, 0.01));
            let dt = 1e-3;
            let mut last = Vector3::zeros();
            let mut hair = Vector3::zeros();
            let mut activations = 0;
            for n in 0..4000 {
                let t = n as f64 * dt;
                let z = 0.01 - 0.02 * (0.5 - 0.5 * (2.0 * std::f64::consts::PI * t / 0.4).cos()) * 2.0;
                let f = c.update(&reading(t, Vector3::new(0.0, 0.0, z)), dt, &hair).unwrap();
                assert!(c.energy >= -1e-12, "{}: energy {}", profile.name, c.energy);
                assert!(f.norm() <= profile.max_force + 1e-12, "{}: force {}", profile.name, f.norm());
                if c.passivity_activations == activations {
                    assert!((f - last).norm() <= profile.max_force_rate * dt + 1e-9, "{}: rate", profile.name);
                }
                activations = c.passivity_activations;
                last = f;
                hair = wall(&c.proxy);
            }
            assert!(c.clamp_activations > 0, "{}: the wall should saturate the device", profile.name);
            println!("{}: clamps {} passivity {} energy {:.3e} J", profile.name, c.clamp_activations, c.passivity_activations, c.energy);
        }
    }

    #[test]
    fn an_energy_generating_environment_is_made_passive() {
        // An active environment (the 'hair' pushes the proxy along its own velocity, a negative damper of
        // 5 N s/m) would feed energy to the hand; the passivity controller must act and keep the port's energy
        // non-negative at every step (1e-12 J round-off).
        let p = DeviceProfile::OMEGA3;
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
        let dt = 1e-3;
        for n in 0..3000 {
            let t = n as f64 * dt;
            let x = Vector3::new(0.02 * (2.0 * std::f64::consts::PI * t).sin(), 0.0, 0.0);
            let active = c.proxy_velocity * 5.0;
            c.update(&reading(t, x), dt, &active).unwrap();
            assert!(c.energy >= -1e-12, "energy {} at t = {t}", c.energy);
        }
        assert!(c.passivity_activations > 0, "the controller never acted");
    }

    #[test]
    fn absurd_input_gives_zero_force_and_an_error() {
        let p = DeviceProfile::PHANTOM_OMNI;
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
        let dt = 1e-3;
        c.update(&reading(0.0, Vector3::zeros()), dt, &Vector3::zeros()).unwrap();
        let bad = [
            reading(0.001, Vector3::new(f64::NAN, 0.0, 0.0)),
            reading(0.001, Vector3::new(0.0, f64::INFINITY, 0.0)),
            reading(f64::NAN, Vector3::zeros()),
            reading(0.001, Vector3::new(1.0, 0.0, 0.0)),
            reading(0.001, Vector3::new(1e300, -1e300, 0.0)),
        ];
        for r in bad {
            assert!(c.update(&r, dt, &Vector3::new(100.0, 0.0, 0.0)).is_err(), "{r:?}");
            assert_eq!(c.force, Vector3::zeros());
            assert!(c.proxy.iter().all(|x| x.is_finite()));
        }
        // Good input afterwards works again and never exceeds the clamps even with an absurd hair force.
        let f = c.update(&reading(0.002, Vector3::new(0.001, 0.0, 0.0)), dt, &Vector3::new(1e9, 0.0, 0.0)).unwrap();
        assert!(f.norm() <= p.max_force);
        let f = c.update(&reading(0.003, Vector3::new(0.001, 0.0, 0.0)), dt, &Vector3::new(f64::NAN, 0.0, 0.0)).unwrap();
        assert!(f.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn free_motion_follows_the_device() {
        // With no hair force, the proxy follows a 0.2 m/s motion within 1 mm and the force stays small (< 0.1 N)
        // after the start.
        let p = DeviceProfile::PHANTOM_DESKTOP;
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
        for n in 0..500 {
            let t = n as f64 * 1e-3;
            let f = c.update(&reading(t, Vector3::new(0.2 * t, 0.0, 0.0)), 1e-3, &Vector3::zeros()).unwrap();
            if n > 100 {
                assert!((c.proxy - c.device).norm() < 1e-3);
                assert!(f.norm() < 0.1, "{}", f.norm());
            }
        }
    }
}
