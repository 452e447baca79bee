//! Viewer commands, applied by the haptic thread before its next step (and recorded).

use crate::tool::Tool;
use nalgebra::{Isometry3, Vector3};

/// A command from the viewer, applied by the haptic thread before its next step (and recorded).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Select a tool.
    SelectTool(Tool),
    /// Hair type (index into [`HairType::ALL`]), curliness in [0, 1], combing ease in [0, 1].
    SetHair {
        /// Index into [`HairType::ALL`].
        hair_type: u8,
        /// Curliness in [0, 1] (0 straight, 1 tight curls of about 1 cm radius).
        curliness: f64,
        /// Combing ease in [0, 1]: scales the friction coefficient by (1 - 0.8 ease).
        combing_ease: f64,
    },
    /// The hair's surface treatment (`tools::treatment::Treatment`: the friction of the tool and of fibre on
    /// fibre, dry and wet), as `HapticParams::treatment` and a tress scenario's `[patch] treatment`.
    SetTreatment(tools::treatment::Treatment),
    /// Put every strand, the lattice, the cuts and the wetness back to the start.
    Reset,
    /// Move the head (the paper's Spaceball): the head frame's pose in the world, its origin at `position`
    /// (m, at most 1 m from the world origin) turned by the rotation vector `rotation` (axis times angle, rad,
    /// at most pi). The lattice's attachment, the body and the local strands' roots follow it.
    SetHead {
        /// Position of the head frame's origin (the cranium's centre), m.
        position: Vector3<f64>,
        /// Rotation of the head frame, rotation vector, rad.
        rotation: Vector3<f64>,
    },
    /// Simulate at most this many strands near the tool (clamped to 1..=`SessionParams::max_active`): the
    /// live haptic thread's strand budget (`crate::budget`) when its steps run long or have room again. Not a
    /// viewer message; recorded so that a replay simulates the same strands.
    LimitStrands(u32),
}

/// The head pose of a [`Command::SetHead`], if its values are finite and within range (position within 1 m,
/// rotation within pi rad).
pub fn head_pose(position: &Vector3<f64>, rotation: &Vector3<f64>) -> Option<Isometry3<f64>> {
    let finite = position.iter().chain(rotation.iter()).all(|x| x.is_finite());
    (finite && position.norm() <= 1.0 && rotation.norm() <= std::f64::consts::PI + 1e-9).then(|| Isometry3::new(*position, *rotation))
}

/// A pose whose translation (m) and rotation quaternion are all finite (the check of every `set_head_pose`).
pub fn is_finite_pose(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().chain(pose.rotation.coords.iter()).all(|x| x.is_finite())
}
