//! Hairstyle generation: guide Super-Helices rooted on the scalp and render strands bound to them.
//!
//! ## What is generated
//! - **Guides** (a few hundred): the local layer's Super-Helices ([`strand::StrandModel`] +
//!   [`strand::StrandState`]), reduced model, rooted at scalp points spread evenly
//!   ([`Head::scalp_even`]), root tangent along the scalp normal. Each guide is the axis of a
//!   wisp, groomed as a planar curve: it leaves the scalp along the normal, turns over the arc
//!   [`HairstyleParams::lift`] to lie along the scalp, wraps around the head at the lifted
//!   radius until it points as steeply down as its plane allows, then goes straight. Its plane
//!   holds the scalp normal and the combing direction [`HairstyleParams::flow`] projected onto
//!   the scalp, **turned towards the vertical where needed for a stable groom** ([`crate::groom`]: a
//!   strand hanging in a plane far from upright is an unstable equilibrium); the hanging part leans
//!   out by [`HairstyleParams::hang_tilt`] (more where needed to clear the body). The model's rest
//!   coordinates are the **sag-free rest shape** of that groomed state
//!   ([`strand::statics::sag_free_rest`]): the groomed guide is in static equilibrium under
//!   gravity, and a stable one (Hessian positive definite, kept in [`Guide::stable`]). A guide no plane
//!   makes stable (long or heavy hair) is relaxed to the nearest stable minimum of its sag-free
//!   model ([`strand::statics::solve_equilibrium`]) if that lies outside the body; else it is kept
//!   with `stable = false`.
//! - **Render strands** (>= 100,000): polylines of a fixed vertex count rooted at random scalp
//!   points (uniform in area), each bound to its `guides_per_render` nearest guides (by root
//!   distance, weights ~ 1/(d + 1 mm)^2, summing to 1) with a per-vertex offset, so that vertex j
//!   is `sum_k w_k G_k(u_j) + offset_j` (G_k(u): guide k's centreline at the fraction u of its
//!   length); at the generated (rest) guide shapes this reproduces the strand exactly, and when
//!   the guides move the strand follows ([`RenderStrands::follow`]). They are also bound to the
//!   lattice with [`Hairstyle::bind`] (quadratic B-spline FFD).
//!
//! ## Curliness (the paper's future work: a high-level property)
//! Curliness c in [0, 1] sets the natural curl as a helix of radius R and curl index
//! CI = (strand length) / (end-to-end length), both interpolated over the range of natural hair
//! (DESIGN.md section 7, after Loussouarn et al. 2007: curl radius 0.6 to 16 cm):
//! - R(c) = R_max (R_min / R_max)^c, R_max = 0.16 m, R_min = 0.006 m (log-linear);
//! - CI(c) = 1 + 1.5 c (1: straight, 2.5: tight curls; an assumption within the range of curl
//!   indices of natural hair, not a fit);
//! - a helix of radius R and pitch 2 pi C has curl index sqrt(R^2 + C^2) / C, so
//!   C = R / sqrt(CI^2 - 1); its Darboux vector in the material frame is
//!   (twist, bend) = (C, R) / (R^2 + C^2), the **rest twist and rest bend** of a curly strand
//!   (exact: a Super-Helix with this constant Darboux vector is that helix, of radius
//!   bend / (twist^2 + bend^2) = R). c = 0 is straight (twist = bend = 0) and the map is
//!   continuous there (C grows without bound as CI -> 1).
//!
//! Guides are wisp axes; a curly wisp is shorter than its hair: guide length = L / CI. Render
//! strands curl about their interpolated wisp axis as that helix (radius R, pitch 2 pi C; the
//! radius fades in over the first [`CURL_RAMP`] from the root and is capped at
//! [`HairstyleParams::max_curl_amplitude`], because a strand in a hairstyle does not leave its wisp
//! by more than a few cm: loose curls of larger radius are drawn as waves of that amplitude).
//! [`Curl`] gives the numbers for the local layer's curly strands.

