//! Follow strands (issue 34): drawn strands added around each strand of a sparse file, as TressFX generates
//! them around its guide strands at load, so that a file of a few hundred guide strands looks like a full
//! head.
//!
//! Follow strand `f` of a strand with vertices `v_j` (root `v_0`, `j = 0..V-1`, `u_j = j / (V - 1)`):
//! 1. Root (strands rooted on the scalp only; a loose strand has none): `v_0` moved by a random offset `o`
//!    uniform in the disk of radius `r` in the scalp's tangent plane, `r` the radius of each
//!    strand's share of the scalp, `sqrt(A / (pi n))` (A the scalp's area, n the strands rooted on it); the
//!    moved root put back on the scalp at the strand root's height over it ([`Head::project`]).
//! 2. Shape: `v_j + d + o tip_spread u_j`, d the root's displacement: the strand's own shape, fanning out
//!    towards the tip by [`FollowParams::tip_spread`] times the root offset (TressFX's tip separation).
//! 3. Every vertex but the root kept [`crate::generate::RENDER_GAP`] outside the body
//!    ([`crate::generate::keep_outside`]).
//!
//! They are render strands like the file's: bound to the guides by the one binding law
//! ([`crate::render::nearest_guides`]) by whoever builds the scene.

use crate::fit::ScalpIndex;
use crate::generate::keep_outside;
use crate::head::Head;
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Parameters of the follow strands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowParams {
    /// Follow strands per strand of the file. Default 0 (the scene chooses: `engine::scene::SceneOptions::follow_strands`).
    pub per_strand: usize,
    /// How far apart follow strands' tips are relative to their roots: the offset from their strand grows
    /// from `o` at the root to `(1 + tip_spread) o` at the tip (dimensionless; a look, not a measurement).
    /// Default 1.
    pub tip_spread: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for FollowParams {
    fn default() -> Self {
        Self { per_strand: 0, tip_spread: 1.0, seed: 1 }
    }
}

/// The follow strands of `strands` (m, head frame, root first, each at least one point) on `head`:
/// `p.per_strand` per strand rooted on the scalp, strand after strand (none around a loose strand), each with as many vertices as its strand (see the module
/// docs). `scalp` tells which strands are rooted on the scalp (within `rooted_distance`, m) and the scalp's
/// area.
pub fn follow_strands(strands: &[Vec<[f32; 3]>], head: &Head, scalp: &ScalpIndex, rooted_distance: f64, p: &FollowParams) -> Vec<Vec<[f32; 3]>> {
    if p.per_strand == 0 || strands.is_empty() {
        return Vec::new();
    }
    let v3 = |q: &[f32; 3]| Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64);
    let near: Vec<_> = strands.par_iter().map(|s| scalp.nearest(&Point3::from(v3(&s[0])))).collect();
    let rooted = near.iter().filter(|n| n.distance <= rooted_distance).count().max(1);
    let area = scalp.spacing * scalp.spacing * scalp.samples().len() as f64;
    let radius = (area / (std::f64::consts::PI * rooted as f64)).sqrt();
    strands
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, s)| {
            let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
            rng.set_stream(i as u64);
            let points: Vec<Vector3<f64>> = s.iter().map(v3).collect();
            let root = points[0];
            let on_scalp = near[i].distance <= rooted_distance;
            let across = near[i].sample.normal;
            let a = if across.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
            let e1 = across.cross(&a).normalize();
            let e2 = across.cross(&e1);
            let height = head.signed_distance(&Point3::from(root));
            let n = points.len();
            (0..if on_scalp { p.per_strand } else { 0 })
                .map(|_| {
                    let (rho, phi) = (radius * rng.random::<f64>().sqrt(), std::f64::consts::TAU * rng.random::<f64>());
                    let o = rho * (phi.cos() * e1 + phi.sin() * e2);
                    let mut moved = root + o;
                    if let (Some(q), Some(nrm)) = (head.project(&Point3::from(moved)), head.normal(&Point3::from(moved))) {
                        moved = q.coords + nrm * height;
                    }
                    let d = moved - root;
                    let mut path: Vec<Point3<f64>> = points.iter().enumerate().map(|(j, q)| Point3::from(q + d + o * (p.tip_spread * j as f64 / (n - 1).max(1) as f64))).collect();
                    keep_outside(head, &mut path);
                    path.iter().map(|q| [q.x as f32, q.y as f32, q.z as f32]).collect::<Vec<_>>()
                })
                .collect::<Vec<_>>()
        })
        .collect()
}
