//! FRAME delivery to the viewers, and how on time it is (docs/protocol.md, "Frames on time").
//!
//! The frame thread publishes one [`Frame`] per period (stamped when published); each viewer's writer takes
//! the latest when it is free (a slow viewer skips frames). The writer's *pickup delay* is the server's own
//! share of a FRAME's lateness: from the frame's publication (or from the writer becoming free, if later) to
//! its send starting. It is what the server's scheduling adds; time spent in a send that the viewer does not
//! drain is the viewer's. [`DeliveryStats`] keeps its largest value and counts over two thresholds, reported in
//! `coiffure serve`'s summary line.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// A FRAME message as published by the frame thread.
pub struct Frame {
    /// The encoded FRAME (flags patched per viewer by its writer).
    pub bytes: Vec<u8>,
    /// When the frame thread published it.
    pub published: Instant,
}

impl Frame {
    /// An empty placeholder (before the first frame).
    pub fn none() -> Self {
        Self { bytes: Vec::new(), published: Instant::now() }
    }
}

/// When the latest FRAMEs were published, by sequence number (the last [`PublishLog::LEN`]): a writer that
/// skipped frames measures its delay from the first one it missed, not from the latest (which a stalled
/// writer would find freshly published). Lock-free: the frame thread never waits for a writer.
pub struct PublishLog {
    epoch: Instant,
    /// Per slot `seq % LEN`: microseconds after `epoch` << 24 | the low 24 bits of `seq` (0: empty).
    slots: Vec<AtomicU64>,
}

impl Default for PublishLog {
    fn default() -> Self {
        Self { epoch: Instant::now(), slots: (0..Self::LEN).map(|_| AtomicU64::new(0)).collect() }
    }
}

impl PublishLog {
    /// Frames remembered (4.3 s at 60 fps).
    pub const LEN: usize = 256;
    const SEQ_BITS: u32 = 24;

    /// Notes that FRAME `seq` is published at `at`.
    pub fn note(&self, seq: u32, at: Instant) {
        let us = at.saturating_duration_since(self.epoch).as_micros() as u64;
        let tag = seq as u64 & ((1 << Self::SEQ_BITS) - 1);
        self.slots[seq as usize % Self::LEN].store((us << Self::SEQ_BITS) | tag, Ordering::Relaxed);
    }

    /// When FRAME `seq` was published, if it is still remembered.
    pub fn at(&self, seq: u32) -> Option<Instant> {
        let v = self.slots[seq as usize % Self::LEN].load(Ordering::Relaxed);
        let tag = seq as u64 & ((1 << Self::SEQ_BITS) - 1);
        (v != 0 && v & ((1 << Self::SEQ_BITS) - 1) == tag).then(|| self.epoch + Duration::from_micros(v >> Self::SEQ_BITS))
    }
}

/// A pickup delay over this is counted as a slip (information: a FRAME is on time if no viewer that reads
/// waits over [`ON_TIME`] between FRAMEs).
pub const SLIP: Duration = Duration::from_millis(20);
/// The on-time bound: at a viewer that reads, no gap between FRAMEs over this, s (docs/protocol.md).
pub const ON_TIME: Duration = Duration::from_millis(100);

/// Counts of the writers' FRAME deliveries over all viewers (shared; updated by each writer).
#[derive(Default)]
pub struct DeliveryStats {
    written: AtomicU64,
    max_pickup_us: AtomicU64,
    over_slip: AtomicU64,
    over_on_time: AtomicU64,
}

impl DeliveryStats {
    /// A writer starts sending FRAME `seq`, published at `published`; the previous FRAME it sent was `last`, and
    /// it has been free (waiting for a frame) since `free_since`. Notes the pickup delay: now less the later of
    /// `free_since` and the publication of the first FRAME it has not sent (`last + 1`, from `log`; `published`
    /// when unknown).
    pub fn pickup(&self, log: &PublishLog, seq: u32, published: Instant, last: Option<u32>, free_since: Instant) {
        let first_missed = last.filter(|&l| l < seq).and_then(|l| log.at(l + 1)).map_or(published, |t| t.min(published));
        let delay = Instant::now().saturating_duration_since(first_missed.max(free_since));
        self.note(delay);
    }

