//! A scene carrying a file's render strands on the built-in head and guides.

use super::builtin::lattice_for_hair;
use super::{RenderHair, Scene, SceneOptions};
use crate::error::SessionError;
use lattice::ffd::FfdLattice;

/// Most lattice nodes a loaded hairstyle may need (about a 1.35 m box at 5 cm cells; [`LoadLimits`]'s default
/// box needs 16,128 at the default 5 cm cells).
pub const MAX_LATTICE_NODES: usize = 20_000;
use nalgebra::Point3;
pub use hairstyle::LoadLimits;

impl Scene {
    /// The built-in head and guides of `opts` carrying the render strands of `curves` instead of generated
    /// ones (positions in m in the head frame, root first, as the viewer saves them; at most
    /// `opts.load` strands and points, every point in its box around the head): each strand resampled to `opts.render_vertices` points evenly along its
    /// length, bound to the guides whose roots are nearest its root (`hairstyle::generate::nearest_guides`), spanning
    /// its length over the nearest guide's length (capped at 1), and a lattice enclosing them all whose
    /// node masses come from the strands (the guides' linear density times their lengths).
    /// Errors name the bad strand (empty, non-finite or outside the box) or the bound or parameter.
    pub fn from_curves(curves: &hairstyle::HairCurves, opts: &SceneOptions) -> Result<Scene, SessionError> {
        let bad = |m: String| SessionError::Scene(m);
        opts.load.check_counts(curves).map_err(bad)?;
        opts.load.check_box(curves).map_err(bad)?;
        let base = Scene::builtin(&SceneOptions { render_strands: 1, ..opts.clone() })?;
        let v = opts.render_vertices;
        let curves = hairstyle::formats::tfx::resample(&hairstyle::HairCurves::from_strands(curves.strands.clone()), v).map_err(|e| bad(e.to_string()))?;
        let k = base.render.guides_per_strand.min(base.guides.len()).max(1);
        let roots: Vec<Point3<f64>> = base.guides.iter().map(|g| Point3::from(g.state.root.position)).collect();
        let density = base.guides.first().map_or(0.0, |g| g.model.mass() / g.model.length);
        let n = curves.strands.len();
        let (mut positions, mut guide, mut weight, mut span) = (Vec::with_capacity(n * v), Vec::with_capacity(n * k), Vec::with_capacity(n * k), Vec::with_capacity(n));
        let mut hair_mass = 0.0;
        for st in &curves.strands {
            let root = Point3::new(st[0][0] as f64, st[0][1] as f64, st[0][2] as f64);
            // The hairstyle's one binding law (inverse-square weights; this used 1/(d + 1 mm) before issue 11).
            let (near, w) = hairstyle::generate::nearest_guides(&roots, &root, k);
            guide.extend_from_slice(&near);
            weight.extend_from_slice(&w);
            let length: f64 = st.windows(2).map(|p| (0..3).map(|a| ((p[1][a] - p[0][a]) as f64).powi(2)).sum::<f64>().sqrt()).sum();
            span.push((length / base.guides[near[0] as usize].model.length).min(1.0) as f32);
            hair_mass += density * length;
            positions.extend_from_slice(st);
        }
        let render = RenderHair { vertices_per_strand: v, guides_per_strand: k, positions, guide, weight, span };
        // The lattice encloses the strands and what the built-in one enclosed (head, guides).
        let (mut lo, mut hi) = (Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY), Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY));
        let base_points = base.lattice.rest.iter().copied();
        let hair_points = render.positions.iter().map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        for p in base_points.chain(hair_points) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let ffd = FfdLattice::enclosing(lo, hi, opts.cell).map_err(|e| bad(e.to_string()))?;
        // A hairstyle on a head fits in a metre-sized box (8,000 nodes at 5 cm); more is a malformed or hostile file
        // (a 60-byte file with one 2.3 m strand asked for 185,193 nodes, 2.2 MB per FRAME).
        if ffd.node_count() > MAX_LATTICE_NODES {
            return Err(bad(format!("the strands span {:?} to {:?} m: a lattice of {} nodes at {} m cells is too large", lo, hi, ffd.node_count(), opts.cell)));
        }
        let radius = hairstyle::HeadParams::default().head_radius;
        let lattice = lattice_for_hair(ffd, &render.positions, hair_mass.max(1e-6), &base.head, radius)?;
        Ok(Scene { head: base.head, head_mesh: base.head_mesh, render, guides: base.guides, hair_type: base.hair_type, lattice, root_hold: base.root_hold })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::GlobalCore;
    use crate::params::SessionParams;
    use crate::tool::ToolInput;
    use nalgebra::Vector3;
    use std::sync::Arc;

    #[test]
    fn a_scene_carries_the_render_strands_of_a_file() {
        // The built-in scene's own render strands, written as curves (what the viewer's Save gives, 3 of
        // them reversed into odd shapes), make a scene: same strand count, each strand keeps its root and tip
        // (1e-6 m), is bound to its nearest guides with weights summing to 1 (1e-6), and a live session runs
        // on it with finite lattice positions. Empty files and non-finite points are refused by name.
        let opts = SceneOptions { render_strands: 500, guides: 40, ..SceneOptions::default() };
        let built = Scene::builtin(&opts).unwrap();
        let v = built.render.vertices_per_strand;
        let mut strands: Vec<Vec<[f32; 3]>> = built.render.positions.chunks(v).map(|c| c.to_vec()).collect();
        strands[0].truncate(3);
        strands[1].push([0.0, -0.3, -0.3]);
        strands[2] = vec![strands[2][0]];
        let scene = Scene::from_curves(&hairstyle::HairCurves::from_strands(strands.clone()), &opts).unwrap();
        assert_eq!(scene.render.strands(), strands.len());
        assert_eq!(scene.render.vertices_per_strand, opts.render_vertices);
        let k = scene.render.guides_per_strand;
        for (i, st) in strands.iter().enumerate() {
            let got = &scene.render.positions[i * opts.render_vertices..(i + 1) * opts.render_vertices];
            let d = |a: [f32; 3], b: [f32; 3]| (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f32>().sqrt();
            assert!(d(got[0], st[0]) < 1e-6 && d(got[got.len() - 1], st[st.len() - 1]) < 1e-6, "strand {i} ends");
            let w: f32 = scene.render.weight[i * k..(i + 1) * k].iter().sum();
            assert!((w - 1.0).abs() < 1e-6, "strand {i} weights sum to {w}");
            let root = Vector3::new(st[0][0] as f64, st[0][1] as f64, st[0][2] as f64);
            let nearest = (0..scene.guides.len()).min_by(|&a, &b| (scene.guides[a].state.root.position - root).norm().total_cmp(&(scene.guides[b].state.root.position - root).norm())).unwrap();
            assert_eq!(scene.render.guide[i * k] as usize, nearest, "strand {i} follows its nearest guide first");
        }
        let scene = Arc::new(scene);
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        for _ in 0..20 {
            g.step(0.01, &ToolInput::default());
        }
        assert!(g.positions().iter().all(|p| p.coords.iter().all(|x| x.is_finite())));
        let empty = Scene::from_curves(&hairstyle::HairCurves::from_strands(vec![]), &opts).unwrap_err().to_string();
        assert!(empty.contains("1 to 200000 strands"), "{empty}");
        let mut nan = strands;
        nan[7][1][2] = f32::NAN;
        let e = Scene::from_curves(&hairstyle::HairCurves::from_strands(nan), &opts).unwrap_err().to_string();
        assert!(e.contains("strand 7 point 1"), "{e}");
    }

    #[test]
    fn a_hairstyle_too_large_for_a_head_is_refused() {
        // Issue 16: one strand across a 2.7 m box (a 60-byte file) asked for a lattice of 185,193 nodes; it is
        // outside the box around the head, and refused naming the point and the box before anything is built.
        let opts = SceneOptions { render_strands: 100, guides: 20, ..SceneOptions::default() };
        let huge = hairstyle::HairCurves::from_strands(vec![vec![[-1.35; 3], [1.35; 3]]]);
        let e = Scene::from_curves(&huge, &opts).unwrap_err().to_string();
        assert!(e.contains("strand 0 point 0") && e.contains("outside the box around the head"), "{e}");
        // A strand corner to corner of the box is taken, and its lattice stays within MAX_LATTICE_NODES;
        // 1 mm beyond a face is refused.
        let l = opts.load;
        let corner = |a: [f64; 3]| [a[0] as f32, a[1] as f32, a[2] as f32];
        let diagonal = hairstyle::HairCurves::from_strands(vec![vec![corner(l.box_min), corner(l.box_max)]]);
        let s = Scene::from_curves(&diagonal, &opts).unwrap();
        assert!(s.lattice.node_count() <= MAX_LATTICE_NODES, "{} nodes", s.lattice.node_count());
        for a in 0..3 {
            let mut p = l.box_max;
            p[a] += 1e-3;
            let e = Scene::from_curves(&hairstyle::HairCurves::from_strands(vec![vec![[0.0; 3], corner(p)]]), &opts).unwrap_err().to_string();
            assert!(e.contains("strand 0 point 1"), "{e}");
        }
        // Counts: more strands or points than the bounds are refused naming them.
        let few = SceneOptions { load: LoadLimits { max_strands: 2, max_points: 5, ..l }, ..opts.clone() };
        let e = Scene::from_curves(&hairstyle::HairCurves::from_strands(vec![vec![[0.0; 3]]; 3]), &few).unwrap_err().to_string();
        assert!(e.contains("1 to 2 strands, got 3"), "{e}");
        let e = Scene::from_curves(&hairstyle::HairCurves::from_strands(vec![vec![[0.0; 3]; 3]; 2]), &few).unwrap_err().to_string();
        assert!(e.contains("6 points; at most 5"), "{e}");
        assert!(l.check_size(64 << 20).is_ok());
        assert!(l.check_size((64 << 20) + 1).unwrap_err().contains("at most 67108864 bytes (64 MiB)"));
    }
}