use crate::formats::HairCurves;
use crate::groom::{combing_direction, groom_directions, groomed_state, PLANE_TILTS};
pub use crate::error::GenerateError;
pub use crate::params::HairstyleParams;
use crate::head::{Head, ScalpPoint};
use lattice::ffd::{Binding, FfdLattice};
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use strand::statics::{sag_free_rest, solve_equilibrium, StaticOptions};
use strand::{HairType, ModelKind, StrandModel, StrandState};

pub use crate::render::{nearest_guides, nearest_guides_where, RenderStrands};
use crate::render::lerp_samples;

/// Largest natural curl radius of the curliness map (c = 0+), m (DESIGN.md section 7).
pub const CURL_RADIUS_MAX: f64 = 0.16;
/// Smallest natural curl radius of the curliness map (c = 1), m (DESIGN.md section 7).
pub const CURL_RADIUS_MIN: f64 = 0.006;
/// Curl index CI = strand length / end-to-end length at curliness 1 (1 at curliness 0).
pub const CURL_INDEX_MAX: f64 = 2.5;
/// Arc length from the root over which a render strand's curl radius fades in, m.
pub const CURL_RAMP: f64 = 0.01;
/// Smallest gap (m) kept between a render strand vertex (other than the root) and the head surface.
pub const RENDER_GAP: f64 = 0.001;

/// The natural curl of a curliness value: helix radius and pitch, curl index, and the rest
/// Darboux vector (twist, bend) of a Super-Helix with that shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curl {
    /// Helix radius R, m.
    pub radius: f64,
    /// Helix pitch 2 pi C (axial length of one turn), m.
    pub pitch: f64,
    /// Curl index CI = arc length / axial length (>= 1).
    pub curl_index: f64,
    /// Rest twist C / (R^2 + C^2), rad/m.
    pub twist: f64,
    /// Rest bend R / (R^2 + C^2), rad/m.
    pub bend: f64,
}

impl Curl {
    /// The curl of curliness `c` in [0, 1]; None for c = 0 (straight hair). See the module docs.
    pub fn from_curliness(c: f64) -> Result<Option<Curl>, GenerateError> {
        if !(0.0..=1.0).contains(&c) {
            return Err(GenerateError::InvalidParameter {
                field: "curliness",
                reason: format!("must be in [0, 1], got {c}"),
            });
        }
        if c == 0.0 {
            return Ok(None);
        }
        let radius = CURL_RADIUS_MAX * (CURL_RADIUS_MIN / CURL_RADIUS_MAX).powf(c);
        let curl_index = 1.0 + (CURL_INDEX_MAX - 1.0) * c;
        let cc = radius / (curl_index * curl_index - 1.0).sqrt();
        let d = radius * radius + cc * cc;
        Ok(Some(Curl {
            radius,
            pitch: std::f64::consts::TAU * cc,
            curl_index,
            twist: cc / d,
            bend: radius / d,
        }))
    }

    /// Helix radius (m) of the Super-Helix rest Darboux vector: bend / (twist^2 + bend^2).
    pub fn darboux_radius(&self) -> f64 {
        self.bend / (self.twist * self.twist + self.bend * self.bend)
    }
}

/// One guide strand: a Super-Helix rooted on the scalp.
#[derive(Debug, Clone, PartialEq)]
pub struct Guide {
    /// The strand model; its rest coordinates are the sag-free rest of the groomed state.
    pub model: StrandModel,
    /// The groomed state (at rest, root on the scalp, tangent along the scalp normal).
    pub state: StrandState,
    /// The scalp point the guide grows from.
    pub root: ScalpPoint,
    /// Whether the groomed state is a stable equilibrium of the sag-free model under gravity.
    pub stable: bool,
}

impl Guide {
    /// `samples` centreline points evenly spaced in arc length from root to tip, m.
    pub fn samples(&self, samples: usize) -> Vec<Point3<f64>> {
        strand::kinematics::centerline(&self.model, &self.state, samples).into_iter().map(|(_, p)| Point3::from(p)).collect()
    }
}

