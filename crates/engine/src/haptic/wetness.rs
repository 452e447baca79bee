//! Wet hair on the haptic layer: the local strands' material, the tool's friction and the wet set of their
//! rest shapes from the guides' wetness in the lattice snapshot.

use super::HapticCore;
use crate::snapshot::LatticeSnapshot;
use strand::styling::{SetModel, SetState};
use tools::interaction::ForceModel;
use tools::wetness::WetnessModel;

/// Stage 5's state: the guides' wetness as last read and their wet sets.
#[derive(Debug, Clone)]
pub(crate) struct WetState {
    /// Wetness of each guide (in [0, 1]) as last read from the lattice snapshot.
    pub wetness: Vec<f32>,
    /// The snapshot version it came from (u64::MAX: apply again).
    pub version: u64,
    /// The wetness law (friction and stiffness against wetness).
    pub model: WetnessModel,
    /// Each guide's wet set (`strand::styling`): the shape its hydrogen bonds hold, updated while it is
    /// a local strand (one per guide, remade with the strands).
    pub sets: Vec<SetState>,
}

impl HapticCore {

    /// The wetness model's material and friction for the active strands, from the guides' wetness in the
    /// lattice snapshot (once per lattice version, and after the active set changes): a wet strand is
    /// heavier, softer, and the tool's friction grows (`tools::wetness::WetnessModel`). The friction of the
    /// interaction (the tool's and the hair-hair contact's) follows the active guides' mean wetness.
    pub(crate) fn apply_wetness(&mut self, lattice: &LatticeSnapshot) {
        if lattice.version == self.wet.version || lattice.wetness.len() != self.wet.wetness.len() {
            return;
        }
        self.wet.version = lattice.version;
        self.wet.wetness.copy_from_slice(&lattice.wetness);
        let h = self.hair.hair_type;
        let (Ok(dry), Ok(section)) = (h.material(), h.section()) else { return };
        let mut mean = 0.0;
        let set_model = SetModel { hydrogen_share: self.model.params.haptic.hydrogen_share };
        self.interaction.wetness.clear();
        for (slot, &g) in self.set.active.iter().enumerate() {
            let w = self.wet.wetness[g] as f64;
            // The capillary share of the tool's drag (`tools::entanglement`) follows each guide's wetness.
            self.interaction.wetness.push(w);
            mean += w / self.set.active.len() as f64;
            let s = &mut self.interaction.strands[slot];
            if let Ok(m) = self.wet.model.wet(&dry, h.friction_coefficient(), section.area(), w) {
                s.model.material = m.material();
            }
            // The wet set (`strand::styling`, the law the headless styling tests check): as the guide dries
            // its rest shape takes the shape it is held in. A cut strand (fewer segments) starts a new set.
            if self.wet.sets[g].set.len() != s.model.dofs() {
                self.wet.sets[g] = SetState::new(&s.model);
            }
            // Unchanged wetness leaves the set and the rest shape as they are (the law moves the set only as the
            // wetness changes), so the update is skipped: it ran for every simulated strand at every global step.
            if self.wet.sets[g].wetness.iter().any(|&x| x != w) {
                let (q, ws) = (s.state.q.clone(), vec![w; s.model.segments]);
                if self.wet.sets[g].update(&set_model, &mut s.model, &q, &ws).is_err() {
                    self.stats.failed += 1;
                }
            }
        }
        if let Ok(m) = self.wet.model.wet(&dry, h.friction_coefficient(), section.area(), mean) {
            // Wet fibres are softer: their contacts' largest stiffness follows (`contact_options`).
            let options = super::strands::contact_options(m.material().young_modulus * section.i_soft());
            let friction = m.friction * self.hair.treatment.friction_factor(tools::treatment::Contact::Tool, mean);
            self.interaction.model = ForceModel::Constraint { friction: self.model.params.haptic.combing_friction(friction, self.hair.combing_ease), options };
        }
        self.interaction.params.hair_contact = self.hair_contact(mean);
        self.interaction.params.body_friction = self.fibre_friction(mean);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::GlobalCore;
    use crate::params::SessionParams;
    use crate::scene::Scene;
    use crate::testing::{small_scene, test_rot};
    use haptics::device::DeviceReading;
    use nalgebra::Vector3;
    use std::sync::Arc;

    /// A comb stroke down the back of the head, 0.1 m/s for 1.5 s at depth y (m), with every guide at wetness
    /// w, after the comb has waited 0.6 s at the start; the core afterwards and the peak and mean force (N) from
    /// 0.2 s into the stroke (the device point accelerating, at most 1 m/s^2, gives 0.05 N on the 50 g proxy in
    /// free air, more than the hair's force here).
    fn comb_stroke(scene: &Arc<Scene>, w: f64, y: f64) -> (HapticCore, f64, f64) {
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        g.set_wetness(w);
        let snap = g.snapshot();
        let (mut peak, mut sum): (f64, f64) = (0.0, 0.0);
        for n in 0..2100 {
            let t = n as f64 * 1e-3;
            let p = Vector3::new(0.0, y, 0.05 - 0.1 * (t - 0.6).max(0.0));
            let c = core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3);
            if n >= 800 {
                peak = peak.max(c.force.norm());
                sum += c.force.norm() / 1300.0;
            }
        }
        (core, peak, sum)
    }

