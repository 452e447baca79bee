//! AMD TressFX 4 `.tfx` format (little-endian).
//!
//! Layout: a 160-byte header — f32 version, u32 number of strands, u32 vertices per strand (4 to
//! 64, the same for every strand), u32 byte offsets from the file start of: vertex positions
//! (4 x f32 per vertex), strand UVs (2 x f32 per strand), vertex UVs (2 x f32 per vertex), strand
//! thickness (f32 per strand) and vertex colours (4 x f32 RGBA per vertex), 0 meaning absent
//! (positions are required), then 32 reserved u32 — and the arrays where the offsets say.
//!
//! Reading: the version is read but not checked; positions are x, y, z (the 4th component, w,
//! is ignored); strand thickness becomes the same thickness on every vertex of the strand;
//! colours keep RGB (alpha is ignored); UV arrays are checked to lie inside the file but not
//! kept; reserved words are ignored. Bytes outside the arrays are not checked.
//!
//! Writing: version 4.0, positions at byte 160 with w = 0.0 for the root (first) vertex of each
//! strand, which TressFX treats as fixed (inverse mass 0), and w = 1.0 for every other (movable)
//! vertex; then the strand thickness if present (the root vertex's thickness is used for the
//! whole strand); then, at the next multiple of 8 bytes, colours if present (alpha 1.0). No UVs,
//! reserved words 0. Every strand must have the same number of vertices, 4 to 64: otherwise
//! [`write()`] returns [`FormatError::Unwritable`]; resampling happens only if the caller asks,
//! through [`resample`]. An empty set of curves is written with 4 vertices per strand.

use super::{put_f32, put_u32, Cursor, FormatError, HairCurves};

const FORMAT: &str = ".tfx";
/// Size of the header in bytes: 4 + 4 + 4 + 5 x 4 + 32 x 4.
pub const HEADER_SIZE: usize = 4 + 4 + 4 + 5 * 4 + 32 * 4;
const _: () = assert!(HEADER_SIZE == 160);
/// Version number written by [`write()`].
pub const VERSION: f32 = 4.0;
/// Allowed numbers of vertices per strand.
pub const VERTICES_PER_STRAND: std::ops::RangeInclusive<u32> = 4..=64;

/// Parse a whole `.tfx` file.
pub fn read(bytes: &[u8]) -> Result<HairCurves, FormatError> {
    let mut c = Cursor::new(bytes, FORMAT);
    let _version = c.f32("version (f32)")?;
    let ns = c.u32("number of strands (u32)")? as u64;
    let nv = c.u32("vertices per strand (u32)")?;
    if !VERTICES_PER_STRAND.contains(&nv) {
        return Err(c.error(8, format!("4 to 64 vertices per strand, found {nv}")));
    }
    let nv = nv as u64;
    let names = [
        "vertex positions",
        "strand UVs",
        "vertex UVs",
        "strand thickness",
        "vertex colours",
    ];
    let sizes = [16 * nv * ns, 8 * ns, 8 * nv * ns, 4 * ns, 16 * nv * ns];
    let mut offsets = [0usize; 5];
    for k in 0..5 {
        let at = c.pos();
        let off = c.u32(&format!("offset of the {} (u32)", names[k]))? as u64;
        let what = || format!("offset of the {} ({} bytes)", names[k], sizes[k]);
        if off == 0 && k == 0 {
            return Err(c.error(
                at,
                format!("a non-zero {}: vertex positions are required", what()),
            ));
        }
        if off != 0 && (off < HEADER_SIZE as u64 || off + sizes[k] > bytes.len() as u64) {
            let msg = format!(
                "{} from {off} inside the {}-byte file, after the header",
                what(),
                bytes.len()
            );
            return Err(c.error(at, msg));
        }
        offsets[k] = off as usize;
    }
    c.take(32 * 4, "32 reserved u32")?;
    // Sizes are now known to fit in the file: allocation is bounded by its length.
    let (ns, nv) = (ns as usize, nv as usize);
    c.seek(offsets[0]);
    let mut strands = Vec::with_capacity(ns);
    for _ in 0..ns {
        let mut s = Vec::with_capacity(nv);
        for _ in 0..nv {
            s.push(c.vec3("vertex position x, y, z (3 x f32)")?);
            c.f32("vertex position w (f32)")?;
        }
        strands.push(s);
    }
    let thickness = if offsets[3] != 0 {
        c.seek(offsets[3]);
        let per_strand = (0..ns)
            .map(|_| c.f32("strand thickness (f32)"))
            .collect::<Result<Vec<_>, _>>()?;
        Some(per_strand.iter().flat_map(|&t| vec![t; nv]).collect())
    } else {
        None
    };
    let color = if offsets[4] != 0 {
        c.seek(offsets[4]);
        let mut color = Vec::with_capacity(ns * nv);
        for _ in 0..ns * nv {
            color.push(c.vec3("vertex colour RGB (3 x f32)")?);
            c.f32("vertex colour alpha (f32)")?;
        }
        Some(color)
    } else {
        None
    };
    Ok(HairCurves {
        strands,
        thickness,
        transparency: None,
        color,
    })
}

