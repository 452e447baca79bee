//! Smoothing of a pointer's target for the haptic loop: a mouse reports positions at 60-125 Hz while the loop
//! runs at 1 kHz. Following each new target at a capped speed moves the device point in bursts (at the cap,
//! then still), and the proxy's inertia turns each burst into a force pulse with no hair at all. Instead, the
//! device point is interpolated at the haptic rate between pointer events: each new event starts a linear
//! ramp from where the point is to the event's position, lasting the mean interval between events (its
//! running average), so the point moves at the pointer's own speed.
//!
//! Per haptic step ([`TargetFilter::step`]):
//! 1. when the reading differs from the last event, it is a new event: the interval since the previous event
//!    updates the running mean (clamped to `[min_interval, max_interval]`) and a ramp starts from the current
//!    point;
//! 2. the ramp advances by `dt / interval` (reaching the event after one mean interval);
//! 3. the device point follows the ramp: it wants the ramp's velocity plus a pull towards the ramp (rate
//!    `2 / interval`), at most `max_speed` and at most `sqrt(2 max_acceleration d)` with `d` the distance to
//!    the last event (so it brakes in time and does not overshoot), and its velocity turns towards that at
//!    most at `max_acceleration` (continuous velocity, bounded acceleration). A jump of the target (a slow
//!    viewer's sparse events, the pressed plane, the first event) is followed as a hand would, and the
//!    proxy's inertia never turns it into a force pulse.
//!
//! A haptic device's stream (`TargetParams::stream`, [`TargetFilter::follow`]) is followed differently: its
//! samples come every period or so, stamped by the device's own clock, but arrive with the jitter of the
//! network and of two loops' phases (none in one step, two in the next). A ramp per arrival turned that
//! jitter into velocity steps of the device point, which the coupling's damper turned into force steps at
//! the Omni's rate limit (0.3 N a step) all through a stroke. Instead, per haptic step:
//! 1. a new sample (a later time stamp) sets the anchor: its position and the velocity from the last sample
//!    at least `min_interval` before it, by their own time stamps (at most `max_speed`; zero after a gap over
//!    `max_interval`; samples closer together keep the velocity), and the offset between the loop's clock
//!    and the device's (the least arrival delay seen, rising at most 1 % of the elapsed time so that it
//!    follows a drifting clock);
//! 2. the point the device is at now on its own clock is the anchor extrapolated at its velocity (for at
//!    most [`STREAM_HORIZON`]: a sender that stops stops there), so a late or missing sample changes
//!    nothing, a late one does not step back, and a sender stalled for a few ms that then sends its samples
//!    in a burst (device-sim on a loaded machine: 8 at once every 8 ms) is followed smoothly (a moved sample
//!    with the last one's stamp is stamped on arrival, on the loop's clock);
//! 3. the device point moves at that extrapolation's velocity plus a pull onto it with time constant
//!    [`STREAM_PULL_STEPS`] steps or twice the mean time between arrivals (a running mean with weight
//!    `smoothing`), whichever is longer, its velocity turning at most at `max_acceleration`.

use nalgebra::Vector3;

/// Least time constant of the pull of a device stream's point onto its extrapolated samples, in haptic
/// steps. Four: a sample that arrives with a position off the extrapolation by `e` moves the point's velocity
/// by at most `e / (4 dt)` (a quarter of the dead-beat correction); samples arriving in bursts are pulled in
/// over twice the time between bursts (the extrapolation's error grows with it).
pub const STREAM_PULL_STEPS: f64 = 4.0;

/// Longest a device stream's last sample is extrapolated when no newer one arrives, s: 0.02 (a sender
/// stalled by its scheduler for up to 20 ms is followed smoothly; a hand that stops during such a stall is
/// overshot by its speed times the stall, 3 mm at 0.15 m/s, and pulled back when the samples return).
pub const STREAM_HORIZON: f64 = 0.02;

/// Rise of the stream's clock offset between samples, s per s of loop time: 1 % (a sample never arrives
/// early, so the least delay seen is the offset; the rise lets it follow a device clock slower than ours).
const OFFSET_RISE: f64 = 0.01;

