//! The groomed shape of a guide, chosen so that it is a **stable** equilibrium of its sag-free model.
//!
//! ## Why stability needs care
//! A strand of hair cannot hold itself up. Groomed in a plane that is not upright (e.g. combed back
//! along the side of the head, hanging at 37 degrees from the vertical), a guide is an equilibrium only
//! thanks to its sag-free rest shape, and an **unstable** one: the Hessian `K - dQ_gravity/dq` of the
//! potential has a negative eigenvalue (the hanging part swings towards the vertical, twisting the
//! strand first: the reduced Super-Helix bends about one material axis only). The rest shape does not
//! enter that Hessian (the elastic energy is quadratic with a constant diagonal K), so no choice of
//! rest shape can fix it: only the groomed **shape** can: planar grooms in the combing plane are stable
//! when their hanging part is near the vertical, and mostly not when it leans (figures: docs/global.md,
//! "Hairstyle generation").
//!
//! ## The grooms tried, in order (the first stable one is kept, [`crate::generate`])
//! 1. **Planar** ([`groomed_bends`]) in the plane `(n, f)` of the root normal `n` and the combing
//!    direction `f` (the projection of [`combing_direction`] onto the scalp): it leaves
//!    the scalp along `n`, turns towards `f` at the curvature `(pi/2) / lift` for up to 90 degrees,
//!    wraps round the head at the lifted radius `rho = |root| + lift / (pi/2) + clearance` until its
//!    tangent is the steepest descent in that plane less the outward lean `tilt`, then goes straight.
//! 2. **Turned** ([`groomed_turned`]): the same lift and wrap (the wrap cut after `w` segments, `w` from
//!    all down to 1), then one straight segment twisting about its tangent so that the next ones bend
//!    **out of the plane to hang straight down**, leaning outwards by `tilt`, over an arc of
//!    [`HANG_TURN_RADIUS`]. Keeps the combing direction at the root (the sides still leave combed
//!    back, the fringe still crosses the forehead sideways) and hangs vertically.
//! 3. **Planar in a plane turned towards the vertical** ([`groom_directions`], [`PLANE_TILTS`]): `f`
//!    turned about `n` by the smallest angle that brings the plane within a tilt of the vertical.
//!
//! Each is tried with the smallest outward lean `tilt` (from [`HairstyleParams::hang_tilt`], in 5 degree
//! steps) that keeps the guide outside the body ([`groomed_state`]).
use crate::params::HairstyleParams;
use crate::head::{Head, ScalpPoint};
use nalgebra::Vector3;
use strand::{RootFrame, StrandError, StrandModel, StrandState};

/// Range of the forward component of a root's unit direction from the head centre over which
/// grooming turns from [`HairstyleParams::flow`] (below the first value: the back and the sides) to
/// [`HairstyleParams::fringe_flow`] (above the second: the forehead), smoothstep in between.
pub const FLOW_FRONT_BLEND: (f64, f64) = (0.5, 0.85);
/// The direction (not unit; of the order of |p| where it matters) a guide rooted at `p` (m, head
/// frame) is combed along, before projection onto the scalp: away from [`HairstyleParams::flow`] on
/// the back and the sides, [`HairstyleParams::fringe_flow`] (mirrored on the left) at the front.
pub fn combing_direction(params: &HairstyleParams, p: &Vector3<f64>) -> Vector3<f64> {
    let r = p.norm();
    let away = p - params.flow.normalize() * r;
    let (a, b) = FLOW_FRONT_BLEND;
    let t = ((p.y / r.max(1e-12) - a) / (b - a)).clamp(0.0, 1.0);
    let w = t * t * (3.0 - 2.0 * t);
    let Some(fringe) = params.fringe_flow.filter(|_| w > 0.0) else {
        return away;
    };
    let mut side = fringe.normalize();
    if p.x < 0.0 {
        side.x = -side.x;
    }
    let back = away.try_normalize(1e-9).unwrap_or(side);
    (back + w * (side - back)) * r
}

/// Largest tilts of the grooming plane from the vertical tried in turn (groom 3 of the module docs),
/// radians (`INFINITY`: the combing direction as it is); 0 (an upright plane, hair combed straight
/// down) is the last resort.
pub const PLANE_TILTS: [f64; 7] = [
    f64::INFINITY,
    0.5236, // 30 deg
    0.3491, // 20 deg
    0.2618, // 15 deg
    0.1745, // 10 deg
    0.0873, // 5 deg
    0.0,
];

