//! The shown guides' reference samples carried by the head and the lattice ([`carried`](crate::scene::carried)),
//! for [`HapticCore::snapshot`](super::HapticCore::snapshot): the viewer's displacement of a sample is its
//! strand point minus this base.
//!
//! Mapping every reference sample through the FFD on every published snapshot was a large share of the
//! haptic thread's step. A reference sample never moves, so its FFD stencil (27 node indices and weights) is
//! found once per
//! guide while the guide is shown, and the bases are summed again only when the lattice nodes or the head
//! change (at the global rate, not the publish rate). The numbers are the same as
//! [`Scene::guide_points`]'s: the same stencil and the same sum ([`FfdLattice::combine`]), blended with the
//! head's rigid motion by the same weight, then the same [`follow_the_leader`].

use lattice::ffd::FfdLattice;
use nalgebra::{Isometry3, Point3, Vector3};

use crate::scene::{follow_the_leader, Scene};

/// The viewer's snapshots of the simulated strands (`HapticCore::snapshot`, `HapticCore::stage_snapshot`, which
/// take `&self`, hence the cells; the core lives on one thread).
#[derive(Debug, Default)]
pub(crate) struct Shown {
    /// The shown guides' reference samples mapped through the lattice, kept between snapshots.
    pub references: std::cell::RefCell<ReferenceCache>,
    /// The next snapshot's staged displacements, one per shown guide.
    pub staged: std::cell::RefCell<Vec<Staged>>,
}

/// One simulated guide's displacements staged for the next snapshot ([`HapticCore::stage_snapshot`](super::HapticCore::stage_snapshot)).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Staged {
    /// The guide.
    pub guide: usize,
    /// The haptic step they were mapped at.
    pub step: u64,
    /// Its samples' shown displacements, m.
    pub displacement: Vec<Vector3<f64>>,
}

/// One guide's stencils and bases.
#[derive(Debug, Clone)]
struct Entry {
    guide: usize,
    /// Each reference sample's FFD stencil (None: the sample could not be located, e.g. NaN; it maps to itself).
    stencils: Vec<Option<([usize; 27], [f64; 27])>>,
    /// Each reference sample's weight of the lattice's motion (`Scene::guide_hold_weights`).
    weights: Vec<f64>,
    /// The bases for the nodes in [`ReferenceCache::nodes`], m (head frame).
    bases: Vec<Vector3<f64>>,
    /// Whether the bases are for the current nodes.
    fresh: bool,
}

/// Per shown guide, its reference samples mapped through the lattice nodes last seen.
#[derive(Debug, Clone, Default)]
pub(crate) struct ReferenceCache {
    /// The lattice nodes the fresh bases were mapped through, m (empty: none yet).
    nodes: Vec<Point3<f64>>,
    /// The head pose they were carried by.
    head: Isometry3<f64>,
    entries: Vec<Entry>,
}

impl ReferenceCache {
    /// Maps through `nodes` and the head at `head` from now on: the bases become stale if either changed
    /// (compared exactly, so a cached base is never from other nodes).
    pub fn use_nodes(&mut self, nodes: &[Point3<f64>], head: &Isometry3<f64>) {
        if !self.is_for(nodes, head) {
            self.head = *head;
            self.nodes.clear();
            self.nodes.extend_from_slice(nodes);
            for e in &mut self.entries {
                e.fresh = false;
            }
        }
    }

    /// The reference samples of `guide` carried by the head and the nodes given to [`use_nodes`](Self::use_nodes)
    /// (`ok`: they are the lattice's nodes; otherwise the references carried by the head alone), m.
    pub fn bases<'a>(&'a mut self, scene: &'a Scene, guide: usize, ok: bool) -> &'a [Vector3<f64>] {
        let i = match self.entries.iter().position(|e| e.guide == guide) {
            Some(i) => i,
            None => {
                let reference = &scene.guides[guide].reference;
                let ffd: &FfdLattice = &scene.lattice.ffd;
                let stencils = reference.iter().map(|p| ffd.weights_clamped(&Point3::from(*p)).ok()).collect();
                self.entries.push(Entry { guide, stencils, weights: scene.guide_hold_weights(guide), bases: Vec::new(), fresh: false });
                self.entries.len() - 1
            }
        };
        self.entry_bases(i, scene, ok)
    }

