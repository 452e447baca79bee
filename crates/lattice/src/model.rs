//! The lattice model (immutable: geometry, masses, stiffeners, attachment weights, parameters) and its state
//! (mutable: node positions and velocities), with the model's construction; the step is in [`crate::lattice`].

use crate::ffd::FfdLattice;
use crate::metaball::MetaballSet;
use crate::params::{CarryParams, LatticeError, LatticeParams};
use nalgebra::{Isometry3, Point3, Vector3};

/// One stiffener (spring) between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffener {
    /// First node (flat index).
    pub i: usize,
    /// Second node (flat index).
    pub j: usize,
    /// Rest length L, m.
    pub rest_length: f64,
    /// Stiffness k_s, N/m.
    pub stiffness: f64,
    /// Axial damping c_s, N s/m.
    pub damping: f64,
}

/// The lattice model (immutable): geometry, masses, stiffeners, attachment weights, parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeModel {
    /// The lattice geometry (rest positions in the head frame, m).
    pub ffd: FfdLattice,
    /// Rest positions of the nodes in the head frame (flat order), m: the groomed shape, where a
    /// state starts ([`LatticeModel::rest_state`]).
    pub rest: Vec<Point3<f64>>,
    /// Attachment target of each node in the head frame, m. Equal to `rest` as built; a sag-free
    /// rest ([`LatticeModel::make_sag_free`]) moves them (and the stiffeners' rest lengths) so that
    /// `rest` is the equilibrium under gravity.
    pub anchors: Vec<Point3<f64>>,
    /// Node masses, kg (> 0): the hair mass each node carries.
    pub masses: Vec<f64>,
    /// Attachment weight a_i of each node, dimensionless in [0, 1] (0: free, 1: fully attached).
    pub attachment: Vec<f64>,
    /// Stiffeners: each node to its 26 neighbours, each pair once, then (if
    /// [`LatticeParams::bending_stiffness`] or damping > 0) bending stiffeners to the second
    /// neighbours along each axis.
    pub stiffeners: Vec<Stiffener>,
    /// Dynamics parameters.
    pub params: LatticeParams,
}

/// The lattice state (mutable): node positions and velocities in the world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeState {
    /// Node positions, m.
    pub positions: Vec<Point3<f64>>,
    /// Node velocities, m/s.
    pub velocities: Vec<Vector3<f64>>,
    /// Linear solves used by the last step: 1 without contacts, 1 + conjugate-gradient
    /// iterations with contacts.
    pub last_cg_iterations: usize,
    /// Steps rejected so far because they would have made the state non-finite (the state was
    /// kept and its velocities zeroed) or were given a bad step size.
    pub rejected_steps: usize,
}

