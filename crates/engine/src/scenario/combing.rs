//! The combing instrument: what a cosmetic lab's combing rig reports of a stroke through a tress. The rig
//! records the force on the comb against the comb's position along the tress (from the roots); from that
//! force-distance profile it gives the combing work (the area under it), the peak and mean force, and the work
//! in each fifth of the tress length (the curve's shape: an end peak at the tips, a plateau, ...).
//!
//! One implementation for every user: tress scenarios (`coiffure run`, `profile.csv`, `summary.json`), Python
//! and the validation suites call [`fifths`] and [`CombingFigures::of`].

use serde::Serialize;
use std::fmt::Write as _;

/// Number of equal parts of the tress length the profile is cut into.
pub const PARTS: usize = 5;

/// The profile over each fifth of the tress length (from the roots: fifth 0 is the roots', fifth 4 the
/// tips').
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Fifths {
    /// Work done against the force over the comb's path within the fifth, J (`int |F| ds`).
    pub work_j: [f64; PARTS],
    /// Distance the comb travelled within the fifth, m.
    pub path_m: [f64; PARTS],
    /// Mean force by comb position over the fifth, N: `work_j / path_m` (0 where the comb did not pass).
    pub mean_force_n: [f64; PARTS],
}

impl Fifths {
    /// The index of the fifth with the largest mean force (0: roots, 4: tips); the first of equals.
    pub fn largest(&self) -> usize {
        (0..PARTS).fold(0, |best, i| if self.mean_force_n[i] > self.mean_force_n[best] { i } else { best })
    }
}

/// The work and mean force by comb position over each fifth of a tress of length `length_m` (m), from a
/// sampled force-distance profile: `position_m[i]`, the comb's position from the roots along the tress (m),
/// and `force_n[i]`, the force on the comb then (N; a magnitude). Between two samples the force is taken as
/// linear in position (the trapezoidal rule), and a piece of path crossing a fifth's boundary is split there
/// (the force interpolated at it), so a force linear in position gives exact fifths. The path counts in
/// either direction (`|ds|`); positions outside `[0, length_m]` (above the roots, below the tips) belong to no
/// fifth.
///
/// # Panics
/// If the slices differ in length or `length_m` is not positive and finite.
pub fn fifths(position_m: &[f64], force_n: &[f64], length_m: f64) -> Fifths {
    assert_eq!(position_m.len(), force_n.len(), "one force per position");
    assert!(length_m.is_finite() && length_m > 0.0, "the tress length must be > 0 m, got {length_m}");
    let part = length_m / PARTS as f64;
    let mut out = Fifths::default();
    for i in 1..position_m.len() {
        let (s0, s1, f0, f1) = (position_m[i - 1], position_m[i], force_n[i - 1], force_n[i]);
        let (lo, hi) = (s0.min(s1), s0.max(s1));
        if !(hi > lo) {
            continue;
        }
        // Force at position s on this piece of path (linear between the two samples).
        let force_at = |s: f64| f0 + (f1 - f0) * (s - s0) / (s1 - s0);
        for k in 0..PARTS {
            let (a, b) = (lo.max(k as f64 * part), hi.min((k + 1) as f64 * part));
            if b > a {
                out.path_m[k] += b - a;
                out.work_j[k] += 0.5 * (force_at(a) + force_at(b)) * (b - a);
            }
        }
    }
    for k in 0..PARTS {
        out.mean_force_n[k] = if out.path_m[k] > 0.0 { out.work_j[k] / out.path_m[k] } else { 0.0 };
    }
    out
}

/// A combing rig's figures of one stroke (or of several, [`CombingFigures::total`]). Names carry their unit;
/// the same names in every summary that has them.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct CombingFigures {
    /// Combing work, J: the area under the whole force-distance profile (`int |F| ds` over the comb's path
    /// along the tress, above the roots and below the tips included).
    pub combing_work_j: f64,
    /// Largest force on the comb, N.
    pub combing_peak_n: f64,
    /// Mean force by comb position over the tress length, N: the fifths' work over the path they were combed
    /// along (0 if the comb did not pass through the tress length).
    pub combing_mean_n: f64,
    /// Work in each fifth of the tress length, from the roots, J ([`fifths`]).
    pub work_fifths_j: [f64; PARTS],
    /// Mean force by comb position in each fifth of the tress length, from the roots, N ([`fifths`]).
    pub mean_force_fifths_n: [f64; PARTS],
}

impl CombingFigures {
    /// The figures of a profile (as for [`fifths`]) through a tress of length `length_m`, m.
    pub fn of(position_m: &[f64], force_n: &[f64], length_m: f64) -> Self {
        let f = fifths(position_m, force_n, length_m);
        let whole = work_along(position_m, force_n);
        let path: f64 = f.path_m.iter().sum();
        Self {
            combing_work_j: whole,
            combing_peak_n: force_n.iter().copied().fold(0.0, f64::max),
            combing_mean_n: if path > 0.0 { f.work_j.iter().sum::<f64>() / path } else { 0.0 },
            work_fifths_j: f.work_j,
            mean_force_fifths_n: f.mean_force_n,
        }
    }

