//! Fit to the head: a hairstyle from another tool placed on the built-in head.
//!
//! Hair files in the wild are y-up or z-up, in centimetres, metres or other units, around their
//! own head at their own origin. [`fit()`] maps a file's strands into Coiffure's head frame (m,
//! z up, y forward, origin at the head centre; see [`crate::head`]) in these stages:
//!
//! 1. **Units** (metres per file unit): `--units` ([`FitOptions::units`]), else the file's
//!    metadata (USD `metersPerUnit`), else from the hairstyle's size: the one of m, cm and mm
//!    that makes the roots' spread (median distance from their median point) closest, in ratio,
//!    to the built-in scalp's.
//! 2. **Up axis and facing**: `--up`/`--front`, else metadata (USD `upAxis`), else each of the
//!    axis-aligned candidates (6 up axes x 4 facings, fewer when one is given) is fitted (stage 3)
//!    and scored; the best wins. The score ([`FitParams`]) is the roots' mean truncated squared
//!    distance to the scalp (saturating at [`FitParams::inlier_distance`]: a root off the scalp
//!    costs 1, so the score counts how much of the hairline fits, which is what tells the facing
//!    of a partial hairstyle: a back half turned to face sideways puts its nape on the ears) plus
//!    the fraction of hair points inside the body (hair through the face or neck), plus the
//!    fraction of strands whose tip is above their root (hair hangs: roots above tips), with the
//!    format's convention ([`convention`]: TressFX and USC-HairSalon files are y up facing +z)
//!    preferred by a factor. Where the roots do not tell the facing (a strip from front to back,
//!    the top of a head, a front half that fits the back of the scalp as well) the convention
//!    decides; a format without one (`.hair`) then gets whichever candidate scored lowest, and
//!    [`FitReport::scores`] shows how close the runner-up was.
//! 3. **Scale and translation** putting the roots onto the scalp, the rotation held at the axes'
//!    (a rotation about the head's centre slides a part of a scalp along the sphere at no cost,
//!    so only the axes can fix it). Only the roots that can be on a head of plausible size are
//!    matched: those at most the scalp's height times [`FitParams::scale_freedom`] below the
//!    highest roots (not a character's mane down its back). Trimmed point-to-plane ICP
//!    ([`FitParams`]): each root's nearest scalp sample ([`ScalpIndex`]), the closest
//!    [`FitParams::trim`] fraction kept, and every root within [`FitParams::inlier_distance`] (so
//!    loose strands do not pull), then the scale and translation minimising the squared distances
//!    to the samples' tangent planes (linear least squares), repeated until the roots stop
//!    moving. The scale stays within [`FitParams::scale_freedom`] of the units (heads from 0.8 to
//!    1.25 times ours): the roots' curvature sets it where they cover enough of a round scalp; a
//!    hairstyle whose head is not round (TressFX's Ratboy: a rat's long head) goes to the end of
//!    that range rather than shrinking until its mane fits the nape.
//! 4. **Push-out**: every point the transform puts inside the body (or within
//!    [`lattice::metaball::PUSH_OUT_SKIN`] of it) is moved out onto that offset surface
//!    ([`lattice::metaball::MetaballSet::push_out_many_f32`]).
//!
//! `--no-fit` ([`FitOptions::fit`] false) keeps only what is given (units and axes from options or
//! metadata, else metres and z up facing +y) and skips stages 3 and 4. The [`FitReport`] says
//! what was chosen and why, the transform, which strands are rooted on the scalp and which are
//! loose, and the roots' distances to the scalp.

pub mod scalp_index;
pub mod similarity;
pub mod units;

use crate::formats::{Format, HairCurves, Metadata};
use crate::head::Head;
use nalgebra::{Matrix3, Point3, Vector3};
pub use scalp_index::ScalpIndex;
pub use similarity::Similarity;
pub use units::{parse_units, units_name};

/// A signed coordinate axis of the file's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// +x
    PosX,
    /// -x
    NegX,
    /// +y
    PosY,
    /// -y
    NegY,
    /// +z
    PosZ,
    /// -z
    NegZ,
}

impl Axis {
    /// All six.
    pub const ALL: [Axis; 6] = [Axis::PosX, Axis::NegX, Axis::PosY, Axis::NegY, Axis::PosZ, Axis::NegZ];

