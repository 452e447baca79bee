//! Small dense linear algebra for the step's symmetric positive definite systems, in place and without
//! allocation (the matrices are at most a few hundred rows).

use nalgebra::{DMatrix, DVector};

/// Cholesky factorization `A = L L^T` in place: on success the lower triangle of `a` holds `L` (the strict
/// upper triangle is left as it was). Returns false if `a` is not (numerically) positive definite.
pub fn cholesky_in_place(a: &mut DMatrix<f64>) -> bool {
    let n = a.nrows();
    for j in 0..n {
        // Column-major storage: column j is contiguous.
        let mut d = a[(j, j)];
        for k in 0..j {
            let l = a[(j, k)];
            d -= l * l;
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[(j, j)] = d;
        let inv = 1.0 / d;
        for k in 0..j {
            let ljk = a[(j, k)];
            if ljk != 0.0 {
                for i in j + 1..n {
                    let v = a[(i, k)];
                    a[(i, j)] -= v * ljk;
                }
            }
        }
        for i in j + 1..n {
            a[(i, j)] *= inv;
        }
    }
    true
}

/// Solves `L L^T x = b` in place, with `L` in the lower triangle of `l` (from [`cholesky_in_place`]).
pub fn cholesky_solve_in_place(l: &DMatrix<f64>, b: &mut DVector<f64>) {
    let n = l.nrows();
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_systems_and_rejects_indefinite_ones() {
        // A = B B^T + n I is SPD; the solution satisfies A x = b to 1e-12 relative.
        let n = 17;
        let b = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
        let a = &b * b.transpose() + DMatrix::identity(n, n) * n as f64;
        let rhs = DVector::from_fn(n, |i, _| (i as f64).sin());
        let mut l = a.clone();
        assert!(cholesky_in_place(&mut l));
        let mut x = rhs.clone();
        cholesky_solve_in_place(&l, &mut x);
        assert!((&a * &x - &rhs).norm() < 1e-12 * rhs.norm() * a.norm());
        let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_in_place(&mut bad));
        let mut nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky_in_place(&mut nan));
    }
}
