//! A live session's record streamed to disk as the session runs: the haptic and global threads hand each step
//! to a writer thread through bounded wait-free queues (`rtrb` single-producer single-consumer ring buffers:
//! a push never waits and never allocates), and the writer thread writes them in chunks (format in the module
//! above), syncing each to disk, at least every [`RecordParams::flush_interval`].
//!
//! Faults: if a queue is full (the writer held up for longer than [`RecordParams::queue_seconds`]) the step is
//! not waited for: recording stops there (a record with a gap would not replay), the steps before it are
//! written with an end chunk saying why, and the steps after are counted. If writing fails (disk full, file
//! unwritable) recording stops, the file is cut back to its last whole chunk and [`RecordStatus::stopped`]
//! says why; the session itself goes on either way.

use super::format::{put_end, put_header, StepsChunk};
use super::{GlobalRecord, RecordSettings, StepRecord};
use crate::error::SessionError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicU8, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub use super::params::RecordParams;

/// Where a record's bytes go: a file ([`RecordFile`]) or, in tests, anything that can fail like one.
pub trait RecordSink: Send {
    /// Writes all of `bytes` at the end.
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()>;
    /// Makes what was written durable (fsync).
    fn sync(&mut self) -> std::io::Result<()>;
    /// Cuts the sink back to its first `len` bytes (after a failed write).
    fn truncate(&mut self, len: u64) -> std::io::Result<()>;
    /// What it is, for messages (the file's path).
    fn name(&self) -> String;
}

/// What a session records to: the sink and the session's settings for the record's header.
pub struct RecordTarget {
    /// Where the bytes go.
    pub sink: Box<dyn RecordSink>,
    /// The session's scene and settings (for `coiffure replay`), if known.
    pub settings: Option<RecordSettings>,
}

/// A record file, created (or emptied) when recording starts.
pub struct RecordFile {
    file: std::fs::File,
    path: PathBuf,
}

impl RecordFile {
    /// Creates `path` (and its folder), emptying an existing file.
    pub fn create(path: &Path) -> std::io::Result<Self> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        Ok(Self { file: std::fs::File::create(path)?, path: path.to_path_buf() })
    }
}

impl RecordSink for RecordFile {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.file.write_all(bytes)
    }
    fn sync(&mut self) -> std::io::Result<()> {
        self.file.sync_data()
    }
    fn truncate(&mut self, len: u64) -> std::io::Result<()> {
        use std::io::Seek;
        self.file.set_len(len)?;
        self.file.seek(std::io::SeekFrom::Start(len)).map(|_| ())
    }
    fn name(&self) -> String {
        self.path.display().to_string()
    }
}

/// Which queue was found full.
const FULL_NONE: u8 = 0;
const FULL_HAPTIC: u8 = 1;
const FULL_GLOBAL: u8 = 2;

/// What a streamed record has done so far, shared by the session's threads and whoever watches (the server's
/// frame thread tells the viewers when recording stops).
#[derive(Debug, Default)]
pub struct RecordStatus {
    recording: AtomicBool,
    full: AtomicU8,
    steps: AtomicU64,
    globals: AtomicU64,
    bytes: AtomicU64,
    unrecorded: AtomicU64,
    stopped: OnceLock<String>,
}

impl RecordStatus {
    /// Still recording.
    pub fn recording(&self) -> bool {
        self.recording.load(Ordering::Acquire)
    }
    /// Why recording stopped before the session ended, once it did.
    pub fn stopped(&self) -> Option<&str> {
        self.stopped.get().map(String::as_str)
    }
    /// Haptic steps in the file (in whole chunks, synced).
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Relaxed)
    }
    /// Bytes of the file (whole chunks, synced).
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }
    /// Haptic steps the session ran after recording stopped (not in the file).
    pub fn unrecorded(&self) -> u64 {
        self.unrecorded.load(Ordering::Relaxed)
    }
    fn stop(&self, why: String) {
        tracing::error!("recording stopped: {why}");
        let _ = self.stopped.set(why);
        self.recording.store(false, Ordering::Release);
    }
}

