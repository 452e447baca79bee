//! The lattice step's linear algebra: the constant implicit matrix A = M + dt C' + dt^2 K' in
//! compressed rows ([`ScalarCsr`]), its fill-reducing ordering (`faer`'s AMD or a grid nested
//! dissection, [`FillOrdering`]), its sparse Cholesky factorisation ([`Factor`], f64 or f32 values)
//! and the conjugate-gradient solve of the contact system (A + D) dv = b preconditioned by it
//! ([`pcg_contacts`]). The derivation is in the docs of [`crate::lattice`].

use crate::model::LatticeModel;
use crate::params::{BendingJacobian, FactorPrecision, FillOrdering};
use nalgebra::Vector3;

/// A symmetric scalar sparse matrix in compressed rows (node by node), applied to the three
/// columns x, y, z at once.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct ScalarCsr {
    n: usize,
    row: Vec<u32>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl ScalarCsr {
    /// Sum of duplicate (row, col, value) entries.
    pub(crate) fn from_entries(n: usize, mut e: Vec<(u32, u32, f64)>) -> Self {
        e.sort_unstable_by_key(|&(r, c, _)| (r, c));
        let mut m = ScalarCsr {
            n,
            row: vec![0; n + 1],
            col: Vec::with_capacity(e.len()),
            val: Vec::with_capacity(e.len()),
        };
        let mut last = (u32::MAX, u32::MAX);
        for (r, c, v) in e {
            if (r, c) == last {
                *m.val.last_mut().unwrap() += v;
            } else {
                m.col.push(c);
                m.val.push(v);
                m.row[r as usize + 1] = m.col.len() as u32;
                last = (r, c);
            }
        }
        for i in 0..n {
            m.row[i + 1] = m.row[i + 1].max(m.row[i]);
        }
        m
    }

    /// out = self * x for each of the three columns (column-major n x 3).
    pub(crate) fn mul_cols(&self, x: &[f64], out: &mut [f64]) {
        let n = self.n;
        let (x0, rest) = x.split_at(n);
        let (x1, x2) = rest.split_at(n);
        for i in 0..n {
            let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
            for k in self.row[i] as usize..self.row[i + 1] as usize {
                let j = self.col[k] as usize;
                let w = self.val[k];
                a += w * x0[j];
                b += w * x1[j];
                c += w * x2[j];
            }
            out[i] = a;
            out[n + i] = b;
            out[2 * n + i] = c;
        }
    }
}

/// Nested-dissection ordering of an `nx` x `ny` x `nz` grid (node (i, j, k) at flat index
/// i + nx (j + ny k)) whose couplings reach `reach` nodes along an axis: `order[new] = old`.
pub(crate) fn grid_nested_dissection(nx: usize, ny: usize, nz: usize, reach: usize) -> Vec<usize> {
    fn rec(lo: [usize; 3], hi: [usize; 3], dims: [usize; 3], reach: usize, out: &mut Vec<usize>) {
        let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        if ext.iter().any(|&e| e == 0) {
            return;
        }
        let axis = (0..3).max_by_key(|&a| ext[a]).expect("three axes");
        if ext[axis] < 2 * reach + 2 || ext[0] * ext[1] * ext[2] <= 16 {
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
                    for i in lo[0]..hi[0] {
                        out.push(i + dims[0] * (j + dims[1] * k));
                    }
                }
            }
            return;
        }
        let mid = lo[axis] + (ext[axis] - reach) / 2;
        let (mut left_hi, mut sep_lo, mut sep_hi, mut right_lo) = (hi, lo, hi, lo);
        left_hi[axis] = mid;
        sep_lo[axis] = mid;
        sep_hi[axis] = mid + reach;
        right_lo[axis] = mid + reach;
        rec(lo, left_hi, dims, reach, out);
        rec(right_lo, hi, dims, reach, out);
        rec_flat(sep_lo, sep_hi, dims, out);
    }
    fn rec_flat(lo: [usize; 3], hi: [usize; 3], dims: [usize; 3], out: &mut Vec<usize>) {
        for k in lo[2]..hi[2] {
            for j in lo[1]..hi[1] {
                for i in lo[0]..hi[0] {
                    out.push(i + dims[0] * (j + dims[1] * k));
                }
            }
        }
    }
    let mut out = Vec::with_capacity(nx * ny * nz);
    rec([0, 0, 0], [nx, ny, nz], [nx, ny, nz], reach.max(1), &mut out);
    out
}

