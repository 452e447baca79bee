//! The guides' strands of the haptic layer: built from the scene with a hair type and curliness, the
//! contact law of the tool on them, and their centrelines.

use super::HapticCore;
use crate::error::SessionError;
use crate::params::HapticParams;
use crate::scene::Scene;
use nalgebra::Vector3;
use strand::{HairType, Strand};
use strand::constraint::ConstraintOptions;
use crate::snapshot::LatticeSnapshot;
use tools::interaction::{Entanglement, ForceModel, HairContact, Hold, LocalInteraction};
use tools::treatment::Contact;

/// `it` with the scene's body (head, neck, shoulders; the live head frame is the world frame) for its strands
/// to rest on.
pub(crate) fn resting_on(scene: &Scene, mut it: LocalInteraction) -> LocalInteraction {
    it.params.body = Some((scene.head.clone(), scene.lattice.params.metaball.threshold));
    it
}

/// The hair the viewer chose (`Command::SetHair`, `Command::SetTreatment`): what the local strands are built
/// of and how they rub.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairSetting {
    /// The hair type (Table 1); the scene's at the start.
    pub hair_type: HairType,
    /// Curliness added to the strands' rest shape, in [0, 1] ([`hairstyle::Curl`]); 0 at the start.
    pub curliness: f64,
    /// Combing ease (a detangler's lowering of the friction, `HapticParams::combing_friction`), in [0, 1]; 0 at
    /// the start.
    pub combing_ease: f64,
    /// The surface treatment (`tools::treatment::Treatment`); `HapticParams::treatment` at the start.
    pub treatment: tools::treatment::Treatment,
}

impl HapticCore {
    /// Every guide's strand in its groomed state, with the hair type's section and material and the
    /// curliness (in [0, 1], [`hairstyle::Curl`]) added to the rest twist and bend, and an air drag of at least
    /// `HapticParams::min_air_drag` (N s/m^2).
    ///
    /// Held by the hair volume (`HapticParams::hold_distance` finite, the live session's default), a strand's
    /// weight is carried by the hold at its place (the neighbours and the scalp beneath, as the sag-free
    /// lattice's pre-stressed springs carry the global layer's): its model has no gravity, its rest shape is its
    /// groomed shape (so the groom is its equilibrium for every hair type, and the only one: the hold's spring
    /// brings it back from anywhere), and the hold's damping (`HapticParams::hold_damping`) is added to its air
    /// drag. Not held, it keeps its weight and the guide's sag-free rest (a single fibre carrying itself).
    pub(crate) fn build_strands(scene: &Scene, h: &HairType, curliness: f64, params: &HapticParams) -> Result<Vec<Strand>, SessionError> {
        let err = |e: strand::StrandError| SessionError::Scene(e.to_string());
        let curl = hairstyle::Curl::from_curliness(curliness.clamp(0.0, 1.0)).map_err(|e| SessionError::Scene(e.to_string()))?;
        let held = params.hold_distance.is_finite();
        scene.guides.iter().map(|g| {
            let mut m = g.model.clone();
            if *h != scene.hair_type {
                m.section = h.section().map_err(err)?;
                m.material = h.material().map_err(err)?;
            }
            if held {
                m.set_rest_coordinates(&g.state.q);
                m.gravity = Vector3::zeros();
            }
            if let Some(c) = curl.as_ref() {
                let (mut q, d) = (m.rest_coordinates(), m.dofs_per_segment());
                for i in 0..m.segments {
                    q[d * i] += c.twist;
                    q[d * i + 1] += c.bend;
                }
                m.set_rest_coordinates(&q);
            }
            m.air_drag = m.air_drag.max(params.min_air_drag);
            if held {
                m.air_drag += params.hold_rates(g.model.gravity.norm()).1 * m.linear_density();
            }
            let mut s = Strand::new(m, g.state.root.clone()).map_err(err)?;
            s.state.q.copy_from(&g.state.q);
            Ok(s)
        }).collect()
    }

    /// The tool's contact law on the dry hair `hair` (its type, surface treatment and combing ease,
    /// [`HapticParams::combing_friction`]), with the constraints' compliance of [`contact_options`] for its fibre.
    pub(crate) fn force_model(params: &HapticParams, hair: &HairSetting) -> ForceModel {
        let h = &hair.hair_type;
        let mu = h.friction_coefficient() * hair.treatment.friction_factor(Contact::Tool, 0.0);
        ForceModel::Constraint { friction: params.combing_friction(mu, hair.combing_ease), options: contact_options(h.bending_stiffness) }
    }

