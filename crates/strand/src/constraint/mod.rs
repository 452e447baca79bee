//! Point constraints solved inside the linearly implicit step: unilateral contacts with Coulomb friction
//! (a tool's surface, the body or another strand touching the strand) and bilateral pins (a clip holding a
//! point of the strand).
//!
//! The step solves `A qdot+ = b + J^T p` with `A = M + hD + h^2 K` (solved in O(N) per right-hand side by the
//! articulated-body recursion of the step), `J` the Jacobians
//! of the constrained points and `p` their impulses (N s, over the step). With `Y = A^-1 J^T` the point
//! velocities after the step are `u = u_free + W p`, `W = J Y` (the Delassus operator).
//!
//! **Soft, bounded constraints** (after MuJoCo's `solref`, and the "soft step" of Catto's solvers). Every
//! constraint row solves, by projected Gauss-Seidel sweeps,
//!
//! `u - v_obstacle + R p = min(beta e, v_max)` (along the error's direction)
//!
//! - `e` is the position error (a contact's penetration depth, a pin's offset to its target), m;
//! - `beta = omega / (2 zeta + h omega)`, `omega = 1 / (tau zeta)`: the error-reduction rate (1/s) of an
//!   implicit spring-damper with time constant `tau` and damping ratio `zeta` ([`ConstraintOptions`]);
//! - `v_max` caps the speed at which an error is corrected: depenetration never asks a point for more than
//!   `v_max` (m/s) on top of the obstacle's own velocity;
//! - `R = 1 / (h^2 k_max)` is the constraint-force mixing (m/s per N s): each constraint is at most as stiff as
//!   a spring of `k_max` (N/m) acting on the distance the point would have to cover in one step. It makes the
//!   regularized problem `(W + R) p = ...` strictly positive definite, so
//!   - no impulse is unbounded: `|p| <= h^2 k_max (v_max + |u_free - v_obstacle|)` for one constraint, even
//!     where the point can hardly move (next to a clamped root, along a taut strand);
//!   - contradictory constraints (a tooth pressing a strand into the scalp, a kinematic root inside the body)
//!     resolve to a finite compromise instead of an impulse race.
//!   Where the point moves freely (mobility `W >> R`) the constraint is as rigid as before.
//!
//! For a contact the normal impulse is >= 0 (a cushion's at least its layer's load times `h`), the tangential
//! impulse is clamped to the Coulomb cone `|p_t| <= mu p_n`; a pin's impulse follows its target's velocity. After the step the positions are projected
//! back onto the pins (post-stabilization, Cline and Pai 2003), by at most `v_max h` per step, so a pinned point
//! does not drift. The force on the strand is `p / h`; the obstacle receives `-p / h`.

use crate::error::{Result, StrandError};
use nalgebra::Vector3;