    #[test]
    fn wet_hair_gives_the_simulated_strands_the_wet_material_and_the_comb_the_wet_friction() {
        // Every guide wet (1) against dry (0): after the same stroke the interaction's friction is the wetness
        // model's (`friction_ratio` x the dry coefficient) and every simulated strand has the wet material (heavier, softer).
        // (This test used to assert that the wet stroke's force was above the dry one's. With the active set
        // chosen by the comb's shape ahead of its motion and its strands stepped until at rest, the heavier and
        // softer wet strands sag out of the comb's fixed path: the mean force of this small scene's stroke is
        // lower wet (0.11 mN) than dry (1.2 mN), while the peak is higher at some depths and lower at others. The
        // wet combing force of issue 12 comes from fibre-fibre friction and clumping, the tress branch's
        // hair-hair contact.)
        let scene = small_scene();
        let ((dry_core, dp, dm), (wet_core, wp, wm)) = (comb_stroke(&scene, 0.0, -0.118), comb_stroke(&scene, 1.0, -0.118));
        eprintln!("comb force dry: peak {dp} N, mean {dm} N; wet: peak {wp} N, mean {wm} N");
        let friction = |c: &HapticCore| match c.interaction.model {
            ForceModel::Constraint { friction, .. } => friction,
            ForceModel::Paper { .. } => f64::NAN,
        };
        let h = scene.hair_type;
        let wet = dry_core.wet.model.wet(&h.material().unwrap(), h.friction_coefficient(), h.section().unwrap().area(), 1.0).unwrap();
        let want = SessionParams::default().haptic.combing_friction(wet.friction, 0.0);
        assert!((friction(&wet_core) - want).abs() < 1e-12 * want, "wet friction {} vs {want}", friction(&wet_core));
        assert!((friction(&dry_core) - SessionParams::default().haptic.combing_friction(h.friction_coefficient(), 0.0)).abs() < 1e-12);
        assert!(friction(&wet_core) > 1.4 * friction(&dry_core), "the fibre surface's wet rise (1.5)");
        // The constraints' cap is the fibre's lateral stiffness over the entanglement span (7.3 mm), 48 EI / span^3,
        // with the wet fibre's softer E when wet (`strands::contact_options`; the formula written out here).
        let cap = |c: &HapticCore| match c.interaction.model {
            ForceModel::Constraint { options, .. } => options.max_stiffness,
            ForceModel::Paper { .. } => f64::NAN,
        };
        let span3 = 7.3e-3f64.powi(3);
        let (dry_cap, wet_cap) = (48.0 * h.bending_stiffness / span3, 48.0 * wet.material().young_modulus * h.section().unwrap().i_soft() / span3);
        assert!((cap(&dry_core) - dry_cap).abs() < 1e-9 * dry_cap && (cap(&wet_core) - wet_cap).abs() < 1e-9 * wet_cap, "caps {} and {} vs {dry_cap} and {wet_cap} N/m", cap(&dry_core), cap(&wet_core));
        assert!(wet_cap < dry_cap && dry_cap < 1.0, "{wet_cap} {dry_cap}");
        assert!(!wet_core.set.active.is_empty() && dp > 1e-4, "the stroke goes through the hair");
        for (s, d) in wet_core.interaction.strands.iter().zip(&dry_core.interaction.strands) {
            assert!(s.model.material.density > d.model.material.density, "{:?} vs {:?}", s.model.material, d.model.material);
        }
    }

    #[test]
    fn wet_hair_dried_by_the_live_session_takes_a_set() {
        // The wet set in the live session (issue 11; headless only before): 0.3 s of a comb stroke through
        // soaked hair (every guide at wetness 1), then a lattice snapshot saying dry. The active strands'
        // rest coordinates move towards the shape they are held in (rms change over their coordinates above
        // 1e-3 rad/m); the same stroke through dry hair dried again leaves them unchanged to the bit.
        let scene = small_scene();
        // The strands as the haptic layer builds them (rest: the groom, `HapticCore::build_strands`).
        let built = HapticCore::build_strands(&scene, &scene.hair_type, 0.0, &SessionParams::default().haptic).unwrap();
        let run = |w: f32| -> f64 {
            let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
            let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
            g.set_wetness(w as f64);
            let wet = g.snapshot();
            let mut dry = wet.clone();
            dry.version += 1;
            dry.wetness.iter_mut().for_each(|x| *x = 0.0);
            for n in 0..301 {
                let t = n as f64 * 1e-3;
                let p = Vector3::new(0.0, -0.118, 0.05 - 0.1 * t);
                let snap = if n < 300 { &wet } else { &dry };
                core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), snap, 1e-3);
            }
            assert!(!core.set.active.is_empty());
            let (mut sq, mut cnt) = (0.0, 0usize);
            for (slot, &g) in core.set.active.iter().enumerate() {
                let d = core.interaction.strands[slot].model.rest_coordinates() - built[g].model.rest_coordinates();
                sq += d.norm_squared();
                cnt += d.len();
            }
            (sq / cnt as f64).sqrt()
        };
        let (wet, dry) = (run(1.0), run(0.0));
        eprintln!("rms rest change after drying: {wet} rad/m (wet), {dry} rad/m (dry throughout)");
        assert!(wet > 1e-3, "{wet}");
        assert_eq!(dry, 0.0);
    }
}
