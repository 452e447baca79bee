//! The frame pump: a thread that reads the session's latest snapshots at the frame rate, encodes one FRAME,
//! publishes it to every viewer's writer, and keeps the latest state a SAVE and new viewers need.

use super::app::{record_stopped, App, LatestGuides};
use crate::delivery::Frame;
use crate::protocol;
use engine::session::{HapticSnapshot, LatticeSnapshot};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tokio::sync::watch;
use triple_buffer::Output;

/// Frame pump statistics (information, logged at the end).
#[derive(Default)]
pub(super) struct PumpStats {
    /// Frames published.
    pub frames: u64,
    /// The runaway guard's count in the latest frame (of the current session).
    pub runaways: u64,
    /// CPU time spent building frames, s.
    pub encode_seconds: f64,
    /// Bytes of FRAME messages published.
    pub bytes: u64,
    /// Frames sent more than one frame period after their scheduled time (the frame thread was not run in time).
    pub late: u64,
    /// The largest delay of a frame behind its scheduled time, s.
    pub max_late: f64,
    /// The longest time from a frame's turn to its publication (encoding, and any wait for a lock), s.
    pub max_build: f64,
}

/// Starts the frame thread at `fps` frames per second (real-time at `priority` if given) on the session's
/// snapshot outputs; it runs until `stop` and returns its statistics.
pub(super) fn spawn(
    app: Arc<App>,
    stop: Arc<AtomicBool>,
    fps: f64,
    priority: Option<i32>,
    lattice: Output<LatticeSnapshot>,
    haptic: Output<HapticSnapshot>,
    frame_tx: watch::Sender<Arc<Frame>>,
) -> std::io::Result<JoinHandle<PumpStats>> {
    std::thread::Builder::new().name("coiffure-frames".into()).spawn(move || {
        // Frames on time on a busy machine: the frame thread (about 45 us of work per frame) runs real-time
        // just below the haptic loop, when the haptic loop does.
        if let Some(p) = priority {
            if let Err(why) = haptics::realtime::request_realtime(p) {
                tracing::warn!("the frame thread runs at normal priority: {why}");
            }
        }
        let (mut lattice, mut haptic) = (lattice, haptic);
        let mut st = PumpStats::default();
        let mut kept_sent = 0u64;
        let mut record_stop_sent = false;
        let period = Duration::from_secs_f64(1.0 / fps);
        let start = Instant::now();
        while !stop.load(Ordering::Relaxed) {
            // A loaded hairstyle's session: its snapshots from now on, and its strands' kept points to all.
            // (The frame thread never waits for a lock a slower thread may hold: try_lock, and retry next frame.)
            if let Some((l, h)) = app.swap.try_lock().ok().and_then(|mut s| s.take()) {
                (lattice, haptic) = (l, h);
                kept_sent = u64::MAX;
            }
            let c0 = cpu_time();
            let w0 = Instant::now();
            let behind = w0.saturating_duration_since(start + period * st.frames as u32).as_secs_f64();
            st.max_late = st.max_late.max(behind);
            if behind > period.as_secs_f64() {
                st.late += 1;
            }
            let (lat, hap) = (lattice.read(), haptic.read());
            let msg = protocol::encode_frame(st.frames as u32, lat, hap);
            // After a scissors cut or a reset: every viewer gets the strands' kept points (STRANDS) before the frame.
            if lat.kept_version != kept_sent {
                kept_sent = lat.kept_version;
                let s = protocol::encode_strands(&lat.kept);
                for v in app.viewers() {
                    v.post(s.clone());
                }
            }
            // The latest state for SAVE (skipped while a SAVE reads it: the next frame's will do).
            if let (Ok(mut l), Ok(mut h)) = (app.latest_lattice.try_lock(), app.latest_head.try_lock()) {
                l.clear();
                l.extend(lat.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]));
                *h = lat.head;
            }
            if let Ok(mut g) = app.latest_guides.try_lock() {
                let samples = if hap.active.is_empty() { 2 } else { (hap.displacement.len() / hap.active.len()).max(2) };
                *g = LatestGuides { kept: lat.kept.clone(), active: hap.active.clone(), displacement: hap.displacement.clone(), samples };
            }
            st.bytes += msg.len() as u64;
            st.runaways = hap.runaways;
            let published = Instant::now();
            app.published.note(st.frames as u32, published);
            let _ = frame_tx.send(Arc::new(Frame { bytes: msg, published }));
            st.max_build = st.max_build.max((published - w0).as_secs_f64());
            // Recording stopped (disk full, file unwritable): every viewer is told why, once.
            if let Some(why) = app.record.as_ref().and_then(|r| r.stopped()).filter(|_| !record_stop_sent) {
                record_stop_sent = true;
                app.broadcast(&record_stopped(why));
            }
            // The device's status to every viewer, about 10 times a second.
            if let Some((_, status)) = &app.udp {
                if st.frames % (fps / 10.0).ceil().max(1.0) as u64 == 0 {
                    app.broadcast(&protocol::encode_device(&status.counts()));
                }
            }
            st.encode_seconds += match (c0, cpu_time()) {
                (Some(a), Some(b)) => b - a,
                _ => w0.elapsed().as_secs_f64(),
            };
            st.frames += 1;
            let next = start + period * st.frames as u32;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
        }
        st
    })
}

/// CPU time of the calling thread, s, or None if the clock is unavailable.
fn cpu_time() -> Option<f64> {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec into the valid, exclusively borrowed `ts`.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then(|| ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64)
}