    /// Unit vector.
    pub fn vector(self) -> Vector3<f64> {
        match self {
            Axis::PosX => Vector3::x(),
            Axis::NegX => -Vector3::x(),
            Axis::PosY => Vector3::y(),
            Axis::NegY => -Vector3::y(),
            Axis::PosZ => Vector3::z(),
            Axis::NegZ => -Vector3::z(),
        }
    }

    /// Name: "+x", "-y", ...
    pub fn name(self) -> &'static str {
        ["+x", "-x", "+y", "-y", "+z", "-z"][self as usize]
    }

    /// Parses "x", "+x", "-x", "X", ... (case-insensitive).
    pub fn parse(s: &str) -> Result<Axis, String> {
        let t = s.trim().to_ascii_lowercase();
        let (neg, a) = match t.strip_prefix('-') {
            Some(a) => (true, a),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        let i = match a {
            "x" => 0,
            "y" => 2,
            "z" => 4,
            _ => return Err(format!("axis `{s}`: expected x, y, z, +x, -x, +y, -y, +z or -z")),
        };
        Ok(Axis::ALL[i + neg as usize])
    }
}

/// What the caller imposes (command-line `--units`, `--up`, `--front`, `--no-fit`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Metres per file unit; None: metadata, else from the size.
    pub units: Option<f64>,
    /// The file's up axis; None: metadata, else detected.
    pub up: Option<Axis>,
    /// The file's facing (the direction the face looks); None: detected.
    pub front: Option<Axis>,
    /// False (`--no-fit`): only the given units and axes, no detection, no ICP, no push-out.
    pub fit: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { units: None, up: None, front: None, fit: true }
    }
}

/// Constants of the fit (one home; see the module docs for their role).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Scalp samples of the nearest-point index. Default 12,000 (about 2 mm apart).
    pub scalp_samples: usize,
    /// Roots used when scoring the orientation candidates (evenly strided). Default 600.
    pub candidate_roots: usize,
    /// Roots used in the final fit. Default 4,000.
    pub fit_roots: usize,
    /// ICP iterations per orientation candidate. Default 25.
    pub candidate_iterations: usize,
    /// ICP iterations of the final fit (it stops earlier once the roots stop moving). Default 300.
    pub fit_iterations: usize,
    /// Fraction of roots (the closest to the scalp) trimmed ICP always keeps. Default 0.2.
    pub trim: f64,
    /// Roots within this distance of the scalp are kept too, and count as rooted on the scalp in
    /// [`FitReport::rooted`]; also the distance at which the score's cost of a root saturates, m.
    /// Default 0.01 m.
    pub inlier_distance: f64,
    /// Depth of the scalp's top band (below its highest sample) whose centre the roots' median
    /// starts over, m (head frame). Default 0.04 m.
    pub band_height: f64,
    /// Heads between 1 / this and this times the built-in head's size, in the units (dimensionless):
    /// the fit may change the scale from the units by this factor at most either way, and roots
    /// more than this times the scalp's height below the highest roots are not matched (they
    /// cannot be on such a head). Default 1.25.
    pub scale_freedom: f64,
    /// ICP stops when no root moves more than this in an iteration, m. Default 1e-5 m.
    pub tolerance: f64,
    /// Weight of the fraction of hair points inside the body in the score. Default 1.
    pub inside_weight: f64,
    /// Weight of the fraction of strands whose tip is above the root in the score. Default 0.25.
    pub hang_weight: f64,
    /// Factor on the score of the format's conventional orientation (< 1 prefers it). Default 0.6.
    pub convention_factor: f64,
}

impl Default for FitParams {
    fn default() -> Self {
        Self {
            scalp_samples: 12_000,
            candidate_roots: 600,
            fit_roots: 4_000,
            candidate_iterations: 25,
            fit_iterations: 300,
            trim: 0.2,
            inlier_distance: 0.01,
            band_height: 0.04,
            scale_freedom: 1.25,
            tolerance: 1e-5,
            inside_weight: 1.0,
            hang_weight: 0.25,
            convention_factor: 0.6,
        }
    }
}

