//! A scene of a loaded hairstyle (issue 34): the file's strands are drawn, with follow strands around them,
//! and the simulated guides are chosen among them, each a Super-Helix fitted to its strand's shape.

use super::builtin::{lattice_for_hair, scene_guide};
use super::{Guide, RenderHair, Scene, SceneOptions};
use crate::error::SessionError;
use lattice::ffd::FfdLattice;

/// Most lattice nodes a loaded hairstyle may need (about a 1.35 m box at 5 cm cells; [`LoadLimits`]'s default
/// box needs 16,128 at the default 5 cm cells).
pub const MAX_LATTICE_NODES: usize = 20_000;
use nalgebra::Point3;
pub use hairstyle::LoadLimits;

/// What a load made of a file's strands ([`Scene::load`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadReport {
    /// Strands of the file.
    pub file_strands: usize,
    /// Follow strands drawn around each of them.
    pub follow_per_strand: usize,
    /// The guides fitted to the file's strands: `(file strand, RMS distance m, largest distance m, stable)`,
    /// the distances between the guide's rest centreline and its strand at evenly spaced arc lengths. Empty
    /// when no strand is rooted on the scalp: the built-in guides then carry the file.
    pub guides: Vec<(usize, f64, f64, bool)>,
}

impl LoadReport {
    /// One line for a status bar or a log: strands, follow strands, guides and their fit (mm).
    pub fn summary(&self) -> String {
        let drawn = format!("{} strands + {} follow strands each", self.file_strands, self.follow_per_strand);
        if self.guides.is_empty() {
            return format!("{drawn}; no strand rooted on the scalp: the built-in guides carry them");
        }
        let mut rms: Vec<f64> = self.guides.iter().map(|g| g.1).collect();
        rms.sort_by(f64::total_cmp);
        let q = |f: f64| rms[((rms.len() - 1) as f64 * f).round() as usize] * 1e3;
        let worst = self.guides.iter().max_by(|a, b| a.2.total_cmp(&b.2)).expect("not empty");
        let stable = self.guides.iter().filter(|g| g.3).count();
        format!(
            "{drawn}; {} guides fitted to the file's strands, distance median {:.2} mm, p95 {:.2} mm, largest {:.2} mm (strand {}); {stable} stable",
            self.guides.len(),
            q(0.5),
            q(0.95),
            worst.2 * 1e3,
            worst.0
        )
    }
}

impl Scene {
    /// [`Scene::load`] without its report.
    pub fn from_curves(curves: &hairstyle::HairCurves, opts: &SceneOptions) -> Result<Scene, SessionError> {
        Scene::load(curves, opts).map(|(s, _)| s)
    }

