//! The record file's steps and chunks (little-endian; see the module above): encoding ([`StepsChunk`], used by
//! the stream writer and by [`Record::to_bytes`]) and reading ([`Record::read`]).

use super::chunk::{self, kind, MAGIC};
use super::{Cut, Ending, GlobalRecord, ReadRecord, Record, RecordError, RecordSettings, StepRecord};
use crate::command::Command;
use crate::tool::{Tool, ToolInput};
use haptics::device::DeviceReading;
use hairstyle::formats::bytes::Cursor;
use nalgebra::{Matrix3, Vector3};

/// Haptic steps per chunk in [`Record::to_bytes`] (the stream writer cuts its chunks by time instead).
const STEPS_PER_CHUNK: usize = 1000;
/// Global-step flag: the lattice was reset before this step.
const RESET: u8 = 8;

fn f(b: &mut Vec<u8>, x: f64) {
    b.extend_from_slice(&x.to_le_bytes());
}

/// Appends a global step.
fn put_global(b: &mut Vec<u8>, g: &GlobalRecord) {
    let i = &g.input;
    b.push(i.tool as u8);
    let moved = i.head != nalgebra::Isometry3::identity();
    b.push(i.present as u8 | (i.pressed as u8) << 1 | (moved as u8) << 2 | if g.reset { RESET } else { 0 });
    i.position.iter().for_each(|&x| f(b, x));
    i.rotation.iter().for_each(|&x| f(b, x));
    b.extend_from_slice(&i.cuts.to_le_bytes());
    if moved {
        // flag bit 2: the head pose follows (translation x y z, unit quaternion i j k w)
        i.head.translation.vector.iter().for_each(|&x| f(b, x));
        i.head.rotation.coords.iter().for_each(|&x| f(b, x));
    }
}

/// Appends a device reading: u8 has-reading (0 or 1), then if 1 the reading.
fn put_reading(b: &mut Vec<u8>, r: &Option<DeviceReading>) {
    match r {
        None => b.push(0),
        Some(r) => {
            b.push(1);
            f(b, r.time);
            r.position.iter().for_each(|&x| f(b, x));
            r.rotation.iter().for_each(|&x| f(b, x));
            b.extend_from_slice(&r.buttons.to_le_bytes());
        }
    }
}

/// Appends a haptic step.
fn put_step(b: &mut Vec<u8>, s: &StepRecord) {
    if s.carried > 0 {
        // Device steps run beyond the readings: flag 3, the device steps' count, each reading, then the carried
        // steps (u32). Records without them read as before (older records have none).
        b.push(3);
        b.push((1 + s.more_readings.len()).min(255) as u8);
        for r in std::iter::once(&s.reading).chain(&s.more_readings).take(255) {
            put_reading(b, r);
        }
        b.extend_from_slice(&s.carried.to_le_bytes());
    } else if s.more_readings.is_empty() {
        put_reading(b, &s.reading);
    } else {
        // Several device steps: flag 2, their count, each reading.
        b.push(2);
        b.push((1 + s.more_readings.len()).min(255) as u8);
        for r in std::iter::once(&s.reading).chain(&s.more_readings).take(255) {
            put_reading(b, r);
        }
    }
    b.extend_from_slice(&s.lattice_version.to_le_bytes());
    s.force.iter().for_each(|&x| f(b, x));
    b.push(s.commands.len().min(255) as u8);
    for c in s.commands.iter().take(255) {
        match *c {
            Command::SelectTool(t) => b.extend_from_slice(&[0, t as u8]),
            Command::SetHair { hair_type, curliness, combing_ease } => {
                b.extend_from_slice(&[1, hair_type]);
                f(b, curliness);
                f(b, combing_ease);
            }
            Command::Reset => b.push(2),
            Command::SetHead { position, rotation } => {
                b.push(3);
                position.iter().chain(rotation.iter()).for_each(|&x| f(b, x));
            }
            Command::LimitStrands(n) => {
                b.push(4);
                b.extend_from_slice(&n.to_le_bytes());
            }
            Command::SetTreatment(t) => b.extend_from_slice(&[5, t.id()]),
        }
    }
}

