//! Warm starts: what each constraint of a strand was at the last step (tool contact or drag on a capsule, pin,
//! body, hair-hair contact) and its impulse, to start the next step's solve from it.

use super::LocalInteraction;
use nalgebra::Vector3;
use strand::constraint::ConstraintRows;

/// One side of a hair-hair contact: the `pair`-th pair of the step ([`HairContactFinder::contacts`]), at its first
/// strand's point or (`second`) at its second strand's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct HairSide {
    pub(super) pair: usize,
    pub(super) second: bool,
    /// The pair's other strand.
    pub(super) other: usize,
}

/// What a strand's constraint is, to find the same constraint at the next step (with its arc length): a tool
/// contact or drag on a capsule, a pin (its index among the pins), a body contact, a hair-hair contact with another
/// strand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum WarmTag {
    Tool(usize),
    Drag(usize),
    Pin(usize),
    Body,
    Hair(usize),
}

/// A constraint's impulse at the last step (N s), with what it was and where (arc length, m): the solve of the
/// next step starts from it ([`LocalInteraction::warm_start`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Warm {
    pub(super) tag: WarmTag,
    pub(super) s: f64,
    pub(super) impulse: Vector3<f64>,
}

impl LocalInteraction {
    /// Warm start: each constraint of `rows` (what each is and where: `tags`) starts the solve from the impulse of
    /// the same constraint at the last step (`last`): the same kind on the same capsule, pin or other strand, the
    /// nearest in arc length within a quarter of a segment (`segment`, m; each impulse of the last step is used
    /// once). The solve then needs fewer sweeps while the contacts persist.
    /// `used`: workspace (which of `last` are taken), storage kept between calls.
    pub(super) fn warm_start(last: &[Warm], tags: &[(WarmTag, f64)], segment: f64, used: &mut Vec<bool>, rows: &mut ConstraintRows) {
        if last.is_empty() {
            return;
        }
        used.clear();
        used.resize(last.len(), false);
        let within = 0.25 * segment;
        for (c, &(tag, s)) in tags.iter().enumerate() {
            let best = last.iter().enumerate().filter(|(i, w)| w.tag == tag && !used[*i] && (w.s - s).abs() <= within).min_by(|a, b| (a.1.s - s).abs().total_cmp(&(b.1.s - s).abs()));
            if let Some((i, w)) = best {
                used[i] = true;
                rows.warm_start(c, &w.impulse);
            }
        }
    }
}
