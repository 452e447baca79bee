//! Tool shapes built from capsules and spheres, described in data (TOML), sized in metres.
//!
//! A shape file has a `name`, a `kind` (`comb`, `brush`, `finger`, `clip`, `scissors`, `dryer`, `sprayer`) and
//! any number of `[[capsule]]` (`a`, `b`, `radius`), `[[sphere]]` (`center`, `radius`) and `[[row]]` entries;
//! a row repeats one capsule `count` times, each copy shifted by `step` (the teeth of a comb, the bristles of
//! a brush). Coordinates are in the tool's own frame. Built-in shapes live in `crates/tools/data/`.

use nalgebra::Vector3;
use serde::Deserialize;
use thiserror::Error;

/// What kind of tool a shape is (decides how the engine uses it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToolKind {
    /// Teeth drawn through the hair.
    Comb,
    /// A bristle pad; can also twist strands about its handle axis (tool x).
    Brush,
    /// A single rounded probe.
    Finger,
    /// Pins a point of a strand at the tool origin.
    Clip,
    /// Cuts strands (global layer).
    Scissors,
    /// Blows and dries (global layer).
    Dryer,
    /// Wets (global layer).
    Sprayer,
}

impl ToolKind {
    /// A solid body in the hair (finger, clip, scissors' blades), which the hair volume (the global layer's
    /// lattice) meets as an obstacle. Not the comb and the brush: the hair passes between their 0.4-0.6 mm
    /// teeth or bristles 5-8 mm apart, which 5 cm lattice cells cannot resolve (as an obstacle with the
    /// lattice's 2 cm margin a comb ploughed the hair volume ahead of a slow stroke); not the dryer and the
    /// sprayer, whose tool point is where they aim, their nozzle a hand's distance away. Those act on the
    /// hair through the local strands.
    pub fn lattice_obstacle(self) -> bool {
        matches!(self, ToolKind::Finger | ToolKind::Clip | ToolKind::Scissors)
    }
}

/// A capsule: the points within `radius` of the segment `[a, b]` (tool frame, m).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Capsule {
    /// One end of the axis, m.
    pub a: [f64; 3],
    /// Other end of the axis, m.
    pub b: [f64; 3],
    /// Radius, m.
    pub radius: f64,
}