/// Appends the magic and the header chunk of a record at `rate_hz` (Hz) of a session with `settings`.
pub(crate) fn put_header(out: &mut Vec<u8>, rate_hz: f64, settings: Option<&RecordSettings>) {
    out.extend_from_slice(MAGIC);
    let mut p = vec![kind::HEADER];
    f(&mut p, rate_hz);
    let text = settings.map(RecordSettings::to_text).unwrap_or_default();
    p.extend_from_slice(&(text.len() as u32).to_le_bytes());
    p.extend_from_slice(text.as_bytes());
    chunk::put(out, &p);
}

/// Appends the end chunk: `globals` and `steps` written in all; `stopped`: why recording stopped before the
/// session ended, if it did.
pub(crate) fn put_end(out: &mut Vec<u8>, globals: u64, steps: u64, stopped: Option<&str>) {
    let mut p = vec![kind::END];
    p.extend_from_slice(&globals.to_le_bytes());
    p.extend_from_slice(&steps.to_le_bytes());
    p.push(stopped.is_some() as u8);
    let why = stopped.unwrap_or("").as_bytes();
    let n = why.len().min(u16::MAX as usize);
    // Cut on a character boundary.
    let n = (0..=n).rev().find(|&k| std::str::from_utf8(&why[..k]).is_ok()).unwrap_or(0);
    p.extend_from_slice(&(n as u16).to_le_bytes());
    p.extend_from_slice(&why[..n]);
    chunk::put(out, &p);
}

/// A steps chunk being filled: global steps and haptic steps, numbered on from the previous chunk's.
#[derive(Debug, Default)]
pub(crate) struct StepsChunk {
    first_global: u64,
    globals: Vec<u8>,
    n_globals: u32,
    first_step: u64,
    steps: Vec<u8>,
    n_steps: u32,
}

impl StepsChunk {
    /// Adds a global step.
    pub fn push_global(&mut self, g: &GlobalRecord) {
        put_global(&mut self.globals, g);
        self.n_globals += 1;
    }

    /// Adds a haptic step.
    pub fn push_step(&mut self, s: &StepRecord) {
        put_step(&mut self.steps, s);
        self.n_steps += 1;
    }

    /// Nothing added since the last [`StepsChunk::finish`].
    pub fn is_empty(&self) -> bool {
        self.n_globals == 0 && self.n_steps == 0
    }

    /// Payload bytes so far.
    pub fn len(&self) -> usize {
        1 + 2 * 12 + self.globals.len() + self.steps.len()
    }

    /// Global and haptic steps added to all chunks, finished or not.
    pub fn totals(&self) -> (u64, u64) {
        (self.first_global + self.n_globals as u64, self.first_step + self.n_steps as u64)
    }

    /// Appends the chunk to `out` (if it has any step) and starts the next one.
    pub fn finish(&mut self, out: &mut Vec<u8>) {
        if self.is_empty() {
            return;
        }
        let mut p = Vec::with_capacity(self.len());
        p.push(kind::STEPS);
        p.extend_from_slice(&self.first_global.to_le_bytes());
        p.extend_from_slice(&self.n_globals.to_le_bytes());
        p.extend_from_slice(&self.globals);
        p.extend_from_slice(&self.first_step.to_le_bytes());
        p.extend_from_slice(&self.n_steps.to_le_bytes());
        p.extend_from_slice(&self.steps);
        chunk::put(out, &p);
        (self.first_global, self.first_step) = self.totals();
        (self.n_globals, self.n_steps) = (0, 0);
        self.globals.clear();
        self.steps.clear();
    }
}

