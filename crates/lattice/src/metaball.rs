//! Metaballs: the implicit bodies (head, neck, shoulders, tools) that lattice nodes collide with.
//!
//! Field (dimensionless): F(x) = sum_i (1 - |x - c_i|^2 / R_i^2)^2 for |x - c_i| < R_i, 0 outside.
//! Each term is 1 at its centre and falls to 0 with zero slope at its radius, so F is C1.
//! The body is {F > T} for a threshold T; an isolated ball's surface is the sphere of radius
//! R sqrt(1 - sqrt(T)) (0.707 R for T = 1/4).
//!
//! ## Collision response (the rule, see [`MetaballSet::response`])
//! With g = grad F (1/m), the outward normal is n = -g/|g| and the signed distance to the surface
//! is estimated to first order as d = (T - F)/|g| (m; < 0 inside, > 0 outside).
//! - inside (d < 0): penalty push out, f = k (-d) n (k = [`MetaballParams::stiffness`], N/m);
//! - thin band outside (0 <= d < w, w = [`MetaballParams::band`]): weak attraction back to the
//!   surface, f = -k_a d (1 - d/w) n (k_a = [`MetaballParams::attraction_stiffness`], N/m), zero at
//!   both edges of the band so the force is continuous in d; the particle is held at the
//!   surface instead of bouncing in and out of the penalty layer (the paper's "stabilising" force);
//! - inside and in the band: normal damping -c (v . n) n (c = [`MetaballParams::damping`], N s/m),
//!   which removes the normal velocity that drives jitter, and leaves tangential sliding free;
//! - beyond the band (d >= w): no force.

use nalgebra::{Point3, Vector3};

/// One metaball (model: immutable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metaball {
    /// Centre c, m.
    pub centre: Point3<f64>,
    /// Radius of influence R, m; > 0. The field term is zero beyond it.
    pub radius: f64,
}

impl Metaball {
    /// A metaball at `centre` (m) with radius of influence `radius` (m).
    pub fn new(centre: Point3<f64>, radius: f64) -> Self {
        Self { centre, radius }
    }

    /// This ball's term (dimensionless) and its gradient (1/m) at `x` (m).
    #[inline]
    pub fn term(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let r = x - self.centre;
        let d2 = r.norm_squared();
        let rr = self.radius * self.radius;
        // outside the ball's reach: no division (most balls, for most points)
        if !(d2 < rr) {
            return (0.0, Vector3::zeros());
        }
        let r2inv = 1.0 / rr;
        let q = 1.0 - d2 * r2inv;
        if q <= 0.0 {
            return (0.0, Vector3::zeros());
        }
        (q * q, (-4.0 * q * r2inv) * r)
    }
}

/// Parameters of the metaball collision response. See the module docs for the rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetaballParams {
    /// Iso-value T of the body's surface (dimensionless, in (0, 1)); inside where F > T.
    /// Default 0.25 (an isolated ball's surface at 0.707 R).
    pub threshold: f64,
    /// Penalty stiffness k of the push out, N/m (force per metre of estimated penetration).
    /// Default 50 N/m.
    pub stiffness: f64,
    /// Stiffness k_a of the weak attraction in the band outside the surface, N/m.
    /// Default 5 N/m (a tenth of the penalty).
    pub attraction_stiffness: f64,
    /// Width w of the attraction band outside the surface, m. Default 0.005 m.
    pub band: f64,
    /// Normal damping c inside the body and in the band, N s/m. Default 0.05 N s/m.
    pub damping: f64,
}

impl Default for MetaballParams {
    fn default() -> Self {
        Self {
            threshold: 0.25,
            stiffness: 50.0,
            attraction_stiffness: 5.0,
            band: 0.005,
            damping: 0.05,
        }
    }
}

/// The result of a collision query of one particle against a metaball set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetaballContact {
    /// Field value F at the particle (dimensionless).
    pub field: f64,
    /// Estimated signed distance d to the surface, m (< 0 inside). Infinite where F = 0.
    pub distance: f64,
    /// Outward surface normal n (unit) used for the response; zero where F = 0.
    pub normal: Vector3<f64>,
    /// Force on the particle, N (penalty + band attraction + normal damping).
    pub force: Vector3<f64>,
}