    /// Hair-hair contact between the local strands (`tools::hair_contact`; None when
    /// `HapticParams::hair_contact` is off): each guide a wisp of [`HapticCore::hairs_per_guide`] fibres
    /// (`HairContact`'s defaults otherwise), its dry fibre-fibre friction raised by the wetness `wetness` (in
    /// [0, 1]; the wetness model's one friction law) and lowered by the combing ease (the one combing-ease
    /// law), as the tool's friction and as the tress scenarios' (`scenario::patch`).
    pub(crate) fn hair_contact(&self, wetness: f64) -> Option<HairContact> {
        if !self.model.params.haptic.hair_contact {
            return None;
        }
        Some(HairContact { fibres: self.hairs_per_guide(), friction: self.fibre_friction(wetness), ..HairContact::default() })
    }

    /// Where the hair volume holds each local strand (`LocalInteraction::holds`): its guide's reference
    /// samples carried by the lattice `lattice` (the shape the viewer shows for it when not simulated). A
    /// strand without one gets it now; the others are taken again a share at a time, each once per global step
    /// (`SessionParams::haptic_rate_hz / global_rate_hz` haptic steps: 10 by default), so that no step maps
    /// every strand's references through a new lattice.
    pub(crate) fn hold_in_place(&mut self, lattice: &LatticeSnapshot) {
        let shares = (self.model.params.haptic_rate_hz / self.model.params.global_rate_hz).round().max(1.0) as u64;
        let n = self.set.active.len();
        self.interaction.holds.resize(n, None);
        let share = (self.step % shares) as usize;
        let ok = lattice.positions.len() == self.model.scene.lattice.node_count();
        let mut cache = self.shown.references.borrow_mut();
        cache.use_nodes(&lattice.positions, &lattice.head);
        for (slot, &g) in self.set.active.iter().enumerate() {
            let hold = &mut self.interaction.holds[slot];
            if hold.is_some() && slot % shares as usize != share {
                continue;
            }
            let bases = cache.bases(&self.model.scene, g, ok);
            match hold {
                Some(h) => {
                    h.points.clear();
                    h.points.extend_from_slice(bases);
                }
                None => *hold = Some(Hold { points: bases.to_vec(), length: self.model.scene.guides[g].model.length }),
            }
        }
    }

    /// Fibre-on-fibre friction coefficient at wetness `wetness` (in [0, 1]), dimensionless: `HairContact`'s
    /// dry value raised by the wetness and the treatment (`HapticParams::treatment`; the one friction law,
    /// `tools::treatment::Treatment::friction`) and lowered by the combing ease (the one combing-ease law). The
    /// hair-hair contacts take it, and so do the strands' contacts with the body
    /// (`LocalInteraction::body_friction`): a strand lies on the scalp under the hair beneath it.
    pub(crate) fn fibre_friction(&self, wetness: f64) -> f64 {
        let d = HairContact::default().friction;
        let wet = self.hair.treatment.friction(&self.wet.model, Contact::Fibre, d, wetness.clamp(0.0, 1.0)).unwrap_or(d);
        self.model.params.haptic.combing_friction(wet, self.hair.combing_ease)
    }

    /// A new local interaction over `strands` with the selected tool's shape (built once) and the current
    /// hair's contact laws (tool on hair, hair on hair); the body the strands rest on moves over from the previous interaction (it is
    /// not copied in the haptic loop).
    pub(crate) fn renew_interaction(&mut self, strands: Vec<Strand>) {
        let body = self.interaction.params.body.take();
        let model = Self::force_model(&self.model.params.haptic, &self.hair);
        let mut it = LocalInteraction::new(strands, self.model.shapes[self.tool as usize].clone(), self.interaction.pose, model);
        it.params.body = body;
        it.params.body_friction = self.fibre_friction(0.0);
        it.params.hold_distance = self.model.params.haptic.hold_distance;
        // The strands' models carry no weight (the hold does, `build_strands`): the hold's spring takes the scene's gravity.
        it.params.hold_gravity = self.model.scene.guides.first().map(|g| g.model.gravity.norm());
        it.params.hair_contact = self.hair_contact(0.0);
        if self.model.params.haptic.entanglement {
            it.params.entanglement = Some(Entanglement { wettability: self.hair.treatment.wettability(), ..Entanglement::for_hair(&self.hair.hair_type) });
        }
        self.interaction = it;
    }
}