impl Record {
    /// Serialises the whole record (header, chunks of [`STEPS_PER_CHUNK`] haptic steps each with the global
    /// steps they read, end chunk): the file a live session recording these steps would have written.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + self.steps.len() * 160 + self.global_inputs.len() * 140);
        put_header(&mut out, self.rate_hz, self.settings.as_ref());
        let mut c = StepsChunk::default();
        let mut globals = self.global_steps().peekable();
        for part in self.steps.chunks(STEPS_PER_CHUNK) {
            // The global steps these haptic steps read come first (a cut file then always replays).
            let need = part.iter().map(|s| s.lattice_version).max().unwrap_or(0);
            while c.totals().0 < need {
                let Some(g) = globals.next() else { break };
                c.push_global(&g);
            }
            part.iter().for_each(|s| c.push_step(s));
            c.finish(&mut out);
        }
        globals.for_each(|g| c.push_global(&g));
        c.finish(&mut out);
        put_end(&mut out, self.global_inputs.len() as u64, self.steps.len() as u64, None);
        out
    }

    /// Parses a whole record: [`Record::read`], and a file without its end chunk is an error naming the offset
    /// where it was cut.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, RecordError> {
        let r = Self::read(bytes)?;
        match r.ending {
            Ending::Complete | Ending::Stopped(_) => Ok(r.record),
            Ending::Cut(c) => Err(RecordError::Bad { offset: c.offset, what: c.why }),
        }
    }

    /// Reads a record up to its end, or up to its last whole chunk if it was cut or damaged there
    /// ([`Ending::Cut`] says at which byte and why). A file whose magic or header chunk is not whole is refused
    /// with the byte offset; so is an older version (named).
    pub fn read(bytes: &[u8]) -> Result<ReadRecord, RecordError> {
        let bad = |offset: usize, what: String| RecordError::Bad { offset, what };
        if bytes.len() < MAGIC.len() {
            return Err(if MAGIC.starts_with(bytes) { bad(bytes.len(), format!("cut inside the magic ({} of its 8 bytes)", bytes.len())) } else { bad(0, "not a Coiffure session record (magic CFREC4)".into()) });
        }
        let magic = &bytes[..8];
        if magic != MAGIC {
            return Err(match magic.strip_prefix(b"CFREC") {
                Some([v, 0, 0]) if v.is_ascii_digit() => bad(0, format!(
                    "a version-{} session record (CFREC{}), written by an older Coiffure {}: this version reads version 4 (CFREC4) only; replay it with the Coiffure that recorded it",
                    *v as char,
                    *v as char,
                    if *v == b'3' { "whose device loop was its physics loop (one device step per haptic step)" } else { "before records were streamed" }
                )),
                _ => bad(0, "not a Coiffure session record (magic CFREC4)".into()),
            });
        }
        let (header, mut at) = match chunk::next(bytes, 8) {
            Ok(Some(h)) => h,
            Ok(None) => return Err(bad(8, "no header chunk after the magic".into())),
            Err(why) => return Err(bad(8, format!("the header chunk: {why}"))),
        };
        let mut h = Reader::on(header, 8 + chunk::CHUNK_HEADER_BYTES);
        if h.u8()? != kind::HEADER {
            return Err(bad(8, "the first chunk is not the header".into()));
        }
        let rate_hz = h.f64()?;
        if !(rate_hz > 0.0 && rate_hz.is_finite()) {
            return Err(bad(h.at() - 8, format!("haptic rate {rate_hz} Hz must be > 0")));
        }
        let n = h.u32()? as usize;
        let text_at = h.at();
        let text = std::str::from_utf8(h.take(n)?).map_err(|e| bad(text_at, format!("the settings are not UTF-8 text: {e}")))?;
        let settings = if text.is_empty() { None } else { Some(RecordSettings::from_text(text).map_err(|e| bad(text_at, format!("the settings: {e}")))?) };
        h.done()?;
        let mut rec = Record { settings, ..Record::new(rate_hz) };
        let cut = |offset: usize, why: String| Ending::Cut(Cut { offset, file_bytes: bytes.len(), why });
        let ending = loop {
            let (payload, next) = match chunk::next(bytes, at) {
                Ok(Some(c)) => c,
                Ok(None) => break cut(at, "the file ends after its last whole chunk, without the end chunk: recording did not end in order (the server was killed or died, or writing failed)".into()),
                Err(why) => break cut(at, why),
            };
            let base = at + chunk::CHUNK_HEADER_BYTES;
            let mut r = Reader::on(payload, base);
            let parsed = match r.u8() {
                Ok(kind::STEPS) => read_steps(&mut r, &mut rec).map(|()| None),
                Ok(kind::END) => read_end(&mut r, &rec).map(Some),
                Ok(k) => Err(bad(base, format!("chunk kind {k} (1 steps or 2 end here)"))),
                Err(e) => Err(e),
            };
            match parsed {
                Err(RecordError::Bad { offset, what }) => break cut(at, format!("the chunk at byte {at} is not valid at byte {offset}: {what}")),
                Ok(None) => at = next,
                Ok(Some(end)) if next == bytes.len() => break end,
                Ok(Some(_)) => break cut(next, format!("{} bytes after the end chunk", bytes.len() - next)),
            }
        };
        Ok(ReadRecord { record: rec, ending })
    }
}

