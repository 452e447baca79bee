//! Hair-hair contact in the local layer: which simulated strands touch, found cheaply enough for the 1 kHz
//! loop, and the point constraints (non-penetration and Coulomb friction) each strand takes from them.
//!
//! Pipeline of [`HairContactFinder::detect`] (no allocation once the workspaces have grown):
//! 1. **Chords**: each strand's sampled centreline pieces are merged into chords, one per helical segment
//!    (the segment's start to its end), with a box grown by half the contact distance.
//! 2. **Broad phase**: sweep and prune (Baraff 1992; Cohen et al. 1995) along the axis on which the chords are
//!    spread widest relative to their boxes' size: the chords are kept sorted by their boxes' lower end on that
//!    axis (insertion sort from the last step's order: O(n) while the strands move little), and each chord is
//!    tested against the following ones until their boxes start beyond its own (a hashed uniform grid of
//!    chord-sized cells was tried first: on the haptic-loop bench it cost more, see bench/RESULTS.md).
//! 3. **Narrow phase**: closest points of the two chords; closer than the contact distance, a contact.
//! 4. **Reduction**: each strand keeps at most one contact per (chord, other strand) and at most
//!    [`HairContact::max_per_strand`] contacts, the deepest.
//!
//! Each strand sees the other strand's point as an obstacle moving with that point's velocity over the last
//! step and is pushed out by half the overlap (the other half is the other strand's); the strands are solved
//! one after the other with last step's neighbours (one Jacobi iteration between strands per haptic step; the
//! soft constraints' compliance keeps it stable).

use crate::bvh::Piece;
use crate::geometry::{closest_segment_params, Aabb};
use nalgebra::Vector3;
use strand::constraint::{ConstraintKind, PointConstraint};
use strand::StrandError;

/// Contact and Coulomb friction between the simulated strands (the local layer's hair-hair interaction), in the
/// same soft constraint solve as the tool's contacts (`strand::constraint::ConstraintOptions` gives their
/// compliance).
///
/// Each simulated strand stands for a wisp of `fibres` real fibres, and two wisps touch when their centrelines
/// come closer than twice the wisp's radius `r_w = r_f sqrt(fibres / packing)` (`r_f` the fibre's semi-major
/// axis): the fibres of a wisp fill a round section at the packing fraction `packing`. For one fibre per strand
/// (`fibres = 1`, `packing = 1`) the contact distance is the fibre diameter. Wetness raises `friction` through
/// `crate::wetness::WetnessModel::friction` (the same law as the tool's friction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairContact {
    /// Real fibres each simulated strand stands for (dimensionless, >= 1). Default 1.
    pub fibres: f64,
    /// Packing fraction of the fibres in a wisp's round section (dimensionless, (0, 1]). Default 0.5 (a
    /// combed tress: hexagonal close packing of cylinders is 0.91, loose hair about 0.3).
    pub packing: f64,
    /// Fibre-fibre Coulomb friction coefficient (dimensionless, >= 0). Default 0.25 (dry hair on hair,
    /// Robbins 2012 ch. 8: about 0.2 with the scales, 0.3 against them).
    pub friction: f64,
    /// Most hair-hair contacts one strand takes per step, deepest first (bounds the solve's cost). Default 4.
    pub max_per_strand: usize,
}

impl Default for HairContact {
    fn default() -> Self {
        Self { fibres: 1.0, packing: 0.5, friction: 0.25, max_per_strand: 4 }
    }
}

impl HairContact {
    /// Contact distance between two strands' centrelines for fibres of semi-major axis `fibre_radius` (m):
    /// twice the wisp radius `r_f sqrt(fibres / packing)`, m.
    pub fn distance(&self, fibre_radius: f64) -> f64 {
        2.0 * fibre_radius * (self.fibres / self.packing).sqrt()
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), StrandError> {
        let bad = |field: &'static str, reason: String| Err(StrandError::InvalidParameter { field, reason });
        if !(self.fibres.is_finite() && self.fibres >= 1.0) {
            return bad("hair_contact.fibres", format!("must be >= 1, got {}", self.fibres));
        }
        if !(self.packing.is_finite() && self.packing > 0.0 && self.packing <= 1.0) {
            return bad("hair_contact.packing", format!("must be in (0, 1], got {}", self.packing));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return bad("hair_contact.friction", format!("must be >= 0, got {}", self.friction));
        }
        Ok(())
    }
}