/// The haptic thread's end of the record: hands steps over without waiting.
pub struct StepSender {
    tx: rtrb::Producer<StepRecord>,
    status: Arc<RecordStatus>,
}

impl StepSender {
    /// Hands `step` to the writer (wait-free). False if it is not recorded: recording had stopped, or the
    /// queue is full (recording stops there).
    pub fn send(&mut self, step: StepRecord) -> bool {
        if self.status.recording.load(Ordering::Relaxed) && self.tx.push(step).is_ok() {
            return true;
        }
        if self.status.recording.swap(false, Ordering::AcqRel) {
            self.status.full.store(FULL_HAPTIC, Ordering::Release);
        }
        self.status.unrecorded.fetch_add(1, Ordering::Relaxed);
        false
    }
}

/// The global thread's end of the record: hands global steps over without waiting.
pub struct GlobalSender {
    tx: rtrb::Producer<GlobalRecord>,
    status: Arc<RecordStatus>,
}

impl GlobalSender {
    /// Hands `step` to the writer (wait-free); false if it is not recorded (as [`StepSender::send`]).
    pub fn send(&mut self, step: GlobalRecord) -> bool {
        if self.status.recording.load(Ordering::Relaxed) && self.tx.push(step).is_ok() {
            return true;
        }
        if self.status.recording.swap(false, Ordering::AcqRel) {
            self.status.full.store(FULL_GLOBAL, Ordering::Release);
        }
        false
    }
}

/// What a finished record holds.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordReport {
    /// The file (the sink's name).
    pub name: String,
    /// Haptic steps in the file.
    pub steps: u64,
    /// Global steps in the file.
    pub global_steps: u64,
    /// Bytes in the file.
    pub bytes: u64,
    /// Haptic steps the session ran after recording stopped.
    pub unrecorded: u64,
    /// Why recording stopped before the session ended (None: it recorded the whole session).
    pub stopped: Option<String>,
}

/// The writer thread of a record.
pub struct RecordWriter {
    thread: Option<JoinHandle<RecordReport>>,
    status: Arc<RecordStatus>,
    name: String,
}

impl RecordWriter {
    /// Writes the header (the session's `settings`) to `sink` (an error there is returned: recording cannot
    /// start) and starts the writer thread; returns it and the senders of the haptic loop (at `rate_hz`) and of
    /// the global loop (at `global_rate_hz`).
    pub fn start(mut sink: Box<dyn RecordSink>, settings: Option<&RecordSettings>, rate_hz: f64, global_rate_hz: f64, params: RecordParams) -> Result<(RecordWriter, StepSender, GlobalSender), SessionError> {
        params.validate()?;
        let mut head = Vec::new();
        put_header(&mut head, rate_hz, settings);
        sink.write_all(&head).and_then(|()| sink.sync()).map_err(|e| SessionError::Start(format!("cannot write the record {}: {e}", sink.name())))?;
        let status = Arc::new(RecordStatus { recording: AtomicBool::new(true), bytes: AtomicU64::new(head.len() as u64), ..RecordStatus::default() });
        let (step_tx, step_rx) = rtrb::RingBuffer::new(params.capacity(rate_hz));
        let (global_tx, global_rx) = rtrb::RingBuffer::new(params.capacity(global_rate_hz));
        let (st, queue, name) = (status.clone(), params.capacity(rate_hz), sink.name());
        let thread = std::thread::Builder::new()
            .name("coiffure-record".into())
            .spawn(move || write_loop(sink, step_rx, global_rx, &st, params, queue, rate_hz))
            .map_err(|e| SessionError::Start(format!("cannot start the record writer: {e}")))?;
        Ok((RecordWriter { thread: Some(thread), status: status.clone(), name }, StepSender { tx: step_tx, status: status.clone() }, GlobalSender { tx: global_tx, status }))
    }

