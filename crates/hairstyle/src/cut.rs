//! Scissors: cut render polylines and guide Super-Helices where the blades close.
//!
//! The blades close over a plane patch, modelled as a disk ([`Blade`]: a point, a normal and a radius). A strand
//! is cut at its *first* crossing of the disk from the root: what stays on the head ends at the cut point, and
//! the part beyond it is returned as a [`Piece`] (a polyline with its mass) for the falling clusters
//! (`lattice::cluster`). A strand that does not cross the disk is untouched.
//!
//! Mass: a strand of linear density lambda (kg/m) and length L has mass lambda L; the kept part and the piece
//! share the cut point, which lies on the cut segment, so their lengths add up to L to rounding and the masses
//! are conserved (tested to 1e-12 relative). Render polylines are cut in f64 ([`cut_polylines`]); for
//! [`HairCurves`] (f32 in files) the cut vertex is then rounded to f32, which changes a strand's length by at
//! most about 1e-7 relative.
//!
//! Guide strands ([`cut_guide`]): the cut arc length is found on the exact Super-Helix centreline (bisection on
//! the signed distance to the blade plane). Super-Helix segments have equal lengths, so the kept strand gets
//! `ceil(s_cut / l)` segments of length `s_cut / N'` (l the old segment length), each taking the coordinates,
//! velocities and rest values of the old segment under its midpoint: it is shorter with fewer and slightly
//! shorter segments, and its shape is the old one resampled.

use crate::formats::HairCurves;
use nalgebra::{DVector, Vector3};
use strand::kinematics::{frame_at, segment_frames};
use strand::{StrandModel, StrandState};

/// The plane patch where the blades close: a disk, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blade {
    /// A point of the cutting plane, the disk's centre, m.
    pub point: [f64; 3],
    /// Normal of the cutting plane (normalized on use).
    pub normal: [f64; 3],
    /// Radius of the disk the blades sweep, m (the blades' length). Strands crossing the plane farther from
    /// `point` are not cut.
    pub radius: f64,
}

/// Why a cut could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutError {
    /// A blade or strand parameter is out of range.
    #[error("scissors: {field}: {reason}")]
    Invalid {
        /// The parameter.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
}

fn invalid(field: &'static str, reason: String) -> CutError {
    CutError::Invalid { field, reason }
}

impl Blade {
    /// Checks the blade, naming the first bad field.
    pub fn validate(&self) -> Result<(), CutError> {
        if !self.point.iter().all(|x| x.is_finite()) {
            return Err(invalid("point", format!("must be finite, got {:?}", self.point)));
        }
        let n = Vector3::from(self.normal);
        if !(n.iter().all(|x| x.is_finite()) && n.norm() > 1e-12) {
            return Err(invalid(
                "normal",
                format!("must be a finite non-zero vector, got {:?}", self.normal),
            ));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(invalid("radius", format!("must be > 0 m, got {}", self.radius)));
        }
        Ok(())
    }

    fn unit_normal(&self) -> Vector3<f64> {
        Vector3::from(self.normal).normalize()
    }

    /// Signed distance of `x` to the cutting plane, m (positive on the normal's side).
    pub fn signed_distance(&self, x: &Vector3<f64>) -> f64 {
        self.unit_normal().dot(&(x - Vector3::from(self.point)))
    }

    /// First crossing of the disk along a polyline from its first point: (segment index j, parameter t in
    /// [0, 1] on segment j, cut point). None if the polyline does not cross the disk.
    pub fn first_crossing(&self, points: &[[f64; 3]]) -> Option<(usize, f64, Vector3<f64>)> {
        let c = Vector3::from(self.point);
        for j in 0..points.len().saturating_sub(1) {
            let a = Vector3::from(points[j]);
            let b = Vector3::from(points[j + 1]);
            let (da, db) = (self.signed_distance(&a), self.signed_distance(&b));
            if (da > 0.0 && db > 0.0) || (da < 0.0 && db < 0.0) || (da == 0.0 && db == 0.0) {
                continue;
            }
            let t = (da / (da - db)).clamp(0.0, 1.0);
            let x = a + (b - a) * t;
            if (x - c).norm() <= self.radius {
                return Some((j, t, x));
            }
        }
        None
    }
}

/// A piece cut off a strand: a polyline (cut point first) and its mass.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Points from the cut to the old tip, m.
    pub points: Vec<[f64; 3]>,
    /// Mass, kg.
    pub mass: f64,
    /// Linear density, kg/m.
    pub linear_density: f64,
    /// Index of the strand it was cut from.
    pub source: usize,
    /// True if it came from a guide strand.
    pub guide: bool,
}