/// A straight chord of one strand's centreline (one helical segment), m.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Chord {
    strand: usize,
    /// Index of the chord along its strand.
    index: usize,
    /// Arc length of `a`, m, and the chord's arc length, m.
    s: f64,
    length: f64,
    a: Vector3<f64>,
    b: Vector3<f64>,
    bounds: Aabb,
}

/// A contact one strand keeps: the other strand, this strand's chord, the overlap (m) and the constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Slot {
    other: usize,
    chord: usize,
    depth: f64,
    constraint: PointConstraint,
}

/// The workspaces of hair-hair contact detection, kept between steps (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct HairContactFinder {
    chords: Vec<Chord>,
    last: Vec<Chord>,
    /// Chord indices sorted by their boxes' lower end along `axis` (kept between steps).
    order: Vec<usize>,
    axis: usize,
    /// Per strand: `max_per_strand` slots and how many are filled.
    slots: Vec<Slot>,
    filled: Vec<usize>,
    cap: usize,
    pairs: usize,
    tested: usize,
}

impl HairContactFinder {
    /// Empty workspaces.
    pub fn new() -> Self {
        Self::default()
    }

    /// Pairs of chords in contact found by the last [`HairContactFinder::detect`] (before the reduction).
    pub fn pairs(&self) -> usize {
        self.pairs
    }

    /// Chord pairs tested in the narrow phase by the last detection (the broad phase's output).
    pub fn tested(&self) -> usize {
        self.tested
    }

    /// The hair-hair constraints strand `strand` takes this step (at most `max_per_strand`).
    pub fn constraints(&self, strand: usize) -> impl Iterator<Item = PointConstraint> + '_ {
        let n = self.filled.get(strand).copied().unwrap_or(0);
        self.slots[strand * self.cap..strand * self.cap + n].iter().map(|s| s.constraint)
    }

    /// Finds the contacts between the `strands` strands whose centreline `pieces` are given (contiguous per
    /// strand, in order from the root; `pieces_per_chord(k)` pieces of strand k make one chord, e.g. the pieces
    /// of one helical segment), for wisps whose centrelines touch at `distance` (m). Velocities are taken over
    /// the last `dt` seconds from the last call's chords (zero if the layout changed).
    pub fn detect(&mut self, params: &HairContact, pieces: &[Piece], pieces_per_chord: impl Fn(usize) -> usize, strands: usize, distance: f64, dt: f64) {
        std::mem::swap(&mut self.chords, &mut self.last);
        self.chords.clear();
        let half = 0.5 * distance;
        let mut i = 0;
        let mut index = 0;
        while i < pieces.len() {
            let k = pieces[i].strand;
            if i > 0 && pieces[i - 1].strand != k {
                index = 0;
            }
            let group = pieces_per_chord(k).max(1);
            let mut j = i;
            while j + 1 < pieces.len() && j + 1 < i + group && pieces[j + 1].strand == k {
                j += 1;
            }
            let (a, b) = (pieces[i].a, pieces[j].b);
            let length = pieces[j].s + pieces[j].length - pieces[i].s;
            self.chords.push(Chord { strand: k, index, s: pieces[i].s, length, a, b, bounds: Aabb::of_segment(&a, &b, half) });
            index += 1;
            i = j + 1;
        }
        let same_layout = self.last.len() == self.chords.len() && self.last.iter().zip(&self.chords).all(|(p, q)| p.strand == q.strand && p.index == q.index);
        // The sweep axis: where the chords' centres spread widest relative to their boxes' mean extent.
        let n = self.chords.len();
        let mut score = [0.0f64; 3];
        for (axis, sc) in score.iter_mut().enumerate() {
            let (mut lo, mut hi, mut extent) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
            for c in &self.chords {
                let m = 0.5 * (c.bounds.min[axis] + c.bounds.max[axis]);
                lo = lo.min(m);
                hi = hi.max(m);
                extent += c.bounds.max[axis] - c.bounds.min[axis];
            }
            *sc = if n > 0 { (hi - lo) / (extent / n as f64).max(1e-300) } else { 0.0 };
        }
        let axis = (0..3).fold(0, |b, a| if score[a] > score[b] { a } else { b });
        let chords = &self.chords;
        let key = |i: usize| chords[i].bounds.min[axis];
        if self.order.len() != n || axis != self.axis {
            self.order.clear();
            self.order.extend(0..n);
            self.order.sort_unstable_by(|&x, &y| key(x).total_cmp(&key(y)));
            self.axis = axis;
        } else {
            // Insertion sort from last step's order (nearly sorted: about O(n)).
            for i in 1..n {
                let mut j = i;
                while j > 0 && key(self.order[j - 1]) > key(self.order[j]) {
                    self.order.swap(j - 1, j);
                    j -= 1;
                }
            }
        }
        // Reduction workspace.
        self.cap = params.max_per_strand;
        self.filled.clear();
        self.filled.resize(strands, 0);
        let empty = Slot { other: 0, chord: 0, depth: 0.0, constraint: PointConstraint { s: 0.0, kind: ConstraintKind::Pin { target: Vector3::zeros() }, velocity: Vector3::zeros() } };
        self.slots.clear();
        self.slots.resize(strands * self.cap, empty);
        self.pairs = 0;
        self.tested = 0;
        for x in 0..n {
            let nx = self.order[x];
            let p = &self.chords[nx];
            for y in x + 1..n {
                let ny = self.order[y];
                let q = &self.chords[ny];
                if q.bounds.min[axis] > p.bounds.max[axis] {
                    break;
                }
                if p.strand == q.strand || !p.bounds.overlaps(&q.bounds) {
                    continue;
                }
                self.tested += 1;
                let (u, v) = closest_segment_params(&p.a, &p.b, &q.a, &q.b);
                let (xp, xq) = (p.a + (p.b - p.a) * u, q.a + (q.b - q.a) * v);
                let gap = xp - xq;
                let dist = gap.norm();
                if dist >= distance || dist < 1e-12 * distance {
                    continue;
                }
                self.pairs += 1;
                let velocity = |c: &Chord, n: usize, t: f64| {
                    if same_layout {
                        let o = &self.last[n];
                        ((c.a - o.a) * (1.0 - t) + (c.b - o.b) * t) / dt
                    } else {
                        Vector3::zeros()
                    }
                };
                let (vp, vq) = (velocity(p, nx, u), velocity(q, ny, v));
                let depth = distance - dist;
                let normal = gap / dist;
                let contact = |normal: Vector3<f64>| ConstraintKind::Contact { normal, depth: 0.5 * depth, friction: params.friction };
                let (sp, sq) = (p.s + u * p.length, q.s + v * q.length);
                let (kp, kq, ip, iq) = (p.strand, q.strand, p.index, q.index);
                keep(&mut self.slots, &mut self.filled, self.cap, kp, Slot { other: kq, chord: ip, depth, constraint: PointConstraint { s: sp, kind: contact(normal), velocity: vq } });
                keep(&mut self.slots, &mut self.filled, self.cap, kq, Slot { other: kp, chord: iq, depth, constraint: PointConstraint { s: sq, kind: contact(-normal), velocity: vp } });
            }
        }
    }
}