    /// The shared status.
    pub fn status(&self) -> Arc<RecordStatus> {
        self.status.clone()
    }

    /// Waits for the writer to write what its senders (dropped by now) handed over, and the end chunk.
    pub fn finish(mut self) -> RecordReport {
        self.join()
    }

    fn join(&mut self) -> RecordReport {
        let mut r = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r,
            _ => RecordReport { name: self.name.clone(), steps: self.status.steps(), global_steps: self.status.globals.load(Ordering::Relaxed), bytes: self.status.bytes(), unrecorded: 0, stopped: Some("the record writer panicked".into()) },
        };
        r.unrecorded = self.status.unrecorded();
        r
    }
}

impl Drop for RecordWriter {
    fn drop(&mut self) {
        if self.thread.is_some() {
            self.join();
        }
    }
}

/// The writer thread: drains the queues into a chunk, writes and syncs it every flush interval, and writes the
/// end chunk when both senders are gone (the session ended) or a queue was found full.
fn write_loop(mut sink: Box<dyn RecordSink>, mut steps: rtrb::Consumer<StepRecord>, mut globals: rtrb::Consumer<GlobalRecord>, status: &RecordStatus, params: RecordParams, queue: usize, rate_hz: f64) -> RecordReport {
    let flush = Duration::from_secs_f64(params.flush_interval);
    let poll = (flush / 5).min(Duration::from_millis(20));
    let mut chunk = StepsChunk::default();
    let mut out = Vec::new();
    let mut last = Instant::now();
    let mut written = status.bytes();
    let name = sink.name();
    loop {
        // Checked before draining, so that what was handed over before is written.
        let ended = steps.is_abandoned() && globals.is_abandoned();
        let full = status.full.load(Ordering::Acquire);
        // Haptic steps first, then global steps: every haptic step drained read a lattice version whose global
        // step was handed over before it, so it is among the global steps drained (a chunk always replays).
        while let Ok(s) = steps.pop() {
            chunk.push_step(&s);
        }
        while let Ok(g) = globals.pop() {
            chunk.push_global(&g);
        }
        let stopped = match full {
            FULL_NONE => None,
            which => Some(format!(
                "the record writer fell behind: its queue of {} was full at haptic step {} (the disk held it up for {} s); the steps before are in the file",
                if which == FULL_HAPTIC { format!("{queue} haptic steps") } else { "global steps".to_string() },
                chunk.totals().1,
                params.queue_seconds
            )),
        };
        let end = ended || stopped.is_some();
        if end || last.elapsed() >= flush || chunk.len() > 8 << 20 {
            chunk.finish(&mut out);
            if end {
                let (g, s) = chunk.totals();
                put_end(&mut out, g, s, stopped.as_deref());
            }
            if !out.is_empty() {
                if let Err(e) = sink.write_all(&out).and_then(|()| sink.sync()) {
                    // The file keeps its whole chunks: cut back any part of this one.
                    let cut = sink.truncate(written).err().map(|e| format!(" (and cutting it back failed: {e})")).unwrap_or_default();
                    let (done_steps, secs) = (status.steps(), status.steps() as f64 / rate_hz);
                    let why = format!("cannot write the record {name} after byte {written}: {e}{cut}; the file holds the first {done_steps} haptic steps ({secs:.1} s) and replays up to there");
                    status.stop(why.clone());
                    return RecordReport { name, steps: done_steps, global_steps: status.globals.load(Ordering::Relaxed), bytes: written, unrecorded: 0, stopped: Some(why) };
                }
                written += out.len() as u64;
                out.clear();
                let (g, s) = chunk.totals();
                status.steps.store(s, Ordering::Relaxed);
                status.globals.store(g, Ordering::Relaxed);
                status.bytes.store(written, Ordering::Relaxed);
            }
            last = Instant::now();
            if end {
                if let Some(why) = &stopped {
                    status.stop(why.clone());
                }
                let (global_steps, steps) = chunk.totals();
                return RecordReport { name, steps, global_steps, bytes: written, unrecorded: 0, stopped };
            }
        }
        std::thread::sleep(poll);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::record::{Ending, Record};
    use crate::tool::{Tool, ToolInput};
    use haptics::device::DeviceReading;
    use nalgebra::{Matrix3, Vector3};
    use std::sync::Mutex;

    /// A sink in memory that fails with ENOSPC ("No space left on device") once it would hold more than `limit`
    /// bytes (keeping the part that fitted, as a file does), and holds each write for `delay`.
    #[derive(Clone)]
    struct Mem {
        bytes: Arc<Mutex<Vec<u8>>>,
        limit: usize,
        delay: Duration,
    }

    impl Mem {
        fn new(limit: usize, delay: Duration) -> Self {
            Self { bytes: Arc::default(), limit, delay }
        }
        fn bytes(&self) -> Vec<u8> {
            self.bytes.lock().unwrap().clone()
        }
    }

    impl RecordSink for Mem {
        fn write_all(&mut self, b: &[u8]) -> std::io::Result<()> {
            std::thread::sleep(self.delay);
            let mut v = self.bytes.lock().unwrap();
            let room = self.limit.saturating_sub(v.len()).min(b.len());
            v.extend_from_slice(&b[..room]);
            if room < b.len() {
                return Err(std::io::Error::from_raw_os_error(28));
            }
            Ok(())
        }
        fn sync(&mut self) -> std::io::Result<()> {
            Ok(())
        }
        fn truncate(&mut self, len: u64) -> std::io::Result<()> {
            self.bytes.lock().unwrap().truncate(len as usize);
            Ok(())
        }
        fn name(&self) -> String {
            "memory".into()
        }
    }

    /// A pseudo-random session of `n` haptic steps, one global step every 10 (as the live threads make them:
    /// a haptic step reads the latest version), some commands and lattice resets; in the order the threads hand
    /// them over.
    fn session(n: u64) -> (Record, Vec<Result<GlobalRecord, StepRecord>>) {
        let mut rec = Record::new(1000.0);
        let mut order = vec![];
        let mut s = 0x9e3779b97f4a7c15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for i in 0..n {
            if i % 10 == 0 {
                let g = GlobalRecord { reset: i % 2000 == 0 && i > 0, input: ToolInput { tool: Tool::ALL[(i / 10) as usize % 6], present: true, pressed: i % 30 == 0, position: Vector3::new(next(), next(), next()), cuts: i / 700, ..ToolInput::default() } };
                if g.reset {
                    rec.global_resets.push(rec.global_inputs.len() as u64 + 1);
                }
                rec.global_inputs.push(g.input);
                order.push(Ok(g));
            }
            let commands = if i % 997 == 0 { vec![Command::SelectTool(Tool::Comb), Command::LimitStrands(40)] } else { vec![] };
            let reading = (i % 50 != 0).then(|| DeviceReading { time: i as f64 * 1e-3, position: Vector3::new(next(), next(), next()), rotation: Matrix3::identity(), buttons: (i % 3) as u32 });
            let st = StepRecord { reading, more_readings: Vec::new(), lattice_version: rec.global_inputs.len() as u64, commands, force: Vector3::new(next(), next(), next()), carried: 0 };
            rec.steps.push(st.clone());
            order.push(Err(st));
        }
        (rec, order)
    }

    /// Hands `order` to the senders at about `per_ms` haptic steps a millisecond; the results of the haptic sends
    /// (and the longest one took, s).
    fn feed(order: Vec<Result<GlobalRecord, StepRecord>>, steps: &mut StepSender, globals: &mut GlobalSender, per_ms: usize) -> (Vec<bool>, f64) {
        let (mut sent, mut longest) = (vec![], 0.0f64);
        for item in order {
            match item {
                Ok(g) => {
                    globals.send(g);
                }
                Err(s) => {
                    let t = Instant::now();
                    sent.push(steps.send(s));
                    longest = longest.max(t.elapsed().as_secs_f64());
                    if sent.len() % per_ms == 0 {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                }
            }
        }
        (sent, longest)
    }

    /// The ends of the chunks of a record file, found by walking their lengths (not through the reader).
    fn chunk_ends(b: &[u8]) -> Vec<usize> {
        let mut ends = vec![];
        let mut at = 8;
        while at + 8 <= b.len() {
            at += 8 + u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
            ends.push(at);
        }
        ends
    }

    #[test]
    fn a_streamed_record_reads_back_whole_and_cut_at_1000_random_offsets_to_its_last_whole_chunk() {
        // 20,000 haptic steps (2,000 global steps) handed over as fast as a 5 kHz loop would, written in chunks
        // every 20 ms: the file reads back to the same record, complete. Cut at 1,000 random byte offsets, it is
        // refused naming an offset within the cut when the cut is in the magic or the header, and otherwise read
        // up to the end of the last whole chunk before the cut (which the reader names), its steps a prefix of the
        // session's, each reading a lattice version whose global step is there (so the cut record replays).
        let (rec, order) = session(20_000);
        let mem = Mem::new(usize::MAX, Duration::ZERO);
        let params = RecordParams { flush_interval: 0.02, queue_seconds: 10.0 };
        let (w, mut steps, mut globals) = RecordWriter::start(Box::new(mem.clone()), None, 1000.0, 100.0, params).unwrap();
        let (sent, _) = feed(order, &mut steps, &mut globals, 5);
        assert!(sent.iter().all(|&s| s), "no step dropped");
        drop((steps, globals));
        let report = w.finish();
        let b = mem.bytes();
        assert_eq!((report.steps, report.global_steps, report.bytes, report.stopped), (20_000, 2_000, b.len() as u64, None));
        let whole = Record::read(&b).unwrap();
        assert_eq!(whole.ending, Ending::Complete);
        assert_eq!(whole.record, rec);
        let ends = chunk_ends(&b);
        eprintln!("{} bytes in {} chunks", b.len(), ends.len());
        assert!(ends.len() >= 10 && *ends.last().unwrap() == b.len(), "{} chunks", ends.len());
        let mut s = 12345u64;
        let mut refused = 0;
        for _ in 0..1000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let n = (s >> 33) as usize % b.len();
            match Record::read(&b[..n]) {
                Err(crate::record::RecordError::Bad { offset, what }) => {
                    assert!(n < ends[0] && offset <= n, "cut at {n}: refused at {offset}: {what}");
                    refused += 1;
                }
                Ok(got) => {
                    let last = ends.iter().copied().filter(|&e| e <= n).last().unwrap();
                    let Ending::Cut(c) = &got.ending else { panic!("cut at {n}: {:?}", got.ending) };
                    assert_eq!((c.offset, c.file_bytes), (last, n), "cut at {n}: {}", c.why);
                    assert!(rec.steps.starts_with(&got.record.steps) && rec.global_inputs.starts_with(&got.record.global_inputs), "cut at {n}");
                    let globals = got.record.global_inputs.len() as u64;
                    assert!(got.record.steps.iter().all(|s| s.lattice_version <= globals), "cut at {n}");
                    assert!(rec.global_resets.starts_with(&got.record.global_resets));
                }
            }
        }
        eprintln!("{refused} of 1000 cuts in the magic or header");
    }

    #[test]
    fn a_full_disk_stops_recording_the_steps_go_on_and_the_file_reads_up_to_the_failure() {
        // The sink fills after 60 kB (a full disk: ENOSPC part way through a chunk). The senders never wait: the
        // steps after the failure are counted as unrecorded; the status says why, naming the error; the file is
        // cut back to its last whole chunk and reads up to it: the steps written, a prefix of the session's.
        let (rec, order) = session(5_000);
        let mem = Mem::new(60_000, Duration::ZERO);
        let params = RecordParams { flush_interval: 0.01, queue_seconds: 10.0 };
        let (w, mut steps, mut globals) = RecordWriter::start(Box::new(mem.clone()), None, 1000.0, 100.0, params).unwrap();
        let status = w.status();
        let (sent, _) = feed(order, &mut steps, &mut globals, 2);
        drop((steps, globals));
        let report = w.finish();
        let why = status.stopped().expect("recording stopped").to_string();
        eprintln!("{why}; {report:?}");
        assert!(why.contains("os error 28") && why.contains("memory"), "{why}");
        assert!(!status.recording());
        assert_eq!(report.stopped.as_deref(), Some(why.as_str()));
        let b = mem.bytes();
        assert_eq!(b.len() as u64, report.bytes, "cut back to the last whole chunk");
        let got = Record::read(&b).unwrap();
        assert!(matches!(&got.ending, Ending::Cut(c) if c.offset == b.len()), "{:?}", got.ending);
        assert_eq!(got.record.steps.len() as u64, report.steps);
        assert!(report.steps > 100 && report.steps < 5_000, "{} steps written", report.steps);
        assert!(rec.steps.starts_with(&got.record.steps));
        let accepted = sent.iter().filter(|&&s| s).count() as u64;
        assert_eq!(report.unrecorded, 5_000 - accepted, "every step after the stop counted");
        assert!(sent.iter().skip_while(|&&s| s).all(|&s| !s), "nothing recorded after the stop");
    }

    #[test]
    fn a_writer_held_up_stops_recording_without_blocking_and_says_so() {
        // Each write takes 1 s (a stalled disk) and the queue holds 0.1 s of steps: the haptic sender finds it full
        // and does not wait (no send takes half the stall; one that waited for the writer would take a whole one);
        // recording stops there; the steps handed over before are written, with an end chunk saying the writer
        // fell behind; the later ones are counted.
        let (rec, order) = session(2_000);
        let mem = Mem::new(usize::MAX, Duration::from_secs(1));
        let params = RecordParams { flush_interval: 0.02, queue_seconds: 0.1 };
        let (w, mut steps, mut globals) = RecordWriter::start(Box::new(mem.clone()), None, 1000.0, 100.0, params).unwrap();
        let (sent, longest) = feed(order, &mut steps, &mut globals, 1);
        drop((steps, globals));
        let report = w.finish();
        let accepted = sent.iter().filter(|&&s| s).count();
        eprintln!("{accepted} steps accepted, the longest send {:.1} us; {report:?}", 1e6 * longest);
        assert!(longest < 0.5, "a send waited {longest} s");
        assert!(accepted < 2_000 && sent.iter().skip_while(|&&s| s).all(|&s| !s));
        let got = Record::read(&mem.bytes()).unwrap();
        let Ending::Stopped(why) = &got.ending else { panic!("{:?}", got.ending) };
        assert!(why.contains("fell behind") && why.contains("100 haptic steps"), "{why}");
        assert_eq!(got.record.steps[..], rec.steps[..accepted]);
        assert_eq!((report.steps, report.unrecorded), (accepted as u64, (2_000 - accepted) as u64));
    }

    #[test]
    fn bad_params_are_refused_naming_the_field() {
        let e = RecordParams { flush_interval: 0.0, ..RecordParams::default() }.validate().unwrap_err().to_string();
        assert!(e.contains("flush_interval"), "{e}");
        let e = RecordParams { queue_seconds: 0.5, ..RecordParams::default() }.validate().unwrap_err().to_string();
        assert!(e.contains("queue_seconds"), "{e}");
    }
}