/// A generated (or loaded) hairstyle on the built-in head.
#[derive(Debug, Clone, PartialEq)]
pub struct Hairstyle {
    /// The head it grows on.
    pub head: Head,
    /// The parameters it was generated with.
    pub params: HairstyleParams,
    /// The natural curl (None: straight hair).
    pub curl: Option<Curl>,
    /// Guide strands (Super-Helices).
    pub guides: Vec<Guide>,
    /// Render strands bound to the guides.
    pub render: RenderStrands,
}

fn build_guide(
    params: &HairstyleParams,
    hair: &HairType,
    head: &Head,
    length: f64,
    index: usize,
    root: ScalpPoint,
) -> Result<Guide, GenerateError> {
    let err = |source| GenerateError::Strand {
        guide: index,
        source,
    };
    let model = StrandModel::new(
        ModelKind::Reduced,
        length,
        params.guide_segments,
        hair.section().map_err(err)?,
        hair.material().map_err(err)?,
    )
    .map_err(err)?;
    // The first groom whose sag-free rest is stable (crate::groom), in order: the combing plane; the
    // same turning out of it to hang down after the wrap, then after ever fewer wrapped segments; planes
    // nearer the vertical (PLANE_TILTS). Each with the smallest outward tilt of the hanging part that
    // keeps the guide outside the body (crate::groom::groomed_state).
    let mut best = None;
    let f0 = groom_directions(params, &root, f64::INFINITY)[0];
    let mut candidates = vec![(f0, None)];
    for wrap in (1..=params.guide_segments).rev() {
        candidates.push((f0, Some(wrap)));
    }
    for max_plane_tilt in PLANE_TILTS {
        for f in groom_directions(params, &root, max_plane_tilt) {
            if !candidates.iter().any(|(g, _)| (g - f).norm() < 1e-12) {
                candidates.push((f, None));
            }
        }
    }
    for (f, turned) in candidates {
        let state = groomed_state(params, head, &model, &root, &f, turned).map_err(err)?;
        let (sag_free, stable) = sag_free_rest(&model, &state, &[]).map_err(err)?;
        best = Some((sag_free, state, stable));
        if stable {
            break;
        }
    }
    let (model, state, stable) = best.expect("at least one plane");
    let (state, stable) = stabilise(&model, state, stable, head);
    Ok(Guide {
        model,
        state,
        root,
        stable,
    })
}

/// The generated groom's last resort for a guide no plane makes stable: a groomed `state` whose sag-free rest
/// (`model`, from [`sag_free_rest`]) is not a stable equilibrium (`stable` false) is relaxed to the nearest
/// stable minimum of that model ([`solve_equilibrium`] from a slightly twisted start) if that lies outside the
/// body; else it is kept, flagged unstable. Returns the state and the flag. A guide fitted to a file's strand
/// is not relaxed (it would leave its strand by centimetres, [`crate::fitted`]); the live session holds every
/// guide, generated or fitted, by the one hold (engine `HapticParams::hold_distance`).
pub fn stabilise(model: &StrandModel, state: StrandState, stable: bool, head: &Head) -> (StrandState, bool) {
    if stable {
        return (state, true);
    }
    let mut start = state.clone();
    for i in 0..model.segments {
        start.q[model.dofs_per_segment() * i] += 1e-3 * if i % 2 == 0 { 1.0 } else { -1.0 };
    }
    if let Ok(eq) = solve_equilibrium(model, &start, &[], &StaticOptions::default()) {
        let s = StrandState { q: eq.q.clone(), ..state.clone() };
        if eq.stable && head.clears(model, &s, 0.0) {
            return (s, true);
        }
    }
    (state, false)
}