/// Reads a steps chunk's body into `rec` (all or nothing: on an error `rec` is left as it was).
fn read_steps(r: &mut Reader, rec: &mut Record) -> Result<(), RecordError> {
    let at = r.at();
    let first = r.u64()?;
    if first != rec.global_inputs.len() as u64 {
        return Err(RecordError::Bad { offset: at, what: format!("its global steps start at {first}, not at {} (a chunk is missing)", rec.global_inputs.len()) });
    }
    let n = r.u32()? as usize;
    let mut inputs = Vec::with_capacity(n.min(r.0.remaining() / MIN_GLOBAL_BYTES));
    let mut resets = Vec::new();
    for i in 0..n {
        let g = read_global(r)?;
        if g.reset {
            resets.push(first + i as u64 + 1);
        }
        inputs.push(g.input);
    }
    let globals = first + n as u64;
    let at = r.at();
    let first = r.u64()?;
    if first != rec.steps.len() as u64 {
        return Err(RecordError::Bad { offset: at, what: format!("its haptic steps start at {first}, not at {} (a chunk is missing)", rec.steps.len()) });
    }
    let n = r.u32()? as usize;
    let mut steps = Vec::with_capacity(n.min(r.0.remaining() / MIN_STEP_BYTES));
    for _ in 0..n {
        let at = r.at();
        let s = read_step(r)?;
        if s.lattice_version > globals {
            return Err(RecordError::Bad { offset: at, what: format!("a haptic step reads lattice version {} but only {globals} global steps are recorded so far", s.lattice_version) });
        }
        steps.push(s);
    }
    r.done()?;
    rec.global_inputs.append(&mut inputs);
    rec.global_resets.append(&mut resets);
    rec.steps.append(&mut steps);
    Ok(())
}

/// Reads the end chunk's body: how the record ends (its totals checked against what was read).
fn read_end(r: &mut Reader, rec: &Record) -> Result<Ending, RecordError> {
    let at = r.at();
    let (globals, steps) = (r.u64()?, r.u64()?);
    if (globals, steps) != (rec.global_inputs.len() as u64, rec.steps.len() as u64) {
        return Err(RecordError::Bad { offset: at, what: format!("it counts {globals} global and {steps} haptic steps, the file has {} and {}", rec.global_inputs.len(), rec.steps.len()) });
    }
    let at = r.at();
    let stopped = r.u8()?;
    let n = r.u16()? as usize;
    let why = r.take(n)?;
    r.done()?;
    let why = String::from_utf8_lossy(why).into_owned();
    match stopped {
        0 => Ok(Ending::Complete),
        1 => Ok(Ending::Stopped(why)),
        k => Err(RecordError::Bad { offset: at, what: format!("end flag {k} (0 or 1)") }),
    }
}

/// Smallest global step: tool, flags, 3 + 9 f64, u64 cuts (bytes).
const MIN_GLOBAL_BYTES: usize = 2 + 12 * 8 + 8;
/// Smallest haptic step: no reading, u64 version, 3 f64 force, no commands (bytes).
const MIN_STEP_BYTES: usize = 1 + 8 + 24 + 1;