/// The constant part of the implicit system for one model and step: A = M + dt C' +
/// dt^2 K' (scalar, shared by the three axes), and A's sparse Cholesky factorisation
/// (symbolic part and values of L, faer's low-level API so the solve's scratch can be kept).
pub(crate) struct Factor {
    a: ScalarCsr,
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    l_values: LValues,
    /// Per stiffener: the middle node of a bending stiffener (two cells along an axis), else
    /// `u32::MAX`. Used with the bending Jacobian bounds.
    pub(crate) mid: Vec<u32>,
    /// The bending Jacobian the matrix was built with.
    pub(crate) bending: BendingJacobian,
}

/// The stored values of the Cholesky factor, in the chosen precision.
enum LValues {
    F64(Vec<f64>),
    F32(Vec<f32>),
}

/// No middle node (not a bending stiffener).
pub(crate) const NO_MID: u32 = u32::MAX;

impl Factor {
    pub(crate) fn new(model: &LatticeModel, dt: f64) -> Self {
        use faer::sparse::linalg::cholesky as chol;
        let n = model.node_count();
        let p = &model.params;
        let mut ae = Vec::with_capacity(2 * model.stiffeners.len() + n);
        for i in 0..n {
            let a = model.attachment[i];
            let kd = a * p.attachment_stiffness;
            ae.push((
                i as u32,
                i as u32,
                model.masses[i] + dt * a * p.attachment_damping + dt * dt * kd,
            ));
        }
        let f = &model.ffd;
        let (nx, nxy) = (f.nx, f.nx * f.ny);
        let ijk = |q: usize| [(q % nx) as i64, ((q % nxy) / nx) as i64, (q / nxy) as i64];
        let mid: Vec<u32> = model
            .stiffeners
            .iter()
            .map(|s| {
                let (a, b) = (ijk(s.i), ijk(s.j));
                let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let axial = d.iter().filter(|&&x| x != 0).count() == 1
                    && d.iter().any(|&x| x.abs() == 2);
                if axial {
                    ((s.i + s.j) / 2) as u32
                } else {
                    NO_MID
                }
            })
            .collect();
        let bending = p.bending_jacobian;
        let pair = |ae: &mut Vec<(u32, u32, f64)>, i: u32, j: u32, sa: f64| {
            for (r, c, sign) in [(i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)] {
                ae.push((r, c, sign * sa));
            }
        };
        for (s, &m) in model.stiffeners.iter().zip(&mid) {
            let (i, j) = (s.i as u32, s.j as u32);
            let sa = dt * s.damping + dt * dt * s.stiffness;
            match (m, bending) {
                (NO_MID, _) | (_, BendingJacobian::Laplacian) => pair(&mut ae, i, j, sa),
                (_, BendingJacobian::DiagonalBound) => {
                    ae.push((i, i, 2.0 * sa));
                    ae.push((j, j, 2.0 * sa));
                }
                (m, BendingJacobian::PathBound) => {
                    pair(&mut ae, i, m, 2.0 * sa);
                    pair(&mut ae, m, j, 2.0 * sa);
                }
            }
        }
        let a = ScalarCsr::from_entries(n, ae);
        let mut trip = Vec::with_capacity(a.val.len());
        for r in 0..n {
            for q in a.row[r] as usize..a.row[r + 1] as usize {
                trip.push(faer::sparse::Triplet::new(r, a.col[q] as usize, a.val[q]));
            }
        }
        let mat = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
            .expect("valid sparse pattern");
        // the longest axial reach of an off-diagonal entry of A, in nodes (2 with bending
        // stiffeners in the Laplacian form)
        let mut reach = 1;
        for r in 0..n {
            for q in a.row[r] as usize..a.row[r + 1] as usize {
                let (x, y) = (ijk(r), ijk(a.col[q] as usize));
                for c in 0..3 {
                    reach = reach.max((x[c] - y[c]).unsigned_abs() as usize);
                }
            }
        }
        let symbolic_with = |ord: chol::SymmetricOrdering<'_, usize>| {
            chol::factorize_symbolic_cholesky(
                mat.symbolic(),
                faer::Side::Lower,
                ord,
                Default::default(),
            )
            .expect("symbolic Cholesky of the lattice matrix")
        };
        let nd = || {
            let fwd = grid_nested_dissection(f.nx, f.ny, f.nz, reach);
            let mut inv = vec![0usize; n];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old] = new;
            }
            let perm = faer::perm::Perm::new_checked(fwd.into_boxed_slice(), inv.into_boxed_slice(), n);
            symbolic_with(chol::SymmetricOrdering::Custom(perm.as_ref()))
        };
        let symbolic = match p.fill_ordering {
            FillOrdering::Amd => symbolic_with(chol::SymmetricOrdering::Amd),
            FillOrdering::NestedDissection => nd(),
            FillOrdering::Auto => {
                let (amd, nd) = (symbolic_with(chol::SymmetricOrdering::Amd), nd());
                if nd.len_val() <= amd.len_val() {
                    nd
                } else {
                    amd
                }
            }
        };
        let par = faer::Par::Seq;
        let mut l_values = vec![0.0; symbolic.len_val()];
        let mut mem = faer::dyn_stack::MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut l_values,
                mat.as_ref(),
                faer::Side::Lower,
                Default::default(),
                par,
                faer::dyn_stack::MemStack::new(&mut mem),
                Default::default(),
            )
            .expect("M + dt C' + dt^2 K' is symmetric positive definite (masses > 0)");
        let l_values = match p.factor_precision {
            FactorPrecision::F64 => LValues::F64(l_values),
            FactorPrecision::F32 => LValues::F32(l_values.iter().map(|&x| x as f32).collect()),
        };
        Factor {
            a,
            symbolic,
            l_values,
            mid,
            bending,
        }
    }

    /// Number of stored values of the Cholesky factor L (its fill).
    pub(crate) fn factor_len(&self) -> usize {
        match &self.l_values {
            LValues::F64(v) => v.len(),
            LValues::F32(v) => v.len(),
        }
    }

    /// Bytes of the stored Cholesky factor values.
    pub(crate) fn factor_bytes(&self) -> usize {
        match &self.l_values {
            LValues::F64(v) => 8 * v.len(),
            LValues::F32(v) => 4 * v.len(),
        }
    }

    /// x <- A^-1 x for the three columns of x (column-major n x 3), with the solve's scratch
    /// taken from (and kept in) `scratch`.
    pub(crate) fn solve_in_place(&self, x: &mut [f64], scratch: &mut SolveScratch) {
        let n = self.a.n;
        let par = faer::Par::Seq;
        let key = self as *const Factor as usize;
        if scratch.0.as_ref().map(|(k, _)| *k) != Some(key) {
            let req = match self.l_values {
                LValues::F64(_) => self.symbolic.solve_in_place_scratch::<f64>(3, par),
                LValues::F32(_) => self.symbolic.solve_in_place_scratch::<f32>(3, par),
            };
            scratch.0 = Some((key, faer::dyn_stack::MemBuffer::new(req)));
        }
        let mem = &mut scratch.0.as_mut().expect("just set").1;
        match &self.l_values {
            LValues::F64(l) => {
                let m = faer::MatMut::from_column_major_slice_mut(x, n, 3);
                faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, l)
                    .solve_in_place_with_conj(
                        faer::Conj::No,
                        m,
                        par,
                        faer::dyn_stack::MemStack::new(mem),
                    );
            }
            LValues::F32(l) => {
                let y = &mut scratch.1;
                y.clear();
                y.extend(x.iter().map(|&v| v as f32));
                let m = faer::MatMut::from_column_major_slice_mut(&mut y[..], n, 3);
                faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, l)
                    .solve_in_place_with_conj(
                        faer::Conj::No,
                        m,
                        par,
                        faer::dyn_stack::MemStack::new(mem),
                    );
                for (o, &v) in x.iter_mut().zip(y.iter()) {
                    *o = v as f64;
                }
            }
        }
    }
}