/// Length of a polyline, m.
pub fn polyline_length(points: &[[f64; 3]]) -> f64 {
    points
        .windows(2)
        .map(|w| (Vector3::from(w[1]) - Vector3::from(w[0])).norm())
        .sum()
}

/// Cuts every polyline (root first, m) that crosses the blade, in place; returns the pieces cut off, each with
/// mass `linear_density` (kg/m) times its length.
pub fn cut_polylines(
    strands: &mut [Vec<[f64; 3]>],
    linear_density: f64,
    blade: &Blade,
) -> Result<Vec<Piece>, CutError> {
    blade.validate()?;
    if !(linear_density.is_finite() && linear_density > 0.0) {
        return Err(invalid(
            "linear_density",
            format!("must be > 0 kg/m, got {linear_density}"),
        ));
    }
    let mut pieces = vec![];
    for (i, s) in strands.iter_mut().enumerate() {
        if s.iter().flatten().any(|x| !x.is_finite()) {
            return Err(invalid("strand points", format!("strand {i} has a non-finite point")));
        }
        if let Some((j, _, x)) = blade.first_crossing(s) {
            let cut = [x.x, x.y, x.z];
            let mut piece = vec![cut];
            piece.extend_from_slice(&s[j + 1..]);
            s.truncate(j + 1);
            s.push(cut);
            pieces.push(Piece {
                mass: linear_density * polyline_length(&piece),
                points: piece,
                linear_density,
                source: i,
                guide: false,
            });
        }
    }
    Ok(pieces)
}

/// Cuts the strands of `curves` (positions in metres, f32) like [`cut_polylines`]; per-vertex attributes get
/// the cut vertex's value by linear interpolation. Returns the pieces, in f64.
pub fn cut_curves(curves: &mut HairCurves, linear_density: f64, blade: &Blade) -> Result<Vec<Piece>, CutError> {
    let mut lines: Vec<Vec<[f64; 3]>> = curves
        .strands
        .iter()
        .map(|s| s.iter().map(|p| p.map(f64::from)).collect())
        .collect();
    // Crossings, before cutting, for the attributes.
    let crossings: Vec<_> = lines.iter().map(|s| blade.first_crossing(s)).collect();
    let lens: Vec<usize> = curves.strands.iter().map(Vec::len).collect();
    let pieces = cut_polylines(&mut lines, linear_density, blade)?;
    let mut offset = 0;
    let mut keep_attr: Vec<(usize, usize, f32)> = vec![]; // (first vertex index, vertices kept before the cut, t)
    for (i, s) in curves.strands.iter_mut().enumerate() {
        let n = s.len();
        if let Some((j, t, _)) = crossings[i] {
            *s = lines[i].iter().map(|p| p.map(|x| x as f32)).collect();
            keep_attr.push((offset, j, t as f32));
        } else {
            keep_attr.push((offset, usize::MAX, 0.0));
        }
        offset += n;
    }
    fn rebuild<T: Copy>(
        v: &[T],
        plan: &[(usize, usize, f32)],
        lens: &[usize],
        lerp: impl Fn(T, T, f32) -> T,
    ) -> Vec<T> {
        let mut out = vec![];
        for (k, &(start, j, t)) in plan.iter().enumerate() {
            if j == usize::MAX {
                out.extend_from_slice(&v[start..start + lens[k]]);
            } else {
                out.extend_from_slice(&v[start..=start + j]);
                out.push(lerp(v[start + j], v[start + j + 1], t));
            }
        }
        out
    }
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    if let Some(v) = &curves.thickness {
        curves.thickness = Some(rebuild(v, &keep_attr, &lens, lerp));
    }
    if let Some(v) = &curves.transparency {
        curves.transparency = Some(rebuild(v, &keep_attr, &lens, lerp));
    }
    if let Some(v) = &curves.color {
        curves.color = Some(rebuild(v, &keep_attr, &lens, |a: [f32; 3], b: [f32; 3], t| {
            [0, 1, 2].map(|k| lerp(a[k], b[k], t))
        }));
    }
    Ok(pieces)
}

/// Cuts a simulated strand ([`cut_guide`] on its model and state) and rebuilds it: the strand that stays on
/// the head keeps its root, time, integrator and safety-net count. None if the blade misses it. The one guide
/// cut of the project (the live session's scissors on its local strands, `engine::haptic`).
pub fn cut_strand(
    s: &strand::Strand,
    blade: &Blade,
    samples_per_segment: usize,
    source: usize,
) -> Result<Option<(strand::Strand, Piece)>, CutError> {
    let Some((m, st, piece)) = cut_guide(&s.model, &s.state, blade, samples_per_segment, source)? else {
        return Ok(None);
    };
    let mut kept = strand::Strand::new(m, st.root.clone()).map_err(|e| invalid("strand", e.to_string()))?;
    kept.state = st;
    kept.integrator = s.integrator;
    kept.clamped_steps = s.clamped_steps;
    Ok(Some((kept, piece)))
}

