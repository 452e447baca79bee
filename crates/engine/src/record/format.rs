//! The record file format (little-endian; see the module above).

use super::{Record, RecordError, StepRecord};
use crate::command::Command;
use crate::tool::{Tool, ToolInput};
use haptics::device::DeviceReading;
use hairstyle::formats::bytes::Cursor;
use nalgebra::{Matrix3, Vector3};

const MAGIC: &[u8; 8] = b"CFREC2\0\0";
const MAGIC_V1: &[u8; 8] = b"CFREC1\0\0";
/// Smallest global input: tool, flags, 3 + 9 f64, u64 cuts (bytes).
const MIN_GLOBAL_INPUT_BYTES: usize = 2 + 12 * 8 + 8;
/// Smallest haptic step: no reading, u64 version, 3 f64 force, no commands (bytes).
const MIN_STEP_BYTES: usize = 1 + 8 + 24 + 1;

impl Record {
    /// Serialises the record.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(64 + self.steps.len() * 130);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&self.rate_hz.to_le_bytes());
        b.extend_from_slice(&(self.global_resets.len() as u64).to_le_bytes());
        for v in &self.global_resets {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let f = |b: &mut Vec<u8>, x: f64| b.extend_from_slice(&x.to_le_bytes());
        b.extend_from_slice(&(self.global_inputs.len() as u64).to_le_bytes());
        for g in &self.global_inputs {
            b.push(g.tool as u8);
            let moved = g.head != nalgebra::Isometry3::identity();
            b.push(g.present as u8 | (g.pressed as u8) << 1 | (moved as u8) << 2);
            g.position.iter().for_each(|&x| f(&mut b, x));
            g.rotation.iter().for_each(|&x| f(&mut b, x));
            b.extend_from_slice(&g.cuts.to_le_bytes());
            if moved {
                // flag bit 2: the head pose follows (translation x y z, unit quaternion i j k w)
                g.head.translation.vector.iter().for_each(|&x| f(&mut b, x));
                g.head.rotation.coords.iter().for_each(|&x| f(&mut b, x));
            }
        }
        b.extend_from_slice(&(self.steps.len() as u64).to_le_bytes());
        for s in &self.steps {
            let reading = |b: &mut Vec<u8>, r: &Option<DeviceReading>| match r {
                None => b.push(0),
                Some(r) => {
                    b.push(1);
                    f(b, r.time);
                    r.position.iter().for_each(|&x| f(b, x));
                    r.rotation.iter().for_each(|&x| f(b, x));
                    b.extend_from_slice(&r.buttons.to_le_bytes());
                }
            };
            if s.more_readings.is_empty() {
                reading(&mut b, &s.reading);
            } else {
                // Several device steps: flag 2, their count, each reading.
                b.push(2);
                b.push((1 + s.more_readings.len()).min(255) as u8);
                for r in std::iter::once(&s.reading).chain(&s.more_readings).take(255) {
                    reading(&mut b, r);
                }
            }
            b.extend_from_slice(&s.lattice_version.to_le_bytes());
            s.force.iter().for_each(|&x| f(&mut b, x));
            b.push(s.commands.len().min(255) as u8);
            for c in s.commands.iter().take(255) {
                match *c {
                    Command::SelectTool(t) => b.extend_from_slice(&[0, t as u8]),
                    Command::SetHair { hair_type, curliness, combing_ease } => {
                        b.extend_from_slice(&[1, hair_type]);
                        f(&mut b, curliness);
                        f(&mut b, combing_ease);
                    }
                    Command::Reset => b.push(2),
                    Command::SetHead { position, rotation } => {
                        b.push(3);
                        position.iter().chain(rotation.iter()).for_each(|&x| f(&mut b, x));
                    }
                    Command::LimitStrands(n) => {
                        b.push(4);
                        b.extend_from_slice(&n.to_le_bytes());
                    }
                    Command::SetTreatment(t) => b.extend_from_slice(&[5, t.id()]),
                }
            }
        }
        b
    }