/// A set of metaballs forming one body or several (model: immutable).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MetaballSet {
    /// The balls.
    pub balls: Vec<Metaball>,
}

impl MetaballSet {
    /// A set from its balls.
    pub fn new(balls: Vec<Metaball>) -> Self {
        Self { balls }
    }

    /// A rough head, neck and shoulders in a head frame (m): z up, y forward (face), origin at the
    /// head's centre; `head_radius` (m) is the radius of the head's surface at the default
    /// threshold T = 1/4. Illustrative, not a measured body.
    pub fn head_neck_shoulders(head_radius: f64) -> Self {
        let s = head_radius / (1.0 - 0.25f64.sqrt()).sqrt(); // ball radius whose T=1/4 surface is head_radius
        let a = head_radius;
        let p = |x: f64, y: f64, z: f64| Point3::new(x * a, y * a, z * a);
        Self::new(vec![
            Metaball::new(p(0.0, 0.0, 0.0), s),          // cranium
            Metaball::new(p(0.0, 0.25, -0.45), 0.8 * s), // face and jaw
            Metaball::new(p(0.0, -0.1, -1.2), 0.6 * s),  // neck
            Metaball::new(p(0.0, -0.1, -1.7), 0.6 * s),  // neck base
            Metaball::new(p(-1.1, -0.1, -2.1), 0.9 * s), // left shoulder
            Metaball::new(p(1.1, -0.1, -2.1), 0.9 * s),  // right shoulder
            Metaball::new(p(0.0, -0.1, -2.3), 1.0 * s),  // upper chest
        ])
    }

    /// Field value F at `x` (m), dimensionless, >= 0.
    pub fn field(&self, x: &Point3<f64>) -> f64 {
        self.balls.iter().map(|b| b.term(x).0).sum()
    }

