//! Virtual coupling between the device and the tool proxy, with force and force-rate clamps, a time-domain
//! passivity observer and controller (Hannaford and Ryu 2002) and input checks.
//!
//! Per haptic step ([`Coupling::update`]):
//! 1. check the reading: non-finite values or a jump faster than the profile's `max_speed` are rejected
//!    (zero force, an [`InputError`] returned, the last good pose kept);
//! 2. the proxy (a light rigid body of mass `proxy_mass`) is pulled towards the device by the coupling
//!    (stiffness `stiffness`, below the device's limit, in parallel with a damper `damping` that sits in
//!    series with a spring of stiffness `damping / damper_time`: a standard linear solid, the viscoelastic
//!    model of a fingertip holding a tool) and pushed by the hair's reaction. The damper branch's force `F_d`
//!    obeys `dF_d/dt = (b (v_dev - v) - F_d) / tau`: it follows `b (v_dev - v)` with the time constant
//!    `tau = damper_time`, so a sudden change of the proxy's velocity (the comb catching hair near the roots,
//!    a stuck wisp letting go) reaches the hand over a few steps instead of in one, by at most
//!    `b |dv| h / (tau + h)` per step. Everything is implicit in the proxy's new velocity: the spring and
//!    the damper branch (`F_d' = (tau F_d + h b (v_dev - v)) / (tau + h)`), and the hair's reaction through
//!    its linearisation [`HairReaction`] (the force `f0` the hair gave at the proxy's position `x0` and
//!    velocity `v0`, its stiffness `K = -dF/dx` and damping `D = -dF/dv`, from the contacts' compliant
//!    response), so that `m (v - v_old) = (k (x_rel - h v) + F_d' + f0 - K (x + h v - x0) - D (v - v0)) h`.
//!    A reaction stiff enough to throw an
//!    explicitly pushed proxy (`|D| h > m`) then only slows it: the proxy takes part in the contact solve as
//!    a body with its mass. Springs and dampers only: the coupling is passive by construction;
//! 3. the device force is minus the coupling force, its rate of change clamped to the profile; then the
//!    passivity controller adds just enough damping to keep the energy the device port has absorbed from the
//!    user non-negative (stability first: this damping may exceed the rate limit); then the magnitude is
//!    clamped to the profile (scaling a force down keeps the step passive);
//! 4. the torque: the tool turns with the device, so the hand feels the hair's torque on the tool, through the
//!    same rate clamp, passivity controller (on the rotational port, with the device's angular velocity) and
//!    magnitude clamp, to the profile's torque limits (none on a 3-DOF device: zero torque).
//!
//! The hair's reaction is a [`HairReaction`], the *local force model* one physics step publishes (force,
//! stiffness, damping and torque about the proxy's state): the same update renders it at any rate, the
//! physics' (1 kHz) or the device's (4-10 kHz, several updates per model), with the passivity observer at
//! the rate of the update.

use crate::profile::DeviceProfile;
use crate::reading::DeviceReading;
use nalgebra::{Matrix3, Vector3};
use thiserror::Error;

/// Longest time since the last accepted reading over which a jump is judged against the device's top speed,
/// s: 1 (at an Omni's 5 m/s, 5 m: beyond any workspace; a stamp far in the future does not excuse any jump).
pub const TELEPORT_WINDOW: f64 = 1.0;

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
        /// Time since the last accepted reading it was judged over (at least the step), s.
        dt: f64,
        /// The profile's limit, m/s.
        max_speed: f64,
    },
}

/// The hair's reaction on the tool proxy, linearised about the proxy's state: the **local force model** that
/// each physics step publishes and the coupling renders against until the next one (an intermediate
/// representation: Mark et al., SIGGRAPH 1996; Adachi et al. 1995). At proxy position `x` and velocity `v` the
/// hair pushes the proxy with `force - stiffness (x - position) - damping (v - velocity)` and twists the tool
/// with `torque`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairReaction {
    /// Force on the proxy at `position` and `velocity`, N.
    pub force: Vector3<f64>,
    /// Effective damping `D = -dF/dv`, N s/m (symmetric, positive semi-definite): how much more the hair
    /// pushes back per m/s the proxy moves faster than `velocity`.
    pub damping: Matrix3<f64>,
    /// Proxy velocity at which `force` was computed, m/s.
    pub velocity: Vector3<f64>,
    /// Proxy position at which `force` was computed, m.
    pub position: Vector3<f64>,
    /// Effective stiffness `K = -dF/dx`, N/m (symmetric, positive semi-definite): how much more the hair
    /// pushes back per m the proxy is deeper than `position`.
    pub stiffness: Matrix3<f64>,
    /// Torque of the hair on the tool about the proxy, N m (held over the model's validity).
    pub torque: Vector3<f64>,
}