/// Scratch memory of the triangular solves, kept between steps (sized for the cached factor,
/// which it is tagged with).
#[derive(Default)]
pub(crate) struct SolveScratch(Option<(usize, faer::dyn_stack::MemBuffer)>, Vec<f32>);

impl Clone for SolveScratch {
    fn clone(&self) -> Self {
        SolveScratch(None, Vec::new())
    }
}

impl std::fmt::Debug for SolveScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SolveScratch")
    }
}

/// One node in contact with an obstacle: its implicit block k n n^T (in K) and s n n^T (in A).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Contact {
    pub(crate) node: usize,
    pub(crate) normal: Vector3<f64>,
    pub(crate) k: f64,
    pub(crate) s: f64,
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// (A + D) y with D the contacts' blocks s n n^T.
pub(crate) fn apply_with_contacts(f: &Factor, contacts: &[Contact], n: usize, y: &[f64], out: &mut [f64]) {
    f.a.mul_cols(y, out);
    for c in contacts {
        let i = c.node;
        let yn = c.normal.x * y[i] + c.normal.y * y[n + i] + c.normal.z * y[2 * n + i];
        for k in 0..3 {
            out[k * n + i] += c.s * yn * c.normal[k];
        }
    }
}

/// Scratch buffers of the step (no allocation per step once sized).
#[derive(Debug, Clone, Default)]
pub(crate) struct StepWork {
    pub(crate) force: Vec<Vector3<f64>>,
    pub(crate) b: Vec<f64>,
    pub(crate) x: Vec<f64>,
    pub(crate) r: Vec<f64>,
    pub(crate) z: Vec<f64>,
    pub(crate) d: Vec<f64>,
    pub(crate) ad: Vec<f64>,
    pub(crate) contacts: Vec<Contact>,
    pub(crate) scratch: SolveScratch,
}