    /// Analytic gradient of F at `x` (m), 1/m.
    pub fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        self.field_and_gradient(x).1
    }

    /// The balls whose reach can touch the axis-aligned box `[lo, hi]` (m), into `out` (replacing its balls, keeping
    /// its storage): every other ball's term is exactly zero at every point of the box, so `out`'s field, gradient
    /// and [`MetaballSet::clear_of`] equal this set's there, bit for bit (the terms that are left are summed in
    /// the same order). Not for [`MetaballSet::push_out`], whose search leaves the box.
    pub fn reaching_into(&self, lo: &Point3<f64>, hi: &Point3<f64>, out: &mut MetaballSet) {
        out.balls.clear();
        out.balls.extend(self.balls.iter().filter(|b| {
            let c = &b.centre;
            let gap = Vector3::new((lo.x - c.x).max(c.x - hi.x).max(0.0), (lo.y - c.y).max(c.y - hi.y).max(0.0), (lo.z - c.z).max(c.z - hi.z).max(0.0));
            // A margin of 1e-9 of the reach for the rounding of the points' own distances.
            gap.norm_squared() < b.radius * b.radius * (1.0 + 1e-9) || !gap.norm_squared().is_finite()
        }));
    }

    /// F (dimensionless) and its gradient (1/m) at `x` (m).
    pub fn field_and_gradient(&self, x: &Point3<f64>) -> (f64, Vector3<f64>) {
        let mut f = 0.0;
        let mut g = Vector3::zeros();
        for b in &self.balls {
            let (fb, gb) = b.term(x);
            f += fb;
            g += gb;
        }
        (f, g)
    }

    /// Index of the ball whose term is largest at `x` (m; the first of equal ones, 0 if none contributes).
    fn strongest_ball(&self, x: &Point3<f64>) -> usize {
        let (mut best, mut best_f) = (0usize, -1.0);
        for (i, b) in self.balls.iter().enumerate() {
            let fb = b.term(x).0;
            if fb > best_f {
                best = i;
                best_f = fb;
            }
        }
        best
    }

    /// True if `x` (m) is inside the body, F(x) > `threshold` (dimensionless).
    pub fn inside(&self, x: &Point3<f64>, threshold: f64) -> bool {
        self.field(x) > threshold
    }

    /// Collision response of a particle at `x` (m) moving at `v` (m/s): the rule of the module
    /// docs with `params`. Where |grad F| vanishes (e.g. exactly at an isolated ball's centre) the
    /// normal is taken from the centre of the largest contributing term to `x` (+z if they
    /// coincide) and the penetration is capped at that ball's radius.
    pub fn response(
        &self,
        params: &MetaballParams,
        x: &Point3<f64>,
        v: &Vector3<f64>,
    ) -> MetaballContact {
        let (f, g) = self.field_and_gradient(x);
        let none = MetaballContact {
            field: f,
            distance: f64::INFINITY,
            normal: Vector3::zeros(),
            force: Vector3::zeros(),
        };
        if f <= 0.0 {
            return none;
        }
        let gn = g.norm();
        // largest contributing ball, for the degenerate-gradient fallback and the depth cap
        let ball = self.balls[self.strongest_ball(x)];
        let cap = ball.radius;
        let (normal, mut d) = if gn > 1e-9 / cap {
            (-g / gn, (params.threshold - f) / gn)
        } else {
            let r = x - ball.centre;
            let n = if r.norm() > 0.0 {
                r.normalize()
            } else {
                Vector3::z()
            };
            (
                n,
                if f > params.threshold {
                    -cap
                } else {
                    f64::INFINITY
                },
            )
        };
        if d < -cap {
            d = -cap;
        }
        if d >= params.band {
            return MetaballContact {
                distance: d,
                normal,
                ..none
            };
        }
        let vn = v.dot(&normal);
        let mut force = -params.damping * vn * normal;
        if d < 0.0 {
            force += params.stiffness * (-d) * normal;
        } else {
            force -= params.attraction_stiffness * d * (1.0 - d / params.band) * normal;
        }
        MetaballContact {
            field: f,
            distance: d,
            normal,
            force,
        }
    }
}

/// Default skin of [`MetaballSet::push_out`]: how far outside the surface a pushed point is put, m.
pub const PUSH_OUT_SKIN: f64 = 5e-4;

/// The skin [`MetaballSet::push_out`] uses for a given `skin` (m): non-negative, 0 if not finite.
fn push_out_skin(skin: f64) -> f64 {
    if skin.is_finite() { skin.max(0.0) } else { 0.0 }
}

/// How near the offset surface [`MetaballSet::push_out`] puts a point, m, for a sanitized `skin` (m).
fn push_out_tolerance(skin: f64) -> f64 {
    1e-3 * skin.max(1e-6)
}

impl MetaballSet {
    /// The first-order signed distance from `x` (m) to the body's surface {F = `threshold`},
    /// d = (T - F)/|grad F| (m; < 0 inside, +infinity where F = 0, outside every ball), and the outward
    /// normal there, n = -grad F/|grad F| (unitless; zero where F = 0). Where the gradient vanishes (e.g. a
    /// ball's centre) the normal is the ray from the largest contributing ball's centre (+z at the centre
    /// itself) and the distance minus that ball's radius inside, +infinity outside. The distance
    /// [`MetaballSet::push_out`] iterates on.
    pub fn distance(&self, x: &Point3<f64>, threshold: f64) -> (f64, Vector3<f64>) {
        let (f, g) = self.field_and_gradient(x);
        if f <= 0.0 {
            return (f64::INFINITY, Vector3::zeros());
        }
        let gn = g.norm();
        if gn > 1e-12 {
            return ((threshold - f) / gn, -g / gn);
        }
        let best = self.strongest_ball(x);
        let n = (x - self.balls[best].centre).try_normalize(1e-300).unwrap_or_else(Vector3::z);
        let d = if f > threshold { -self.balls[best].radius } else { f64::INFINITY };
        (d, n)
    }

