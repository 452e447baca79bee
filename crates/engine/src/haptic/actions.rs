//! What each tool does with the primary button on the local strands: the scissors cut the active guides,
//! the clip pins the nearest strand point, the dryer blows on the strands near it.

use super::HapticCore;
use crate::tool::{Tool, ToolInput};
use hairstyle::cut::cut_strand;
use nalgebra::{Matrix3, Vector3};
use strand::PointForce;
use tools::dryer::{HairDrag, HairDryer};


/// Stage 6's state: what the scissors, the clip and the dryer did so far.
#[derive(Debug, Clone, Default)]
pub(crate) struct ToolActions {
    /// Scissors closes so far.
    pub cuts: u64,
    /// Whether the primary button was held in the last step.
    pub was_pressed: bool,
    /// Where the scissors last closed (device frame, m), if they did since the button was pressed.
    pub last_cut_at: Option<Vector3<f64>>,
    /// Whether the clip holds the strands.
    pub clipped: bool,
}

impl HapticCore {
    /// The tool's action this step with the primary button `pressed`, the tool at `proxy` (m) turned by
    /// `rotation`.
    pub(crate) fn act(&mut self, pressed: bool, proxy: &Vector3<f64>, rotation: &Matrix3<f64>) {
        // Scissors: closing the blades (the button going down) cuts the active guides where the blades are,
        // and again each time the held scissors have moved `snip_distance` (dragging cuts along the path); the
        // global layer cuts the render strands when it sees the count go up (`ToolInput::cuts`).
        let snip = self.tool == Tool::Scissors && pressed && (!self.actions.was_pressed || self.actions.last_cut_at.is_none_or(|p| (p - *proxy).norm() > self.model.params.haptic.snip_distance));
        if !pressed {
            self.actions.last_cut_at = None;
        }
        if snip {
            self.actions.cuts += 1;
            self.actions.last_cut_at = Some(*proxy);
            let blade = ToolInput { position: *proxy, rotation: *rotation, ..Default::default() }.blade(self.model.params.global.blade_radius);
            for (slot, &g) in self.set.active.iter().enumerate() {
                if let Ok(Some((kept, _piece))) = cut_strand(&self.interaction.strands[slot], &blade, self.model.params.haptic.cut_pieces, g) {
                    self.interaction.strands[slot] = kept;
                    // Its tip is now the cut end: no speed across the cut.
                    if let Some(m) = self.set.members.get_mut(slot) {
                        m.tip = None;
                    }
                }
            }
        }
        // A nozzle's choice of the local strands follows its jet while it blows (`HapticCore::reach`): choose
        // again when it starts or stops.
        if pressed != self.actions.was_pressed && matches!(self.tool, Tool::Dryer | Tool::Sprayer) {
            self.set.last_select = None;
        }
        self.actions.was_pressed = pressed;
        if self.tool == Tool::Clip {
            if pressed && !self.actions.clipped {
                self.actions.clipped = self.interaction.clip(self.model.params.haptic.clip_reach).is_some();
            } else if !pressed && self.actions.clipped {
                self.interaction.release();
                self.actions.clipped = false;
            }
        }
        // The dryer's jet blows on the simulated strands near the tool too: the jet's drag on each of
        // `dryer_pieces` pieces per strand (one hair: frontal area length x diameter), by the one law
        // `HairDryer::hair_force` that `GlobalCore` blows the lattice with, held over the step.
        if self.tool == Tool::Dryer && pressed {
            let jet = HairDryer { cone: ToolInput { position: *proxy, rotation: *rotation, ..Default::default() }.cone(HairDryer::default().cone, self.model.params.global.nozzle_standoff), ..HairDryer::default() };
            let pieces = self.model.params.haptic.dryer_pieces;
            for slot in 0..self.interaction.strands.len() {
                let s = &self.interaction.strands[slot];
                let piece = s.model.length / pieces as f64;
                let line = strand::kinematics::centerline(&s.model, &s.state, pieces + 1);
                let drag = HairDrag::for_section_area(s.model.section.area());
                let loads: Vec<PointForce> = line
                    .windows(2)
                    .map(|w| PointForce::new(0.5 * (w[0].0 + w[1].0), jet.hair_force(&(0.5 * (w[0].1 + w[1].1)), piece, piece * drag.hair_diameter, &drag).unwrap_or_default()))
                    .filter(|f| f.force != Vector3::zeros())
                    .collect();
                for f in loads {
                    self.interaction.add_load(slot, f);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::global::GlobalCore;
    use crate::params::SessionParams;
    use crate::snapshot::HapticSnapshot;
    use crate::testing::{small_scene, test_rot};
    use haptics::device::DeviceReading;

    #[test]
    fn the_dryer_blows_the_simulated_strands_along_its_jet() {
        // The dryer held still behind the hair at the back of the head (its jet along the tool's -z, here +y;
        // the tool point, where it aims, 0.118 m behind the head's centre, its nozzle 15 cm farther), blowing
        // for 0.6 s. Its local strands are those along its jet (none while it does not blow: its only solid is
        // the nozzle's body, far from the hair). The jet's drag (`HairDryer::hair_force`, quadratic: about
        // 7e-3 N per metre of hair at 10 m/s, many times a hair's weight; the linear drag used here before
        // issue 11 gave 1e-4 N/m) pushes them along the jet: their tips' mean displacement along +y from their
        // groomed tips is over 5 mm, and nothing goes non-finite. Not blowing, no strand is simulated.
        let scene = small_scene();
        let run = |blow: bool| {
            let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
            core.apply(&Command::SelectTool(Tool::Dryer));
            let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
            for n in 0..600 {
                let p = Vector3::new(0.0, -0.118, 0.0);
                core.step(Some(DeviceReading { time: n as f64 * 1e-3, position: p, rotation: test_rot(), buttons: blow as u32 }), &snap, 1e-3);
            }
            let tips: Vec<(usize, Vector3<f64>)> = core.set.active.iter().zip(&core.interaction.strands).map(|(&g, s)| (g, strand::kinematics::centerline(&s.model, &s.state, 2)[1].1)).collect();
            tips
        };
        assert!(run(false).is_empty(), "a nozzle that does not blow simulates no strand");
        let blown = run(true);
        assert!(!blown.is_empty());
        let along: Vec<f64> = blown.iter().map(|(g, t)| (t - scene.guides[*g].reference.last().unwrap()).y).collect();
        let mean = along.iter().sum::<f64>() / along.len() as f64;
        eprintln!("dryer: tips moved along the jet by {along:?} m (mean {mean} m)");
        assert!(blown.iter().all(|(_, t)| t.iter().all(|x| x.is_finite())));
        assert!(mean > 5e-3, "mean tip displacement along the jet {mean} m");
    }

    #[test]
    fn closing_the_scissors_cuts_the_active_guides_and_counts_the_cut() {
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        core.apply(&Command::SelectTool(Tool::Scissors));
        let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
        let p = Vector3::new(0.0, -0.118, -0.03);
        for n in 0..200 {
            let buttons = (n >= 100) as u32;
            core.step(Some(DeviceReading { time: n as f64 * 1e-3, position: p, rotation: test_rot(), buttons }), &snap, 1e-3);
        }
        assert_eq!(core.tool_input().cuts, 1);
        let lens = core.active_lengths();
        let full = scene.guides[0].model.length;
        eprintln!("active lengths after the cut {lens:?} (guides {full} m)");
        assert!(!lens.is_empty() && lens.iter().any(|&l| l < full - 1e-3), "{lens:?}");
        let mut hs = HapticSnapshot::default();
        core.snapshot(&snap, 1e-3, &mut hs);
        assert_eq!(hs.displacement.len(), hs.active.len() * scene.samples());
        assert!(hs.displacement.iter().all(|d| d.norm() < 0.5));
    }
}
