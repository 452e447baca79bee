//! The live session's two haptic threads: the **device loop** at the device's rate
//! (`SessionParams::device_rate_hz`, a [`HapticLoop`] reading and writing the device, running a
//! [`DeviceSide`]) and the **physics** at the haptic rate (a thread running the caller's physics step), on the
//! schedule [`crate::haptic::HapticCore::step_rates`] runs in lockstep, so a live session and its replay agree
//! to the bit:
//! - physics period k starts at the first device step within half a device period of one physics period after
//!   the device step that started period k - 1, or later (every `device_steps`-th device step when the device loop keeps its rate; a
//!   later one after the loop lost ticks to a busy machine, so the physics keeps the wall clock's pace
//!   instead of waiting for `device_steps` ticks; at most [`MAX_DEVICE_STEPS`] device steps per period). There
//!   the device thread takes the model physics step k - 1 published (waiting for it if it is late: a late
//!   physics step delays the device loop, counted in [`PhysicsStats::waits`]) and hands physics step k the
//!   proxy's state and the previous period's readings ([`Handover`]), which the record keeps, so the replay
//!   runs the same device steps per period;
//! - the device steps of period k, each of `dt / device_steps` s, render that model while physics step k runs
//!   on its own thread, with the whole period to finish.
//!
//! Nothing takes a lock: the hand-overs go through wait-free triple buffers with a period counter each.

use crate::haptic::{DeviceSide, ProxyState, Published};
use haptics::coupling::HairReaction;
use haptics::local_model::FedModel;
use haptics::device::{DeviceCommand, DeviceReading, HapticDevice};
use haptics::haptic_loop::{Histogram, HapticLoop, LoopStats};
use nalgebra::Vector3;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use triple_buffer::triple_buffer;

/// Most device steps per physics step (10 kHz over 1 kHz).
pub const MAX_DEVICE_STEPS: usize = 10;

/// How long the device thread waits for a late physics step before it goes on with the model it has, s (the
/// physics thread is stuck; counted in [`PhysicsStats::stalls`], and the record stops matching its replay).
pub const PHYSICS_STALL: f64 = 0.1;

/// What the device thread hands the physics thread at the start of physics period `period`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handover {
    /// The physics period starting (1 for the first).
    pub period: u64,
    /// The device side's proxy state at the period's start.
    pub proxy: ProxyState,
    /// The previous period's device readings (the first `count`).
    pub readings: [Option<DeviceReading>; MAX_DEVICE_STEPS],
    /// How many readings the previous period had (0 before the first).
    pub count: usize,
    /// The previous period's last force sent to the device, N.
    pub force: Vector3<f64>,
}

impl Handover {
    /// The previous period's device readings.
    pub fn previous_readings(&self) -> &[Option<DeviceReading>] {
        &self.readings[..self.count]
    }
}

/// Timing of the physics thread.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PhysicsStats {
    /// Physics steps run.
    pub steps: u64,
    /// Step time: mean, median, 99th, 99.9th percentile and longest, s.
    pub step_mean: f64,
    /// Median step time, s.
    pub step_p50: f64,
    /// 99th percentile, s.
    pub step_p99: f64,
    /// 99.9th percentile, s.
    pub step_p999: f64,
    /// Longest step, s.
    pub step_max: f64,
    /// Steps longer than the physics period (their model came late to the device loop).
    pub over: u64,
    /// Periods whose start the device thread had to wait for the physics step before.
    pub waits: u64,
    /// Waits given up after [`PHYSICS_STALL`] (the device loop went on with an older model).
    pub stalls: u64,
    /// Physics steps that panicked (the device loop renders no hair for the next period).
    pub panics: u64,
}

/// The running pair of threads; [`DeviceLoop::stop`] ends both.
pub struct DeviceLoop {
    device: HapticLoop<Box<dyn HapticDevice>>,
    physics: JoinHandle<(Histogram, u64, u64)>,
    stop: Arc<AtomicBool>,
    waits: Arc<AtomicU64>,
    stalls: Arc<AtomicU64>,
}

impl DeviceLoop {
    /// Starts the physics thread (running `physics` once per period with the hand-over, returning what it
    /// publishes) and the device loop at `device_rate_hz` (`device_steps` device steps of `dt / device_steps`
    /// s per physics period of `dt` s, the device side `side` rendering `first` until the first physics step
    /// has published). `priority`: the device loop's real-time priority (`HapticLoop::spawn_with_priority`);
    /// the physics thread asks for the same.
    #[allow(clippy::too_many_arguments)]
    pub fn spawn<P, R>(mut device: Box<dyn HapticDevice>, mut side: DeviceSide, first: Published, dt: f64, device_steps: usize, priority: Option<i32>, mut physics: P, on_refused: R) -> Result<Self, String>
    where
        P: FnMut(&Handover) -> Published + Send + 'static,
        R: Fn(String) + Send + Clone + 'static,
    {
        if !(1..=MAX_DEVICE_STEPS).contains(&device_steps) {
            return Err(format!("device steps per physics step must be 1..={MAX_DEVICE_STEPS}, got {device_steps}"));
        }
        let (mut hand_in, mut hand_out) = triple_buffer(&Handover { period: 0, proxy: side.proxy_state(), readings: [None; MAX_DEVICE_STEPS], count: 0, force: Vector3::zeros() });
        let (mut pub_in, mut pub_out) = triple_buffer(&first);
        let handed = Arc::new(AtomicU64::new(0));
        let done = Arc::new(AtomicU64::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let (waits, stalls) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));

