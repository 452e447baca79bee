pub mod error;
pub mod hair_type;
pub mod helix;
pub mod kinematics;
pub mod material;
pub mod model;
pub mod section;
pub mod state;