/// Keeps every vertex of `path` (m, head frame) but the root at least [`RENDER_GAP`] outside the body of
/// `head` (pushed along the body's normal, up to four times, at most 5 cm in at a time).
pub fn keep_outside(head: &Head, path: &mut [Point3<f64>]) {
    for p in path.iter_mut().skip(1) {
        for _ in 0..4 {
            let d = head.signed_distance(p);
            if d >= RENDER_GAP {
                break;
            }
            let Some(nrm) = head.normal(p) else { break };
            *p += (RENDER_GAP - d.max(-0.05) + 1e-5) * nrm;
        }
    }
}

/// Parallel-transported unit vector perpendicular to each tangent of a polyline.
fn transported_normals(p: &[Point3<f64>]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let n = p.len();
    let tangent = |j: usize| {
        let (a, b) = if j == 0 {
            (0, 1)
        } else if j == n - 1 {
            (n - 2, n - 1)
        } else {
            (j - 1, j + 1)
        };
        (p[b] - p[a]).try_normalize(1e-15).unwrap_or(Vector3::z())
    };
    let mut out = Vec::with_capacity(n);
    let t0 = tangent(0);
    let mut u = t0
        .cross(&Vector3::z())
        .try_normalize(1e-6)
        .unwrap_or_else(|| t0.cross(&Vector3::x()).normalize());
    for j in 0..n {
        let t = tangent(j);
        u = (u - t * t.dot(&u)).try_normalize(1e-9).unwrap_or_else(|| {
            t.cross(&Vector3::x())
                .try_normalize(1e-6)
                .unwrap_or(Vector3::y())
        });
        out.push((u, t.cross(&u)));
    }
    out
}

impl Hairstyle {
    /// Generates a hairstyle. Deterministic for a given `params` (including the seed), whatever
    /// the number of threads.
    pub fn generate(params: &HairstyleParams) -> Result<Self, GenerateError> {
        let hair = params.hair()?;
        let head = Head::new(params.head)?;
        let curl = Curl::from_curliness(params.curliness)?;
        let guides = Self::build_guides(params, &hair, &head, curl.as_ref())?;
        // roots: chunks of 1024 with their own random stream, so the result does not depend on threads
        const CHUNK: usize = 1024;
        let chunks = params.render_count.div_ceil(CHUNK);
        let roots: Vec<ScalpPoint> = (0..chunks)
            .into_par_iter()
            .flat_map_iter(|c| {
                let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
                rng.set_stream(c as u64 + 1);
                let n = CHUNK.min(params.render_count - c * CHUNK);
                head.scalp_random(n, &mut rng)
            })
            .collect();
        if roots.len() != params.render_count {
            return Err(GenerateError::InvalidParameter {
                field: "head",
                reason: format!(
                    "could only sample {} of {} scalp points",
                    roots.len(),
                    params.render_count
                ),
            });
        }
        let guide_samples: Vec<Vec<Point3<f64>>> = guides
            .par_iter()
            .map(|g| g.samples(params.guide_samples))
            .collect();
        let guide_roots: Vec<Point3<f64>> = guides.iter().map(|g| g.root.position).collect();
        let guide_combs: Vec<Vector3<f64>> = guides.iter().map(|g| combing_direction(params, &g.root.position.coords)).collect();
        let v = params.render_vertices;
        let per: Vec<(Vec<u32>, Vec<f32>, f32, Vec<[f32; 3]>, Vec<[f32; 3]>)> = roots
            .par_iter()
            .enumerate()
            .map(|(i, root)| {
                let mut rng = ChaCha8Rng::seed_from_u64(params.seed ^ 0x9e37_79b9_7f4a_7c15);
                rng.set_stream(i as u64);
                let span = 1.0 - params.length_jitter * rng.random::<f64>();
                let phase = std::f64::consts::TAU * rng.random::<f64>();
                let comb = combing_direction(params, &root.position.coords);
                let (idx, w) = nearest_guides_where(&guide_roots, &root.position, params.guides_per_render, &|g| {
                    guide_combs[g].dot(&comb) > 0.0
                });
                let axis: Vec<Point3<f64>> = (0..v)
                    .map(|j| {
                        let u = span * j as f64 / (v - 1) as f64;
                        let mut p = Vector3::zeros();
                        for (g, wg) in idx.iter().zip(&w) {
                            p += *wg as f64 * lerp_samples(&guide_samples[*g as usize], u).coords;
                        }
                        Point3::from(p)
                    })
                    .collect();
                let shift = root.position - axis[0];
                let mut path: Vec<Point3<f64>> = axis.iter().map(|a| a + shift).collect();
                if let Some(c) = &curl {
                    let frames = transported_normals(&path);
                    let guide_len = guides[idx[0] as usize].model.length;
                    let amp = c.radius.min(params.max_curl_amplitude);
                    let cc = c.pitch / std::f64::consts::TAU;
                    for (j, p) in path.iter_mut().enumerate() {
                        let z = span * guide_len * j as f64 / (v - 1) as f64; // axial arc length
                        let ramp = (z / CURL_RAMP).min(1.0);
                        let ramp = ramp * ramp * (3.0 - 2.0 * ramp);
                        let phi = phase + z / cc;
                        let (a, b) = frames[j];
                        *p += amp * ramp * (phi.cos() * a + phi.sin() * b);
                    }
                }
                keep_outside(&head, &mut path);
                let pos: Vec<[f32; 3]> = path
                    .iter()
                    .map(|p| [p.x as f32, p.y as f32, p.z as f32])
                    .collect();
                let off: Vec<[f32; 3]> = path
                    .iter()
                    .zip(&axis)
                    .map(|(p, a)| [(p.x - a.x) as f32, (p.y - a.y) as f32, (p.z - a.z) as f32])
                    .collect();
                (idx, w, span as f32, pos, off)
            })
            .collect();
        let mut render = RenderStrands {
            vertices_per_strand: v,
            guide_samples: params.guide_samples,
            guides_per_strand: params.guides_per_render,
            ..Default::default()
        };
        render.positions.reserve(v * per.len());
        render.offsets.reserve(v * per.len());
        for (idx, w, span, pos, off) in per {
            render.guide_indices.extend(idx);
            render.guide_weights.extend(w);
            render.span.push(span);
            render.positions.extend(pos);
            render.offsets.extend(off);
        }
        Ok(Self {
            head,
            params: params.clone(),
            curl,
            guides,
            render,
        })
    }

