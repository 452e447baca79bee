//! Lane arithmetic for [`super::StrandBatch`]: four strands' numbers side by side (`f64x4`), 3-vectors and 3x3
//! matrices of lanes, and the lane-wise helix kinematics (a segment's closed-form frame and its rates).

use super::LANES;
use crate::helix::{SERIES_A, SERIES_B, SERIES_BELOW, SERIES_C, SERIES_DB, SERIES_DC};
use crate::dynamics::Motion;
use nalgebra::{Matrix3, Vector3};
use std::ops::{Add, AddAssign, Mul, Neg, Sub};
use wide::{f64x4, CmpLt};

pub(super) type L = f64x4;

#[inline(always)]
pub(super) fn sp(x: f64) -> L {
    L::splat(x)
}

#[inline(always)]
pub(super) fn lane(x: L, j: usize) -> f64 {
    x.as_array_ref()[j]
}

/// A 3-vector of lanes.
#[derive(Debug, Clone, Copy)]
pub(super) struct V3 {
    pub(super) x: L,
    pub(super) y: L,
    pub(super) z: L,
}

impl V3 {
    #[inline(always)]
    pub(super) fn new(x: L, y: L, z: L) -> Self {
        Self { x, y, z }
    }
    #[inline(always)]
    pub(super) fn zero() -> Self {
        Self::new(sp(0.0), sp(0.0), sp(0.0))
    }
    #[inline(always)]
    pub(super) fn dot(self, o: V3) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    pub(super) fn cross(self, o: V3) -> V3 {
        V3::new(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)
    }
    #[inline(always)]
    pub(super) fn cmul(self, o: V3) -> V3 {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    #[inline(always)]
    pub(super) fn norm_squared(self) -> L {
        self.dot(self)
    }
    pub(super) fn gather(v: [Vector3<f64>; LANES]) -> Self {
        V3::new(L::from([v[0].x, v[1].x, v[2].x, v[3].x]), L::from([v[0].y, v[1].y, v[2].y, v[3].y]), L::from([v[0].z, v[1].z, v[2].z, v[3].z]))
    }
    #[inline(always)]
    pub(super) fn lane(self, j: usize) -> Vector3<f64> {
        Vector3::new(lane(self.x, j), lane(self.y, j), lane(self.z, j))
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl AddAssign for V3 {
    #[inline(always)]
    fn add_assign(&mut self, o: V3) {
        *self = *self + o;
    }
}
impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3::new(-self.x, -self.y, -self.z)
    }
}
impl Mul<L> for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, s: L) -> V3 {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
}

/// A 3x3 matrix of lanes, row-major.
#[derive(Debug, Clone, Copy)]
pub(super) struct M3 {
    pub(super) r: [[L; 3]; 3],
}

impl M3 {
    #[inline(always)]
    pub(super) fn mul_v(&self, v: V3) -> V3 {
        let r = &self.r;
        V3::new(r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z, r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z, r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z)
    }
    /// `self^T v`.
    #[inline(always)]
    pub(super) fn tr_mul_v(&self, v: V3) -> V3 {
        let r = &self.r;
        V3::new(r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z, r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z, r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z)
    }
    #[inline(always)]
    pub(super) fn mul_m(&self, o: &M3) -> M3 {
        let mut out = [[sp(0.0); 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = self.r[i][0] * o.r[0][j] + self.r[i][1] * o.r[1][j] + self.r[i][2] * o.r[2][j];
            }
        }
        M3 { r: out }
    }
    pub(super) fn gather(m: [Matrix3<f64>; LANES]) -> Self {
        let mut r = [[sp(0.0); 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = L::from([m[0][(i, j)], m[1][(i, j)], m[2][(i, j)], m[3][(i, j)]]);
            }
        }
        M3 { r }
    }
    pub(super) fn lane(&self, k: usize) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| lane(self.r[i][j], k))
    }
}

/// Motion of a frame, lane-wise (see `dynamics::Motion`).
#[derive(Debug, Clone, Copy)]
pub(super) struct MotionL {
    pub(super) rot: M3,
    pub(super) x: V3,
    pub(super) v: V3,
    pub(super) a: V3,
    pub(super) w: V3,
    pub(super) alpha: V3,
}