/// What a point constraint does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConstraintKind {
    /// Unilateral contact along `normal` (from the obstacle to the strand) with Coulomb friction coefficient
    /// `friction` (dimensionless, >= 0).
    Contact {
        /// Unit normal from the obstacle towards the strand.
        normal: Vector3<f64>,
        /// Penetration depth along the normal, m (>= 0).
        depth: f64,
        /// Coulomb friction coefficient.
        friction: f64,
    },
    /// The strand point at `s` is held at `target` (m, world), moving with the constraint's velocity.
    Pin {
        /// Where the point must be, m.
        target: Vector3<f64>,
    },
    /// A contact through a compressible layer between the obstacle and the point (a wisp of many fibres pressed by
    /// a body too thick to part it, the point being the wisp's centreline: `tools::cushion::cushion_load`):
    /// the layer pushes the point along `normal` with `load` (N) whatever its motion (the fibres the obstacle has
    /// reached, bent aside, press on the others), and where the point itself reaches the obstacle (`depth > 0`: the
    /// layer packed) the contact is also non-penetrating as [`ConstraintKind::Contact`], the normal force being then
    /// the larger of the two. The layer's load is taken at the step's end, as an implicit spring of `stiffness`:
    /// `load + stiffness h (v_obstacle - u) . normal` (`u` the point's velocity after the step; at least 0), so a
    /// stiff layer on a light point is stable at any step. Coulomb friction `friction` on the whole normal force.
    /// With `load` and `stiffness` 0 and `depth > 0` it is [`ConstraintKind::Contact`].
    Cushion {
        /// Unit normal from the obstacle towards the point.
        normal: Vector3<f64>,
        /// Penetration of the point itself into the obstacle along the normal, m (finite; `<= 0`: the point is
        /// clear of it, the layer's load alone acts).
        depth: f64,
        /// Coulomb friction coefficient.
        friction: f64,
        /// The layer's push at the step's start, N (>= 0).
        load: f64,
        /// How fast the layer's push grows as the obstacle comes closer to the point, N/m (>= 0).
        stiffness: f64,
    },
    /// Coulomb drag without a normal direction: the point is carried along with the constraint's velocity by
    /// a force of at most `max_force` (N), opposing the relative motion (e.g. a tooth passing through a wisp,
    /// whose parted fibres press on it with a load of their own: `tools::entanglement`). Regularised below
    /// `slip_speed`: the largest force is `max_force min(1, |u| / slip_speed)`, with `u` the point's velocity
    /// relative to the constraint's without the drag's own impulse (what the rest of the step gives it), so a
    /// point the drag would hold at rest creeps instead, and the force comes up continuously as the relative
    /// motion starts (no jump from holding to sliding). 0: plain Coulomb.
    Drag {
        /// Largest force, N (>= 0).
        max_force: f64,
        /// Relative speed at and above which the drag may reach `max_force`, m/s (>= 0; 0: always).
        slip_speed: f64,
    },
}

/// A constraint on the centreline point at arc length `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointConstraint {
    /// Arc length from the root, m.
    pub s: f64,
    /// Contact or pin.
    pub kind: ConstraintKind,
    /// Velocity of the obstacle's surface (contact) or of the pin (m/s).
    pub velocity: Vector3<f64>,
}

/// Options of the constraint solver: the compliance of every constraint (tool, body, hair-hair contacts and
/// pins) and the solver's effort. See the module documentation for the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstraintOptions {
    /// Time constant `tau` of the constraint's error correction (MuJoCo's `solref[0]`), s: a penetration or pin
    /// offset decays like a spring-damper of natural frequency `1 / (tau zeta)`. Default 0.004 (4 haptic steps;
    /// MuJoCo advises at least two steps).
    pub time_constant: f64,
    /// Damping ratio `zeta` of that spring-damper (MuJoCo's `solref[1]`), dimensionless. Default 1 (critical).
    pub damping_ratio: f64,
    /// Largest speed at which a position error is corrected, m/s (on top of the obstacle's velocity). Default
    /// 0.05: a strand pushed out of the scalp or a tooth comes out at 5 cm/s at most.
    pub max_correction_speed: f64,
    /// Largest stiffness of one constraint, N/m: sets the constraint-force mixing `R = 1 / (h^2 k_max)`, so one
    /// constraint's impulse over a step is at most `h^2 k_max` times the velocity change it asks for (force at
    /// most `k_max` times the distance it would make the point cover in one step). Default 100 N/m: near the
    /// root of an H1 fibre the bending stiffness `3 EI / s^3` reaches it at s = 0.6 mm, so only points that
    /// can hardly move are softened. `f64::INFINITY` gives rigid constraints.
    pub max_stiffness: f64,
    /// Most projected Gauss-Seidel sweeps per solve. Default 10: the local interaction starts each solve from the
    /// last step's impulses ([`ConstraintRows::warm_start`]), so the sweeps of successive steps add up while the
    /// contacts persist (with hair-hair contacts the linked solve seldom reaches `tolerance`; 30 cold sweeps a
    /// step cost a third of the haptic step, bench/HISTORY.md).
    pub iterations: usize,
    /// The sweeps of a group of strands (one strand, or strands linked by contacts with each other) stop early
    /// once a whole sweep changed none of the group's impulses by more than `tolerance` times its largest
    /// impulse (dimensionless, >= 0; 0 always runs `iterations` sweeps). Default 1e-6.
    pub tolerance: f64,
}

impl Default for ConstraintOptions {
    fn default() -> Self {
        Self { time_constant: 0.004, damping_ratio: 1.0, max_correction_speed: 0.05, max_stiffness: 100.0, iterations: 10, tolerance: 1e-6 }
    }
}