    fn note(&self, delay: Duration) {
        self.written.fetch_add(1, Ordering::Relaxed);
        self.max_pickup_us.fetch_max(delay.as_micros() as u64, Ordering::Relaxed);
        self.over_slip.fetch_add((delay > SLIP) as u64, Ordering::Relaxed);
        self.over_on_time.fetch_add((delay > ON_TIME) as u64, Ordering::Relaxed);
    }

    /// (FRAMEs written to viewers, largest pickup delay s, pickups over [`SLIP`], pickups over [`ON_TIME`]).
    pub fn get(&self) -> (u64, f64, u64, u64) {
        let r = |a: &AtomicU64| a.load(Ordering::Relaxed);
        (r(&self.written), 1e-6 * r(&self.max_pickup_us) as f64, r(&self.over_slip), r(&self.over_on_time))
    }

    /// The summary line's part: `N FRAMEs written to viewers, pickup delay max X ms, A over 20 ms, B over 100 ms`.
    pub fn summary(&self) -> String {
        let (n, max, slip, late) = self.get();
        format!("{n} FRAMEs written to viewers, writer pickup delay max {:.1} ms, {slip} over {} ms, {late} over {} ms", 1e3 * max, SLIP.as_millis(), ON_TIME.as_millis())
    }
}

/// Puts the calling thread back on the normal scheduling policy (`SCHED_OTHER`). The server's runtime threads
/// run real-time (one below the frame thread) so that writers are never queued behind normal work; a heavy job
/// (LOAD, SAVE) on one of its blocking threads calls this first, so that it is the one that waits.
pub fn normal_priority() {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param { sched_priority: 0 };
        // SAFETY: pthread_self() is the calling thread, and `param` is a valid sched_param for SCHED_OTHER.
        let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_OTHER, &param) };
        if rc != 0 {
            tracing::debug!("pthread_setschedparam(SCHED_OTHER) failed with error {rc}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pickup_delays_are_measured_from_the_later_of_publication_and_the_writer_being_free() {
        let s = DeliveryStats::default();
        let mut log = PublishLog::default();
        log.epoch -= Duration::from_secs(10); // (publications before the log's epoch are not remembered right)
        let now = Instant::now();
        let ms = Duration::from_millis;
        // Published 150 ms ago, but the writer was busy until 1 ms ago: a 1 ms pickup (the wait was the viewer's send).
        log.note(7, now - ms(150));
        s.pickup(&log, 7, now - ms(150), Some(6), now - ms(1));
        let (n, max, slip, late) = s.get();
        assert_eq!((n, slip, late), (1, 0, 0));
        assert!(max < 0.1, "{max}");
        // Published 150 ms ago with the writer free all along: the server's own 150 ms.
        s.pickup(&log, 7, now - ms(150), Some(6), now - Duration::from_secs(1));
        let (n, max, slip, late) = s.get();
        assert_eq!((n, slip, late), (2, 1, 1));
        assert!((0.15..0.5).contains(&max), "{max}");
        // A stalled writer finds FRAME 15 just published, but missed 8-14 (the first 140 ms ago): 140 ms, not 0.
        for q in 8..=15u32 {
            log.note(q, now - ms(140) + ms(20) * (q - 8));
        }
        s.pickup(&log, 15, now, Some(7), now - Duration::from_secs(1));
        assert_eq!(s.get().3, 2, "{}", s.summary());
        // Forgotten frames (over LEN back) fall back on the frame's own publication.
        assert!(log.at(15 + PublishLog::LEN as u32).is_none() && log.at(15).is_some());
        s.pickup(&log, 15 + 2 * PublishLog::LEN as u32, now, Some(15 + PublishLog::LEN as u32), now - Duration::from_secs(1));
        assert_eq!(s.get().3, 2, "{}", s.summary());
        s.note(ms(30));
        assert_eq!(s.get().2, 3, "{}", s.summary());
        // A thread put back on the normal policy is not real-time (whether or not it was).
        std::thread::spawn(|| {
            let _ = haptics::realtime::request_realtime(3);
            normal_priority();
            assert!(!haptics::realtime::is_realtime());
        })
        .join()
        .unwrap();
        assert!(s.summary().starts_with("5 FRAMEs written to viewers, writer pickup delay max "), "{}", s.summary());
    }
}
