//! Viewer commands, applied by the haptic thread before its next step (and recorded).

use crate::tool::Tool;

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
    /// Put every strand, the lattice, the cuts and the wetness back to the start.
    Reset,
}
