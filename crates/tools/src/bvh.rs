//! Bounding-volume hierarchy (AABB tree) over the straight pieces of strand centrelines, as in the paper's
//! section 4.3. Built once by median splits, then refitted each step (O(n)) as the strands move.

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
    /// Leaf: range of `order`; inner: children indices.
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
    nodes: Vec<Node>,
    order: Vec<usize>,
    /// Grown box of every piece.
    boxes: Vec<Aabb>,
    margin: f64,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Builds the tree over `pieces` with boxes grown by `margin` (m).
    pub fn build(pieces: &[Piece], margin: f64) -> Self {
        let boxes = pieces.iter().map(|p| Aabb::of_segment(&p.a, &p.b, margin)).collect();
        let mut bvh = Self { nodes: Vec::with_capacity(2 * pieces.len() / LEAF_SIZE + 1), order: (0..pieces.len()).collect(), boxes, margin };
        if !pieces.is_empty() {
            bvh.split(pieces, 0, pieces.len());
        }
        bvh
    }

    fn split(&mut self, pieces: &[Piece], start: usize, end: usize) -> usize {
        let bounds = self.order[start..end].iter().fold(Aabb::empty(), |b, &i| b.merge(&self.boxes[i]));
        let id = self.nodes.len();
        self.nodes.push(Node { bounds, kind: NodeKind::Leaf { start, end } });
        if end - start > LEAF_SIZE {
            let extent = bounds.max - bounds.min;
            let axis = extent.imax();
            let mid = (start + end) / 2;
            let centre = |i: usize| (pieces[i].a[axis] + pieces[i].b[axis]) * 0.5;
            self.order[start..end].select_nth_unstable_by(mid - start, |&x, &y| centre(x).total_cmp(&centre(y)));
            let left = self.split(pieces, start, mid);
            let right = self.split(pieces, mid, end);
            self.nodes[id].kind = NodeKind::Inner { left, right };
        }
        id
    }

    /// Margin the boxes are grown by, m.
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Number of pieces the tree was built over.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// True if the tree holds no piece.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Recomputes every box for the pieces' new positions, keeping the tree's topology (same pieces, same order).
    pub fn refit(&mut self, pieces: &[Piece]) {
        for (b, p) in self.boxes.iter_mut().zip(pieces) {
            *b = Aabb::of_segment(&p.a, &p.b, self.margin);
        }
        for id in (0..self.nodes.len()).rev() {
            let bounds = match self.nodes[id].kind {
                NodeKind::Leaf { start, end } => self.order[start..end].iter().fold(Aabb::empty(), |b, &i| b.merge(&self.boxes[i])),
                NodeKind::Inner { left, right } => self.nodes[left].bounds.merge(&self.nodes[right].bounds),
            };
            self.nodes[id].bounds = bounds;
        }
    }

    /// Indices of the pieces whose (grown) boxes overlap `query`, appended to `out`.
    pub fn query(&self, query: &Aabb, out: &mut Vec<usize>) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id];
            if !node.bounds.overlaps(query) {
                continue;
            }
            match node.kind {
                NodeKind::Leaf { start, end } => {
                    out.extend(self.order[start..end].iter().copied().filter(|&i| self.boxes[i].overlaps(query)))
                }
                NodeKind::Inner { left, right } => {
                    stack.push(left);
                    stack.push(right);
                }
            }
        }
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
                got.sort();
                assert_eq!(got, brute(&p, q, 1e-3), "round {round}");
            }
            for (i, piece) in p.iter_mut().enumerate() {
                let d = Vector3::new((i as f64).sin(), (i as f64).cos(), 0.3) * 0.01;
                piece.a += d;
                piece.b += d;
            }
            bvh.refit(&p);
        }
    }
}
