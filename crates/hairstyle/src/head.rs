//! The built-in head, neck and shoulders: metaballs for collisions, a matching triangle mesh for
//! display, and the scalp region that hair grows from.
//!
//! ## Frame and units
//! Head frame, SI units (m): origin at the **centre of the head** (the cranium ball's centre), z up,
//! y forward (towards the face), x to the head's right (right-handed: x = y x z).
//! The body is [`MetaballSet::head_neck_shoulders`]: the cranium's surface is a sphere of radius
//! [`HeadParams::head_radius`] (0.09 m by default) where no other ball reaches; face, neck,
//! shoulders and chest are further balls. Inside is where the field F exceeds
//! [`HeadParams::threshold`].
//!
//! ## Scalp
//! A surface point p is scalp if its direction from the head centre lies within a cone of
//! half-angle `theta` about an axis tilted backwards by `alpha` from +z ([`Scalp`]); `alpha` and
//! `theta` follow from the hairline's elevation at the front (forehead) and at the back (nape),
//! [`HeadParams::hairline_front`] and [`HeadParams::hairline_back`]: front elevation
//! = 90 deg + alpha - theta, back elevation = 90 deg - alpha - theta.
//!
//! ## Mesh
//! Surface nets on a regular grid of the field (one vertex per grid cell crossed by the surface,
//! one quad per crossed grid edge), each vertex then projected onto the iso-surface by Newton
//! steps along the gradient, with normals -grad F / |grad F|; so the display mesh lies on the
//! collision surface to [`MESH_PROJECTION_TOLERANCE`].

use lattice::metaball::MetaballSet;
use nalgebra::{Point3, Vector3};
use rand::Rng;
use thiserror::Error;

/// Vertices of the display mesh lie within this distance (m, first-order estimate
/// |F - T| / |grad F|) of the collision iso-surface.
pub const MESH_PROJECTION_TOLERANCE: f64 = 1e-7;

/// Errors of head construction and scalp sampling.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum HeadError {
    /// A parameter is out of range; `field` names it.
    #[error("invalid head parameter `{field}`: {reason}")]
    InvalidParameter {
        /// Parameter name.
        field: &'static str,
        /// What is wrong, with the value.
        reason: String,
    },
}

/// Parameters of the built-in head.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadParams {
    /// Radius of the cranium's surface, m. Default 0.09 m.
    pub head_radius: f64,
    /// Iso-value T of the body surface (dimensionless, in (0, 1)); must match the lattice's
    /// `MetaballParams::threshold`. Default 0.25.
    pub threshold: f64,
    /// Hairline elevation at the front (forehead) above the horizontal plane through the head
    /// centre, radians. Default 35 deg.
    pub hairline_front: f64,
    /// Hairline elevation at the back (nape), radians (negative: below the centre). Default -30 deg.
    pub hairline_back: f64,
    /// Grid cell size of the display mesh, m. Default 0.012 m (about 6,000 triangles).
    pub mesh_cell: f64,
}

impl Default for HeadParams {
    fn default() -> Self {
        Self {
            head_radius: 0.09,
            threshold: 0.25,
            hairline_front: 35f64.to_radians(),
            hairline_back: (-30f64).to_radians(),
            mesh_cell: 0.012,
        }
    }
}

impl HeadParams {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), HeadError> {
        let bad = |field, reason: String| Err(HeadError::InvalidParameter { field, reason });
        if !(self.head_radius > 0.0 && self.head_radius < 10.0) {
            return bad(
                "head_radius",
                format!("must be in (0, 10) m, got {}", self.head_radius),
            );
        }
        if !(self.threshold > 0.0 && self.threshold < 1.0) {
            return bad(
                "threshold",
                format!("must be in (0, 1), got {}", self.threshold),
            );
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        if !(self.hairline_front.abs() < half_pi) {
            return bad(
                "hairline_front",
                format!("must be in (-pi/2, pi/2) rad, got {}", self.hairline_front),
            );
        }
        if !(self.hairline_back.abs() < half_pi && self.hairline_back <= self.hairline_front) {
            return bad(
                "hairline_back",
                format!(
                    "must be in (-pi/2, hairline_front] rad, got {}",
                    self.hairline_back
                ),
            );
        }
        if !(self.mesh_cell > 0.0 && self.mesh_cell <= 0.5 * self.head_radius) {
            return bad(
                "mesh_cell",
                format!("must be in (0, head_radius / 2] m, got {}", self.mesh_cell),
            );
        }
        Ok(())
    }
}

