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
//!    and scored; the best wins. The score ([`FitParams`]) is the trimmed root-to-scalp residual
//!    (relative to the head radius) plus the fraction of hair points inside the body (hair through
//!    the face or neck), plus the fraction of strands whose tip is above their root (hair hangs:
//!    roots above tips), with the format's convention ([`convention`]: TressFX and USC-HairSalon
//!    files are y up facing +z) preferred by a factor.
//! 3. **Similarity transform** (scale, rotation, translation) putting the roots onto the scalp:
//!    trimmed ICP ([`FitParams`]): each root's nearest scalp point (tangent-plane projection,
//!    [`ScalpIndex`]), the closest [`FitParams::trim`] fraction kept, and every root within
//!    [`FitParams::inlier_distance`] (so strands whose roots are not on a scalp, e.g. loose
//!    strands or hair rooted on the neck, do not pull), the least-squares similarity
//!    of the kept pairs ([`Similarity::fit`]), repeated until the roots stop moving. The
//!    orientation candidates are fitted with the scale held within [`FitParams::scale_freedom`]
//!    of the units (a head about our size, so that no candidate wins by shrinking onto the scalp);
//!    the final fit of the chosen orientation lets the scale adapt within
//!    [`FitParams::scale_range`] of the units (a head of another size, or roots covering only
//!    part of a scalp: a character's mohawk strip from forehead to back, e.g. TressFX's Ratboy,
//!    goes to the range's lower end, 0.3, with 57 % of its roots within 1 cm of the scalp and a
//!    root-to-scalp median of 2.8 mm; a full hairstyle keeps its scale).
//! 4. **Push-out**: every point the transform puts inside the body (or within
//!    [`lattice::metaball::PUSH_OUT_SKIN`] of it) is moved out onto that offset surface
//!    ([`lattice::metaball::MetaballSet::push_out_many_f32`]).
//!
//! `--no-fit` ([`FitOptions::fit`] false) keeps only what is given (units and axes from options or
//! metadata, else metres and z up facing +y) and skips stages 3 and 4. The [`FitReport`] says
//! what was chosen and why, the transform, and the roots' distances to the scalp.

pub mod scalp_index;
pub mod similarity;

use crate::formats::{Format, HairCurves, Metadata};
use crate::head::Head;
use nalgebra::{Matrix3, Point3, Vector3};
pub use scalp_index::ScalpIndex;
pub use similarity::Similarity;

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

/// Parses a unit: "m", "cm", "mm", "in" (inch), "ft", or a number of metres per unit.
pub fn parse_units(s: &str) -> Result<f64, String> {
    let v = match s.trim().to_ascii_lowercase().as_str() {
        "m" => 1.0,
        "dm" => 0.1,
        "cm" => 0.01,
        "mm" => 0.001,
        "in" | "inch" => 0.0254,
        "ft" => 0.3048,
        t => t.parse::<f64>().map_err(|_| format!("units `{s}`: expected m, cm, mm, in, ft or metres per unit (a number)"))?,
    };
    if !(v > 0.0 && v.is_finite()) {
        return Err(format!("units `{s}`: metres per unit must be a positive number"));
    }
    Ok(v)
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
    /// ICP iterations of the final fit (a scale far from the units is reached slowly). Default 300.
    pub fit_iterations: usize,
    /// Fraction of roots (the closest to the scalp) trimmed ICP always keeps. Default 0.2.
    pub trim: f64,
    /// Roots within this distance of the scalp are kept too (and count as on the scalp in
    /// [`FitReport::inliers`]), m. Default 0.01 m.
    pub inlier_distance: f64,
    /// Range of the scale relative to the units in the final fit (a head of another size).
    /// Default (0.3, 3).
    pub scale_range: (f64, f64),
    /// Depth of the top band of roots (below the highest) whose extent sets the starting scale, m
    /// (head frame). Default 0.04 m.
    pub band_height: f64,
    /// ICP of the orientation candidates may change the scale from the units by this factor at
    /// most (either way). Default 1.25.
    pub scale_freedom: f64,
    /// ICP stops when no root moves more than this in an iteration, m. Default 1e-5 m.
    pub tolerance: f64,
    /// Fraction of roots in the score's trimmed residual. Default 0.5.
    pub score_fraction: f64,
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
            scale_range: (0.3, 3.0),
            band_height: 0.04,
            scale_freedom: 1.25,
            tolerance: 1e-5,
            score_fraction: 0.5,
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
    /// Fraction of roots the trimmed ICP kept in its last iteration (1 without a fit).
    pub inliers: f64,
    /// Root-to-scalp distances after the fit and push-out, m, over all strands.
    pub root_distance: Distances,
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
}

