//! Distances between four pairs of segments at once (SIMD lanes, `wide::f64x4`): the quick reject of the hair-hair
//! narrow phase ([`crate::hair_contact`]). Most pairs of chords whose boxes overlap are farther apart than the
//! contact distance (on the live comb, most of those tested); four of them are measured here
//! in the time of about one scalar [`crate::geometry::closest_segment_params`], and only those that may touch go
//! on to the exact test.
//!
//! The lanes run `closest_segment_params`'s own arithmetic, operation for operation (the same products and sums
//! in the same order, the same branches as selections), so they give its closest points bit for bit (tested); a
//! lane is let through unless its distance is past the contact distance by a relative 1e-6, and degenerate
//! (point-like) segments are always let through, so the exact test alone decides which pairs touch.

use nalgebra::Vector3;
use wide::{f64x4, CmpEq, CmpGe, CmpGt, CmpLe, CmpLt};

/// Relative slack of the reject: a pair is rejected only if its distance is at least `distance (1 + SLACK)`.
const SLACK: f64 = 1e-6;

/// The lanes (bit `l` for pair `l`) of the four segment pairs `[p0[l], p1[l]]`, `[q0[l], q1[l]]` that may be
/// closer than `distance` (m): every pair whose distance (as `closest_segment_params` finds it) is below
/// `distance (1 + 1e-6)`, every pair with a point-like segment, and every pair with a NaN coordinate; and each pair's
/// closest points `(s, t)` as `closest_segment_params` gives them, bit for bit (the same operations), where the
/// lane is in `exact` (none of its segments point-like, no NaN); elsewhere the scalar function must be asked.
pub fn may_be_closer(p0: [&Vector3<f64>; 4], p1: [&Vector3<f64>; 4], q0: [&Vector3<f64>; 4], q1: [&Vector3<f64>; 4], distance: f64) -> Closest4 {
    let lanes = |v: [&Vector3<f64>; 4], c: usize| f64x4::from([v[0][c], v[1][c], v[2][c], v[3][c]]);
    let xyz = |v: [&Vector3<f64>; 4]| [lanes(v, 0), lanes(v, 1), lanes(v, 2)];
    let (p0, p1, q0, q1) = (xyz(p0), xyz(p1), xyz(q0), xyz(q1));
    let sub = |a: [f64x4; 3], b: [f64x4; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64x4; 3], b: [f64x4; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (zero, one) = (f64x4::splat(0.0), f64x4::splat(1.0));
    let clamp01 = |x: f64x4| x.cmp_lt(zero).blend(zero, x.cmp_gt(one).blend(one, x));
    // closest_segment_params, lane by lane.
    let d1 = sub(p1, p0);
    let d2 = sub(q1, q0);
    let r = sub(p0, q0);
    let a = dot(d1, d1);
    let e = dot(d2, d2);
    let f = dot(d2, r);
    let eps = f64x4::splat(1e-30);
    let degenerate = a.cmp_le(eps) | e.cmp_le(eps);
    let c = dot(d1, r);
    let b = dot(d1, d2);
    let denom = a * e - b * b;
    let s = denom.cmp_gt(f64x4::splat(1e-14) * a * e).blend(clamp01((b * f - c * e) / denom), zero);
    let t = (b * s + f) / e;
    let below = t.cmp_lt(zero);
    let above = t.cmp_gt(one) & !below;
    let s = below.blend(clamp01(-c / a), above.blend(clamp01((b - c) / a), s));
    let t = below.blend(zero, above.blend(one, t));
    // The gap between the two points, as the narrow phase takes it.
    let xp = [p0[0] + d1[0] * s, p0[1] + d1[1] * s, p0[2] + d1[2] * s];
    let xq = [q0[0] + d2[0] * t, q0[1] + d2[1] * t, q0[2] + d2[2] * t];
    let gap = sub(xp, xq);
    let far = distance * (1.0 + SLACK);
    let apart = dot(gap, gap).cmp_ge(f64x4::splat(far * far)) & !degenerate;
    let exact = !degenerate & s.cmp_eq(s) & t.cmp_eq(t);
    Closest4 { through: !apart.move_mask() & 0b1111, exact: exact.move_mask() & 0b1111, s: s.to_array(), t: t.to_array() }
}

/// What [`may_be_closer`] finds of four segment pairs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest4 {
    /// The lanes that may be closer than the distance (bit `l` for pair `l`).
    pub through: i32,
    /// The lanes whose `s` and `t` are `closest_segment_params`' own.
    pub exact: i32,
    /// Each pair's closest points: `p0 + s (p1 - p0)` and `q0 + t (q1 - q0)`.
    pub s: [f64; 4],
    pub t: [f64; 4],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::closest_segment_params;

    #[test]
    fn the_lanes_reject_only_pairs_the_scalar_test_finds_apart() {
        // 40,000 random segment pairs in 1 cm (a quarter parallel, some crossing, some point-like, some with a NaN),
        // four at a time, against contact distances of 0.5 to 5 mm: every pair closer than the distance by
        // closest_segment_params is let through; every pair let through is a point-like or NaN one or closer than
        // the distance plus 1e-6 of it; every far pair is rejected (the reject works); and the lanes' closest points
        // are the scalar's to the bit wherever they say so (all but the point-like and NaN pairs).
        let mut seed = 99u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut far, mut rejected, mut near, mut exact) = (0, 0, 0, 0);
        for block in 0..10_000 {
            let distance = 5e-4 + 4.5e-3 * rnd();
            let mut segs: Vec<[Vector3<f64>; 4]> = Vec::new();
            for l in 0..4 {
                let mut v = || Vector3::new(rnd(), rnd(), rnd()) * 0.01;
                let (p0, mut p1, q0, mut q1) = (v(), v(), v(), v());
                match (block * 4 + l) % 13 {
                    0..=2 => q1 = q0 + (p1 - p0) * (0.3 + rnd()),
                    3 => p1 = p0,
                    4 => q1 = q0,
                    5 if block % 50 == 0 => p1.y = f64::NAN,
                    _ => {}
                }
                segs.push([p0, p1, q0, q1]);
            }
            let pick = |k: usize| [&segs[0][k], &segs[1][k], &segs[2][k], &segs[3][k]];
            let found = may_be_closer(pick(0), pick(1), pick(2), pick(3), distance);
            let mask = found.through;
            for (l, [p0, p1, q0, q1]) in segs.iter().enumerate() {
                let (s, t) = closest_segment_params(p0, p1, q0, q1);
                let d = ((p0 + (p1 - p0) * s) - (q0 + (q1 - q0) * t)).norm();
                if found.exact & (1 << l) != 0 {
                    assert_eq!((found.s[l].to_bits(), found.t[l].to_bits()), (s.to_bits(), t.to_bits()), "block {block} lane {l}: the lanes' closest points are the scalar's");
                    exact += 1;
                }
                let through = mask & (1 << l) != 0;
                let odd = (p1 - p0).norm_squared() <= 1e-30 || (q1 - q0).norm_squared() <= 1e-30 || d.is_nan();
                if d < distance || odd {
                    assert!(through, "block {block} lane {l}: distance {d} < {distance} (or point-like / NaN) rejected");
                    near += 1;
                } else {
                    far += 1;
                    if through {
                        assert!(d < distance * (1.0 + 1e-6), "block {block} lane {l}: {d} far from {distance} let through");
                    } else {
                        rejected += 1;
                    }
                }
            }
        }
        assert!(near > 1_000 && far > 20_000, "{near} near, {far} far");
        assert!(exact > 30_000, "{exact} pairs with the scalar's closest points");
        assert_eq!(rejected, far, "every far pair is rejected");
    }
}
