//! Repeated strokes (`[tool] strokes = N`): the tool path played N times, the tool returning to the start
//! between strokes out of the hair, as a combing rig's comb does.
//!
//! The return, from the stroke's last pose to its first, at the stroke's mean speed (its path length over its
//! duration), through three waypoints:
//! 1. out of the tress sideways: from the last pose, horizontally away from the tress's axis (the vertical
//!    through the centre of the roots) along `u`, the horizontal direction from that axis to the stroke's
//!    first position (-y if that position is on the axis), to `clearance` from the axis;
//! 2. up beside the tress to the first pose's height (and turning to its rotation);
//! 3. back in along `-u` to the first pose (a comb slides in along its teeth).

use crate::path::{ToolPath, Waypoint};
use nalgebra::Vector3;
use tools::contact::ToolPose;
use tools::shape::ToolShape;

/// Margin between the tool's bounding sphere and the tress's roots when the tool is out of the hair, m.
pub const RETURN_MARGIN: f64 = 0.01;

/// A stroke path played `strokes` times, with the return between strokes.
#[derive(Debug, Clone)]
pub struct StrokeCycle {
    stroke: ToolPath,
    back: Option<ToolPath>,
    strokes: u32,
    period: f64,
}

impl StrokeCycle {
    /// Most strokes a scenario may ask for.
    pub const MAX_STROKES: u32 = 1000;

    /// `strokes` plays of `stroke` (1..=[`Self::MAX_STROKES`]); the tool leaves the tress to `clearance` (m)
    /// from the tress's axis through `axis` (x, y of the roots' centre, m) between strokes. Errors name what is
    /// wrong.
    pub fn new(stroke: ToolPath, strokes: u32, axis: [f64; 2], clearance: f64) -> Result<Self, String> {
        if !(1..=Self::MAX_STROKES).contains(&strokes) {
            return Err(format!("tool.strokes must be 1..={}, got {strokes}", Self::MAX_STROKES));
        }
        if strokes == 1 {
            let period = stroke.end_time();
            return Ok(Self { stroke, back: None, strokes, period });
        }
        let w = stroke.waypoints();
        let (first, last) = (w[0], w[w.len() - 1]);
        let duration = last.t - first.t;
        let speed = stroke.length() / duration.max(f64::MIN_POSITIVE);
        if !(duration > 0.0 && speed > 0.0 && speed.is_finite()) {
            return Err("tool.strokes > 1 needs a tool path that moves (two waypoints or more at different places)".into());
        }
        let p0 = Vector3::from(first.position);
        let p1 = Vector3::from(last.position);
        let off = Vector3::new(p0.x - axis[0], p0.y - axis[1], 0.0);
        let u = if off.norm() > 1e-3 { off.normalize() } else { -Vector3::y() };
        let axis3 = |z: f64| Vector3::new(axis[0], axis[1], z);
        // The tool's origin on the line through `p` along u, at `clearance` from the axis.
        let outside = |p: Vector3<f64>| axis3(p.z) + u * clearance + (p - axis3(p.z) - u * u.dot(&(p - axis3(p.z))));
        let a = outside(p1);
        let b = outside(p0);
        let mut t = 0.0;
        let mut back = vec![Waypoint { t, ..last }];
        for (p, r) in [(a, last.rotation), (b, first.rotation), (p0, first.rotation)] {
            let prev = Vector3::from(back[back.len() - 1].position);
            t += ((p - prev).norm() / speed).max(1e-3);
            back.push(Waypoint { t, position: p.into(), rotation: r });
        }
        let back = ToolPath::new(back)?;
        let period = stroke.end_time() + back.end_time();
        Ok(Self { stroke, back: Some(back), strokes, period })
    }

    /// The clearance that takes `shape` out of a tress whose roots fill a rectangle `extent` (m): its
    /// bounding sphere about its origin, half the rectangle's diagonal and [`RETURN_MARGIN`], m.
    pub fn clearance(shape: &ToolShape, extent: [f64; 2]) -> f64 {
        let reach = shape.capsules.iter().flat_map(|c| [c.a, c.b].map(|p| Vector3::from(p).norm() + c.radius)).fold(0.0, f64::max);
        reach + 0.5 * extent[0].hypot(extent[1]) + RETURN_MARGIN
    }

