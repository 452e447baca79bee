//! Snapshots exchanged between the threads through triple buffers: the lattice (global thread) and the
//! haptic state (haptic thread).

use nalgebra::{Matrix3, Point3, Vector3};
use std::sync::Arc;

/// A lattice snapshot: node positions (world, m) and the global step that produced it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LatticeSnapshot {
    /// Global steps done (0: the rest state).
    pub version: u64,
    /// Node positions, m.
    pub positions: Vec<Point3<f64>>,
    /// Wall time of the step, s (information).
    pub step_seconds: f64,
    /// Mean wetness in [0, 1] of each guide (over its segments' `WetnessField` values).
    pub wetness: Vec<f32>,
    /// Changes of `kept` so far (scissors cuts and resets): the viewer re-reads `kept` when it changes.
    pub kept_version: u64,
    /// Points kept of each render strand (vertices 0..kept stay on the head; V: uncut).
    pub kept: Arc<Vec<u16>>,
    /// The falling cut clusters' chains: node positions (world, m), one list per chain.
    pub chains: Vec<Vec<[f32; 3]>>,
    /// The head pose of this step (head frame to world).
    pub head: nalgebra::Isometry3<f64>,
}

/// What the haptic thread publishes for the viewer.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HapticSnapshot {
    /// Haptic steps done.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Selected tool (wire id).
    pub tool: u8,
    /// Tool proxy pose (what touches the hair).
    pub tool_position: Vector3<f64>,
    /// Tool rotation (tool frame to world).
    pub tool_rotation: Matrix3<f64>,
    /// Device point (where the mouse put the device), m.
    pub device_position: Vector3<f64>,
    /// Force on the user's hand, N.
    pub force: Vector3<f64>,
    /// Contacts in the last step.
    pub contacts: u32,
    /// Active guides (indices into the scene's guides).
    pub active: Vec<u32>,
    /// Displacement of each active guide's samples from its reference mapped through the lattice, m
    /// (active.len() * samples entries).
    pub displacement: Vec<Vector3<f64>>,
    /// Lattice version the last step used.
    pub lattice_version: u64,
    /// Steps in which the runaway guard put the tool proxy back on the device (`HapticCore::runaways`,
    /// `HapticParams::max_proxy_lag`), since the session started.
    pub runaways: u64,
    /// The hair's surface treatment (`HapticParams::treatment`, set by [`crate::command::Command::SetTreatment`]).
    pub treatment: tools::treatment::Treatment,
    /// The tool-hair friction coefficient in use (the hair type's, with the treatment, the wetness of the
    /// simulated strands and the combing ease; 0 for the paper's force model).
    pub tool_friction: f64,
}