impl ConstraintOptions {
    /// The solver before compliance was introduced: rigid constraints (no force mixing, no speed cap) removing
    /// half of a position error per step of `h` seconds. Kept to show what the bounds change.
    pub fn rigid(h: f64) -> Self {
        // beta = omega / (2 zeta + h omega) = 0.5 / h  <=>  omega = 2 zeta / h  <=>  tau = h / (2 zeta^2).
        Self { time_constant: 0.5 * h, damping_ratio: 1.0, max_correction_speed: f64::INFINITY, max_stiffness: f64::INFINITY, iterations: 30, tolerance: 1e-6 }
    }

    /// Error-reduction rate `beta = omega / (2 zeta + h omega)` with `omega = 1 / (tau zeta)`, 1/s, for a step of
    /// `h` seconds.
    pub fn error_reduction_rate(&self, h: f64) -> f64 {
        let omega = 1.0 / (self.time_constant * self.damping_ratio);
        omega / (2.0 * self.damping_ratio + h * omega)
    }

    /// Constraint-force mixing `R = 1 / (h^2 k_max)`, m/s per N s, for a step of `h` seconds (0: rigid).
    pub fn force_mixing(&self, h: f64) -> f64 {
        1.0 / (h * h * self.max_stiffness)
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, reason: String| Err(StrandError::InvalidParameter { field, reason });
        if !(self.time_constant.is_finite() && self.time_constant > 0.0) {
            return bad("time_constant", format!("must be a finite time > 0 s, got {}", self.time_constant));
        }
        if !(self.damping_ratio.is_finite() && self.damping_ratio > 0.0) {
            return bad("damping_ratio", format!("must be finite and > 0, got {}", self.damping_ratio));
        }
        if !(self.max_correction_speed > 0.0) {
            return bad("max_correction_speed", format!("must be > 0 m/s, got {}", self.max_correction_speed));
        }
        if !(self.max_stiffness > 0.0) {
            return bad("max_stiffness", format!("must be > 0 N/m, got {}", self.max_stiffness));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad("tolerance", format!("must be finite and >= 0, got {}", self.tolerance));
        }
        Ok(())
    }
}

impl PointConstraint {
    fn validate(&self) -> Result<()> {
        let bad = |what: &str| Err(StrandError::InvalidParameter { field: "constraint", reason: format!("{what} in {self:?}") });
        if !self.s.is_finite() || !self.velocity.iter().all(|x| x.is_finite()) {
            return bad("non-finite arc length or velocity");
        }
        match self.kind {
            ConstraintKind::Contact { normal, depth, friction } => {
                if !normal.iter().all(|x| x.is_finite()) || (normal.norm() - 1.0).abs() > 1e-6 {
                    return bad("contact normal must be a unit vector");
                }
                if !(depth.is_finite() && depth >= 0.0) || !(friction.is_finite() && friction >= 0.0) {
                    return bad("depth and friction must be finite and >= 0");
                }
            }
            ConstraintKind::Cushion { normal, depth, friction, load, stiffness } => {
                if !normal.iter().all(|x| x.is_finite()) || (normal.norm() - 1.0).abs() > 1e-6 {
                    return bad("contact normal must be a unit vector");
                }
                let finite_positive = |x: f64| x.is_finite() && x >= 0.0;
                if !depth.is_finite() || !finite_positive(friction) || !finite_positive(load) || !finite_positive(stiffness) {
                    return bad("cushion depth must be finite, friction, load and stiffness finite and >= 0");
                }
            }
            ConstraintKind::Pin { target } => {
                if !target.iter().all(|x| x.is_finite()) {
                    return bad("non-finite pin target");
                }
            }
            ConstraintKind::Drag { max_force, slip_speed } => {
                if !(max_force.is_finite() && max_force >= 0.0) {
                    return bad("drag force must be finite and >= 0");
                }
                if !(slip_speed.is_finite() && slip_speed >= 0.0) {
                    return bad("drag slip speed must be finite and >= 0");
                }
            }
        }
        Ok(())
    }
}

mod rows;
mod slide;
mod solve;
mod step;

pub use rows::ConstraintRows;
pub use solve::{solve, ConstraintLink};