fn read_global(r: &mut Reader) -> Result<GlobalRecord, RecordError> {
    let at = r.at();
    let id = r.u8()?;
    let tool = Tool::from_id(id).ok_or(RecordError::Bad { offset: at, what: format!("tool id {id}") })?;
    let flags = r.u8()?;
    if flags > 15 {
        return Err(RecordError::Bad { offset: at + 1, what: format!("global step flags {flags} (0-15)") });
    }
    let position = Vector3::new(r.f64()?, r.f64()?, r.f64()?);
    let mut m = [0.0; 9];
    for x in &mut m {
        *x = r.f64()?;
    }
    let cuts = r.u64()?;
    let mut head = nalgebra::Isometry3::identity();
    if flags & 4 != 0 {
        let at = r.at();
        let t = Vector3::new(r.f64()?, r.f64()?, r.f64()?);
        let (i, j, k, w) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
        let q = nalgebra::Quaternion::new(w, i, j, k);
        if !(t.iter().all(|x| x.is_finite()) && (q.norm() - 1.0).abs() < 1e-6) {
            return Err(RecordError::Bad { offset: at, what: "head pose: non-finite or not a unit quaternion".into() });
        }
        head = nalgebra::Isometry3::from_parts(t.into(), nalgebra::UnitQuaternion::new_unchecked(q));
    }
    let input = ToolInput { tool, present: flags & 1 != 0, pressed: flags & 2 != 0, position, rotation: Matrix3::from_column_slice(&m), cuts, head };
    Ok(GlobalRecord { reset: flags & RESET != 0, input })
}

fn read_step(r: &mut Reader) -> Result<StepRecord, RecordError> {
    let (reading, more_readings, carried) = match r.u8()? {
        k @ (2 | 3) => {
            let at = r.at();
            let n = r.u8()?;
            let least = if k == 2 { 2 } else { 1 };
            if n < least {
                return Err(RecordError::Bad { offset: at, what: format!("{n} device steps after flag {k} (at least {least})") });
            }
            let first = r.reading()?;
            let more = (1..n).map(|_| r.reading()).collect::<Result<Vec<_>, _>>()?;
            let carried = if k == 3 {
                let at = r.at();
                match r.u32()? {
                    0 => return Err(RecordError::Bad { offset: at, what: "0 carried device steps after flag 3 (at least 1)".into() }),
                    c => c,
                }
            } else {
                0
            };
            (first, more, carried)
        }
        k => (r.reading_after(k)?, Vec::new(), 0),
    };
    let lattice_version = r.u64()?;
    let force = Vector3::new(r.f64()?, r.f64()?, r.f64()?);
    let nc = r.u8()?;
    let mut commands = Vec::with_capacity(nc as usize);
    for _ in 0..nc {
        let at = r.at();
        commands.push(match r.u8()? {
            0 => {
                let id = r.u8()?;
                Command::SelectTool(Tool::from_id(id).ok_or(RecordError::Bad { offset: at + 1, what: format!("tool id {id}") })?)
            }
            1 => Command::SetHair { hair_type: r.u8()?, curliness: r.f64()?, combing_ease: r.f64()? },
            2 => Command::Reset,
            3 => Command::SetHead { position: Vector3::new(r.f64()?, r.f64()?, r.f64()?), rotation: Vector3::new(r.f64()?, r.f64()?, r.f64()?) },
            4 => Command::LimitStrands(r.u32()?),
            5 => {
                let id = r.u8()?;
                Command::SetTreatment(tools::treatment::Treatment::from_id(id).ok_or(RecordError::Bad { offset: at + 1, what: format!("treatment id {id}") })?)
            }
            k => return Err(RecordError::Bad { offset: at, what: format!("command kind {k}") }),
        });
    }
    Ok(StepRecord { reading, more_readings, lattice_version, commands, force, carried })
}