    /// True if [`MetaballSet::push_out`] certainly leaves `x` (m) where it is: `x` is farther than `skin`
    /// (m) outside the body {F > `threshold`} by the first-order distance, with a margin of 1e-9 of it. The
    /// push-out's first test ([`MetaballSet::distance`] against the skin) rearranged, without division or
    /// square root: a caller with many points mostly
    /// clear of the body tests them with this first, and pushes out the others (the local strands' body
    /// contacts, cheaper a step than pushing out every point). False does not mean the push-out moves `x`.
    pub fn clear_of(&self, x: &Point3<f64>, threshold: f64, skin: f64) -> bool {
        let skin = push_out_skin(skin);
        let (f, g) = self.field_and_gradient(x);
        // push_out returns x when (T - F) / |g| >= skin - tol (or F <= 0).
        let margin = (skin - push_out_tolerance(skin)).max(0.0) * (1.0 + 1e-9);
        let gap = threshold - f;
        f <= 0.0 || (gap > 0.0 && gap * gap > margin * margin * g.norm_squared())
    }

    /// `x` (m) moved out of the body {F > `threshold`} onto the offset surface at distance `skin`
    /// (m, >= 0) outside it, if it is closer than that (inside, or outside within `skin`); else
    /// `x` unchanged. The move is along the outward normal n = -grad F/|grad F| at `x` (where the
    /// gradient vanishes, e.g. a ball's centre: the ray from the largest contributing ball's
    /// centre, +z at the centre itself): the root t of d(x + t n) = skin, d = (T - F)/|grad F|
    /// the first-order signed distance (+infinity where F = 0), by secant steps on d along the ray
    /// (slope 1 where the secant is unusable: d' = 1 near the surface, where one step is exact to
    /// O(depth^2)) kept inside a bracket and bisected when they leave it; at most 60 field evaluations, to
    /// |d - skin| <= 1e-3 skin. Returns the point, m.
    ///
    /// The result is continuous in `x` (points within the skin are moved onto it, not only
    /// points inside), so hair rendered on the offset surface does not flicker.
    pub fn push_out(&self, x: &Point3<f64>, threshold: f64, skin: f64) -> Point3<f64> {
        let skin = push_out_skin(skin);
        let tol = push_out_tolerance(skin);
        let dist = |p: &Point3<f64>| self.distance(p, threshold);
        let (d0, n) = dist(x);
        if d0 >= skin - tol {
            return *x;
        }
        let cap = self.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        let (mut lo, mut hi): (f64, Option<f64>) = (0.0, None);
        let mut t = (skin - d0).clamp(tol, cap);
        let mut prev = (0.0, d0 - skin);
        for _ in 0..60 {
            let d = dist(&(x + t * n)).0;
            let ph = d - skin;
            if ph.abs() <= tol {
                return x + t * n;
            }
            if ph < 0.0 {
                lo = t;
            } else {
                hi = Some(t);
            }
            // secant slope of d along the ray where it is usable, else 1 (exact near the surface)
            let slope = (ph - prev.1) / (t - prev.0);
            let slope = if slope.is_finite() && slope > 0.1 { slope } else { 1.0 };
            prev = (t, ph);
            let newton = t - ph / slope;
            t = match hi {
                None => lo + (-ph).clamp(tol, cap),
                Some(h) if newton.is_finite() && newton > lo && newton < h => newton,
                Some(h) => 0.5 * (lo + h),
            };
        }
        x + hi.unwrap_or(t) * n
    }

    /// [`push_out`](Self::push_out) applied to every point of `points` in place (both cores,
    /// rayon), with `threshold` (dimensionless) and `skin` (m). Returns how many points moved.
    pub fn push_out_many(&self, points: &mut [Point3<f64>], threshold: f64, skin: f64) -> usize {
        self.push_out_each(points, |x| *x, |x, y| *x = y, threshold, skin)
    }

