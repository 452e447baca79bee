//! The chunks of a record file (format in the module above): each carries its length and a CRC-32 of its
//! payload, so that each can be checked on its own and a file cut at any byte is read up to its last whole one.

/// The magic of the record format written and read (version 3).
pub const MAGIC: &[u8; 8] = b"CFREC4\0\0";
/// Bytes before a chunk's payload: u32 length, u32 CRC-32.
pub const CHUNK_HEADER_BYTES: usize = 8;
/// Largest chunk payload, bytes (a longer announced length is damage, not a chunk).
pub const MAX_PAYLOAD: usize = 64 << 20;

/// Chunk kinds (the payload's first byte).
pub mod kind {
    /// The header: the haptic rate.
    pub const HEADER: u8 = 0;
    /// Global and haptic steps.
    pub const STEPS: u8 = 1;
    /// The end: totals and whether recording stopped early.
    pub const END: u8 = 2;
}

/// Appends one chunk with `payload` (its first byte the kind) to `out`.
pub fn put(out: &mut Vec<u8>, payload: &[u8]) {
    debug_assert!(!payload.is_empty() && payload.len() <= MAX_PAYLOAD);
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out.extend_from_slice(payload);
}

/// The next whole chunk of `bytes` at `at`: Ok(Some((payload, offset after it))), Ok(None) at the end of the
/// bytes, or Err(why) if the bytes there are not a whole, intact chunk.
pub fn next(bytes: &[u8], at: usize) -> Result<Option<(&[u8], usize)>, String> {
    let rest = &bytes[at.min(bytes.len())..];
    if rest.is_empty() {
        return Ok(None);
    }
    if rest.len() < CHUNK_HEADER_BYTES {
        return Err(format!("cut inside a chunk header ({} of its {CHUNK_HEADER_BYTES} bytes)", rest.len()));
    }
    let len = u32::from_le_bytes(rest[0..4].try_into().expect("4 bytes")) as usize;
    let crc = u32::from_le_bytes(rest[4..8].try_into().expect("4 bytes"));
    if len == 0 || len > MAX_PAYLOAD {
        return Err(format!("a chunk length of {len} bytes (1 to {MAX_PAYLOAD}): damaged"));
    }
    let have = rest.len() - CHUNK_HEADER_BYTES;
    if have < len {
        return Err(format!("cut inside a chunk ({have} of its {len} bytes)"));
    }
    let payload = &rest[CHUNK_HEADER_BYTES..CHUNK_HEADER_BYTES + len];
    let got = crc32fast::hash(payload);
    if got != crc {
        return Err(format!("a chunk of {len} bytes whose checksum is {got:08x}, not {crc:08x} as written: damaged"));
    }
    Ok(Some((payload, at + CHUNK_HEADER_BYTES + len)))
}
