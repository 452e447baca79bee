//! Cem Yuksel's `.hair` format (little-endian).
//!
//! Layout: a 128-byte header — `"HAIR"`, u32 number of strands, u32 total number of points,
//! u32 bit flags of the arrays present (bit 0 segments, bit 1 points, bit 2 thickness, bit 3
//! transparency, bit 4 colour), u32 default number of segments, f32 default thickness, f32
//! default transparency, 3 x f32 default colour, 88 bytes of information text — then the arrays
//! present, in that order: segments (u16 per strand, points = segments + 1), points (3 x f32 per
//! point), thickness (f32 per point), transparency (f32 per point), colour (3 x f32 per point).
//!
//! Reading: the points array is required (a file without positions cannot be loaded); without a
//! segments array every strand has the default number of segments. An absent thickness,
//! transparency or colour array gives `None` in [`HairCurves`]; the header defaults are then
//! available from [`read_header`]. Unknown flag bits (5 to 31) and bytes after the last array are
//! errors.
//!
//! Writing: always a segments and a points array, plus each attribute present. Header defaults
//! written: 0 segments, thickness 1.0, transparency 0.0, colour (1, 1, 1) (the defaults of Cem
//! Yuksel's reference code); information text `"Coiffure"` padded with zero bytes.

use super::{put_f32, put_u32, Cursor, FormatError, HairCurves};

const FORMAT: &str = ".hair";
/// Size of the header in bytes.
pub const HEADER_SIZE: usize = 128;
/// Flag bit: segments array present.
pub const HAS_SEGMENTS: u32 = 1 << 0;
/// Flag bit: points array present.
pub const HAS_POINTS: u32 = 1 << 1;
/// Flag bit: thickness array present.
pub const HAS_THICKNESS: u32 = 1 << 2;
/// Flag bit: transparency array present.
pub const HAS_TRANSPARENCY: u32 = 1 << 3;
/// Flag bit: colour array present.
pub const HAS_COLOR: u32 = 1 << 4;
/// Information text written by [`write()`] (then zero bytes up to 88).
pub const INFO_TEXT: &[u8] = b"Coiffure";

/// The 128-byte header of a `.hair` file.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Number of strands.
    pub num_strands: u32,
    /// Total number of points (vertices) over all strands.
    pub num_points: u32,
    /// Bit flags of the arrays present (see the `HAS_*` constants).
    pub flags: u32,
    /// Number of segments of each strand when there is no segments array.
    pub default_segments: u32,
    /// Thickness (file units) of every point when there is no thickness array.
    pub default_thickness: f32,
    /// Transparency of every point when there is no transparency array.
    pub default_transparency: f32,
    /// Colour (RGB) of every point when there is no colour array.
    pub default_color: [f32; 3],
    /// The 88 bytes of free information text.
    pub info: [u8; 88],
}

/// Parse and check the header only (signature, flags, and that the arrays it announces fit in
/// the file).
pub fn read_header(bytes: &[u8]) -> Result<Header, FormatError> {
    header(&mut Cursor::new(bytes, FORMAT))
}

fn header(c: &mut Cursor) -> Result<Header, FormatError> {
    if c.take(4, "signature \"HAIR\"")? != b"HAIR" {
        return Err(c.error(0, "signature \"HAIR\""));
    }
    let num_strands = c.u32("number of strands (u32)")?;
    let num_points = c.u32("total number of points (u32)")?;
    let flags = c.u32("array flags (u32)")?;
    if flags & !0x1f != 0 {
        return Err(c.error(
            12,
            format!("array flags using bits 0 to 4 only, found {flags:#x}"),
        ));
    }
    if flags & HAS_POINTS == 0 {
        return Err(c.error(
            12,
            "array flags with bit 1 (points array) set; found it clear",
        ));
    }
    let default_segments = c.u32("default number of segments (u32)")?;
    let default_thickness = c.f32("default thickness (f32)")?;
    let default_transparency = c.f32("default transparency (f32)")?;
    let default_color = c.vec3("default colour (3 x f32)")?;
    let info = c.take(88, "information text")?.try_into().unwrap();
    // Size of the arrays announced, against the file, before anything is allocated.
    let (s, p) = (num_strands as u64, num_points as u64);
    let per_point = [
        (HAS_POINTS, 12),
        (HAS_THICKNESS, 4),
        (HAS_TRANSPARENCY, 4),
        (HAS_COLOR, 12),
    ]
    .iter()
    .filter(|(bit, _)| flags & bit != 0)
    .map(|(_, size)| size)
    .sum::<u64>();
    let seg_bytes = if flags & HAS_SEGMENTS != 0 { 2 * s } else { 0 };
    let total = seg_bytes + per_point * p; // < 2^40, no overflow
    if total > c.remaining() as u64 {
        let msg = format!(
            "{num_strands} strands and {num_points} points needing {total} bytes of arrays after \
             the header, but the file has {} bytes after it",
            c.remaining()
        );
        return Err(c.error(4, msg));
    }
    Ok(Header {
        num_strands,
        num_points,
        flags,
        default_segments,
        default_thickness,
        default_transparency,
        default_color,
        info,
    })
}

