//! The timed actions of a global scenario: scissors cuts, dryer and sprayer passes, and the script of the
//! live tool's inputs they make ([`ToolScript`]).

use super::ScenarioError;
use crate::global::ToolSettings;
use crate::tool::{Tool, ToolInput};
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use tools::dryer::{Cone, HairDryer};
use tools::sprayer::Sprayer;

/// One timed action of a global scenario.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Action {
    /// Scissors: the blades close at time `t` over a disk.
    Cut(CutAction),
    /// Hair dryer moved along a path for a while.
    Dry(ConeAction),
    /// Water sprayer moved along a path for a while.
    Spray(ConeAction),
}

/// A scissors cut.
#[derive(Debug, Clone, Deserialize)]
pub struct CutAction {
    /// When the blades close, s.
    pub t: f64,
    /// Centre of the disk the blades sweep, m (head frame: origin at the head centre, z up, y to the face).
    pub point: [f64; 3],
    /// Normal of the cutting plane.
    pub normal: [f64; 3],
    /// Radius of the disk, m.
    pub radius: f64,
}

/// A dryer or sprayer pass.
#[derive(Debug, Clone, Deserialize)]
pub struct ConeAction {
    /// Start time, s.
    pub start: f64,
    /// How long it acts, s.
    pub duration: f64,
    /// Nozzle poses `{ t, apex, axis }` (t from `start`, s; m), linearly interpolated; held outside.
    pub path: Vec<ConePose>,
    /// Half-angle of the cone, rad (default: the tool's).
    pub half_angle: Option<f64>,
    /// Range of the cone, m (default: the tool's).
    pub range: Option<f64>,
    /// Dryer: air speed at the nozzle, m/s (default 10).
    pub air_speed: Option<f64>,
    /// Dryer: drying rate k0, 1/s (default 0.05); sprayer: wetting rate s0, 1/s (default 1).
    pub rate: Option<f64>,
}

/// A nozzle pose on a dryer or sprayer path.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConePose {
    /// Time from the action's start, s.
    pub t: f64,
    /// Nozzle position, m.
    pub apex: [f64; 3],
    /// Blowing direction.
    pub axis: [f64; 3],
}

impl ConeAction {
    pub(crate) fn active(&self, t: f64) -> bool {
        t >= self.start && t < self.start + self.duration
    }
    /// Nozzle (apex, axis) at scenario time t.
    pub(crate) fn pose(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let tau = t - self.start;
        let p = &self.path;
        if tau <= p[0].t {
            return (p[0].apex.into(), p[0].axis.into());
        }
        for w in p.windows(2) {
            if tau <= w[1].t {
                let a = (tau - w[0].t) / (w[1].t - w[0].t);
                let lerp = |x: [f64; 3], y: [f64; 3]| Vector3::from(x) * (1.0 - a) + Vector3::from(y) * a;
                return (lerp(w[0].apex, w[1].apex), lerp(w[0].axis, w[1].axis));
            }
        }
        let l = p[p.len() - 1];
        (l.apex.into(), l.axis.into())
    }
    pub(crate) fn validate(&self, what: &str, i: usize) -> Result<(), ScenarioError> {
        let bad = |m: String| Err(ScenarioError::Invalid(format!("action {i} ({what}): {m}")));
        if !(self.start.is_finite() && self.start >= 0.0 && self.duration.is_finite() && self.duration > 0.0) {
            return bad(format!(
                "start must be >= 0 s and duration > 0 s, got {} and {}",
                self.start, self.duration
            ));
        }
        if self.path.is_empty() {
            return bad("path needs at least one pose { t, apex, axis }".into());
        }
        for (k, w) in self.path.iter().enumerate() {
            if !(w.t.is_finite() && w.apex.iter().chain(&w.axis).all(|x| x.is_finite()))
                || Vector3::from(w.axis).norm() < 1e-12
            {
                return bad(format!("path[{k}] must be finite with a non-zero axis"));
            }
            if k > 0 && w.t <= self.path[k - 1].t {
                return bad(format!("path[{k}]: times must increase"));
            }
        }
        Ok(())
    }
    pub(crate) fn cone(&self, t: f64, default: Cone) -> Cone {
        let (apex, axis) = self.pose(t);
        Cone {
            apex,
            axis,
            half_angle: self.half_angle.unwrap_or(default.half_angle),
            range: self.range.unwrap_or(default.range),
        }
    }
    pub(crate) fn dryer(&self, t: f64) -> HairDryer {
        let d = HairDryer::default();
        HairDryer {
            cone: self.cone(t, d.cone),
            air_speed: self.air_speed.unwrap_or(d.air_speed),
            drying_rate: self.rate.unwrap_or(d.drying_rate),
        }
    }
    pub(crate) fn sprayer(&self, t: f64) -> Sprayer {
        let s = Sprayer::default();
        Sprayer {
            cone: self.cone(t, s.cone),
            wetting_rate: self.rate.unwrap_or(s.wetting_rate),
        }
    }
}