    fn build_guides(
        params: &HairstyleParams,
        hair: &HairType,
        head: &Head,
        curl: Option<&Curl>,
    ) -> Result<Vec<Guide>, GenerateError> {
        let roots = head.scalp_even(params.guide_count);
        if roots.len() != params.guide_count {
            return Err(GenerateError::InvalidParameter {
                field: "head",
                reason: format!(
                    "could only place {} of {} guide roots",
                    roots.len(),
                    params.guide_count
                ),
            });
        }
        let length = params.length / curl.map_or(1.0, |c| c.curl_index);
        roots
            .into_par_iter()
            .enumerate()
            .map(|(i, r)| build_guide(params, hair, head, length, i, r))
            .collect()
    }

    /// Guide centrelines at their current states, `params.guide_samples` points each (m).
    pub fn guide_samples(&self) -> Vec<Vec<Point3<f64>>> {
        self.guides
            .par_iter()
            .map(|g| g.samples(self.params.guide_samples))
            .collect()
    }

    /// FFD binding of every render strand vertex to `lattice` (vertices outside its embedded
    /// volume are clamped onto it). Memory: 27 x 12 bytes per vertex.
    pub fn bind(&self, lattice: &FfdLattice) -> Result<Binding, GenerateError> {
        let pts: Vec<Point3<f64>> = self
            .render
            .positions
            .iter()
            .map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        Ok(Binding::new_clamped(lattice, &pts)?)
    }

