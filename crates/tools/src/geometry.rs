//! Geometric primitives of tool-strand collision: closest points between segments, axis-aligned boxes.

use nalgebra::Vector3;

/// Where on the segment `[a, b]` the point closest to `p` lies: `t` in [0, 1] with the point `a + t (b - a)`
/// (0 for a degenerate segment).
pub fn closest_point_param(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let n2 = ab.norm_squared();
    if n2 > 0.0 {
        ((p - a).dot(&ab) / n2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Distance from `p` to the segment `[a, b]` (same unit as the points, m in Coiffure).
pub fn point_segment_distance(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    (a + (b - a) * closest_point_param(p, a, b) - p).norm()
}

/// Closest points between segments `[p0, p1]` and `[q0, q1]`: returns `(s, t)` in [0, 1] with the points
/// `p0 + s (p1 - p0)` and `q0 + t (q1 - q0)`. Handles degenerate (point) segments and parallel ones.
pub fn closest_segment_params(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> (f64, f64) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let eps = 1e-30;
    if a <= eps && e <= eps {
        return (0.0, 0.0);
    }
    if a <= eps {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(&r);
    if e <= eps {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-14 * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// The smaller of two numbers, as nalgebra's componentwise `inf` takes it (`a` when they compare equal).
#[inline(always)]
fn lower(a: f64, b: f64) -> f64 {
    if a <= b { a } else { b }
}

/// The larger of two numbers, as nalgebra's componentwise `sup` takes it (`a` when they compare equal).
#[inline(always)]
fn upper(a: f64, b: f64) -> f64 {
    if a >= b { a } else { b }
}

/// Axis-aligned bounding box, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner, m.
    pub min: Vector3<f64>,
    /// Upper corner, m.
    pub max: Vector3<f64>,
}

impl Aabb {
    /// The empty box (contains nothing; the identity of [`Aabb::merge`]).
    pub fn empty() -> Self {
        Self { min: Vector3::repeat(f64::INFINITY), max: Vector3::repeat(f64::NEG_INFINITY) }
    }

    /// Box around a segment, grown by `margin` (m) on every side.
    #[inline]
    pub fn of_segment(a: &Vector3<f64>, b: &Vector3<f64>, margin: f64) -> Self {
        let m = -margin;
        Self {
            min: Vector3::new(lower(a.x, b.x) + m, lower(a.y, b.y) + m, lower(a.z, b.z) + m),
            max: Vector3::new(upper(a.x, b.x) + margin, upper(a.y, b.y) + margin, upper(a.z, b.z) + margin),
        }
    }

    /// Smallest box containing both.
    #[inline]
    pub fn merge(&self, o: &Aabb) -> Self {
        let (a, b) = (&self.min, &o.min);
        let (c, d) = (&self.max, &o.max);
        Self {
            min: Vector3::new(lower(a.x, b.x), lower(a.y, b.y), lower(a.z, b.z)),
            max: Vector3::new(upper(c.x, d.x), upper(c.y, d.y), upper(c.z, d.z)),
        }
    }

    /// Whether the boxes overlap (touching counts).
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        let (a, b) = (&self.min, &self.max);
        let (c, d) = (&o.min, &o.max);
        (a.x <= d.x && c.x <= b.x) && (a.y <= d.y && c.y <= b.y) && (a.z <= d.z && c.z <= b.z)
    }

    /// Centre, m.
    pub fn center(&self) -> Vector3<f64> {
        (self.min + self.max) * 0.5
    }

    /// Distance from `p` to the box, m (0 inside or on it).
    pub fn distance_to(&self, p: &Vector3<f64>) -> f64 {
        (self.min - p).sup(&(p - self.max)).sup(&Vector3::zeros()).norm()
    }

    /// Whether the segment from `a` to `b` (m) has a point in the box (touching counts): the slab test, the
    /// segment's parameter range clipped by each axis's pair of planes.
    pub fn meets_segment(&self, a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        for i in 0..3 {
            let d = b[i] - a[i];
            if d == 0.0 {
                if a[i] < self.min[i] || a[i] > self.max[i] {
                    return false;
                }
                continue;
            }
            let (u, v) = ((self.min[i] - a[i]) / d, (self.max[i] - a[i]) / d);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
            if t0 > t1 {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_distance_to_a_box_is_zero_inside_and_euclidean_outside() {
        // By hand: beside a face, off an edge, off a corner, inside; exact to 1e-15 m.
        let bx = Aabb { min: Vector3::new(0.0, 0.0, 0.0), max: Vector3::new(1.0, 2.0, 3.0) };
        assert_eq!(bx.distance_to(&Vector3::new(0.5, 1.0, 1.0)), 0.0);
        assert!((bx.distance_to(&Vector3::new(-0.5, 1.0, 1.0)) - 0.5).abs() < 1e-15);
        assert!((bx.distance_to(&Vector3::new(4.0, 6.0, 1.0)) - 5.0).abs() < 1e-15);
        assert!((bx.distance_to(&Vector3::new(-1.0, -2.0, 5.0)) - 3.0).abs() < 1e-15);
    }

    #[test]
    fn a_segment_meets_a_box_where_a_sampled_point_of_it_lies_inside() {
        // Against an independent answer: 2,001 points sampled along each of 900 segments (through the box, beside
        // it, ending inside, parallel to a face, degenerate). The slab test must say "meets" where a sample lies
        // in the box shrunk by 1 mm (of a 1 m box) and "misses" where none lies in the box grown by 1 mm; the few
        // segments that graze it within that margin are counted, not judged.
        let bx = Aabb { min: Vector3::new(0.0, 0.0, 0.0), max: Vector3::new(1.0, 1.0, 1.0) };
        let sampled = |a: &Vector3<f64>, b: &Vector3<f64>, grow: f64| {
            (0..=2000).any(|i| {
                let p = a + (b - a) * (i as f64 / 2000.0);
                (0..3).all(|k| p[k] >= bx.min[k] - grow && p[k] <= bx.max[k] + grow)
            })
        };
        let grid: Vec<f64> = (-10..20).map(|k| 0.05 + 0.1 * k as f64).collect();
        let (mut met, mut missed, mut grazing) = (0, 0, 0);
        for (n, &x) in grid.iter().enumerate() {
            let a = Vector3::new(x, grid[(n * 7) % grid.len()], grid[(n * 13) % grid.len()]);
            for (m, &y) in grid.iter().enumerate() {
                let b = if m % 5 == 0 { a } else { Vector3::new(grid[(m * 3) % grid.len()], y, grid[(m * 11 + n) % grid.len()]) };
                if sampled(&a, &b, -1e-3) {
                    assert!(bx.meets_segment(&a, &b), "{a:?} to {b:?} passes through the box");
                    met += 1;
                } else if !sampled(&a, &b, 1e-3) {
                    assert!(!bx.meets_segment(&a, &b), "{a:?} to {b:?} passes beside the box");
                    missed += 1;
                } else {
                    grazing += 1;
                }
            }
        }
        assert!(met > 50 && missed > 50 && grazing < 30, "{met} meet, {missed} miss, {grazing} graze of 900");
    }

    fn brute(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> f64 {
        let n = 400;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                let p = p0 + (p1 - p0) * (i as f64 / n as f64);
                let q = q0 + (q1 - q0) * (j as f64 / n as f64);
                best = best.min((p - q).norm());
            }
        }
        best
    }

    #[test]
    fn closest_points_match_brute_force() {
        // A 401 x 401 grid search bounds the true distance from above within (segment length / 400);
        // the analytic distance must not exceed it and be within 1e-2 of the segments' length of it.
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for case in 0..200 {
            let mut v = || Vector3::new(rnd(), rnd(), rnd());
            let (p0, mut p1, q0, mut q1) = (v(), v(), v(), v());
            if case % 10 == 0 {
                q1 = q0 + (p1 - p0) * 0.7; // parallel
            }
            if case % 17 == 0 {
                p1 = p0; // a point
            }
            let (s, t) = closest_segment_params(&p0, &p1, &q0, &q1);
            let d = ((p0 + (p1 - p0) * s) - (q0 + (q1 - q0) * t)).norm();
            let b = brute(&p0, &p1, &q0, &q1);
            assert!(d <= b + 1e-12, "case {case}: {d} > {b}");
            assert!(b - d < 2e-2, "case {case}: {d} vs {b}");
        }
    }

    #[test]
    fn boxes_overlap_and_merge() {
        let a = Aabb::of_segment(&Vector3::new(0.0, 0.0, 0.0), &Vector3::new(1.0, 1.0, 0.0), 0.1);
        let b = Aabb::of_segment(&Vector3::new(1.05, 0.5, 0.0), &Vector3::new(2.0, 0.5, 0.0), 0.0);
        let c = Aabb::of_segment(&Vector3::new(1.2, 0.5, 0.0), &Vector3::new(2.0, 0.5, 0.0), 0.0);
        assert!(a.overlaps(&b) && !a.overlaps(&c));
        let m = a.merge(&c);
        assert_eq!(m.min, Vector3::new(-0.1, -0.1, -0.1));
        assert_eq!(m.max, Vector3::new(2.0, 1.1, 0.1));
        assert!(Aabb::empty().merge(&a) == a);
    }
}