/// Offers a contact to strand `k` (each strand has `cap` of the `slots`, `filled[k]` of them in use): it replaces a
/// shallower one on the same (chord, other strand), else takes a free slot, else replaces the strand's shallowest
/// contact if deeper.
fn keep(slots: &mut [Slot], filled: &mut [usize], cap: usize, k: usize, slot: Slot) {
    if cap == 0 || k >= filled.len() {
        return;
    }
    let base = k * cap;
    let n = filled[k];
    let mine = &mut slots[base..base + cap];
    if let Some(same) = mine[..n].iter_mut().find(|s| s.other == slot.other && s.chord == slot.chord) {
        if slot.depth > same.depth {
            *same = slot;
        }
        return;
    }
    if n < cap {
        mine[n] = slot;
        filled[k] += 1;
        return;
    }
    let (weakest, depth) = mine.iter().enumerate().map(|(i, s)| (i, s.depth)).fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b });
    if slot.depth > depth {
        mine[weakest] = slot;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Straight vertical strands of `chords` chords of 1 cm each (3 pieces per chord), roots at `xs` (m).
    fn strands(xs: &[(f64, f64)], chords: usize) -> Vec<Piece> {
        let mut out = Vec::new();
        for (k, &(x, y)) in xs.iter().enumerate() {
            for i in 0..3 * chords {
                let (s, l) = (i as f64 * 0.01 / 3.0, 0.01 / 3.0);
                let at = |s: f64| Vector3::new(x + 0.02 * s, y, 0.3 - s);
                out.push(Piece { strand: k, s, length: l, a: at(s), b: at(s + l) });
            }
        }
        out
    }

    fn brute(pieces: &[Piece], distance: f64) -> usize {
        // Chords by hand, every pair of different strands.
        let chords: Vec<(usize, Vector3<f64>, Vector3<f64>)> = pieces.chunks(3).map(|c| (c[0].strand, c[0].a, c[2].b)).collect();
        let mut n = 0;
        for i in 0..chords.len() {
            for j in i + 1..chords.len() {
                if chords[i].0 == chords[j].0 {
                    continue;
                }
                let (u, v) = closest_segment_params(&chords[i].1, &chords[i].2, &chords[j].1, &chords[j].2);
                let d = ((chords[i].1 + (chords[i].2 - chords[i].1) * u) - (chords[j].1 + (chords[j].2 - chords[j].1) * v)).norm();
                if d < distance {
                    n += 1;
                }
            }
        }
        n
    }

    #[test]
    fn the_sweep_finds_every_touching_pair_once() {
        // A pseudo-random tress of 40 strands of 12 chords in a 6 x 3 mm rectangle: the sweep finds exactly the
        // chord pairs a brute-force test of all pairs finds (no pair missed, none counted twice), for contact
        // distances from 0.2 to 3 mm, twice (the second time from the first one's order). At 0.2 mm it sends
        // fewer than 5 % of the 112,320 pairs of chords of different strands to the narrow phase.
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let xs: Vec<(f64, f64)> = (0..40).map(|_| (0.006 * rnd(), 0.003 * rnd())).collect();
        let pieces = strands(&xs, 12);
        let params = HairContact { max_per_strand: 1000, ..Default::default() };
        let mut grid = HairContactFinder::new();
        for distance in [2e-4, 2e-4, 1e-3, 1e-3, 3e-3] {
            grid.detect(&params, &pieces, |_| 3, xs.len(), distance, 1e-3);
            let want = brute(&pieces, distance);
            println!("distance {distance}: {} pairs (brute force {want}), {} tested", grid.pairs(), grid.tested());
            assert!(want > 0);
            assert_eq!(grid.pairs(), want, "distance {distance}");
            if distance == 2e-4 {
                assert!(grid.tested() * 20 < 112_320, "{} pairs tested", grid.tested());
            }
        }
    }

    #[test]
    fn each_strand_keeps_its_deepest_contacts_within_the_cap() {
        // Strand 0 at x = 0 beside strands at 0.5, 0.8 and 1.2 mm and a far one at 5 mm (contact distance
        // 1.5 mm): with a cap of 2, strand 0 keeps 2 contacts, both against the nearest strand (overlap 1 mm, the
        // deepest; on two different chords), pushing it away (-x); the far strand has none.
        let xs = [(0.0, 0.0), (0.0005, 0.0), (0.0008, 0.0), (0.0012, 0.0), (0.005, 0.0)];
        let pieces = strands(&xs, 4);
        let params = HairContact { max_per_strand: 2, ..Default::default() };
        let mut grid = HairContactFinder::new();
        grid.detect(&params, &pieces, |_| 3, xs.len(), 1.5e-3, 1e-3);
        let mine: Vec<PointConstraint> = grid.constraints(0).collect();
        assert_eq!(mine.len(), 2);
        for c in &mine {
            let ConstraintKind::Contact { normal, depth, .. } = c.kind else { panic!("not a contact") };
            assert!(normal.x < -0.99, "pushed towards -x: {normal}");
            // Against strand 1 (0.5 mm apart along x, tilted by 0.02: 0.5 mm / sqrt(1 + 0.02^2) apart; the overlap
            // is the contact distance minus that, half of it each), to round-off.
            let want = 0.5 * (1.5e-3 - 0.5e-3 / (1.0f64 + 0.02 * 0.02).sqrt());
            assert!((depth - want).abs() < 1e-12, "depth {depth}, want {want}");
        }
        assert_eq!(grid.constraints(4).count(), 0);
        // Strand 1 touches 0, 2 and 3 (and keeps 2 of them); every strand keeps at most the cap.
        assert!((0..5).all(|k| grid.constraints(k).count() <= 2));
    }

    #[test]
    fn contact_velocities_come_from_the_last_step() {
        // Two touching strands; the second moves +y by 1 mm between calls (dt 1 ms): the first strand's obstacle
        // moves at 1 m/s along y.
        let xs = [(0.0, 0.0), (0.001, 0.0)];
        let params = HairContact::default();
        let mut grid = HairContactFinder::new();
        grid.detect(&params, &strands(&xs, 2), |_| 3, 2, 1.5e-3, 1e-3);
        let moved = [(0.0, 0.0), (0.001, 0.001)];
        grid.detect(&params, &strands(&moved, 2), |_| 3, 2, 1.5e-3, 1e-3);
        let c: Vec<PointConstraint> = grid.constraints(0).collect();
        assert!(!c.is_empty());
        for c in c {
            assert!((c.velocity - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-9, "{}", c.velocity);
        }
    }
}