    /// The figures of several strokes together (of their profiles, each from [`CombingFigures::of`], and the
    /// path each combed along each fifth, m): work summed, the largest peak, means weighted by path.
    pub fn total(strokes: &[(CombingFigures, [f64; PARTS])]) -> Self {
        let mut out = Self::default();
        let mut path = [0.0; PARTS];
        for (s, p) in strokes {
            out.combing_work_j += s.combing_work_j;
            out.combing_peak_n = out.combing_peak_n.max(s.combing_peak_n);
            for k in 0..PARTS {
                out.work_fifths_j[k] += s.work_fifths_j[k];
                path[k] += p[k];
            }
        }
        for k in 0..PARTS {
            out.mean_force_fifths_n[k] = if path[k] > 0.0 { out.work_fifths_j[k] / path[k] } else { 0.0 };
        }
        let all: f64 = path.iter().sum();
        out.combing_mean_n = if all > 0.0 { out.work_fifths_j.iter().sum::<f64>() / all } else { 0.0 };
        out
    }
}

/// The combing rig's figures of each stroke, as arrays over the strokes (the first is stroke 1).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct PerStroke {
    /// Combing work of each stroke, J.
    pub combing_work_j: Vec<f64>,
    /// Largest force on the comb in each stroke, N.
    pub combing_peak_n: Vec<f64>,
    /// Mean force by comb position over the tress length in each stroke, N.
    pub combing_mean_n: Vec<f64>,
    /// Work in each fifth of the tress length (from the roots) in each stroke, J.
    pub work_fifths_j: Vec<[f64; PARTS]>,
    /// Mean force by comb position in each fifth (from the roots) in each stroke, N.
    pub mean_force_fifths_n: Vec<[f64; PARTS]>,
}

impl PerStroke {
    /// From each stroke's figures (as [`CombingProfile::strokes`] gives them).
    pub fn of(strokes: &[(CombingFigures, [f64; PARTS])]) -> Self {
        let col = |f: fn(&CombingFigures) -> f64| strokes.iter().map(|(s, _)| f(s)).collect();
        Self {
            combing_work_j: col(|s| s.combing_work_j),
            combing_peak_n: col(|s| s.combing_peak_n),
            combing_mean_n: col(|s| s.combing_mean_n),
            work_fifths_j: strokes.iter().map(|(s, _)| s.work_fifths_j).collect(),
            mean_force_fifths_n: strokes.iter().map(|(s, _)| s.mean_force_fifths_n).collect(),
        }
    }
}

/// `int |F| ds` over the whole profile (trapezoidal rule, path in either direction), J.
fn work_along(position_m: &[f64], force_n: &[f64]) -> f64 {
    (1..position_m.len()).map(|i| 0.5 * (force_n[i - 1] + force_n[i]) * (position_m[i] - position_m[i - 1]).abs()).sum()
}

/// A combing rig's recording: one row per haptic step while the comb strokes (the returns between strokes
/// left out). `profile.csv` has these columns in this order.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CombingProfile {
    /// Stroke number, from 1.
    pub stroke: Vec<u32>,
    /// Time since the tool started, s.
    pub t: Vec<f64>,
    /// The comb's position from the roots along the tress, m.
    pub position_m: Vec<f64>,
    /// Force on the comb (magnitude), N.
    pub force_n: Vec<f64>,
}

impl CombingProfile {
    /// Appends one step.
    pub fn push(&mut self, stroke: u32, t: f64, position_m: f64, force_n: f64) {
        self.stroke.push(stroke);
        self.t.push(t);
        self.position_m.push(position_m);
        self.force_n.push(force_n);
    }

    /// Steps.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No step.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The rows of stroke `n` (from 1), as a range of indices.
    pub fn stroke_rows(&self, n: u32) -> std::ops::Range<usize> {
        let start = self.stroke.partition_point(|&s| s < n);
        start..self.stroke.partition_point(|&s| s <= n)
    }

    /// The figures of each stroke (the first is stroke 1) through a tress of length `length_m`, m, with the
    /// path each combed along each fifth, m (for [`CombingFigures::total`]).
    pub fn strokes(&self, length_m: f64) -> Vec<(CombingFigures, [f64; PARTS])> {
        let n = self.stroke.last().copied().unwrap_or(0);
        (1..=n)
            .map(|k| {
                let r = self.stroke_rows(k);
                let (p, f) = (&self.position_m[r.clone()], &self.force_n[r]);
                (CombingFigures::of(p, f, length_m), fifths(p, f, length_m).path_m)
            })
            .collect()
    }

