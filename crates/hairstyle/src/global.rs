//! The global layer's glue: a lattice built around a hairstyle, carrying its mass, attached to
//! the head and colliding with the body; render strands follow it by FFD.

use crate::generate::{GenerateError, Hairstyle};
use lattice::ffd::{Binding, FfdError};
use lattice::lattice::{CarryParams, LatticeError, LatticeModel, LatticeParams};
use lattice::metaball::{Metaball, MetaballSet};
use nalgebra::{Isometry3, Point3};

/// A hairstyle's lattice (model) with the FFD binding of its render strand vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct HairLattice {
    /// The lattice model (head frame rest positions, node masses from the hair).
    pub model: LatticeModel,
    /// FFD binding of every render strand vertex (same order as `RenderStrands::positions`).
    pub binding: Binding,
}

impl HairLattice {
    /// World positions (m) of the render strand vertices for lattice nodes at `nodes` (world,
    /// m): the FFD of the binding (both cores), then every vertex inside the body `body_world`
    /// (world frame; e.g. [`body_in_world`]) or within `skin` (m) of its surface is pushed out
    /// onto the offset surface at `skin` ([`MetaballSet::push_out_many`], threshold
    /// `model.params.metaball.threshold`; [`lattice::metaball::PUSH_OUT_SKIN`] = 0.5 mm is the
    /// usual skin). The lattice nodes collide with the body, but the vertices between them
    /// (several per cell) can sag into it where the lattice does; this keeps them out. Returns
    /// how many vertices were pushed.
    pub fn render_positions(
        &self,
        nodes: &[Point3<f64>],
        body_world: &MetaballSet,
        skin: f64,
        out: &mut Vec<Point3<f64>>,
    ) -> Result<usize, FfdError> {
        self.binding.apply_parallel(nodes, out)?;
        Ok(body_world.push_out_many(out, self.model.params.metaball.threshold, skin))
    }
}

/// The metaball set `body` (head frame) placed in the world by the head pose `head`.
pub fn body_in_world(body: &MetaballSet, head: &Isometry3<f64>) -> MetaballSet {
    MetaballSet::new(
        body.balls
            .iter()
            .map(|b| Metaball::new(head * b.centre, b.radius))
            .collect(),
    )
}

impl Hairstyle {
    /// Mass of each render strand vertex, kg: the strand's mass (density x section area x
    /// length) shared equally by its vertices. One render strand stands for one hair.
    pub fn render_vertex_masses(&self) -> Result<Vec<f64>, GenerateError> {
        let hair = self.params.hair()?;
        let section = hair
            .section()
            .map_err(|source| GenerateError::Strand { guide: 0, source })?;
        let rho_a = hair.density * section.area();
        let v = self.render.vertices_per_strand;
        let mut out = Vec::with_capacity(self.render.positions.len());
        for i in 0..self.render.len() {
            let s = self.render.strand(i);
            let len: f64 = s
                .windows(2)
                .map(|w| {
                    ((w[1][0] - w[0][0]).powi(2)
                        + (w[1][1] - w[0][1]).powi(2)
                        + (w[1][2] - w[0][2]).powi(2))
                    .sqrt() as f64
                })
                .sum();
            out.extend(std::iter::repeat_n(rho_a * len / v as f64, v));
        }
        Ok(out)
    }

    /// The lattice carrying this hairstyle ([`LatticeModel::carrying`] over the render strand
    /// vertices and their masses, the head's body for attachment) and the FFD binding of the
    /// render vertices. `params.metaball.threshold` should equal the head's threshold.
    pub fn lattice(
        &self,
        carry: &CarryParams,
        params: LatticeParams,
    ) -> Result<HairLattice, GenerateError> {
        let pts: Vec<Point3<f64>> = self
            .render
            .positions
            .iter()
            .map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        let masses = self.render_vertex_masses()?;
        let model =
            LatticeModel::carrying(&pts, &masses, &self.head.body, carry, params).map_err(|e| {
                match e {
                    LatticeError::Ffd(f) => GenerateError::Ffd(f),
                    other => GenerateError::InvalidParameter {
                        field: "lattice",
                        reason: other.to_string(),
                    },
                }
            })?;
        let binding = Binding::new_clamped(&model.ffd, &pts)?;
        Ok(HairLattice { model, binding })
    }
}