/// Where a choice of the fit came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Given by the caller (`--units`, `--up`, `--front`).
    Option,
    /// The file's metadata (USD stage metadata).
    Metadata,
    /// Detected from the hairstyle (its size; its shape and the format's convention).
    Detected,
    /// Not detected (`--no-fit`): metres, z up, facing +y.
    Assumed,
}

impl Source {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Source::Option => "option",
            Source::Metadata => "metadata",
            Source::Detected => "detected",
            Source::Assumed => "assumed",
        }
    }
}

/// Distances (m) of the roots to the scalp.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Distances {
    /// Median, m.
    pub median: f64,
    /// 95th percentile, m.
    pub p95: f64,
    /// Largest, m.
    pub max: f64,
}

impl Distances {
    /// Of a set of distances (m); zeros when empty.
    pub fn of(mut d: Vec<f64>) -> Self {
        if d.is_empty() {
            return Self::default();
        }
        d.sort_by(f64::total_cmp);
        let q = |f: f64| d[((f * (d.len() - 1) as f64).round() as usize).min(d.len() - 1)];
        Distances { median: q(0.5), p95: q(0.95), max: d[d.len() - 1] }
    }
}

/// What the fit did.
#[derive(Debug, Clone, PartialEq)]
pub struct FitReport {
    /// Metres per file unit (before the fitted scale).
    pub meters_per_unit: f64,
    /// Where the units came from.
    pub units_source: Source,
    /// The file's up axis.
    pub up: Axis,
    /// The file's facing.
    pub front: Axis,
    /// Where the up axis and facing came from.
    pub orientation_source: Source,
    /// The transform from file coordinates to the head frame (m): its scale is m per file unit.
    pub transform: Similarity,
    /// Fraction of strands rooted on the scalp: root within [`FitParams::inlier_distance`] of it
    /// after the fit and push-out. The others are loose (not rooted on a scalp of our head: e.g. a
    /// character's mane down its back, loose strands).
    pub rooted: f64,
    /// Root-to-scalp distances after the fit and push-out, m, over all strands.
    pub root_distance: Distances,
    /// The same over the rooted strands, m.
    pub rooted_distance: Distances,
    /// The same over the loose strands, m (zeros when there are none).
    pub loose_distance: Distances,
    /// Number of points pushed out of the body.
    pub pushed_out: usize,
    /// Score of the chosen orientation and of the runner-up (lower is better; None when the
    /// orientation was not detected).
    pub scores: Option<(f64, f64)>,
}

/// Why a hairstyle cannot be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// No strand with a point.
    #[error("the hairstyle has no strand with a point")]
    Empty,
    /// A point is not finite.
    #[error("strand {strand} point {point} is not finite: {value:?}")]
    NotFinite {
        /// Strand index.
        strand: usize,
        /// Point index.
        point: usize,
        /// The point.
        value: [f32; 3],
    },
    /// `up` and `front` are parallel.
    #[error("the up axis {up} and the facing {front} must be perpendicular")]
    Parallel {
        /// Up axis name.
        up: &'static str,
        /// Facing name.
        front: &'static str,
    },
}

/// The format's conventional (up, front), if it has one: TressFX (`.tfx`, Direct3D/Maya) and
/// USC-HairSalon (`.data`) are y up facing +z; USD is y up (its fallback `upAxis`) facing +z.
pub fn convention(format: Option<Format>) -> Option<(Axis, Axis)> {
    match format? {
        Format::Tfx | Format::Usc | Format::Usda => Some((Axis::PosY, Axis::PosZ)),
        Format::Hair => None,
    }
}

/// The rotation taking the file's `up` to +z and `front` to +y (the head frame).
pub fn axes_rotation(up: Axis, front: Axis) -> Matrix3<f64> {
    let (u, f) = (up.vector(), front.vector());
    let r = f.cross(&u); // the head's +x = y x z
    Matrix3::from_rows(&[r.transpose(), f.transpose(), u.transpose()])
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median point (per coordinate) and median distance from it.
fn spread(p: &[Point3<f64>]) -> (Point3<f64>, f64) {
    let m = Point3::from(Vector3::from_fn(|a, _| median(&mut p.iter().map(|q| q[a]).collect::<Vec<_>>())));
    let s = median(&mut p.iter().map(|q| (q - m).norm()).collect::<Vec<_>>());
    (m, s)
}

fn strided<T: Copy>(v: &[T], n: usize) -> Vec<T> {
    if v.len() <= n {
        return v.to_vec();
    }
    (0..n).map(|i| v[i * v.len() / n]).collect()
}

/// The state shared by the candidate fits.
struct Fitter<'a> {
    head: &'a Head,
    index: ScalpIndex,
    params: FitParams,
    scalp_spread: f64,
    /// The scalp's height (highest sample minus lowest), m.
    scalp_height: f64,
}