/// Parameters of the pointer smoothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetParams {
    /// Shortest interval assumed between pointer events, s. Default 0.004 (250 Hz).
    pub min_interval: f64,
    /// Longest interval assumed between pointer events (a pointer at rest sends none), s. Default 0.05.
    pub max_interval: f64,
    /// Weight of a new interval in the running mean, in (0, 1]. Default 0.2.
    pub smoothing: f64,
    /// Largest speed of the device point, m/s. Default 1.5.
    pub max_speed: f64,
    /// Largest acceleration of the device point, m/s^2. Default 1: the 50 g proxy then needs at most about
    /// 0.05 N to follow in free air (a 6 cm jump of the target is followed in about 0.5 s).
    pub max_acceleration: f64,
    /// The readings are a device's stream stamped by its own clock ([`TargetFilter::follow`]: extrapolated
    /// on that clock at the samples' own velocity), not a pointer's sparse events (interpolated over their
    /// mean interval). Default false.
    pub stream: bool,
}

impl Default for TargetParams {
    fn default() -> Self {
        Self { min_interval: 0.004, max_interval: 0.05, smoothing: 0.2, max_speed: 1.5, max_acceleration: 1.0, stream: false }
    }
}

/// The device point of a pointer, interpolated between its events.
#[derive(Debug, Clone)]
pub struct TargetFilter {
    /// Parameters.
    pub params: TargetParams,
    /// Current device point, m.
    pub point: Vector3<f64>,
    /// Velocity of the point, m/s.
    pub velocity: Vector3<f64>,
    from: Vector3<f64>,
    to: Vector3<f64>,
    /// Progress along the current ramp, in [0, 1].
    progress: f64,
    /// Running mean interval between events, s.
    interval: f64,
    /// Time since the last event, s.
    since: f64,
    /// A device stream's samples and clocks (unused for a pointer).
    stream: Stream,
}

/// What [`TargetFilter::follow`] keeps of a device stream.
#[derive(Debug, Clone, Default)]
struct Stream {
    /// The last sample: its time stamp (s, the device's clock, or its arrival's, see `stamp`), position (m) and
    /// velocity (m/s).
    anchor: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    /// The sample the velocity is measured from: time stamp (s) and position (m).
    base: Option<(f64, Vector3<f64>)>,
    /// The last sample's own time stamp, s.
    stamp: Option<f64>,
    /// The filter's own clock, s (the sum of its steps), and its offset from the device's clock, s.
    clock: f64,
    offset: Option<f64>,
}

impl TargetFilter {
    /// A filter at rest at `position` (m).
    pub fn new(params: TargetParams, position: Vector3<f64>) -> Self {
        let interval = (1.0 / 60.0f64).clamp(params.min_interval, params.max_interval);
        Self { params, point: position, velocity: Vector3::zeros(), from: position, to: position, progress: 1.0, interval, since: 0.0, stream: Stream::default() }
    }

    /// One haptic step of `dt` s with the latest reading's position `target` (m) and time stamp `time` (s):
    /// a device stream ([`TargetParams::stream`]) is extrapolated on its own clock (see the module's
    /// documentation), a pointer interpolated between its events ([`TargetFilter::step`]). Returns the
    /// device point (m). Non-finite targets or times are ignored (the point holds its course).
    pub fn follow(&mut self, target: &Vector3<f64>, time: f64, dt: f64) -> Vector3<f64> {
        if !self.params.stream {
            return self.step(target, dt);
        }
        if !(dt > 0.0 && dt.is_finite()) {
            return self.point;
        }
        self.stream.clock += dt;
        self.since += dt;
        let valid = time.is_finite() && target.iter().all(|x| x.is_finite());
        let st = &self.stream;
        let advanced = st.stamp.map_or(true, |s| time > s);
        let moved = st.stamp == Some(time) && st.anchor.is_some_and(|a| *target != a.1);
        if valid && (advanced || moved) {
            self.take_sample(target, time, advanced, dt);
        } else if let Some(o) = self.stream.offset.as_mut() {
            *o += OFFSET_RISE * dt;
        }
        let st = &self.stream;
        let Some((t0, x0, v0)) = st.anchor else { return self.point };
        // Where the device is now on its own clock: the anchor extrapolated, for at most STREAM_HORIZON.
        let age = (st.clock - st.offset.unwrap_or(0.0) - t0).max(0.0);
        let (want_x, want_v) = if age < STREAM_HORIZON { (x0 + v0 * age, v0) } else { (x0 + v0 * STREAM_HORIZON, Vector3::zeros()) };
        let pull = (STREAM_PULL_STEPS * dt).max(2.0 * self.interval);
        self.drive(want_v + (want_x - self.point) / pull, self.params.max_speed, dt)
    }

