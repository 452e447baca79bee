//! Real-time scheduling for the haptic thread.
//!
//! A haptic loop must finish every step within its period (1 ms at 1 kHz). On a busy machine the ordinary
//! scheduler may hand the core to another process for several milliseconds, which no speed-up of the step
//! can hide (bench/RESULTS.md, "Haptic loop"). Haptic applications therefore run their loop thread with a
//! real-time policy: Linux `SCHED_FIFO` at a modest priority, which preempts every normal thread. The kernel's
//! real-time throttling (`/proc/sys/kernel/sched_rt_runtime_us`, 95 % by default) keeps a spinning loop from
//! locking the machine up.
//!
//! The request needs the right to do it (root, `CAP_SYS_NICE`, or an `rtprio` limit in
//! `/etc/security/limits.conf`); without it [`request_realtime`] says so and the loop runs at normal priority.

/// Lowest and highest `SCHED_FIFO` priorities accepted by [`request_realtime`].
pub const PRIORITY_RANGE: std::ops::RangeInclusive<i32> = 1..=99;

/// Gives the calling thread the `SCHED_FIFO` real-time policy at `priority` (1 to 99; 10 is a sensible
/// value for a haptic loop: above normal threads, below the kernel's own real-time work). On failure the
/// thread keeps its policy and the error says why (permission, unsupported platform, bad priority).
pub fn request_realtime(priority: i32) -> Result<(), String> {
    if !PRIORITY_RANGE.contains(&priority) {
        return Err(format!("real-time priority must be in 1..=99, got {priority}"));
    }
    imp::set_fifo(priority)
}

/// Asks for the calling thread's sleeps to end on time: Linux timer slack 1 ns (`PR_SET_TIMERSLACK`; the default
/// 50 us lets the kernel wake a normal thread that much late). Best effort; nothing elsewhere.
pub fn precise_sleep() {
    imp::precise_sleep()
}

/// While alive, holds every CPU's wake-up latency at 0 (Linux PM QoS, `/dev/cpu_dma_latency`): an idle CPU polls
/// instead of entering an idle state it takes time to leave. On a virtual machine that state is the virtual CPU
/// halted, which the host then has to run again when a timer fires: a real-time loop sleeping between its periods
/// wakes late by as much (bench/RESULTS.md: the device loop's misses with and without it). Costs an idle
/// CPU's power while held; the kernel restores the default when it is dropped (the file closed).
#[derive(Debug)]
pub struct CpuLatencyHold {
    _file: std::fs::File,
}

/// Holds the CPUs' wake-up latency at 0 until the returned value is dropped ([`CpuLatencyHold`]). Needs write access
/// to `/dev/cpu_dma_latency` (root); the error says why not.
pub fn hold_cpu_latency() -> Result<CpuLatencyHold, String> {
    imp::hold_cpu_latency().map(|f| CpuLatencyHold { _file: f })
}

/// The CPUs' wake-up latency the kernel holds now, s (the strictest of every holder's; Linux
/// `/dev/cpu_dma_latency`), or None where it cannot be read (no such file, no right to read it).
pub fn cpu_latency() -> Option<f64> {
    imp::cpu_latency()
}

/// True if the calling thread runs with the `SCHED_FIFO` policy.
pub fn is_realtime() -> bool {
    imp::is_fifo()
}

/// The CPU time the calling thread has run so far, s (Linux `CLOCK_THREAD_CPUTIME_ID`; on a virtual machine with
/// paravirtual steal accounting, as here, the time its vCPU was taken away by the host is not in it). A step's
/// wall time minus its CPU time is the time it was ready or running but off its CPU (preempted). None where
/// the clock is not available.
pub fn thread_cpu_time() -> Option<f64> {
    imp::thread_cpu_time()
}

#[cfg(target_os = "linux")]
mod imp {
    pub fn set_fifo(priority: i32) -> Result<(), String> {
        let param = libc::sched_param { sched_priority: priority };
        // SAFETY: pthread_self() is the calling thread, and `param` is a valid sched_param for the call.
        let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
        match rc {
            0 => Ok(()),
            libc::EPERM => Err(format!(
                "SCHED_FIFO priority {priority} not permitted (needs root, CAP_SYS_NICE or an rtprio limit); \
                 the haptic loop runs at normal priority"
            )),
            e => Err(format!("pthread_setschedparam(SCHED_FIFO, {priority}) failed with error {e}")),
        }
    }

    const PM_QOS: &str = "/dev/cpu_dma_latency";