impl HairReaction {
    /// No contact.
    pub fn none() -> Self {
        Self { force: Vector3::zeros(), damping: Matrix3::zeros(), velocity: Vector3::zeros(), position: Vector3::zeros(), stiffness: Matrix3::zeros(), torque: Vector3::zeros() }
    }

    /// A force with no velocity or position dependence (an explicit push).
    pub fn explicit(force: Vector3<f64>) -> Self {
        Self { force, ..Self::none() }
    }

    /// The model's force on the proxy at position `x` (m) and velocity `v` (m/s), N.
    pub fn force_at(&self, x: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
        self.force - self.stiffness * (x - self.position) - self.damping * (v - self.velocity)
    }

    /// Non-finite parts replaced by none; the damping and stiffness symmetrised and their negative eigenvalues
    /// dropped (the hair may only take energy out through them).
    pub fn sanitized(&self) -> Self {
        let ok = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        let or_zero = |v: &Vector3<f64>| if ok(v) { *v } else { Vector3::zeros() };
        let psd = |m: &Matrix3<f64>| {
            if m.iter().all(|x| x.is_finite()) {
                let sym = (m + m.transpose()) * 0.5;
                let e = sym.symmetric_eigen();
                let vals = e.eigenvalues.map(|x| x.max(0.0));
                e.eigenvectors * Matrix3::from_diagonal(&vals) * e.eigenvectors.transpose()
            } else {
                Matrix3::zeros()
            }
        };
        // A stiffness about a non-finite position has no anchor: dropped.
        let stiffness = if ok(&self.position) { psd(&self.stiffness) } else { Matrix3::zeros() };
        Self { force: or_zero(&self.force), damping: psd(&self.damping), velocity: or_zero(&self.velocity), position: or_zero(&self.position), stiffness, torque: or_zero(&self.torque) }
    }
}

/// Parameters of the coupling. Defaults suit a 1 kHz loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingParams {
    /// Coupling stiffness, N/m. Default: half the device's `max_stiffness`.
    pub stiffness: f64,
    /// Coupling damping `b`, N s/m: the damper of the coupling's viscoelastic branch. Default: critical
    /// damping of the proxy, `2 sqrt(k m)`.
    pub damping: f64,
    /// Relaxation time `tau` of the damper branch, s (>= 0): the damper sits in series with a spring of
    /// stiffness `b / tau`, so its force follows `b (v_dev - v_proxy)` with this time constant and changes by
    /// at most `b |dv| h / (tau + h)` in a step of `h` when the proxy's velocity jumps by `dv` (0: a plain
    /// damper, whose force jumps by `b |dv|`). Default 0.003 (3 haptic steps; a fingertip's viscoelastic
    /// relaxation is slower, tens of ms): the proxy's spring mode stays damped (Omni: 39 Hz, damping ratio
    /// 0.56; 16 Hz critically damped with a plain damper), while the comb catching hair near the roots (the
    /// proxy slowed by 0.01-0.016 m/s in one step in the browser's stroke) gives the hand 0.04 N in one step
    /// instead of 0.13-0.16 N.
    pub damper_time: f64,
    /// Mass of the tool proxy, kg. Default 0.05.
    pub proxy_mass: f64,
}

