//! Hair-hair contact in the local layer: which simulated strands touch, found cheaply enough for the 1 kHz
//! loop, as pairs of points for the soft constraint solve (non-penetration and Coulomb friction).
//!
//! Pipeline of [`HairContactFinder::detect`] (no allocation once the workspaces have grown):
//! 1. **Chords**: each strand's sampled centreline pieces are merged into chords, one per helical segment
//!    (the segment's start to its end), with a box grown by half the contact distance.
//! 2. **Broad phase** ([`crate::sweep`]): sweep and prune (Baraff 1992; Cohen et al. 1995) along the axis on which
//!    the chords are spread widest relative to their boxes' size, four boxes at a time in SIMD lanes: the pairs of
//!    chords of two strands whose boxes overlap on every axis, in sweep order (a hashed uniform grid of
//!    chord-sized cells was tried first: on the haptic-loop bench it cost more, see bench/RESULTS.md).
//! 3. **Narrow phase**: closest points of the two chords; closer than the contact distance, a contact (four pairs
//!    at a time in SIMD lanes reject those that are apart first, [`crate::segments4`]).
//! 4. **Reduction**: each strand keeps at most one contact per (chord, other strand) and at most
//!    [`HairContact::max_per_strand`] contacts, the deepest.
//!
//! Each kept contact is one [`HairPair`]: a non-penetration contact with Coulomb friction between two strands'
//! points, solved for both strands at once in the same soft constraint solve as the tool's and the body's
//! contacts (`strand::constraint::solve` with a `ConstraintLink`: the relative velocity of the two points and
//! the sum of their mobilities), so neither strand sees the other as a moving obstacle of the last step.

use crate::bvh::Piece;
use crate::geometry::{closest_segment_params, Aabb};
use crate::segments4::may_be_closer;
use crate::sweep::SweepAndPrune;
use nalgebra::Vector3;
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
    /// The chord in the strand's rest shape (NaN: none; see [`HairContactFinder::detect`]), m.
    rest_a: Vector3<f64>,
    rest_b: Vector3<f64>,
}

/// A contact one strand keeps: the other strand, both chords, the overlap (m), both points' arc lengths (m) and
/// the normal towards this strand.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Slot {
    other: usize,
    chord: usize,
    other_chord: usize,
    depth: f64,
    s: f64,
    other_s: f64,
    normal: Vector3<f64>,
}

/// One contact between two simulated strands: the `first` strand's point at arc length `s.0` and the `second`
/// strand's at `s.1` (m) are closer than the contact distance by `depth` (m); `normal` is the unit vector from
/// the second point towards the first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairPair {
    /// The two strands (first, second).
    pub strands: (usize, usize),
    /// Arc lengths of the two points from their roots, m.
    pub s: (f64, f64),
    /// Unit normal from the second strand's point towards the first's.
    pub normal: Vector3<f64>,
    /// Overlap of the two wisps, m (> 0).
    pub depth: f64,
}