impl MotionL {
    pub(super) fn lane(&self, j: usize) -> Motion {
        Motion { rot: self.rot.lane(j), x: self.x.lane(j), v: self.v.lane(j), a: self.a.lane(j), w: self.w.lane(j), alpha: self.alpha.lane(j) }
    }
}

/// `dynamics::PointKinematics::<2>`, lane-wise.
pub(super) struct PointL {
    pub(super) motion: MotionL,
    pub(super) w_cols: [V3; 2],
    pub(super) u_cols: [V3; 2],
}


/// `helix::coefficients_with_rates`, lane-wise: `[a, b, c, db, dc, b_dot, c_dot, db_dot, dc_dot]`. Each lane
/// takes the series or the closed form as the scalar code does; a branch no lane needs is skipped.
#[inline(always)]
pub(super) fn coefficients_with_rates(u: L, u_dot: L) -> [L; 9] {
    let below = u.cmp_lt(sp(SERIES_BELOW));
    let series = || {
        let horner = |k: &[f64]| {
            let (mut p, mut dp) = (sp(k[k.len() - 1]), sp(0.0));
            for &c in k[..k.len() - 1].iter().rev() {
                dp = dp * u + p;
                p = p * u + sp(c);
            }
            (p, dp * u_dot)
        };
        let (b, c, db, dc, a) = (horner(&SERIES_B), horner(&SERIES_C), horner(&SERIES_DB), horner(&SERIES_DC), horner(&SERIES_A).0);
        [a, b.0, c.0, db.0, dc.0, b.1, c.1, db.1, dc.1]
    };
    let closed = || {
        // Forward-mode dual numbers (value, rate) written out.
        type D = (L, L);
        let mul = |a: D, b: D| -> D { (a.0 * b.0, a.0 * b.1 + a.1 * b.0) };
        let div = |a: D, b: D| -> D {
            let inv = sp(1.0) / b.0;
            (a.0 * inv, (a.1 * b.0 - a.0 * b.1) * inv * inv)
        };
        let sub = |a: D, b: D| -> D { (a.0 - b.0, a.1 - b.1) };
        let scale = |a: D, s: f64| -> D { (a.0 * sp(s), a.1 * sp(s)) };
        let ud: D = (u, u_dot);
        let tr = u.sqrt();
        let t: D = (tr, u_dot * (sp(0.5) / tr));
        let (sn, cs) = t.0.sin_cos();
        let s: D = (sn, t.1 * cs);
        let one_minus_cos: D = (sp(1.0) - cs, t.1 * sn);
        let b = div(one_minus_cos, ud);
        let c = div(sub(t, s), mul(ud, t));
        let uu2 = scale(mul(ud, ud), 2.0);
        let db = div(sub(mul(t, s), scale(one_minus_cos, 2.0)), uu2);
        let dc = div(sub(mul(t, one_minus_cos), scale(sub(t, s), 3.0)), mul(uu2, t));
        [s.0 / t.0, b.0, c.0, db.0, dc.0, b.1, c.1, db.1, dc.1]
    };
    if below.all() {
        series()
    } else if below.none() {
        closed()
    } else {
        let (s, c) = (series(), closed());
        std::array::from_fn(|k| below.blend(s[k], c[k]))
    }
}

/// What `helix::segment_kinematics` gives, lane-wise, for the reduced model (only the first two columns of
/// the derivatives).
pub(super) struct SegmentL {
    pub(super) rotation: M3,
    pub(super) offset: V3,
    pub(super) angular: [V3; 2],
    pub(super) linear: [V3; 2],
    pub(super) angular_bias: V3,
    pub(super) linear_bias: V3,
}

