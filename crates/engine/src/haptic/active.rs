//! The active set: the guides nearest the tool, simulated as local strands (their states persist when
//! they leave the set).

use super::HapticCore;
use crate::scene::ffd_map;
use nalgebra::{Point3, Vector3};

impl HapticCore {
    /// Copies the active strands' states back into the guide set.
    pub(crate) fn write_back(&mut self) {
        for (slot, &g) in self.active.iter().enumerate() {
            if let Some(s) = self.interaction.strands.get(slot) {
                self.strands[g] = s.clone();
            }
        }
    }

    /// Chooses the guides nearest to the tool (their settled shapes through the lattice) as the active set.
    pub(crate) fn select(&mut self, tool: &Vector3<f64>, nodes: &[Point3<f64>]) {
        let r = self.params.activation_radius;
        let mut near: Vec<(f64, usize)> = Vec::new();
        for (g, guide) in self.scene.guides.iter().enumerate() {
            let d = guide.reference.iter().map(|p| (ffd_map(&self.scene.lattice.ffd, nodes, p) - tool).norm()).fold(f64::INFINITY, f64::min);
            if d < r {
                near.push((d, g));
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut chosen: Vec<usize> = near.iter().take(self.params.max_active).map(|x| x.1).collect();
        chosen.sort_unstable();
        if chosen != self.active {
            self.write_back();
            self.active = chosen;
            let strands = self.active.iter().map(|&g| self.strands[g].clone()).collect();
            self.renew_interaction(strands);
            self.wet_version = u64::MAX;
        }
        self.last_select = Some(*tool);
    }


    /// Re-selects the active set when the tool has moved `HapticParams::reselect_distance` (never while the
    /// clip holds a strand).
    pub(crate) fn reselect(&mut self, proxy: &Vector3<f64>, nodes: &[Point3<f64>]) {
        let moved = self.last_select.map_or(true, |p| (p - proxy).norm() > self.params.haptic.reselect_distance);
        if moved && !self.clipped && nodes.len() == self.scene.lattice.node_count() {
            self.select(proxy, nodes);
        }
    }

    /// The active strands' roots move with the head, which is rigid (and fixed in the scene's frame): each
    /// root is held at its guide's root on the scalp, at rest. Not with the lattice: the tool's own
    /// repelling obstacle deforms the lattice, and roots following it sank into the head and were kicked out.
    pub(crate) fn roots_follow(&mut self, _nodes: &[Point3<f64>], dt: f64) {
        for (slot, &g) in self.active.iter().enumerate() {
            let target = self.scene.guides[g].state.root.position;
            let root = &mut self.interaction.strands[slot].state.root;
            // A root that is elsewhere (a state from before) is brought back over one step.
            root.velocity = (target - root.position) / dt;
            root.angular_velocity = Vector3::zeros();
            root.acceleration = Vector3::zeros();
        }
    }
}