impl LatticeModel {
    /// A model over `ffd`'s nodes with node masses `masses` (kg, one per node, > 0) and
    /// attachment weights `attachment` (one per node, clamped to [0, 1]).
    pub fn new(
        ffd: FfdLattice,
        masses: Vec<f64>,
        attachment: Vec<f64>,
        params: LatticeParams,
    ) -> Result<Self, LatticeError> {
        let n = ffd.node_count();
        for len in [masses.len(), attachment.len()] {
            if len != n {
                return Err(LatticeError::NodeCount {
                    expected: n,
                    got: len,
                });
            }
        }
        if let Some((i, &m)) = masses
            .iter()
            .enumerate()
            .find(|(_, m)| !(**m > 0.0 && m.is_finite()))
        {
            return Err(LatticeError::InvalidMass(i, m));
        }
        let attachment = attachment.into_iter().map(|a| a.clamp(0.0, 1.0)).collect();
        let rest = ffd.rest_positions();
        let mut stiffeners = Vec::with_capacity(13 * n);
        let (nx, ny, nz) = (ffd.nx as i64, ffd.ny as i64, ffd.nz as i64);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    for dk in -1..=1i64 {
                        for dj in -1..=1i64 {
                            for di in -1..=1i64 {
                                // each pair once: offsets lexicographically after (0, 0, 0)
                                if (dk, dj, di) <= (0, 0, 0) {
                                    continue;
                                }
                                let (a, b, c) = (i + di, j + dj, k + dk);
                                if a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz {
                                    continue;
                                }
                                let p = ffd.index(i as usize, j as usize, k as usize);
                                let q = ffd.index(a as usize, b as usize, c as usize);
                                stiffeners.push(Stiffener {
                                    i: p,
                                    j: q,
                                    rest_length: (rest[q] - rest[p]).norm(),
                                    stiffness: params.stiffener_stiffness,
                                    damping: params.stiffener_damping,
                                });
                            }
                        }
                    }
                }
            }
        }
        if params.bending_stiffness > 0.0 || params.bending_damping > 0.0 {
            for k in 0..ffd.nz {
                for j in 0..ffd.ny {
                    for i in 0..ffd.nx {
                        let p = ffd.index(i, j, k);
                        let ends = [
                            (i + 2 < ffd.nx).then(|| ffd.index(i + 2, j, k)),
                            (j + 2 < ffd.ny).then(|| ffd.index(i, j + 2, k)),
                            (k + 2 < ffd.nz).then(|| ffd.index(i, j, k + 2)),
                        ];
                        for q in ends.into_iter().flatten() {
                            stiffeners.push(Stiffener {
                                i: p,
                                j: q,
                                rest_length: (rest[q] - rest[p]).norm(),
                                stiffness: params.bending_stiffness,
                                damping: params.bending_damping,
                            });
                        }
                    }
                }
            }
        }
        Ok(Self {
            ffd,
            anchors: rest.clone(),
            rest,
            masses,
            attachment,
            stiffeners,
            params,
        })
    }

    /// A model with every node of mass `node_mass` (kg) and fully attached.
    pub fn uniform(
        ffd: FfdLattice,
        node_mass: f64,
        params: LatticeParams,
    ) -> Result<Self, LatticeError> {
        let n = ffd.node_count();
        Self::new(ffd, vec![node_mass; n], vec![1.0; n], params)
    }

    /// A lattice of cell size `carry.cell` (m) enclosing the points `points` (m, head frame; e.g.
    /// hair vertices) carrying their masses `masses` ([`LatticeModel::carrying_in`]).
    pub fn carrying(
        points: &[Point3<f64>],
        masses: &[f64],
        body: &MetaballSet,
        carry: &CarryParams,
        params: LatticeParams,
    ) -> Result<Self, LatticeError> {
        carry.validate()?;
        let (lo, hi) = Self::check_points(points, masses)?;
        let ffd = FfdLattice::enclosing(lo, hi, carry.cell)?;
        Self::carrying_in(ffd, points.iter().copied().zip(masses.iter().copied()), body, carry, params)
    }

    /// The lattice `ffd` carrying `points`, pairs of a point (m, head frame; e.g. a hair vertex) and
    /// its mass (kg, finite, >= 0): each point's mass spread on the nodes with the quadratic
    /// B-spline weights of the FFD (so each node carries the hair around it and the total is
    /// conserved; points outside are clamped onto it), plus `carry.empty_node_mass` per node. Nodes
    /// inside `body` (head frame) or within `carry.attach_distance` of its surface are fully
    /// attached to the head; the weight falls linearly over `carry.attach_falloff` beyond, to
    /// `carry.min_attachment`. The one law of a lattice around hair: the live scene
    /// (`engine::scene`) and generated hairstyles (`hairstyle::Hairstyle::lattice`) both use it.
    /// (`carry.cell` is `ffd`'s.)
    pub fn carrying_in(
        ffd: FfdLattice,
        points: impl IntoIterator<Item = (Point3<f64>, f64)>,
        body: &MetaballSet,
        carry: &CarryParams,
        params: LatticeParams,
    ) -> Result<Self, LatticeError> {
        carry.validate()?;
        let n = ffd.node_count();
        let mut node_mass = vec![carry.empty_node_mass; n];
        for (k, (p, m)) in points.into_iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) || !(m >= 0.0 && m.is_finite()) {
                return Err(LatticeError::InvalidMass(k, m));
            }
            let (idx, w) = ffd.weights_clamped(&p)?;
            for (i, w) in idx.iter().zip(&w) {
                node_mass[*i] += w * m;
            }
        }
        let threshold = params.metaball.threshold;
        let attachment = ffd
            .rest_positions()
            .iter()
            .map(|x| {
                let (f, g) = body.field_and_gradient(x);
                if f > threshold {
                    return 1.0;
                }
                let gn = g.norm();
                let d = if f > 0.0 && gn > 0.0 {
                    (threshold - f) / gn
                } else {
                    f64::INFINITY
                };
                (1.0 - (d - carry.attach_distance) / carry.attach_falloff).clamp(carry.min_attachment, 1.0)
            })
            .collect();
        Self::new(ffd, node_mass, attachment, params)
    }

    /// Checks points (finite) and masses (one per point, finite, >= 0); their bounding box, m.
    fn check_points(points: &[Point3<f64>], masses: &[f64]) -> Result<(Point3<f64>, Point3<f64>), LatticeError> {
        if points.is_empty() || points.len() != masses.len() {
            return Err(LatticeError::NodeCount {
                expected: points.len().max(1),
                got: masses.len(),
            });
        }
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        for (i, p) in points.iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) || !(masses[i] >= 0.0 && masses[i].is_finite()) {
                return Err(LatticeError::InvalidMass(i, masses[i]));
            }
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        Ok((lo, hi))
    }

    /// Total mass of the nodes, kg.
    pub fn total_mass(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.rest.len()
    }

    /// The state at rest in the head pose `head` (head frame to world): nodes at their
    /// attachment targets, zero velocity.
    pub fn rest_state(&self, head: &Isometry3<f64>) -> LatticeState {
        LatticeState {
            positions: self.rest.iter().map(|p| head * p).collect(),
            velocities: vec![Vector3::zeros(); self.node_count()],
            last_cg_iterations: 0,
            rejected_steps: 0,
        }
    }

    /// Total mechanical energy, J: kinetic + stiffener and attachment elastic energy +
    /// gravitational potential (zero at the world origin). Dissipative forces are not included,
    /// so with no obstacles and a still head this never increases under [`step`](Self::step).
    pub fn energy(&self, state: &LatticeState, head: &Isometry3<f64>) -> f64 {
        let p = &self.params;
        let mut e = 0.0;
        for (i, (x, v)) in state.positions.iter().zip(&state.velocities).enumerate() {
            let m = self.masses[i];
            e += 0.5 * m * v.norm_squared() - m * p.gravity.dot(&x.coords);
            let target = head * self.anchors[i];
            e += 0.5 * p.attachment_stiffness * self.attachment[i] * (x - target).norm_squared();
        }
        for s in &self.stiffeners {
            let ext = (state.positions[s.j] - state.positions[s.i]).norm() - s.rest_length;
            e += 0.5 * s.stiffness * ext * ext;
        }
        e
    }
}
