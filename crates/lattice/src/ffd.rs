//! Quadratic B-spline free-form deformation (FFD) on a regular lattice.
//!
//! x = sum over 27 nodes B_a(u) B_b(v) B_c(w) P_abc, with the uniform quadratic B-spline pieces
//! B0(t) = (1-t)^2/2, B1(t) = (-2t^2+2t+1)/2, B2(t) = t^2/2 (C1 across cells, partition of unity,
//! reproduces linear functions).
//!
//! ## Node and cell convention
//! Node (i, j, k) rests at `origin + h (i, j, k)`, i in 0..nx (likewise j, k); nodes are stored
//! flat at index `i + nx (j + ny k)`. Cells are centred on nodes: along one axis, with
//! s = (x - origin)/h in node units, the point lies in cell i = round(s) (the interval
//! [i - 1/2, i + 1/2)), has local coordinate t = s - i + 1/2 in [0, 1], and uses nodes i-1, i, i+1
//! with weights B0(t), B1(t), B2(t). So a cell needs a node on each side: the deformable
//! (embedded) volume is s in [1/2, n - 3/2] per axis, i.e. from `origin + h/2` to
//! `origin + (n - 3/2) h`. A lattice enclosing a volume must therefore extend at least half a cell
//! (one node beyond the cell holding the volume's boundary) past it on every side; see
//! [`FfdLattice::enclosing`]. Each axis needs n >= 3 nodes.
//!
//! ## Outside the embedded volume
//! [`FfdLattice::weights`] returns [`FfdError::Outside`]; [`FfdLattice::weights_clamped`] clamps
//! each node coordinate s into [1/2, n - 3/2] first (the point then moves with the nearest point
//! of the embedded volume's boundary).

use nalgebra::{Point3, Vector3};
use thiserror::Error;

/// Points within this distance (in cells, i.e. units of h) outside the embedded volume are
/// accepted by [`FfdLattice::weights`] and snapped onto its boundary, so that boundary points
/// computed in floating point (e.g. `origin + (n - 3/2) h`) are not rejected by round-off.
pub const BOUNDARY_TOLERANCE: f64 = 1e-9;

/// Errors of the FFD.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FfdError {
    /// The point (m) lies outside the embedded volume of the lattice.
    #[error("point ({0}, {1}, {2}) m lies outside the lattice's embedded volume")]
    Outside(f64, f64, f64),
    /// The lattice description is invalid (fewer than 3 nodes on an axis, non-positive cell size).
    #[error("invalid lattice: {0}")]
    InvalidLattice(String),
    /// The node slice does not have one position per lattice node.
    #[error("expected {expected} node positions, got {got}")]
    NodeCount {
        /// Number of nodes in the lattice.
        expected: usize,
        /// Number of positions given.
        got: usize,
    },
}

/// Quadratic B-spline pieces at local coordinate t in [0, 1]: (B0, B1, B2). Dimensionless.
#[inline]
pub fn basis(t: f64) -> [f64; 3] {
    let u = 1.0 - t;
    [
        0.5 * u * u,
        0.5 * (-2.0 * t * t + 2.0 * t + 1.0),
        0.5 * t * t,
    ]
}

/// Derivatives d/dt of the quadratic B-spline pieces at t in [0, 1]: (B0', B1', B2'). Dimensionless.
#[inline]
pub fn basis_derivative(t: f64) -> [f64; 3] {
    [t - 1.0, 1.0 - 2.0 * t, t]
}

/// A regular FFD lattice (the model: immutable rest geometry). See the module docs for the
/// node and cell convention.
#[derive(Debug, Clone, PartialEq)]
pub struct FfdLattice {
    /// Rest position of node (0, 0, 0), m.
    pub origin: Point3<f64>,
    /// Cell size (node spacing), m; > 0.
    pub h: f64,
    /// Node count along x; >= 3.
    pub nx: usize,
    /// Node count along y; >= 3.
    pub ny: usize,
    /// Node count along z; >= 3.
    pub nz: usize,
}

