//! Parameters of the lattice dynamics ([`LatticeParams`], [`CarryParams`]), the choices of its linear solve
//! ([`BendingJacobian`], [`FactorPrecision`], [`FillOrdering`]) and its errors ([`LatticeError`]).

use crate::metaball::MetaballParams;
use nalgebra::Vector3;
use thiserror::Error;

/// Errors of the lattice particle system.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LatticeError {
    /// A per-node array has the wrong length.
    #[error("expected {expected} per-node values, got {got}")]
    NodeCount {
        /// Number of nodes.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A node mass is not positive and finite.
    #[error("node {0} has invalid mass {1} kg (must be > 0)")]
    InvalidMass(usize, f64),
    /// A parameter is out of range (named, with its value).
    #[error("invalid lattice parameter: {0}")]
    InvalidParameter(String),
    /// The FFD lattice could not be built.
    #[error(transparent)]
    Ffd(#[from] crate::ffd::FfdError),
}

/// Parameters of the lattice dynamics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeParams {
    /// Stiffness k_s of each stiffener (26-neighbour spring), N/m. Default 20 N/m.
    pub stiffener_stiffness: f64,
    /// Axial damping c_s of each stiffener, N s/m. Default 0.02 N s/m.
    pub stiffener_damping: f64,
    /// Stiffness of each bending stiffener (spring to the second neighbour along a lattice axis,
    /// two cells away), N/m; 0 adds none. Default 5 N/m.
    pub bending_stiffness: f64,
    /// Axial damping of each bending stiffener, N s/m. Default 0.005 N s/m.
    pub bending_damping: f64,
    /// Stiffness k_a of the attachment of a node with weight 1 to its head-fixed rest position,
    /// N/m. Default 5 N/m.
    pub attachment_stiffness: f64,
    /// Damping c_a of the attachment of a node with weight 1, N s/m. Default 0.01 N s/m.
    pub attachment_damping: f64,
    /// Gravity g, m/s^2. Default (0, 0, -9.81) (z up).
    pub gravity: Vector3<f64>,
    /// Relative residual at which the conjugate-gradient solve stops (dimensionless).
    /// Default 1e-10.
    pub cg_tolerance: f64,
    /// Maximum conjugate-gradient iterations per step. Default 500.
    pub cg_max_iterations: usize,
    /// Fill-reducing ordering of the factorised system matrix (speed only). Default
    /// [`FillOrdering::Auto`].
    pub fill_ordering: FillOrdering,
    /// How the bending stiffeners (to second neighbours) enter the implicit matrix (speed, and
    /// numerical damping of bending; never the forces). Default [`BendingJacobian::PathBound`].
    pub bending_jacobian: BendingJacobian,
    /// Precision in which the Cholesky factor of the implicit matrix is stored and applied
    /// (speed and memory; the forces and the state stay f64). Default [`FactorPrecision::F32`].
    pub factor_precision: FactorPrecision,
    /// Metaball collision response parameters (used when a step is given obstacles).
    /// Default: [`MetaballParams::default`] with penalty stiffness 1000 N/m and attraction
    /// 100 N/m, so the penalty dominates what an interior node's 26 stiffeners resist with
    /// along an axis (k_s (2 + 8/2 + 8/3) ~ 8.7 k_s = 173 N/m at the default k_s).
    pub metaball: MetaballParams,
}

impl Default for LatticeParams {
    fn default() -> Self {
        Self {
            stiffener_stiffness: 20.0,
            stiffener_damping: 0.02,
            bending_stiffness: 5.0,
            bending_damping: 0.005,
            attachment_stiffness: 5.0,
            attachment_damping: 0.01,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            cg_tolerance: 1e-10,
            cg_max_iterations: 500,
            fill_ordering: FillOrdering::Auto,
            bending_jacobian: BendingJacobian::PathBound,
            factor_precision: FactorPrecision::F32,
            metaball: MetaballParams {
                stiffness: 1000.0,
                attraction_stiffness: 100.0,
                ..MetaballParams::default()
            },
        }
    }
}