        // Physics thread.
        let (handed_p, done_p, stop_p) = (handed.clone(), done.clone(), stop.clone());
        // The device loop's thread, once it has waited for a late physics step (the physics thread wakes it).
        let device_thread: Arc<std::sync::OnceLock<std::thread::Thread>> = Arc::default();
        let device_thread_p = device_thread.clone();
        let refused = on_refused.clone();
        let physics_thread = std::thread::Builder::new()
            .name("coiffure-physics".into())
            .spawn(move || {
                if let Some(p) = priority {
                    if let Err(why) = haptics::realtime::request_realtime(p) {
                        refused(format!("physics thread: {why}"));
                    }
                }
                let (mut hist, mut over, mut panics) = (Histogram::new(), 0u64, 0u64);
                let mut next = 1u64;
                let mut last = first;
                while !stop_p.load(Ordering::Relaxed) {
                    if handed_p.load(Ordering::Acquire) < next {
                        std::thread::park_timeout(Duration::from_millis(1));
                        continue;
                    }
                    let h = *hand_out.read();
                    let t0 = Instant::now();
                    let out = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| physics(&h))) {
                        Ok(p) => p,
                        Err(_) => {
                            // No hair for the next period (a model of its own: the device side takes it).
                            panics += 1;
                            Published { model: HairReaction::none(), step: u64::MAX - h.period, ..last }
                        }
                    };
                    last = out;
                    pub_in.write(out);
                    done_p.store(h.period, Ordering::Release);
                    if let Some(t) = device_thread_p.get() {
                        t.unpark();
                    }
                    let took = t0.elapsed().as_secs_f64();
                    hist.add(took);
                    over += (took > dt) as u64;
                    next = h.period + 1;
                }
                (hist, over, panics)
            })
            .map_err(|e| format!("cannot start the physics thread: {e}"))?;

        // Device loop. A device that forwards the model (the UDP device's version-2 answers) gets each new one.
        let mut feed = device.model_feed();
        let waker = physics_thread.thread().clone();
        let (waits_d, stalls_d) = (waits.clone(), stalls.clone());
        let h = dt / device_steps as f64;
        let mut published = first;
        let mut readings = [None; MAX_DEVICE_STEPS];
        let mut count = 0;
        let mut force = Vector3::zeros();
        // Physics periods by the wall clock: the start of the current one, and how many have started.
        let period = Duration::from_secs_f64(dt);
        let half_tick = Duration::from_secs_f64(h / 2.0);
        let mut started: Option<Instant> = None;
        let mut k = 0u64;
        let step = move |reading: Option<DeviceReading>, _t: f64, _dt: f64| -> DeviceCommand {
            let now = Instant::now();
            let due = match started {
                None => true,
                Some(s) => now + half_tick >= s + period || count == MAX_DEVICE_STEPS,
            };
            if due {
                // A device step late by more than a period starts the next period late: the lost periods are not
                // run (the physics clock skips them, as the device loop skips ticks).
                started = Some(now);
                k += 1;
                if k >= 2 && done.load(Ordering::Acquire) < k - 1 {
                    // Physics step k - 1 is late: wait for its model (the schedule the replay runs).
                    waits_d.fetch_add(1, Ordering::Relaxed);
                    let since = Instant::now();
                    // Parked, not spinning: on a busy machine a spinning device thread takes the core the late
                    // physics step needs (the physics thread unparks it when it has published).
                    device_thread.get_or_init(std::thread::current);
                    while done.load(Ordering::Acquire) < k - 1 {
                        if since.elapsed().as_secs_f64() > PHYSICS_STALL {
                            stalls_d.fetch_add(1, Ordering::Relaxed);
                            break;
                        }
                        std::thread::park_timeout(Duration::from_micros(200));
                    }
                }
                published = *pub_out.read();
                if let Some(f) = feed.as_mut() {
                    f.publish(FedModel { number: published.step, valid_for: dt, hair: published.model, coupling: side.coupling.params });
                }
                hand_in.write(Handover { period: k, proxy: side.proxy_state(), readings, count, force });
                handed.store(k, Ordering::Release);
                waker.unpark();
                count = 0;
            }
            let cmd = side.step(reading, h, &published);
            readings[count] = reading;
            count += 1;
            force = cmd.force;
            cmd
        };
        let rate = device_steps as f64 / dt;
        let device = match HapticLoop::spawn_with_priority(rate, device, step, None, priority, move |why| on_refused(format!("device loop: {why}"))) {
            Ok(d) => d,
            Err(e) => {
                stop.store(true, Ordering::Relaxed);
                return Err(e);
            }
        };
        Ok(Self { device, physics: physics_thread, stop, waits, stalls })
    }

    /// Stops both threads; returns the device loop's and the physics thread's timing.
    pub fn stop(self) -> (LoopStats, PhysicsStats) {
        let (device, _dev) = self.device.stop();
        self.stop.store(true, Ordering::Relaxed);
        self.physics.thread().unpark();
        let (hist, over, panics) = self.physics.join().unwrap_or_else(|_| (Histogram::new(), 0, 1));
        let physics = PhysicsStats {
            steps: hist.n,
            step_mean: hist.mean(),
            step_p50: hist.quantile(0.5),
            step_p99: hist.quantile(0.99),
            step_p999: hist.quantile(0.999),
            step_max: hist.max,
            over,
            waits: self.waits.load(Ordering::Relaxed),
            stalls: self.stalls.load(Ordering::Relaxed),
            panics,
        };
        (device, physics)
    }
}
