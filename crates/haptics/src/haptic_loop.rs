//! The fixed-rate haptic loop: a thread that, every period, reads the device, runs a step function and writes
//! the command back. It never waits on a lock (devices exchange data through wait-free buffers) and records
//! its timing in fixed-size histograms (no allocation while running).

use crate::device::{DeviceCommand, DeviceReading, HapticDevice};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Largest loop rate accepted, Hz (a device loop at 10 kHz).
pub const MAX_RATE_HZ: f64 = 10_000.0;

/// The loop sleeps until this long before a step's start and spins the rest, s: the wake-up's lateness with
/// the thread's timer slack set to 1 ns (Linux `PR_SET_TIMERSLACK`; the default slack is 50 us). At 4-10 kHz
/// (periods of 100-250 us) spinning whole periods would take a core of a 2-core machine.
pub const SPIN_MARGIN: f64 = 60e-6;

/// Timing of a loop run. Times in s.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoopStats {
    /// Steps run.
    pub steps: u64,
    /// Mean time spent in the step function, s.
    pub step_mean: f64,
    /// Median step time, s (1 us resolution).
    pub step_p50: f64,
    /// 99th percentile of the step time, s (1 us resolution).
    pub step_p99: f64,
    /// 99.9th percentile of the step time, s.
    pub step_p999: f64,
    /// Longest step, s.
    pub step_max: f64,
    /// Mean period between step starts, s.
    pub period_mean: f64,
    /// 99.9th percentile of the period, s.
    pub period_p999: f64,
    /// Steps that finished after their period's end (their deadline).
    pub misses: u64,
    /// Whole periods in which no step ran because an earlier step overran (the loop was preempted or a step
    /// was slow). After a late step the loop does not run the lost periods back to back (a burst of steps with
    /// the same device reading, on a machine already short of time): the next step starts one period after
    /// the late one ended, and the schedule goes on from there, one period per step; the simulated clock
    /// (`n * period`) is continuous. (A step function that keeps the wall clock's pace itself, as the live
    /// session's device loop does, then never sees a tick come early.)
    pub skipped: u64,
    /// The misses by cause (they add up to `misses`): the step started late by more than it then took (the
    /// thread woke late: the kernel or, on a virtual machine, the host did not run it in time; see `wake_p999`).
    pub misses_late_start: u64,
    /// Misses that started in time but whose step was off its CPU for more than half its wall time (preempted
    /// by an interrupt or a thread of higher priority, the virtual CPU taken by the host, or the step blocked).
    pub misses_preempted: u64,
    /// Misses whose step took that long on its CPU: the step function's own cost. (Telling these from the preempted
    /// ones reads the thread's CPU clock at each step's start: a system call, not served by the vDSO.)
    pub misses_slow: u64,
    /// How late the loop's sleeps woke against the time asked for, 99.9th percentile and longest, s: the host's
    /// wake-up latency the spin margin ([`SPIN_MARGIN`]) absorbs up to its length (as `cyclictest` measures it).
    pub wake_p999: f64,
    /// Latest wake-up, s.
    pub wake_max: f64,
    /// Steps whose step function panicked: the device got zero force for them and the loop went on.
    pub panics: u64,
    /// True if the loop thread ran with real-time priority ([`HapticLoop::spawn_with_priority`]).
    pub realtime: bool,
}

/// Histogram of durations with 1 us bins up to 20 ms (and an overflow bin): no allocation while adding.
#[derive(Debug, Clone)]
pub struct Histogram {
    bins: Vec<u64>,
    sum: f64,
    /// Longest duration added, s.
    pub max: f64,
    /// Durations added.
    pub n: u64,
}

impl Default for Histogram {
    fn default() -> Self {
        Self::new()
    }
}

impl Histogram {
    const BINS: usize = 20_000;
    /// Empty.
    pub fn new() -> Self {
        Self { bins: vec![0; Self::BINS + 1], sum: 0.0, max: 0.0, n: 0 }
    }
    /// Adds a duration, s.
    pub fn add(&mut self, seconds: f64) {
        let b = ((seconds * 1e6) as usize).min(Self::BINS);
        self.bins[b] += 1;
        self.sum += seconds;
        self.max = self.max.max(seconds);
        self.n += 1;
    }
    /// The `q` quantile (in [0, 1]), s, to 1 us.
    pub fn quantile(&self, q: f64) -> f64 {
        let target = (q * self.n as f64).ceil() as u64;
        let mut acc = 0;
        for (i, c) in self.bins.iter().enumerate() {
            acc += c;
            if acc >= target.max(1) {
                return (i as f64 + 1.0) * 1e-6;
            }
        }
        self.max
    }
    /// The mean, s.
    pub fn mean(&self) -> f64 {
        if self.n == 0 { 0.0 } else { self.sum / self.n as f64 }
    }
}