/// The unit directions `f` along the scalp a guide at `root` may be groomed towards within
/// `max_plane_tilt` (rad) of the vertical: the combing direction turned about the normal by the smallest
/// angle (1 degree steps) that brings the plane `(n, f)` within that tilt, one each way round, the one
/// leaning back (smaller forward component y: away from the face) first. Just the combing direction if
/// its plane is already within the tilt.
pub fn groom_directions(params: &HairstyleParams, root: &ScalpPoint, max_plane_tilt: f64) -> Vec<Vector3<f64>> {
    let n = root.normal;
    let proj = |v: Vector3<f64>| v - n * n.dot(&v);
    let p = root.position.coords;
    let f = proj(combing_direction(params, &p))
        .try_normalize(1e-6 * p.norm())
        .or_else(|| proj(-Vector3::y()).try_normalize(1e-6))
        .unwrap_or_else(|| proj(Vector3::x()).normalize());
    let m = n.cross(&f);
    let limit = max_plane_tilt.min(std::f64::consts::FRAC_PI_2).sin() + 1e-12;
    // f turned by a about n: cos a f + sin a m; its plane's normal: cos a m - sin a f
    let within = |a: f64| (a.cos() * m - a.sin() * f).z.abs() <= limit;
    if within(0.0) {
        return vec![f];
    }
    let mut out: Vec<Vector3<f64>> = [1.0, -1.0]
        .into_iter()
        .filter_map(|sign: f64| {
            (1..=180).map(|deg| sign * (deg as f64).to_radians()).find(|&a| within(a)).map(|a| a.cos() * f + a.sin() * m)
        })
        .collect();
    out.sort_by(|a, b| a.y.total_cmp(&b.y));
    out
}

/// Groomed bends (rad/m) of each of `segments` segments of a guide of `length` (m) rooted at `root`,
/// groomed towards `f` (unit, along the scalp), whose hanging part leans outwards by `tilt` (rad);
/// and the root's major axis `m = n x f`.
pub fn groomed_bends(
    params: &HairstyleParams,
    root: &ScalpPoint,
    f: &Vector3<f64>,
    length: f64,
    segments: usize,
    tilt: f64,
) -> (Vector3<f64>, Vec<f64>) {
    let n = root.normal;
    let m = n.cross(f);
    // steepest descent in the plane (n, f)
    let down = -Vector3::z();
    let ds = down - m * m.dot(&down);
    // turning angle from the normal to the steepest descent, going round from the normal towards f
    let psi_end = if ds.norm() > 1e-6 {
        ds.dot(f).atan2(ds.dot(&n)).rem_euclid(std::f64::consts::TAU)
    } else {
        std::f64::consts::FRAC_PI_2
    };
    // hang slightly outwards (tilt) rather than straight down along the body
    let psi_end = (psi_end - tilt).max(0.0);
    let half_pi = std::f64::consts::FRAC_PI_2;
    let k1 = half_pi / params.lift;
    let r1 = params.lift / half_pi;
    let a1 = psi_end.min(half_pi) / k1;
    let rho = root.position.coords.norm() + r1 + params.clearance;
    let a2 = (psi_end - half_pi).max(0.0) * rho;
    // integral of the curvature from 0 to s
    let turned = |s: f64| -> f64 {
        if s <= a1 {
            k1 * s
        } else if s <= a1 + a2 {
            k1 * a1 + (s - a1) / rho
        } else {
            k1 * a1 + a2 / rho
        }
    };
    let l = length / segments as f64;
    let bends = (0..segments).map(|i| (turned((i + 1) as f64 * l) - turned(i as f64 * l)) / l).collect();
    (m, bends)
}