/// The scalp region: directions from the head centre within `half_angle` of `axis`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scalp {
    /// Unit axis of the scalp cap (head frame), tilted backwards from +z.
    pub axis: Vector3<f64>,
    /// Half-angle of the cap, radians.
    pub half_angle: f64,
}

impl Scalp {
    /// The cap whose boundary crosses the sagittal plane at elevations `front` (forehead) and
    /// `back` (nape), radians.
    pub fn from_hairline(front: f64, back: f64) -> Self {
        let half_pi = std::f64::consts::FRAC_PI_2;
        let half_angle = half_pi - 0.5 * (front + back);
        let tilt = front - half_pi + half_angle;
        Self {
            axis: Vector3::new(0.0, -tilt.sin(), tilt.cos()),
            half_angle,
        }
    }

    /// True if the direction of `p` (m, head frame) from the head centre is inside the cap.
    pub fn contains_direction(&self, p: &Point3<f64>) -> bool {
        let n = p.coords.norm();
        n > 0.0 && p.coords.dot(&self.axis) >= self.half_angle.cos() * n
    }
}

/// A point on the scalp: position on the iso-surface and outward unit normal (head frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalpPoint {
    /// Position, m.
    pub position: Point3<f64>,
    /// Outward unit normal of the body surface there.
    pub normal: Vector3<f64>,
}

/// Triangle mesh for display (f32, ready for a GPU buffer).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HeadMesh {
    /// Vertex positions, m (head frame).
    pub positions: Vec<[f32; 3]>,
    /// Unit outward vertex normals (from the field gradient).
    pub normals: Vec<[f32; 3]>,
    /// Triangles, three vertex indices each, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

impl HeadMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// The built-in head, neck and shoulders (model: immutable). See the module docs for the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Head {
    /// Parameters it was built from.
    pub params: HeadParams,
    /// The collision body (metaballs, head frame).
    pub body: MetaballSet,
    /// The scalp region.
    pub scalp: Scalp,
}

impl Default for Head {
    fn default() -> Self {
        Self::new(HeadParams::default()).expect("default head parameters are valid")
    }
}

impl Head {
    /// The built-in body with `params`.
    pub fn new(params: HeadParams) -> Result<Self, HeadError> {
        params.validate()?;
        // The metaball set's radii are set for its own default threshold 1/4; the cranium keeps
        // radius `head_radius` at that threshold. A different threshold scales the balls so that
        // the cranium still has radius `head_radius`.
        let body = MetaballSet::head_neck_shoulders(params.head_radius);
        let scale = ((1.0 - 0.25f64.sqrt()) / (1.0 - params.threshold.sqrt())).sqrt();
        let body = MetaballSet::new(
            body.balls
                .into_iter()
                .map(|mut b| {
                    b.radius *= scale;
                    b
                })
                .collect(),
        );
        Ok(Self {
            params,
            body,
            scalp: Scalp::from_hairline(params.hairline_front, params.hairline_back),
        })
    }

    /// Field value F at `p` (m), dimensionless.
    pub fn field(&self, p: &Point3<f64>) -> f64 {
        self.body.field(p)
    }

    /// True if `p` (m) is inside the body (F > T).
    pub fn inside(&self, p: &Point3<f64>) -> bool {
        self.body.field(p) > self.params.threshold
    }

    /// Whether a strand's centreline clears the surface by `margin` (m): every one of 64 points evenly spaced
    /// in arc length after the root at a [`Head::signed_distance`] of at least `margin`.
    pub fn clears(&self, model: &strand::StrandModel, state: &strand::StrandState, margin: f64) -> bool {
        strand::kinematics::centerline(model, state, 64).iter().skip(1).all(|(_, p)| self.signed_distance(&Point3::from(*p)) >= margin)
    }

