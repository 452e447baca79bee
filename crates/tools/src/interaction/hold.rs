//! The hold of the hair volume on a simulated strand: its place among the unsimulated neighbours, pulled towards
//! with the strand's weight per hold distance, in turns.

use super::LocalInteraction;
use nalgebra::Vector3;
use strand::PointForce;

/// Loads per held strand that carry the hold ([`LocalInteraction::hold_distance`]).
pub const HOLD_LOADS: usize = 4;

/// A held strand gets its hold every this many steps, that many times as strong (in turns: strand `k` at the
/// steps where the step count modulo this is `k` modulo this). 4 ms at 1 kHz against the hold's period
/// `2 pi sqrt(hold_distance / |g|)` (0.35 s at the live session's 3 cm), so the impulses act as the steady
/// spring.
pub const HOLD_EVERY: usize = 4;

/// The hold's spring per unit mass, `omega^2 = |g| / hold_distance`, 1/s^2, for gravity `g` (m/s^2) and the
/// hold distance (m): each piece of a held strand is pulled towards its place with its own weight per hold
/// distance. 0 without a hold (the distance not finite or not positive). The one hold law: the local strands'
/// loads ([`LocalInteraction::hold_strands`]) and the engine's relaxation of handed-over guides both use it.
pub fn hold_rate(gravity: f64, hold_distance: f64) -> f64 {
    if hold_distance.is_finite() && hold_distance > 0.0 { gravity.abs() / hold_distance } else { 0.0 }
}

/// Where the hair volume holds a simulated strand: its place among the unsimulated neighbours (e.g. the
/// groomed strand carried by the global layer's lattice), as points evenly spaced in arc length.
#[derive(Debug, Clone, PartialEq)]
pub struct Hold {
    /// Points from the root (first) to the tip (last) of the uncut strand, evenly spaced in arc length, m
    /// (the strands' frame); at least two.
    pub points: Vec<Vector3<f64>>,
    /// The uncut strand's length the points span, m.
    pub length: f64,
}

impl Hold {
    /// The hold's point at arc length `s` (m; clamped to the points' span), linearly interpolated.
    pub fn at(&self, s: f64) -> Vector3<f64> {
        strand::samples::lerp(&self.points, s / self.length.max(1e-12))
    }
}

impl LocalInteraction {
    /// The hold of the unsimulated neighbours ([`LocalInteraction::hold_distance`]) as loads for this step:
    /// from last step's collision pieces (the strands' points at the start of that step; none right after
    /// the strands changed), each held strand's pieces in [`HOLD_LOADS`] runs along its length, each run one
    /// load at its pieces' mean arc length: the sum of `-k length (midpoint - hold point)` over its pieces.
    /// A strand is held every [`HOLD_EVERY`] steps (strand index modulo, in turns), that many times as
    /// strongly: the same impulse over that time, at a quarter of the cost per step.
    pub(super) fn hold_strands(&mut self) {
        self.hold_phase = (self.hold_phase + 1) % HOLD_EVERY;
        if !(self.params.hold_distance > 0.0 && self.params.hold_distance.is_finite()) || self.ws.rebuild_tree || self.holds.is_empty() {
            return;
        }
        let mut i = 0;
        while i < self.pieces.len() {
            // The pieces are contiguous per strand, in strand order.
            let k = self.pieces[i].strand;
            let end = i + self.pieces[i..].iter().take_while(|p| p.strand == k).count();
            let pieces = i..end;
            i = end;
            if k % HOLD_EVERY != self.hold_phase {
                continue;
            }
            for load in self.hold_loads(k, pieces).into_iter().flatten() {
                // Not finite (never expected): left out.
                self.add_load(k, load);
            }
        }
    }

    /// The hold's [`HOLD_LOADS`] loads on strand `k` (see [`LocalInteraction::hold_strands`]) from its collision
    /// pieces `pieces` (indices into the last step's pieces): forces in N at the runs' mean arc lengths in m,
    /// [`HOLD_EVERY`] times the spring's; None for a run without pieces, or for all if the strand is not held.
    pub(super) fn hold_loads(&self, k: usize, pieces: std::ops::Range<usize>) -> [Option<PointForce>; HOLD_LOADS] {
        let mut loads = [None; HOLD_LOADS];
        let (Some(Some(hold)), Some(strand)) = (self.holds.get(k), self.strands.get(k)) else { return loads };
        // Spring per unit length, N/m per m, times HOLD_EVERY (this strand's turn stands for that many steps).
        let stiffness = HOLD_EVERY as f64 * strand.model.linear_density() * hold_rate(self.params.hold_gravity.unwrap_or_else(|| strand.model.gravity.norm()), self.params.hold_distance);
        let length = strand.model.length.max(1e-9);
        // Per run along the strand: sum of s x piece length (m^2), of piece lengths (m), of forces (N).
        let mut runs = [(0.0, 0.0, Vector3::zeros()); HOLD_LOADS];
        for p in &self.pieces[pieces] {
            let s = p.s + 0.5 * p.length;
            let run = &mut runs[((s / length * HOLD_LOADS as f64) as usize).min(HOLD_LOADS - 1)];
            run.0 += s * p.length;
            run.1 += p.length;
            run.2 -= (0.5 * (p.a + p.b) - hold.at(s)) * (stiffness * p.length);
        }
        for (load, (sw, w, f)) in loads.iter_mut().zip(runs) {
            if w > 0.0 {
                *load = Some(PointForce::new(sw / w, f));
            }
        }
        loads
    }
}