    /// Axis-aligned bounds (m) of the render strands and guides: (min, max).
    pub fn bounds(&self) -> (Point3<f64>, Point3<f64>) {
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = -lo;
        let mut add = |p: Point3<f64>| {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        };
        for p in &self.render.positions {
            add(Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        }
        for g in self.guide_samples() {
            g.into_iter().for_each(&mut add);
        }
        (lo, hi)
    }

    /// The render strands as polylines (m), for writing with [`crate::formats`].
    pub fn to_curves(&self) -> HairCurves {
        let v = self.render.vertices_per_strand;
        HairCurves::from_strands(
            self.render
                .positions
                .chunks(v)
                .map(|s| s.to_vec())
                .collect(),
        )
    }

    /// A hairstyle whose render strands are the strands of `curves` (m, head frame; each
    /// resampled by arc length to `params.render_vertices` vertices; root first), bound to guides
    /// generated with `params` (its render settings other than the vertex count are unused).
    pub fn from_curves(
        curves: &HairCurves,
        params: &HairstyleParams,
    ) -> Result<Self, GenerateError> {
        let hair = params.hair()?;
        let head = Head::new(params.head)?;
        let curl = Curl::from_curliness(params.curliness)?;
        let guides = Self::build_guides(params, &hair, &head, curl.as_ref())?;
        let guide_samples: Vec<Vec<Point3<f64>>> = guides
            .par_iter()
            .map(|g| g.samples(params.guide_samples))
            .collect();
        let guide_roots: Vec<Point3<f64>> = guides.iter().map(|g| g.root.position).collect();
        let v = params.render_vertices;
        let per: Result<Vec<_>, GenerateError> = curves
            .strands
            .par_iter()
            .enumerate()
            .map(|(i, s)| {
                let pts: Vec<Point3<f64>> = s
                    .iter()
                    .map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64))
                    .collect();
                if pts.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
                    return Err(GenerateError::BadStrand {
                        strand: i,
                        reason: "non-finite vertex".into(),
                    });
                }
                let path = resample(&pts, v).ok_or_else(|| GenerateError::BadStrand {
                    strand: i,
                    reason: format!(
                        "needs at least 2 points and a non-zero length, has {} points",
                        pts.len()
                    ),
                })?;
                let length: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
                let (idx, w) = nearest_guides(&guide_roots, &path[0], params.guides_per_render);
                let span = (length / guides[idx[0] as usize].model.length).min(1.0);
                let axis = (0..v).map(|j| {
                    let u = span * j as f64 / (v - 1) as f64;
                    let mut p = Vector3::zeros();
                    for (g, wg) in idx.iter().zip(&w) {
                        p += *wg as f64 * lerp_samples(&guide_samples[*g as usize], u).coords;
                    }
                    p
                });
                let off: Vec<[f32; 3]> = path
                    .iter()
                    .zip(axis)
                    .map(|(p, a)| [(p.x - a.x) as f32, (p.y - a.y) as f32, (p.z - a.z) as f32])
                    .collect();
                let pos: Vec<[f32; 3]> = path
                    .iter()
                    .map(|p| [p.x as f32, p.y as f32, p.z as f32])
                    .collect();
                Ok((idx, w, span as f32, pos, off))
            })
            .collect();
        let mut render = RenderStrands {
            vertices_per_strand: v,
            guide_samples: params.guide_samples,
            guides_per_strand: params.guides_per_render,
            ..Default::default()
        };
        for (idx, w, span, pos, off) in per? {
            render.guide_indices.extend(idx);
            render.guide_weights.extend(w);
            render.span.push(span);
            render.positions.extend(pos);
            render.offsets.extend(off);
        }
        let mut params = params.clone();
        params.render_count = render.len();
        Ok(Self {
            head,
            params,
            curl,
            guides,
            render,
        })
    }
}

/// `n` points evenly spaced in arc length along a polyline; None if it has fewer than 2 points
/// or zero length (`strand::samples::resample`).
fn resample(p: &[Point3<f64>], n: usize) -> Option<Vec<Point3<f64>>> {
    let coords: Vec<_> = p.iter().map(|x| x.coords).collect();
    Some(strand::samples::resample(&coords, n)?.into_iter().map(Point3::from).collect())
}