    /// First-order signed distance (m) from `p` to the surface, (T - F) / |grad F|: negative
    /// inside. Infinite where the field is zero or flat.
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        let (f, g) = self.body.field_and_gradient(p);
        let gn = g.norm();
        if f <= 0.0 || gn < 1e-12 {
            return if f > self.params.threshold {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            };
        }
        (self.params.threshold - f) / gn
    }

    /// Outward unit normal -grad F / |grad F| at `p` (m); None where the gradient vanishes.
    pub fn normal(&self, p: &Point3<f64>) -> Option<Vector3<f64>> {
        (-self.body.gradient(p)).try_normalize(1e-12)
    }

    /// Newton steps along the gradient onto the iso-surface, starting near it; None if it does
    /// not converge to [`MESH_PROJECTION_TOLERANCE`] in 20 steps.
    pub fn project(&self, p: &Point3<f64>) -> Option<Point3<f64>> {
        let t = self.params.threshold;
        let mut x = *p;
        for _ in 0..20 {
            let (f, g) = self.body.field_and_gradient(&x);
            let g2 = g.norm_squared();
            if g2 < 1e-12 {
                return None;
            }
            let d = (t - f) / g2.sqrt();
            if d.abs() < MESH_PROJECTION_TOLERANCE {
                return Some(x);
            }
            // step limited to 1 cm so a far start cannot jump across the body
            x += (g / g2.sqrt()) * d.clamp(-0.01, 0.01);
        }
        None
    }

    /// The outermost surface point along the ray from the head centre in direction `dir`
    /// (any length), found by marching in from 3 head radii in 1 mm steps and bisecting to 1e-12 m.
    pub fn surface_along(&self, dir: &Vector3<f64>) -> Option<ScalpPoint> {
        let d = dir.try_normalize(1e-300)?;
        let t = self.params.threshold;
        let f = |r: f64| self.body.field(&Point3::from(r * d)) - t;
        let r_max = 3.0 * self.params.head_radius;
        let step = 1e-3;
        let mut hi = r_max;
        if f(hi) > 0.0 {
            return None;
        }
        let mut lo = hi - step;
        while f(lo) <= 0.0 {
            hi = lo;
            lo -= step;
            if lo <= 0.0 {
                return None;
            }
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 {
                lo = mid
            } else {
                hi = mid
            }
            if hi - lo < 1e-12 {
                break;
            }
        }
        let position = Point3::from(0.5 * (lo + hi) * d);
        let position = self.project(&position).unwrap_or(position);
        Some(ScalpPoint {
            position,
            normal: self.normal(&position)?,
        })
    }

    /// True if `p` (m), a point of the body surface, is on the scalp.
    pub fn is_scalp(&self, p: &Point3<f64>) -> bool {
        self.scalp.contains_direction(p)
    }

    /// Unit direction from the head centre in the scalp cap, from two numbers in [0, 1):
    /// uniform in solid angle when they are uniform.
    fn cap_direction(&self, a: f64, b: f64) -> Vector3<f64> {
        let c = self.scalp.half_angle.cos();
        let z = 1.0 - (1.0 - c) * a;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * b;
        let local = Vector3::new(r * phi.cos(), r * phi.sin(), z);
        // rotate +z onto the cap axis (a rotation about x, as the axis lies in the y-z plane)
        let ax = self.scalp.axis;
        let (s, co) = (-ax.y, ax.z); // axis = (0, -sin t, cos t)
        Vector3::new(
            local.x,
            co * local.y - s * local.z,
            s * local.y + co * local.z,
        )
    }

    /// `n` scalp points spread evenly (a Fibonacci spiral in the scalp cap, even in solid
    /// angle about the head centre). Deterministic.
    pub fn scalp_even(&self, n: usize) -> Vec<ScalpPoint> {
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        (0..n)
            .filter_map(|i| {
                let a = (i as f64 + 0.5) / n as f64;
                let b = (i as f64 * golden).fract();
                self.surface_along(&self.cap_direction(a, b))
            })
            .collect()
    }

    /// `n` random scalp points, uniform in surface area (directions uniform in solid angle,
    /// then thinned by the area element r^2 / (n . d) of the surface seen from the centre).
    pub fn scalp_random<R: Rng>(&self, n: usize, rng: &mut R) -> Vec<ScalpPoint> {
        let mut out = Vec::with_capacity(n);
        let r0 = self.params.head_radius;
        // bound of the area weight (r/r0)^2 / cos: r <= 1.3 r0, cos >= 0.5 on this body
        let bound = 1.3f64.powi(2) / 0.5;
        let mut tries = 0usize;
        while out.len() < n && tries < 100 * n + 1000 {
            tries += 1;
            let d = self.cap_direction(rng.random::<f64>(), rng.random::<f64>());
            let Some(p) = self.surface_along(&d) else {
                continue;
            };
            let r = p.position.coords.norm();
            let w = (r / r0).powi(2) / p.normal.dot(&d).max(0.5);
            if rng.random::<f64>() * bound <= w {
                out.push(p);
            }
        }
        out
    }

    /// The display mesh (surface nets of the field, vertices projected onto the iso-surface).
    pub fn mesh(&self) -> HeadMesh {
        let h = self.params.mesh_cell;
        let t = self.params.threshold;
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        for b in &self.body.balls {
            for a in 0..3 {
                lo[a] = lo[a].min(b.centre[a] - b.radius);
                hi[a] = hi[a].max(b.centre[a] + b.radius);
            }
        }
        lo -= Vector3::repeat(h);
        let n: Vec<usize> = (0..3)
            .map(|a| ((hi[a] + h - lo[a]) / h).ceil() as usize + 1)
            .collect();
        let (nx, ny, nz) = (n[0], n[1], n[2]);
        let gp = |i: usize, j: usize, k: usize| lo + h * Vector3::new(i as f64, j as f64, k as f64);
        let gi = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let mut field = vec![0.0; nx * ny * nz];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    field[gi(i, j, k)] = self.body.field(&gp(i, j, k)) - t;
                }
            }
        }
        let inside = |v: f64| v > 0.0;
        // one vertex per cell with a sign change
        let (cx, cy) = (nx - 1, ny - 1);
        let ci = |i: usize, j: usize, k: usize| i + cx * (j + cy * k);
        let mut cell_vertex = vec![u32::MAX; cx * cy * (nz - 1)];
        let mut mesh = HeadMesh::default();
        const EDGES: [([usize; 3], [usize; 3]); 12] = [
            ([0, 0, 0], [1, 0, 0]),
            ([0, 1, 0], [1, 1, 0]),
            ([0, 0, 1], [1, 0, 1]),
            ([0, 1, 1], [1, 1, 1]),
            ([0, 0, 0], [0, 1, 0]),
            ([1, 0, 0], [1, 1, 0]),
            ([0, 0, 1], [0, 1, 1]),
            ([1, 0, 1], [1, 1, 1]),
            ([0, 0, 0], [0, 0, 1]),
            ([1, 0, 0], [1, 0, 1]),
            ([0, 1, 0], [0, 1, 1]),
            ([1, 1, 0], [1, 1, 1]),
        ];
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let mut sum = Vector3::zeros();
                    let mut count = 0;
                    for (a, b) in EDGES {
                        let fa = field[gi(i + a[0], j + a[1], k + a[2])];
                        let fb = field[gi(i + b[0], j + b[1], k + b[2])];
                        if inside(fa) != inside(fb) {
                            let s = fa / (fa - fb);
                            let pa = gp(i + a[0], j + a[1], k + a[2]);
                            let pb = gp(i + b[0], j + b[1], k + b[2]);
                            sum += pa.coords + s * (pb - pa);
                            count += 1;
                        }
                    }
                    if count == 0 {
                        continue;
                    }
                    let guess = Point3::from(sum / count as f64);
                    let p = self.project(&guess).unwrap_or(guess);
                    let nrm = self.normal(&p).unwrap_or(Vector3::z());
                    cell_vertex[ci(i, j, k)] = mesh.positions.len() as u32;
                    mesh.positions.push([p.x as f32, p.y as f32, p.z as f32]);
                    mesh.normals
                        .push([nrm.x as f32, nrm.y as f32, nrm.z as f32]);
                }
            }
        }
        // one quad per grid edge with a sign change, between the four cells around it
        for k in 1..nz - 1 {
            for j in 1..ny - 1 {
                for i in 1..nx - 1 {
                    let f0 = field[gi(i, j, k)];
                    for axis in 0..3 {
                        let (i1, j1, k1) = match axis {
                            0 => (i + 1, j, k),
                            1 => (i, j + 1, k),
                            _ => (i, j, k + 1),
                        };
                        if i1 >= nx || j1 >= ny || k1 >= nz {
                            continue;
                        }
                        let f1 = field[gi(i1, j1, k1)];
                        if inside(f0) == inside(f1) {
                            continue;
                        }
                        // cells around the edge, counter-clockwise about +axis (b then c)
                        let cells: [(usize, usize, usize); 4] = match axis {
                            0 => [(i, j - 1, k - 1), (i, j, k - 1), (i, j, k), (i, j - 1, k)],
                            1 => [(i - 1, j, k - 1), (i - 1, j, k), (i, j, k), (i, j, k - 1)],
                            _ => [(i - 1, j - 1, k), (i, j - 1, k), (i, j, k), (i - 1, j, k)],
                        };
                        let v: Vec<u32> = cells
                            .iter()
                            .map(|&(a, b, c)| cell_vertex[ci(a, b, c)])
                            .collect();
                        if v.contains(&u32::MAX) {
                            continue;
                        }
                        // outward is +axis when the edge's start is inside
                        let q = if inside(f0) {
                            [v[0], v[1], v[2], v[3]]
                        } else {
                            [v[0], v[3], v[2], v[1]]
                        };
                        mesh.indices
                            .extend_from_slice(&[q[0], q[1], q[2], q[0], q[2], q[3]]);
                    }
                }
            }
        }
        mesh
    }
}
