//! Nearest point on the scalp: the scalp sampled evenly ([`Head::scalp_even`]) with outward
//! normals, in a k-d tree for exact nearest-sample queries.

use crate::head::{Head, ScalpPoint};
use nalgebra::{Point3, Vector3};

/// The scalp as evenly spread samples in a k-d tree (head frame, m).
#[derive(Debug, Clone)]
pub struct ScalpIndex {
    points: Vec<ScalpPoint>,
    /// Mean spacing of the samples, m.
    pub spacing: f64,
    /// The samples' indices in k-d order: the median of each range splits it on `axis[range mid]`.
    tree: Vec<u32>,
    axis: Vec<u8>,
    /// Bounding sphere of the samples (centre, radius), m.
    centre: Point3<f64>,
    radius: f64,
}

/// Points further than this outside the samples' bounding sphere are matched through their
/// radial projection onto it (m).
const FAR: f64 = 0.02;

/// The nearest scalp sample to a point, and the point's distance to the scalp.
#[derive(Debug, Clone, Copy)]
pub struct Nearest {
    /// The sample.
    pub sample: ScalpPoint,
    /// Distance to the scalp, m: along the sample's normal when the point lies over the sample's
    /// patch (tangential offset within the sample spacing), else to the sample itself.
    pub distance: f64,
    /// The surface correspondence: the point projected onto the sample's tangent plane when it
    /// lies over the sample's patch, else the sample.
    pub on_surface: Point3<f64>,
}

impl ScalpIndex {
    /// `n` scalp samples of `head` in a k-d tree.
    pub fn new(head: &Head, n: usize) -> Self {
        let points = head.scalp_even(n.max(16));
        // area of the cap seen from the centre, estimated as 2 pi r^2 (1 - cos theta)
        let r = head.params.head_radius;
        let area = std::f64::consts::TAU * r * r * (1.0 - head.scalp.half_angle.cos());
        let spacing = (area / points.len() as f64).sqrt();
        let mut tree: Vec<u32> = (0..points.len() as u32).collect();
        let mut axis = vec![0u8; points.len()];
        fn build(pts: &[ScalpPoint], idx: &mut [u32], axis: &mut [u8]) {
            if idx.len() <= 1 {
                return;
            }
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &i in idx.iter() {
                for a in 0..3 {
                    lo[a] = lo[a].min(pts[i as usize].position[a]);
                    hi[a] = hi[a].max(pts[i as usize].position[a]);
                }
            }
            let a = (0..3).max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y]))).unwrap();
            let m = idx.len() / 2;
            idx.select_nth_unstable_by(m, |&x, &y| pts[x as usize].position[a].total_cmp(&pts[y as usize].position[a]));
            axis[m] = a as u8;
            let (left, right) = idx.split_at_mut(m);
            let (al, ar) = axis.split_at_mut(m);
            build(pts, left, al);
            build(pts, &mut right[1..], &mut ar[1..]);
        }
        build(&points, &mut tree, &mut axis);
        let centre = Point3::from(points.iter().fold(Vector3::zeros(), |s, p| s + p.position.coords) / points.len() as f64);
        let radius = points.iter().map(|p| (p.position - centre).norm()).fold(0.0, f64::max);
        Self { points, spacing, tree, axis, centre, radius }
    }

    /// The samples.
    pub fn samples(&self) -> &[ScalpPoint] {
        &self.points
    }

    fn search(&self, lo: usize, hi: usize, p: &Point3<f64>, best: &mut (usize, f64)) {
        if lo >= hi {
            return;
        }
        let m = lo + (hi - lo) / 2;
        let i = self.tree[m] as usize;
        let q = &self.points[i].position;
        let d2 = (q - p).norm_squared();
        if d2 < best.1 {
            *best = (i, d2);
        }
        if hi - lo == 1 {
            return;
        }
        let a = self.axis[m] as usize;
        let diff = p[a] - q[a];
        let (near, far) = if diff < 0.0 { ((lo, m), (m + 1, hi)) } else { ((m + 1, hi), (lo, m)) };
        self.search(near.0, near.1, p, best);
        if diff * diff < best.1 {
            self.search(far.0, far.1, p, best);
        }
    }

    /// The nearest sample to `p` (m) and `p`'s distance to the scalp. For a point more than 2 cm
    /// outside the samples' bounding sphere, the sample nearest to its radial projection onto
    /// that sphere (the distance is then an upper bound, close for far points).
    pub fn nearest(&self, p: &Point3<f64>) -> Nearest {
        let mut best = (0usize, f64::INFINITY);
        let r = p - self.centre;
        let q = if r.norm() > self.radius + FAR { self.centre + r * (self.radius / r.norm()) } else { *p };
        self.search(0, self.tree.len(), &q, &mut best);
        let best = best.0;
        let sample = self.points[best];
        let off: Vector3<f64> = p - sample.position;
        let normal_part = off.dot(&sample.normal);
        let tangential = (off - normal_part * sample.normal).norm();
        if tangential <= self.spacing {
            Nearest { sample, distance: normal_part.abs(), on_surface: p - normal_part * sample.normal }
        } else {
            Nearest { sample, distance: off.norm(), on_surface: sample.position }
        }
    }
}
