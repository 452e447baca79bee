//! A loaded hairstyle's own strands as its guides (issue 34): the simulated guides are chosen among the
//! file's strands and each is the Super-Helix that reproduces its strand's shape.
//!
//! Stages ([`guides_from_curves`]):
//! 1. Candidates: strands rooted on the scalp (root within [`GuideFitParams::rooted_distance`] of it, as
//!    `fit::FitParams::inlier_distance` counts them) and at least [`GuideFitParams::min_length`] long.
//! 2. Choice: all candidates up to the budget, else a subset spread over the scalp by farthest-point
//!    sampling of their roots ([`spread_over`]), as game engines pick simulated guides among a groom's strands.
//! 3. Fit: a reduced Super-Helix of the hair type's section and material per chosen strand
//!    ([`strand::fit::fit_polyline`]: least squares on the model's own kinematics, segments refined until the
//!    largest distance is within the tolerance), its per-strand error kept ([`FittedGuide`]).
//! 4. Rest: the sag-free rest of the fitted state ([`strand::statics::sag_free_rest`]) so that it holds under
//!    gravity, and its stability flag ([`Guide::stable`], as the built-in groom's). A guide whose sag-free
//!    rest is not stable (long hair hanging in a plane far from upright twists out of it: the reduced model
//!    cannot bend about its minor axis) keeps its drawn shape, flagged unstable: the built-in groom's last
//!    resort, relaxing to another stable minimum ([`crate::generate::stabilise`]), moved such guides by
//!    centimetres from their strands, and the live session holds every local strand, generated or fitted, at
//!    its place with its weight carried by the hair around it (`HapticParams::hold_distance`). Measured (engine
//!    `scene::loaded_tests`, docs/hairstyles.md): the unstable ones of long grooms lie mostly off the body (the
//!    outer layers, on the hair beneath), so the head's contact would not carry them either. The full model (3 coordinates per segment) made none of them stable
//!    in the test family (engine `scene::loaded_tests`), at twice the cost, so it is not tried.

use crate::error::GenerateError;
use crate::fit::ScalpIndex;
use crate::formats::HairCurves;
use crate::generate::Guide;
use crate::head::{Head, ScalpPoint};
use crate::params::HairstyleParams;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use strand::fit::{fit_polyline, FitOptions};
use strand::statics::sag_free_rest;
use strand::{ModelKind, StrandModel};

/// Parameters of the guides fitted to a file's strands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuideFitParams {
    /// Most guides (the rest of the strands are drawn only, bound to these). Default 200 (the live scene's
    /// guide count, `engine::scene::SceneOptions::guides`).
    pub budget: usize,
    /// A strand is rooted on the scalp, and may be a guide, if its root is within this of the scalp, m.
    /// Default 0.01 m (`fit::FitParams::inlier_distance`).
    pub rooted_distance: f64,
    /// Shortest strand that may be a guide, m. Default 0.005 m.
    pub min_length: f64,
    /// The Super-Helix fit of each guide (tolerance, most segments).
    pub fit: FitOptions,
}

impl Default for GuideFitParams {
    fn default() -> Self {
        Self { budget: 200, rooted_distance: 0.01, min_length: 0.005, fit: FitOptions::default() }
    }
}

/// A guide fitted to a file's strand, and how near its shape it is.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedGuide {
    /// The guide (its state the fitted shape; its model's rest the sag-free rest of that state).
    pub guide: Guide,
    /// Index of its strand in the file.
    pub strand: usize,
    /// Root-mean-square distance of its centreline from the strand's at evenly spaced arc lengths, m.
    pub rms: f64,
    /// Largest such distance, m.
    pub max: f64,
}

