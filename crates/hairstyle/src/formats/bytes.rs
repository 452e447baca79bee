//! Little-endian byte reading (with offset-naming errors) and writing for the binary formats: the
//! hair files here and the engine's session records (`engine::record`).

use super::FormatError;

/// A little-endian reader over a byte slice that reports errors by byte offset.
pub struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: &'static str,
}

impl<'a> Cursor<'a> {
    /// A reader at the start of `bytes`, naming `format` (e.g. ".hair") in its errors.
    pub fn new(bytes: &'a [u8], format: &'static str) -> Self {
        Self {
            bytes,
            pos: 0,
            format,
        }
    }

    /// Current byte offset.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left after the current offset.
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Move to an absolute offset (checked by the next read).
    pub fn seek(&mut self, pos: usize) {
        self.pos = pos;
    }

    /// An error at byte `offset`.
    pub fn error(&self, offset: usize, expected: impl Into<String>) -> FormatError {
        FormatError::Binary {
            format: self.format,
            offset: offset as u64,
            expected: expected.into(),
        }
    }

    /// Check that `count` items of `size` bytes fit in the rest of the file, before allocating.
    pub fn need(&self, count: u64, size: u64, what: &str) -> Result<(), FormatError> {
        let left = self.remaining() as u64;
        match count.checked_mul(size) {
            Some(n) if n <= left => Ok(()),
            _ => Err(self.error(
                self.pos,
                format!(
                    "{what}: {count} x {size} bytes, but only {left} bytes are left in the file"
                ),
            )),
        }
    }

    /// Take `n` bytes.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], FormatError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(self.error(
                self.pos,
                format!(
                    "{what} ({n} bytes), but the file ends at byte {}",
                    self.bytes.len()
                ),
            )),
        }
    }

    /// Reads a u8 (`what` names it in the error).
    pub fn u8(&mut self, what: &str) -> Result<u8, FormatError> {
        Ok(self.take(1, what)?[0])
    }

    /// Reads a little-endian u64.
    pub fn u64(&mut self, what: &str) -> Result<u64, FormatError> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }

    /// Reads a little-endian f64.
    pub fn f64(&mut self, what: &str) -> Result<f64, FormatError> {
        Ok(f64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }

    /// Reads a little-endian u16.
    pub fn u16(&mut self, what: &str) -> Result<u16, FormatError> {
        Ok(u16::from_le_bytes(self.take(2, what)?.try_into().unwrap()))
    }

    /// Reads a little-endian u32.
    pub fn u32(&mut self, what: &str) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }

    /// Reads a little-endian i32.
    pub fn i32(&mut self, what: &str) -> Result<i32, FormatError> {
        Ok(i32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }

    /// Reads a little-endian f32.
    pub fn f32(&mut self, what: &str) -> Result<f32, FormatError> {
        Ok(f32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }

    /// Reads three little-endian f32.
    pub fn vec3(&mut self, what: &str) -> Result<[f32; 3], FormatError> {
        Ok([self.f32(what)?, self.f32(what)?, self.f32(what)?])
    }

    /// Error unless the whole file has been read.
    pub fn finish(&self) -> Result<(), FormatError> {
        if self.pos == self.bytes.len() {
            Ok(())
        } else {
            let extra = self.bytes.len() - self.pos;
            Err(self.error(self.pos, format!("end of file, found {extra} more bytes")))
        }
    }
}

/// Little-endian pushes for the writers.
pub(crate) fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_le_bytes());
}
