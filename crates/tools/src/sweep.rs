//! Broad phase of the hair-hair contact ([`crate::hair_contact`]): sweep and prune (Baraff 1992; Cohen et al.
//! 1995) of axis-aligned boxes (m) that belong to groups (strands), listing every pair of boxes of two different
//! groups that overlap on all three axes.
//!
//! The boxes are kept sorted by their lower end along the axis on which they are spread widest relative to their
//! size (a stable sort from the last call's order: about O(n) while they move little). Each box is then tested
//! against the following ones until their lower ends pass its upper end. That scan is the cost (about 11,000
//! pairs a step for the 512 chords of the live comb's 64 strands, most of them apart on another axis), so it runs
//! four boxes at a time in SIMD lanes (`wide::f64x4`) over the boxes' bounds packed per axis in sweep order, and
//! only the pairs whose boxes overlap on every axis leave the lanes. The pairs come out in the same order as the
//! one-at-a-time sweep (each box in sweep order, then its partners in sweep order), so what follows is unchanged.

use crate::geometry::Aabb;
use wide::{f64x4, CmpGt, CmpLe, CmpNe};

/// SIMD lanes of the scan.
const LANES: usize = 4;

/// The sweep's workspaces, kept between calls (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct SweepAndPrune {
    /// Box indices sorted by their lower end along `axis` (kept between calls).
    order: Vec<usize>,
    /// Workspaces of the sort: (lower end as an integer in `f64::total_cmp`'s order, box index), and the lower
    /// ends so, by box.
    keyed: Vec<(i64, usize)>,
    keys: Vec<i64>,
    axis: usize,
    /// The boxes' lower and upper ends in sweep order along `axis`, then along the next axis and the one after
    /// (m), padded for the last lanes; and their groups.
    lo: [Vec<f64>; 3],
    hi: [Vec<f64>; 3],
    group: Vec<f64>,
    /// The pairs found, as positions in sweep order (storage kept between calls).
    hits: Vec<[u32; 2]>,
}

impl SweepAndPrune {
    /// Empty workspaces.
    pub fn new() -> Self {
        Self::default()
    }

    /// The box indices in the last call's sweep order.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// The last call's sweep axis (0, 1, 2: x, y, z).
    pub fn axis(&self) -> usize {
        self.axis
    }

    /// Clears `out` and lists in it every pair `(i, j)` of `boxes` (indices) that overlap on every axis (closed
    /// intervals; a NaN bound never overlaps) and whose `groups` differ, `i` before `j` in the sweep order; in
    /// sweep order of `i`, then of `j`.
    pub fn pairs(&mut self, boxes: &[Aabb], groups: &[usize], out: &mut Vec<(usize, usize)>) {
        assert_eq!(boxes.len(), groups.len(), "one group per box");
        assert!(boxes.len() < u32::MAX as usize - LANES, "at most 2^32 - 5 boxes");
        out.clear();
        let n = boxes.len();
        self.sort(boxes);
        let axes = [self.axis, (self.axis + 1) % 3, (self.axis + 2) % 3];
        // A scan starts at any box, so the lanes may run up to LANES - 1 past the last one.
        let padded = n + LANES;
        for (d, &a) in axes.iter().enumerate() {
            let (lo, hi) = (&mut self.lo[d], &mut self.hi[d]);
            lo.clear();
            hi.clear();
            lo.extend(self.order.iter().map(|&i| boxes[i].min[a]));
            hi.extend(self.order.iter().map(|&i| boxes[i].max[a]));
            // Padding lanes are masked out below; NaN keeps them from ever overlapping besides.
            lo.resize(padded, f64::NAN);
            hi.resize(padded, f64::NAN);
        }
        // Groups as lanes too (exact below 2^53; NaN padding).
        self.group.clear();
        self.group.extend(self.order.iter().map(|&i| groups[i] as f64));
        self.group.resize(padded, f64::NAN);
        let [lo0, lo1, lo2] = &self.lo;
        let [hi0, hi1, hi2] = &self.hi;
        let group = &self.group;
        let lane = |v: &[f64], y: usize| f64x4::from(<[f64; LANES]>::try_from(&v[y..y + LANES]).expect("padded for the last lanes"));
        // A block with pairs writes them without branching on each lane: every lane's positions are stored after the
        // hits among the lanes before it and the count moves past the hits (the hits' storage stays LANES ahead of
        // the count); a block without any (most: boxes apart on another axis) stores nothing.
        let hits = &mut self.hits;
        let mut count = 0;
        for x in 0..n {
            let (p_lo0, p_hi0) = (f64x4::splat(lo0[x]), f64x4::splat(hi0[x]));
            let (p_lo1, p_hi1) = (f64x4::splat(lo1[x]), f64x4::splat(hi1[x]));
            let (p_lo2, p_hi2) = (f64x4::splat(lo2[x]), f64x4::splat(hi2[x]));
            let p_group = f64x4::splat(group[x]);
            let mut y = x + 1;
            while y < n {
                // Lanes y..y + 4 (past n: masked). The sweep stops at the first box whose lower end is past this
                // box's upper end (sorted, so all later ones are too; a NaN bound never stops it).
                let q_lo0 = lane(lo0, y);
                let valid = if n - y >= LANES { 0b1111 } else { (1 << (n - y)) - 1 };
                let stop = q_lo0.cmp_gt(p_hi0).move_mask() & valid;
                let before = if stop == 0 { valid } else { (1 << stop.trailing_zeros()) - 1 };
                let overlap = p_lo0.cmp_le(lane(hi0, y))
                    & q_lo0.cmp_le(p_hi0)
                    & p_lo1.cmp_le(lane(hi1, y))
                    & lane(lo1, y).cmp_le(p_hi1)
                    & p_lo2.cmp_le(lane(hi2, y))
                    & lane(lo2, y).cmp_le(p_hi2)
                    & lane(group, y).cmp_ne(p_group);
                let mask = (overlap.move_mask() & before) as usize;
                if mask != 0 {
                    if hits.len() < count + LANES {
                        hits.resize(2 * (count + LANES), [0; 2]);
                    }
                    for l in 0..LANES {
                        // Lane l goes after the hits among the lanes before it (independent stores, in lane order).
                        hits[count + (mask & ((1 << l) - 1)).count_ones() as usize] = [x as u32, (y + l) as u32];
                    }
                    count += mask.count_ones() as usize;
                }
                if stop != 0 {
                    break;
                }
                y += LANES;
            }
        }
        out.extend(hits[..count].iter().map(|&[x, y]| (self.order[x as usize], self.order[y as usize])));
    }