/// Position of a strand's centreline at arc length `s`, m.
fn position_at(model: &StrandModel, q: &DVector<f64>, frames: &[strand::kinematics::Frame], s: f64) -> Vector3<f64> {
    frame_at(model, q, frames, s).position
}

/// Cuts a guide strand (a Super-Helix `model` in `state`) at its first crossing of the blade. Returns None if it
/// does not cross, else the model and state of the shorter strand that stays on the head (same root and time,
/// coordinates and velocities resampled) and the piece cut off (sampled at `samples_per_segment` points per
/// old segment, at least 1; `source` is recorded in it).
pub fn cut_guide(
    model: &StrandModel,
    state: &StrandState,
    blade: &Blade,
    samples_per_segment: usize,
    source: usize,
) -> Result<Option<(StrandModel, StrandState, Piece)>, CutError> {
    blade.validate()?;
    let frames = segment_frames(model, state);
    let m = model.segments * samples_per_segment.max(1);
    let ds = model.length / m as f64;
    let samples: Vec<[f64; 3]> = (0..=m)
        .map(|k| position_at(model, &state.q, &frames, k as f64 * ds).into())
        .collect();
    let Some((j, t, _)) = blade.first_crossing(&samples) else {
        return Ok(None);
    };
    // Refine the arc length by bisection on the signed distance, between samples j and j + 1.
    let f = |s: f64| blade.signed_distance(&position_at(model, &state.q, &frames, s));
    let (mut lo, mut hi) = (j as f64 * ds, (j + 1) as f64 * ds);
    let mut s_cut = lo + t * ds;
    let flo = f(lo);
    if flo != 0.0 && flo * f(hi) < 0.0 {
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid) * flo > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        s_cut = 0.5 * (lo + hi);
    } else if flo == 0.0 {
        s_cut = lo;
    }
    let l = model.segment_length();
    let s_cut = s_cut.clamp(0.0, model.length);
    // Piece: the exact cut point, then the samples beyond it.
    let x_cut = position_at(model, &state.q, &frames, s_cut);
    let mut points = vec![[x_cut.x, x_cut.y, x_cut.z]];
    let first_after = ((s_cut / ds).floor() as usize + 1).min(m + 1);
    points.extend_from_slice(&samples[first_after..]);
    let lambda = model.linear_density();
    let piece = Piece {
        points,
        mass: lambda * (model.length - s_cut),
        linear_density: lambda,
        source,
        guide: true,
    };
    // Kept strand: at least a tiny length (a strand cut at the root keeps a stub of 1e-6 of its length).
    let kept_len = s_cut.max(1e-6 * model.length);
    let n_new = ((kept_len / l).ceil() as usize).clamp(1, model.segments);
    let d = model.dofs_per_segment();
    let mut new_model = model.clone();
    new_model.length = kept_len;
    new_model.segments = n_new;
    let old_index = |k: usize| (((k as f64 + 0.5) * kept_len / n_new as f64 / l) as usize).min(model.segments - 1);
    new_model.rest = (0..n_new).map(|k| model.rest[old_index(k)]).collect();
    new_model.validate().map_err(|e| invalid("guide", e.to_string()))?;
    let mut kept = StrandState::at_rest(&new_model, state.root.clone());
    for k in 0..n_new {
        let o = old_index(k);
        for c in 0..d {
            kept.q[k * d + c] = state.q[o * d + c];
            kept.qdot[k * d + c] = state.qdot[o * d + c];
        }
    }
    kept.time = state.time;
    Ok(Some((new_model, kept, piece)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use strand::{HairType, ModelKind, RootFrame, Strand};

    /// Wavy polylines hanging down from z = 0.
    fn strands(n: usize) -> Vec<Vec<[f64; 3]>> {
        (0..n)
            .map(|i| {
                let x0 = 0.003 * i as f64;
                (0..40)
                    .map(|k| {
                        [
                            x0 + 0.002 * (k as f64 * 0.7 + i as f64).sin(),
                            0.001 * (k as f64 * 0.3).cos(),
                            -0.005 * k as f64 - 0.0001 * i as f64,
                        ]
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn cutting_polylines_conserves_mass_and_shortens() {
        let lambda = 8.5e-9;
        let mut s = strands(30);
        let before: Vec<f64> = s.iter().map(|p| polyline_length(p)).collect();
        let total = lambda * before.iter().sum::<f64>();
        // A slanted blade about 12 cm down, 5 cm wide: cuts the first strands only.
        let blade = Blade {
            point: [0.0, 0.0, -0.12],
            normal: [0.1, 0.0, 1.0],
            radius: 0.05,
        };
        let pieces = cut_polylines(&mut s, lambda, &blade).unwrap();
        assert!(!pieces.is_empty() && pieces.len() < 30, "{} pieces", pieces.len());
        let after =
            lambda * s.iter().map(|p| polyline_length(p)).sum::<f64>() + pieces.iter().map(|p| p.mass).sum::<f64>();
        assert!(((after - total) / total).abs() < 1e-12, "mass {after} vs {total}");
        for p in &pieces {
            let kept = &s[p.source];
            assert!(polyline_length(kept) < before[p.source]);
            assert_eq!(kept.last().unwrap(), &p.points[0], "they share the cut point");
            assert!(blade.signed_distance(&Vector3::from(p.points[0])).abs() < 1e-15);
            for q in kept {
                assert!(
                    blade.signed_distance(&Vector3::from(*q)) >= -1e-15,
                    "what stays is above the blade"
                );
            }
        }
        for (i, p) in s.iter().enumerate() {
            if !pieces.iter().any(|c| c.source == i) {
                assert_eq!(polyline_length(p), before[i], "strand {i} untouched");
            }
        }
    }

    #[test]
    fn curves_keep_their_attributes() {
        let mut c = HairCurves::from_strands(vec![
            vec![[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, -2.0]],
            vec![[5.0, 0.0, 0.0], [5.0, 0.0, -1.0]],
        ]);
        c.thickness = Some(vec![1.0, 2.0, 3.0, 7.0, 8.0]);
        let blade = Blade {
            point: [0.0, 0.0, -1.5],
            normal: [0.0, 0.0, 1.0],
            radius: 1.0,
        };
        let pieces = cut_curves(&mut c, 1.0, &blade).unwrap();
        assert_eq!(pieces.len(), 1);
        assert_eq!(c.strands[0], vec![[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, -1.5]]);
        assert_eq!(c.thickness.as_ref().unwrap(), &vec![1.0, 2.0, 2.5, 7.0, 8.0]);
        c.check_attributes("test").unwrap();
        assert!((pieces[0].mass - 0.5).abs() < 1e-15);
    }

    #[test]
    fn cutting_a_guide_conserves_mass_and_keeps_the_shape() {
        let h = HairType::CAUCASIAN;
        let (tw, bd) = h.rest_curvature();
        let model = StrandModel::new(ModelKind::Reduced, 0.2, 16, h.section().unwrap(), h.material().unwrap())
            .unwrap()
            .with_uniform_rest(tw, bd, 0.0);
        let root = RootFrame::new(Vector3::zeros(), -Vector3::z(), Vector3::x()).unwrap();
        let guide = Strand::new(model, root).unwrap();
        let tip_z = strand::statics::tip(&guide.model, &guide.state, &guide.state.q).z;
        let z_cut = 0.5 * tip_z;
        let blade = Blade {
            point: [0.0, 0.0, z_cut],
            normal: [0.0, 0.0, 1.0],
            radius: 0.5,
        };
        let (km, ks, piece) = cut_guide(&guide.model, &guide.state, &blade, 8, 3).unwrap().unwrap();
        let kept = Strand::new(km, ks.root.clone())
            .map(|mut s| {
                s.state = ks;
                s
            })
            .unwrap();
        let m0 = guide.model.mass();
        assert!(((kept.model.mass() + piece.mass - m0) / m0).abs() < 1e-12);
        assert!(kept.model.length < guide.model.length && kept.model.segments < 16);
        assert!(
            (piece.points[0][2] - z_cut).abs() < 1e-12,
            "the piece starts on the blade"
        );
        // The kept strand's shape is the old one resampled: its tip is near the cut (within a few % of the
        // piece's first point distance), far from the old tip.
        let tip = strand::statics::tip(&kept.model, &kept.state, &kept.state.q);
        assert!(
            (tip - Vector3::from(piece.points[0])).norm() < 0.1 * kept.model.length,
            "{tip:?}"
        );
        assert!(cut_guide(
            &guide.model,
            &guide.state,
            &Blade {
                point: [0.0, 0.0, 1.0],
                ..blade
            },
            8,
            0
        )
        .unwrap()
        .is_none());
        assert!(cut_guide(
            &guide.model,
            &guide.state,
            &Blade {
                radius: f64::NAN,
                ..blade
            },
            8,
            0
        )
        .unwrap_err()
        .to_string()
        .contains("radius"));
    }
}
