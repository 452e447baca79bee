//! Bounding-volume hierarchy (AABB tree) over the straight pieces of strand centrelines, as in the paper's
//! section 4.3. Built in O(n) without sorting any piece, then refitted each step (O(n)) as the strands move:
//! - each run of consecutive pieces of one strand (a strand's centreline, root to tip) gets a subtree that
//!   halves the run by index: consecutive pieces of a strand are neighbours in space, so the halves are tight
//!   and stay so as the strand bends (a refit keeps them right);
//! - the runs are grouped by median splits of their boxes' centres along the longest axis (a few dozen runs:
//!   the only sorting, over strands, not pieces).
//! A build therefore costs about a refit (the active set changes every few dozen haptic steps; a median split
//! over every piece cost far more than that). A query returns the overlapping pieces in ascending
//! index order, whatever the tree's shape, so what the caller does with them does not depend on the tree.

use crate::geometry::Aabb;
use nalgebra::Vector3;

/// A straight piece of a strand's centreline, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// Which strand (index in the caller's list).
    pub strand: usize,
    /// Arc length of `a` from the strand's root, m.
    pub s: f64,
    /// Length of the piece along the strand, m.
    pub length: f64,
    /// Start point, m.
    pub a: Vector3<f64>,
    /// End point, m.
    pub b: Vector3<f64>,
}

#[derive(Debug, Clone)]
struct Node {
    bounds: Aabb,
    /// Leaf: a range of piece indices; inner: children indices (both after the parent in `nodes`).
    kind: NodeKind,
}

#[derive(Debug, Clone)]
enum NodeKind {
    Leaf { start: usize, end: usize },
    Inner { left: usize, right: usize },
}

/// AABB tree over [`Piece`]s; boxes are grown by a margin (m) to cover a step's motion and the hair radius.
#[derive(Debug, Clone)]
pub struct Bvh {
    /// Parents before their children (a refit walks them backwards).
    nodes: Vec<Node>,
    /// Grown box of every piece.
    boxes: Vec<Aabb>,
    /// Workspace of a build: the runs of one strand's pieces (start, end, box, box centre).
    runs: Vec<(usize, usize, Aabb, Vector3<f64>)>,
    margin: f64,
}