    /// Strokes.
    pub fn strokes(&self) -> u32 {
        self.strokes
    }

    /// Time from the start of one stroke to the start of the next, s.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Time the last stroke ends, s.
    pub fn end_time(&self) -> f64 {
        (self.strokes - 1) as f64 * self.period + self.stroke.end_time()
    }

    /// The tool's pose at time `t` (s) and the stroke it is in (1..=strokes; 0 while it returns). The times
    /// `(k P, k P + T]` are stroke k + 1's (P the period, T the stroke path's end); after the last stroke the
    /// tool holds its last pose, counted in the last stroke.
    pub fn pose(&self, t: f64) -> (ToolPose, u32) {
        let k = if self.period > 0.0 { ((t / self.period).ceil() - 1.0).clamp(0.0, (self.strokes - 1) as f64) } else { 0.0 };
        let local = t - k * self.period;
        let n = k as u32 + 1;
        match &self.back {
            Some(back) if local > self.stroke.end_time() && n < self.strokes => (back.pose(local - self.stroke.end_time()), 0),
            _ => (self.stroke.pose(local), n),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stroke() -> ToolPath {
        // 0.2 m down in 0.8 s (0.25 m/s), from 1.2 cm in front of the tress's axis.
        ToolPath::new(vec![
            Waypoint { t: 0.0, position: [0.0, -0.012, 0.29], rotation: [1.5707963, 0.0, 0.0] },
            Waypoint { t: 0.8, position: [0.0, -0.012, 0.09], rotation: [1.5707963, 0.0, 0.0] },
        ])
        .unwrap()
    }

    #[test]
    fn the_tool_returns_around_the_tress_at_the_stroke_speed() {
        let c = StrokeCycle::new(stroke(), 3, [0.0, 0.0], 0.08).unwrap();
        // Return: out 0.068 m, up 0.2 m, in 0.068 m at 0.25 m/s = 1.344 s; period 2.144 s.
        assert!((c.period() - (0.8 + 0.336 / 0.25)).abs() < 1e-12, "{}", c.period());
        assert!((c.end_time() - (2.0 * c.period() + 0.8)).abs() < 1e-12);
        // Stroke 2 starts where stroke 1 did; the return is out of the tress (y <= -0.012) and never below the
        // stroke's end or above its start; the stroke numbers.
        assert_eq!(c.pose(0.4).1, 1);
        assert_eq!(c.pose(0.8).1, 1);
        assert_eq!(c.pose(0.81).1, 0);
        let (p, n) = c.pose(c.period() + 1e-9);
        assert_eq!(n, 2);
        assert!((p.position - Vector3::new(0.0, -0.012, 0.29)).norm() < 1e-6);
        let mut far = 0.0f64;
        for i in 1..=1000 {
            let (p, n) = c.pose(0.8 + (c.period() - 0.8) * i as f64 / 1000.0);
            assert_eq!(n, 0, "returning");
            assert!(p.position.y <= -0.012 + 1e-12 && (0.09 - 1e-12..=0.29 + 1e-12).contains(&p.position.z), "{p:?}");
            far = far.min(p.position.y);
        }
        assert!((far + 0.08).abs() < 1e-12, "out to the clearance: {far}");
        // After the last stroke the tool holds, counted in the last stroke.
        assert_eq!(c.pose(c.end_time() + 1.0).1, 3);
        assert!((c.pose(c.end_time() + 1.0).0.position.z - 0.09).abs() < 1e-12);
    }

    #[test]
    fn one_stroke_is_the_path_itself_and_bad_counts_are_named() {
        let c = StrokeCycle::new(stroke(), 1, [0.0, 0.0], 0.08).unwrap();
        assert_eq!(c.end_time(), 0.8);
        for t in [0.0, 0.3, 0.8, 5.0] {
            assert_eq!(c.pose(t), (stroke().pose(t), 1));
        }
        assert!(StrokeCycle::new(stroke(), 0, [0.0, 0.0], 0.08).unwrap_err().contains("tool.strokes"));
        let still = ToolPath::new(vec![Waypoint { t: 0.0, position: [0.0; 3], rotation: [0.0; 3] }]).unwrap();
        assert!(StrokeCycle::new(still, 2, [0.0, 0.0], 0.08).unwrap_err().contains("moves"));
    }
}
