//! The nozzle tools on the global layer: the dryer's jet blowing on the lattice and the sprayer's and
//! dryer's wetness of the guides in their cones.

use super::GlobalCore;
use crate::tool::{Tool, ToolInput};
use tools::dryer::HairDryer;
use tools::sprayer::Sprayer;

impl GlobalCore {
    /// Dryer jet on the lattice nodes (while the dryer is held pressed), as a velocity change dv = F dt / m
    /// with F the jet's drag on the hair a node stands for (m / lambda metres of it).
    pub(crate) fn blow(&mut self, input: &ToolInput, dt: f64) {
        if input.present && input.pressed && input.tool == Tool::Dryer {
            let d = HairDryer { cone: input.cone(self.dryer.cone), ..self.dryer };
            for (i, x) in self.state.positions.iter().enumerate() {
                let m = self.model.masses[i];
                let f = d.force(&x.coords, self.air_drag * m / self.lambda);
                self.state.velocities[i] += f * (dt / m);
            }
        }
    }

    /// Wetness: the held sprayer or dryer in its cone, at the guides' segment centres through the lattice.
    pub(crate) fn moisten(&mut self, input: &ToolInput, dt: f64) {
        if input.present && input.pressed && matches!(input.tool, Tool::Dryer | Tool::Sprayer) {
            let centres = self.centres_now();
            let r = if input.tool == Tool::Sprayer {
                Sprayer { cone: input.cone(self.sprayer.cone), ..self.sprayer }.spray(&mut self.wet, &centres, dt)
            } else {
                HairDryer { cone: input.cone(self.dryer.cone), ..self.dryer }.dry(&mut self.wet, &centres, dt)
            };
            self.failed += r.is_err() as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SessionParams;
    use crate::testing::{small_scene, test_rot};
    use nalgebra::Vector3;
    use tools::dryer::Cone;

    #[test]
    fn sprayer_raises_and_dryer_lowers_wetness_in_the_cone_only() {
        // The nozzle 0.35 m behind the head (0.15 m behind the tool point) aims at it (+y). Every guide segment whose centre is in the cone
        // at the end gets wetter (sprayer) or drier (dryer); every segment outside the cone widened by
        // 0.15 rad keeps its wetness exactly (the lattice moves a little meanwhile, hence the margin).
        let scene = small_scene();
        let params = SessionParams::default();
        let spray = ToolInput { tool: Tool::Sprayer, present: true, position: Vector3::new(0.0, -0.2, 0.0), rotation: test_rot(), pressed: true, cuts: 0 };
        for (tool, start) in [(Tool::Sprayer, 0.0), (Tool::Dryer, 0.5)] {
            let mut g = GlobalCore::new(scene.clone(), &params);
            g.set_wetness(start);
            let input = ToolInput { tool, ..spray };
            for _ in 0..100 {
                g.step(0.01, &input);
            }
            let cone = input.cone(if tool == Tool::Sprayer { Sprayer::default().cone } else { HairDryer::default().cone });
            let wide = Cone { half_angle: cone.half_angle + 0.15, range: cone.range + 0.02, ..cone };
            let (mut inside, mut outside) = (0, 0);
            for (gi, cs) in g.centres_now().iter().enumerate() {
                for (k, x) in cs.iter().enumerate() {
                    let w = g.wetness().values[gi][k];
                    if cone.weight(x).0 > 0.05 {
                        inside += 1;
                        if tool == Tool::Sprayer {
                            assert!(w > start + 1e-3, "sprayed segment {gi}/{k}: {w}");
                        } else {
                            assert!(w < start - 1e-4, "dried segment {gi}/{k}: {w}");
                        }
                    } else if wide.weight(x).0 == 0.0 {
                        outside += 1;
                        assert_eq!(w, start, "segment {gi}/{k} outside the cone changed");
                    }
                }
            }
            let snap = g.snapshot();
            let mean = snap.wetness.iter().map(|&w| w as f64).sum::<f64>() / snap.wetness.len() as f64;
            eprintln!("{tool:?}: {inside} segments in the cone, {outside} outside; mean guide wetness {start} -> {mean}");
            assert!(inside >= 5 && outside >= 20, "{inside} in, {outside} out");
            assert!(if tool == Tool::Sprayer { mean > start } else { mean < start });
        }
    }
}
