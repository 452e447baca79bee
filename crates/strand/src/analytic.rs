//! Analytic and independently computed answers the strand model is validated against (DESIGN.md 8).
//! None of this uses the Super-Helix code.

/// First roots `beta_n L` of the cantilever frequency equation `cos(bL) cosh(bL) = -1`.
pub const CANTILEVER_BETA_L: [f64; 3] = [1.875_104_068_711_961, 4.694_091_132_974_175, 7.854_757_438_237_613];

/// Greenhill's critical value of `q L^3 / EI` for a column standing up under its own weight.
pub const GREENHILL: f64 = 7.837;

/// Tip deflection of a small-deflection cantilever under a uniform load `q` (N/m): `q L^4 / (8 EI)`, m.
pub fn cantilever_tip_deflection(q: f64, length: f64, ei: f64) -> f64 {
    q * length.powi(4) / (8.0 * ei)
}

/// Natural angular frequency of bending mode `n` (0-based, up to 2) of a clamped-free Euler-Bernoulli beam
/// with flexural rigidity `ei` (N m^2) and mass per length `rho_a` (kg/m), rad/s.
pub fn cantilever_frequency(n: usize, ei: f64, rho_a: f64, length: f64) -> f64 {
    CANTILEVER_BETA_L[n].powi(2) * (ei / (rho_a * length.powi(4))).sqrt()
}

/// Length beyond which a strand standing up under its own weight (`q` N/m) buckles: `(7.837 EI / q)^(1/3)`, m.
pub fn greenhill_critical_length(ei: f64, q: f64) -> f64 {
    (GREENHILL * ei / q).cbrt()
}

/// Large-deflection cantilever under its own weight by shooting: solves `EI theta'' + q (L - s) cos theta = 0`,
/// `theta(0) = 0`, `theta'(L) = 0` (theta: angle below the horizontal) with RK4 over `steps` steps and bisection
/// on `theta'(0)`. Returns the tip `(x, z)` relative to the root (x along the root tangent, z up), m.
pub fn elastica_cantilever_tip(ei: f64, q: f64, length: f64, steps: usize) -> (f64, f64) {
    let h = length / steps as f64;
    let run = |c: f64| -> [f64; 4] {
        // y = (theta, theta', x, z)
        let f = |s: f64, y: &[f64; 4]| [y[1], -q * (length - s) * y[0].cos() / ei, y[0].cos(), -y[0].sin()];
        let mut y = [0.0, c, 0.0, 0.0];
        for i in 0..steps {
            let s = i as f64 * h;
            let add = |k: &[f64; 4], t: f64| [y[0] + t * k[0], y[1] + t * k[1], y[2] + t * k[2], y[3] + t * k[3]];
            let k1 = f(s, &y);
            let k2 = f(s + h / 2.0, &add(&k1, h / 2.0));
            let k3 = f(s + h / 2.0, &add(&k2, h / 2.0));
            let k4 = f(s + h, &add(&k3, h));
            for j in 0..4 {
                y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
        }
        y
    };
    // theta'(L) grows with theta'(0); the root moment is at most q L^2 / 2.
    let (mut lo, mut hi) = (0.0, q * length * length / (2.0 * ei));
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if run(mid)[1] > 0.0 {
            hi = mid
        } else {
            lo = mid
        }
    }
    let y = run(0.5 * (lo + hi));
    (y[2], y[3])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequency_roots_solve_the_characteristic_equation() {
        for bl in CANTILEVER_BETA_L {
            assert!((bl.cos() * bl.cosh() + 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn shooting_reduces_to_linear_theory_for_small_loads() {
        // q L^3/EI = 1e-3: the tip drop equals q L^4 / 8EI to 1e-6 relative.
        let (ei, l) = (1.0, 1.0);
        let q = 1e-3;
        let (_, z) = elastica_cantilever_tip(ei, q, l, 2000);
        let lin = cantilever_tip_deflection(q, l, ei);
        assert!((-z - lin).abs() < 1e-6 * lin, "{z} vs {lin}");
    }
}