    /// Chooses the sweep axis (where the boxes' centres spread widest relative to their mean extent) and sorts
    /// `order` by the boxes' lower ends on it: from scratch when the axis or the number of boxes changed, else a
    /// stable sort from the last order.
    fn sort(&mut self, boxes: &[Aabb]) {
        let n = boxes.len();
        let mut score = [0.0f64; 3];
        for (axis, sc) in score.iter_mut().enumerate() {
            let (mut lo, mut hi, mut extent) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
            for b in boxes {
                let m = 0.5 * (b.min[axis] + b.max[axis]);
                lo = lo.min(m);
                hi = hi.max(m);
                extent += b.max[axis] - b.min[axis];
            }
            *sc = if n > 0 { (hi - lo) / (extent / n as f64).max(1e-300) } else { 0.0 };
        }
        let axis = (0..3).fold(0, |b, a| if score[a] > score[b] { a } else { b });
        let key = |i: usize| boxes[i].min[axis];
        let total = |x: f64| {
            let bits = x.to_bits() as i64;
            bits ^ (((bits >> 63) as u64) >> 1) as i64
        };
        if self.order.len() != n || axis != self.axis {
            // From scratch, by the keys as integers in `f64::total_cmp`'s order read from one array (the same
            // comparisons, so the same order, as comparing the boxes' lower ends with `total_cmp`).
            self.keys.clear();
            self.keys.extend(boxes.iter().map(|b| total(b.min[axis])));
            let keys = &self.keys;
            self.order.clear();
            self.order.extend(0..n);
            self.order.sort_unstable_by(|&x, &y| keys[x].cmp(&keys[y]));
            self.axis = axis;
        } else {
            // A stable sort from last call's order (the order an insertion sort would give; -0 and +0 compare
            // equal, as in the insertion sort's `>`; a total order, so no NaN can upset it), on (key, box) pairs
            // side by side, the keys as integers in `f64::total_cmp`'s order. While the boxes move little the order
            // is nearly sorted and an insertion sort finishes in about O(n); when it has moved more than `2 n`
            // entries (strands joined far from those they replaced) a merge sort of the sorted runs takes over
            // from last call's order, which gives the same order in O(n log n) at most.
            let flat = |i: usize| if key(i) == 0.0 { 0.0 } else { key(i) };
            self.keyed.clear();
            self.keyed.extend(self.order.iter().map(|&i| (total(flat(i)), i)));
            if !insertion_sort(&mut self.keyed, 2 * n) {
                self.keyed.clear();
                self.keyed.extend(self.order.iter().map(|&i| (total(flat(i)), i)));
                self.keyed.sort_by_key(|k| k.0);
            }
            self.order.clear();
            self.order.extend(self.keyed.iter().map(|k| k.1));
        }
    }
}