    /// As [`bases`](Self::bases) with `ok`, for a guide it already holds (a shown guide's), or None: one search
    /// of the entries, and no entry made for a guide it does not hold.
    pub fn held_bases<'a>(&'a mut self, scene: &'a Scene, guide: usize) -> Option<&'a [Vector3<f64>]> {
        let i = self.entries.iter().position(|e| e.guide == guide)?;
        Some(self.entry_bases(i, scene, true))
    }

    /// Entry `i`'s bases, mapped again if stale.
    fn entry_bases<'a>(&'a mut self, i: usize, scene: &'a Scene, ok: bool) -> &'a [Vector3<f64>] {
        let reference = &scene.guides[self.entries[i].guide].reference;
        let e = &mut self.entries[i];
        if !e.fresh {
            e.bases.clear();
            for ((s, p), &w) in e.stencils.iter().zip(reference).zip(&e.weights) {
                // As `scene::carried`: the head's rigid motion, blended into the FFD by the sample's weight.
                let rigid = (self.head * Point3::from(*p)).coords;
                let base = match (ok && w > 0.0, s.as_ref()) {
                    (true, Some((idx, fw))) => rigid + (FfdLattice::combine(idx, fw, &self.nodes) - rigid) * w,
                    (true, None) => rigid + (*p - rigid) * w,
                    (false, _) => rigid,
                };
                e.bases.push(base);
            }
            follow_the_leader(reference, &self.head, &mut e.bases);
            e.fresh = true;
        }
        &e.bases
    }

    /// Whether its bases are for the nodes `nodes` and the head at `head` (those last given to
    /// [`use_nodes`](Self::use_nodes)).
    pub fn is_for(&self, nodes: &[Point3<f64>], head: &Isometry3<f64>) -> bool {
        self.nodes.as_slice() == nodes && self.head == *head
    }

    /// Whether it holds `guide`'s stencils (a shown guide's). The scan asks [`held_bases`](Self::held_bases);
    /// this is for the tests.
    #[cfg(test)]
    pub fn holds(&self, guide: usize) -> bool {
        self.entries.iter().any(|e| e.guide == guide)
    }

    /// The head pose the bases are carried by (the one last given to [`use_nodes`](Self::use_nodes)).
    pub fn head(&self) -> &Isometry3<f64> {
        &self.head
    }

    /// Whether the nodes last given are a lattice's of `count` nodes.
    pub fn has_nodes(&self, count: usize) -> bool {
        self.nodes.len() == count
    }

    /// Drops the guides not in `shown` (those no snapshot shows any more).
    pub fn keep_only(&mut self, shown: &[u32]) {
        self.entries.retain(|e| shown.contains(&(e.guide as u32)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::GlobalCore;
    use crate::params::SessionParams;
    use crate::testing::small_scene;

    /// The rest nodes moved by a smooth field scaled by `a` (m), so every stencil sees different nodes.
    fn moved(nodes: &[Point3<f64>], a: f64) -> Vec<Point3<f64>> {
        nodes.iter().map(|p| p + Vector3::new(a * (7.0 * p.y).sin(), a * (5.0 * p.z).cos(), -a * p.x)).collect()
    }

    #[test]
    fn bases_equal_the_carried_references_exactly_and_follow_the_nodes_and_the_head() {
        // The cache must give bit-for-bit the numbers of carrying each reference sample afresh
        // (`Scene::guide_points`), also after the nodes or the head change (stale bases would differ by ~mm here)
        // and for guides dropped and re-shown.
        let scene = small_scene();
        let rest = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot().positions;
        let mut cache = ReferenceCache::default();
        let guides = [0, scene.guides.len() / 2, scene.guides.len() - 1];
        for (round, a) in [0.0, 3e-3, 3e-3, -2e-3, -2e-3].into_iter().enumerate() {
            let nodes = moved(&rest, a);
            let head = if round == 4 { Isometry3::new(Vector3::new(0.0, 0.01, 0.0), Vector3::new(0.0, 0.0, 0.2)) } else { Isometry3::identity() };
            cache.use_nodes(&nodes, &head);
            // Round 2 shows one guide only, so the others are dropped and made again in round 3.
            let shown: &[usize] = if round == 2 { &guides[..1] } else { &guides };
            for &g in shown {
                let want = scene.guide_points(&nodes, &head, g);
                assert_eq!(cache.bases(&scene, g, true), want.as_slice(), "guide {g}, round {round}");
            }
            cache.keep_only(&shown.iter().map(|&g| g as u32).collect::<Vec<_>>());
            assert_eq!(cache.entries.len(), shown.len());
        }
        assert_ne!(moved(&rest, 3e-3), rest, "the test moves the nodes");
    }
}