    /// Parses a record; errors name the byte offset.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, RecordError> {
        let mut r = Reader(Cursor::new(bytes, "session record"));
        let magic = r.take(8)?;
        let v2 = magic == MAGIC;
        if !v2 && magic != MAGIC_V1 {
            return Err(RecordError::Bad { offset: 0, what: "not a Coiffure session record (magic CFREC2 or CFREC1)".into() });
        }
        let rate_hz = r.f64()?;
        if !(rate_hz > 0.0 && rate_hz.is_finite()) {
            return Err(RecordError::Bad { offset: 8, what: format!("haptic rate {rate_hz} Hz must be > 0") });
        }
        let n = r.u64()? as usize;
        // Capacities are bounded by what the rest of the file can hold (a damaged count must not allocate).
        let mut global_resets = Vec::with_capacity(n.min(r.0.remaining() / 8));
        for _ in 0..n {
            global_resets.push(r.u64()?);
        }
        let mut global_inputs = Vec::new();
        if v2 {
            let n = r.u64()? as usize;
            global_inputs.reserve(n.min(r.0.remaining() / MIN_GLOBAL_INPUT_BYTES));
            for _ in 0..n {
                let at = r.at();
                let id = r.u8()?;
                let tool = Tool::from_id(id).ok_or(RecordError::Bad { offset: at, what: format!("tool id {id}") })?;
                let flags = r.u8()?;
                if flags > 7 {
                    return Err(RecordError::Bad { offset: at + 1, what: format!("tool flags {flags} (0-7)") });
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
                global_inputs.push(ToolInput { tool, present: flags & 1 != 0, pressed: flags & 2 != 0, position, rotation: Matrix3::from_column_slice(&m), cuts, head });
            }
        }
        let n = r.u64()? as usize;
        let mut steps = Vec::with_capacity(n.min(r.0.remaining() / MIN_STEP_BYTES));
        for _ in 0..n {
            let (reading, more_readings) = match r.u8()? {
                2 => {
                    let at = r.at();
                    let n = r.u8()?;
                    if n < 2 {
                        return Err(RecordError::Bad { offset: at, what: format!("{n} device steps after flag 2 (at least 2)") });
                    }
                    let first = r.reading()?;
                    let more = (1..n).map(|_| r.reading()).collect::<Result<Vec<_>, _>>()?;
                    (first, more)
                }
                k => (r.reading_after(k)?, Vec::new()),
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
            steps.push(StepRecord { reading, more_readings, lattice_version, commands, force });
        }
        if r.at() != bytes.len() {
            return Err(RecordError::Bad { offset: r.at(), what: format!("{} trailing bytes", bytes.len() - r.at()) });
        }
        Ok(Record { rate_hz, global_resets, global_inputs, steps })
    }
}

/// The hair formats' little-endian reader (one byte reader in the project), its errors as record errors.
struct Reader<'a>(Cursor<'a>);

impl<'a> Reader<'a> {
    fn err(e: hairstyle::formats::FormatError) -> RecordError {
        match e {
            hairstyle::formats::FormatError::Binary { offset, expected, .. } => RecordError::Bad { offset: offset as usize, what: format!("truncated: {expected}") },
            e => RecordError::Bad { offset: 0, what: e.to_string() },
        }
    }
    fn at(&self) -> usize {
        self.0.pos()
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], RecordError> {
        self.0.take(n, "bytes").map_err(Self::err)
    }
    fn u8(&mut self) -> Result<u8, RecordError> {
        self.0.u8("a byte").map_err(Self::err)
    }
    fn u32(&mut self) -> Result<u32, RecordError> {
        self.0.u32("a u32").map_err(Self::err)
    }
    fn u64(&mut self) -> Result<u64, RecordError> {
        self.0.u64("a u64").map_err(Self::err)
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
        self.0.f64("an f64").map_err(Self::err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damaged_records_are_refused_with_the_offset() {
        let mut r = Record::new(1000.0);
        r.steps.push(crate::record::StepRecord { reading: None, more_readings: Vec::new(), lattice_version: 3, commands: vec![Command::Reset], force: Vector3::new(1.0, 2.0, 3.0) });
        let b = r.to_bytes();
        assert_eq!(Record::from_bytes(&b).unwrap(), r);
        for n in 0..b.len() {
            assert!(Record::from_bytes(&b[..n]).is_err(), "prefix of {n} bytes");
        }
        // A version-1 file (no global inputs: magic CFREC1 and no count after the resets) still loads.
        let mut v1 = b"CFREC1\0\0".to_vec();
        v1.extend_from_slice(&b[8..24 + 8 * r.global_resets.len()]);
        v1.extend_from_slice(&b[32 + 8 * r.global_resets.len()..]);
        assert_eq!(Record::from_bytes(&v1).unwrap(), r);
        r.global_inputs.push(ToolInput { tool: Tool::Scissors, present: true, pressed: true, cuts: 3, ..ToolInput::default() });
        // A moved head (flag bit 2 and the pose) and a head command round-trip exactly.
        r.global_inputs.push(ToolInput { head: nalgebra::Isometry3::new(Vector3::new(0.01, 0.0, 0.02), Vector3::new(0.0, 0.1, 0.5)), ..ToolInput::default() });
        r.steps.push(crate::record::StepRecord { reading: None, more_readings: Vec::new(), lattice_version: 4, commands: vec![Command::SetHead { position: Vector3::new(0.01, 0.0, 0.02), rotation: Vector3::new(0.0, 0.1, 0.5) }], force: Vector3::zeros() });
        let b = r.to_bytes();
        assert_eq!(Record::from_bytes(&b).unwrap(), r);
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(matches!(Record::from_bytes(&bad), Err(crate::record::RecordError::Bad { offset: 0, .. })));
    }
}
