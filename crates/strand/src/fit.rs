//! A Super-Helix reproducing a drawn curve: the root frame and the per-segment Darboux coordinates whose
//! centreline is nearest a polyline, by least squares on the strand model's own kinematics.
//!
//! The unknowns are the coordinates `q` (twist and bend per segment: 2N for the reduced model, 3N for the
//! full one) and the root's orientation (a rotation increment `w` applied to the root frame; the root
//! position is the polyline's first point). The residuals are the centreline points at `S` arc lengths
//! evenly spaced along the strand minus the polyline's points at the same fractions of its length
//! ([`crate::samples::resample`]); the model's length is the polyline's. Stages:
//! 1. Root frame: tangent along the polyline's first samples, major axis normal to its first bend.
//! 2. Growth (continuation over the length): eighth by eighth of the segments, the coordinates of the segments so far
//!    are fitted (Levenberg-Marquardt, Jacobians as [`crate::kinematics::jacobian_with_frames`]'s) to the
//!    samples they cover, the new segments starting with their predecessor's coordinates. A curl is caught
//!    turn by turn instead of from a straight start.
//! 3. Refinement: while the largest distance exceeds [`FitOptions::tolerance`] and the segments are fewer
//!    than [`FitOptions::max_segments`], every segment is split in two (the same curve) and all
//!    coordinates fitted again.

use crate::error::{Result, StrandError};
use crate::kinematics::{centerline, darboux, locate, own_twists, point_velocity, segment_frames};
use crate::model::StrandModel;
use crate::state::{RootFrame, StrandState};
use nalgebra::{DMatrix, DVector, Rotation3, Vector3};

/// Options of [`fit_polyline`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Samples compared per segment (at least 16 in all). Default 4.
    pub samples_per_segment: usize,
    /// Largest distance (m) between the fitted centreline and the polyline at the samples below which the
    /// segments are not refined. Default 1e-3 m.
    pub tolerance: f64,
    /// Most segments refinement may reach (the model's own count is the least). Default 32.
    pub max_segments: usize,
    /// Levenberg-Marquardt iterations per fit. Default 40.
    pub max_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { samples_per_segment: 4, tolerance: 1e-3, max_segments: 32, max_iterations: 40 }
    }
}

/// A fitted Super-Helix and how near the polyline it is.
#[derive(Debug, Clone, PartialEq)]
pub struct PolylineFit {
    /// The model: the template's with the polyline's length and the segments refinement reached (its rest
    /// coordinates are the template's per-segment value of the first segment, unchanged: set a rest shape
    /// after, e.g. [`crate::statics::sag_free_rest`]).
    pub model: StrandModel,
    /// The fitted state (at rest, velocities zero), m and rad/m.
    pub state: StrandState,
    /// Root-mean-square distance at the compared samples, m.
    pub rms: f64,
    /// Largest distance at the compared samples, m.
    pub max: f64,
}

/// Fits a Super-Helix of `template`'s kind, section and material to the polyline `points` (m, root first;
/// see the module docs). Errors name a polyline with fewer than two points, a zero or non-finite length.
pub fn fit_polyline(template: &StrandModel, points: &[Vector3<f64>], opts: &FitOptions) -> Result<PolylineFit> {
    let bad = |reason: String| StrandError::InvalidParameter { field: "polyline", reason };
    if points.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(bad("has a non-finite point".into()));
    }
    let length: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    if points.len() < 2 || !(length > 0.0) {
        return Err(bad(format!("needs at least 2 points and a non-zero length, has {} points of length {length} m", points.len())));
    }
    let mut model = template.clone();
    model.length = length;
    model.rest = vec![template.rest.first().copied().unwrap_or_default(); model.segments];
    model.validate()?;
    let d = model.dofs_per_segment();
    // 1. Root frame.
    let fine = crate::samples::resample(points, 64).ok_or_else(|| bad("cannot be resampled".into()))?;
    let tangent = (fine[2] - fine[0]).try_normalize(1e-12).unwrap_or_else(|| (fine[63] - fine[0]).normalize());
    let bend = (2..63).map(|k| (fine[k] - fine[0]) - tangent * tangent.dot(&(fine[k] - fine[0]))).find(|v| v.norm() > 1e-6 * length);
    let major = bend.map(|b| tangent.cross(&b)).filter(|m| m.norm() > 1e-12).unwrap_or_else(|| {
        let a = if tangent.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        tangent.cross(&a)
    });
    let root = RootFrame::new(points[0], tangent, major)?;
    let mut state = StrandState::at_rest(&model, root);
    state.q.fill(0.0);
    // 2. Growth, segment by segment.
    let samples = |m: &StrandModel| (opts.samples_per_segment.max(1) * m.segments).max(16) + 1;
    let target = |n: usize| crate::samples::resample(points, n).ok_or_else(|| bad("cannot be resampled".into()));
    let s_count = samples(&model);
    let goal = target(s_count)?;
    let block = (model.segments / 8).max(1);
    for m in (block..=model.segments).step_by(block) {
        for j in m - block..m {
            for k in 0..d {
                state.q[j * d + k] = if j > 0 { state.q[(j - 1) * d + k] } else { 0.0 };
            }
        }
        let upto = model.length * m as f64 / model.segments as f64;
        let active: Vec<usize> = (1..s_count).filter(|&k| model.length * k as f64 / (s_count - 1) as f64 <= upto + 1e-12).collect();
        least_squares(&model, &mut state, &goal, &active, m * d, opts.max_iterations / 2 + 1);
    }
    let all: Vec<usize> = (1..s_count).collect();
    least_squares(&model, &mut state, &goal, &all, model.dofs(), opts.max_iterations);
    let (mut rms, mut max) = distances(&model, &state, &goal);
    // 3. Refinement.
    while max > opts.tolerance && 2 * model.segments <= opts.max_segments.max(template.segments) {
        let mut finer = model.clone();
        finer.segments *= 2;
        finer.rest = vec![model.rest[0]; finer.segments];
        let q = DVector::from_fn(finer.dofs(), |j, _| state.q[(j / d / 2) * d + j % d]);
        let mut next = StrandState::at_rest(&finer, state.root.clone());
        next.q = q;
        let goal = target(samples(&finer))?;
        let all: Vec<usize> = (1..goal.len()).collect();
        least_squares(&finer, &mut next, &goal, &all, finer.dofs(), opts.max_iterations);
        let (r, mx) = distances(&finer, &next, &goal);
        if !(r < rms) {
            break;
        }
        (model, state, rms, max) = (finer, next, r, mx);
    }
    Ok(PolylineFit { model, state, rms, max })
}