impl CouplingParams {
    /// Defaults for a device profile.
    pub fn for_profile(p: &DeviceProfile) -> Self {
        let k = 0.5 * p.max_stiffness;
        let m = 0.05;
        Self { stiffness: k, damping: 2.0 * (k * m).sqrt(), damper_time: 0.003, proxy_mass: m }
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
    /// Torque last sent to the device, N m (always zero on a profile with no torque, `max_torque` 0).
    pub torque: Vector3<f64>,
    /// Last accepted device rotation (tool frame to world).
    pub rotation: Matrix3<f64>,
    /// Device angular velocity (finite difference of the rotations, world frame), rad/s.
    pub angular_velocity: Vector3<f64>,
    /// Force of the coupling's damper branch on the proxy, N (see [`CouplingParams::damper_time`]).
    pub damper_force: Vector3<f64>,
    /// Passivity observer: energy absorbed from the user through the device port's force, J (kept >= 0).
    pub energy: f64,
    /// Passivity observer of the port's torque: energy absorbed from the user through it, J (kept >= 0).
    pub rotational_energy: f64,
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
            torque: Vector3::zeros(),
            rotation: Matrix3::identity(),
            angular_velocity: Vector3::zeros(),
            damper_force: Vector3::zeros(),
            energy: 0.0,
            rotational_energy: 0.0,
            passivity_activations: 0,
            clamp_activations: 0,
            last_time: None,
        }
    }

    /// One haptic step of `dt` seconds with a device reading and the hair's reaction on the tool proxy
    /// (`hair_force`, N). Returns the force to send to the device (N), or an error (and zero force) for a bad
    /// reading; the proxy then holds still.
    pub fn update(&mut self, reading: &DeviceReading, dt: f64, hair_force: &Vector3<f64>) -> Result<Vector3<f64>, InputError> {
        self.update_implicit(reading, dt, &HairReaction::explicit(*hair_force))
    }

    /// As [`Coupling::update`], with the hair's reaction linearised in the proxy's velocity ([`HairReaction`]),
    /// taken implicitly. Non-finite parts of the reaction are ignored, the damping is made symmetric positive
    /// semi-definite.
    pub fn update_implicit(&mut self, reading: &DeviceReading, dt: f64, hair: &HairReaction) -> Result<Vector3<f64>, InputError> {
        let finite = reading.time.is_finite() && reading.position.iter().all(|x| x.is_finite()) && reading.rotation.iter().all(|x| x.is_finite());
        if !finite || !dt.is_finite() || dt <= 0.0 {
            self.reject();
            return Err(InputError::NonFinite { time: reading.time });
        }
        // A teleport: farther from the last accepted reading than the device's top speed covers in the time
        // since it (by the readings' own stamps, at least one step, at most TELEPORT_WINDOW). Judged by the time
        // since, a stream that resumes after its sender stalled is taken back as soon as the time covers the
        // distance; judged by one step, every reading after the stall stayed too far from the stale one and the
        // hand felt nothing for the rest of the session (the CHAI3D bridge test on a loaded host: a 19 ms stall).
        let jump = (reading.position - self.device).norm();
        let since = self.last_time.map_or(dt, |t0| {
            let e = reading.time - t0;
            if e.is_finite() { e.clamp(dt, TELEPORT_WINDOW.max(dt)) } else { dt }
        });
        if self.last_time.is_some() && jump > self.profile.max_speed * since {
            self.reject();
            return Err(InputError::Teleport { distance: jump, dt: since, max_speed: self.profile.max_speed });
        }
        self.device_velocity = if self.last_time.is_some() { (reading.position - self.device) / dt } else { Vector3::zeros() };
        self.angular_velocity = if self.last_time.is_some() { angular_velocity(&self.rotation, &reading.rotation, dt) } else { Vector3::zeros() };
        self.device = reading.position;
        self.rotation = reading.rotation;
        self.last_time = Some(reading.time);
        let hair = hair.sanitized();

        // Proxy dynamics, implicit in the new velocity (the coupling spring and damper branch at the new proxy
        // state, the hair's reaction linearised about the velocity it was computed at). The damper branch,
        // backward Euler: F_d' = keep F_d + c (v_dev - v), keep = tau / (tau + h), c = b h / (tau + h).
        let (k, b, m) = (self.params.stiffness, self.params.damping, self.params.proxy_mass);
        let tau = self.params.damper_time.max(0.0);
        let (keep, c) = (tau / (tau + dt), b * dt / (tau + dt));
        let x_rel = self.device - self.proxy;
        // The hair at the new state: f0 - K (x + h v - x0) - D (v - v0).
        // (m + c h + k h^2) v + D h v + K h^2 v = m v_old + (k x_rel + keep F_d + c v_dev + f0 - K (x - x0) + D v0) h,
        // solved for v.
        let a = Matrix3::identity() * (m + c * dt + k * dt * dt) + hair.damping * dt + hair.stiffness * (dt * dt);
        let hair_now = hair.force - hair.stiffness * (self.proxy - hair.position) + hair.damping * hair.velocity;
        let rhs = self.proxy_velocity * m + (x_rel * k + self.damper_force * keep + self.device_velocity * c + hair_now) * dt;
        // `a` is symmetric positive definite (m > 0, D >= 0): Cholesky never fails for finite input.
        let v_new = a.cholesky().map_or(rhs / (m + c * dt + k * dt * dt), |ch| ch.solve(&rhs));
        self.proxy_velocity = v_new;
        self.proxy += v_new * dt;
        self.damper_force = self.damper_force * keep + (self.device_velocity - self.proxy_velocity) * c;
        let coupling = (self.device - self.proxy) * k + self.damper_force;

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
        self.torque = self.render_torque(&hair.torque, dt);
        Ok(f)
    }

    /// The torque on the hand for the hair's torque on the tool `hair` (N m): the tool turns with the device
    /// (no rotational proxy), so the hand feels the hair's torque, rate-limited to the profile's
    /// `max_torque_rate`, passivity-controlled on its own port (damping along the device's angular velocity
    /// keeps `rotational_energy` >= 0) and clamped to `max_torque` (zero on a 3-DOF profile).
    fn render_torque(&mut self, hair: &Vector3<f64>, dt: f64) -> Vector3<f64> {
        let p = &self.profile;
        if !(p.max_torque > 0.0) {
            return Vector3::zeros();
        }
        let mut t = *hair;
        let max_step = p.max_torque_rate * dt;
        let step = t - self.torque;
        if step.norm() > max_step {
            t = self.torque + step * (max_step / step.norm());
        }
        let w = self.angular_velocity;
        let de = -t.dot(&w) * dt;
        if self.rotational_energy + de < 0.0 && w.norm_squared() > 0.0 {
            t -= w * (-(self.rotational_energy + de) / (w.norm_squared() * dt));
            self.passivity_activations += 1;
        }
        if t.norm() > p.max_torque {
            t *= p.max_torque / t.norm();
        }
        self.rotational_energy -= t.dot(&w) * dt;
        t
    }

    /// Puts the proxy at `position` (m), at rest, with no force in the coupling's damper branch and zero force
    /// to the device (the runaway guard's reset); the device's state is kept.
    pub fn put_proxy_at(&mut self, position: Vector3<f64>) {
        self.proxy = position;
        self.proxy_velocity = Vector3::zeros();
        self.damper_force = Vector3::zeros();
        self.force = Vector3::zeros();
        self.torque = Vector3::zeros();
    }

    fn reject(&mut self) {
        self.force = Vector3::zeros();
        self.torque = Vector3::zeros();
        self.angular_velocity = Vector3::zeros();
        self.damper_force = Vector3::zeros();
        self.proxy_velocity = Vector3::zeros();
        self.device_velocity = Vector3::zeros();
    }
}

