//! USC-HairSalon `.data` format (little-endian).
//!
//! Layout: i32 number of strands; then per strand an i32 number of points `n` followed by
//! `n` x (3 x f32) positions. Nothing else: only positions are stored, so [`write()`] drops any
//! thickness, transparency or colour, and [`read()`] returns none. Negative counts and bytes after
//! the last strand are errors. Strands of 0 or 1 point (found in the USC database for bald
//! scalp samples) are kept as they are.

use super::{put_f32, put_u32, Cursor, FormatError, HairCurves};

const FORMAT: &str = ".data";

/// Parse a whole `.data` file.
pub fn read(bytes: &[u8]) -> Result<HairCurves, FormatError> {
    let mut c = Cursor::new(bytes, FORMAT);
    let ns = c.i32("number of strands (i32)")?;
    if ns < 0 {
        return Err(c.error(0, format!("a non-negative number of strands, found {ns}")));
    }
    // Each strand takes at least its 4-byte count: bound the allocation by the file size.
    c.need(ns as u64, 4, "strand counts")?;
    let mut strands = Vec::with_capacity(ns as usize);
    for i in 0..ns {
        let at = c.pos();
        let n = c.i32("number of points of a strand (i32)")?;
        if n < 0 {
            return Err(c.error(
                at,
                format!("a non-negative number of points for strand {i}, found {n}"),
            ));
        }
        c.need(
            n as u64,
            12,
            &format!("points of strand {i} (3 x f32 each)"),
        )?;
        let s = (0..n)
            .map(|_| c.vec3("point (3 x f32)"))
            .collect::<Result<Vec<_>, _>>()?;
        strands.push(s);
    }
    c.finish()?;
    Ok(HairCurves::from_strands(strands))
}

/// Serialise the strand positions as a `.data` file (attributes are not stored). Errors only if
/// a count does not fit in an i32.
pub fn write(curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
    let count = |n: usize| {
        i32::try_from(n).map_err(|_| FormatError::Unwritable {
            format: FORMAT,
            reason: format!("count {n} does not fit in an i32"),
        })
    };
    let mut out = Vec::with_capacity(4 + 4 * curves.strands.len() + 12 * curves.num_points());
    put_u32(&mut out, count(curves.strands.len())? as u32);
    for s in &curves.strands {
        put_u32(&mut out, count(s.len())? as u32);
        for p in s {
            p.iter().for_each(|&x| put_f32(&mut out, x));
        }
    }
    Ok(out)
}