/// One ICP correspondence: a root `a` (after the fixed rotation, file units) and its nearest
/// scalp point `b` with the plane normal there (None: matched point to point).
struct Pair {
    a: Vector3<f64>,
    b: Vector3<f64>,
    normal: Option<Vector3<f64>>,
}

impl Fitter<'_> {
    /// The roots that can lie on a scalp of a plausible size with the axes `rot` and `units` (m
    /// per file unit): those at most the scalp's height times [`FitParams::scale_freedom`] below
    /// the 99th percentile of the roots' heights. The rest (a mane down a character's back, a
    /// rat-tail) cannot be on a head of about our size, whatever the placement.
    fn plausible(&self, roots: &[Point3<f64>], rot: &Matrix3<f64>, units: f64) -> Vec<Point3<f64>> {
        let up = rot.row(2).transpose();
        let mut h: Vec<f64> = roots.iter().map(|r| units * up.dot(&r.coords)).collect();
        h.sort_by(f64::total_cmp);
        let top = h[((0.99 * (h.len() - 1) as f64).round() as usize).min(h.len() - 1)];
        let depth = self.scalp_height * self.params.scale_freedom;
        let sel: Vec<Point3<f64>> = roots.iter().copied().filter(|r| units * up.dot(&r.coords) >= top - depth).collect();
        if sel.len() >= 3 { sel } else { roots.to_vec() }
    }

    /// Trimmed point-to-plane ICP from `start` with its rotation held: only the scale (within
    /// `range`, m per file unit) and the translation change. Returns the transform and the
    /// fraction of roots kept in the last iteration.
    fn icp(&self, roots: &[Point3<f64>], start: Similarity, range: (f64, f64), iterations: usize) -> (Similarity, f64) {
        let rot = start.rotation;
        // centred on the roots' centroid c (well-conditioned least squares): x = s (a - c) + u,
        // u = t + s c
        let c = roots.iter().fold(Vector3::zeros(), |s, r| s + rot * r.coords) / roots.len().max(1) as f64;
        let a: Vec<Vector3<f64>> = roots.iter().map(|r| rot * r.coords - c).collect();
        let (mut s, mut t) = (start.scale, start.translation + start.scale * c);
        let mut kept = 1.0;
        for _ in 0..iterations {
            let near: Vec<_> = a.iter().map(|x| self.index.nearest(&Point3::from(s * x + t))).collect();
            let mut order: Vec<usize> = (0..a.len()).collect();
            order.sort_by(|&i, &j| near[i].distance.total_cmp(&near[j].distance));
            // trimmed ICP: the closest `trim` fraction, and every root within `inlier_distance`
            let n = a.len();
            let k_trim = ((self.params.trim * n as f64).ceil() as usize).clamp(3.min(n), n);
            let within = order.iter().take_while(|&&i| near[i].distance <= self.params.inlier_distance).count();
            let k = within.max(k_trim);
            kept = k as f64 / n as f64;
            let pairs: Vec<Pair> = order[..k]
                .iter()
                .map(|&i| {
                    // over the sample's patch: point to its tangent plane; else to the sample
                    let on_plane = near[i].on_surface != near[i].sample.position;
                    Pair { a: a[i], b: near[i].sample.position.coords, normal: on_plane.then_some(near[i].sample.normal) }
                })
                .collect();
            let Some((s1, t1)) = scale_translation(&pairs, range) else { break };
            let step = a.iter().map(|x| ((s1 - s) * x + (t1 - t)).norm()).fold(0.0, f64::max);
            (s, t) = (s1, t1);
            if step < self.params.tolerance {
                break;
            }
        }
        (Similarity { scale: s, rotation: rot, translation: t - s * c }, kept)
    }

    /// The starting transform for axes `rot` and `units`: the roots' top (99th percentile of
    /// heights) on the scalp's top, their horizontal median over the scalp's top band's centre
    /// (the band [`FitParams::band_height`] deep), at scale `units`.
    fn start(&self, roots: &[Point3<f64>], rot: Matrix3<f64>, units: f64) -> Similarity {
        let scalp: Vec<Point3<f64>> = self.index.samples().iter().map(|p| p.position).collect();
        let top = scalp.iter().map(|q| q.z).fold(f64::NEG_INFINITY, f64::max);
        let band: Vec<&Point3<f64>> = scalp.iter().filter(|q| q.z >= top - self.params.band_height).collect();
        let c = band.iter().fold(Vector3::zeros(), |s, q| s + q.coords) / band.len() as f64;
        let x: Vec<Point3<f64>> = roots.iter().map(|r| Point3::from(units * (rot * r.coords))).collect();
        let mut h: Vec<f64> = x.iter().map(|q| q.z).collect();
        h.sort_by(f64::total_cmp);
        let x_top = h[((0.99 * (h.len() - 1) as f64).round() as usize).min(h.len() - 1)];
        let (m, _) = spread(&x);
        Similarity { scale: units, rotation: rot, translation: Vector3::new(c.x - m.x, c.y - m.y, top - x_top) }
    }

    /// Score of a candidate fit (lower is better; see the module docs).
    fn score(&self, t: &Similarity, roots: &[Point3<f64>], strands: &[Vec<Point3<f64>>]) -> f64 {
        let (a, b, c) = self.score_parts(t, roots, strands);
        a + self.params.inside_weight * b + self.params.hang_weight * c
    }

    /// The score's terms: the roots' mean truncated squared distance to the scalp (min(d,
    /// inlier_distance)^2 / inlier_distance^2: 0 on the scalp, 1 off it), the fraction of hair
    /// points inside the body, the fraction of strands whose tip is above the root.
    fn score_parts(&self, t: &Similarity, roots: &[Point3<f64>], strands: &[Vec<Point3<f64>>]) -> (f64, f64, f64) {
        let delta = self.params.inlier_distance;
        let off = roots.iter().map(|r| (self.index.nearest(&t.apply(r)).distance / delta).min(1.0).powi(2)).sum::<f64>() / roots.len().max(1) as f64;
        let threshold = self.head.params.threshold;
        let (mut inside, mut points, mut up) = (0usize, 0usize, 0usize);
        for s in strands {
            for p in s.iter().skip(1) {
                points += 1;
                inside += (self.head.body.field(&t.apply(p)) > threshold + 0.05) as usize;
            }
            let (a, b) = (t.apply(&s[0]), t.apply(&s[s.len() - 1]));
            up += (b.z > a.z + 0.01 * self.head.params.head_radius) as usize;
        }
        (off, inside as f64 / points.max(1) as f64, up as f64 / strands.len().max(1) as f64)
    }
}

