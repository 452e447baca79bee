//! The live session's public names in one place (the rooms are [`crate::scene`], [`crate::tool`],
//! [`crate::command`], [`crate::params`], [`crate::snapshot`], [`crate::global`], [`crate::haptic`],
//! [`crate::live`] and [`crate::replay`]): `engine::session::Session` and its companions keep their paths.

pub use crate::command::Command;
pub use crate::error::SessionError;
pub use crate::global::{CutJob, CutReport, CutResult, GlobalCore};
pub use crate::haptic::HapticCore;
pub use crate::live::{Session, SessionIo, SessionReport};
pub use crate::params::{GlobalParams, HapticParams, InputKind, SessionParams, DEVICE_FOLLOW};
pub use crate::replay::replay;
pub use crate::scene::{ffd_map, Guide, Mesh, RenderHair, Scene, SceneOptions};
pub use crate::snapshot::{HapticSnapshot, LatticeSnapshot};
pub use crate::tool::{tool_metaballs, Tool, ToolInput};