    /// [`push_out_many`](Self::push_out_many) for f32 points (m; e.g.
    /// [`crate::ffd::CompactBinding`]'s output), computed in f64. Returns how many points moved.
    pub fn push_out_many_f32(&self, points: &mut [[f32; 3]], threshold: f64, skin: f64) -> usize {
        let get = |x: &[f32; 3]| Point3::new(x[0] as f64, x[1] as f64, x[2] as f64);
        self.push_out_each(points, get, |x, y| *x = [y.x as f32, y.y as f32, y.z as f32], threshold, skin)
    }

    /// Pushes out every point (read with `get`, written with `set` when it moves) on all cores,
    /// skipping points outside the bounding box of every ball's reach. Returns how many moved.
    fn push_out_each<T: Send>(
        &self,
        points: &mut [T],
        get: impl Fn(&T) -> Point3<f64> + Sync,
        set: impl Fn(&mut T, Point3<f64>) + Sync,
        threshold: f64,
        skin: f64,
    ) -> usize {
        use rayon::prelude::*;
        if self.balls.is_empty() {
            return 0;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for b in &self.balls {
            for a in 0..3 {
                lo[a] = lo[a].min(b.centre[a] - b.radius);
                hi[a] = hi[a].max(b.centre[a] + b.radius);
            }
        }
        points
            .par_chunks_mut(4096)
            .map(|chunk| {
                let mut moved = 0;
                for x in chunk {
                    let p = get(x);
                    if (0..3).any(|a| p[a] < lo[a] || p[a] > hi[a]) {
                        continue;
                    }
                    let y = self.push_out(&p, threshold, skin);
                    if y != p {
                        set(x, y);
                        moved += 1;
                    }
                }
                moved
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set() -> MetaballSet {
        MetaballSet::new(vec![
            Metaball::new(Point3::new(0.0, 0.0, 0.0), 0.1),
            Metaball::new(Point3::new(0.06, 0.02, -0.01), 0.07),
            Metaball::new(Point3::new(-0.03, 0.09, 0.04), 0.05),
        ])
    }

    #[test]
    fn the_balls_reaching_a_box_give_the_same_field_in_it_bit_for_bit() {
        // The head, neck and shoulders, and boxes of every size (a hair's point to the whole body) placed over a
        // grid around it: at every point of a box (its corners, centre and a lattice inside), the field and
        // gradient of the reaching balls equal the whole set's exactly, and so does `clear_of`; boxes far from
        // the body keep no ball, and a box over the cranium keeps at least it.
        let body = MetaballSet::head_neck_shoulders(0.09);
        let mut near = MetaballSet::default();
        let (mut boxes, mut dropped) = (0, 0);
        for size in [1e-4, 0.01, 0.05, 0.2] {
            for i in -6..=6 {
                for j in -6..=6 {
                    for k in -8..=4 {
                        let lo = Point3::new(0.05 * i as f64, 0.05 * j as f64, 0.05 * k as f64);
                        let hi = lo + Vector3::new(size, 0.7 * size, 1.3 * size);
                        body.reaching_into(&lo, &hi, &mut near);
                        boxes += 1;
                        dropped += body.balls.len() - near.balls.len();
                        for a in 0..=4 {
                            for b in 0..=4 {
                                for c in 0..=4 {
                                    let t = Vector3::new(a as f64, b as f64, c as f64) / 4.0;
                                    let x = lo + (hi - lo).component_mul(&t);
                                    assert_eq!(near.field_and_gradient(&x), body.field_and_gradient(&x), "box {lo} .. {hi}, point {x}");
                                    assert_eq!(near.clear_of(&x, 0.25, 1e-3), body.clear_of(&x, 0.25, 1e-3));
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(dropped > boxes, "the boxes kept {dropped} fewer balls than the whole set over {boxes} boxes");
        let far = Point3::new(1.0, 1.0, 1.0);
        body.reaching_into(&far, &(far + Vector3::repeat(0.01)), &mut near);
        assert!(near.balls.is_empty());
        body.reaching_into(&Point3::new(0.0, 0.0, 0.09), &Point3::new(0.01, 0.01, 0.1), &mut near);
        assert!(near.balls.contains(&body.balls[0]), "the cranium reaches the top of the head");
    }

    fn points() -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        for i in 0..9 {
            for j in 0..9 {
                for k in 0..9 {
                    let p = Point3::new(
                        -0.12 + 0.03 * i as f64 + 0.0013,
                        -0.1 + 0.028 * j as f64 + 0.0007,
                        -0.11 + 0.027 * k as f64 + 0.0003,
                    );
                    out.push(p);
                }
            }
        }
        out
    }

    /// Central differences with step 1e-7 m (truncation ~ step^2 |F'''| ~ 1e-14/R^3 relative to
    /// |grad F| ~ 1/R, i.e. ~1e-10; round-off ~ 1e-16/1e-7 ~ 1e-9): relative agreement 1e-6
    /// wherever |grad F| is not tiny, absolute 1e-6 /m otherwise.
    #[test]
    fn gradient_matches_finite_differences() {
        let s = set();
        let h = 1e-7;
        let mut checked = 0;
        for p in points() {
            let g = s.gradient(&p);
            let mut fd = Vector3::zeros();
            for a in 0..3 {
                let mut e = Vector3::zeros();
                e[a] = h;
                fd[a] = (s.field(&(p + e)) - s.field(&(p - e))) / (2.0 * h);
            }
            let err = (fd - g).norm();
            assert!(err <= 1e-6 * g.norm().max(1.0), "{p}: {g} vs {fd}");
            if g.norm() > 1.0 {
                checked += 1;
            }
        }
        assert!(checked > 50, "too few points inside the balls: {checked}");
    }

    #[test]
    fn field_is_zero_outside_every_ball() {
        let s = set();
        for p in points() {
            let outside_all = s.balls.iter().all(|b| (p - b.centre).norm() >= b.radius);
            if outside_all {
                assert_eq!(s.field(&p), 0.0);
                assert_eq!(s.gradient(&p), Vector3::zeros());
                let c = s.response(&MetaballParams::default(), &p, &Vector3::new(1.0, 0.0, 0.0));
                assert_eq!(c.force, Vector3::zeros());
            } else {
                assert!(s.field(&p) > 0.0);
            }
        }
        // single ball: exact value and surface radius
        let b = MetaballSet::new(vec![Metaball::new(Point3::origin(), 0.1)]);
        assert_eq!(b.field(&Point3::origin()), 1.0);
        let r_surf = 0.1 * (1.0 - 0.25f64.sqrt()).sqrt();
        assert!(b.inside(&Point3::new(r_surf - 1e-9, 0.0, 0.0), 0.25));
        assert!(!b.inside(&Point3::new(r_surf + 1e-9, 0.0, 0.0), 0.25));
    }

    #[test]
    fn particle_inside_is_pushed_outwards() {
        let params = MetaballParams::default();
        let b = MetaballSet::new(vec![Metaball::new(Point3::new(0.1, 0.2, 0.3), 0.1)]);
        let r_surf = 0.1 * (1.0 - 0.25f64.sqrt()).sqrt();
        for dir in [
            Vector3::x(),
            Vector3::new(1.0, -2.0, 0.5).normalize(),
            -Vector3::z(),
        ] {
            let mut last = f64::INFINITY;
            for r in [0.9 * r_surf, 0.6 * r_surf, 0.3 * r_surf] {
                let x = b.balls[0].centre + r * dir;
                let c = b.response(&params, &x, &Vector3::zeros());
                assert!(c.distance < 0.0);
                assert!((c.normal - dir).norm() < 1e-12);
                let push = c.force.dot(&dir);
                assert!(push > 0.0 && (c.force - push * dir).norm() < 1e-12);
                // deeper -> harder push
                assert!(push > 0.0 && (last == f64::INFINITY || push > last));
                last = push;
            }
            // first-order distance is exact to O(depth^2) near the surface
            let x = b.balls[0].centre + (r_surf - 1e-4) * dir;
            let c = b.response(&params, &x, &Vector3::zeros());
            assert!((c.distance + 1e-4).abs() < 1e-6, "{}", c.distance);
            assert!((c.force.norm() - params.stiffness * (-c.distance)).abs() < 1e-12);
        }
        // degenerate gradient at the very centre: still pushed out (along +z), finite
        let c = b.response(&params, &b.balls[0].centre, &Vector3::zeros());
        assert!(c.force.z > 0.0 && c.force.norm().is_finite());
        // several balls: pushed away from the body
        let s = set();
        let x = Point3::new(0.0, 0.0, 0.06);
        let c = s.response(&params, &x, &Vector3::zeros());
        assert!(s.inside(&x, params.threshold));
        let fd_step = 1e-4 * c.force.normalize();
        assert!(s.field(&(x + fd_step)) < s.field(&x));
    }

    #[test]
    fn band_attracts_weakly_and_damps_normal_velocity() {
        let params = MetaballParams::default();
        let b = MetaballSet::new(vec![Metaball::new(Point3::origin(), 0.1)]);
        let r_surf = 0.1 * (1.0 - 0.25f64.sqrt()).sqrt();
        let n = Vector3::new(0.0, 1.0, 0.0);
        // in the band: pulled towards the surface, weaker than the penalty at the same depth
        let x = Point3::from((r_surf + 0.5 * params.band) * n);
        let c = b.response(&params, &x, &Vector3::zeros());
        assert!(c.distance > 0.0 && c.distance < params.band);
        let pull = -c.force.dot(&n);
        assert!(pull > 0.0);
        let x_in = Point3::from((r_surf - 0.5 * params.band) * n);
        let push = b.response(&params, &x_in, &Vector3::zeros()).force.dot(&n);
        assert!(pull < push);
        // beyond the band: nothing
        let x_far = Point3::from((r_surf + 2.0 * params.band) * n);
        assert_eq!(
            b.response(&params, &x_far, &Vector3::new(0.0, -1.0, 0.0))
                .force,
            Vector3::zeros()
        );
        // normal damping opposes normal velocity, tangential velocity is free
        let c_vn = b.response(&params, &x, &(-0.2 * n));
        assert!((c_vn.force - c.force - params.damping * 0.2 * n).norm() < 1e-12);
        let c_vt = b.response(&params, &x, &Vector3::new(0.3, 0.0, 0.0));
        assert!((c_vt.force - c.force).norm() < 1e-12);
        // force continuous across the surface (d = 0) and the band's outer edge
        let f_at = |r: f64| {
            b.response(&params, &Point3::from(r * n), &Vector3::zeros())
                .force
        };
        assert!((f_at(r_surf - 1e-9) - f_at(r_surf + 1e-9)).norm() < 1e-6);
    }

    #[test]
    fn head_neck_shoulders_has_head_at_radius() {
        let body = MetaballSet::head_neck_shoulders(0.09);
        let t = MetaballParams::default().threshold;
        assert!(body.inside(&Point3::origin(), t));
        assert!(body.inside(&Point3::new(0.0, 0.0, 0.08), t));
        assert!(!body.inside(&Point3::new(0.0, 0.0, 0.1), t));
        assert!(body.inside(&Point3::new(0.1, -0.009, -0.19), t)); // shoulder
        assert!(!body.inside(&Point3::new(0.3, 0.0, 0.0), t));
    }

    /// `clear_of` is never true where `push_out` moves a point (skins of a hair's radius to a
    /// centimetre, points from inside the head to 5 cm outside it, and at the surface's skin to
    /// 1e-6 of it), and it is true for at least 99 % of the points beyond twice the skin by the
    /// first-order distance (it would be useless otherwise).
    #[test]
    fn clear_of_never_hides_a_point_the_push_out_moves() {
        let t = 0.25;
        let body = MetaballSet::head_neck_shoulders(0.1);
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut clear, mut beyond, mut moved) = (0, 0, 0);
        for skin in [4e-5, PUSH_OUT_SKIN, 1e-2] {
            for k in 0..20_000 {
                let dir = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.6).normalize();
                // From 2 cm inside the head's surface to 5 cm outside it; every fourth point on the skin
                // itself, within 1e-6 of it (where the two tests meet).
                let r = if k % 4 == 0 {
                    let on = body.push_out(&Point3::from(dir * 0.05), t, skin);
                    on.coords.norm() * (1.0 + (rnd() - 0.5) * 2e-6)
                } else {
                    0.08 + 0.07 * rnd()
                };
                let x = Point3::from(dir * r);
                let pushed = body.push_out(&x, t, skin) != x;
                let c = body.clear_of(&x, t, skin);
                assert!(!(c && pushed), "skin {skin}: {x:?} clear but pushed out");
                moved += pushed as usize;
                if !pushed && body.distance(&x, t).0 > 2.0 * skin {
                    beyond += 1;
                    clear += c as usize;
                }
            }
        }
        assert!(moved > 5_000, "points pushed out: {moved}");
        assert!(clear as f64 >= 0.99 * beyond as f64, "{clear} of {beyond} points beyond twice the skin clear");
    }

    /// Points inside a single ball (surface radius r_s = 0.707 R) land on the sphere of radius
    /// r_s + skin along their ray, to 1e-5 m (the iteration stops where the first-order distance
    /// is the skin, which is off the true distance by O(skin^2/R) ~ 4e-6 m: measured 1.8e-6 m);
    /// points beyond the skin do not move; the body of several
    /// balls: every pushed point is outside by at least 0.99 skin (exact signed distance estimate
    /// (T - F)/|grad F|).
    #[test]
    fn push_out_puts_points_on_the_skin() {
        let t: f64 = 0.25;
        let skin = PUSH_OUT_SKIN;
        let c = Point3::new(0.1, -0.2, 0.3);
        let b = MetaballSet::new(vec![Metaball::new(c, 0.1)]);
        let r_s = 0.1 * (1.0 - t.sqrt()).sqrt();
        for dir in [Vector3::x(), Vector3::new(1.0, -2.0, 0.5).normalize(), -Vector3::z()] {
            for r in [0.0001, 0.3 * r_s, 0.9 * r_s, r_s, r_s + 0.5 * skin] {
                let y = b.push_out(&(c + r * dir), t, skin);
                let ry = y - c;
                assert!((ry.norm() - (r_s + skin)).abs() < 1e-5, "r {r}: {}", ry.norm());
                assert!((ry.normalize() - dir).norm() < 1e-9);
            }
            let far = c + (r_s + 2.0 * skin) * dir;
            assert_eq!(b.push_out(&far, t, skin), far);
        }
        // the very centre: pushed along +z onto the skin
        let y = b.push_out(&c, t, skin);
        assert!(((y - c).norm() - (r_s + skin)).abs() < 1e-5 && (y - c).z > 0.0);
        let s = set();
        let mut pts = points();
        let inside_before = pts.iter().filter(|p| s.inside(p, t)).count();
        assert!(inside_before > 20);
        let mut pts32: Vec<[f32; 3]> = pts.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let moved = s.push_out_many(&mut pts, t, skin);
        assert_eq!(s.push_out_many_f32(&mut pts32, t, skin), moved);
        for (a, b) in pts.iter().zip(&pts32) {
            // f32 rounding of input and output (~1e-8 m at 0.1 m)
            assert!((a - Point3::new(b[0] as f64, b[1] as f64, b[2] as f64)).norm() < 1e-6);
        }
        assert!(moved >= inside_before);
        for (p, q) in pts.iter().zip(points()) {
            let (f, g) = s.field_and_gradient(p);
            let d = if f > 0.0 { (t - f) / g.norm() } else { f64::INFINITY };
            assert!(d >= 0.99 * skin, "{q} -> {p}: distance {d}");
            // never farther than the body's extent (a ball's diameter)
            assert!((p - q).norm() < 0.2, "{q} -> {p} moved too far");
        }
    }
}