/// The scale s (clamped to `range`) and translation t minimising the sum of squared residuals
/// n . (s a + t - b) (point to plane) or |s a + t - b| (point to point) over `pairs`: linear
/// least squares in (s, t), solved by normal equations. None when degenerate.
fn scale_translation(pairs: &[Pair], range: (f64, f64)) -> Option<(f64, Vector3<f64>)> {
    use nalgebra::{Matrix4, Vector4};
    let (mut m, mut r) = (Matrix4::<f64>::zeros(), Vector4::<f64>::zeros());
    let mut add = |j: Vector4<f64>, y: f64| {
        m += j * j.transpose();
        r += j * y;
    };
    for p in pairs {
        match p.normal {
            Some(n) => add(Vector4::new(n.dot(&p.a), n.x, n.y, n.z), n.dot(&p.b)),
            None => {
                for k in 0..3 {
                    let e = Vector3::ith(k, 1.0);
                    add(Vector4::new(p.a[k], e.x, e.y, e.z), p.b[k]);
                }
            }
        }
    }
    // a tiny relative ridge (Levenberg) keeps the system solvable when the pairs leave a
    // direction unconstrained (e.g. three planes with parallel normals)
    let ridge = Matrix4::from_diagonal(&(m.diagonal() * 1e-12 + Vector4::repeat(1e-300)));
    let x = (m + ridge).cholesky()?.solve(&r);
    let s = x[0];
    if s >= range.0 && s <= range.1 {
        return Some((s, Vector3::new(x[1], x[2], x[3])));
    }
    // clamped scale: the translation re-solved with s fixed
    let s = s.clamp(range.0, range.1);
    let m3 = (m + ridge).fixed_view::<3, 3>(1, 1).into_owned();
    let r3 = r.fixed_rows::<3>(1).into_owned() - m.fixed_view::<3, 1>(1, 0).into_owned() * s;
    let t = m3.cholesky()?.solve(&r3);
    Some((s, t))
}