    pub fn hold_cpu_latency() -> Result<std::fs::File, String> {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new().write(true).open(PM_QOS).map_err(|e| format!("cannot hold the CPUs' wake-up latency at 0: {PM_QOS}: {e} (needs root)"))?;
        f.write_all(&0i32.to_ne_bytes()).map_err(|e| format!("cannot hold the CPUs' wake-up latency at 0: writing {PM_QOS}: {e}"))?;
        Ok(f)
    }

    pub fn cpu_latency() -> Option<f64> {
        use std::io::Read;
        let mut b = [0u8; 4];
        std::fs::File::open(PM_QOS).and_then(|mut f| f.read_exact(&mut b)).ok()?;
        Some(i32::from_ne_bytes(b) as f64 * 1e-6)
    }

    pub fn precise_sleep() {
        // SAFETY: PR_SET_TIMERSLACK takes an unsigned long and changes only the calling thread's slack.
        unsafe {
            libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong);
        }
    }

    pub fn is_fifo() -> bool {
        let mut policy = 0;
        let mut param = libc::sched_param { sched_priority: 0 };
        // SAFETY: both out-pointers are valid for writes.
        let rc = unsafe { libc::pthread_getschedparam(libc::pthread_self(), &mut policy, &mut param) };
        rc == 0 && policy == libc::SCHED_FIFO
    }

    pub fn thread_cpu_time() -> Option<f64> {
        let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `t` is a valid timespec for writes.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        (rc == 0).then(|| t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64)
    }
}

#[cfg(not(target_os = "linux"))]
mod imp {
    pub fn set_fifo(_priority: i32) -> Result<(), String> {
        Err("real-time scheduling of the haptic thread is only implemented on Linux".into())
    }

    pub fn precise_sleep() {}

    pub fn hold_cpu_latency() -> Result<std::fs::File, String> {
        Err("holding the CPUs' wake-up latency (PM QoS) needs Linux".into())
    }

    pub fn cpu_latency() -> Option<f64> {
        None
    }

    pub fn is_fifo() -> bool {
        false
    }

    pub fn thread_cpu_time() -> Option<f64> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cpu_latency_hold_holds_zero_until_dropped() {
        // Where the process may (root on Linux), the hold brings the kernel's wake-up latency to 0 while alive;
        // elsewhere it says why not, naming the file. (What comes back when dropped depends on the other holders,
        // such as another test process's session: not asserted.)
        match hold_cpu_latency() {
            Ok(hold) => {
                assert_eq!(cpu_latency(), Some(0.0), "held");
                drop(hold);
                assert!(cpu_latency().is_some_and(|s| s >= 0.0), "readable after the hold");
            }
            Err(why) => assert!(why.contains("cpu_dma_latency") || why.contains("Linux"), "{why}"),
        }
    }

    #[test]
    fn the_threads_cpu_time_counts_its_work_and_not_its_sleep() {
        // A thread that sleeps 30 ms and then spins 30 ms of wall time: its CPU time grows by under 5 ms over the
        // sleep and by at most the 30 ms of the spin (more than nothing: the spin ran on a CPU at least part of it).
        std::thread::spawn(|| {
            let Some(a) = thread_cpu_time() else { return };
            std::thread::sleep(std::time::Duration::from_millis(30));
            let b = thread_cpu_time().unwrap();
            let t = std::time::Instant::now();
            while t.elapsed().as_secs_f64() < 0.03 {
                std::hint::spin_loop();
            }
            let c = thread_cpu_time().unwrap();
            assert!(b - a < 5e-3, "{} s of CPU time asleep", b - a);
            assert!(c - b > 0.0 && c - b <= t.elapsed().as_secs_f64() + 1e-4, "{} s of CPU time in a 30 ms spin", c - b);
        })
        .join()
        .unwrap();
    }

    #[test]
    fn bad_priorities_are_refused_and_a_request_either_works_or_says_why() {
        assert!(request_realtime(0).unwrap_err().contains("1..=99"));
        assert!(request_realtime(100).is_err());
        // On a fresh thread (so the test runner's threads keep their policy): either the request is
        // granted and the thread reports SCHED_FIFO, or it is refused with a reason and the policy is unchanged.
        std::thread::spawn(|| match request_realtime(10) {
            Ok(()) => assert!(is_realtime()),
            Err(why) => {
                assert!(!why.is_empty());
                assert!(!is_realtime());
            }
        })
        .join()
        .unwrap();
    }
}
