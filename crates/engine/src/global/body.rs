//! The body as a position constraint on the lattice nodes.

use super::GlobalCore;

/// How far outside the body's surface a pushed-out lattice node is put, m: enough that rounding never
/// leaves it inside (`MetaballSet::push_out` lands within 1e-3 of this), far below anything drawn.
const NODE_SKIN: f64 = 1e-6;

impl GlobalCore {
    /// Pushes nodes that started outside the body back onto its surface (`MetaballSet::push_out`, a position
    /// correction along the outward normal) and removes their inward velocity.
    pub(crate) fn push_out_of_body(&mut self) {
        let t = self.model.params.metaball.threshold;
        let body = &self.scene.head;
        for i in 0..self.state.positions.len() {
            if !self.outside[i] {
                continue;
            }
            // The body's one push-out law (`MetaballSet::push_out`, the same the tools and the render strands
            // use), just outside the surface.
            let x0 = self.head.inverse() * self.state.positions[i];
            let x = body.push_out(&x0, t, NODE_SKIN);
            let moved = x != x0;
            if moved {
                let n = -(self.head * body.gradient(&x)).normalize();
                self.state.positions[i] = self.head * x;
                let v = &mut self.state.velocities[i];
                let vn = v.dot(&n);
                if vn < 0.0 {
                    *v -= n * vn;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SessionParams;
    use crate::testing::small_scene;
    use crate::tool::ToolInput;

    #[test]
    fn lattice_nodes_thrown_at_the_head_stay_outside_the_body() {
        // Every node that starts outside the body is thrown at the head's centre at 10 m/s: after each step,
        // none of them is inside the body (metaball field above the threshold by more than 1e-9). The same
        // throw without the push-out does put nodes inside (so the test can fail).
        let scene = small_scene();
        let run = |push: bool| -> (usize, f64) {
            let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
            let t = g.model.params.metaball.threshold;
            let outside = g.outside.clone();
            for (i, x) in g.state.positions.clone().iter().enumerate() {
                if outside[i] && x.coords.norm() > 1e-9 {
                    g.state.velocities[i] = -x.coords.normalize() * 10.0;
                }
            }
            if !push {
                g.outside.iter_mut().for_each(|o| *o = false);
            }
            let mut worst = f64::NEG_INFINITY;
            for _ in 0..20 {
                g.step(0.01, &ToolInput::default());
                for (i, x) in g.state.positions.iter().enumerate() {
                    if outside[i] {
                        worst = worst.max(scene.head.field(x) - t);
                    }
                }
            }
            (outside.iter().filter(|&&o| o).count(), worst)
        };
        let ((outside, worst), (_, without)) = (run(true), run(false));
        eprintln!("{outside} nodes outside the body at rest; largest field above the surface {worst} (without the push-out {without})");
        assert!(outside > 100);
        assert!(without > 1e-4, "the throw reaches the body: {without}");
        assert!(worst <= 1e-9, "a node went into the body: field {worst} above the threshold");
    }
}
