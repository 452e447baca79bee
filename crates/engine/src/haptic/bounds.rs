//! What the active set's choice ([`super::active`]) needs to pass over what cannot come near the tool: each
//! guide's carried shape bounded ([`GuideBounds`]) and the capsules farther than the distance found ([`nearer`]).

use nalgebra::Vector3;
use tools::geometry::{point_segment_distance, Aabb};

/// Each capsule's segment's box ([`Aabb::of_segment`], no margin), for [`nearer`].
pub(crate) fn segment_boxes(caps: &[(Vector3<f64>, Vector3<f64>, f64)]) -> Vec<Aabb> {
    caps.iter().map(|(a, b, _)| Aabb::of_segment(a, b, 0.0)).collect()
}

/// The least of `d` and the distances from `q` to the capsules `caps` (ends and radius, m, with their segments' boxes
/// `boxes`, [`segment_boxes`]), m: a capsule whose box is farther than `d` cannot lower it and is passed over (the
/// slack, 1e-12 m, is far above the rounding of either distance), the same number as taking every capsule.
pub(crate) fn nearer(q: &Vector3<f64>, caps: &[(Vector3<f64>, Vector3<f64>, f64)], boxes: &[Aabb], mut d: f64) -> f64 {
    for ((a, b, rad), bx) in caps.iter().zip(boxes) {
        if bx.distance_to(q) - rad > d + 1e-12 {
            continue;
        }
        d = d.min(point_segment_distance(q, a, b) - rad);
    }
    d
}

/// Each guide's carried shape bounded, so that the choice's scan passes over the guides far from the tool
/// without carrying their samples by the head and the lattice. The carried hair keeps its rest segment lengths
/// with its root where the head holds it (`scene::carry_strand`), so every carried sample of guide g lies
/// within the guide's length `radii[g]` of its root `centres[g]` carried by the head.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GuideBounds {
    /// Each guide's root (head frame), m.
    pub(crate) centres: Vec<Vector3<f64>>,
    /// Its reference's length (rounding allowance included), m.
    pub(crate) radii: Vec<f64>,
    /// Per guide, per reference sample: the reference's length from that sample to the tip (rounding allowance
    /// included), m. Carried sample k lies within it of every carried sample before it, so a scan that finds a
    /// sample farther than that from the tool's reach passes over the rest of the guide.
    pub(crate) beyond: Vec<Vec<f64>>,
}

impl GuideBounds {
    /// Rounding allowance on each radius, m: the ball test must never pass over a guide the samples' own test
    /// would choose.
    const ROUNDING: f64 = 1e-9;

    /// The bounds of the scene's guides.
    pub fn new(scene: &crate::scene::Scene) -> Self {
        let centres = scene.guides.iter().map(|g| g.reference.first().copied().unwrap_or_default()).collect();
        let radii = scene.guides.iter().map(|g| g.reference.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>() * (1.0 + 1e-12) + Self::ROUNDING).collect();
        let beyond = scene
            .guides
            .iter()
            .map(|g| {
                let mut left: Vec<f64> = g.reference.windows(2).rev().scan(0.0, |sum, w| {
                    *sum += (w[1] - w[0]).norm();
                    Some(*sum)
                }).collect();
                left.reverse();
                left.push(0.0);
                left.iter().map(|l| l * (1.0 + 1e-12) + Self::ROUNDING).collect()
            })
            .collect();
        Self { centres, radii, beyond }
    }
}