/// Angular velocity (world frame, rad/s) that turns `from` into `to` in `dt` s: the rotation vector of
/// `to from^T` over `dt` (both re-orthonormalised first; zero if either is not a rotation).
pub fn angular_velocity(from: &Matrix3<f64>, to: &Matrix3<f64>, dt: f64) -> Vector3<f64> {
    let rel = nalgebra::Rotation3::from_matrix(&(to * from.transpose()));
    let w = rel.scaled_axis() / dt;
    if w.iter().all(|x| x.is_finite()) { w } else { Vector3::zeros() }
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
    fn a_stream_resuming_after_a_stall_is_taken_back_and_a_teleport_is_not() {
        // A family: every haptic device profile, the device moving at 0.1-1 m/s stamped every 1 ms (1 kHz) or
        // 0.25 ms (4 kHz), its sender stalling 5, 20 or 50 ms (up to ten times the profile's top speed over one
        // step): the reading after the stall is accepted and the hair's 0.5 N comes back within 50 steps (a
        // one-step judgement rejected it, and every reading after it, for good). Then a 0.3 m jump within one
        // step is rejected, and the stream's next reading is accepted. Reports the worst case.
        let mut cases = 0;
        let mut weakest = f64::INFINITY;
        for p in [DeviceProfile::PHANTOM_OMNI, DeviceProfile::PHANTOM_DESKTOP, DeviceProfile::OMEGA3, DeviceProfile::PHANTOM_PREMIUM_6DOF] {
            for speed in [0.1, 0.5, 1.0] {
                for dt in [1e-3, 2.5e-4] {
                    for stall in [0.005, 0.02, 0.05] {
                        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
                        let at = |t: f64| reading(t, Vector3::new(speed * t, 0.0, 0.0));
                        let hair = Vector3::new(0.0, -0.5, 0.0);
                        let mut t = 0.0;
                        for _ in 0..(0.05 / dt) as usize {
                            c.update(&at(t), dt, &hair).unwrap();
                            t += dt;
                        }
                        t += stall;
                        for _ in 0..(0.05 / dt) as usize {
                            assert!(c.update(&at(t), dt, &hair).is_ok(), "{} {speed} m/s, dt {dt}, stall {stall}: rejected at t {t}", p.name);
                            t += dt;
                        }
                        assert!(c.force.y < -0.4, "{} {speed} m/s, dt {dt}, stall {stall}: the hair's 0.5 N is felt again: {:?}", p.name, c.force);
                        weakest = weakest.min(-c.force.y);
                        let jump = reading(t, Vector3::new(speed * t + 0.3, 0.0, 0.0));
                        assert!(matches!(c.update(&jump, dt, &Vector3::zeros()), Err(InputError::Teleport { .. })), "{}: a 0.3 m jump", p.name);
                        t += dt;
                        assert!(c.update(&at(t), dt, &Vector3::zeros()).is_ok(), "{}: the stream after the jump", p.name);
                        cases += 1;
                    }
                }
            }
        }
        eprintln!("{cases} cases; weakest force felt again 50 ms after a stall: {weakest:.3} N (of the hair's 0.5 N)");
        assert_eq!(cases, 72);
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

    /// A dense patch of hair as seen by the proxy inside the slab 2 cm <= y <= 15 cm: a stiff viscous drag
    /// `D = 2000 N s/m` (each of many light strands answers within a step) that saturates at 1.5 N (they slide
    /// off), reached 1 cm inside the patch (the hair thins out over its edges). Returns the reaction at proxy
    /// velocity `v`, linearised (D where not saturated, the secant `cap / |v|` where it is).
    fn dense_patch(proxy: &Vector3<f64>, v: &Vector3<f64>) -> HairReaction {
        let d = 2000.0;
        let cap = 1.5 * ((proxy.y - 0.02) / 0.01).min((0.15 - proxy.y) / 0.01).clamp(0.0, 1.0);
        if !(0.02..=0.15).contains(&proxy.y) {
            return HairReaction { velocity: *v, ..HairReaction::none() };
        }
        let f = -v * d;
        if f.norm() > cap {
            // Saturated: its secant (the drag that gives the cap at this speed), which stays right as the
            // proxy slows down.
            HairReaction { force: f * (cap / f.norm()), damping: Matrix3::identity() * (cap / v.norm()), velocity: *v, ..HairReaction::none() }
        } else {
            HairReaction { force: f, damping: Matrix3::identity() * d, velocity: *v, ..HairReaction::none() }
        }
    }

    #[test]
    fn an_implicit_proxy_is_not_thrown_by_a_stiff_dense_patch() {
        // Omni profile, the device drawn 10 cm through the dense patch (a minimum-jerk stroke at a mean 0.1,
        // 0.2 and 0.3 m/s, the stroke speeds) and held there 0.2 s. Explicitly (`D h / m = 40`, with
        // a plain damper, `damper_time` 0, whose force follows the chattering proxy at once), once the proxy
        // slows down the reaction flips sign every step: the proxy chatters and the device force jumps at the
        // rate clamp (0.3 N per step). Taken implicitly the proxy stays within 1.5 N / k + 1 mm
        // of the device (never more than 0.5 mm ahead of it: it is not thrown forward), the device force never
        // changes by more than 0.1 N in one step and no clamp acts.
        let p = DeviceProfile::PHANTOM_OMNI;
        let run = |speed: f64, implicit: bool| {
            let params = if implicit { CouplingParams::for_profile(&p) } else { CouplingParams { damper_time: 0.0, ..CouplingParams::for_profile(&p) } };
            let mut c = Coupling::new(p, params, Vector3::zeros());
            let mut hair = HairReaction::none();
            let (mut gap, mut jump, mut ahead, mut peak) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            let mut last = Vector3::zeros();
            let duration = 0.1 / speed;
            for n in 0..(duration / 1e-3) as usize + 200 {
                let t = n as f64 * 1e-3;
                // A hand's stroke of 10 cm (minimum jerk, mean speed `speed`), then rest.
                let u = (t / duration).min(1.0);
                let x = Vector3::new(0.0, 0.1 * (10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5)), 0.0);
                let r = if implicit { hair } else { HairReaction::explicit(hair.force) };
                let f = c.update_implicit(&reading(t, x), 1e-3, &r).unwrap();
                gap = gap.max((c.proxy - c.device).norm());
                ahead = ahead.max(c.proxy.y - c.device.y);
                jump = jump.max((f - last).norm());
                peak = peak.max(f.norm());
                last = f;
                hair = dense_patch(&c.proxy, &c.proxy_velocity);
            }
            (gap, jump, ahead, peak, c.clamp_activations)
        };
        let k = CouplingParams::for_profile(&p).stiffness;
        for speed in [0.1, 0.2, 0.3] {
            let (gap, jump, ahead, peak, clamps) = run(speed, true);
            println!("implicit {speed} m/s: gap {gap:.2e} m, ahead {ahead:.2e} m, largest step change {jump:.3} N, peak {peak:.3} N, clamps {clamps}");
            assert!(gap <= 1.5 / k + 1e-3, "{speed} m/s: proxy {gap} m from the device");
            assert!(ahead <= 5e-4, "{speed} m/s: proxy {ahead} m ahead of the device");
            assert!(jump <= 0.1, "{speed} m/s: force jumped {jump} N in one step");
            assert!(peak < p.max_force && clamps == 0, "{speed} m/s: clamped ({peak} N, {clamps} steps)");
            let (_, jump, _, _, clamps) = run(speed, false);
            println!("explicit {speed} m/s: largest step change {jump:.3} N, clamps {clamps}");
            assert!(jump > 0.25 && clamps > 0, "{speed} m/s: the explicit proxy should chatter (jump {jump} N, {clamps} clamps)");
        }
    }

    #[test]
    fn a_sudden_stop_reaches_the_hand_over_the_damper_time() {
        // The hand moves at v = 0.02 m/s from rest while the proxy is held still (a hair reaction of damping
        // 1e9 N s/m: the comb caught on a stiff wisp at once). The damper branch obeys
        // dF/dt = (b v - F) / tau: F(t) = b v (1 - exp(-t / tau)), and its backward-Euler steps give exactly
        // F_n = b v (1 - (tau / (tau + h))^n). Asserted: the device force is minus the spring k v t plus F_n
        // (within 1e-6 N: the proxy creeps by v h k / 1e9 per step), F_n within 0.25 (h / tau) b v of the exponential
        // (backward Euler's first-order lag: 0.055 b v at most for tau = 3 h), and no step changes the force by more than
        // b v h / (tau + h) + k v h (0.06 N); a plain damper (`damper_time` 0) jumps by b v + k v h at once
        // (0.21 N), checked too.
        let p = DeviceProfile::PHANTOM_OMNI;
        let (h, v) = (1e-3, 0.02);
        let held = HairReaction { damping: Matrix3::identity() * 1e9, ..HairReaction::none() };
        let run = |params: CouplingParams| {
            let mut c = Coupling::new(p, params, Vector3::zeros());
            let mut forces = Vec::new();
            for n in 0..=40 {
                let t = n as f64 * h;
                forces.push(c.update_implicit(&reading(t, Vector3::new(v * t, 0.0, 0.0)), h, &held).unwrap().x);
            }
            forces
        };
        let params = CouplingParams::for_profile(&p);
        let (k, b, tau) = (params.stiffness, params.damping, params.damper_time);
        let f = run(params);
        let mut largest: f64 = 0.0;
        for n in 1..f.len() {
            let t = n as f64 * h;
            let discrete = b * v * (1.0 - (tau / (tau + h)).powi(n as i32));
            let exact = b * v * (1.0 - (-t / tau).exp());
            assert!((-f[n] - (k * v * t + discrete)).abs() < 1e-6, "step {n}: {} vs {}", -f[n], k * v * t + discrete);
            assert!((discrete - exact).abs() < 0.25 * h / tau * b * v, "step {n}: scheme {discrete} vs law {exact}");
            largest = largest.max((f[n] - f[n - 1]).abs());
        }
        let bound = b * v * h / (tau + h) + k * v * h;
        println!("damper time {tau} s: largest step change {largest:.4} N (bound {bound:.4} N)");
        assert!(largest <= bound + 1e-6, "{largest} N in one step");
        let plain = run(CouplingParams { damper_time: 0.0, ..params });
        let first = (plain[1] - plain[0]).abs();
        println!("plain damper: first step change {first:.4} N");
        assert!((first - (b * v + k * v * h)).abs() < 1e-6, "plain damper's first step {first} N");
    }

    #[test]
    fn a_reaction_damping_with_bad_parts_is_made_safe() {
        // A non-symmetric, indefinite or NaN damping matrix never makes the proxy move faster than the device
        // (the sanitised damping only takes energy out): the proxy stays finite and within 1 cm.
        let p = DeviceProfile::PHANTOM_OMNI;
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
        let bad = [
            Matrix3::new(-1e4, 0.0, 0.0, 0.0, 10.0, 5e3, 0.0, -5e3, 10.0),
            Matrix3::from_element(f64::NAN),
            Matrix3::identity() * 1e12,
        ];
        for n in 0..600 {
            let t = n as f64 * 1e-3;
            let r = HairReaction { damping: bad[n % 3], velocity: c.proxy_velocity, ..HairReaction::none() };
            c.update_implicit(&reading(t, Vector3::new(0.05 * t, 0.0, 0.0)), 1e-3, &r).unwrap();
            assert!(c.proxy.iter().all(|x| x.is_finite()));
            assert!((c.proxy - c.device).norm() < 0.01, "step {n}: {}", (c.proxy - c.device).norm());
        }
    }

    fn turning(t: f64, x: Vector3<f64>, angle: f64) -> DeviceReading {
        DeviceReading { rotation: nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), angle).into_inner(), ..reading(t, x) }
    }

    #[test]
    fn the_torque_is_rate_limited_clamped_to_the_profile_and_zero_on_3dof_devices() {
        // A hair torque that steps from 0 to T about x (T from 0.01 to 10 N m, both signs) while the device is
        // held still: on the Phantom Premium 6-DOF profile the torque sent rises by max_torque_rate * dt per step
        // (1e-12 N m) and settles at T or at the 0.188 N m clamp, whichever is smaller; on every 3-DOF
        // profile it stays exactly zero.
        for profile in [DeviceProfile::PHANTOM_PREMIUM_6DOF, DeviceProfile::PHANTOM_OMNI, DeviceProfile::PHANTOM_DESKTOP, DeviceProfile::OMEGA3] {
            for t_hair in [0.01, 0.1, 0.188, 1.0, 10.0, -0.05, -3.0] {
                let mut c = Coupling::new(profile, CouplingParams::for_profile(&profile), Vector3::zeros());
                let hair = HairReaction { torque: Vector3::new(t_hair, 0.0, 0.0), ..HairReaction::none() };
                let dt = 1e-3;
                let mut last = 0.0;
                for n in 0..200 {
                    c.update_implicit(&reading(n as f64 * dt, Vector3::zeros()), dt, &hair).unwrap();
                    let t = c.torque.x;
                    if profile.max_torque == 0.0 {
                        assert_eq!(c.torque, Vector3::zeros(), "{}", profile.name);
                        continue;
                    }
                    assert!(c.torque.norm() <= profile.max_torque + 1e-12, "{}: {} N m", profile.name, c.torque.norm());
                    assert!((t - last).abs() <= profile.max_torque_rate * dt + 1e-12, "{}: step {n}", profile.name);
                    last = t;
                }
                if profile.max_torque > 0.0 {
                    let expect = t_hair.signum() * t_hair.abs().min(profile.max_torque);
                    assert!((c.torque.x - expect).abs() < 1e-12, "{} N m for a hair torque of {t_hair}: {}", expect, c.torque.x);
                }
            }
        }
    }

    #[test]
    fn a_torque_that_would_feed_the_hand_energy_is_made_passive() {
        // An active environment twists the tool along the device's own turning (torque = +0.5 N m s/rad times
        // the angular velocity, a negative rotational damper) while the hand turns the device back and forth
        // (0.6 rad at 1 Hz): the rotational port's energy stays >= 0 at every step (1e-12 J) and the controller
        // acts. A resisting environment (the opposite sign) never needs it and its energy grows.
        let p = DeviceProfile::PHANTOM_PREMIUM_6DOF;
        for sign in [1.0, -1.0] {
            let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
            let dt = 1e-3;
            for n in 0..3000 {
                let t = n as f64 * dt;
                let hair = HairReaction { torque: c.angular_velocity * (0.5 * sign), ..HairReaction::none() };
                c.update_implicit(&turning(t, Vector3::zeros(), 0.6 * (2.0 * std::f64::consts::PI * t).sin()), dt, &hair).unwrap();
                assert!(c.rotational_energy >= -1e-12, "energy {} at t = {t}", c.rotational_energy);
            }
            if sign > 0.0 {
                assert!(c.passivity_activations > 0, "the controller never acted");
            } else {
                assert_eq!(c.passivity_activations, 0);
                assert!(c.rotational_energy > 0.0);
            }
        }
    }

    #[test]
    fn the_angular_velocity_is_the_turn_between_readings() {
        // Turning about a generated family of axes by 0.001-0.05 rad per step of 0.1-1 ms: the finite difference
        // gives axis * angle / dt within 1e-9 relative.
        for (i, axis) in [Vector3::x(), Vector3::y(), Vector3::new(1.0, -2.0, 0.5).normalize(), Vector3::new(-0.3, 0.2, 1.0).normalize()].iter().enumerate() {
            for angle in [0.001, 0.01, 0.05] {
                for dt in [1e-4, 2.5e-4, 1e-3] {
                    let from = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3 * i as f64).into_inner();
                    let to = nalgebra::Rotation3::from_scaled_axis(axis * angle).into_inner() * from;
                    let w = angular_velocity(&from, &to, dt);
                    assert!((w - axis * (angle / dt)).norm() <= 1e-9 * angle / dt, "{w:?}");
                }
            }
        }
    }

    #[test]
    fn a_stiff_local_model_holds_the_proxy_where_the_springs_balance_at_every_rate() {
        // The local force model of a surface pushing back with stiffness K = 400-3000 N/m along y from x0 = 0
        // (f0 = 0), the device held 5 mm into it: the proxy settles where the coupling spring k and K balance,
        // y = k d / (k + K), and the hand feels k (d - y), at 1, 4 and 10 kHz (within 1e-6 m and 1e-4 N
        // after 1 s), with no clamp acting; the passivity observer never goes below zero.
        let p = DeviceProfile::PHANTOM_DESKTOP;
        let params = CouplingParams::for_profile(&p);
        let k = params.stiffness;
        let d = 0.005;
        for stiff in [400.0, 1000.0, 3000.0] {
            for rate in [1000.0, 4000.0, 10000.0] {
                let dt = 1.0 / rate;
                let mut c = Coupling::new(p, params, Vector3::zeros());
                let model = HairReaction { stiffness: Matrix3::from_diagonal(&Vector3::new(0.0, stiff, 0.0)), ..HairReaction::none() };
                for n in 0..(rate as usize) {
                    let t = n as f64 * dt;
                    // The hand moves in over 0.2 s (a ramp slow enough for the rate clamp), then holds.
                    let y = d * (t / 0.2).min(1.0);
                    c.update_implicit(&reading(t, Vector3::new(0.0, y, 0.0)), dt, &model).unwrap();
                    assert!(c.energy >= -1e-12);
                }
                let y = k * d / (k + stiff);
                assert!((c.proxy.y - y).abs() < 1e-6, "K {stiff} at {rate} Hz: proxy at {} m, expected {y} m", c.proxy.y);
                assert!((c.force.y + k * (d - y)).abs() < 1e-4, "K {stiff} at {rate} Hz: force {} N, expected {}", c.force.y, -k * (d - y));
                assert_eq!(c.clamp_activations, 0);
            }
        }
    }
}
