//! The active set: the guides nearest the tool, simulated as local strands (their states persist when
//! they leave the set).

use super::{resting_on, HapticCore};
use crate::scene::ffd_map;
use nalgebra::{Point3, Vector3};
use tools::interaction::LocalInteraction;

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
            self.interaction = resting_on(&self.scene, LocalInteraction::new(strands, self.tool.shape(), self.interaction.pose, Self::force_model(&self.hair_type, self.combing_ease)));
            self.wet_version = u64::MAX;
        }
        self.last_select = Some(*tool);
    }


    /// Re-selects the active set when the tool has moved 1 cm (never while the clip holds a strand).
    pub(crate) fn reselect(&mut self, proxy: &Vector3<f64>, nodes: &[Point3<f64>]) {
        let moved = self.last_select.map_or(true, |p| (p - proxy).norm() > 0.01);
        if moved && !self.clipped && nodes.len() == self.scene.lattice.node_count() {
            self.select(proxy, nodes);
        }
    }

    /// The active strands' roots follow the lattice (FFD of each guide's rest root position).
    pub(crate) fn roots_follow(&mut self, nodes: &[Point3<f64>], dt: f64) {
        if nodes.len() == self.scene.lattice.node_count() {
            for (slot, &g) in self.active.iter().enumerate() {
                let target = ffd_map(&self.scene.lattice.ffd, nodes, &self.scene.guides[g].state.root.position);
                let root = &mut self.interaction.strands[slot].state.root;
                root.velocity = (target - root.position) / dt;
                root.acceleration = Vector3::zeros();
            }
        }
    }
}
