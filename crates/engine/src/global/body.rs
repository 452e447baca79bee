//! The body as a position constraint on the lattice nodes.

use super::GlobalCore;

impl GlobalCore {
    /// Pushes nodes that started outside the body back onto its surface (a position correction along the
    /// field gradient, a few Newton steps) and removes their inward velocity.
    pub(crate) fn push_out_of_body(&mut self) {
        let t = self.model.params.metaball.threshold;
        let body = &self.scene.head;
        for i in 0..self.state.positions.len() {
            if !self.outside[i] {
                continue;
            }
            let mut x = self.head.inverse() * self.state.positions[i];
            let mut moved = false;
            for _ in 0..self.params.push_out_iterations {
                let (f, g) = body.field_and_gradient(&x);
                let gg = g.norm_squared();
                if f <= t || !(gg > 1e-12) {
                    break;
                }
                x -= g * ((f - t) / gg * 1.05);
                moved = true;
            }
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