    /// The built-in head carrying the hairstyle `curves` (positions in m in the head frame, root first, as
    /// the viewer saves them; at most `opts.load` strands and points, every point in its box around the
    /// head). Stages:
    /// 1. Guides: up to `opts.guides` of the file's strands rooted on the scalp, spread over it, each a
    ///    Super-Helix of `opts.hair_type` fitted to its shape with its sag-free rest
    ///    (`hairstyle::fitted::guides_from_curves`, at least `opts.segments` segments); the built-in guides
    ///    if no strand is rooted on the scalp.
    /// 2. Drawn strands: each file strand resampled to `opts.render_vertices` points evenly along its length,
    ///    then `opts.follow_strands` follow strands around each (`hairstyle::follow`), within
    ///    `opts.load.max_strands` in all.
    /// 3. Binding: each drawn strand bound to the guides whose roots are nearest its root
    ///    (`hairstyle::generate::nearest_guides`, the one law), spanning its length over the nearest guide's
    ///    length (capped at 1).
    /// 4. Lattice: enclosing them all, node masses from the strands (the guides' linear density times their
    ///    lengths).
    ///
    /// Errors name the bad strand (empty, non-finite or outside the box) or the bound or parameter.
    pub fn load(curves: &hairstyle::HairCurves, opts: &SceneOptions) -> Result<(Scene, LoadReport), SessionError> {
        let bad = |m: String| SessionError::Scene(m);
        opts.load.check_counts(curves).map_err(bad)?;
        opts.load.check_box(curves).map_err(bad)?;
        let n = curves.strands.len();
        let follow = match opts.follow_strands {
            Some(f) if n.saturating_mul(f + 1) > opts.load.max_strands => {
                return Err(bad(format!("{f} follow strands for each of {n} strands make {} drawn strands; at most {} may be loaded", n.saturating_mul(f + 1), opts.load.max_strands)));
            }
            Some(f) => f,
            None => (opts.render_strands / n).saturating_sub(1).min((opts.load.max_strands / n).saturating_sub(1)),
        };
        // 1. Guides.
        let params = hairstyle::HairstyleParams { hair_type: opts.hair_type.clone(), guide_segments: opts.segments, ..Default::default() };
        let head = hairstyle::Head::new(params.head).map_err(|e| bad(e.to_string()))?;
        let fit = hairstyle::fitted::GuideFitParams { budget: opts.guides, ..Default::default() };
        let fitted = hairstyle::fitted::guides_from_curves(curves, &params, &head, &fit).map_err(|e| bad(e.to_string()))?;
        let hair_type = strand::HairType::by_name(&opts.hair_type).ok_or_else(|| SessionError::Param(format!("unknown hair type {:?}", opts.hair_type)))?;
        let guides: Vec<Guide> = if fitted.is_empty() {
            Scene::builtin(&SceneOptions { render_strands: 1, ..opts.clone() })?.guides
        } else {
            fitted.iter().map(|f| scene_guide(&f.guide, opts.samples)).collect()
        };
        let report = LoadReport { file_strands: n, follow_per_strand: follow, guides: fitted.iter().map(|f| (f.strand, f.rms, f.max, f.guide.stable)).collect() };
        // 2. Drawn strands.
        let v = opts.render_vertices;
        let mut curves = hairstyle::formats::tfx::resample(&hairstyle::HairCurves::from_strands(curves.strands.clone()), v).map_err(|e| bad(e.to_string()))?;
        if follow > 0 {
            let scalp = hairstyle::fit::ScalpIndex::new(&head, hairstyle::fit::FitParams::default().scalp_samples);
            let fp = hairstyle::follow::FollowParams { per_strand: follow, seed: opts.seed, ..Default::default() };
            let more = hairstyle::follow::follow_strands(&curves.strands, &head, &scalp, fit.rooted_distance, &fp);
            // Follow strands stay in the box around the head (a strand at its edge fans out of it).
            let (lo, hi) = (opts.load.box_min, opts.load.box_max);
            curves.strands.extend(more.into_iter().map(|s| s.into_iter().map(|p| std::array::from_fn(|a| p[a].clamp(lo[a] as f32, hi[a] as f32))).collect()));
        }
        // 3. Binding.
        let k = hairstyle::HairstyleParams::default().guides_per_render.min(guides.len()).max(1);
        let roots: Vec<Point3<f64>> = guides.iter().map(|g| Point3::from(g.state.root.position)).collect();
        let density = guides.first().map_or(0.0, |g| g.model.mass() / g.model.length);
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
            span.push((length / guides[near[0] as usize].model.length).min(1.0) as f32);
            hair_mass += density * length;
            positions.extend_from_slice(st);
        }
        let render = RenderHair { vertices_per_strand: v, guides_per_strand: k, positions, guide, weight, span };
        // 4. The lattice encloses the strands, the guides and the head (a cube of its radius, as the built-in one).
        let radius = head.params.head_radius;
        let (mut lo, mut hi) = (Point3::new(-radius, -radius, -radius), Point3::new(radius, radius, radius));
        let hair_points = render.positions.iter().map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        let guide_points = guides.iter().flat_map(|g| g.reference.iter().map(|p| Point3::from(*p)));
        for p in hair_points.chain(guide_points) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let ffd = FfdLattice::enclosing(lo, hi, opts.cell).map_err(|e| bad(e.to_string()))?;
        // A hairstyle on a head fits in a metre-sized box (8,000 nodes at 5 cm); more is a malformed or hostile file
        // (a 60-byte file with one 2.3 m strand asked for 185,193 nodes, 2.2 MB per FRAME).
        if ffd.node_count() > MAX_LATTICE_NODES {
            return Err(bad(format!("the strands span {:?} to {:?} m: a lattice of {} nodes at {} m cells is too large", lo, hi, ffd.node_count(), opts.cell)));
        }
        let lattice = lattice_for_hair(ffd, &render.positions, hair_mass.max(1e-6), &head.body, radius)?;
        let mesh = head.mesh();
        let head_mesh = super::Mesh { positions: mesh.positions, indices: mesh.indices };
        Ok((Scene { head: head.body, head_mesh, render, guides, hair_type, lattice, root_hold: crate::params::HairLatticeParams::default().root_hold }, report))
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