/// [`segment_kinematics`] for the reduced model (`omega.z = rate.z = 0`: twist `o0`, bend `o1` and their rates
/// `n0`, `n1`), with the terms that vanish left out.
#[inline(always)]
pub(super) fn segment_kinematics_reduced(o0: L, o1: L, n0: L, n1: L, sigma: L) -> SegmentL {
    let two = sp(2.0);
    let (p0, p1) = (o0 * sigma, o1 * sigma);
    let (d0, d1) = (n0 * sigma, n1 * sigma);
    let u = p0 * p0 + p1 * p1;
    let pn = p0 * n0 + p1 * n1;
    let u_dot = two * sigma * pn;
    let [a, b, c, db, dc, b_dot, c_dot, db_dot, dc_dot] = coefficients_with_rates(u, u_dot);
    let diag = sp(1.0) - b * u;
    let (p00, p01, p11) = (p0 * p0, p0 * p1, p1 * p1);
    let rotation = M3 { r: [[p00 * b + diag, p01 * b, p1 * a], [p01 * b, p11 * b + diag, -p0 * a], [-p1 * a, p0 * a, diag]] };
    let diag_c = sp(1.0) - c * u;
    let angular = [V3::new(p00 * c + diag_c, p01 * c, -p1 * b) * sigma, V3::new(p01 * c, p11 * c + diag_c, p0 * b) * sigma];
    let ppe_x = p00 - u;
    let offset = V3::new(sp(1.0) + ppe_x * c, p01 * c, -p1 * b) * sigma;
    let (gx, gy, gz) = (ppe_x * (two * dc), p01 * (two * dc), -p1 * (two * db));
    let s2 = sigma * sigma;
    let linear = [V3::new(gx * p0, gy * p0 + p1 * c, gz * p0) * s2, V3::new(gx * p1 - two * p1 * c, gy * p1 + p0 * c, gz * p1 - b) * s2];
    let w = p0 * n1 - p1 * n0;
    let cs = c * sigma;
    let angular_bias = V3::new(p1 * w * c_dot + n1 * w * cs, -(p0 * w) * c_dot - n0 * w * cs, w * b_dot) * sigma;
    let p_dot = sigma * (n0 * n0 + n1 * n1);
    let k1 = two * (db_dot * pn + db * p_dot);
    let k2 = two * (dc_dot * pn + dc * p_dot);
    let k3 = two * dc * pn;
    let k4 = two * db * pn;
    let k5 = two * cs;
    let linear_bias = V3::new(
        ppe_x * k2 - two * p1 * d1 * k3 - two * p1 * n1 * c_dot - n1 * n1 * k5,
        p01 * k2 + (d0 * p1 + p0 * d1) * k3 + (n0 * p1 + p0 * n1) * c_dot + n0 * n1 * k5,
        -(p1 * k1) - d1 * k4 - n1 * b_dot,
    ) * s2;
    SegmentL { rotation, offset, angular, linear, angular_bias, linear_bias }
}