/// The live session's constraint solver options for simulated fibres of flexural rigidity `ei` (N m^2): the
/// defaults, with no constraint (tool, body or hair-hair contact, pin) stiffer than the fibre's lateral stiffness
/// over the span between the neighbours that hold it sideways in the hair, `48 EI / span^3`
/// (`tools::entanglement::Entanglement::fibre_stiffness`, the span of the tress calibration, 7.3 mm; caucasian
/// dry 0.35 N/m, against the solver's default cap of 100 N/m). A simulated guide is a chain of rigid-curvature
/// segments (8 of 2.5 cm in the built-in hairstyle) and stands for hundreds of fibres, so a tooth pressing it near its
/// root, or two teeth shearing it on opposite sides, met the whole segment's resistance and the solver's cap
/// (newtons at the hand on issue 12's upward strokes). A real fibre there bends over one span.
pub(crate) fn contact_options(ei: f64) -> ConstraintOptions {
    ConstraintOptions { max_stiffness: Entanglement::default().fibre_stiffness(ei), ..ConstraintOptions::default() }
}

/// `samples` centreline points of a strand evenly in arc length, root to tip, m.
#[cfg(test)]
pub(crate) fn centreline(s: &Strand, samples: usize) -> Vec<Vector3<f64>> {
    strand::kinematics::centerline(&s.model, &s.state, samples).into_iter().map(|(_, p)| p).collect()
}

/// `samples` centreline points of a strand at the arc lengths of its uncut guide (`length`, m, evenly from root
/// to tip); past the end of a cut strand, its tip. Equal to `centreline` for an uncut strand.
pub(crate) fn samples_along(s: &Strand, length: f64, samples: usize) -> Vec<Vector3<f64>> {
    samples_and_tip(s, length, samples).points
}

/// A strand's [`samples_along`] and its tip (the last of its segment frames), m, from one evaluation of its frames.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Sampled {
    pub points: Vec<Vector3<f64>>,
    pub tip: Vector3<f64>,
}

/// [`samples_along`] with the strand's tip, its frames evaluated once (the same numbers as each alone).
pub(crate) fn samples_and_tip(s: &Strand, length: f64, samples: usize) -> Sampled {
    let frames = strand::kinematics::segment_frames(&s.model, &s.state);
    let tip = frames.last().map_or(s.state.root.position, |f| f.position);
    let points = if s.model.length >= length - 1e-12 {
        // As `centreline`.
        strand::kinematics::centerline_from(&s.model, &s.state.q, &frames, samples).into_iter().map(|(_, p)| p).collect()
    } else {
        (0..samples).map(|k| {
            let at = (k as f64 / (samples - 1).max(1) as f64 * length).min(s.model.length);
            strand::kinematics::frame_at(&s.model, &s.state.q, &frames, at).position
        }).collect()
    };
    Sampled { points, tip }
}

#[cfg(test)]
mod tests {
    use crate::haptic::HapticCore;
    use crate::params::SessionParams;
    use crate::testing::small_scene;

    #[test]
    fn the_live_hair_contact_is_a_wisp_of_the_guides_hairs_with_the_wet_friction() {
        // On by default (off: none); on, each guide is a wisp of the real hairs it stands for, and its fibre-fibre
        // friction follows the wetness by the wetness model's law (dry 0.25; soaked, times the model's friction
        // ratio) and the combing ease by the one combing-ease law; the interaction takes it (and keeps it on a
        // new one).
        let scene = small_scene();
        let mut off = SessionParams::default();
        off.haptic.hair_contact = false;
        assert!(HapticCore::new(scene.clone(), off).unwrap().interaction.params.hair_contact.is_none());
        let params = SessionParams::default();
        assert!(params.haptic.hair_contact);
        let mut core = HapticCore::new(scene, params).unwrap();
        let dry = core.hair_contact(0.0).unwrap();
        assert_eq!(dry.fibres, core.hairs_per_guide());
        assert!((dry.friction - 0.25).abs() < 1e-15, "{}", dry.friction);
        let wet = core.hair_contact(1.0).unwrap();
        let want = core.wet.model.friction(0.25, 1.0).unwrap();
        assert!(want > 0.25 && (wet.friction - want).abs() < 1e-12, "{} vs {want}", wet.friction);
        core.hair.combing_ease = 1.0;
        let eased = core.hair_contact(0.0).unwrap();
        assert!((eased.friction - params.haptic.combing_friction(0.25, 1.0)).abs() < 1e-15);
        core.renew_interaction(Vec::new());
        assert_eq!(core.interaction.params.hair_contact, Some(eased));
    }
}