    /// The CSV text: header `stroke,t,position_m,force_n`, one line per step.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(self.len() * 48 + 32);
        s.push_str("stroke,t,position_m,force_n\n");
        for i in 0..self.len() {
            let _ = writeln!(s, "{},{:.4},{:.6e},{:.6e}", self.stroke[i], self.t[i], self.position_m[i], self.force_n[i]);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Irregular positions from `a` to `b` (m): a fixed pseudo-random spacing that puts samples on both sides
    /// of every fifth's boundary but none on one.
    fn positions(a: f64, b: f64, n: usize) -> Vec<f64> {
        let mut w: Vec<f64> = (0..n).map(|i| 1.0 + 0.7 * ((i as f64 * 2.399).sin())).collect();
        let total: f64 = w.iter().sum();
        let mut s = a;
        let mut out = vec![a];
        for x in w.iter_mut() {
            s += (b - a) * *x / total;
            out.push(s);
        }
        out
    }

    #[test]
    fn a_constant_force_over_a_known_path_does_force_times_distance() {
        // 0.3 N from 2 cm above the roots to 3 cm below the tips of a 0.2 m tress: every fifth 0.04 m x 0.3 N,
        // the whole 0.25 m x 0.3 N; mean 0.3 N everywhere.
        let s = positions(-0.02, 0.23, 997);
        let f = vec![0.3; s.len()];
        let c = CombingFigures::of(&s, &f, 0.2);
        assert!((c.combing_work_j - 0.075).abs() < 1e-12, "{c:?}");
        assert_eq!(c.combing_peak_n, 0.3);
        assert!((c.combing_mean_n - 0.3).abs() < 1e-12);
        for k in 0..PARTS {
            assert!((c.work_fifths_j[k] - 0.012).abs() < 1e-12, "{c:?}");
            assert!((c.mean_force_fifths_n[k] - 0.3).abs() < 1e-12);
        }
        // Back up the same path: the distance counts, not its sign.
        let back: Vec<f64> = s.iter().rev().copied().collect();
        assert!((CombingFigures::of(&back, &f, 0.2).combing_work_j - 0.075).abs() < 1e-12);
    }

    #[test]
    fn fifths_of_a_linear_profile_are_exact() {
        // F = a + b s over [0, L] (N), L = 0.3 m: fifth k's work is a h + b (s1^2 - s0^2) / 2 with h = L / 5,
        // its mean force a + b (s0 + s1) / 2. Irregular samples straddling every boundary.
        let (a, b, l) = (0.05, 2.0, 0.3);
        let s = positions(0.0, l, 613);
        let f: Vec<f64> = s.iter().map(|x| a + b * x).collect();
        let got = fifths(&s, &f, l);
        let h = l / 5.0;
        for k in 0..PARTS {
            let (s0, s1) = (k as f64 * h, (k + 1) as f64 * h);
            assert!((got.work_j[k] - (a * h + b * (s1 * s1 - s0 * s0) / 2.0)).abs() < 1e-14, "fifth {k}: {got:?}");
            assert!((got.path_m[k] - h).abs() < 1e-14);
            assert!((got.mean_force_n[k] - (a + b * (s0 + s1) / 2.0)).abs() < 1e-12);
        }
        assert_eq!(got.largest(), 4, "a force rising to the tips peaks in the tips' fifth");
    }

    #[test]
    fn a_stroke_that_stops_short_has_no_force_in_the_fifths_it_did_not_reach() {
        // A 0.1 N step profile over [0, 0.5 L) then nothing: fifths 0 and 1 full, fifth 2 half combed, 3 and 4
        // not reached.
        let l = 0.25;
        let s = positions(0.0, 0.5 * l, 400);
        let f = vec![0.1; s.len()];
        let got = fifths(&s, &f, l);
        assert!((got.path_m[2] - 0.5 * l / 5.0).abs() < 1e-14);
        assert_eq!((got.path_m[3], got.path_m[4], got.mean_force_n[4]), (0.0, 0.0, 0.0));
        assert!((got.mean_force_n[2] - 0.1).abs() < 1e-12);
    }

    #[test]
    fn strokes_are_figured_apart_and_together() {
        // Stroke 1 at 0.2 N, stroke 2 at 0.4 N, each over the whole 0.2 m tress: works 0.04 and 0.08 J; together
        // 0.12 J, peak 0.4 N, mean 0.3 N in every fifth.
        let mut p = CombingProfile::default();
        for (n, f) in [(1u32, 0.2), (2, 0.4)] {
            for (i, s) in positions(0.0, 0.2, 333).into_iter().enumerate() {
                p.push(n, i as f64 * 1e-3, s, f);
            }
        }
        let strokes = p.strokes(0.2);
        assert_eq!(strokes.len(), 2);
        assert!((strokes[0].0.combing_work_j - 0.04).abs() < 1e-12);
        assert!((strokes[1].0.combing_work_j - 0.08).abs() < 1e-12);
        let all = CombingFigures::total(&strokes);
        assert!((all.combing_work_j - 0.12).abs() < 1e-12);
        assert_eq!(all.combing_peak_n, 0.4);
        assert!((all.combing_mean_n - 0.3).abs() < 1e-12);
        assert!(all.mean_force_fifths_n.iter().all(|m| (m - 0.3).abs() < 1e-12), "{all:?}");
        assert_eq!(p.to_csv().lines().next(), Some("stroke,t,position_m,force_n"));
        assert_eq!(p.to_csv().lines().count(), 1 + p.len());
    }
}
