//! The live tools: the toolbar's [`Tool`]s and their shapes, what the global layer reads of the tool each
//! step ([`ToolInput`]: the scissors' blade, the nozzles' cone), and the tool as a metaball obstacle for the
//! lattice.

use crate::params::GlobalParams;
use hairstyle::cut::Blade;
use lattice::metaball::{Metaball, MetaballSet};
use nalgebra::{Matrix3, Point3, Vector3};
use tools::dryer::Cone;
use tools::shape::ToolShape;

/// The tools of the toolbar, with their wire ids (docs/protocol.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Tool {
    /// Comb (teeth drawn through the hair).
    Comb = 0,
    /// Brush (bristle pad; twists strands).
    Brush = 1,
    /// Scissors: cuts the strands the blades close on (while the primary button is held).
    Scissors = 2,
    /// Hair dryer: lowers wetness in its cone.
    Dryer = 3,
    /// Water sprayer: raises wetness in its cone.
    Sprayer = 4,
    /// Clip: pins the strand point nearest its jaws while the primary button is held.
    Clip = 5,
}

impl Tool {
    /// All tools in wire order.
    pub const ALL: [Tool; 6] = [Tool::Comb, Tool::Brush, Tool::Scissors, Tool::Dryer, Tool::Sprayer, Tool::Clip];
    /// The tool's name: "comb", "brush", "scissors", "dryer", "sprayer", "clip".
    pub fn name(self) -> &'static str {
        ["comb", "brush", "scissors", "dryer", "sprayer", "clip"][self as usize]
    }
    /// The tool with wire id `id`, if any.
    pub fn from_id(id: u8) -> Option<Tool> {
        Self::ALL.get(id as usize).copied()
    }
    /// The tool's shape (capsules and spheres, tool frame, m): what is solid of it. The nozzles' (dryer,
    /// sprayer) is their nozzle, a 2 cm ball `nozzle_standoff` m (`GlobalParams::nozzle_standoff`) behind the
    /// tool point along the tool's +z: the tool point is where the jet aims, air, nothing solid.
    pub fn shape(self, nozzle_standoff: f64) -> ToolShape {
        let builtin = |n: &str| ToolShape::builtin(n).expect("built-in shapes parse (tested in tools)");
        let inline = |t: &str| ToolShape::from_toml(t).expect("inline shapes parse (tested below)");
        match self {
            Tool::Comb => builtin("comb"),
            Tool::Brush => builtin("brush"),
            Tool::Clip => builtin("clip"),
            // Closed blades: two thin capsules along the tool's x axis.
            Tool::Scissors => inline(SCISSORS_TOML),
            // Nozzles: the nozzle's body, behind the aim point.
            Tool::Dryer | Tool::Sprayer => inline(&NOZZLE_TOML.replace("NAME", self.name()).replace("STANDOFF", &format!("{nozzle_standoff:e}"))),
        }
    }
}

const SCISSORS_TOML: &str = "name = \"scissors\"\nkind = \"scissors\"\n[[capsule]]\na = [-0.04, 0.0, 0.0]\nb = [0.04, 0.0, 0.0]\nradius = 0.0015\n";
const NOZZLE_TOML: &str = "name = \"NAME\"\nkind = \"NAME\"\n[[sphere]]\ncenter = [0.0, 0.0, STANDOFF]\nradius = 0.02\n";

/// What the global layer reads of the tool each step: published by the haptic thread after every haptic
/// step, kept in the record for replay ([`Record::global_inputs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolInput {
    /// Selected tool.
    pub tool: Tool,
    /// False until the device gave a reading (the tool then acts on nothing).
    pub present: bool,
    /// Tool proxy position (world, m).
    pub position: Vector3<f64>,
    /// Tool rotation (tool frame to world).
    pub rotation: Matrix3<f64>,
    /// Primary button held (dryer blowing, sprayer spraying).
    pub pressed: bool,
    /// Scissors closes so far: the global layer cuts the render strands once per increment, with the blade
    /// of [`ToolInput::blade`].
    pub cuts: u64,
    /// The head pose (head frame to world) the haptic thread has (`Command::SetHead`): the global layer
    /// takes it for its next step. Default identity.
    pub head: nalgebra::Isometry3<f64>,
}

impl Default for ToolInput {
    fn default() -> Self {
        Self { tool: Tool::Comb, present: false, position: Vector3::zeros(), rotation: Matrix3::identity(), pressed: false, cuts: 0, head: nalgebra::Isometry3::identity() }
    }
}


impl ToolInput {
    /// The scissors' cutting disk: centred on the proxy, in the plane normal to the tool's y axis (the
    /// stroke direction), radius `radius` (m; `GlobalParams::blade_radius`).
    pub fn blade(&self, radius: f64) -> Blade {
        let n = self.rotation.column(1).into_owned();
        Blade { point: self.position.into(), normal: n.into(), radius }
    }
    /// The nozzle's cone (dryer, sprayer): axis along the tool's -z, apex `standoff` (m;
    /// `GlobalParams::nozzle_standoff`) back from the
    /// proxy along +z (the viewer puts the tool where the mouse points on the hair: the nozzle aims there
    /// from a hand's distance, as a dryer or a sprayer is held).
    pub fn cone(&self, mut cone: Cone, standoff: f64) -> Cone {
        cone.apex = self.position + self.rotation.column(2).into_owned() * standoff;
        cone.axis = -self.rotation.column(2).into_owned();
        cone
    }
}

/// The tool as a metaball set (world frame): balls along each capsule, spaced at `obstacle_spacing` of
/// their radius, whose iso-surface (at the default threshold, 0.707 R for a lone ball) lies
/// `obstacle_margin` outside the capsule, so the lattice feels it.
pub fn tool_metaballs(shape: &ToolShape, position: &Vector3<f64>, rotation: &Matrix3<f64>, params: &GlobalParams) -> MetaballSet {
    let mut balls = Vec::new();
    for c in &shape.capsules {
        let r = (c.radius + params.obstacle_margin) / 0.707;
        let (a, b) = (rotation * Vector3::from(c.a) + position, rotation * Vector3::from(c.b) + position);
        let n = (((b - a).norm() / (params.obstacle_spacing * r)).ceil() as usize).clamp(1, params.obstacle_max_balls);
        for k in 0..=n {
            let p = a + (b - a) * (k as f64 / n as f64);
            balls.push(Metaball::new(Point3::from(p), r));
        }
    }
    MetaballSet::new(balls)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_tool_shapes_parse() {
        for t in Tool::ALL {
            assert!(!t.shape(0.15).capsules.is_empty(), "{t:?}");
        }
        // Nothing of a nozzle is within 10 cm of its aim point (the tool point): its body is at the nozzle.
        for t in [Tool::Dryer, Tool::Sprayer] {
            let s = t.shape(0.15);
            for c in &s.capsules {
                let d = tools::geometry::point_segment_distance(&Vector3::zeros(), &Vector3::from(c.a), &Vector3::from(c.b)) - c.radius;
                assert!(d > 0.1, "{t:?}: solid {d} m from the aim point");
                assert!((Vector3::from(c.a) - Vector3::new(0.0, 0.0, 0.15)).norm() < 1e-12);
            }
        }
        assert_eq!(Tool::from_id(5), Some(Tool::Clip));
        assert_eq!(Tool::from_id(6), None);
    }
}
