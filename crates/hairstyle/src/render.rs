//! Render strands bound to guides: the binding law ([`nearest_guides`]: the nearest guides by root,
//! inverse-square weights) and the strands following their guides' centrelines ([`RenderStrands`]).

use crate::error::GenerateError;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// The render strands: polylines with a fixed vertex count, bound to guides.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RenderStrands {
    /// Vertices per strand (root first).
    pub vertices_per_strand: usize,
    /// Guide centreline samples the binding refers to (see [`RenderStrands::follow`]).
    pub guide_samples: usize,
    /// Guides each strand follows.
    pub guides_per_strand: usize,
    /// Vertex positions, m (head frame): strand i is `positions[i V .. (i + 1) V]`.
    pub positions: Vec<[f32; 3]>,
    /// Guide indices, `guides_per_strand` per strand.
    pub guide_indices: Vec<u32>,
    /// Guide weights (summing to 1 per strand), `guides_per_strand` per strand.
    pub guide_weights: Vec<f32>,
    /// Fraction of the guide's length each strand spans (<= 1), one per strand.
    pub span: Vec<f32>,
    /// Per-vertex offset from the weighted guide point, m; one per vertex.
    pub offsets: Vec<[f32; 3]>,
}

impl RenderStrands {
    /// Number of strands.
    pub fn len(&self) -> usize {
        self.span.len()
    }

    /// True if there are no strands.
    pub fn is_empty(&self) -> bool {
        self.span.is_empty()
    }

    /// The vertices of strand `i`.
    pub fn strand(&self, i: usize) -> &[[f32; 3]] {
        let v = self.vertices_per_strand;
        &self.positions[i * v..(i + 1) * v]
    }

    /// Weighted guide point (the wisp axis) of vertex `j` of strand `i`, given guide centreline
    /// samples `guides` (each with `guide_samples` points, m).
    pub fn axis_point(&self, guides: &[Vec<Point3<f64>>], i: usize, j: usize) -> Point3<f64> {
        let k = self.guides_per_strand;
        let u = self.span[i] as f64 * j as f64 / (self.vertices_per_strand - 1) as f64;
        let mut p = Vector3::zeros();
        for g in 0..k {
            let w = self.guide_weights[i * k + g] as f64;
            p += w * lerp_samples(&guides[self.guide_indices[i * k + g] as usize], u).coords;
        }
        Point3::from(p)
    }

    /// Vertex positions (m) of every strand when the guides' centrelines are `guides` (each
    /// `guide_samples` points, root to tip): `sum_k w_k G_k(u_j) + offset_j`. Written into `out`
    /// (resized). Parallel (rayon). Errors if a guide has the wrong number of samples or an
    /// index is out of range.
    pub fn follow(
        &self,
        guides: &[Vec<Point3<f64>>],
        out: &mut Vec<[f32; 3]>,
    ) -> Result<(), GenerateError> {
        if let Some((g, s)) = guides
            .iter()
            .enumerate()
            .find(|(_, s)| s.len() != self.guide_samples)
        {
            return Err(GenerateError::InvalidParameter {
                field: "guides",
                reason: format!(
                    "guide {g} has {} samples, expected {}",
                    s.len(),
                    self.guide_samples
                ),
            });
        }
        if let Some(&bad) = self
            .guide_indices
            .iter()
            .find(|&&i| i as usize >= guides.len())
        {
            return Err(GenerateError::InvalidParameter {
                field: "guides",
                reason: format!(
                    "binding refers to guide {bad} but {} guides were given",
                    guides.len()
                ),
            });
        }
        let v = self.vertices_per_strand;
        out.resize(self.positions.len(), [0.0; 3]);
        out.par_chunks_mut(v).enumerate().for_each(|(i, strand)| {
            for (j, o) in strand.iter_mut().enumerate() {
                let a = self.axis_point(guides, i, j);
                let off = self.offsets[i * v + j];
                *o = [
                    (a.x + off[0] as f64) as f32,
                    (a.y + off[1] as f64) as f32,
                    (a.z + off[2] as f64) as f32,
                ];
            }
        });
        Ok(())
    }
}

/// Linear interpolation in evenly spaced samples (at least two) at the fraction `u` in [0, 1] of the length
/// (`strand::samples::between`).
pub(crate) fn lerp_samples(s: &[Point3<f64>], u: f64) -> Point3<f64> {
    let (i, t) = strand::samples::between(s.len(), u);
    s[i] + t * (s[i + 1] - s[i])
}

/// The guide binding of a render strand rooted at `p` (m): the `k` guides whose roots (`roots`, m)
/// are nearest, nearest first, with Shepard inverse-square weights 1/(d + 1 mm)^2 (d the root
/// distance, m; the 1 mm keeps a strand on a guide's root finite) normalised to sum to 1. The one
/// binding law of generated hairstyles and of loaded strands (`engine::scene::Scene::from_curves`).
pub fn nearest_guides(roots: &[Point3<f64>], p: &Point3<f64>, k: usize) -> (Vec<u32>, Vec<f32>) {
    nearest_guides_where(roots, p, k, &|_| true)
}

/// [`nearest_guides`] among the guides `g` for which `accept(g)` holds; among all if fewer than `k` do.
/// Generated hairstyles accept the guides combed the same way as the strand (no blending across a
/// parting, where guides on either side leave in opposite directions).
pub fn nearest_guides_where(roots: &[Point3<f64>], p: &Point3<f64>, k: usize, accept: &dyn Fn(usize) -> bool) -> (Vec<u32>, Vec<f32>) {
    if (0..roots.len()).filter(|&g| accept(g)).take(k).count() < k {
        return nearest_guides_where(roots, p, k, &|_| true);
    }
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(k + 1);
    for (g, r) in roots.iter().enumerate() {
        if !accept(g) {
            continue;
        }
        let d = (r - p).norm_squared();
        if best.len() < k || d < best[best.len() - 1].0 {
            let at = best.partition_point(|&(x, _)| x <= d);
            best.insert(at, (d, g));
            best.truncate(k);
        }
    }
    let w: Vec<f64> = best
        .iter()
        .map(|&(d, _)| 1.0 / (d.sqrt() + 1e-3).powi(2))
        .collect();
    let total: f64 = w.iter().sum();
    (
        best.iter().map(|&(_, g)| g as u32).collect(),
        w.iter().map(|x| (x / total) as f32).collect(),
    )
}