/// Sorts `keyed` by its keys, stably, by insertion, unless that takes more than `budget` moves: then returns false
/// with `keyed` partly sorted.
fn insertion_sort(keyed: &mut [(i64, usize)], budget: usize) -> bool {
    let mut moves = 0;
    for i in 1..keyed.len() {
        let v = keyed[i];
        let mut j = i;
        while j > 0 && keyed[j - 1].0 > v.0 {
            keyed[j] = keyed[j - 1];
            j -= 1;
        }
        keyed[j] = v;
        moves += i - j;
        if moves > budget {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Every pair of boxes in `order` (each before the other in it), overlapping on all axes, of two groups: the
    /// full search in the sweep's order.
    fn all_pairs(boxes: &[Aabb], groups: &[usize], order: &[usize]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (x, &i) in order.iter().enumerate() {
            for &j in &order[x + 1..] {
                let (a, b) = (&boxes[i], &boxes[j]);
                let overlap = (0..3).all(|d| a.min[d] <= b.max[d] && b.min[d] <= a.max[d]);
                if overlap && groups[i] != groups[j] {
                    out.push((i, j));
                }
            }
        }
        out
    }

    fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn the_lanes_list_exactly_the_full_searchs_pairs_in_its_order() {
        // 300 random configurations of 0 to 150 boxes (segments of random direction and length in a 2 x 2 x 4 cm
        // block, grown by 0.1 to 3 mm, in 1 to 12 groups), each swept twice (the second time from the first
        // order, after a small random motion): the same pairs as the full search over the sweep's order, in the
        // same order; the order is sorted by the lower end on the sweep axis; and the number of boxes covers
        // every count of padding lanes. Some boxes share their lower end and some have NaN bounds.
        let mut rnd = rng(11);
        let mut sap = SweepAndPrune::new();
        let mut out = Vec::new();
        let mut total = 0;
        for case in 0..300 {
            let n = (rnd() * 151.0) as usize;
            let groups_n = 1 + (rnd() * 12.0) as usize;
            let grow = 1e-4 + rnd() * 2.9e-3;
            let mut ends: Vec<(Vector3<f64>, Vector3<f64>)> = (0..n)
                .map(|_| {
                    let a = Vector3::new(0.02 * rnd(), 0.02 * rnd(), 0.04 * rnd());
                    let b = a + Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.02 * rnd();
                    (a, b)
                })
                .collect();
            let groups: Vec<usize> = (0..n).map(|_| (rnd() * groups_n as f64) as usize).collect();
            for pass in 0..2 {
                let mut boxes: Vec<Aabb> = ends
                    .iter()
                    .map(|(a, b)| Aabb::of_segment(a, b, grow))
                    .collect();
                if n > 3 && case % 7 == 0 {
                    boxes[1].min = boxes[0].min;
                    boxes[2].max.x = f64::NAN;
                    boxes[3].min.y = f64::NAN;
                }
                sap.pairs(&boxes, &groups, &mut out);
                let order = sap.order().to_vec();
                let key = |i: usize| boxes[i].min[sap.axis()];
                assert!(
                    order.windows(2).all(|w| !(key(w[0]) > key(w[1]))),
                    "case {case} pass {pass}: not sorted"
                );
                let want = all_pairs(&boxes, &groups, &order);
                assert_eq!(out, want, "case {case} pass {pass}: {n} boxes");
                total += want.len();
                for e in ends.iter_mut() {
                    let step = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1e-3;
                    e.0 += step;
                    e.1 += step;
                }
            }
        }
        assert!(total > 10_000, "the configurations touch: {total} pairs");
    }

    #[test]
    fn the_insertion_sort_is_the_stable_sort_or_gives_up_past_its_budget() {
        // 200 random arrays of up to 300 keys with many ties, nearly sorted or shuffled: within its budget the
        // insertion sort gives exactly the stable sort's order (ties in their first order); past it, it says so.
        let mut rnd = rng(3);
        let (mut done, mut gave_up) = (0, 0);
        for case in 0..200 {
            let n = (rnd() * 300.0) as usize;
            let mut keyed: Vec<(i64, usize)> = (0..n).map(|i| (if case % 2 == 0 { (i / 3) as i64 + (rnd() * 2.0) as i64 } else { (rnd() * 40.0) as i64 }, i)).collect();
            let mut want = keyed.clone();
            want.sort_by_key(|k| k.0);
            if insertion_sort(&mut keyed, 2 * n) {
                assert_eq!(keyed, want, "case {case}");
                done += 1;
            } else {
                gave_up += 1;
            }
        }
        assert!(done > 50 && gave_up > 50, "{done} sorted, {gave_up} gave up");
    }

    #[test]
    fn far_boxes_and_one_group_give_no_pair() {
        // Two boxes 1 mm apart on x (no pair); overlapping but of one group (no pair); overlapping, two groups
        // (one pair, the earlier in sweep order first).
        let b = |x: f64| {
            Aabb::of_segment(
                &Vector3::new(x, 0.0, 0.0),
                &Vector3::new(x, 0.0, 0.01),
                1e-4,
            )
        };
        let mut sap = SweepAndPrune::new();
        let mut out = Vec::new();
        sap.pairs(&[b(0.0), b(0.001)], &[0, 1], &mut out);
        assert!(out.is_empty());
        sap.pairs(&[b(0.0), b(0.0001)], &[3, 3], &mut out);
        assert!(out.is_empty());
        sap.pairs(&[b(0.0001), b(0.0)], &[0, 1], &mut out);
        assert_eq!(out, vec![(1, 0)]);
        sap.pairs(&[], &[], &mut out);
        assert!(out.is_empty());
    }
}