/// Places `curves` (file units and axes) on `head`: see the module docs. `format` and `meta` say
/// what the file is and what it declares. Returns the strands in the head frame (m; thickness
/// scaled) and the report.
pub fn fit(
    curves: &HairCurves,
    format: Option<Format>,
    meta: &Metadata,
    opts: &FitOptions,
    head: &Head,
    params: &FitParams,
) -> Result<(HairCurves, FitReport), FitError> {
    for (i, s) in curves.strands.iter().enumerate() {
        if let Some(j) = s.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(FitError::NotFinite { strand: i, point: j, value: s[j] });
        }
    }
    let p64 = |p: &[f32; 3]| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let all_roots: Vec<Point3<f64>> = curves.strands.iter().filter(|s| !s.is_empty()).map(|s| p64(&s[0])).collect();
    if all_roots.is_empty() {
        return Err(FitError::Empty);
    }
    if let (Some(u), Some(f)) = (opts.up, opts.front) {
        if u.vector().dot(&f.vector()) != 0.0 {
            return Err(FitError::Parallel { up: u.name(), front: f.name() });
        }
    }
    let meta_up = meta.up_axis.map(|c| if c == 'Z' { Axis::PosZ } else { Axis::PosY });
    let index = ScalpIndex::new(head, params.scalp_samples);
    let scalp_points: Vec<Point3<f64>> = index.samples().iter().map(|p| p.position).collect();
    let (_, scalp_spread) = spread(&scalp_points);
    let heights = scalp_points.iter().map(|p| p.z);
    let scalp_height = heights.clone().fold(f64::NEG_INFINITY, f64::max) - heights.fold(f64::INFINITY, f64::min);
    let fitter = Fitter { head, index, params: *params, scalp_spread, scalp_height };

    // 1. units
    let (units, units_source) = match (opts.units, meta.meters_per_unit, opts.fit) {
        (Some(u), _, _) => (u, Source::Option),
        (None, Some(u), _) => (u, Source::Metadata),
        (None, None, false) => (1.0, Source::Assumed),
        (None, None, true) => {
            let (_, s) = spread(&all_roots);
            let u = [1.0, 0.01, 0.001]
                .into_iter()
                .min_by(|a, b| {
                    let e = |u: f64| (u * s / fitter.scalp_spread).ln().abs();
                    e(*a).total_cmp(&e(*b))
                })
                .unwrap();
            (if s > 0.0 { u } else { 1.0 }, Source::Detected)
        }
    };

    // 2. orientation candidates
    let up_given = opts.up.map(|a| (a, Source::Option)).or(meta_up.map(|a| (a, Source::Metadata)));
    let mut candidates: Vec<(Axis, Axis)> = Vec::new();
    let ups: Vec<Axis> = match (up_given, opts.fit) {
        (Some((a, _)), _) => vec![a],
        (None, false) => vec![Axis::PosZ],
        (None, true) => Axis::ALL.to_vec(),
    };
    for &u in &ups {
        let fronts: Vec<Axis> = match (opts.front, opts.fit) {
            (Some(f), _) => vec![f],
            (None, false) if u.vector().dot(&Vector3::y()) == 0.0 => vec![Axis::PosY],
            (None, false) => vec![Axis::PosZ],
            (None, true) => Axis::ALL.into_iter().filter(|f| f.vector().dot(&u.vector()) == 0.0).collect(),
        };
        candidates.extend(fronts.into_iter().filter(|f| f.vector().dot(&u.vector()) == 0.0).map(|f| (u, f)));
    }
    let orientation_source = match (candidates.len(), up_given, opts.front) {
        (1, Some((_, s)), Some(_)) => s,
        (1, None, Some(_)) => Source::Option,
        (1, Some((_, s)), None) if !opts.fit => s,
        (1, _, _) if !opts.fit => Source::Assumed,
        _ => Source::Detected,
    };

    let mut out = curves.clone();
    if !opts.fit {
        let (u, f) = candidates[0];
        let t = Similarity { scale: units, rotation: axes_rotation(u, f), translation: Vector3::zeros() };
        transform_curves(&mut out, &t);
        let d: Vec<f64> = all_roots.iter().map(|r| fitter.index.nearest(&t.apply(r)).distance).collect();
        let (rooted, root_distance, rooted_distance, loose_distance) = root_classes(d, params.inlier_distance);
        let report = FitReport {
            meters_per_unit: units,
            units_source,
            up: u,
            front: f,
            orientation_source,
            transform: t,
            rooted,
            root_distance,
            rooted_distance,
            loose_distance,
            pushed_out: 0,
            scores: None,
        };
        return Ok((out, report));
    }

    // 3. candidate fits and scores, then the final fit of the best
    let roots_c = strided(&all_roots, params.candidate_roots);
    let nonempty: Vec<&Vec<[f32; 3]>> = curves.strands.iter().filter(|s| !s.is_empty()).collect();
    let strands_c: Vec<Vec<Point3<f64>>> = strided(&nonempty, params.candidate_roots)
        .into_iter()
        .map(|s| strided(&s.iter().map(p64).collect::<Vec<_>>(), 8))
        .collect();
    let conv = convention(format).filter(|_| meta_up.is_none() || meta_up == convention(format).map(|c| c.0));
    let near_units = (units / params.scale_freedom, units * params.scale_freedom);
    let mut scored: Vec<(f64, (Axis, Axis), Similarity)> = candidates
        .iter()
        .map(|&(u, f)| {
            let rot = axes_rotation(u, f);
            let sel = fitter.plausible(&roots_c, &rot, units);
            let start = fitter.start(&sel, rot, units);
            let (t, _) = fitter.icp(&sel, start, near_units, params.candidate_iterations);
            let mut s = fitter.score(&t, &sel, &strands_c);
            if conv == Some((u, f)) {
                s *= params.convention_factor;
            }
            (s, (u, f), t)
        })
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (best_score, (up, front), start) = scored[0];
    let scores = (scored.len() > 1 && orientation_source == Source::Detected).then(|| (best_score, scored[1].0));
    let roots_f = fitter.plausible(&strided(&all_roots, params.fit_roots), &start.rotation, units);
    let (t, _) = fitter.icp(&roots_f, start, near_units, params.fit_iterations);

    // 4. transform and push out
    transform_curves(&mut out, &t);
    let mut pushed_out = 0;
    for s in &mut out.strands {
        pushed_out += head.body.push_out_many_f32(s, head.params.threshold, lattice::metaball::PUSH_OUT_SKIN);
    }
    let d: Vec<f64> = out.strands.iter().filter(|s| !s.is_empty()).map(|s| fitter.index.nearest(&p64(&s[0])).distance).collect();
    let (rooted, root_distance, rooted_distance, loose_distance) = root_classes(d, params.inlier_distance);
    let report = FitReport {
        meters_per_unit: units,
        units_source,
        up,
        front,
        orientation_source,
        transform: t,
        rooted,
        root_distance,
        rooted_distance,
        loose_distance,
        pushed_out,
        scores,
    };
    Ok((out, report))
}