    /// Takes a stream's new sample (position `target`, m, stamped `time`, s; `advanced`: later than the last
    /// stamp): its velocity, the anchor, the mean time between arrivals and the clocks' offset. A sample with
    /// the last one's stamp but moved (a client that does not stamp its poses, or stamps them coarsely) is
    /// stamped on arrival, on the loop's clock since the last sample; an earlier stamp never comes here (the
    /// UDP device refuses it before).
    fn take_sample(&mut self, target: &Vector3<f64>, time: f64, advanced: bool, dt: f64) {
        let p = self.params;
        let st = &mut self.stream;
        st.stamp = Some(time);
        let time = match st.anchor {
            Some((t0, ..)) if !advanced || time <= t0 => t0 + self.since,
            _ => time,
        };
        let velocity = match (st.anchor, st.base) {
            (Some((t1, ..)), _) if time - t1 > p.max_interval => Vector3::zeros(),
            (Some(_), Some((tb, xb))) if time - tb >= p.min_interval => {
                let v = (target - xb) / (time - tb);
                if v.norm() > p.max_speed { v * (p.max_speed / v.norm()) } else { v }
            }
            // Samples closer together than min_interval keep the velocity.
            (Some((.., v)), Some(_)) => v,
            _ => Vector3::zeros(),
        };
        if st.base.map_or(true, |(tb, _)| time - tb >= p.min_interval) {
            st.base = Some((time, *target));
        }
        st.anchor = Some((time, *target, velocity));
        let delay = st.clock - time;
        st.offset = Some(st.offset.map_or(delay, |o| delay.min(o + OFFSET_RISE * dt)));
        // The mean time between arrivals, on the loop's clock (the pull's time scale).
        self.interval += p.smoothing * (self.since.clamp(p.min_interval, p.max_interval) - self.interval);
        self.since = 0.0;
    }

    /// Moves the point for `dt` s towards the velocity `want` (m/s), at most `cap` (m/s), its velocity turning
    /// at most at `max_acceleration`; returns the point (m).
    fn drive(&mut self, mut want: Vector3<f64>, cap: f64, dt: f64) -> Vector3<f64> {
        if want.norm() > cap {
            want *= cap / want.norm();
        }
        let mut dv = want - self.velocity;
        let turn = self.params.max_acceleration * dt;
        if dv.norm() > turn {
            dv *= turn / dv.norm();
        }
        self.velocity += dv;
        self.point += self.velocity * dt;
        self.point
    }