/// `budget` of the points `roots[eligible]` spread by farthest-point sampling (first the one nearest their
/// centroid, then each time the one farthest from those chosen); all of them, in order, if they are no more
/// than `budget`. Indices into `roots`; deterministic.
pub fn spread_over(roots: &[Point3<f64>], eligible: &[usize], budget: usize) -> Vec<usize> {
    if eligible.len() <= budget {
        return eligible.to_vec();
    }
    if budget == 0 {
        return Vec::new();
    }
    let centroid = eligible.iter().fold(Vector3::zeros(), |s, &i| s + roots[i].coords) / eligible.len() as f64;
    let first = *eligible.iter().min_by(|&&a, &&b| (roots[a].coords - centroid).norm_squared().total_cmp(&(roots[b].coords - centroid).norm_squared())).unwrap();
    let mut chosen = vec![first];
    let mut near: Vec<f64> = eligible.iter().map(|&i| (roots[i] - roots[first]).norm_squared()).collect();
    while chosen.len() < budget {
        let (k, _) = near.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
        let pick = eligible[k];
        chosen.push(pick);
        near.par_iter_mut().zip(eligible.par_iter()).for_each(|(d, &i)| *d = d.min((roots[i] - roots[pick]).norm_squared()));
    }
    chosen
}

/// The file strands that may be guides (stage 1 of the module docs), with their scalp normals.
pub fn candidates(curves: &HairCurves, scalp: &ScalpIndex, p: &GuideFitParams) -> Vec<(usize, Vector3<f64>)> {
    curves
        .strands
        .par_iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let root = Point3::new(s.first()?[0] as f64, s[0][1] as f64, s[0][2] as f64);
            let length: f64 = s.windows(2).map(|w| (0..3).map(|a| ((w[1][a] - w[0][a]) as f64).powi(2)).sum::<f64>().sqrt()).sum();
            let near = scalp.nearest(&root);
            (length >= p.min_length && near.distance <= p.rooted_distance && root.iter().all(|x| x.is_finite())).then_some((i, near.sample.normal))
        })
        .collect()
}

/// Guides fitted to the strands of `curves` (m, head frame, root first) on `head`, of the hair type of
/// `params` (`guide_segments` the least segments; see the module docs). Empty if no strand is rooted on the
/// scalp. Errors name the guide whose model cannot be built.
pub fn guides_from_curves(curves: &HairCurves, params: &HairstyleParams, head: &Head, p: &GuideFitParams) -> Result<Vec<FittedGuide>, GenerateError> {
    let hair = params.hair()?;
    let scalp = ScalpIndex::new(head, crate::fit::FitParams::default().scalp_samples);
    let can = candidates(curves, &scalp, p);
    let roots: Vec<Point3<f64>> = curves.strands.iter().map(|s| s.first().map_or(Point3::origin(), |r| Point3::new(r[0] as f64, r[1] as f64, r[2] as f64))).collect();
    let eligible: Vec<usize> = can.iter().map(|c| c.0).collect();
    let chosen = spread_over(&roots, &eligible, p.budget);
    let normal = |i: usize| can[eligible.binary_search(&i).expect("chosen among the candidates")].1;
    chosen
        .par_iter()
        .enumerate()
        .map(|(g, &i)| {
            let err = |source| GenerateError::Strand { guide: g, source };
            let points: Vec<Vector3<f64>> = curves.strands[i].iter().map(|q| Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64)).collect();
            let template = StrandModel::new(ModelKind::Reduced, 0.1, params.guide_segments.max(1), hair.section().map_err(err)?, hair.material().map_err(err)?).map_err(err)?;
            let fit = fit_polyline(&template, &points, &p.fit).map_err(|e| GenerateError::BadStrand { strand: i, reason: e.to_string() })?;
            let (model, stable) = sag_free_rest(&fit.model, &fit.state, &[]).map_err(err)?;
            let (state, rms, max) = (fit.state, fit.rms, fit.max);
            let root = ScalpPoint { position: roots[i], normal: normal(i) };
            Ok(FittedGuide { guide: Guide { model, state, root, stable }, strand: i, rms, max })
        })
        .collect()
}