/// Of the roots' distances to the scalp (m): the fraction within `rooted_within` (m), and the
/// distances of all, of those within and of the others.
fn root_classes(d: Vec<f64>, rooted_within: f64) -> (f64, Distances, Distances, Distances) {
    let (on, off): (Vec<f64>, Vec<f64>) = d.iter().partition(|&&x| x <= rooted_within);
    (on.len() as f64 / d.len().max(1) as f64, Distances::of(d), Distances::of(on), Distances::of(off))
}

/// Applies `t` to every point of `c` (f32) and scales the thickness by its scale.
pub fn transform_curves(c: &mut HairCurves, t: &Similarity) {
    for p in c.strands.iter_mut().flatten() {
        let q = t.apply(&Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        *p = [q.x as f32, q.y as f32, q.z as f32];
    }
    if let Some(w) = &mut c.thickness {
        w.iter_mut().for_each(|x| *x = (*x as f64 * t.scale) as f32);
    }
}

/// Why a hair file cannot be loaded onto the head.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file cannot be read.
    #[error(transparent)]
    Format(#[from] crate::formats::FormatError),
    /// The strands cannot be fitted.
    #[error("cannot fit the hairstyle: {0}")]
    Fit(#[from] FitError),
    /// The file is over a bound of [`crate::LoadLimits`] (size, strands, points); says which.
    #[error("{0}")]
    Limit(String),
}

/// Parses `bytes` in `format` and fits the strands onto the built-in head with `opts` and the
/// default [`FitParams`]: the viewer's LOAD. The file's size is checked against `limits` before it is read,
/// its strand and point counts before the fit (the box around the head is `engine::scene::Scene::from_curves`'
/// check, after the fit).
pub fn read_and_fit(format: Format, bytes: &[u8], opts: &FitOptions, limits: &crate::LoadLimits) -> Result<(HairCurves, FitReport), LoadError> {
    limits.check_size(bytes.len()).map_err(LoadError::Limit)?;
    let (curves, meta) = format.read_with_metadata(bytes)?;
    limits.check_counts(&curves).map_err(LoadError::Limit)?;
    Ok(fit(&curves, Some(format), &meta, opts, &Head::default(), &FitParams::default())?)
}

/// [`read_and_fit`] of a file, the format chosen by its extension.
pub fn fit_file(path: impl AsRef<std::path::Path>, opts: &FitOptions) -> Result<(HairCurves, FitReport), LoadError> {
    let (curves, format, meta) = crate::formats::read_file_with_metadata(path)?;
    Ok(fit(&curves, Some(format), &meta, opts, &Head::default(), &FitParams::default())?)
}


#[cfg(test)]
mod tests {
    use super::*;


    /// Exact pairs (points on planes through s a + t, and points matched point to point) give
    /// back s and t; a scale outside the range is clamped and t re-solved for it.
    #[test]
    fn scale_translation_recovers_a_known_scale_and_translation() {
        let (s, t) = (0.013, Vector3::new(-0.2, 1.5, 0.07));
        let pairs: Vec<Pair> = (0..40)
            .map(|i| {
                let f = i as f64;
                let a = Vector3::new((0.7 * f).sin(), (1.3 * f).cos(), 0.1 * f - 2.0) * 9.0;
                let n = Vector3::new((0.4 * f).cos(), (0.9 * f).sin(), 0.5).normalize();
                // b anywhere on the plane through s a + t with normal n (offset along the plane)
                let along = n.cross(&Vector3::new(0.3, -0.2, 1.0)).normalize() * (0.01 * f);
                let x = s * a + t;
                Pair { a, b: if i % 5 == 0 { x } else { x + along }, normal: (i % 5 != 0).then_some(n) }
            })
            .collect();
        let (s1, t1) = scale_translation(&pairs, (0.0, 1.0)).unwrap();
        assert!((s1 - s).abs() < 1e-12 && (t1 - t).norm() < 1e-10, "{s1} {t1:?}");
        // clamped: t is the least-squares translation for the clamped scale
        let (s2, t2) = scale_translation(&pairs, (0.02, 1.0)).unwrap();
        assert_eq!(s2, 0.02);
        let cost = |t: Vector3<f64>| pairs.iter().map(|p| match p.normal {
            Some(n) => n.dot(&(0.02 * p.a + t - p.b)).powi(2),
            None => (0.02 * p.a + t - p.b).norm_squared(),
        }).sum::<f64>();
        for d in [Vector3::x(), Vector3::y(), Vector3::z()] {
            assert!(cost(t2) <= cost(t2 + 1e-4 * d) && cost(t2) <= cost(t2 - 1e-4 * d));
        }
    }
}