    /// One haptic step of `dt` s with the pointer's latest target (m). Returns the device point (m).
    /// Non-finite targets are ignored (the point holds).
    pub fn step(&mut self, target: &Vector3<f64>, dt: f64) -> Vector3<f64> {
        if !(dt > 0.0 && dt.is_finite()) {
            return self.point;
        }
        self.since += dt;
        if target.iter().all(|x| x.is_finite()) && *target != self.to {
            let p = &self.params;
            let seen = self.since.clamp(p.min_interval, p.max_interval);
            self.interval += p.smoothing * (seen - self.interval);
            self.since = 0.0;
            self.from = self.from + (self.to - self.from) * self.progress;
            self.to = *target;
            self.progress = 0.0;
        }
        // The ramp (it stops at its event; the follower below smooths a late event's pause) and its velocity.
        let moving = self.progress < 1.0;
        let ramp = self.from + (self.to - self.from) * self.progress;
        self.progress = (self.progress + dt / self.interval).min(1.0);
        let ramp_velocity = if moving { (self.to - self.from) / self.interval } else { Vector3::zeros() };
        // The follower: the velocity it wants is the ramp's plus a pull towards it (rate 2 / interval, at most
        // 1 / dt), at most max_speed and sqrt(2 a_max d) with d the distance to the last event (it brakes in
        // time); its velocity turns towards that at most max_acceleration (continuous velocity, bounded
        // acceleration: the coupling sees neither a step nor a jerk it could turn into a force pulse).
        let p = &self.params;
        let rate = (2.0 / self.interval).min(1.0 / dt);
        let cap = p.max_speed.min((2.0 * p.max_acceleration * (self.to - self.point).norm()).sqrt());
        self.drive(ramp_velocity + (ramp - self.point) * rate, cap, dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coupling::{Coupling, CouplingParams};
    use crate::device::{DeviceProfile, DeviceReading};
    use nalgebra::Matrix3;

    /// A 60 Hz pointer (events 16 or 17 ms apart) drawing an 18 cm stroke in 0.9 s (a minimum-jerk profile,
    /// as a hand moves: peak 0.375 m/s, mean 0.2 m/s) then resting, fed to a 1 kHz coupling with no hair.
    fn free_air_peak(smooth: bool) -> f64 {
        let p = DeviceProfile::PHANTOM_OMNI;
        let start = Vector3::new(0.0, 0.0, 0.0);
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), start);
        let mut filter = TargetFilter::new(TargetParams::default(), start);
        let mut capped = start;
        let mut target = start;
        let mut peak = 0.0f64;
        let mut next_event = 0;
        for n in 0..1500 {
            let t = n as f64 * 1e-3;
            if n == next_event {
                let u = (t / 0.9).min(1.0);
                target = Vector3::new(0.0, 0.18 * (10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5)), 0.0);
                next_event += if (n / 16) % 3 == 0 { 17 } else { 16 };
            }
            let x = if smooth {
                filter.step(&target, 1e-3)
            } else {
                // The old device point: follows the target at 1 m/s.
                let d = target - capped;
                capped += if d.norm() > 1e-3 { d * (1e-3 / d.norm()) } else { d };
                capped
            };
            let f = c.update(&DeviceReading { time: t, position: x, rotation: Matrix3::identity(), buttons: 0 }, 1e-3, &Vector3::zeros()).unwrap();
            peak = peak.max(f.norm());
        }
        peak
    }

    #[test]
    fn a_60_hz_mouse_path_gives_a_small_free_air_force() {
        // Free air: the proxy (50 g) only needs m a (at most 0.04 N for this stroke) to follow, plus the
        // coupling damper's answer to the point's velocity changes at each event; with the interpolated point
        // the force stays under 0.15 N over the whole stroke (measured 0.051 N with the acceleration cap, 0.105 N without). The speed-capped point it replaces gives pulses
        // above 0.5 N.
        let smooth = free_air_peak(true);
        let capped = free_air_peak(false);
        println!("free-air peak force: interpolated {smooth:.4} N, speed-capped {capped:.4} N");
        assert!(smooth < 0.15, "interpolated: {smooth} N");
        assert!(capped > 0.5, "speed-capped: {capped} N");
    }

    /// Free-air force on the hand (peak, largest one-step change, N) when the pointer's target jumps by
    /// `jump` (m) in one event, as a viewer's first event or the button pressing the tool into the hair does,
    /// then (after 0.2 s, while the point still moves) turns to `jump + turn`, and rests; and where the
    /// device point ends (m from the target) and the force at the end (N).
    fn jump_response(params: TargetParams, jump: Vector3<f64>, turn: Vector3<f64>) -> (f64, f64, f64, f64) {
        let p = DeviceProfile::PHANTOM_OMNI;
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), Vector3::zeros());
        let mut filter = TargetFilter::new(params, Vector3::zeros());
        let (mut peak, mut change, mut last) = (0.0f64, 0.0f64, Vector3::zeros());
        let goal = jump + turn;
        for n in 0..3000 {
            let x = filter.step(if n < 200 { &jump } else { &goal }, 1e-3);
            let f = c.update(&DeviceReading { time: n as f64 * 1e-3, position: x, rotation: Matrix3::identity(), buttons: 0 }, 1e-3, &Vector3::zeros()).unwrap();
            peak = peak.max(f.norm());
            change = change.max((f - last).norm());
            last = f;
        }
        (peak, change, (filter.point - goal).norm(), last.norm())
    }

    #[test]
    fn a_jump_of_the_target_is_followed_without_a_force_pulse() {
        // The browser's comb stroke hit the Omni's 3.3 N clamp in free air: the first pointer event after the
        // page loaded jumps 15 cm, and pressing the button moves the target 6 cm onto the pressed plane; the
        // point followed at up to 1.5 m/s, accelerating at hundreds of m/s^2, and the 50 g proxy's inertia
        // became a force pulse. With the acceleration capped at 1 m/s^2 (and braking before the event) the
        // hand feels at most m a_max plus the braking's excess (0.1 N asserted, 0.062 N measured), the force changes by less
        // than 0.05 N a step (0.017 N measured), and the point ends on the target (1e-6 m). Without the cap the same jumps give
        // pulses above 1 N, so the check can fail.
        // A turn while moving (an L-shaped pair of events) must not leave the point circling the target (an
        // earlier acceleration-capped follower did, at 0.05 N): it ends still on it.
        for (jump, turn) in [(Vector3::new(0.0, 0.15, 0.0), Vector3::zeros()), (Vector3::new(0.02, -0.06, 0.01), Vector3::zeros()), (Vector3::new(0.0, 0.1, 0.0), Vector3::new(0.0, 0.0, -0.05))] {
            let (peak, change, miss, end) = jump_response(TargetParams::default(), jump, turn);
            let (old_peak, _, _, _) = jump_response(TargetParams { max_acceleration: f64::INFINITY, ..TargetParams::default() }, jump, turn);
            println!("jump {:.3} m, turn {:.3} m: peak {peak:.4} N, largest step change {change:.5} N, ends {miss:.2e} m off with {end:.2e} N; uncapped peak {old_peak:.3} N", jump.norm(), turn.norm());
            assert!(peak < 0.1, "peak {peak} N");
            assert!(change < 0.05, "one-step change {change} N");
            assert!(miss < 1e-6 && end < 1e-4, "ends {miss} m from the target with {end} N");
            assert!(old_peak > 1.0, "uncapped: {old_peak} N");
        }
    }

    #[test]
    fn the_point_reaches_each_event_and_ignores_nan() {
        let mut f = TargetFilter::new(TargetParams::default(), Vector3::zeros());
        let goal = Vector3::new(0.01, 0.0, 0.0);
        for _ in 0..500 {
            f.step(&goal, 1e-3);
        }
        assert!((f.point - goal).norm() < 1e-9, "{}", (f.point - goal).norm());
        f.step(&Vector3::new(f64::NAN, 0.0, 0.0), 1e-3);
        assert!((f.point - goal).norm() < 1e-9);
        // A 1 m jump is followed at max_speed at most.
        let before = f.point;
        f.step(&Vector3::new(1.0, 0.0, 0.0), 1e-3);
        assert!((f.point - before).norm() <= 1.5e-3 + 1e-15);
    }

    /// A 1 kHz device's stream as the live session follows it (the engine's `DEVICE_FOLLOW`).
    fn device_stream() -> TargetParams {
        TargetParams { min_interval: 0.00025, max_interval: 0.05, smoothing: 0.2, max_speed: 5.0, max_acceleration: 1000.0, stream: true }
    }

    /// A hand's 9 cm stroke along z in 0.6 s (minimum jerk: peak 0.28 m/s, at most 1.4 m/s^2), then at rest,
    /// sampled every 1 ms by the device's clock and delivered by `arrival(i, t_i)` (loop time, s), read by a
    /// 1 kHz loop that takes the latest sample delivered and feeds the follower with `params` and a free-air
    /// coupling (Omni). Returns the largest one-step change of the force (N), the peak force (N) and how far
    /// the point ends from the hand (m).
    fn stream_run(params: TargetParams, arrival: impl Fn(usize, f64) -> f64) -> (f64, f64, f64) {
        let p = DeviceProfile::PHANTOM_OMNI;
        let hand = |t: f64| {
            let u = (t / 0.6).clamp(0.0, 1.0);
            Vector3::new(0.0, 0.0, 0.09 * (10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5)))
        };
        let samples: Vec<(f64, f64)> = (0..1000).map(|i| {
            let t = 0.00037 + i as f64 * 1e-3;
            (t, arrival(i, t))
        }).collect();
        let mut filter = TargetFilter::new(params, hand(0.0));
        let mut c = Coupling::new(p, CouplingParams::for_profile(&p), hand(0.0));
        let (mut change, mut peak, mut last) = (0.0f64, 0.0f64, Vector3::zeros());
        let mut latest = None;
        for n in 1..900 {
            let now = n as f64 * 1e-3;
            for (i, &(_, a)) in samples.iter().enumerate() {
                if a <= now && latest.map_or(true, |l| i > l) {
                    latest = Some(i);
                }
            }
            let Some(i) = latest else { continue };
            let (t, _) = samples[i];
            let x = filter.follow(&hand(t), t, 1e-3);
            let f = c.update(&DeviceReading { time: now, position: x, rotation: Matrix3::identity(), buttons: 0 }, 1e-3, &Vector3::zeros()).unwrap();
            change = change.max((f - last).norm());
            peak = peak.max(f.norm());
            last = f;
        }
        (change, peak, (filter.point - hand(1.0)).norm())
    }

    /// A small deterministic generator in [0, 1) (the test's arrival jitter).
    fn jitter(i: usize) -> f64 {
        let x = (i as u64).wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((x >> 11) as f64) / ((1u64 << 53) as f64)
    }

    #[test]
    fn a_device_stream_with_arrival_jitter_or_bursts_gives_a_smooth_force() {
        // The server's device path: 1 kHz samples stamped by the device's clock, read by the 1 kHz loop. With
        // arrival delays of 0.2-1.0 ms (none read in some steps, two in others) the stream follower gives the
        // hand a force that changes by less than 0.02 N a step in free air (0.006 N measured); the pointer's
        // ramp per arrival, which the device path used before, gives steps of more than 0.1 N (0.3 N, the
        // Omni's rate limit, as in the live loop), so the check can fail. With the sender stalled and sending
        // 8 samples at once every 8 ms (device-sim on a loaded machine) the extrapolation misses by up to
        // a T^2 (90 um here) at each burst: steps under 0.05 N (0.034 N measured; the ramp, which then lags a
        // whole 8 ms, 0.022 N). The point ends on the hand (1e-6 m).
        let device = device_stream();
        let jittered = |i: usize, t: f64| t + 0.0002 + 0.0008 * jitter(i);
        let bursts = |_: usize, t: f64| ((t / 0.008).floor() + 1.0) * 0.008 + 0.0001;
        for (name, arrival) in [("jitter", &jittered as &dyn Fn(usize, f64) -> f64), ("bursts", &bursts)] {
            let (change, peak, miss) = stream_run(device, arrival);
            let (ramp_change, ramp_peak, _) = stream_run(TargetParams { stream: false, ..device }, arrival);
            println!("{name}: stream largest step {change:.4} N, peak {peak:.4} N, ends {miss:.1e} m off; ramp per arrival {ramp_change:.4} N, peak {ramp_peak:.4} N");
            assert!(change < if name == "jitter" { 0.02 } else { 0.05 }, "{name}: {change} N");
            assert!(name != "jitter" || ramp_change > 0.1, "{name}: the ramp gave {ramp_change} N");
            assert!(miss < 1e-6, "{name}: ends {miss} m off");
        }
    }

    #[test]
    fn a_silent_stream_is_extrapolated_for_a_while_then_held_and_bad_samples_ignored() {
        // Samples at 0.1 m/s along x every 1 ms for 50 ms, then none: the point goes on at the samples' velocity
        // for STREAM_HORIZON (20 ms) and stops there, 2 mm past the last sample (within 0.1 mm); a NaN sample, a
        // sample stamped earlier than the last, and a repeated time stamp change nothing.
        let device = device_stream();
        let mut f = TargetFilter::new(device, Vector3::zeros());
        let x = |t: f64| Vector3::new(0.1 * t, 0.0, 0.0);
        for n in 0..=50 {
            let t = n as f64 * 1e-3;
            f.follow(&x(t), t, 1e-3);
        }
        let last = x(0.05);
        for _ in 0..100 {
            f.follow(&last, 0.05, 1e-3);
            f.follow(&Vector3::new(f64::NAN, 0.0, 0.0), 0.06, 1e-3);
            f.follow(&Vector3::new(1.0, 0.0, 0.0), 0.01, 1e-3);
        }
        let past = (f.point - last).x;
        assert!((past - 0.1 * STREAM_HORIZON).abs() < 1e-4, "{past} m past the last sample");
        assert!(f.velocity.norm() < 1e-9, "held: {} m/s", f.velocity.norm());
    }

    #[test]
    fn a_stream_whose_stamps_do_not_advance_is_stamped_on_arrival() {
        // A client that stamps every pose 0 (allowed: stamps must not decrease) moving at 0.1 m/s along x: the
        // point follows it (ends within 0.1 mm of the last pose, moving at 0.1 m/s within 1 %), not frozen on
        // the first pose.
        let device = device_stream();
        let mut f = TargetFilter::new(device, Vector3::zeros());
        let mut x = Vector3::zeros();
        for n in 0..200 {
            x = Vector3::new(0.1 * n as f64 * 1e-3, 0.0, 0.0);
            f.follow(&x, 0.0, 1e-3);
        }
        assert!((f.point - x).norm() < 1e-4, "{} m from the last pose", (f.point - x).norm());
        assert!((f.velocity.x - 0.1).abs() < 1e-3, "{} m/s", f.velocity.x);
    }
}