impl StepWork {
    pub(crate) fn resize(&mut self, n: usize) {
        if self.force.len() != n {
            self.force = vec![Vector3::zeros(); n];
            for v in [
                &mut self.b,
                &mut self.x,
                &mut self.r,
                &mut self.z,
                &mut self.d,
                &mut self.ad,
            ] {
                *v = vec![0.0; 3 * n];
            }
        }
    }
}

/// Conjugate gradients on (A + D) x = b preconditioned by A^-1 (the factorisation), starting from
/// `ws.x`; stops when |r| <= tol |b|. Returns the iterations used.
pub(crate) fn pcg_contacts(f: &Factor, ws: &mut StepWork, n: usize, tol: f64, max_iter: usize) -> usize {
    let b_norm = dot(&ws.b, &ws.b).sqrt();
    if b_norm == 0.0 {
        ws.x.iter_mut().for_each(|x| *x = 0.0);
        return 0;
    }
    apply_with_contacts(f, &ws.contacts, n, &ws.x, &mut ws.ad);
    for i in 0..3 * n {
        ws.r[i] = ws.b[i] - ws.ad[i];
    }
    if dot(&ws.r, &ws.r).sqrt() <= tol * b_norm {
        return 0;
    }
    ws.z.copy_from_slice(&ws.r);
    f.solve_in_place(&mut ws.z, &mut ws.scratch);
    ws.d.copy_from_slice(&ws.z);
    let mut rz = dot(&ws.r, &ws.z);
    for it in 0..max_iter {
        apply_with_contacts(f, &ws.contacts, n, &ws.d, &mut ws.ad);
        let alpha = rz / dot(&ws.d, &ws.ad);
        for i in 0..3 * n {
            ws.x[i] += alpha * ws.d[i];
            ws.r[i] -= alpha * ws.ad[i];
        }
        if dot(&ws.r, &ws.r).sqrt() <= tol * b_norm {
            return it + 1;
        }
        ws.z.copy_from_slice(&ws.r);
        f.solve_in_place(&mut ws.z, &mut ws.scratch);
        let rz_new = dot(&ws.r, &ws.z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..3 * n {
            ws.d[i] = ws.z[i] + beta * ws.d[i];
        }
    }
    max_iter
}