/// A running haptic loop; [`HapticLoop::stop`] ends it and returns its statistics and device.
pub struct HapticLoop<D: HapticDevice + 'static> {
    stop: Arc<AtomicBool>,
    handle: JoinHandle<(LoopStats, D)>,
}

impl<D: HapticDevice + 'static> HapticLoop<D> {
    /// Starts a loop at `rate_hz` (at most [`MAX_RATE_HZ`]) calling `step(reading, t, dt)` each period with the
    /// device's latest reading (None if it has none) and sending the returned command to the device. Runs at
    /// most `max_steps` steps if given.
    pub fn spawn<F>(rate_hz: f64, device: D, step: F, max_steps: Option<u64>) -> Result<Self, String>
    where
        F: FnMut(Option<DeviceReading>, f64, f64) -> DeviceCommand + Send + 'static,
    {
        Self::spawn_with_priority(rate_hz, device, step, max_steps, None, |_| {})
    }

    /// [`HapticLoop::spawn`] with the loop thread asking for real-time priority `realtime_priority`
    /// (`SCHED_FIFO`, 1..=99, see [`crate::realtime`]) before its first step. If the request is refused the
    /// loop runs at normal priority and `on_refused` is called, on the loop thread, with the reason;
    /// [`LoopStats::realtime`] tells which it was.
    pub fn spawn_with_priority<F, R>(
        rate_hz: f64,
        mut device: D,
        mut step: F,
        max_steps: Option<u64>,
        realtime_priority: Option<i32>,
        on_refused: R,
    ) -> Result<Self, String>
    where
        F: FnMut(Option<DeviceReading>, f64, f64) -> DeviceCommand + Send + 'static,
        R: FnOnce(String) + Send + 'static,
    {
        if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= MAX_RATE_HZ) {
            return Err(format!("loop rate must be in (0, {MAX_RATE_HZ}] Hz, got {rate_hz}"));
        }
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let handle = std::thread::Builder::new()
            .name("coiffure-haptic".into())
            .spawn(move || {
                if let Some(priority) = realtime_priority {
                    if let Err(why) = crate::realtime::request_realtime(priority) {
                        on_refused(why);
                    }
                }
                let realtime = crate::realtime::is_realtime();
                crate::realtime::precise_sleep();
                let period = Duration::from_secs_f64(1.0 / rate_hz);
                let dt = period.as_secs_f64();
                let (mut steps_h, mut periods_h, mut wakes_h) = (Histogram::new(), Histogram::new(), Histogram::new());
                let (mut late_start, mut preempted, mut slow) = (0u64, 0u64, 0u64);
                // The schedule: step `k` of the current run of on-time steps starts at `epoch + k period`.
                let mut epoch = Instant::now();
                let mut k = 0u32;
                let mut last_start: Option<Instant> = None;
                let (mut n, mut misses, mut skipped, mut panics) = (0u64, 0u64, 0u64, 0u64);
                while !flag.load(Ordering::Relaxed) && max_steps.map_or(true, |m| n < m) {
                    let deadline = epoch + period * k;
                    // Sleep until shortly before the deadline, then spin for precision.
                    let now = Instant::now();
                    let margin = Duration::from_secs_f64(SPIN_MARGIN);
                    if deadline > now + margin + margin / 2 {
                        let wake = deadline - margin;
                        std::thread::sleep(wake - now);
                        wakes_h.add(Instant::now().saturating_duration_since(wake).as_secs_f64());
                    }
                    while Instant::now() < deadline {
                        std::hint::spin_loop();
                    }
                    let t0 = Instant::now();
                    let cpu0 = crate::realtime::thread_cpu_time();
                    if let Some(l) = last_start {
                        periods_h.add((t0 - l).as_secs_f64());
                    }
                    last_start = Some(t0);
                    let t = n as f64 * dt;
                    let reading = device.read(t);
                    // A panic in the step must not leave the device with its last force or kill the loop:
                    // zero force for that step, counted.
                    let cmd = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| step(reading, t, dt))) {
                        Ok(cmd) => cmd,
                        Err(_) => {
                            panics += 1;
                            DeviceCommand::default()
                        }
                    };
                    device.write(&cmd);
                    let t1 = Instant::now();
                    let took = (t1 - t0).as_secs_f64();
                    steps_h.add(took);
                    let due = epoch + period * (k + 1);
                    if t1 > due {
                        // Why: a late start, a step off its CPU, or the step's own time.
                        let cpu = crate::realtime::thread_cpu_time().zip(cpu0).map(|(b, a)| (b - a).max(0.0));
                        if t0.saturating_duration_since(deadline).as_secs_f64() > took {
                            late_start += 1;
                        } else if cpu.is_some_and(|c| took - c > 0.5 * took) {
                            preempted += 1;
                        } else {
                            slow += 1;
                        }
                        // Late (started late, or overran): counted, and the schedule starts again from this
                        // step's end: the next one period after it (see `LoopStats::skipped`).
                        misses += 1;
                        skipped += ((t1 - due).as_secs_f64() / dt) as u64;
                        (epoch, k) = (t1, 1);
                    } else {
                        k += 1;
                    }
                    n += 1;
                }
                let stats = LoopStats {
                    steps: n,
                    step_mean: steps_h.mean(),
                    step_p50: steps_h.quantile(0.5),
                    step_p99: steps_h.quantile(0.99),
                    step_p999: steps_h.quantile(0.999),
                    step_max: steps_h.max,
                    period_mean: periods_h.mean(),
                    period_p999: periods_h.quantile(0.999),
                    misses,
                    skipped,
                    misses_late_start: late_start,
                    misses_preempted: preempted,
                    misses_slow: slow,
                    wake_p999: wakes_h.quantile(0.999),
                    wake_max: wakes_h.max,
                    panics,
                    realtime,
                };
                (stats, device)
            })
            .map_err(|e| format!("cannot start the haptic thread: {e}"))?;
        Ok(Self { stop, handle })
    }

    /// Stops the loop (after its current step) and returns its statistics and the device.
    pub fn stop(self) -> (LoopStats, D) {
        self.stop.store(true, Ordering::Relaxed);
        self.handle.join().expect("the haptic thread panicked")
    }

    /// Waits for a loop started with `max_steps` to finish.
    pub fn join(self) -> (LoopStats, D) {
        self.handle.join().expect("the haptic thread panicked")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backends::ScriptedDevice;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn runs_at_the_requested_rate_and_counts_steps() {
        // 300 steps at 1 kHz: every step runs, in order, and the mean period is 1 ms within 5 %.
        // (Timing percentiles on a shared CI machine are information, not assertions; see bench/RESULTS.md.)
        let dev = ScriptedDevice::new(|t| Some(DeviceReading { time: t, position: Vector3::new(t, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 0 }));
        let lp = HapticLoop::spawn(1000.0, dev, |r, _, _| DeviceCommand { force: r.unwrap().position, torque: Vector3::zeros() }, Some(300)).unwrap();
        let (stats, dev) = lp.join();
        assert_eq!(stats.steps, 300);
        assert_eq!(dev.commands.len(), 300);
        assert!((dev.commands[299].force.x - 0.299).abs() < 1e-12);
        // The periods lost to overruns (a preempted step on a loaded machine) lengthen the mean; never shorten it.
        let lost = (stats.skipped + stats.misses) as f64 / 299.0;
        assert!(stats.period_mean > 0.95e-3 && stats.period_mean < 1.05e-3 * (1.0 + lost), "mean period {} ({} skipped)", stats.period_mean, stats.skipped);
        assert!(stats.step_p999 >= stats.step_p99 && stats.step_max >= stats.step_mean);
        assert!(!stats.realtime);
        assert!(HapticLoop::spawn(20_000.0, ScriptedDevice::new(|_| None), |_, _, _| DeviceCommand::default(), Some(1)).is_err());
    }

    #[test]
    fn after_an_overrun_the_loop_does_not_burst() {
        // Step 50 takes 20 ms (a preempted or slow step). The loop counts it and the 19-20 periods it lost,
        // and starts the schedule again: the steps after it keep to one per period. A loop that caught up
        // ran the lost steps back to back (20 starts microseconds apart). Asserted: at least 1 miss and 15
        // skipped periods, and never two steps in a row starting closer than half a period after the one before.
        let starts = Arc::new(std::sync::Mutex::new(Vec::with_capacity(200)));
        let log = starts.clone();
        let step = move |_: Option<DeviceReading>, _: f64, _: f64| {
            let mut l = log.lock().unwrap();
            l.push(Instant::now());
            if l.len() == 50 {
                std::thread::sleep(Duration::from_millis(20));
            }
            DeviceCommand::default()
        };
        let (stats, _) = HapticLoop::spawn(1000.0, ScriptedDevice::new(|_| None), step, Some(120)).unwrap().join();
        assert!(stats.misses >= 1 && stats.skipped >= 15, "{} misses, {} skipped", stats.misses, stats.skipped);
        // The 20 ms step slept: a miss off its CPU, not the step's own time; the causes add up to the misses.
        assert!(stats.misses_preempted >= 1, "{stats:?}");
        assert_eq!(stats.misses_late_start + stats.misses_preempted + stats.misses_slow, stats.misses);
        let starts = starts.lock().unwrap();
        let gaps: Vec<u64> = starts.windows(2).map(|w| (w[1] - w[0]).as_micros() as u64).collect();
        // Runs of consecutive starts closer than half a period: a catch-up is one run of ~20; on schedule a
        // step that started late (a busy machine) but ended in its period is followed by one short gap, never two.
        let (mut run, mut longest) = (0, 0);
        for g in &gaps {
            run = if *g < 500 { run + 1 } else { 0 };
            longest = longest.max(run);
        }
        assert!(longest <= 1, "{longest} steps in a row started less than half a period apart: gaps {gaps:?} us");
    }

    #[test]
    fn a_step_that_computes_past_its_period_is_a_slow_miss() {
        // Every tenth step of a 1 kHz loop computes for 3 ms of its CPU time: five misses (at least; a loaded
        // machine may add others), of which at least one (on CI's busy cores, a step may be off its CPU for half
        // its time) counted as the step's own time where the thread CPU clock exists; every miss has one cause.
        let mut k = 0;
        let step = move |_: Option<DeviceReading>, _: f64, _: f64| {
            k += 1;
            if k % 10 == 0 {
                let (t, c) = (Instant::now(), crate::realtime::thread_cpu_time());
                while t.elapsed() < Duration::from_millis(3) || crate::realtime::thread_cpu_time().zip(c).is_some_and(|(b, a)| b - a < 3e-3) {
                    std::hint::spin_loop();
                }
            }
            DeviceCommand::default()
        };
        let (stats, _) = HapticLoop::spawn(1000.0, ScriptedDevice::new(|_| None), step, Some(50)).unwrap().join();
        assert!(stats.misses >= 5, "{stats:?}");
        assert_eq!(stats.misses_late_start + stats.misses_preempted + stats.misses_slow, stats.misses);
        if crate::realtime::thread_cpu_time().is_some() {
            assert!(stats.misses_slow >= 1, "every computing step off its CPU for half its time: {stats:?}");
        }
        // (The quantile is to the 1 us bin above.)
        assert!(stats.wake_p999 <= stats.wake_max + 1e-6 && stats.wake_p999 > 0.0, "{stats:?}");
    }

    #[test]
    fn a_loop_with_real_time_priority_runs_or_reports_why_not() {
        // Either the thread gets SCHED_FIFO (stats say so) or the refusal reason reaches the caller; the
        // loop runs all its steps in both cases.
        let (tx, rx) = std::sync::mpsc::channel();
        let dev = ScriptedDevice::new(|_| None);
        let lp = HapticLoop::spawn_with_priority(1000.0, dev, |_, _, _| DeviceCommand::default(), Some(50), Some(10), move |why| {
            tx.send(why).unwrap()
        })
        .unwrap();
        let (stats, _) = lp.join();
        assert_eq!(stats.steps, 50);
        match rx.try_recv() {
            Ok(why) => assert!(!stats.realtime && why.contains("SCHED_FIFO"), "{why}"),
            Err(_) => assert!(stats.realtime),
        }
        assert!(HapticLoop::spawn_with_priority(1000.0, ScriptedDevice::new(|_| None), |_, _, _| DeviceCommand::default(), Some(1), Some(0), |_| {}).is_ok());
    }

    #[test]
    fn a_panicking_step_gives_zero_force_and_the_loop_goes_on() {
        // Every third step panics: those steps send zero force, the others their own, and all 30 run.
        let dev = ScriptedDevice::new(|t| Some(DeviceReading { time: t, position: Vector3::new(1.0, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 0 }));
        let mut k = 0;
        let step = move |r: Option<DeviceReading>, _: f64, _: f64| {
            k += 1;
            assert!(k % 3 != 0, "step {k} fails on purpose");
            DeviceCommand { force: r.unwrap().position, torque: Vector3::zeros() }
        };
        let (stats, dev) = HapticLoop::spawn(1000.0, dev, step, Some(30)).unwrap().join();
        assert_eq!(stats.steps, 30);
        assert_eq!(stats.panics, 10);
        for (i, c) in dev.commands.iter().enumerate() {
            let expect = if (i + 1) % 3 == 0 { 0.0 } else { 1.0 };
            assert_eq!(c.force.x, expect, "step {}", i + 1);
        }
    }
}