/// Serialise curves as a `.tfx` file (see the module documentation for what is written).
/// Errors if the strands do not all have the same number of vertices, from 4 to 64, or if an
/// attribute does not have one value per vertex.
pub fn write(curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
    curves.check_attributes(FORMAT)?;
    let unwritable = |reason: String| FormatError::Unwritable {
        format: FORMAT,
        reason,
    };
    let nv = curves.strands.first().map_or(4, Vec::len);
    if let Some((i, s)) = curves
        .strands
        .iter()
        .enumerate()
        .find(|(_, s)| s.len() != nv)
    {
        return Err(unwritable(format!(
            "every strand must have the same number of vertices, but strand 0 has {nv} and strand \
             {i} has {} (use tfx::resample to resample them)",
            s.len()
        )));
    }
    if !VERTICES_PER_STRAND.contains(&(nv as u32)) {
        return Err(unwritable(format!(
            "{nv} vertices per strand (4 to 64 allowed; see tfx::resample)"
        )));
    }
    let ns = curves.strands.len();
    let too_big = || {
        unwritable(format!(
            "{ns} strands do not fit in a file with 32-bit offsets"
        ))
    };
    let pos_end = (HEADER_SIZE as u64)
        .checked_add(16 * (ns * nv) as u64)
        .ok_or_else(too_big)?;
    let thick_at = if curves.thickness.is_some() {
        pos_end
    } else {
        0
    };
    let after = if curves.thickness.is_some() {
        pos_end + 4 * ns as u64
    } else {
        pos_end
    };
    let color_at = if curves.color.is_some() {
        after.next_multiple_of(8)
    } else {
        0
    };
    let end = if curves.color.is_some() {
        color_at + 16 * (ns * nv) as u64
    } else {
        after
    };
    if end > u32::MAX as u64 {
        return Err(too_big());
    }

    let mut out = Vec::with_capacity(end as usize);
    put_f32(&mut out, VERSION);
    for v in [
        ns as u32,
        nv as u32,
        HEADER_SIZE as u32,
        0,
        0,
        thick_at as u32,
        color_at as u32,
    ] {
        put_u32(&mut out, v);
    }
    out.resize(HEADER_SIZE, 0);
    for s in &curves.strands {
        for (j, p) in s.iter().enumerate() {
            p.iter().for_each(|&x| put_f32(&mut out, x));
            put_f32(&mut out, if j == 0 { 0.0 } else { 1.0 });
        }
    }
    if let Some(t) = &curves.thickness {
        (0..ns).for_each(|i| put_f32(&mut out, t[i * nv]));
    }
    if let Some(colors) = &curves.color {
        out.resize(color_at as usize, 0);
        for c in colors {
            c.iter().for_each(|&x| put_f32(&mut out, x));
            put_f32(&mut out, 1.0);
        }
    }
    debug_assert_eq!(out.len() as u64, end);
    Ok(out)
}

/// Resample every strand to `n` vertices evenly spaced along its length (arc length), keeping
/// both ends; per-vertex attributes are interpolated linearly at the same places. A strand of
/// one vertex, or of zero length, becomes `n` copies of its root. Errors if `n < 2` or a strand
/// is empty. Use it before [`write()`] for strands of unequal or out-of-range vertex counts.
pub fn resample(curves: &HairCurves, n: usize) -> Result<HairCurves, FormatError> {
    curves.check_attributes(FORMAT)?;
    let unwritable = |reason: String| FormatError::Unwritable {
        format: FORMAT,
        reason,
    };
    if n < 2 {
        return Err(unwritable(format!(
            "cannot resample to {n} vertices (at least 2)"
        )));
    }
    let mut out = HairCurves {
        strands: Vec::with_capacity(curves.strands.len()),
        thickness: curves.thickness.as_ref().map(|_| Vec::new()),
        transparency: curves.transparency.as_ref().map(|_| Vec::new()),
        color: curves.color.as_ref().map(|_| Vec::new()),
    };
    let mut base = 0;
    for (i, s) in curves.strands.iter().enumerate() {
        if s.is_empty() {
            return Err(unwritable(format!("strand {i} has no vertex to resample")));
        }
        let points: Vec<nalgebra::Vector3<f64>> = s.iter().map(|p| nalgebra::Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
        let cum = strand::samples::cumulative_lengths(&points);
        // Segment j and fraction t where each target length falls (`strand::samples::stations`); a
        // strand of one vertex or of zero length: n copies of its root.
        let at = strand::samples::stations(&cum, n).unwrap_or_else(|| vec![(0, 0.0); n]);
        let mut strand = Vec::with_capacity(n);
        for (j, t) in at {
            let t = t as f32;
            let j1 = (j + 1).min(s.len() - 1);
            let lerp = |a: f32, b: f32| a + (b - a) * t;
            strand.push(std::array::from_fn(|c| lerp(s[j][c], s[j1][c])));
            if let (Some(o), Some(v)) = (&mut out.thickness, &curves.thickness) {
                o.push(lerp(v[base + j], v[base + j1]));
            }
            if let (Some(o), Some(v)) = (&mut out.transparency, &curves.transparency) {
                o.push(lerp(v[base + j], v[base + j1]));
            }
            if let (Some(o), Some(v)) = (&mut out.color, &curves.color) {
                o.push(std::array::from_fn(|c| {
                    lerp(v[base + j][c], v[base + j1][c])
                }));
            }
        }
        out.strands.push(strand);
        base += s.len();
    }
    Ok(out)
}