/// `helix::segment_kinematics` lane-wise (same formulas, see there); the reference for
/// [`segment_kinematics_reduced`].
#[cfg(test)]
pub(super) fn segment_kinematics(omega: V3, rate: V3, sigma: L) -> SegmentL {
    let zero = sp(0.0);
    let two = sp(2.0);
    let phi = omega * sigma;
    let phi_dot = rate * sigma;
    let nu = rate;
    let u = phi.norm_squared();
    let pn = phi.dot(nu);
    let u_dot = two * sigma * pn;
    let [a, b, c, db, dc, b_dot, c_dot, db_dot, dc_dot] = coefficients_with_rates(u, u_dot);
    let (p0, p1, p2) = (phi.x, phi.y, phi.z);
    let pe = V3::new(zero, p2, -p1);
    let ppe = V3::new(p0 * p0 - u, p0 * p1, p0 * p2);
    // E = 1 + a K + b (phi phi^T - u 1).
    let diag = sp(1.0) - b * u;
    let rotation = M3 {
        r: [
            [p0 * p0 * b + diag, -p2 * a + p0 * p1 * b, p1 * a + p0 * p2 * b],
            [p2 * a + p1 * p0 * b, p1 * p1 * b + diag, -p0 * a + p1 * p2 * b],
            [-p1 * a + p2 * p0 * b, p0 * a + p2 * p1 * b, p2 * p2 * b + diag],
        ],
    };
    // angular = sigma (1 + b K + c (phi phi^T - u 1)), first two columns.
    let diag = sp(1.0) - c * u;
    let angular = [
        V3::new(p0 * p0 * c + diag, p2 * b + p1 * p0 * c, -p1 * b + p2 * p0 * c) * sigma,
        V3::new(-p2 * b + p0 * p1 * c, p1 * p1 * c + diag, p0 * b + p2 * p1 * c) * sigma,
    ];
    let offset = (V3::new(sp(1.0), zero, zero) + pe * b + ppe * c) * sigma;
    // linear = sigma^2 [g phi^T - c [[0, 2 p1, 2 p2], [-p1, -p0, 0], [-p2, 0, -p0]] - b [e0]x], two columns.
    let g = pe * (two * db) + ppe * (two * dc);
    let s2 = sigma * sigma;
    let linear = [
        V3::new(g.x * p0, g.y * p0 + p1 * c, g.z * p0 + p2 * c) * s2,
        V3::new(g.x * p1 - two * p1 * c, g.y * p1 + p0 * c, g.z * p1 - b) * s2,
    ];
    let pnu = phi.cross(nu);
    let angular_bias = (pnu * b_dot + phi.cross(pnu) * c_dot + nu.cross(pnu) * (c * sigma)) * sigma;
    let p_dot = sigma * nu.norm_squared();
    let nue = V3::new(zero, nu.z, -nu.y);
    let pde = V3::new(zero, phi_dot.z, -phi_dot.y);
    let linear_bias = (pe * (two * (db_dot * pn + db * p_dot))
        + pde * (two * db * pn)
        + nue * b_dot
        + ppe * (two * (dc_dot * pn + dc * p_dot))
        + (phi_dot.cross(pe) + phi.cross(pde)) * (two * dc * pn)
        + (nu.cross(pe) + phi.cross(nue)) * c_dot
        + nu.cross(nue) * (two * c * sigma))
        * s2;
    SegmentL { rotation, offset, angular, linear, angular_bias, linear_bias }
}

/// `dynamics::point_kinematics::<2>` lane-wise.
#[inline(always)]
pub(super) fn point_kinematics_l(start: &MotionL, omega: V3, rate: V3, sigma: L) -> PointL {
    let sk = segment_kinematics_reduced(omega.x, omega.y, rate.x, rate.y, sigma);
    let r = start.rot.mul_v(sk.offset);
    let w_cols = [start.rot.mul_v(sk.angular[0]), start.rot.mul_v(sk.angular[1])];
    let u_cols = [start.rot.mul_v(sk.linear[0]), start.rot.mul_v(sk.linear[1])];
    let w_loc = w_cols[0] * rate.x + w_cols[1] * rate.y;
    let v_loc = u_cols[0] * rate.x + u_cols[1] * rate.y;
    let motion = MotionL {
        rot: start.rot.mul_m(&sk.rotation),
        x: start.x + r,
        v: start.v + start.w.cross(r) + v_loc,
        a: start.a + start.alpha.cross(r) + start.w.cross(start.w.cross(r) + v_loc * sp(2.0)) + start.rot.mul_v(sk.linear_bias),
        w: start.w + w_loc,
        alpha: start.alpha + start.w.cross(w_loc) + start.rot.mul_v(sk.angular_bias),
    };
    PointL { motion, w_cols, u_cols }
}

pub(super) type L6 = [L; 6];

#[inline(always)]
pub(super) fn dot6(a: &L6, b: &L6) -> L {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

/// Index of the symmetric 3x3 entry `(a, b)` in a 6-array `(00, 10, 20, 11, 21, 22)`.
#[inline(always)]
pub(super) fn sym(a: usize, b: usize) -> usize {
    let (a, b) = if a >= b { (a, b) } else { (b, a) };
    match (a, b) {
        (0, 0) => 0,
        (1, 0) => 1,
        (2, 0) => 2,
        (1, 1) => 3,
        (2, 1) => 4,
        _ => 5,
    }
}