/// How a bending stiffener (i, k) of stiffness k_b (and damping c_b), joining two nodes two
/// cells apart along an axis through the middle node j, enters the constant implicit matrix
/// A = M + dt C' + dt^2 K' ([`LatticeParams::bending_jacobian`]). The forces are always the exact
/// ones; only the Jacobian approximation changes.
///
/// Both bounds below replace the stiffener's isotropic block s L_ik (s = dt c_b + dt^2 k_b,
/// L_ik the Laplacian of the pair, e^T L_ik e = |e_i - e_k|^2) by a larger one in the
/// positive-semidefinite order, from |a + b|^2 <= 2 |a|^2 + 2 |b|^2:
/// |e_i - e_k|^2 <= 2 |e_i - e_j|^2 + 2 |e_j - e_k|^2 (path) and <= 2 |e_i|^2 + 2 |e_k|^2
/// (diagonal). Like the isotropic stiffener block itself (module docs), a larger Jacobian only
/// adds numerical damping of the fast modes it overestimates; it never removes stability, and the
/// fixed points (static equilibria) are unchanged. What changes is the sparsity of A: without
/// second-neighbour entries the fill-reducing ordering can cut the lattice with one-node-thick
/// separators, and the Cholesky factor is much sparser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BendingJacobian {
    /// The exact isotropic block s L_ik on the pair (i, k) (second-neighbour entries in A).
    Laplacian,
    /// 2 s on the diagonal of i and of k: no off-diagonal entries at all (the crudest bound:
    /// it also damps rigid motion of the pair, so it slows the response most).
    DiagonalBound,
    /// 2 s L_ij + 2 s L_jk on the two first-neighbour edges through the middle node j (whose
    /// entries A has anyway): the pattern of A is the 26-neighbour one, and rigid motion stays
    /// undamped. Default.
    #[default]
    PathBound,
}

/// Precision of the stored Cholesky factor of the implicit matrix
/// ([`LatticeParams::factor_precision`]).
///
/// With [`FactorPrecision::F32`] the factor L is computed in f64, rounded to f32 and kept so; the
/// triangular solves run in f32 on f32 copies of the right-hand sides (half the memory traffic,
/// twice the SIMD width). The solve then returns A~^-1 b with A~ = L~ L~^T symmetric positive
/// definite and |A~ - A| <= c eps_32 |A| (eps_32 = 6e-8): the step is the same linearly implicit
/// Euler step with a slightly different (still symmetric, still >= M-like) approximate Jacobian,
/// so it stays first-order accurate, its fixed points are exactly the zeros of the forces, and
/// the relative change of dv is at most about eps_32 cond(A) (cond(A) = 1 + dt^2 k_max / m_min,
/// some 10^2 to 10^4 on hair lattices). With contacts the conjugate-gradient solve of the
/// contact system still reaches [`LatticeParams::cg_tolerance`] (the f32 factor is only its
/// preconditioner).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FactorPrecision {
    /// The factor in f64.
    F64,
    /// The factor in f32. Default.
    #[default]
    F32,
}

/// How a lattice is built around hair ([`LatticeModel::carrying`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarryParams {
    /// Lattice cell size, m. Default 0.02 m.
    pub cell: f64,
    /// Nodes within this distance (m) outside the body surface are fully attached (weight 1).
    /// Default 0.01 m.
    pub attach_distance: f64,
    /// Beyond `attach_distance` the attachment weight falls linearly to 0 over this distance, m.
    /// Default 0.02 m.
    pub attach_falloff: f64,
    /// Mass given to every node besides the hair it carries, kg (keeps empty nodes' equations
    /// well posed). Default 1e-6 kg.
    pub empty_node_mass: f64,
    /// Least attachment weight of any node, dimensionless in [0, 1]: nodes far from the body keep
    /// this share of the attachment spring (0: they hang on the stiffeners alone). Default 0 (the
    /// live scene uses 0.35: the hair's own stiffness holds its far ends to the head).
    pub min_attachment: f64,
}

impl Default for CarryParams {
    fn default() -> Self {
        Self {
            cell: 0.02,
            attach_distance: 0.01,
            attach_falloff: 0.02,
            empty_node_mass: 1e-6,
            min_attachment: 0.0,
        }
    }
}

impl CarryParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), LatticeError> {
        let bad =
            |field: &str, v: f64| Err(LatticeError::InvalidParameter(format!("{field} = {v}")));
        if !(self.cell > 0.0 && self.cell.is_finite()) {
            return bad("cell (m, > 0)", self.cell);
        }
        if !(self.attach_distance.is_finite()) {
            return bad("attach_distance (m, finite)", self.attach_distance);
        }
        if !(self.attach_falloff > 0.0 && self.attach_falloff.is_finite()) {
            return bad("attach_falloff (m, > 0)", self.attach_falloff);
        }
        if !(self.empty_node_mass > 0.0 && self.empty_node_mass.is_finite()) {
            return bad("empty_node_mass (kg, > 0)", self.empty_node_mass);
        }
        if !(0.0..=1.0).contains(&self.min_attachment) {
            return bad("min_attachment (in [0, 1])", self.min_attachment);
        }
        Ok(())
    }
}

/// Fill-reducing ordering of the sparse Cholesky factorisation of the system matrix
/// ([`LatticeParams::fill_ordering`]). It changes the cost of a step, never its result beyond
/// round-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FillOrdering {
    /// Both orderings below are analysed once per factorisation and the one giving the sparser
    /// factor is used. Default.
    #[default]
    Auto,
    /// Approximate minimum degree (faer's default).
    Amd,
    /// Geometric nested dissection of the regular lattice: recursive bisection of the node box
    /// along its longest axis by a separator slab as thick as the stiffeners reach (2 nodes with
    /// bending stiffeners, else 1), separators ordered last.
    NestedDissection,
}