impl FfdLattice {
    /// A lattice with node (0,0,0) at `origin` (m), spacing `h` (m) and node counts `n`.
    pub fn new(origin: Point3<f64>, h: f64, n: [usize; 3]) -> Result<Self, FfdError> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(FfdError::InvalidLattice(format!(
                "cell size {h} m must be > 0"
            )));
        }
        if n.iter().any(|&k| k < 3) {
            return Err(FfdError::InvalidLattice(format!(
                "node counts {n:?} must all be >= 3"
            )));
        }
        Ok(Self {
            origin,
            h,
            nx: n[0],
            ny: n[1],
            nz: n[2],
        })
    }

    /// The smallest lattice of spacing `h` (m) whose embedded volume contains the box
    /// [`lo`, `hi`] (m): one node lies beyond the box on every side (the box starts half a cell
    /// inside the first cell that is fully supported).
    pub fn enclosing(lo: Point3<f64>, hi: Point3<f64>, h: f64) -> Result<Self, FfdError> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(FfdError::InvalidLattice(format!(
                "cell size {h} m must be > 0"
            )));
        }
        let origin = lo - Vector3::repeat(0.5 * h);
        let mut n = [0usize; 3];
        for a in 0..3 {
            // need (n - 3/2) h >= hi - origin
            let ext = ((hi[a] - origin[a]) / h + 1.5).ceil().max(3.0);
            n[a] = ext as usize;
        }
        Self::new(origin, h, n)
    }

    /// Total number of nodes, nx ny nz.
    pub fn node_count(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Flat index of node (i, j, k): `i + nx (j + ny k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.nx * (j + self.ny * k)
    }

    /// Rest position of node (i, j, k), m.
    pub fn rest_position(&self, i: usize, j: usize, k: usize) -> Point3<f64> {
        self.origin + self.h * Vector3::new(i as f64, j as f64, k as f64)
    }

    /// Rest positions of all nodes in flat order, m.
    pub fn rest_positions(&self) -> Vec<Point3<f64>> {
        let mut out = Vec::with_capacity(self.node_count());
        for k in 0..self.nz {
            for j in 0..self.ny {
                for i in 0..self.nx {
                    out.push(self.rest_position(i, j, k));
                }
            }
        }
        out
    }

    fn dims(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Per axis: the lower node index (cell index - 1) and local coordinate t, after optionally
    /// clamping. Returns None if outside and not clamping.
    fn locate(&self, p: &Point3<f64>, clamp: bool) -> Option<([usize; 3], [f64; 3])> {
        let dims = self.dims();
        let mut lower = [0usize; 3];
        let mut t = [0.0; 3];
        for a in 0..3 {
            let n = dims[a] as f64;
            let mut s = (p[a] - self.origin[a]) / self.h;
            let (lo, hi) = (0.5, n - 1.5);
            let near = s >= lo - BOUNDARY_TOLERANCE && s <= hi + BOUNDARY_TOLERANCE;
            if near || (clamp && !s.is_nan()) {
                s = s.clamp(lo, hi);
            } else {
                return None;
            }
            let cell = ((s + 0.5).floor() as usize).min(dims[a] - 2);
            t[a] = s - cell as f64 + 0.5;
            lower[a] = cell - 1;
        }
        Some((lower, t))
    }

    #[allow(clippy::needless_range_loop)]
    fn stencil(&self, lower: [usize; 3], t: [f64; 3]) -> ([usize; 27], [f64; 27]) {
        let bx = basis(t[0]);
        let by = basis(t[1]);
        let bz = basis(t[2]);
        let mut idx = [0usize; 27];
        let mut w = [0.0; 27];
        let mut m = 0;
        for c in 0..3 {
            for b in 0..3 {
                for a in 0..3 {
                    idx[m] = self.index(lower[0] + a, lower[1] + b, lower[2] + c);
                    w[m] = bx[a] * by[b] * bz[c];
                    m += 1;
                }
            }
        }
        (idx, w)
    }

    /// The 27 node indices (flat) and weights (dimensionless, summing to 1) of point `p` (m).
    /// Order: x fastest, then y, then z, over nodes cell-1..=cell+1 on each axis.
    /// Errors with [`FfdError::Outside`] if `p` is outside the embedded volume.
    pub fn weights(&self, p: &Point3<f64>) -> Result<([usize; 27], [f64; 27]), FfdError> {
        let (lower, t) = self
            .locate(p, false)
            .ok_or(FfdError::Outside(p.x, p.y, p.z))?;
        Ok(self.stencil(lower, t))
    }

    /// Like [`weights`](Self::weights) but clamps `p` into the embedded volume first (never fails
    /// for finite `p`; NaN coordinates still error).
    pub fn weights_clamped(&self, p: &Point3<f64>) -> Result<([usize; 27], [f64; 27]), FfdError> {
        let (lower, t) = self
            .locate(p, true)
            .ok_or(FfdError::Outside(p.x, p.y, p.z))?;
        Ok(self.stencil(lower, t))
    }

    fn check_nodes(&self, nodes: &[Point3<f64>]) -> Result<(), FfdError> {
        if nodes.len() != self.node_count() {
            return Err(FfdError::NodeCount {
                expected: self.node_count(),
                got: nodes.len(),
            });
        }
        Ok(())
    }

    /// Deformed position (m) of the point whose rest position is `p` (m), given the current node
    /// positions `nodes` (m, flat order, one per node). Errors outside the embedded volume.
    pub fn deform(&self, p: &Point3<f64>, nodes: &[Point3<f64>]) -> Result<Vector3<f64>, FfdError> {
        self.check_nodes(nodes)?;
        let (idx, w) = self.weights(p)?;
        Ok(Self::combine(&idx, &w, nodes))
    }

    /// As [`FfdLattice::deform`], with `p` clamped to the embedded volume first (a point just outside
    /// follows the nearest cells; [`FfdLattice::weights_clamped`]), m.
    pub fn deform_clamped(&self, p: &Point3<f64>, nodes: &[Point3<f64>]) -> Result<Vector3<f64>, FfdError> {
        self.check_nodes(nodes)?;
        let (idx, w) = self.weights_clamped(p)?;
        Ok(Self::combine(&idx, &w, nodes))
    }

    /// The weighted sum of the stencil's nodes (a stencil from [`weights`](Self::weights) or
    /// [`weights_clamped`](Self::weights_clamped)), m: with the stencil kept, mapping a fixed rest point through
    /// new nodes costs only this sum. `nodes` must have [`node_count`](Self::node_count) entries (panics otherwise).
    pub fn combine(idx: &[usize; 27], w: &[f64; 27], nodes: &[Point3<f64>]) -> Vector3<f64> {
        let mut x = Vector3::zeros();
        for m in 0..27 {
            x += w[m] * nodes[idx[m]].coords;
        }
        x
    }

    /// Jacobian d(deformed)/d(rest) (dimensionless, 3x3) at rest point `p` (m): column a is the
    /// derivative along rest axis a. Errors outside the embedded volume.
    pub fn jacobian(
        &self,
        p: &Point3<f64>,
        nodes: &[Point3<f64>],
    ) -> Result<nalgebra::Matrix3<f64>, FfdError> {
        self.check_nodes(nodes)?;
        let (lower, t) = self
            .locate(p, false)
            .ok_or(FfdError::Outside(p.x, p.y, p.z))?;
        let b = [basis(t[0]), basis(t[1]), basis(t[2])];
        let d = [
            basis_derivative(t[0]),
            basis_derivative(t[1]),
            basis_derivative(t[2]),
        ];
        let mut jac = nalgebra::Matrix3::zeros();
        for c in 0..3 {
            for bb in 0..3 {
                for a in 0..3 {
                    let x = nodes[self.index(lower[0] + a, lower[1] + bb, lower[2] + c)].coords;
                    let g = Vector3::new(
                        d[0][a] * b[1][bb] * b[2][c],
                        b[0][a] * d[1][bb] * b[2][c],
                        b[0][a] * b[1][bb] * d[2][c],
                    ) / self.h;
                    jac += x * g.transpose();
                }
            }
        }
        Ok(jac)
    }
}

/// Precomputed FFD weights of many points (structure of arrays): point q uses nodes
/// `indices[27 q .. 27 q + 27]` with weights `weights[27 q .. 27 q + 27]`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Binding {
    /// Flat node indices, 27 per point.
    pub indices: Vec<u32>,
    /// Weights (dimensionless), 27 per point, each point's summing to 1.
    pub weights: Vec<f64>,
    /// Number of nodes of the lattice the binding was made for.
    pub node_count: usize,
}

impl Binding {
    /// Binds rest points `points` (m) to `lattice`; errors if any point is outside the embedded
    /// volume (use [`Binding::new_clamped`] to clamp instead).
    pub fn new(lattice: &FfdLattice, points: &[Point3<f64>]) -> Result<Self, FfdError> {
        Self::build(lattice, points, false)
    }

    /// Binds rest points `points` (m) to `lattice`, clamping points outside the embedded volume.
    pub fn new_clamped(lattice: &FfdLattice, points: &[Point3<f64>]) -> Result<Self, FfdError> {
        Self::build(lattice, points, true)
    }

    fn build(lattice: &FfdLattice, points: &[Point3<f64>], clamp: bool) -> Result<Self, FfdError> {
        let mut b = Binding {
            indices: Vec::with_capacity(27 * points.len()),
            weights: Vec::with_capacity(27 * points.len()),
            node_count: lattice.node_count(),
        };
        for p in points {
            let (idx, w) = if clamp {
                lattice.weights_clamped(p)?
            } else {
                lattice.weights(p)?
            };
            b.indices.extend(idx.iter().map(|&i| i as u32));
            b.weights.extend_from_slice(&w);
        }
        Ok(b)
    }

    /// Number of bound points.
    pub fn len(&self) -> usize {
        self.weights.len() / 27
    }

    /// True if no point is bound.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Writes the deformed positions (m) of the bound points into `out` (resized to
    /// [`len`](Self::len)), given current node positions `nodes` (m, flat order). One thread.
    pub fn apply(&self, nodes: &[Point3<f64>], out: &mut Vec<Point3<f64>>) -> Result<(), FfdError> {
        self.check_nodes(nodes)?;
        out.resize(self.len(), Point3::origin());
        self.deform_range(nodes, 0, out);
        Ok(())
    }

    /// As [`Binding::apply`], spread over all cores (rayon), in chunks of 4096 points. The result is
    /// identical to the one-thread version, bit for bit (each point is computed the same way).
    pub fn apply_parallel(&self, nodes: &[Point3<f64>], out: &mut Vec<Point3<f64>>) -> Result<(), FfdError> {
        use rayon::prelude::*;
        self.check_nodes(nodes)?;
        out.resize(self.len(), Point3::origin());
        const CHUNK: usize = 4096;
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| self.deform_range(nodes, c * CHUNK, chunk));
        Ok(())
    }

    fn check_nodes(&self, nodes: &[Point3<f64>]) -> Result<(), FfdError> {
        if nodes.len() != self.node_count {
            return Err(FfdError::NodeCount {
                expected: self.node_count,
                got: nodes.len(),
            });
        }
        Ok(())
    }

    /// Deformed positions of the points `first..first + out.len()`.
    fn deform_range(&self, nodes: &[Point3<f64>], first: usize, out: &mut [Point3<f64>]) {
        let idx = &self.indices[27 * first..27 * (first + out.len())];
        let wts = &self.weights[27 * first..27 * (first + out.len())];
        for ((o, idx), w) in out.iter_mut().zip(idx.chunks_exact(27)).zip(wts.chunks_exact(27)) {
            let mut x = Vector3::zeros();
            for m in 0..27 {
                x += w[m] * nodes[idx[m] as usize].coords;
            }
            *o = Point3::from(x);
        }
    }
}

/// A compact FFD binding for very many points (e.g. 150,000 strands x 32 vertices): per point the
/// flat index of its lowest stencil node (u32) and the 3 x 3 per-axis B-spline weights (f32),
/// 40 bytes a point against 324 for [`Binding`]; positions come out as f32 (m). The 27 weights
/// are the products of the per-axis ones, as in [`FfdLattice::weights`]; the result agrees with
/// [`Binding::apply`] to about 1e-7 m for lattices within a metre of the origin.
#[derive(Debug, Clone, PartialEq)]
pub struct CompactBinding {
    /// Per point: flat index of node (i-1, j-1, k-1) of its cell (i, j, k).
    base: Vec<u32>,
    /// Per point: x weights B0..B2, then y, then z (dimensionless).
    weights: Vec<[f32; 9]>,
    nx: usize,
    ny: usize,
    node_count: usize,
}

impl CompactBinding {
    /// Binds rest points `points` (m, f32 as render strands store them) to `lattice`; `clamp`
    /// clamps points outside the embedded volume, otherwise they give [`FfdError::Outside`].
    pub fn new(lattice: &FfdLattice, points: &[[f32; 3]], clamp: bool) -> Result<Self, FfdError> {
        if lattice.node_count() > u32::MAX as usize {
            return Err(FfdError::InvalidLattice(format!(
                "{} nodes do not fit u32 indices",
                lattice.node_count()
            )));
        }
        let mut base = Vec::with_capacity(points.len());
        let mut weights = Vec::with_capacity(points.len());
        for q in points {
            let p = Point3::new(q[0] as f64, q[1] as f64, q[2] as f64);
            let (lower, t) = lattice
                .locate(&p, clamp)
                .ok_or(FfdError::Outside(p.x, p.y, p.z))?;
            base.push(lattice.index(lower[0], lower[1], lower[2]) as u32);
            let mut w = [0f32; 9];
            for a in 0..3 {
                let b = basis(t[a]);
                for m in 0..3 {
                    w[3 * a + m] = b[m] as f32;
                }
            }
            weights.push(w);
        }
        Ok(Self {
            base,
            weights,
            nx: lattice.nx,
            ny: lattice.ny,
            node_count: lattice.node_count(),
        })
    }

    /// Number of bound points.
    pub fn len(&self) -> usize {
        self.base.len()
    }

    /// True if no point is bound.
    pub fn is_empty(&self) -> bool {
        self.base.is_empty()
    }

    /// Bytes held per bound point (index + weights).
    pub const BYTES_PER_POINT: usize = 4 + 9 * 4;

    fn nodes_f32(&self, nodes: &[Point3<f64>]) -> Result<Vec<[f32; 3]>, FfdError> {
        if nodes.len() != self.node_count {
            return Err(FfdError::NodeCount {
                expected: self.node_count,
                got: nodes.len(),
            });
        }
        Ok(nodes
            .iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect())
    }

    /// Writes the deformed positions (m, f32) of the bound points into `out` (resized to
    /// [`len`](Self::len)), given node positions `nodes` (m, flat order). One thread.
    pub fn apply(&self, nodes: &[Point3<f64>], out: &mut Vec<[f32; 3]>) -> Result<(), FfdError> {
        let n = self.nodes_f32(nodes)?;
        out.resize(self.len(), [0.0; 3]);
        self.deform_range(&n, 0, out);
        Ok(())
    }

    /// As [`CompactBinding::apply`], spread over all cores (rayon) in chunks of 4096 points;
    /// identical to the one-thread result bit for bit.
    pub fn apply_parallel(
        &self,
        nodes: &[Point3<f64>],
        out: &mut Vec<[f32; 3]>,
    ) -> Result<(), FfdError> {
        use rayon::prelude::*;
        let n = self.nodes_f32(nodes)?;
        out.resize(self.len(), [0.0; 3]);
        const CHUNK: usize = 4096;
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| self.deform_range(&n, c * CHUNK, chunk));
        Ok(())
    }

    fn deform_range(&self, nodes: &[[f32; 3]], first: usize, out: &mut [[f32; 3]]) {
        let (sy, sz) = (self.nx, self.nx * self.ny);
        let base = &self.base[first..first + out.len()];
        let wts = &self.weights[first..first + out.len()];
        for ((o, &b), w) in out.iter_mut().zip(base).zip(wts) {
            let b = b as usize;
            let mut x = [0f32; 3];
            for c in 0..3 {
                let mut yz = [0f32; 3];
                for bb in 0..3 {
                    let row = &nodes[b + c * sz + bb * sy..b + c * sz + bb * sy + 3];
                    let mut r = [0f32; 3];
                    for a in 0..3 {
                        for d in 0..3 {
                            r[d] += w[a] * row[a][d];
                        }
                    }
                    for d in 0..3 {
                        yz[d] += w[3 + bb] * r[d];
                    }
                }
                for d in 0..3 {
                    x[d] += w[6 + c] * yz[d];
                }
            }
            *o = x;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3};

    fn lattice() -> FfdLattice {
        FfdLattice::new(Point3::new(-0.1, 0.05, -0.2), 0.03, [6, 5, 7]).unwrap()
    }

    /// Deterministic pseudo-random points filling the embedded volume (including its boundary).
    fn sample_points(l: &FfdLattice, n: usize) -> Vec<Point3<f64>> {
        let mut seed = 0x9E3779B97F4A7C15u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let dims = [l.nx, l.ny, l.nz];
        let mut pts: Vec<Point3<f64>> = (0..n)
            .map(|_| {
                let mut p = l.origin;
                for a in 0..3 {
                    let s = 0.5 + rnd() * (dims[a] as f64 - 2.0);
                    p[a] += s * l.h;
                }
                p
            })
            .collect();
        // corners of the embedded volume and a node and a cell face
        let lo = l.origin + Vector3::repeat(0.5 * l.h);
        let hi =
            l.origin + l.h * Vector3::new(l.nx as f64 - 1.5, l.ny as f64 - 1.5, l.nz as f64 - 1.5);
        pts.push(lo);
        pts.push(hi);
        pts.push(l.rest_position(2, 2, 3));
        pts.push(l.origin + l.h * Vector3::new(2.5, 1.5, 3.5));
        pts
    }

    fn wiggled_nodes(l: &FfdLattice) -> Vec<Point3<f64>> {
        l.rest_positions()
            .iter()
            .enumerate()
            .map(|(q, p)| {
                let f = q as f64;
                p + 0.01 * Vector3::new((1.3 * f).sin(), (2.1 * f).cos(), (0.7 * f + 1.0).sin())
            })
            .collect()
    }

    #[test]
    fn partition_of_unity() {
        let l = lattice();
        for p in sample_points(&l, 500) {
            let (_, w) = l.weights(&p).unwrap();
            let s: f64 = w.iter().sum();
            assert!((s - 1.0).abs() < 1e-12, "sum {s}");
            assert!(w.iter().all(|&x| x >= 0.0));
        }
    }

    #[test]
    fn undeformed_lattice_is_identity() {
        let l = lattice();
        let nodes = l.rest_positions();
        let pts = sample_points(&l, 500);
        for p in &pts {
            let x = l.deform(p, &nodes).unwrap();
            assert!((x - p.coords).norm() < 1e-12, "{p} -> {x}");
        }
        let b = Binding::new(&l, &pts).unwrap();
        let mut out = Vec::new();
        b.apply(&nodes, &mut out).unwrap();
        for (p, x) in pts.iter().zip(&out) {
            assert!((x - p).norm() < 1e-12);
        }
    }

    #[test]
    fn affine_deformation_is_reproduced() {
        let l = lattice();
        let rot = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, -0.5)),
            0.8,
        );
        let a: Matrix3<f64> = rot.matrix() * Matrix3::from_diagonal(&Vector3::new(1.3, 0.7, 2.0));
        let shift = Vector3::new(0.4, -1.2, 0.3);
        let map = |p: &Point3<f64>| a * p.coords + shift;
        let nodes: Vec<Point3<f64>> = l
            .rest_positions()
            .iter()
            .map(|p| Point3::from(map(p)))
            .collect();
        let pts = sample_points(&l, 500);
        let b = Binding::new(&l, &pts).unwrap();
        let mut out = Vec::new();
        b.apply(&nodes, &mut out).unwrap();
        for (p, x) in pts.iter().zip(&out) {
            let want = map(p);
            assert!((x.coords - want).norm() < 1e-12, "{p}: {x} vs {want}");
            assert!((l.deform(p, &nodes).unwrap() - want).norm() < 1e-12);
            assert!((l.jacobian(p, &nodes).unwrap() - a).norm() < 1e-12);
        }
    }

    /// C1 across the face between cells 2 and 3 along each axis, with wiggled (non-affine) nodes.
    /// Value: |x(b+e) - x(b-e)| <= 2 e |J| + 1e-12 with e = 1e-9 m (continuity, no jump).
    /// Gradient: one-sided central FD (step d = 1e-6 m) taken entirely within each cell, at
    /// distance e + d of the face; the two must agree to 1e-4 (they differ by O(d) x the second
    /// derivative, which jumps across the face: |x''| <~ 0.1/h^2 here).
    /// Analytic Jacobians at +-e of the face agree to 1e-6 (they differ by about 2 e |x''|; the
    /// wiggles of 0.01 m over h = 0.03 m give |x''| ~ 0.04 m / h^2 ~ 50 /m, so ~1e-7; a C0-only
    /// interpolant would jump by O(0.01 m / h) ~ 0.3 here).
    #[test]
    fn c1_across_cell_faces() {
        let l = lattice();
        let nodes = wiggled_nodes(&l);
        let base = l.origin + l.h * Vector3::new(2.3, 1.8, 3.1);
        let e = 1e-9;
        let d = 1e-6;
        for a in 0..3 {
            let mut face = base;
            face[a] = l.origin[a] + 2.5 * l.h; // boundary between cells 2 and 3
            let mut dir = Vector3::zeros();
            dir[a] = 1.0;
            let f = |p: Point3<f64>| l.deform(&p, &nodes).unwrap();
            let jump = (f(face + e * dir) - f(face - e * dir)).norm();
            let jnorm = l.jacobian(&face, &nodes).unwrap().norm();
            assert!(jump <= 2.0 * e * jnorm + 1e-12, "value jump {jump}");
            for g in 0..3 {
                let mut dg = Vector3::zeros();
                dg[g] = d;
                let lp = face - (e + d) * dir;
                let rp = face + (e + d) * dir;
                let gl = (f(lp + dg) - f(lp - dg)) / (2.0 * d);
                let gr = (f(rp + dg) - f(rp - dg)) / (2.0 * d);
                assert!((gl - gr).norm() < 1e-3, "axis {a} grad {g}: {gl} vs {gr}");
            }
            let jl = l.jacobian(&(face - e * dir), &nodes).unwrap();
            let jr = l.jacobian(&(face + e * dir), &nodes).unwrap();
            assert!(
                (jl - jr).norm() < 1e-6,
                "jacobian jump {}",
                (jl - jr).norm()
            );
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let l = lattice();
        let nodes = wiggled_nodes(&l);
        let p = l.origin + l.h * Vector3::new(2.3, 1.8, 3.1);
        let j = l.jacobian(&p, &nodes).unwrap();
        let d = 1e-6;
        for a in 0..3 {
            let mut dv = Vector3::zeros();
            dv[a] = d;
            let fd = (l.deform(&(p + dv), &nodes).unwrap() - l.deform(&(p - dv), &nodes).unwrap())
                / (2.0 * d);
            assert!((fd - j.column(a)).norm() < 1e-7, "{fd} vs {}", j.column(a));
        }
    }

    #[test]
    fn outside_errors_and_clamped_does_not() {
        let l = lattice();
        let p = l.origin + Vector3::repeat(0.4 * l.h); // s = 0.4 < 1/2
        assert!(matches!(l.weights(&p), Err(FfdError::Outside(..))));
        let (idx, w) = l.weights_clamped(&p).unwrap();
        let (idx0, w0) = l.weights(&(l.origin + Vector3::repeat(0.5 * l.h))).unwrap();
        assert_eq!(idx, idx0);
        for m in 0..27 {
            assert!((w[m] - w0[m]).abs() < 1e-12);
        }
        let far = l.origin + l.h * Vector3::new(l.nx as f64, 1.0, 1.0);
        assert!(l.weights(&far).is_err());
        assert!(l.weights_clamped(&far).is_ok());
        assert!(l.weights_clamped(&Point3::new(f64::NAN, 0.0, 0.0)).is_err());
        assert!(l.deform(&l.rest_position(2, 2, 2), &[]).is_err());
    }

    #[test]
    fn enclosing_lattice_contains_the_box() {
        let lo = Point3::new(-0.12, -0.1, -0.15);
        let hi = Point3::new(0.12, 0.2, 0.1);
        let l = FfdLattice::enclosing(lo, hi, 0.025).unwrap();
        assert!(l.weights(&lo).is_ok());
        assert!(l.weights(&hi).is_ok());
        assert!(FfdLattice::new(Point3::origin(), 0.1, [2, 3, 3]).is_err());
        assert!(FfdLattice::new(Point3::origin(), 0.0, [3, 3, 3]).is_err());
    }

    #[test]
    fn parallel_apply_equals_serial_bit_for_bit() {
        let l = lattice();
        let pts = sample_points(&l, 10_000);
        let b = Binding::new_clamped(&l, &pts).unwrap();
        let nodes: Vec<Point3<f64>> = l.rest_positions().iter().enumerate().map(|(i, p)| p + Vector3::new((i as f64).sin() * 1e-3, 0.0, 2e-3)).collect();
        let (mut a, mut c) = (Vec::new(), Vec::new());
        b.apply(&nodes, &mut a).unwrap();
        b.apply_parallel(&nodes, &mut c).unwrap();
        assert_eq!(a, c);
        assert!(b.apply_parallel(&nodes[1..], &mut c).is_err());
    }
    /// The compact binding gives the full binding's positions to 1e-6 m (f32 weights and
    /// positions: about 1e-7 m here), serial and parallel alike, and checks the node count.
    #[test]
    fn compact_binding_matches_full_binding() {
        let l = lattice();
        let pts = sample_points(&l, 20_000);
        let pts32: Vec<[f32; 3]> = pts.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        // bind the full binding to the same f32-rounded rest points
        let pts64: Vec<Point3<f64>> = pts32.iter().map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
        let full = Binding::new_clamped(&l, &pts64).unwrap();
        let compact = CompactBinding::new(&l, &pts32, true).unwrap();
        assert_eq!(compact.len(), full.len());
        let nodes = wiggled_nodes(&l);
        let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
        full.apply(&nodes, &mut a).unwrap();
        compact.apply(&nodes, &mut b).unwrap();
        compact.apply_parallel(&nodes, &mut c).unwrap();
        assert_eq!(b, c);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - Point3::new(q[0] as f64, q[1] as f64, q[2] as f64)).norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "compact vs full: {worst} m");
        assert!(compact.apply(&nodes[1..], &mut b).is_err());
        let outside = [[l.origin.x as f32 - 1.0, l.origin.y as f32, l.origin.z as f32]];
        assert!(matches!(CompactBinding::new(&l, &outside, false), Err(FfdError::Outside(..))));
        assert!(CompactBinding::new(&l, &outside, true).is_ok());
    }
}
