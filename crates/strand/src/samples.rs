//! Samples along a curve, the one law for every layer: where a fraction of the length falls among evenly
//! spaced samples ([`between`], [`lerp`]), and where evenly spaced arc lengths fall on a polyline
//! ([`stations`], [`resample`]). Linear between samples; callers interpolate their own quantities (points,
//! displacements, per-vertex attributes) at the places these give.

use nalgebra::Vector3;

/// Where the fraction `u` of the length (clamped to [0, 1]; NaN taken as 0) falls among `n` evenly spaced
/// samples: the sample `i` before it (at most `n - 2`) and the fraction `f` in [0, 1] of the way to sample
/// `i + 1`. `(0, 0.0)` for `n < 2`.
pub fn between(n: usize, u: f64) -> (usize, f64) {
    if n < 2 {
        return (0, 0.0);
    }
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let x = u * (n - 1) as f64;
    let i = (x as usize).min(n - 2);
    (i, (x - i as f64).clamp(0.0, 1.0))
}

/// The evenly spaced `samples` (m, root first) linearly interpolated at the fraction `u` of the length
/// ([`between`]); the first sample if there are fewer than two, zero if none.
pub fn lerp(samples: &[Vector3<f64>], u: f64) -> Vector3<f64> {
    match samples.len() {
        0 => Vector3::zeros(),
        1 => samples[0],
        n => {
            let (i, f) = between(n, u);
            samples[i] * (1.0 - f) + samples[i + 1] * f
        }
    }
}

/// Where `n` arc lengths evenly spaced from 0 to the total (both ends included) fall on a polyline whose
/// cumulative lengths are `cumulative` (m, from 0, non-decreasing, one per vertex): for each, the segment `j`
/// (from vertex `j` to `j + 1`) and the fraction in [0, 1] along it. None for fewer than two vertices, `n < 2`,
/// or a zero or non-finite total length.
pub fn stations(cumulative: &[f64], n: usize) -> Option<Vec<(usize, f64)>> {
    let v = cumulative.len();
    let total = *cumulative.last()?;
    if v < 2 || n < 2 || !(total > 0.0 && total.is_finite()) {
        return None;
    }
    Some(
        (0..n)
            .map(|k| {
                let target = total * k as f64 / (n - 1) as f64;
                let j = cumulative.partition_point(|&c| c <= target).clamp(1, v - 1) - 1;
                let len = cumulative[j + 1] - cumulative[j];
                (j, if len > 0.0 { ((target - cumulative[j]) / len).clamp(0.0, 1.0) } else { 0.0 })
            })
            .collect(),
    )
}

/// Cumulative lengths of the polyline `points` (m): 0 at the first vertex, then the sum of the segments' lengths.
pub fn cumulative_lengths(points: &[Vector3<f64>]) -> Vec<f64> {
    let mut cum = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            s += (p - points[k - 1]).norm();
        }
        cum.push(s);
    }
    cum
}

/// `n` points evenly spaced in arc length along the polyline `points` (m), both ends kept ([`stations`]);
/// None as for [`stations`].
pub fn resample(points: &[Vector3<f64>], n: usize) -> Option<Vec<Vector3<f64>>> {
    let at = stations(&cumulative_lengths(points), n)?;
    Some(at.into_iter().map(|(j, f)| points[j] * (1.0 - f) + points[j + 1] * f).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn between_and_lerp_reproduce_a_straight_line_and_clamp() {
        // Samples of the line x = 3u (u in [0, 1]) at every count from 2 to 40: the interpolation is the line
        // itself at any u (to 1e-12), ends included; u outside [0, 1] (and NaN) is clamped.
        for n in 2..=40 {
            let s: Vec<Vector3<f64>> = (0..n).map(|k| Vector3::new(3.0 * k as f64 / (n - 1) as f64, 1.0, 0.0)).collect();
            for m in 0..=97 {
                let u = m as f64 / 97.0;
                assert!((lerp(&s, u).x - 3.0 * u).abs() < 1e-12, "n {n} u {u}");
                let (i, f) = between(n, u);
                assert!(i <= n - 2 && (0.0..=1.0).contains(&f));
            }
            assert_eq!(lerp(&s, -1.0), s[0]);
            assert_eq!(lerp(&s, 2.0), s[n - 1]);
            assert_eq!(lerp(&s, f64::NAN), s[0]);
        }
        assert_eq!(between(1, 0.5), (0, 0.0));
        assert_eq!(lerp(&[], 0.5), Vector3::zeros());
    }

    #[test]
    fn resampling_gives_even_arc_lengths_on_the_polyline_and_keeps_its_ends() {
        // Random-ish polylines (uneven segments, some of zero length): every resampled point lies on the
        // polyline at the arc length k L / (n - 1) (to 1e-12 m), the ends are the polyline's ends.
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..50 {
            let v = 2 + case % 9;
            let mut p = vec![Vector3::zeros()];
            for k in 1..v {
                let step = if k % 4 == 3 { Vector3::zeros() } else { Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd()) * 0.01 };
                p.push(p[k - 1] + step);
            }
            let cum = cumulative_lengths(&p);
            let total = cum[v - 1];
            if total == 0.0 {
                assert!(resample(&p, 5).is_none());
                continue;
            }
            for n in [2, 3, 10, 33] {
                let r = resample(&p, n).unwrap();
                assert_eq!(r.len(), n);
                assert!((r[0] - p[0]).norm() < 1e-15 && (r[n - 1] - p[v - 1]).norm() < 1e-12, "case {case}");
                for (k, (j, f)) in stations(&cum, n).unwrap().into_iter().enumerate() {
                    let s = cum[j] + f * (cum[j + 1] - cum[j]);
                    assert!((s - total * k as f64 / (n - 1) as f64).abs() < 1e-12, "case {case} n {n} k {k}");
                }
            }
        }
        assert!(resample(&[Vector3::zeros()], 4).is_none());
        assert!(stations(&[0.0, 1.0], 1).is_none());
    }
}