/// The actions as the live tool's inputs: what a global scenario gives [`crate::global::GlobalCore::step`] each global
/// step, as the haptic thread gives it in the live session. A cut is the scissors closing once (pressed,
/// `cuts` one more) with the tool's y axis along the blade's normal; a dryer or sprayer pass is that tool
/// held pressed with its nozzle on the action's path (the tool point `GlobalParams::nozzle_standoff` in
/// front of the nozzle along the jet, the tool's -z along the jet). Between actions the tool is away
/// (`present` false: it touches nothing).
#[derive(Debug, Clone)]
pub struct ToolScript {
    actions: Vec<Action>,
    standoff: f64,
    cuts: u64,
    base: ToolSettings,
}

impl ToolScript {
    /// The script of `actions` (validated by the scenario), nozzles `standoff` m behind the tool point, the
    /// tools' settings outside the actions' own keys from `base`.
    pub fn new(actions: &[Action], standoff: f64, base: ToolSettings) -> Self {
        Self { actions: actions.to_vec(), standoff, cuts: 0, base }
    }

    /// The tool input and the tools' settings of the global step over (t0, t1] (s): a cut whose time falls
    /// in it, else the dryer or sprayer pass active at t0, else the tool away.
    pub fn input(&mut self, t0: f64, t1: f64) -> (ToolInput, ToolSettings) {
        let mut settings = self.base;
        for a in &self.actions {
            if let Action::Cut(c) = a {
                if c.t > t0 && c.t <= t1 || (t0 <= 0.0 && c.t == 0.0) {
                    self.cuts += 1;
                    settings.blade_radius = c.radius;
                    let rotation = frame_with_axis(1, &Vector3::from(c.normal));
                    let input = ToolInput { tool: Tool::Scissors, present: true, position: c.point.into(), rotation, pressed: true, cuts: self.cuts, ..ToolInput::default() };
                    return (input, settings);
                }
            }
        }
        for a in &self.actions {
            let (tool, c) = match a {
                Action::Dry(c) if c.active(t0) => (Tool::Dryer, c),
                Action::Spray(c) if c.active(t0) => (Tool::Sprayer, c),
                _ => continue,
            };
            let (apex, axis) = c.pose(t0);
            let jet = axis.normalize();
            settings.dryer = c.dryer(t0);
            settings.sprayer = c.sprayer(t0);
            let rotation = frame_with_axis(2, &-jet);
            let input = ToolInput { tool, present: true, position: apex + jet * self.standoff, rotation, pressed: true, cuts: self.cuts, ..ToolInput::default() };
            return (input, settings);
        }
        (ToolInput { cuts: self.cuts, ..ToolInput::default() }, settings)
    }
}

/// A rotation (tool frame to world) whose column `k` is the unit vector along `dir` (non-zero).
fn frame_with_axis(k: usize, dir: &Vector3<f64>) -> Matrix3<f64> {
    let a = dir.normalize();
    let helper = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let b = (helper - a * a.dot(&helper)).normalize();
    let c = a.cross(&b);
    // Columns (k, k+1, k+2 mod 3) = (a, b, c): right-handed.
    let mut cols = [Vector3::zeros(); 3];
    cols[k] = a;
    cols[(k + 1) % 3] = b;
    cols[(k + 2) % 3] = c;
    Matrix3::from_columns(&cols)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tool_frames_are_rotations_with_the_asked_axis() {
        for (k, d) in [(1, Vector3::new(0.0, 0.0, 1.0)), (2, Vector3::new(0.3, 1.0, 0.0)), (2, Vector3::new(1.0, 0.0, 0.0)), (1, Vector3::new(0.0, -2.0, 0.0))] {
            let r = frame_with_axis(k, &d);
            assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12 && (r.determinant() - 1.0).abs() < 1e-12, "{r}");
            assert!((r.column(k) - d.normalize()).norm() < 1e-12);
        }
    }
}
