//! How a tool contact pushes a strand: the paper's velocity-proportional force, or constraints.

use strand::constraint::ConstraintOptions;

/// How a contact pushes a strand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ForceModel {
    /// The paper's section 4.3: `F = gain * tdot_perp * w A / l`, with `tdot_perp` the tool's velocity
    /// perpendicular to the strand tangent (m/s), `w = rho g` the specific weight (N/m^3), `A` the section
    /// area (m^2) and `l` the arc length from the root to the contact (m). As published this is not a force
    /// (N/(m s)); `gain` (m s) makes it one. Applied explicitly as a point force.
    Paper {
        /// Gain turning the published expression into newtons, m s. Default 1.
        gain: f64,
    },
    /// Physically consistent: non-penetration and Coulomb friction as constraints in the implicit step.
    Constraint {
        /// Friction coefficient (dimensionless), e.g. from [`strand::HairType::friction_coefficient`].
        friction: f64,
        /// Solver options.
        options: ConstraintOptions,
    },
}