/// A sphere (tool frame, m).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// Centre, m.
    pub center: [f64; 3],
    /// Radius, m.
    pub radius: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Row {
    count: usize,
    step: [f64; 3],
    capsule: Capsule,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeFile {
    name: String,
    kind: ToolKind,
    #[serde(default)]
    capsule: Vec<Capsule>,
    #[serde(default)]
    sphere: Vec<Sphere>,
    #[serde(default)]
    row: Vec<Row>,
}

/// Error reading a tool shape.
#[derive(Debug, Error)]
pub enum ShapeError {
    /// Not valid TOML, or unknown or missing keys.
    #[error("malformed tool shape: {0}")]
    Malformed(#[from] toml::de::Error),
    /// A value out of range; names the entry.
    #[error("invalid tool shape: {0}")]
    Invalid(String),
    /// No built-in shape of that name.
    #[error("no built-in tool shape {0:?} (known: comb, brush, finger, clip)")]
    Unknown(String),
}

/// A tool's collision shape: capsules and spheres in the tool frame (m). Spheres are capsules of zero length.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolShape {
    /// Name, e.g. "comb".
    pub name: String,
    /// What the tool does.
    pub kind: ToolKind,
    /// Every primitive as a capsule (a sphere has `a == b`).
    pub capsules: Vec<Capsule>,
}

/// Most primitives a shape may have (a guard against runaway rows).
pub const MAX_PRIMITIVES: usize = 10_000;

impl ToolShape {
    /// Parses and checks a shape file's text.
    pub fn from_toml(text: &str) -> Result<Self, ShapeError> {
        let f: ShapeFile = toml::from_str(text)?;
        let mut capsules = f.capsule.clone();
        capsules.extend(f.sphere.iter().map(|s| Capsule { a: s.center, b: s.center, radius: s.radius }));
        for (i, r) in f.row.iter().enumerate() {
            if r.count == 0 || r.count > MAX_PRIMITIVES {
                return Err(ShapeError::Invalid(format!("row {i}: count must be 1..{MAX_PRIMITIVES}, got {}", r.count)));
            }
            let step = Vector3::from(r.step);
            for k in 0..r.count {
                let d = step * k as f64;
                capsules.push(Capsule {
                    a: (Vector3::from(r.capsule.a) + d).into(),
                    b: (Vector3::from(r.capsule.b) + d).into(),
                    radius: r.capsule.radius,
                });
            }
        }
        if capsules.is_empty() {
            return Err(ShapeError::Invalid(format!("shape {:?} has no capsule, sphere or row", f.name)));
        }
        if capsules.len() > MAX_PRIMITIVES {
            return Err(ShapeError::Invalid(format!("{} primitives, more than {MAX_PRIMITIVES}", capsules.len())));
        }
        for (i, c) in capsules.iter().enumerate() {
            let finite = c.a.iter().chain(c.b.iter()).all(|x| x.is_finite());
            if !finite || !(c.radius.is_finite() && c.radius > 0.0) {
                return Err(ShapeError::Invalid(format!("primitive {i}: coordinates must be finite and radius > 0, got {c:?}")));
            }
            if Vector3::from(c.a).amax() > 10.0 || Vector3::from(c.b).amax() > 10.0 || c.radius > 10.0 {
                return Err(ShapeError::Invalid(format!("primitive {i}: larger than 10 m (units are metres), got {c:?}")));
            }
        }
        Ok(Self { name: f.name, kind: f.kind, capsules })
    }

    /// One of the shapes shipped in `crates/tools/data/`: "comb", "brush", "finger", "clip".
    pub fn builtin(name: &str) -> Result<Self, ShapeError> {
        let text = match name {
            "comb" => include_str!("../data/comb.toml"),
            "brush" => include_str!("../data/brush.toml"),
            "finger" => include_str!("../data/finger.toml"),
            "clip" => include_str!("../data/clip.toml"),
            other => return Err(ShapeError::Unknown(other.to_string())),
        };
        Self::from_toml(text)
    }

    /// Smallest primitive radius, m (sets how finely a fast motion is sub-stepped to avoid tunnelling).
    pub fn min_radius(&self) -> f64 {
        self.capsules.iter().map(|c| c.radius).fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_shapes_load() {
        let comb = ToolShape::builtin("comb").unwrap();
        assert_eq!(comb.kind, ToolKind::Comb);
        assert_eq!(comb.capsules.len(), 26, "spine + 25 teeth");
        let last = comb.capsules.last().unwrap();
        assert!((last.a[0] - 0.06).abs() < 1e-12, "25 teeth 5 mm apart from -6 cm end at +6 cm");
        assert!((comb.min_radius() - 0.0006).abs() < 1e-15);
        assert_eq!(ToolShape::builtin("brush").unwrap().capsules.len(), 2 + 35);
        assert_eq!(ToolShape::builtin("finger").unwrap().kind, ToolKind::Finger);
        let clip = ToolShape::builtin("clip").unwrap();
        assert_eq!(clip.capsules.len(), 3);
        assert!(matches!(ToolShape::builtin("rake"), Err(ShapeError::Unknown(_))));
    }

    #[test]
    fn bad_shapes_are_reported() {
        let bad = [
            ("name = \"x\"\nkind = \"comb\"\n", "no capsule"),
            ("name = \"x\"\nkind = \"rake\"\n[[sphere]]\ncenter=[0,0,0]\nradius=0.1\n", "kind"),
            ("name = \"x\"\nkind = \"comb\"\n[[sphere]]\ncenter=[0,0,0]\nradius=-0.1\n", "radius"),
            ("name = \"x\"\nkind = \"comb\"\n[[sphere]]\ncenter=[0,0,nan]\nradius=0.1\n", "finite"),
            ("name = \"x\"\nkind = \"comb\"\n[[sphere]]\ncentre=[0,0,0]\nradius=0.1\n", "centre"),
            ("name = \"x\"\nkind = \"comb\"\n[[row]]\ncount=0\nstep=[0,0,0]\ncapsule={a=[0,0,0],b=[0,0,1],radius=0.1}\n", "count"),
            ("name = \"x\"\nkind = \"comb\"\n[[sphere]]\ncenter=[0,0,50]\nradius=0.1\n", "metres"),
            ("name = ", "malformed"),
        ];
        for (text, word) in bad {
            let err = ToolShape::from_toml(text).unwrap_err().to_string();
            assert!(err.contains(word), "{text:?}: {err}");
        }
    }
}
