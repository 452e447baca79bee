//! Where the render strands are now: the one Rust law of the render hair following the head, the lattice and
//! the local strands, used by the `[[action]]` scenarios' output and the server's save. The viewer's vertex
//! shader (`web/src/shaders/hairDeform.glsl.ts`, steps 2 and 3: the strand carried by the head and the
//! lattice, [`carry_strand`], then the guides' displacement interpolated along the guide) computes the same on
//! the GPU; its wet clumping, curl helix and body push-out (steps 1, 4, 5) are display effects that are not
//! saved.

use super::{carry_strand, root_hold_weight, Scene};
use nalgebra::{Isometry3, Point3, Vector3};

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
    /// Rest arc length of vertex `j` of render strand `i` from the strand's root, m (the sum of its rest
    /// segments' lengths, in f64 of the f32 positions, as the viewer sums them).
    pub fn render_arc_length(&self, i: usize, j: usize) -> f64 {
        let nv = self.render.vertices_per_strand;
        let p = |k: usize| Vector3::from(self.render.positions[i * nv + k]).cast::<f64>();
        (1..=j.min(nv.saturating_sub(1))).map(|k| (p(k) - p(k - 1)).norm()).sum()
    }

    /// Render strand `i` carried by the head at `head` and the lattice of node positions `nodes` now, without
    /// the local strands: the one law of the carried hair ([`carry_strand`]; each vertex's lattice weight from
    /// its rest arc length, [`root_hold_weight`]), m (world).
    pub fn render_strand(&self, nodes: &[Point3<f64>], head: &Isometry3<f64>, i: usize) -> Vec<Vector3<f64>> {
        let nv = self.render.vertices_per_strand;
        let rest: Vec<Vector3<f64>> = self.render.positions[i * nv..(i + 1) * nv].iter().map(|p| Vector3::from(*p).cast::<f64>()).collect();
        let mut arc = 0.0;
        let weights: Vec<f64> = (0..nv)
            .map(|j| {
                if j > 0 {
                    arc += (rest[j] - rest[j - 1]).norm();
                }
                root_hold_weight(arc, self.root_hold)
            })
            .collect();
        let mut out = Vec::with_capacity(nv);
        carry_strand(&self.lattice.ffd, nodes, head, &rest, &weights, &mut out);
        out
    }

    /// Vertex `j` of render strand `i` now, m (world): the strand carried by the head at `head` and the lattice
    /// of node positions `nodes` ([`Scene::render_strand`]), plus, for each of its guides that is active, the
    /// guide's displacement at the fraction `span_i j / (V - 1)` of its length (linear between samples) times
    /// the strand's weight for that guide.
    pub fn render_vertex(&self, nodes: &[Point3<f64>], head: &Isometry3<f64>, guides: &GuideDisplacements, i: usize, j: usize) -> Vector3<f64> {
        self.render_strand(nodes, head, i)[j] + self.guide_offset(guides, i, j)
    }

    /// The active guides' displacement of vertex `j` of render strand `i` (see [`Scene::render_vertex`]), m.
    fn guide_offset(&self, guides: &GuideDisplacements, i: usize, j: usize) -> Vector3<f64> {
        let r = &self.render;
        let nv = r.vertices_per_strand;
        let mut q = Vector3::zeros();
        let (k, s) = (r.guides_per_strand, guides.samples);
        if guides.active.is_empty() || s == 0 {
            return q;
        }
        let u = r.span[i] as f64 * j as f64 / (nv - 1).max(1) as f64;
        for m in 0..k {
            let g = r.guide[i * k + m];
            if let Some(a) = guides.active.iter().position(|&x| x == g) {
                let d = strand::samples::lerp(&guides.displacement[a * s..(a + 1) * s], u);
                q += d * r.weight[i * k + m] as f64;
            }
        }
        q
    }

    /// Every render strand now ([`Scene::render_vertex`]), each cut to its kept length `kept[i]` (vertex
    /// units: `V - 1` uncut, `k + f` ends on the straight segment from vertex k to k + 1 at the fraction f, where
    /// the global layer cut it; a missing entry: uncut), as f32 curves (m). Strands left with fewer than two
    /// points are left out. Lattice `nodes` of the wrong count are taken as the rest lattice.
    pub fn render_curves(&self, nodes: &[Point3<f64>], head: &Isometry3<f64>, kept: &[f64], guides: &GuideDisplacements) -> hairstyle::HairCurves {
        let rest: Vec<Point3<f64>>;
        let nodes = if nodes.len() == self.lattice.node_count() {
            nodes
        } else {
            rest = self.lattice.rest.iter().map(|p| head * p).collect();
            &rest
        };
        let nv = self.render.vertices_per_strand;
        let last = nv.saturating_sub(1) as f64;
        let f32s = |q: Vector3<f64>| [q.x as f32, q.y as f32, q.z as f32];
        let strands = (0..self.render.strands())
            .map(|i| {
                let k = kept.get(i).map_or(last, |&k| if k.is_finite() { k.clamp(0.0, last) } else { last });
                let whole = k.floor() as usize;
                let strand = self.render_strand(nodes, head, i);
                let vertex = |j: usize| strand[j] + self.guide_offset(guides, i, j);
                let mut s: Vec<[f32; 3]> = (0..=whole).map(|j| f32s(vertex(j))).collect();
                let frac = k - whole as f64;
                if frac > 0.0 && whole + 1 < nv {
                    let (a, b) = (vertex(whole), vertex(whole + 1));
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
    fn render_strands_keep_their_roots_and_lengths_follow_the_lattice_beyond_and_the_active_guides() {
        // At rest and without active guides every vertex is its rest position (to 1e-7 m, the FFD's round trip
        // in f32). Under a uniform lattice shift of 2.3 cm (a 2 cm cell would move the roots by it through the
        // FFD alone) every root stays where the head holds it, every rest segment keeps its length (1e-9 m) and
        // the tips move with the shift (most of it along it). The head turned and moved with the lattice carried
        // rigidly moves every vertex rigidly (1e-9 m); an active guide displaced by a constant vector moves the
        // strands bound to it by their weight for it times that vector (1e-9 m).
        let s = small_scene();
        let id = Isometry3::identity();
        let none = GuideDisplacements::default();
        let rest = s.lattice.rest.clone();
        let nv = s.render.vertices_per_strand;
        let far = nv - 1;
        let p0 = s.render.positions[5 * nv + far];
        let v = s.render_vertex(&rest, &id, &none, 5, far);
        assert!((v - Vector3::new(p0[0] as f64, p0[1] as f64, p0[2] as f64)).norm() < 1e-7, "{v:?} vs {p0:?}");
        let shift = Vector3::new(0.01, -0.02, 0.005);
        let moved: Vec<Point3<f64>> = rest.iter().map(|p| p + shift).collect();
        for i in 0..s.render.strands() {
            let x = s.render_strand(&moved, &id, i);
            let r: Vec<Vector3<f64>> = (0..nv).map(|j| Vector3::from(s.render.positions[i * nv + j]).cast::<f64>()).collect();
            assert!((x[0] - r[0]).norm() < 1e-12, "root of strand {i} left the head");
            for j in 1..nv {
                assert!(((x[j] - x[j - 1]).norm() - (r[j] - r[j - 1]).norm()).abs() < 1e-9, "strand {i} segment {j} changed its length");
            }
            let tip = x[nv - 1] - r[nv - 1];
            assert!(tip.dot(&shift) > 0.5 * shift.norm_squared(), "strand {i}: tip moved {tip:?} under the shift {shift:?}");
        }
        let head = Isometry3::new(Vector3::new(0.01, 0.0, -0.02), Vector3::new(0.1, -0.3, 0.2));
        let carried: Vec<Point3<f64>> = rest.iter().map(|p| head * p).collect();
        for j in 0..nv {
            let r = Point3::from(Vector3::from(s.render.positions[5 * nv + j]).cast::<f64>());
            assert!((s.render_vertex(&carried, &head, &none, 5, j) - (head * r).coords).norm() < 1e-9, "vertex {j}");
        }
        let k = s.render.guides_per_strand;
        let g = s.render.guide[5 * k];
        let n = s.samples();
        let d = Vector3::new(0.0, 0.03, 0.0);
        let disp = vec![d; n];
        let active = [g];
        let with = GuideDisplacements { active: &active, displacement: &disp, samples: n };
        let want: f64 = (0..k).filter(|&m| s.render.guide[5 * k + m] == g).map(|m| s.render.weight[5 * k + m] as f64).sum();
        let got = s.render_vertex(&rest, &id, &with, 5, far) - v;
        assert!(want > 0.0 && (got - d * want).norm() < 1e-9, "{got:?} vs {want} x {d:?}");
        // Kept points cut the curves; strands with fewer than 2 points are left out.
        let mut kept = vec![s.render.vertices_per_strand as u16; s.render.strands()];
        kept[0] = 3;
        kept[1] = 1;
        let c = s.render_curves(&rest, &id, &Scene::kept_lengths_of_points(&kept), &none);
        assert_eq!(c.strands.len(), s.render.strands() - 1);
        assert_eq!(c.strands[0].len(), 3);
        // A fractional kept length ends between two vertices, on the straight segment.
        let mut k = vec![(s.render.vertices_per_strand - 1) as f64; s.render.strands()];
        k[0] = 2.25;
        let c = s.render_curves(&moved, &id, &k, &none);
        let (a, b) = (s.render_vertex(&moved, &id, &none, 0, 2), s.render_vertex(&moved, &id, &none, 0, 3));
        let whole = s.render_curves(&moved, &id, &[], &none);
        assert!((0..nv).all(|j| (0..3).all(|x| (whole.strands[0][j][x] as f64 - s.render_vertex(&moved, &id, &none, 0, j)[x]).abs() < 1e-7)), "the curves are the vertices");
        let e = a * 0.75 + b * 0.25;
        assert_eq!(c.strands[0].len(), 4);
        assert!((0..3).all(|x| (c.strands[0][3][x] as f64 - e[x]).abs() < 1e-7));
    }
}