/// The groomed state of a guide of `model` (its length and segments) rooted at `root`, groomed towards
/// `f`: the smallest outward tilt of the hanging part ([`HairstyleParams::hang_tilt`] plus 5 degree
/// steps, up to 50 degrees more) that keeps the guide outside the body (sampled at 64 points,
/// first-order distance >= clearance / 2); the last try if none does.
pub fn groomed_state(
    params: &HairstyleParams,
    head: &Head,
    model: &StrandModel,
    root: &ScalpPoint,
    f: &Vector3<f64>,
    turned: Option<usize>,
) -> Result<StrandState, StrandError> {
    let mut state = None;
    for step in 0..=10 {
        let tilt = params.hang_tilt + step as f64 * 5f64.to_radians();
        let (major, coords) = if let Some(wrap) = turned {
            groomed_turned(params, root, f, model, tilt, wrap)?
        } else {
            let (m, b) = groomed_bends(params, root, f, model.length, model.segments, tilt);
            (m, b.into_iter().map(|b| (0.0, b)).collect())
        };
        let frame = RootFrame::new(root.position.coords, root.normal, major)?;
        let mut s = StrandState::at_rest(model, frame);
        s.q.fill(0.0);
        for (i, (t, b)) in coords.iter().enumerate() {
            s.q[2 * i] = *t;
            s.q[2 * i + 1] = *b;
        }
        let clear = head.clears(model, &s, 0.5 * params.clearance);
        state = Some(s);
        if clear {
            break;
        }
    }
    Ok(state.expect("at least one try"))
}

/// Radius of the turn of a [`groomed_turned`] guide from its grooming plane to the hang direction, m.
pub const HANG_TURN_RADIUS: f64 = 0.03;

/// Groomed coordinates `(twist, bend)` (rad/m) per segment of a guide groomed in the plane `(n, f)` (lift
/// and wrap as [`groomed_bends`], to the plane's steepest descent) that then **turns out of that plane to
/// hang straight down**, leaning outwards (horizontally away from the head) by `tilt` (rad): the first
/// straight segment after the wrap twists about its tangent by the angle (within +-90 degrees) that takes
/// the major axis to the turn's axis, the next ones bend about it over an arc of [`HANG_TURN_RADIUS`]
/// (at least one segment), the rest is straight. Exact in the reduced model (a twisted straight segment
/// stays straight). Without a straight segment to twist in, or with no room left, there is no turn.
/// Also returns the root's major axis `m = n x f`.
pub fn groomed_turned(
    params: &HairstyleParams,
    root: &ScalpPoint,
    f: &Vector3<f64>,
    model: &StrandModel,
    tilt: f64,
    wrap_segments: usize,
) -> Result<(Vector3<f64>, Vec<(f64, f64)>), StrandError> {
    let (m, mut bends) = groomed_bends(params, root, f, model.length, model.segments, 0.0);
    bends.iter_mut().skip(wrap_segments).for_each(|b| *b = 0.0);
    let mut q: Vec<(f64, f64)> = bends.iter().map(|b| (0.0, *b)).collect();
    let Some(k) = bends.iter().position(|b| b.abs() < 1e-12).filter(|&k| bends[k..].iter().all(|b| b.abs() < 1e-12) && k + 1 < model.segments) else {
        return Ok((m, q));
    };
    let mut state = StrandState::at_rest(model, RootFrame::new(root.position.coords, root.normal, m)?);
    state.q.fill(0.0);
    for (i, b) in bends.iter().enumerate() {
        state.q[2 * i + 1] = *b;
    }
    let frame = strand::kinematics::segment_frames(model, &state)[k];
    let (tw, n1) = (frame.rotation.column(0).into_owned(), frame.rotation.column(1).into_owned());
    // outwards: the horizontal part of the wrap's outward normal there (a positive bend turns the
    // tangent towards -n2, so n2 points away from the centre of the bend)
    let out = Vector3::new(frame.rotation[(0, 2)], frame.rotation[(1, 2)], 0.0)
        .try_normalize(1e-6)
        .or_else(|| Vector3::new(root.normal.x, root.normal.y, 0.0).try_normalize(1e-6))
        .unwrap_or(Vector3::x());
    let d = (-Vector3::z() * tilt.cos() + out * tilt.sin()).normalize();
    let beta = tw.dot(&d).clamp(-1.0, 1.0).acos();
    let Some(axis) = tw.cross(&d).try_normalize(1e-9).filter(|_| beta > 1e-9) else {
        return Ok((m, q));
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut phi = n1.cross(&axis).dot(&tw).atan2(n1.dot(&axis));
    let mut sign = 1.0;
    if phi > half_pi {
        phi -= std::f64::consts::PI;
        sign = -1.0;
    } else if phi < -half_pi {
        phi += std::f64::consts::PI;
        sign = -1.0;
    }
    let l = model.segment_length();
    q[k].0 = phi / l;
    let turn = ((beta * HANG_TURN_RADIUS / l).round() as usize).clamp(1, model.segments - k - 1);
    for qi in &mut q[k + 1..k + 1 + turn] {
        qi.1 = sign * beta / (turn as f64 * l);
    }
    Ok((m, q))
}
