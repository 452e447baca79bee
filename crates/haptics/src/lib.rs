//! # Coiffure haptics
//!
//! The device side of the haptic loop: a [`device::HapticDevice`] trait with backends, device profiles
//! (force and force-rate limits), and the [`coupling::Coupling`] that turns a device pose into a tool proxy
//! pose and the hair's reaction into a safe device force: virtual coupling, clamps, a time-domain passivity
//! observer and controller, and rejection of NaN or teleporting input. SI units (m, s, N).

pub mod backends;
pub mod coupling;
pub mod device;
pub mod haptic_loop;
pub mod local_model;
pub mod model_blend;
pub mod profile;
pub mod reading;
pub mod realtime;
pub mod sim;
pub mod target;
pub mod udp;
pub mod workspace;
