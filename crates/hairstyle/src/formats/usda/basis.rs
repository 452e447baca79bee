//! USD `BasisCurves` cubic bases evaluated to polylines.
//!
//! A curve of control points is cut into cubic segments of four control points each, after the
//! USD rules for `basis` and `wrap` (UsdGeomBasisCurves): `bezier` steps 3 points per segment and
//! needs 4 + 3k points (nonperiodic, pinned) or 3k (periodic); `bspline` and `catmullRom` step 1
//! and need at least 4 points (nonperiodic: n - 3 segments; periodic: n segments, wrapping);
//! `pinned` `bspline`/`catmullRom` add a phantom point at each end (2 P0 - P1, 2 Pn-1 - Pn-2) so
//! that the curve passes through its end points (n - 1 segments, at least 2 points). Each
//! segment is sampled at [`SAMPLES_PER_SEGMENT`] evenly spaced parameters, and the end of the
//! last segment is added (a periodic curve is closed: its first sample is repeated at the end).

/// Polyline points per cubic segment (the segment's end is the next segment's start).
pub const SAMPLES_PER_SEGMENT: usize = 4;

/// A cubic basis of USD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// Cubic Bezier (USD's fallback basis).
    Bezier,
    /// Uniform cubic B-spline.
    Bspline,
    /// Catmull-Rom spline.
    CatmullRom,
}

/// Curve wrap mode of USD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    /// Open curve (USD's fallback).
    Nonperiodic,
    /// Closed curve.
    Periodic,
    /// Open curve through its end points.
    Pinned,
}

impl Basis {
    /// Weights of the four control points at parameter `t` in [0, 1].
    fn weights(self, t: f64) -> [f64; 4] {
        let (t2, t3) = (t * t, t * t * t);
        let u = 1.0 - t;
        match self {
            Basis::Bezier => [u * u * u, 3.0 * t * u * u, 3.0 * t2 * u, t3],
            Basis::Bspline => [
                u * u * u / 6.0,
                (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                t3 / 6.0,
            ],
            Basis::CatmullRom => [
                0.5 * (-t3 + 2.0 * t2 - t),
                0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                0.5 * (t3 - t2),
            ],
        }
    }
}

/// The segments of one curve: each the indices of its four control points in the extended point
/// list (the control points with the phantom points of a pinned curve at both ends).
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    basis: Basis,
    phantoms: bool,
    periodic: bool,
    segments: Vec<[usize; 4]>,
}

impl Plan {
    /// The segments of a curve of `n` control points, or a message saying what `n` must be.
    pub fn new(basis: Basis, wrap: Wrap, n: usize) -> Result<Plan, String> {
        let name = match basis {
            Basis::Bezier => "bezier",
            Basis::Bspline => "bspline",
            Basis::CatmullRom => "catmullRom",
        };
        let (phantoms, periodic) = match (basis, wrap) {
            (Basis::Bezier, Wrap::Pinned) => (false, false),
            (_, Wrap::Pinned) => (true, false),
            (_, Wrap::Periodic) => (false, true),
            (_, Wrap::Nonperiodic) => (false, false),
        };
        let segments: Vec<[usize; 4]> = match (basis, periodic) {
            (Basis::Bezier, false) => {
                if n < 4 || (n - 4) % 3 != 0 {
                    return Err(format!("a nonperiodic bezier curve needs 4 + 3k control points, found {n}"));
                }
                (0..(n - 1) / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2, 3 * k + 3]).collect()
            }
            (Basis::Bezier, true) => {
                if n < 3 || n % 3 != 0 {
                    return Err(format!("a periodic bezier curve needs 3k control points, found {n}"));
                }
                (0..n / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2, (3 * k + 3) % n]).collect()
            }
            (_, true) => {
                if n < 3 {
                    return Err(format!("a periodic {name} curve needs at least 3 control points, found {n}"));
                }
                (0..n).map(|k| [k, (k + 1) % n, (k + 2) % n, (k + 3) % n]).collect()
            }
            (_, false) if phantoms => {
                if n < 2 {
                    return Err(format!("a pinned {name} curve needs at least 2 control points, found {n}"));
                }
                (0..n - 1).map(|k| [k, k + 1, k + 2, k + 3]).collect()
            }
            (_, false) => {
                if n < 4 {
                    return Err(format!("a nonperiodic {name} curve needs at least 4 control points, found {n}"));
                }
                (0..n - 3).map(|k| [k, k + 1, k + 2, k + 3]).collect()
            }
        };
        Ok(Plan { basis, phantoms, periodic, segments })
    }

    /// Number of cubic segments.
    pub fn segments(&self) -> usize {
        self.segments.len()
    }

    /// Number of `varying` values of the curve: one per segment end (periodic: one per segment).
    pub fn varying(&self) -> usize {
        self.segments.len() + !self.periodic as usize
    }

    /// Number of polyline points [`Plan::eval`] gives.
    pub fn samples(&self) -> usize {
        self.segments.len() * SAMPLES_PER_SEGMENT + 1
    }

    /// The polyline of per-control-point values `v` (one per control point: points, or `vertex`
    /// primvars), `D` components each.
    pub fn eval<const D: usize>(&self, v: &[[f32; D]]) -> Vec<[f32; D]> {
        let ext: Vec<[f64; D]> = if self.phantoms {
            let n = v.len();
            let f = |a: &[f32; D], b: &[f32; D]| std::array::from_fn(|k| 2.0 * a[k] as f64 - b[k] as f64);
            std::iter::once(f(&v[0], &v[1]))
                .chain(v.iter().map(|p| p.map(f64::from)))
                .chain(std::iter::once(f(&v[n - 1], &v[n - 2])))
                .collect()
        } else {
            v.iter().map(|p| p.map(f64::from)).collect()
        };
        let mut out = Vec::with_capacity(self.samples());
        let point = |seg: &[usize; 4], t: f64| -> [f32; D] {
            let w = self.basis.weights(t);
            std::array::from_fn(|k| (0..4).map(|j| w[j] * ext[seg[j]][k]).sum::<f64>() as f32)
        };
        for seg in &self.segments {
            for j in 0..SAMPLES_PER_SEGMENT {
                out.push(point(seg, j as f64 / SAMPLES_PER_SEGMENT as f64));
            }
        }
        if self.periodic {
            out.push(out[0]);
        } else if let Some(last) = self.segments.last() {
            out.push(point(last, 1.0));
        }
        out
    }

    /// The polyline of `varying` values `v` ([`Plan::varying`] of them: one per segment end),
    /// linear along each segment.
    pub fn eval_varying<const D: usize>(&self, v: &[[f32; D]]) -> Vec<[f32; D]> {
        let m = v.len();
        let mut out = Vec::with_capacity(self.samples());
        for s in 0..self.segments.len() {
            let (a, b) = (v[s % m], v[(s + 1) % m]);
            for j in 0..SAMPLES_PER_SEGMENT {
                let t = j as f32 / SAMPLES_PER_SEGMENT as f32;
                out.push(std::array::from_fn(|k| a[k] + t * (b[k] - a[k])));
            }
        }
        out.push(v[self.segments.len() % m]);
        out
    }
}