/// The workspaces of hair-hair contact detection, kept between steps (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct HairContactFinder {
    chords: Vec<Chord>,
    /// The chords' boxes (grown by half the contact distance; m) and strands, the broad phase's input, and its
    /// output: pairs of chords (indices into `chords`) whose boxes overlap, of two strands, in sweep order.
    boxes: Vec<Aabb>,
    groups: Vec<usize>,
    /// The chords' ends (`a`, `b`; m) side by side, for the narrow phase's lanes.
    ends: Vec<[Vector3<f64>; 2]>,
    sweep: SweepAndPrune,
    candidates: Vec<(usize, usize)>,
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

    /// The contacts kept by the last detection, each pair of points once: every contact some strand kept among
    /// its deepest `max_per_strand` (so a strand may take part in more than `max_per_strand` of them, those the
    /// other strand kept).
    pub fn contacts(&self) -> impl Iterator<Item = HairPair> + '_ {
        let cap = self.cap;
        let mine = move |k: usize| &self.slots[k * cap..k * cap + self.filled[k]];
        (0..self.filled.len()).flat_map(move |k| {
            mine(k)
                .iter()
                .filter(move |sl| sl.other > k || !mine(sl.other).iter().any(|o| o.other == k && o.chord == sl.other_chord && o.other_chord == sl.chord))
                .map(move |sl| HairPair { strands: (k, sl.other), s: (sl.s, sl.other_s), normal: sl.normal, depth: sl.depth })
        })
    }

    /// Finds the contacts between the `strands` strands whose centreline `pieces` are given (contiguous per
    /// strand, in order from the root; `pieces_per_chord(k)` pieces of strand k make one chord, e.g. the pieces
    /// of one helical segment), for wisps whose centrelines touch at `distance` (m).
    ///
    /// `rest` (empty, or one piece per piece of `pieces`, NaN where a strand has none) gives the strands' rest
    /// shapes: two chords that are closer than `distance` at rest touch only closer than their rest distance
    /// (wisps that overlap in the groom keep that overlap instead of being pushed apart; the depth is measured
    /// from it).
    pub fn detect(&mut self, params: &HairContact, pieces: &[Piece], rest: &[Piece], pieces_per_chord: impl Fn(usize) -> usize, strands: usize, distance: f64) {
        let has_rest = rest.len() == pieces.len();
        self.chords.clear();
        self.boxes.clear();
        self.ends.clear();
        self.groups.clear();
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
            let (rest_a, rest_b) = if has_rest { (rest[i].a, rest[j].b) } else { (Vector3::repeat(f64::NAN), Vector3::repeat(f64::NAN)) };
            self.chords.push(Chord { strand: k, index, s: pieces[i].s, length, a, b, rest_a, rest_b });
            self.boxes.push(Aabb::of_segment(&a, &b, half));
            self.ends.push([a, b]);
            self.groups.push(k);
            index += 1;
            i = j + 1;
        }
        self.sweep.pairs(&self.boxes, &self.groups, &mut self.candidates);
        // Reduction workspace.
        self.cap = params.max_per_strand;
        self.filled.clear();
        self.filled.resize(strands, 0);
        let empty = Slot { other: 0, chord: 0, other_chord: 0, depth: 0.0, s: 0.0, other_s: 0.0, normal: Vector3::zeros() };
        self.slots.clear();
        self.slots.resize(strands * self.cap, empty);
        self.pairs = 0;
        self.tested = 0;
        // Narrow phase, four candidates at a time: the lanes reject the pairs that are apart, the scalar test
        // decides on the others, in the broad phase's order.
        let m = self.candidates.len();
        let mut k = 0;
        while k < m {
            let lanes = (m - k).min(4);
            let chord = |l: usize| {
                let (i, j) = self.candidates[k + l.min(lanes - 1)];
                (&self.ends[i], &self.ends[j])
            };
            let (c0, c1, c2, c3) = (chord(0), chord(1), chord(2), chord(3));
            let found = may_be_closer([&c0.0[0], &c1.0[0], &c2.0[0], &c3.0[0]], [&c0.0[1], &c1.0[1], &c2.0[1], &c3.0[1]], [&c0.1[0], &c1.1[0], &c2.1[0], &c3.1[0]], [&c0.1[1], &c1.1[1], &c2.1[1], &c3.1[1]], distance);
            self.tested += lanes;
            for l in 0..lanes {
                if found.through & (1 << l) != 0 {
                    let (nx, ny) = self.candidates[k + l];
                    let closest = (found.exact & (1 << l) != 0).then(|| (found.s[l], found.t[l]));
                    self.touch(nx, ny, closest, distance);
                }
            }
            k += lanes;
        }
    }

    /// The narrow phase's exact test of the chords `nx` and `ny` (indices into `chords`, in the broad phase's
    /// order) with their closest points' parameters `closest` when the lanes found them (`closest_segment_params`'
    /// own), else found here: closer than the contact `distance` (m; or than their rest distance), a contact
    /// offered to both strands.
    fn touch(&mut self, nx: usize, ny: usize, closest: Option<(f64, f64)>, distance: f64) {
        let (p, q) = (&self.chords[nx], &self.chords[ny]);
        let (u, v) = closest.unwrap_or_else(|| closest_segment_params(&p.a, &p.b, &q.a, &q.b));
        let (xp, xq) = (p.a + (p.b - p.a) * u, q.a + (q.b - q.a) * v);
        let gap = xp - xq;
        let dist = gap.norm();
        if dist >= distance || dist < 1e-12 * distance {
            return;
        }
        // Closer than the contact distance at rest (both rest chords known): the rest distance is theirs.
        let mut limit = distance;
        if p.rest_a.x.is_finite() && q.rest_a.x.is_finite() {
            let (u0, v0) = closest_segment_params(&p.rest_a, &p.rest_b, &q.rest_a, &q.rest_b);
            limit = limit.min(((p.rest_a + (p.rest_b - p.rest_a) * u0) - (q.rest_a + (q.rest_b - q.rest_a) * v0)).norm());
            if dist >= limit {
                return;
            }
        }
        self.pairs += 1;
        let depth = limit - dist;
        let normal = gap / dist;
        let (sp, sq) = (p.s + u * p.length, q.s + v * q.length);
        let (kp, kq, ip, iq) = (p.strand, q.strand, p.index, q.index);
        keep(&mut self.slots, &mut self.filled, self.cap, kp, Slot { other: kq, chord: ip, other_chord: iq, depth, s: sp, other_s: sq, normal });
        keep(&mut self.slots, &mut self.filled, self.cap, kq, Slot { other: kp, chord: iq, other_chord: ip, depth, s: sq, other_s: sp, normal: -normal });
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
            grid.detect(&params, &pieces, &[], |_| 3, xs.len(), distance);
            let want = brute(&pieces, distance);
            println!("distance {distance}: {} pairs (brute force {want}), {} tested", grid.pairs(), grid.tested());
            assert!(want > 0);
            assert_eq!(grid.pairs(), want, "distance {distance}");
            if distance == 2e-4 {
                assert!(grid.tested() * 20 < 112_320, "{} pairs tested", grid.tested());
            }
        }
    }

    /// The contacts the full search finds: every pair of chords of two strands in the last sweep's order (no broad
    /// phase, no lanes) through the exact test, into fresh slots.
    fn full_search(found: &HairContactFinder, distance: f64) -> (usize, Vec<HairPair>) {
        let mut full = found.clone();
        full.filled.iter_mut().for_each(|f| *f = 0);
        full.pairs = 0;
        let order = found.sweep.order().to_vec();
        for (x, &i) in order.iter().enumerate() {
            for &j in &order[x + 1..] {
                if full.chords[i].strand != full.chords[j].strand {
                    full.touch(i, j, None, distance);
                }
            }
        }
        (full.pairs, full.contacts().collect())
    }

    #[test]
    fn the_contacts_are_the_full_searchs_over_random_moving_tresses() {
        // 60 random tresses of 2 to 40 wavy strands (1 to 12 chords of 1 to 4 pieces) in a 1 x 1 cm patch, with
        // rest shapes for some, each moved over 8 steps (small random motions, and a strand leaving or joining
        // between steps, which changes the number of chords), contact distances 0.3 to 3 mm, caps 1 to 6: at
        // every step the same contacts as the full search of all chord pairs in the sweep's order, bit for bit
        // and in the same order, and the same number of touching pairs.
        let mut seed = 5u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut total = 0;
        for case in 0..60 {
            let n = 2 + (rnd() * 39.0) as usize;
            let per = 1 + (rnd() * 4.0) as usize;
            let chords = 1 + (rnd() * 12.0) as usize;
            let distance = 3e-4 + 2.7e-3 * rnd();
            let params = HairContact { max_per_strand: 1 + (rnd() * 6.0) as usize, ..Default::default() };
            let shape = |root: (f64, f64), phase: f64, amp: f64, k: usize| -> Vec<Piece> {
                let m = per * chords;
                let l = 0.02 / m as f64;
                let at = |s: f64| Vector3::new(root.0 + amp * (40.0 * s + phase).sin(), root.1 + amp * (25.0 * s + phase).cos(), 0.3 - s);
                (0..m).map(|i| Piece { strand: k, s: i as f64 * l, length: l, a: at(i as f64 * l), b: at((i + 1) as f64 * l) }).collect()
            };
            let mut roots: Vec<((f64, f64), f64, f64)> = (0..n).map(|_| ((0.01 * rnd(), 0.01 * rnd()), 6.0 * rnd(), 0.004 * rnd())).collect();
            let with_rest = case % 3 == 0;
            let mut finder = HairContactFinder::new();
            for step in 0..8 {
                if step == 4 && roots.len() > 2 {
                    roots.remove((rnd() * roots.len() as f64) as usize);
                }
                if step == 6 {
                    roots.push(((0.01 * rnd(), 0.01 * rnd()), 6.0 * rnd(), 0.004 * rnd()));
                }
                let pieces: Vec<Piece> = roots.iter().enumerate().flat_map(|(k, r)| shape(r.0, r.1, r.2, k)).collect();
                let rest: Vec<Piece> = if with_rest {
                    roots.iter().enumerate().flat_map(|(k, r)| shape(r.0, r.1 + 0.3, r.2, k)).collect()
                } else {
                    Vec::new()
                };
                finder.detect(&params, &pieces, &rest, |_| per, roots.len(), distance);
                let found: Vec<HairPair> = finder.contacts().collect();
                let (pairs, want) = full_search(&finder, distance);
                assert_eq!(finder.pairs(), pairs, "case {case} step {step}");
                assert_eq!(found, want, "case {case} step {step}");
                total += found.len();
                for r in roots.iter_mut() {
                    r.0 .0 += 2e-4 * (rnd() - 0.5);
                    r.0 .1 += 2e-4 * (rnd() - 0.5);
                    r.1 += 0.05 * (rnd() - 0.5);
                }
            }
        }
        assert!(total > 2_000, "the tresses touch: {total} contacts");
    }

    #[test]
    fn each_strand_keeps_its_deepest_contacts_within_the_cap() {
        // Strand 0 at x = 0 beside strands at 0.5, 0.8 and 1.2 mm and a far one at 5 mm (contact distance
        // 1.5 mm): with a cap of 2, strand 0 keeps 2 contacts, both against the nearest strand (overlap 1 mm, the
        // deepest; on two different chords), the normal pointing from strand 1 to strand 0 (-x); the far strand
        // has none; every pair is listed once.
        let xs = [(0.0, 0.0), (0.0005, 0.0), (0.0008, 0.0), (0.0012, 0.0), (0.005, 0.0)];
        let pieces = strands(&xs, 4);
        let params = HairContact { max_per_strand: 2, ..Default::default() };
        let mut grid = HairContactFinder::new();
        grid.detect(&params, &pieces, &[], |_| 3, xs.len(), 1.5e-3);
        let all: Vec<HairPair> = grid.contacts().collect();
        let of = |k: usize| all.iter().filter(move |p| p.strands.0 == k || p.strands.1 == k);
        let zero: Vec<&HairPair> = of(0).collect();
        assert_eq!(zero.len(), 2, "{zero:?}");
        for p in &zero {
            assert_eq!(p.strands, (0, 1), "strand 0 keeps its contacts with strand 1 (the deepest)");
            assert!(p.normal.x < -0.99, "from strand 1 towards strand 0 (-x): {}", p.normal);
            // 0.5 mm apart along x, tilted by 0.02: 0.5 mm / sqrt(1 + 0.02^2) apart; the overlap is the contact
            // distance minus that, to round-off.
            let want = 1.5e-3 - 0.5e-3 / (1.0f64 + 0.02 * 0.02).sqrt();
            assert!((p.depth - want).abs() < 1e-12, "depth {}, want {want}", p.depth);
        }
        assert_eq!(of(4).count(), 0);
        // No pair twice (in either order).
        for (i, p) in all.iter().enumerate() {
            for q in &all[i + 1..] {
                let same = |a: &HairPair, b: &HairPair| a.strands == b.strands && (a.s.0 - b.s.0).abs() < 1e-12 && (a.s.1 - b.s.1).abs() < 1e-12;
                let mirrored = HairPair { strands: (q.strands.1, q.strands.0), s: (q.s.1, q.s.0), ..*q };
                assert!(!same(p, q) && !same(p, &mirrored), "{p:?} listed twice");
            }
        }
    }

    #[test]
    fn wisps_overlapping_at_rest_touch_only_closer_than_their_rest_distance() {
        // Two strands 0.5 mm apart at rest (contact distance 1.5 mm). With their rest shapes given, in the rest
        // shape there is no contact; moved to 0.3 mm apart the overlap is measured from the rest distance
        // (0.5 - 0.3 mm, to round-off); a third strand that is 1 mm from strand 0 now and had no rest shape
        // (NaN) is measured against the full distance. Without rest shapes the rest configuration is in contact.
        let params = HairContact::default();
        let rest = strands(&[(0.0, 0.0), (0.0005, 0.0), (0.01, 0.0)], 2);
        let mut grid = HairContactFinder::new();
        grid.detect(&params, &rest, &rest, |_| 3, 3, 1.5e-3);
        assert_eq!(grid.contacts().count(), 0, "at rest, overlapping wisps are left as they are");
        grid.detect(&params, &rest, &[], |_| 3, 3, 1.5e-3);
        assert!(grid.contacts().count() > 0, "without rest shapes they are in contact");
        let now = strands(&[(0.0, 0.0), (0.0003, 0.0), (0.001, 0.0)], 2);
        let mut with_nan = rest.clone();
        for p in with_nan.iter_mut().filter(|p| p.strand == 2) {
            p.a = Vector3::repeat(f64::NAN);
            p.b = Vector3::repeat(f64::NAN);
        }
        grid.detect(&params, &now, &with_nan, |_| 3, 3, 1.5e-3);
        let tilt = (1.0f64 + 0.02 * 0.02).sqrt();
        let all: Vec<HairPair> = grid.contacts().collect();
        let pair = |a: usize, b: usize| all.iter().filter(move |p| p.strands == (a, b));
        assert!(pair(0, 1).count() > 0 && pair(0, 2).count() > 0, "{all:?}");
        // Parallel chords are 0.3 / tilt mm apart now and 0.5 / tilt at rest; chords meeting end to end at the
        // same arc length 0.3 and 0.5 mm: the overlap from the rest distance is one of the two.
        for p in pair(0, 1) {
            let (lo, hi) = ((0.5e-3 - 0.3e-3) / tilt, 0.5e-3 - 0.3e-3);
            assert!(p.depth > lo - 1e-12 && p.depth < hi + 1e-12, "depth from the rest distance: {} want {lo}..{hi}", p.depth);
        }
        for p in pair(0, 2) {
            let want = 1.5e-3 - 1e-3 / tilt;
            assert!((p.depth - want).abs() < 1e-12, "no rest shape: depth from the contact distance: {} want {want}", p.depth);
        }
    }
}
