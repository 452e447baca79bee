//! # Coiffure strand: the local interaction layer's hair strand
//!
//! A hair strand of length L is a Super-Helix: N helical segments, each with a constant Darboux vector in
//! its material frame. The paper's **reduced** model keeps two coordinates per segment (twist about the
//! tangent `n0` and bend about the cross-section's major axis `n1`); the **full** model of Bertails et al.
//! (2006) adds bending about the minor axis `n2`. Both share one implementation: kinematics in closed form
//! ([`helix`], [`kinematics`]), Lagrangian dynamics ([`dynamics`]), time integration ([`integrator`]) and
//! statics ([`statics`]).
//!
//! Model/data split as in MuJoCo: [`model::StrandModel`] is immutable (geometry, material, rest shape,
//! environment), [`state::StrandState`] is the mutable state (coordinates, velocities, root motion).
//! SI units everywhere (m, kg, s, N, Pa; curvatures in rad/m).
//!
//! ```
//! use strand::{hair_type::HairType, integrator::Strand, model::{ModelKind, StrandModel}, state::RootFrame};
//! use nalgebra::Vector3;
//! let h = HairType::H1;
//! let model = StrandModel::new(ModelKind::Reduced, 0.1, 16, h.section().unwrap(), h.material().unwrap()).unwrap();
//! let root = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap();
//! let mut strand = Strand::new(model, root).unwrap();
//! for _ in 0..100 {
//!     strand.step(1e-3, &[]).unwrap(); // 1 ms, linearly implicit Euler
//! }
//! assert!(strand.state.time > 0.099);
//! ```

pub mod analytic;
pub mod batch;
pub mod constraint;
pub mod dynamics;
pub mod error;
pub mod fit;
pub mod hair_type;
pub mod helix;
pub mod integrator;
pub mod kinematics;
pub mod linalg;
pub mod material;
pub mod model;
#[cfg(feature = "reference")]
pub mod reference;
pub mod samples;
pub mod section;
pub mod spec;
pub mod state;
pub mod statics;
pub mod styling;

pub use batch::StrandBatch;
pub use dynamics::PointForce;
pub use error::StrandError;
pub use hair_type::HairType;
pub use integrator::{Integrator, Strand};
pub use model::{ModelKind, StrandModel};
pub use state::{RootFrame, StrandState};