/// Parse a whole `.hair` file.
pub fn read(bytes: &[u8]) -> Result<HairCurves, FormatError> {
    let mut c = Cursor::new(bytes, FORMAT);
    let h = header(&mut c)?;
    let (ns, np) = (h.num_strands as usize, h.num_points as usize);
    // Points per strand, checked against the total before allocating.
    let counts: Vec<usize> = if h.flags & HAS_SEGMENTS != 0 {
        let counts = (0..ns)
            .map(|_| c.u16("segment count (u16)").map(|s| s as usize + 1))
            .collect::<Result<Vec<_>, _>>()?;
        let sum: u64 = counts.iter().map(|&n| n as u64).sum();
        if sum != np as u64 {
            let msg = format!("segments adding up to {np} points (header), found {sum}");
            return Err(c.error(HEADER_SIZE, msg));
        }
        counts
    } else {
        let per = h.default_segments as u64 + 1;
        if ns as u64 * per != np as u64 {
            let msg = format!(
                "default segments ({}) x {ns} strands matching {np} points (no segments array)",
                h.default_segments
            );
            return Err(c.error(16, msg));
        }
        vec![per as usize; ns]
    };
    let mut strands = Vec::with_capacity(ns);
    for &n in &counts {
        let s = (0..n)
            .map(|_| c.vec3("point (3 x f32)"))
            .collect::<Result<Vec<_>, _>>()?;
        strands.push(s);
    }
    let mut scalars = |bit: u32, what: &str| -> Result<Option<Vec<f32>>, FormatError> {
        if h.flags & bit == 0 {
            return Ok(None);
        }
        (0..np)
            .map(|_| c.f32(what))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    };
    let thickness = scalars(HAS_THICKNESS, "thickness (f32)")?;
    let transparency = scalars(HAS_TRANSPARENCY, "transparency (f32)")?;
    let color = if h.flags & HAS_COLOR != 0 {
        Some(
            (0..np)
                .map(|_| c.vec3("colour (3 x f32)"))
                .collect::<Result<Vec<_>, _>>()?,
        )
    } else {
        None
    };
    c.finish()?;
    Ok(HairCurves {
        strands,
        thickness,
        transparency,
        color,
    })
}

/// Serialise curves as a `.hair` file. Errors if a strand has no point or more than 65536 points,
/// if there are more than 2^32 - 1 points, or if an attribute does not have one value per point.
pub fn write(curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
    curves.check_attributes(FORMAT)?;
    let unwritable = |reason: String| FormatError::Unwritable {
        format: FORMAT,
        reason,
    };
    for (i, s) in curves.strands.iter().enumerate() {
        if s.is_empty() || s.len() > 65536 {
            return Err(unwritable(format!(
                "strand {i} has {} points (1 to 65536 allowed)",
                s.len()
            )));
        }
    }
    let ns =
        u32::try_from(curves.strands.len()).map_err(|_| unwritable("too many strands".into()))?;
    let np =
        u32::try_from(curves.num_points()).map_err(|_| unwritable("too many points".into()))?;
    let mut flags = HAS_SEGMENTS | HAS_POINTS;
    flags |= if curves.thickness.is_some() {
        HAS_THICKNESS
    } else {
        0
    };
    flags |= if curves.transparency.is_some() {
        HAS_TRANSPARENCY
    } else {
        0
    };
    flags |= if curves.color.is_some() { HAS_COLOR } else { 0 };

    let mut out = Vec::with_capacity(HEADER_SIZE + 2 * ns as usize + 32 * np as usize);
    out.extend_from_slice(b"HAIR");
    for v in [ns, np, flags, 0] {
        put_u32(&mut out, v);
    }
    for v in [1.0, 0.0, 1.0, 1.0, 1.0] {
        put_f32(&mut out, v);
    }
    let mut info = [0u8; 88];
    info[..INFO_TEXT.len()].copy_from_slice(INFO_TEXT);
    out.extend_from_slice(&info);
    debug_assert_eq!(out.len(), HEADER_SIZE);
    for s in &curves.strands {
        out.extend_from_slice(&((s.len() - 1) as u16).to_le_bytes());
    }
    for p in curves.strands.iter().flatten() {
        p.iter().for_each(|&x| put_f32(&mut out, x));
    }
    for v in curves
        .thickness
        .iter()
        .chain(&curves.transparency)
        .flatten()
    {
        put_f32(&mut out, *v);
    }
    for c in curves.color.iter().flatten() {
        c.iter().for_each(|&x| put_f32(&mut out, x));
    }
    Ok(out)
}
