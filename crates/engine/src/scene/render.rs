//! Where the render strands are now: the one Rust law of the render hair following the lattice and the
//! local strands, used by the `[[action]]` scenarios' output and the server's save. The viewer's vertex
//! shader (`web/src/shaders/hairDeform.glsl.ts`, steps 2 and 3: FFD of the rest position, then the
//! guides' displacement interpolated along the guide) computes the same on the GPU; its wet clumping,
//! curl helix and body push-out (steps 1, 4, 5) are display effects that are not saved.

use super::{ffd_map, Scene};
use nalgebra::{Point3, Vector3};

/// The local strands' displacements the render strands follow (what the haptic snapshot carries:
/// `HapticSnapshot::active` and `displacement`).
#[derive(Debug, Clone, Copy, Default)]
pub struct GuideDisplacements<'a> {
    /// Active guides (indices into the scene's guides).
    pub active: &'a [u32],
    /// Displacement of each active guide's samples from its reference through the lattice, m
    /// (`active.len() x samples` entries, guide after guide).
    pub displacement: &'a [Vector3<f64>],
    /// Samples per guide (`Scene::samples`).
    pub samples: usize,
}

impl Scene {
    /// Vertex `j` of render strand `i` now, m (head frame): its rest position through the lattice of node
    /// positions `nodes` (the FFD, [`ffd_map`]), plus, for each of its guides that is active, the guide's
    /// displacement at the fraction `span_i j / (V - 1)` of its length (linear between samples) times the
    /// strand's weight for that guide.
    pub fn render_vertex(&self, nodes: &[Point3<f64>], guides: &GuideDisplacements, i: usize, j: usize) -> Vector3<f64> {
        let r = &self.render;
        let nv = r.vertices_per_strand;
        let p = r.positions[i * nv + j];
        let mut q = ffd_map(&self.lattice.ffd, nodes, &Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        let (k, s) = (r.guides_per_strand, guides.samples);
        if guides.active.is_empty() || s == 0 {
            return q;
        }
        let u = r.span[i] as f64 * j as f64 / (nv - 1).max(1) as f64;
        for m in 0..k {
            let g = r.guide[i * k + m];
            if let Some(a) = guides.active.iter().position(|&x| x == g) {
                let x = u * (s - 1) as f64;
                let lo = (x.floor() as usize).min(s - 1);
                let hi = (lo + 1).min(s - 1);
                let f = x - lo as f64;
                let d = guides.displacement[a * s + lo] * (1.0 - f) + guides.displacement[a * s + hi] * f;
                q += d * r.weight[i * k + m] as f64;
            }
        }
        q
    }

    /// Every render strand now ([`Scene::render_vertex`]), each cut to its kept length `kept[i]` (vertex
    /// units: `V - 1` uncut, `k + f` ends on the straight segment from vertex k to k + 1 at the fraction f, where
    /// the global layer cut it; a missing entry: uncut), as f32 curves (m). Strands left with fewer than two
    /// points are left out. Lattice `nodes` of the wrong count are taken as the rest lattice.
    pub fn render_curves(&self, nodes: &[Point3<f64>], kept: &[f64], guides: &GuideDisplacements) -> hairstyle::HairCurves {
        let rest;
        let nodes = if nodes.len() == self.lattice.node_count() {
            nodes
        } else {
            rest = self.lattice.rest.clone();
            &rest
        };
        let nv = self.render.vertices_per_strand;
        let last = nv.saturating_sub(1) as f64;
        let f32s = |q: Vector3<f64>| [q.x as f32, q.y as f32, q.z as f32];
        let strands = (0..self.render.strands())
            .map(|i| {
                let k = kept.get(i).map_or(last, |&k| if k.is_finite() { k.clamp(0.0, last) } else { last });
                let whole = k.floor() as usize;
                let mut s: Vec<[f32; 3]> = (0..=whole).map(|j| f32s(self.render_vertex(nodes, guides, i, j))).collect();
                let frac = k - whole as f64;
                if frac > 0.0 && whole + 1 < nv {
                    let (a, b) = (self.render_vertex(nodes, guides, i, whole), self.render_vertex(nodes, guides, i, whole + 1));
                    s.push(f32s(a * (1.0 - frac) + b * frac));
                }
                s
            })
            .filter(|s| s.len() >= 2)
            .collect();
        hairstyle::HairCurves::from_strands(strands)
    }

    /// Kept lengths (vertex units, [`Scene::render_curves`]) of the viewer's kept points (`kept[i]` points
    /// of strand i, `LatticeSnapshot::kept`).
    pub fn kept_lengths_of_points(kept: &[u16]) -> Vec<f64> {
        kept.iter().map(|&k| k as f64 - 1.0).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::small_scene;

    #[test]
    fn render_strands_follow_the_lattice_and_the_active_guides() {
        // At rest and without active guides every vertex is its rest position (to 1e-9 m, the FFD's
        // round trip); a uniform lattice shift moves every vertex by it; an active guide displaced by a
        // constant vector moves the strands bound to it by their weight for it times that vector (1e-9 m).
        let s = small_scene();
        let none = GuideDisplacements::default();
        let rest = s.lattice.rest.clone();
        let p0 = s.render.positions[5 * s.render.vertices_per_strand + 3];
        let v = s.render_vertex(&rest, &none, 5, 3);
        assert!((v - Vector3::new(p0[0] as f64, p0[1] as f64, p0[2] as f64)).norm() < 1e-7, "{v:?} vs {p0:?}");
        let shift = Vector3::new(0.01, -0.02, 0.005);
        let moved: Vec<Point3<f64>> = rest.iter().map(|p| p + shift).collect();
        assert!((s.render_vertex(&moved, &none, 5, 3) - v - shift).norm() < 1e-9);
        let k = s.render.guides_per_strand;
        let g = s.render.guide[5 * k];
        let n = s.samples();
        let d = Vector3::new(0.0, 0.03, 0.0);
        let disp = vec![d; n];
        let active = [g];
        let with = GuideDisplacements { active: &active, displacement: &disp, samples: n };
        let want: f64 = (0..k).filter(|&m| s.render.guide[5 * k + m] == g).map(|m| s.render.weight[5 * k + m] as f64).sum();
        let got = s.render_vertex(&rest, &with, 5, 3) - v;
        assert!(want > 0.0 && (got - d * want).norm() < 1e-9, "{got:?} vs {want} x {d:?}");
        // Kept points cut the curves; strands with fewer than 2 points are left out.
        let mut kept = vec![s.render.vertices_per_strand as u16; s.render.strands()];
        kept[0] = 3;
        kept[1] = 1;
        let c = s.render_curves(&rest, &Scene::kept_lengths_of_points(&kept), &none);
        assert_eq!(c.strands.len(), s.render.strands() - 1);
        assert_eq!(c.strands[0].len(), 3);
        // A fractional kept length ends between two vertices, on the straight segment.
        let mut k = vec![(s.render.vertices_per_strand - 1) as f64; s.render.strands()];
        k[0] = 2.25;
        let c = s.render_curves(&rest, &k, &none);
        let (a, b) = (s.render_vertex(&rest, &none, 0, 2), s.render_vertex(&rest, &none, 0, 3));
        let e = a * 0.75 + b * 0.25;
        assert_eq!(c.strands[0].len(), 4);
        assert!((0..3).all(|x| (c.strands[0][3][x] as f64 - e[x]).abs() < 1e-7));
    }
}
