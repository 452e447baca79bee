//! The built-in scene: the built-in head and a generated hairstyle, with the lattice around the hair.

use super::{Guide, Mesh, RenderHair, Scene, SceneOptions};
use crate::error::SessionError;
use lattice::ffd::FfdLattice;
use lattice::lattice::{LatticeModel, LatticeParams};
use nalgebra::Point3;
use strand::HairType;

impl Scene {
    /// The built-in scene: the built-in head (metaballs and display mesh) and a generated hairstyle
    /// (`hairstyle::Hairstyle::generate`), with the lattice around it.
    pub fn builtin(opts: &SceneOptions) -> Result<Scene, SessionError> {
        if opts.samples < 2 || !(opts.cell > 0.0) {
            return Err(SessionError::Param(format!("samples must be >= 2 and cell > 0 m: {opts:?}")));
        }
        let params = hairstyle::HairstyleParams {
            hair_type: opts.hair_type.clone(),
            length: opts.length,
            curliness: opts.curliness,
            guide_count: opts.guides,
            guide_segments: opts.segments,
            render_count: opts.render_strands,
            render_vertices: opts.render_vertices,
            guide_samples: opts.samples.max(16),
            seed: opts.seed,
            ..Default::default()
        };
        let style = hairstyle::Hairstyle::generate(&params).map_err(|e| SessionError::Scene(e.to_string()))?;
        let hair_type = HairType::by_name(&opts.hair_type).ok_or_else(|| SessionError::Param(format!("unknown hair type {:?}", opts.hair_type)))?;
        let mesh = style.head.mesh();
        let head_mesh = Mesh { positions: mesh.positions, indices: mesh.indices };
        let guides: Vec<Guide> = style
            .guides
            .iter()
            .map(|g| {
                let reference = hairstyle::generate::sample_strand(&g.model, &g.state, opts.samples).into_iter().map(|p| p.coords).collect();
                Guide { model: g.model.clone(), state: g.state.clone(), reference }
            })
            .collect();
        let r = &style.render;
        let render = RenderHair { vertices_per_strand: r.vertices_per_strand, guides_per_strand: r.guides_per_strand, positions: r.positions.clone(), guide: r.guide_indices.clone(), weight: r.guide_weights.clone(), span: r.span.clone() };
        // Lattice around the hair and head.
        let (lo, hi) = style.bounds();
        let rad = style.head.params.head_radius;
        let lo = Point3::new(lo.x.min(-rad), lo.y.min(-rad), lo.z.min(-rad));
        let hi = Point3::new(hi.x.max(rad), hi.y.max(rad), hi.z.max(rad));
        let ffd = FfdLattice::enclosing(lo, hi, opts.cell).map_err(|e| SessionError::Scene(e.to_string()))?;
        let hair_mass: f64 = style.guides.first().map_or(0.0, |g| g.model.mass()) * render.strands() as f64;
        let lattice = lattice_for_hair(ffd, &render.positions, hair_mass.max(1e-6), rad)?;
        Ok(Scene { head: style.head.body.clone(), head_mesh, render, guides, hair_type, lattice })
    }
}

/// A lattice model whose node masses share `hair_mass` (kg) by the render vertices each node's cell holds
/// (plus a floor of 2 % of the mean), attached fully near the head and more loosely further out.
pub(super) fn lattice_for_hair(ffd: FfdLattice, positions: &[[f32; 3]], hair_mass: f64, r: f64) -> Result<LatticeModel, SessionError> {
    let n = ffd.node_count();
    let mut count = vec![0.0f64; n];
    for p in positions {
        let q = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let s = (q - ffd.origin) / ffd.h;
        let (i, j, k) = (s.x.round() as usize, s.y.round() as usize, s.z.round() as usize);
        if i < ffd.nx && j < ffd.ny && k < ffd.nz {
            count[ffd.index(i, j, k)] += 1.0;
        }
    }
    let total: f64 = count.iter().sum::<f64>().max(1.0);
    let mean = hair_mass / n as f64;
    let masses: Vec<f64> = count.iter().map(|c| hair_mass * c / total + 0.02 * mean).collect();
    let rest = ffd.rest_positions();
    let attachment: Vec<f64> = rest.iter().map(|p| {
        let d = (p.coords.norm() - r).max(0.0);
        (1.0 - d / (3.0 * r)).clamp(0.35, 1.0)
    }).collect();
    LatticeModel::new(ffd, masses, attachment, LatticeParams::default()).map_err(|e| SessionError::Scene(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::haptic::{centreline, HapticCore};
    use crate::scene::ffd_map;
    use nalgebra::Vector3;
    use std::sync::Arc;

    fn small_scene() -> Arc<Scene> {
        let o = SceneOptions { render_strands: 2000, guides: 60, ..SceneOptions::default() };
        Arc::new(Scene::builtin(&o).unwrap())
    }

    #[test]
    fn builtin_scene_is_inside_the_lattice_and_guides_start_at_their_reference() {
        // Every render vertex is inside the lattice's embedded volume, so the viewer's FFD reproduces it at
        // rest (to 1e-9 m in f64); each guide's strand starts exactly on its reference centreline.
        let s = small_scene();
        let f = &s.lattice.ffd;
        for p in &s.render.positions {
            let q = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            assert!(f.weights(&Point3::from(q)).is_ok(), "{q:?} outside the lattice");
            let back = ffd_map(f, &s.lattice.rest, &q);
            assert!((back - q).norm() < 1e-9, "FFD at rest reproduces the point: {back:?} vs {q:?}");
        }
        assert_eq!(s.render.positions.len(), 2000 * 12);
        assert_eq!(s.render.guide.len(), 2000 * s.render.guides_per_strand);
        assert!(s.render.guide.iter().all(|&g| (g as usize) < s.guides.len()));
        assert!(s.guides.iter().all(|g| g.reference.len() == 16));
        let strands = HapticCore::build_strands(&s, &s.hair_type, 0.0).unwrap();
        for (st, g) in strands.iter().zip(&s.guides) {
            for (a, b) in centreline(st, 16).iter().zip(&g.reference) {
                assert!((a - b).norm() < 1e-12);
            }
        }
    }
}