/// Most pieces in a leaf.
const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Builds the tree over `pieces` with boxes grown by `margin` (m).
    pub fn build(pieces: &[Piece], margin: f64) -> Self {
        let mut bvh = Self { nodes: Vec::new(), boxes: Vec::new(), runs: Vec::new(), margin };
        bvh.rebuild(pieces, margin);
        bvh
    }

    /// Builds the tree anew over `pieces` with boxes grown by `margin` (m), in the storage of the old one (no
    /// allocation once it has held as many pieces: fresh pages cost the haptic thread page faults).
    pub fn rebuild(&mut self, pieces: &[Piece], margin: f64) {
        self.margin = margin;
        self.boxes.clear();
        self.boxes.extend(pieces.iter().map(|p| Aabb::of_segment(&p.a, &p.b, margin)));
        self.nodes.clear();
        // Runs of consecutive pieces of the same strand: (start, end, box, centre).
        let mut runs = std::mem::take(&mut self.runs);
        runs.clear();
        let mut start = 0;
        for i in 1..=pieces.len() {
            if i == pieces.len() || pieces[i].strand != pieces[start].strand {
                let b = self.boxes[start..i].iter().fold(Aabb::empty(), |b, x| b.merge(x));
                runs.push((start, i, b, (b.min + b.max) * 0.5));
                start = i;
            }
        }
        if !runs.is_empty() {
            self.group(&mut runs);
        }
        self.runs = runs;
    }

    /// A subtree over `runs` (median splits of their centres), returning its root's index.
    fn group(&mut self, runs: &mut [(usize, usize, Aabb, Vector3<f64>)]) -> usize {
        if let [(start, end, ..)] = runs {
            return self.halve(*start, *end);
        }
        let bounds = runs.iter().fold(Aabb::empty(), |b, r| b.merge(&r.2));
        let id = self.nodes.len();
        self.nodes.push(Node { bounds, kind: NodeKind::Leaf { start: 0, end: 0 } });
        let axis = (bounds.max - bounds.min).imax();
        let mid = runs.len() / 2;
        runs.select_nth_unstable_by(mid, |x, y| x.3[axis].total_cmp(&y.3[axis]));
        let (l, r) = runs.split_at_mut(mid);
        let left = self.group(l);
        let right = self.group(r);
        self.nodes[id].kind = NodeKind::Inner { left, right };
        id
    }

    /// A subtree over the pieces `start..end` (consecutive pieces of one strand), halved by index, returning
    /// its root's index.
    fn halve(&mut self, start: usize, end: usize) -> usize {
        let id = self.nodes.len();
        self.nodes.push(Node { bounds: Aabb::empty(), kind: NodeKind::Leaf { start, end } });
        self.nodes[id].bounds = if end - start > LEAF_SIZE {
            let mid = (start + end) / 2;
            let left = self.halve(start, mid);
            let right = self.halve(mid, end);
            self.nodes[id].kind = NodeKind::Inner { left, right };
            self.nodes[left].bounds.merge(&self.nodes[right].bounds)
        } else {
            self.boxes[start..end].iter().fold(Aabb::empty(), |b, x| b.merge(x))
        };
        id
    }

    /// Margin the boxes are grown by, m.
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Number of pieces the tree was built over.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// True if the tree holds no piece.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// Recomputes every box for the pieces' new positions, keeping the tree's topology (same pieces, same order;
    /// a piece that moved far from its neighbours loosens its nodes' boxes, never makes a query miss it).
    pub fn refit(&mut self, pieces: &[Piece]) {
        for (b, p) in self.boxes.iter_mut().zip(pieces) {
            *b = Aabb::of_segment(&p.a, &p.b, self.margin);
        }
        for id in (0..self.nodes.len()).rev() {
            let bounds = match self.nodes[id].kind {
                NodeKind::Leaf { start, end } => self.boxes[start..end].iter().fold(Aabb::empty(), |b, x| b.merge(x)),
                NodeKind::Inner { left, right } => self.nodes[left].bounds.merge(&self.nodes[right].bounds),
            };
            self.nodes[id].bounds = bounds;
        }
    }

    /// Indices of the pieces whose (grown) boxes overlap `query`, appended to `out` in ascending order.
    pub fn query(&self, query: &Aabb, out: &mut Vec<usize>) {
        if self.nodes.is_empty() {
            return;
        }
        let first = out.len();
        // Depth-first: the stack holds at most one pending sibling per level (the tree's depth is about
        // log2(strands) + log2(pieces per strand / LEAF_SIZE)).
        let mut stack = [0usize; 128];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let id = stack[top];
            let node = &self.nodes[id];
            if !node.bounds.overlaps(query) {
                continue;
            }
            match node.kind {
                NodeKind::Leaf { start, end } => out.extend((start..end).filter(|&i| self.boxes[i].overlaps(query))),
                NodeKind::Inner { left, right } => {
                    stack[top] = right;
                    stack[top + 1] = left;
                    top += 2;
                }
            }
        }
        out[first..].sort_unstable();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pieces(seed: u64, n: usize) -> Vec<Piece> {
        let mut s = seed;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|i| {
                let a = Vector3::new(rnd(), rnd(), rnd()) * 0.2;
                let b = a + Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.01;
                Piece { strand: i / 16, s: (i % 16) as f64 * 0.01, length: 0.01, a, b }
            })
            .collect()
    }

    fn brute(p: &[Piece], q: &Aabb, margin: f64) -> Vec<usize> {
        (0..p.len()).filter(|&i| Aabb::of_segment(&p[i].a, &p[i].b, margin).overlaps(q)).collect()
    }

    #[test]
    fn queries_equal_brute_force_before_and_after_refit() {
        let mut p = pieces(7, 1000);
        let mut bvh = Bvh::build(&p, 1e-3);
        let queries = [
            Aabb { min: Vector3::new(0.05, 0.05, 0.05), max: Vector3::new(0.08, 0.1, 0.07) },
            Aabb { min: Vector3::repeat(-1.0), max: Vector3::repeat(1.0) },
            Aabb { min: Vector3::repeat(0.5), max: Vector3::repeat(0.6) },
        ];
        for round in 0..2 {
            for q in &queries {
                let mut got = vec![];
                bvh.query(q, &mut got);
                assert_eq!(got, brute(&p, q, 1e-3), "round {round}: the overlapping pieces, in ascending order");
            }
            for (i, piece) in p.iter_mut().enumerate() {
                let d = Vector3::new((i as f64).sin(), (i as f64).cos(), 0.3) * 0.01;
                piece.a += d;
                piece.b += d;
            }
            bvh.refit(&p);
        }
    }

    /// Whatever the pieces' order (one strand, a strand in every piece, strands interleaved), the tree finds
    /// exactly the brute-force set, and its leaves hold at most LEAF_SIZE pieces.
    #[test]
    fn any_grouping_of_pieces_gives_the_brute_force_answer() {
        let base = pieces(3, 600);
        let groupings: [(&str, fn(usize) -> usize); 4] =
            [("one strand", |_| 0), ("one piece per strand", |i| i), ("interleaved", |i| i % 7), ("runs of 16", |i| i / 16)];
        for (name, strand) in groupings {
            let p: Vec<Piece> = base.iter().enumerate().map(|(i, x)| Piece { strand: strand(i), ..*x }).collect();
            let bvh = Bvh::build(&p, 2e-3);
            assert!(bvh.nodes.iter().all(|n| match n.kind {
                NodeKind::Leaf { start, end } => end - start <= LEAF_SIZE,
                NodeKind::Inner { .. } => true,
            }), "{name}: leaf sizes");
            for k in 0..50 {
                let c = Vector3::new((k as f64 * 0.37).fract(), (k as f64 * 0.61).fract(), (k as f64 * 0.83).fract()) * 0.2;
                let q = Aabb { min: c.add_scalar(-0.01 - 0.001 * k as f64), max: c.add_scalar(0.01) };
                let mut got = vec![7usize];
                bvh.query(&q, &mut got);
                assert_eq!(got[0], 7, "{name}: what was in `out` stays");
                assert_eq!(got[1..], brute(&p, &q, 2e-3)[..], "{name}: query {k}");
            }
        }
        let empty = Bvh::build(&[], 1e-3);
        let mut got = vec![];
        empty.query(&Aabb { min: Vector3::repeat(-1.0), max: Vector3::repeat(1.0) }, &mut got);
        assert!(got.is_empty() && empty.is_empty());
    }
}
