//! The mutable state of one strand (MuJoCo's "data" side): coordinates, velocities and the root's motion.

use crate::error::{Result, StrandError};
use crate::model::StrandModel;
use nalgebra::{DVector, Matrix3, Vector3};

/// The frame the strand's root is clamped to (on the scalp), and its motion. The global layer moves it.
#[derive(Debug, Clone, PartialEq)]
pub struct RootFrame {
    /// Root position, m.
    pub position: Vector3<f64>,
    /// Material frame at the root: columns are the tangent `n0`, the major axis `n1` and `n2 = n0 x n1`.
    pub rotation: Matrix3<f64>,
    /// Root velocity, m/s.
    pub velocity: Vector3<f64>,
    /// Root angular velocity, rad/s (world frame).
    pub angular_velocity: Vector3<f64>,
    /// Root acceleration, m/s^2.
    pub acceleration: Vector3<f64>,
    /// Root angular acceleration, rad/s^2 (world frame).
    pub angular_acceleration: Vector3<f64>,
}

impl RootFrame {
    /// A root at rest at `position` (m) with tangent `tangent` and the section's major axis towards
    /// `major_axis` (made orthogonal to the tangent). Neither needs to be normalized.
    pub fn new(position: Vector3<f64>, tangent: Vector3<f64>, major_axis: Vector3<f64>) -> Result<Self> {
        if !position.iter().all(|x| x.is_finite()) {
            return Err(StrandError::InvalidParameter { field: "root_position", reason: format!("must be finite, got {position:?}") });
        }
        let n0 = tangent.try_normalize(1e-300).filter(|v| v.iter().all(|x| x.is_finite())).ok_or_else(|| {
            StrandError::InvalidParameter { field: "root_tangent", reason: format!("must be a finite non-zero vector, got {tangent:?}") }
        })?;
        let n1 = (major_axis - n0 * n0.dot(&major_axis))
            .try_normalize(1e-9 * major_axis.norm().max(1e-300))
            .filter(|v| v.iter().all(|x| x.is_finite()))
            .ok_or_else(|| StrandError::InvalidParameter {
                field: "root_major_axis",
                reason: format!("must be finite and not parallel to root_tangent, got {major_axis:?}"),
            })?;
        let n2 = n0.cross(&n1);
        Ok(Self {
            position,
            rotation: Matrix3::from_columns(&[n0, n1, n2]),
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
            acceleration: Vector3::zeros(),
            angular_acceleration: Vector3::zeros(),
        })
    }

    /// Checks that everything is finite and the rotation orthonormal (to 1e-9).
    pub fn validate(&self) -> Result<()> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let all = [
            ("root_position", self.position.as_slice()),
            ("root_velocity", self.velocity.as_slice()),
            ("root_angular_velocity", self.angular_velocity.as_slice()),
            ("root_acceleration", self.acceleration.as_slice()),
            ("root_angular_acceleration", self.angular_acceleration.as_slice()),
        ];
        for (field, v) in all {
            if !finite(v) {
                return Err(StrandError::InvalidParameter { field, reason: format!("must be finite, got {v:?}") });
            }
        }
        let r = &self.rotation;
        if !finite(r.as_slice()) || (r.transpose() * r - Matrix3::identity()).norm() > 1e-9 || r.determinant() < 0.0 {
            return Err(StrandError::InvalidParameter { field: "root_rotation", reason: "must be a proper rotation matrix".into() });
        }
        Ok(())
    }
}

/// Generalized coordinates and velocities of a strand, with its root frame and time.
#[derive(Debug, Clone, PartialEq)]
pub struct StrandState {
    /// Darboux components per segment `(twist, bend[, bend2])`, rad/m; length 2N or 3N.
    pub q: DVector<f64>,
    /// Their time derivatives, rad/(m s).
    pub qdot: DVector<f64>,
    /// The clamped root and its motion.
    pub root: RootFrame,
    /// Simulation time, s.
    pub time: f64,
}

impl StrandState {
    /// The strand at its rest shape, at rest, clamped to `root`.
    pub fn at_rest(model: &StrandModel, root: RootFrame) -> Self {
        Self { q: model.rest_coordinates(), qdot: DVector::zeros(model.dofs()), root, time: 0.0 }
    }
}
