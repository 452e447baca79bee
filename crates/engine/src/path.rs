//! A scripted tool path: poses at given times, linearly interpolated (position) and held (rotation).

use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::Deserialize;
use tools::contact::ToolPose;

/// One waypoint of a tool path.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    /// Time, s.
    pub t: f64,
    /// Tool origin, m.
    pub position: [f64; 3],
    /// Tool rotation as a rotation vector (axis times angle, rad); default none.
    #[serde(default)]
    pub rotation: [f64; 3],
}

/// A tool path: waypoints in increasing time. Before the first and after the last the tool holds still.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolPath {
    waypoints: Vec<Waypoint>,
}

impl ToolPath {
    /// Checks the waypoints: at least one, finite, strictly increasing times; names the bad one.
    pub fn new(waypoints: Vec<Waypoint>) -> Result<Self, String> {
        if waypoints.is_empty() {
            return Err("a tool path needs at least one waypoint".into());
        }
        for (i, w) in waypoints.iter().enumerate() {
            if !(w.t.is_finite() && w.position.iter().chain(w.rotation.iter()).all(|x| x.is_finite())) {
                return Err(format!("waypoint {i}: every value must be finite, got {w:?}"));
            }
            if i > 0 && w.t <= waypoints[i - 1].t {
                return Err(format!("waypoint {i}: times must increase, got {} after {}", w.t, waypoints[i - 1].t));
            }
        }
        Ok(Self { waypoints })
    }

    /// Pose at time `t` (s): positions interpolated linearly, rotation vectors interpolated linearly.
    pub fn pose(&self, t: f64) -> ToolPose {
        let w = &self.waypoints;
        let (p, r) = if t <= w[0].t {
            (Vector3::from(w[0].position), Vector3::from(w[0].rotation))
        } else if t >= w[w.len() - 1].t {
            (Vector3::from(w[w.len() - 1].position), Vector3::from(w[w.len() - 1].rotation))
        } else {
            let k = w.partition_point(|x| x.t <= t);
            let (a, b) = (&w[k - 1], &w[k]);
            let f = (t - a.t) / (b.t - a.t);
            let lerp = |x: [f64; 3], y: [f64; 3]| Vector3::from(x) * (1.0 - f) + Vector3::from(y) * f;
            (lerp(a.position, b.position), lerp(a.rotation, b.rotation))
        };
        let rotation: Matrix3<f64> = Rotation3::new(r).into_inner();
        ToolPose { position: p, rotation }
    }

    /// Time of the last waypoint, s.
    pub fn end_time(&self) -> f64 {
        self.waypoints[self.waypoints.len() - 1].t
    }

    /// The waypoints, in increasing time.
    pub fn waypoints(&self) -> &[Waypoint] {
        &self.waypoints
    }

    /// Length of the path through its waypoints' positions, m.
    pub fn length(&self) -> f64 {
        self.waypoints.windows(2).map(|w| (Vector3::from(w[1].position) - Vector3::from(w[0].position)).norm()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_holds() {
        let p = ToolPath::new(vec![
            Waypoint { t: 0.0, position: [0.0, 0.0, 0.0], rotation: [0.0; 3] },
            Waypoint { t: 1.0, position: [1.0, 2.0, 0.0], rotation: [0.0; 3] },
        ])
        .unwrap();
        assert_eq!(p.pose(0.5).position, Vector3::new(0.5, 1.0, 0.0));
        assert_eq!(p.pose(-1.0).position, Vector3::zeros());
        assert_eq!(p.pose(2.0).position, Vector3::new(1.0, 2.0, 0.0));
        assert!(ToolPath::new(vec![]).is_err());
        let w = Waypoint { t: 0.0, position: [0.0; 3], rotation: [0.0; 3] };
        assert!(ToolPath::new(vec![w, w]).unwrap_err().contains("increase"));
        let nan = Waypoint { t: 0.0, position: [f64::NAN, 0.0, 0.0], rotation: [0.0; 3] };
        assert!(ToolPath::new(vec![nan]).unwrap_err().contains("finite"));
    }
}
