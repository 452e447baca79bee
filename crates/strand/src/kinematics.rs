//! Closed-form kinematics of a strand: frames, centreline positions and the Jacobian dr/dq at any arc length.
//!
//! Segment Q maps its start frame `(R_Q, x_Q)` to the next by the helix transform of [`crate::helix`]:
//! `R_Q+1 = R_Q E_Q(l)`, `x_Q+1 = x_Q + R_Q p_Q(l)`. A change of the coordinates of segment Q moves every
//! point beyond it rigidly, by the spatial twist `S_Q` (the "motion subspace"), and moves the points inside it
//! by the segment's own derivative. Spatial twists are `(omega, v)` with `v` the velocity of the point at the
//! origin; throughout this crate that origin is the root position.

use crate::helix::{segment_derivatives, segment_transform};
use crate::model::StrandModel;
use crate::state::StrandState;
use nalgebra::{DVector, Matrix3, Matrix3xX, SMatrix, Vector3};

/// A spatial twist basis: up to 3 columns `(omega; v)`, one per coordinate of a segment.
pub type Twists = SMatrix<f64, 6, 3>;

/// Material frame (columns `n0, n1, n2`) and centreline point, position in m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Rotation whose columns are the tangent `n0`, the major axis `n1` and the minor axis `n2`.
    pub rotation: Matrix3<f64>,
    /// Centreline position, m (world coordinates).
    pub position: Vector3<f64>,
}

/// Darboux vector `(twist, bend, bend2)` of segment `i` from the coordinate vector, rad/m.
pub fn darboux(model: &StrandModel, q: &DVector<f64>, i: usize) -> Vector3<f64> {
    let d = model.dofs_per_segment();
    let mut w = Vector3::zeros();
    for k in 0..d {
        w[k] = q[i * d + k];
    }
    w
}

/// Frames at the start of every segment and at the tip (N + 1 frames), world coordinates.
pub fn segment_frames(model: &StrandModel, state: &StrandState) -> Vec<Frame> {
    let l = model.segment_length();
    let mut frames = Vec::with_capacity(model.segments + 1);
    let mut f = Frame { rotation: state.root.rotation, position: state.root.position };
    frames.push(f);
    for i in 0..model.segments {
        let (e, p) = segment_transform(&darboux(model, &state.q, i), l);
        f = Frame { rotation: f.rotation * e, position: f.position + f.rotation * p };
        frames.push(f);
    }
    frames
}

/// Segment index and arc length inside it (m) of the arc length `s` from the root, clamped to [0, L].
pub fn locate(model: &StrandModel, s: f64) -> (usize, f64) {
    let l = model.segment_length();
    let s = s.clamp(0.0, model.length);
    let i = ((s / l) as usize).min(model.segments - 1);
    (i, s - i as f64 * l)
}

/// Frame at arc length `s` (m) given the segment start frames from [`segment_frames`].
pub fn frame_at(model: &StrandModel, q: &DVector<f64>, frames: &[Frame], s: f64) -> Frame {
    let (i, sigma) = locate(model, s);
    let (e, p) = segment_transform(&darboux(model, q, i), sigma);
    let f = frames[i];
    Frame { rotation: f.rotation * e, position: f.position + f.rotation * p }
}

/// `samples` centreline points evenly spaced from root to tip, as `(s, position)`; at least 2 samples.
pub fn centerline(model: &StrandModel, state: &StrandState, samples: usize) -> Vec<(f64, Vector3<f64>)> {
    centerline_from(model, &state.q, &segment_frames(model, state), samples)
}

/// [`centerline`] from the strand's segment frames `frames` ([`segment_frames`] of the state whose coordinates are
/// `q`), for a caller that needs the frames too.
pub fn centerline_from(model: &StrandModel, q: &DVector<f64>, frames: &[Frame], samples: usize) -> Vec<(f64, Vector3<f64>)> {
    let n = samples.max(2);
    (0..n)
        .map(|j| {
            let s = model.length * j as f64 / (n - 1) as f64;
            (s, frame_at(model, q, frames, s).position)
        })
        .collect()
}