/// The hair formats' little-endian reader (one byte reader in the project) on a chunk's payload, its errors as
/// record errors with offsets in the file (`base`: the payload's offset).
struct Reader<'a>(Cursor<'a>, usize);

impl<'a> Reader<'a> {
    fn on(payload: &'a [u8], base: usize) -> Self {
        Reader(Cursor::new(payload, "session record"), base)
    }
    fn err(&self, e: hairstyle::formats::FormatError) -> RecordError {
        match e {
            hairstyle::formats::FormatError::Binary { offset, expected, .. } => RecordError::Bad { offset: self.1 + offset as usize, what: format!("the chunk ends early: {expected}") },
            e => RecordError::Bad { offset: self.at(), what: e.to_string() },
        }
    }
    /// Offset in the file, bytes.
    fn at(&self) -> usize {
        self.1 + self.0.pos()
    }
    fn done(&self) -> Result<(), RecordError> {
        match self.0.remaining() {
            0 => Ok(()),
            n => Err(RecordError::Bad { offset: self.at(), what: format!("{n} bytes left over in the chunk") }),
        }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], RecordError> {
        self.0.take(n, "bytes").map_err(|e| self.err(e))
    }
    fn u8(&mut self) -> Result<u8, RecordError> {
        self.0.u8("a byte").map_err(|e| self.err(e))
    }
    fn u16(&mut self) -> Result<u16, RecordError> {
        self.0.u16("a u16").map_err(|e| self.err(e))
    }
    fn u32(&mut self) -> Result<u32, RecordError> {
        self.0.u32("a u32").map_err(|e| self.err(e))
    }
    fn u64(&mut self) -> Result<u64, RecordError> {
        self.0.u64("a u64").map_err(|e| self.err(e))
    }
    /// A device reading: u8 has-reading (0 or 1), then if 1 the reading.
    fn reading(&mut self) -> Result<Option<DeviceReading>, RecordError> {
        let k = self.u8()?;
        self.reading_after(k)
    }
    /// The rest of a device reading after its has-reading flag `k` (0: none; 1: the reading follows).
    fn reading_after(&mut self, k: u8) -> Result<Option<DeviceReading>, RecordError> {
        match k {
            0 => Ok(None),
            1 => {
                let time = self.f64()?;
                let position = Vector3::new(self.f64()?, self.f64()?, self.f64()?);
                let mut m = [0.0; 9];
                for x in &mut m {
                    *x = self.f64()?;
                }
                let buttons = self.u32()?;
                Ok(Some(DeviceReading { time, position, rotation: Matrix3::from_column_slice(&m), buttons }))
            }
            k => Err(RecordError::Bad { offset: self.at() - 1, what: format!("reading flag {k} (0, 1 or 2)") }),
        }
    }
    fn f64(&mut self) -> Result<f64, RecordError> {
        self.0.f64("an f64").map_err(|e| self.err(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(v: u64, commands: Vec<Command>) -> StepRecord {
        StepRecord { reading: None, more_readings: Vec::new(), lattice_version: v, commands, force: Vector3::new(1.0, 2.0, v as f64), carried: 0 }
    }

    #[test]
    fn a_record_round_trips_and_every_cut_reads_to_its_last_whole_chunk() {
        // 2,500 haptic steps (three chunks), global steps with a reset and a moved head: written and read back
        // exactly; cut anywhere: refused inside the magic and header (naming the offset), else read up to the
        // last whole chunk before the cut, whose end is where the reader says it stopped.
        let mut r = Record::new(1000.0);
        r.settings = Some(RecordSettings { render_strands: 5000, input: "device".into(), ..RecordSettings::default() });
        for i in 0..260u64 {
            r.global_inputs.push(ToolInput { tool: Tool::Scissors, present: true, pressed: i % 2 == 0, cuts: i / 10, ..ToolInput::default() });
        }
        r.global_inputs[7].head = nalgebra::Isometry3::new(Vector3::new(0.01, 0.0, 0.02), Vector3::new(0.0, 0.1, 0.5));
        r.global_resets = vec![5, 120];
        for i in 0..2500u64 {
            let c = if i == 33 { vec![Command::Reset, Command::SetHead { position: Vector3::new(0.01, 0.0, 0.02), rotation: Vector3::new(0.0, 0.1, 0.5) }] } else { vec![] };
            r.steps.push(step(i / 10, c));
        }
        let b = r.to_bytes();
        let whole = Record::read(&b).unwrap();
        assert_eq!(whole.ending, Ending::Complete);
        assert_eq!(whole.record, r);
        // The chunk ends, found by walking the lengths (not through the reader).
        let mut ends = vec![];
        let mut at = 8;
        while at < b.len() {
            at += 8 + u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
            ends.push(at);
        }
        assert_eq!(ends.len(), 6, "header, three steps chunks, one of the global steps no haptic step read, end");
        // Every byte near a chunk's end (and in the magic and header), and every 37th byte elsewhere.
        let cuts = (0..b.len()).filter(|&n| n % 37 == 0 || n < ends[0] || ends.iter().any(|&e| n.abs_diff(e) <= 12));
        for n in cuts {
            match Record::read(&b[..n]) {
                Err(RecordError::Bad { offset, what }) => assert!(n < ends[0] && offset <= n, "{n}: refused at {offset}: {what}"),
                Ok(got) => {
                    let last = *ends.iter().filter(|&&e| e <= n).last().unwrap();
                    let Ending::Cut(c) = &got.ending else { panic!("{n}: {:?}", got.ending) };
                    assert_eq!(c.offset, last, "{n}: {}", c.why);
                    assert!([0, 1000, 2000, 2500].contains(&got.record.steps.len()) && r.steps.starts_with(&got.record.steps), "{n}");
                    assert!(r.global_inputs.starts_with(&got.record.global_inputs));
                    assert!(got.record.steps.iter().all(|s| s.lattice_version <= got.record.global_inputs.len() as u64));
                    assert!(Record::from_bytes(&b[..n]).is_err());
                }
            }
        }
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(matches!(Record::from_bytes(&bad), Err(RecordError::Bad { offset: 0, .. })));
        // A flipped byte in a steps chunk: read up to the chunk before it, which fails its checksum.
        let mut bad = b.clone();
        bad[ends[1] + 100] ^= 1;
        let got = Record::read(&bad).unwrap();
        assert_eq!(got.record.steps.len(), 1000);
        assert!(matches!(&got.ending, Ending::Cut(c) if c.offset == ends[1] && c.why.contains("checksum")), "{:?}", got.ending);
    }

    #[test]
    fn older_versions_are_refused_naming_their_version() {
        for v in [1, 2, 3] {
            let mut b = format!("CFREC{v}\0\0").into_bytes();
            b.extend_from_slice(&1000.0f64.to_le_bytes());
            let e = Record::read(&b).unwrap_err().to_string();
            assert!(e.contains(&format!("version-{v}")) && e.contains(&format!("CFREC{v}")) && e.contains("at byte 0"), "{e}");
        }
    }

    #[test]
    fn a_record_that_stopped_early_says_why() {
        let mut b = Vec::new();
        put_header(&mut b, 1000.0, None);
        let mut c = StepsChunk::default();
        c.push_step(&step(0, vec![]));
        c.finish(&mut b);
        put_end(&mut b, 0, 1, Some("the queue was full"));
        let got = Record::read(&b).unwrap();
        assert_eq!(got.ending, Ending::Stopped("the queue was full".into()));
        assert_eq!(got.record.steps.len(), 1);
        // A steps chunk reading a lattice version no global step produced yet is not replayable: refused there.
        let mut b = Vec::new();
        put_header(&mut b, 1000.0, None);
        let at = b.len();
        let mut c = StepsChunk::default();
        c.push_step(&step(3, vec![]));
        c.finish(&mut b);
        let got = Record::read(&b).unwrap();
        assert!(matches!(&got.ending, Ending::Cut(c) if c.offset == at && c.why.contains("lattice version 3")), "{:?}", got.ending);
    }
}