/// RMS and largest distance (m) between the centreline of `model` in `state` and the polyline `points` (m,
/// root first) at `samples` arc lengths evenly spaced along each; None as for [`crate::samples::resample`].
pub fn centreline_distance(model: &StrandModel, state: &StrandState, points: &[Vector3<f64>], samples: usize) -> Option<(f64, f64)> {
    Some(distances(model, state, &crate::samples::resample(points, samples)?))
}

/// RMS and largest distance (m) of the centreline of `state` from `goal` (evenly spaced in arc length).
fn distances(model: &StrandModel, state: &StrandState, goal: &[Vector3<f64>]) -> (f64, f64) {
    let c = centerline(model, state, goal.len());
    let d: Vec<f64> = c.iter().zip(goal).map(|((_, p), g)| (p - g).norm()).collect();
    ((d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(), d.iter().copied().fold(0.0, f64::max))
}

/// Levenberg-Marquardt on the first `free` coordinates of `state.q` and the root's orientation, over the
/// samples `active` (indices into `goal`, the targets at evenly spaced arc lengths of the whole strand).
fn least_squares(model: &StrandModel, state: &mut StrandState, goal: &[Vector3<f64>], active: &[usize], free: usize, iterations: usize) {
    if active.is_empty() {
        return;
    }
    let n = goal.len();
    let at = |k: usize| model.length * k as f64 / (n - 1) as f64;
    let residual = |st: &StrandState| -> (DVector<f64>, f64) {
        let frames = segment_frames(model, st);
        let r = DVector::from_iterator(3 * active.len(), active.iter().flat_map(|&k| {
            let p = crate::kinematics::frame_at(model, &st.q, &frames, at(k)).position;
            let e = p - goal[k];
            [e.x, e.y, e.z]
        }));
        let f = r.norm_squared();
        (r, f)
    };
    let unknowns = free + 3;
    let (mut r, mut f) = residual(state);
    let mut mu = 1e-3;
    for _ in 0..iterations {
        let frames = segment_frames(model, state);
        let origin = state.root.position;
        let l = model.segment_length();
        let d = model.dofs_per_segment();
        // Each segment's twists at its end move every point beyond it rigidly: computed once per iteration.
        let whole: Vec<_> = (0..model.segments).map(|j| own_twists(&frames[j], &darboux(model, &state.q, j), l, &origin).0).collect();
        let mut jac = DMatrix::zeros(3 * active.len(), unknowns);
        for (row, &k) in active.iter().enumerate() {
            let (i, sigma) = locate(model, at(k));
            let (own, f) = own_twists(&frames[i], &darboux(model, &state.q, i), sigma, &origin);
            let x = f.position - origin;
            for c in 0..free {
                let (j, m) = (c / d, c % d);
                let t = if j < i { whole[j].column(m).into_owned() } else if j == i { own.column(m).into_owned() } else { continue };
                jac.view_mut((3 * row, c), (3, 1)).copy_from(&point_velocity(&t, &x));
            }
            for a in 0..3 {
                let mut e = Vector3::zeros();
                e[a] = 1.0;
                jac.view_mut((3 * row, free + a), (3, 1)).copy_from(&e.cross(&x));
            }
        }
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * &r;
        let scale = (0..unknowns).map(|i| jtj[(i, i)]).fold(0.0, f64::max).max(1e-30);
        let mut improved = false;
        for _ in 0..12 {
            let mut a = jtj.clone();
            for i in 0..unknowns {
                a[(i, i)] += mu * jtj[(i, i)] + 1e-9 * scale;
            }
            let Some(ch) = a.cholesky() else {
                mu *= 10.0;
                continue;
            };
            let step = -ch.solve(&g);
            let mut trial = state.clone();
            for i in 0..free {
                trial.q[i] += step[i];
            }
            let w = Vector3::new(step[free], step[free + 1], step[free + 2]);
            trial.root.rotation = *Rotation3::new(w).matrix() * state.root.rotation;
            let (rt, ft) = residual(&trial);
            if ft.is_finite() && ft < f {
                let gain = (f - ft) / f.max(1e-300);
                *state = trial;
                (r, f) = (rt, ft);
                mu = (mu / 3.0).max(1e-9);
                improved = gain > 1e-10;
                break;
            }
            mu *= 4.0;
        }
        if !improved {
            break;
        }
    }
    // Keep the rotation orthonormal after the updates.
    let rot = Rotation3::from_matrix(&state.root.rotation);
    state.root.rotation = *rot.matrix();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hair_type::HairType;
    use crate::model::ModelKind;

    fn template(kind: ModelKind, segments: usize) -> StrandModel {
        let h = HairType::H1;
        StrandModel::new(kind, 0.1, segments, h.section().unwrap(), h.material().unwrap()).unwrap()
    }

    #[test]
    fn a_super_helix_centreline_is_recovered_exactly() {
        // Centrelines of Super-Helices with random coordinates (8 segments, lengths 5-40 cm, curvatures up to
        // 60 rad/m, random root frames), given as 64-point polylines: the fit with the same segment count
        // finds a centreline within 0.2 mm of every compared sample (the polyline's chords cut the arcs by
        // up to l^2 k / 8 per 64th of the length, ~0.1 mm at the largest curvature here).
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut worst = 0.0f64;
        for case in 0..12 {
            let mut m = template(ModelKind::Reduced, 8);
            m.length = 0.05 + 0.35 * (rnd() + 0.5);
            let root = RootFrame::new(Vector3::new(rnd(), rnd(), rnd()) * 0.1, Vector3::new(rnd(), rnd(), rnd()), Vector3::new(rnd(), rnd(), rnd())).unwrap();
            let mut st = StrandState::at_rest(&m, root);
            let amp = 60.0 * (case as f64 / 11.0);
            for j in 0..m.dofs() {
                st.q[j] = amp * rnd() * (1.0 - 0.5 * (j % 2) as f64) / (1.0 + m.length * 5.0);
            }
            let pts: Vec<Vector3<f64>> = centerline(&m, &st, 64).into_iter().map(|(_, p)| p).collect();
            let opts = FitOptions { max_segments: 8, ..FitOptions::default() };
            let fit = fit_polyline(&template(ModelKind::Reduced, 8), &pts, &opts).unwrap();
            worst = worst.max(fit.max);
            assert!(fit.max < 2e-4, "case {case}: max {} m (length {} m)", fit.max, m.length);
            assert!((fit.model.length - pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>()).abs() < 1e-12);
        }
        eprintln!("worst Super-Helix recovery {worst:e} m");
    }

    #[test]
    fn refinement_reaches_the_tolerance_on_a_curve_no_coarse_helix_draws() {
        // A circle arc whose curvature grows linearly (a clothoid, 30 cm, 0 to 80 rad/m) with a sine wobble out
        // of plane: 4 segments cannot draw it within 0.5 mm; refinement splits them until the largest
        // distance is within it, and never increases the distance.
        let n = 200;
        let mut p = vec![Vector3::zeros()];
        let (mut dir, ds) = (Vector3::new(0.0, 0.0, -1.0), 0.3 / n as f64);
        for k in 1..n {
            let s = k as f64 * ds;
            let ang = 80.0 * s / 0.3 * ds;
            dir = Rotation3::new(Vector3::new(ang, 0.0, 0.3 * (s * 40.0).cos() * ds)) * dir;
            p.push(p[k - 1] + dir * ds);
        }
        let opts = FitOptions { tolerance: 5e-4, ..FitOptions::default() };
        let coarse = fit_polyline(&template(ModelKind::Reduced, 4), &p, &FitOptions { max_segments: 4, ..opts }).unwrap();
        let fine = fit_polyline(&template(ModelKind::Reduced, 4), &p, &opts).unwrap();
        eprintln!("clothoid: 4 segments {:e} m; {} segments {:e} m", coarse.max, fine.model.segments, fine.max);
        assert!(coarse.max > 5e-4);
        assert!(fine.max <= 5e-4 && fine.model.segments > 4, "{} segments, {} m", fine.model.segments, fine.max);
        let e = fit_polyline(&template(ModelKind::Reduced, 4), &[Vector3::zeros()], &FitOptions::default()).unwrap_err().to_string();
        assert!(e.contains("at least 2 points"), "{e}");
    }
}