/// Spatial twists (about `origin`) given to the material at arc length `sigma` of segment `i` by unit rates
/// of that segment's own coordinates; also returns the point's frame. `start` is the segment's start frame.
pub fn own_twists(start: &Frame, omega: &Vector3<f64>, sigma: f64, origin: &Vector3<f64>) -> (Twists, Frame) {
    let (e, p) = segment_transform(omega, sigma);
    let (ang, lin) = segment_derivatives(omega, sigma);
    let frame = Frame { rotation: start.rotation * e, position: start.position + start.rotation * p };
    let x = frame.position - origin;
    let mut t = Twists::zeros();
    for k in 0..3 {
        let w = start.rotation * ang.column(k);
        let v = start.rotation * lin.column(k) - w.cross(&x);
        t.fixed_view_mut::<3, 1>(0, k).copy_from(&w);
        t.fixed_view_mut::<3, 1>(3, k).copy_from(&v);
    }
    (t, frame)
}

/// Velocity of the point `x` (relative to the twist's origin) under the spatial twist `t`: `v + omega x x`.
pub fn point_velocity(t: &nalgebra::SVector<f64, 6>, x: &Vector3<f64>) -> Vector3<f64> {
    let w = Vector3::new(t[0], t[1], t[2]);
    Vector3::new(t[3], t[4], t[5]) + w.cross(x)
}

/// Jacobian `dr(s)/dq` of the centreline point at arc length `s` (3 x 2N or 3 x 3N), m per (rad/m).
pub fn jacobian(model: &StrandModel, state: &StrandState, s: f64) -> Matrix3xX<f64> {
    jacobian_with_frames(model, state, &segment_frames(model, state), s)
}

/// [`jacobian`] with the segment frames of `state` already computed by [`segment_frames`] (several points of
/// one state share them).
pub fn jacobian_with_frames(model: &StrandModel, state: &StrandState, frames: &[Frame], s: f64) -> Matrix3xX<f64> {
    let d = model.dofs_per_segment();
    let l = model.segment_length();
    let origin = state.root.position;
    let (i, sigma) = locate(model, s);
    let (own, f) = own_twists(&frames[i], &darboux(model, &state.q, i), sigma, &origin);
    let x = f.position - origin;
    let mut jac = Matrix3xX::zeros(model.dofs());
    for j in 0..i {
        let (sj, _) = own_twists(&frames[j], &darboux(model, &state.q, j), l, &origin);
        for k in 0..d {
            jac.set_column(j * d + k, &point_velocity(&sj.column(k).into_owned(), &x));
        }
    }
    for k in 0..d {
        jac.set_column(i * d + k, &point_velocity(&own.column(k).into_owned(), &x));
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::model::ModelKind;
    use crate::section::CrossSection;
    use crate::state::RootFrame;

    fn curly(kind: ModelKind) -> (StrandModel, StrandState) {
        let m = StrandModel::new(kind, 0.12, 6, CrossSection::new(45e-6, 33e-6).unwrap(), Material::default()).unwrap();
        let root = RootFrame::new(Vector3::new(0.01, -0.02, 0.3), Vector3::new(0.2, 0.1, -1.0), Vector3::y()).unwrap();
        let mut st = StrandState::at_rest(&m, root);
        for (i, q) in st.q.iter_mut().enumerate() {
            *q = 20.0 * ((i as f64) * 1.7).sin() + 5.0;
        }
        (m, st)
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        // Central differences with step 1e-6 rad/m: truncation ~1e-12 m, so agreement to 1e-9 m per unit q.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            for s in [0.0, 0.013, 0.05, 0.08, 0.12] {
                let jac = jacobian(&m, &st, s);
                for j in 0..m.dofs() {
                    let h = 1e-6;
                    let mut a = st.clone();
                    let mut b = st.clone();
                    a.q[j] += h;
                    b.q[j] -= h;
                    let fa = frame_at(&m, &a.q, &segment_frames(&m, &a), s).position;
                    let fb = frame_at(&m, &b.q, &segment_frames(&m, &b), s).position;
                    let fd = (fa - fb) / (2.0 * h);
                    assert!((jac.column(j) - fd).norm() < 1e-9, "{kind:?} s={s} j={j}: {} vs {}", jac.column(j), fd);
                }
            }
        }
    }

    #[test]
    fn frames_stay_orthonormal_and_arc_length_is_kept() {
        // Inextensible: the polyline through 2001 samples has length L to 1e-6 relative (chord error).
        let (m, st) = curly(ModelKind::Full);
        for f in segment_frames(&m, &st) {
            assert!((f.rotation.transpose() * f.rotation - Matrix3::identity()).norm() < 1e-12);
        }
        let pts = centerline(&m, &st, 2001);
        let len: f64 = pts.windows(2).map(|w| (w[1].1 - w[0].1).norm()).sum();
        assert!((len - m.length).abs() < 1e-6 * m.length, "length {len}");
    }
}