impl Fitter<'_> {
    /// Trimmed ICP from `start` (scale kept within `range`, m per file unit); returns the
    /// transform and the kept fraction.
    fn icp(&self, roots: &[Point3<f64>], start: Similarity, range: (f64, f64), iterations: usize) -> (Similarity, f64) {
        let mut t = start;
        let mut kept = 1.0;
        let mut prev: Vec<Point3<f64>> = roots.iter().map(|r| t.apply(r)).collect();
        for _ in 0..iterations {
            let near: Vec<_> = prev.iter().map(|x| self.index.nearest(x)).collect();
            let mut order: Vec<usize> = (0..roots.len()).collect();
            order.sort_by(|&a, &b| near[a].distance.total_cmp(&near[b].distance));
            // trimmed ICP: the closest `trim` fraction, then (once it holds) every root within
            // `inlier_distance` of the scalp
            let n = roots.len();
            let k_trim = ((self.params.trim * n as f64).ceil() as usize).clamp(3.min(n), n);
            let within = order.iter().take_while(|&&i| near[i].distance <= self.params.inlier_distance).count();
            let best_k = within.max(k_trim);
            kept = best_k as f64 / n as f64;
            let a: Vec<Point3<f64>> = order[..best_k].iter().map(|&i| roots[i]).collect();
            let b: Vec<Point3<f64>> = order[..best_k].iter().map(|&i| near[i].on_surface).collect();
            let Some(next) = Similarity::fit(&a, &b, range) else { break };
            t = next;
            let moved: Vec<Point3<f64>> = roots.iter().map(|r| t.apply(r)).collect();
            let step = moved.iter().zip(&prev).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            prev = moved;
            if step < self.params.tolerance {
                break;
            }
        }
        (t, kept)
    }

    /// The starting transform for axes `rot` and `units`: the roots' top band (those within
    /// [`FitParams::band_height`] of the highest root) centred on the scalp's top band, scaled so
    /// that the band's longer horizontal extent (5th to 95th percentile) matches the scalp's.
    fn start(&self, roots: &[Point3<f64>], rot: Matrix3<f64>, units: f64) -> Similarity {
        // (centre x, y, top z, longer horizontal extent) of the band `h` deep
        let band = |p: &[Point3<f64>], h: f64| {
            let top = p.iter().map(|q| q.z).fold(f64::NEG_INFINITY, f64::max);
            let sel: Vec<&Point3<f64>> = p.iter().filter(|q| q.z >= top - h).collect();
            let c = sel.iter().fold(Vector3::zeros(), |s, q| s + q.coords) / sel.len() as f64;
            let extent = |a: usize| {
                let mut v: Vec<f64> = sel.iter().map(|q| q[a]).collect();
                v.sort_by(f64::total_cmp);
                v[(0.95 * (v.len() - 1) as f64) as usize] - v[(0.05 * (v.len() - 1) as f64) as usize]
            };
            (Vector3::new(c.x, c.y, top), extent(0).max(extent(1)))
        };
        let scalp: Vec<Point3<f64>> = self.index.samples().iter().map(|p| p.position).collect();
        let h = self.params.band_height;
        let (scalp_top, scalp_extent) = band(&scalp, h);
        let raw: Vec<Point3<f64>> = roots.iter().map(|r| Point3::from(rot * r.coords)).collect();
        let _ = scalp_extent;
        let scale = units;
        let x: Vec<Point3<f64>> = raw.iter().map(|r| Point3::from(scale * r.coords)).collect();
        let (top, _) = band(&x, h);
        Similarity { scale, rotation: rot, translation: scalp_top - top }
    }

    /// Score of a candidate fit (lower is better; see the module docs).
    fn score(&self, t: &Similarity, roots: &[Point3<f64>], strands: &[Vec<Point3<f64>>]) -> f64 {
        let (a, b, c) = self.score_parts(t, roots, strands);
        a + self.params.inside_weight * b + self.params.hang_weight * c
    }

    /// The score's terms: trimmed residual / head radius, fraction inside, fraction hanging up.
    fn score_parts(&self, t: &Similarity, roots: &[Point3<f64>], strands: &[Vec<Point3<f64>>]) -> (f64, f64, f64) {
        let mut d: Vec<f64> = roots.iter().map(|r| self.index.nearest(&t.apply(r)).distance).collect();
        d.sort_by(f64::total_cmp);
        let k = ((self.params.score_fraction * d.len() as f64).ceil() as usize).clamp(1, d.len());
        let rms = (d[..k].iter().map(|x| x * x).sum::<f64>() / k as f64).sqrt();
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
        (rms / self.head.params.head_radius, inside as f64 / points.max(1) as f64, up as f64 / strands.len().max(1) as f64)
    }
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
    let fitter = Fitter { head, index, params: *params, scalp_spread };

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
        let d = all_roots.iter().map(|r| fitter.index.nearest(&t.apply(r)).distance).collect();
        let report = FitReport {
            meters_per_unit: units,
            units_source,
            up: u,
            front: f,
            orientation_source,
            transform: t,
            inliers: 1.0,
            root_distance: Distances::of(d),
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
    let mut scored: Vec<(f64, (Axis, Axis), Similarity)> = candidates
        .iter()
        .map(|&(u, f)| {
            let start = fitter.start(&roots_c, axes_rotation(u, f), units);
            let near_units = (units / params.scale_freedom, units * params.scale_freedom);
            let (t, _) = fitter.icp(&roots_c, start, near_units, params.candidate_iterations);
            let mut s = fitter.score(&t, &roots_c, &strands_c);
            if conv == Some((u, f)) {
                s *= params.convention_factor;
            }
            (s, (u, f), t)
        })
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (best_score, (up, front), start) = scored[0];
    let scores = (scored.len() > 1 && orientation_source == Source::Detected).then(|| (best_score, scored[1].0));
    let roots_f = strided(&all_roots, params.fit_roots);
    // the final fit lets the scale adapt to a head of another size (a character's head, a
    // hairstyle covering only part of a scalp such as a mohawk strip)
    let head_sizes = (units * params.scale_range.0, units * params.scale_range.1);
    let (t, inliers) = fitter.icp(&roots_f, start, head_sizes, params.fit_iterations);

    // 4. transform and push out
    transform_curves(&mut out, &t);
    let mut pushed_out = 0;
    for s in &mut out.strands {
        pushed_out += head.body.push_out_many_f32(s, head.params.threshold, lattice::metaball::PUSH_OUT_SKIN);
    }
    let d = out.strands.iter().filter(|s| !s.is_empty()).map(|s| fitter.index.nearest(&p64(&s[0])).distance).collect();
    let report = FitReport {
        meters_per_unit: units,
        units_source,
        up,
        front,
        orientation_source,
        transform: t,
        inliers,
        root_distance: Distances::of(d),
        pushed_out,
        scores,
    };
    Ok((out, report))
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
