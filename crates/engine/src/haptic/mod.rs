//! The haptic layer: the device loop at the device's rate (4 kHz by default, [`device_side`]) and the physics
//! at 1 kHz: the *local strands* (the few guide strands nearest the tool, Super-Helices) the tool acts on.
//!
//! One physics period ([`HapticCore::step_rates`]; the live session runs the same schedule on two threads):
//! 1-2c. **Device steps** ([`DeviceSide::step`], several per period): the device point follows the pointer's
//!    target or a streaming device's samples (`haptics::target`); the virtual coupling renders the local
//!    force model the previous physics step published (force, stiffness, damping and torque about the
//!    proxy's state, taken implicitly so the reaction can never throw the proxy:
//!    `haptics::coupling::HairReaction`), giving the force and torque on the hand; the tool stays outside
//!    the head (`HapticParams::body_clearance`, a god-object for the body); the runaway guard.
//!
//! Then the physics step ([`HapticCore::physics_step`]) with the proxy's state at the period's start:
//! 3. **Active set**: the guides near the tool's path over the next `HapticParams::lookahead` s become the
//!    local strands; strands that left it are still stepped until at rest and back in place, then handed
//!    over to the global layer without a jump (their displacement carried there, relaxed by the hold; [`active`]).
//! 4. **Roots**: the local strands' roots stay with the head (rigid), not with the tool-deformed lattice;
//!    the hair volume holds each strand near its place (its groom through the lattice,
//!    `HapticParams::hold_distance`).
//! 5. **Wetness**: the guides' wetness from the lattice snapshot sets the strands' material and the
//!    friction, and the wet-set law updates their rest shapes as they dry ([`wetness`]).
//! 6. **Tool actions**: scissors cut, clip pins, dryer blows ([`actions`]).
//! 7. **Local strands**: the local interaction steps the strands with the tool's contacts; its reaction
//!    linearised about the proxy's state (force, stiffness, damping, torque: the local force model), times the
//!    real hairs each guide stands for ([`HapticCore::hairs_per_guide`]), is published for the device steps
//!    of the next period.
//! 8. **Tracking**: each local strand's tip speed, the leaving strands' rest, the display's fade in, the
//!    handed-over guides' offsets relaxed by the hold
//!    ([`active`]).

pub mod actions;
mod active;
pub mod device_side;
mod reference;
mod strands;
mod wetness;

#[cfg(test)]
pub(crate) use strands::centreline;
pub(crate) use strands::resting_on;

use crate::command::Command;
use crate::error::SessionError;
use crate::params::SessionParams;
use crate::scene::Scene;
use crate::snapshot::{HapticSnapshot, LatticeSnapshot};
use crate::tool::{Tool, ToolInput};
pub use device_side::{DeviceSide, ProxyState, Published};
use haptics::coupling::{Coupling, HairReaction};
use haptics::device::{DeviceCommand, DeviceReading};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;
use strand::{HairType, Strand};
use strands::samples_along;
use tools::contact::ToolPose;
use tools::interaction::LocalInteraction;
use strand::styling::SetState;
use tools::wetness::WetnessModel;

/// The haptic layer's state and step (coupling, local strands, wetness, cuts), shared by the live thread
/// and [`replay`].
pub struct HapticCore {
    pub(crate) scene: Arc<Scene>,
    pub(crate) params: SessionParams,
    /// Each tool's shape (by wire id), built once.
    pub(crate) shapes: Vec<tools::shape::ToolShape>,
    pub(crate) tool: Tool,
    pub(crate) hair_type: HairType,
    pub(crate) curliness: f64,
    pub(crate) combing_ease: f64,
    /// The device loop's side (stages 1-2c: device point, coupling, body, runaway guard) as the lockstep
    /// schedule runs it ([`HapticCore::step_rates`]); the live session runs its own copy on the device thread.
    pub side: DeviceSide,
    /// The proxy's state the last physics step used (the device side's, at the start of its period).
    pub(crate) proxy: ProxyState,
    /// The device side's re-anchorings seen (`ProxyState::anchors`).
    pub(crate) anchors: u64,
    /// Every guide's strand while it is not simulated (it keeps its last state there); None while it is: the
    /// interaction has it (moved, not copied: a copy of a strand's workspaces was most of a joining step).
    pub(crate) strands: Vec<Option<Strand>>,
    /// Simulated guides, in the interaction's order (their strands live in the interaction meanwhile and
    /// move back to `strands` when they leave or the set is cleared), and each one's membership.
    pub(crate) active: Vec<usize>,
    pub(crate) members: Vec<active::Member>,
    /// Guides handed over to the global layer whose displacement from their carried place is still relaxing
    /// (no longer simulated, or simulated again with it; [`active::HandedOver`]).
    pub(crate) handed: Vec<active::HandedOver>,
    /// The shown guides' reference samples mapped through the lattice, kept between snapshots
    /// ([`HapticCore::snapshot`] takes `&self`, hence the cell; the core lives on one thread).
    pub(crate) references: std::cell::RefCell<reference::ReferenceCache>,
    /// The next snapshot's staged displacements ([`HapticCore::stage_snapshot`]), one per shown guide.
    pub(crate) staged: std::cell::RefCell<Vec<Staged>>,
    /// The choice of the active set in progress, if any (spread over steps).
    pub(crate) choice: Option<active::Choice>,
    /// Each guide's settled shape bounded for the choice's scan (fixed, from the scene).
    pub(crate) bounds: active::GuideBounds,
    /// Guides the last finished choice chose that have yet to join, nearest first (they join
    /// `HapticParams::joins_per_step` at a time).
    pub(crate) queued: Vec<usize>,
    /// Fastest tip of the simulated strands over the last step, m/s.
    pub(crate) max_tip_speed: f64,
    pub(crate) interaction: LocalInteraction,
    /// The hair's reaction on the proxy from the last step (scaled to the real hairs), linearised.
    pub(crate) hair_force: HairReaction,
    /// Wetness of each guide as last read from the lattice snapshot, and the version it came from
    /// (u64::MAX: apply again).
    pub(crate) wetness: Vec<f32>,
    pub(crate) wet_version: u64,
    pub(crate) wet_model: WetnessModel,
    /// Each guide's wet set (`strand::styling`): the shape its hydrogen bonds hold, updated while it is
    /// a local strand (one per guide, remade with the strands).
    pub(crate) sets: Vec<SetState>,
    /// Scissors closes so far, and whether the primary button was held in the last step.
    pub(crate) cuts: u64,
    pub(crate) was_pressed: bool,
    pub(crate) last_cut_at: Option<Vector3<f64>>,
    pub(crate) step: u64,
    pub(crate) last_contacts: u32,
    pub(crate) last_select: Option<Vector3<f64>>,
    pub(crate) clipped: bool,
    /// The most strands simulated now ([`Command::LimitStrands`], the live thread's strand budget), in
    /// 1..=`SessionParams::max_active`; `max_active` unless limited.
    pub(crate) strand_limit: usize,
    /// The head pose (head frame to world): the roots and the body follow it. Identity unless a scenario
    /// or the viewer moves the head ([`HapticCore::set_head_pose`]).
    pub(crate) head: nalgebra::Isometry3<f64>,
    /// Rejected device readings (NaN, teleport), as the device side counted them up to the last physics step.
    pub rejected: u64,
    /// Steps in which the runaway guard put the proxy back on the device (`HapticParams::max_proxy_lag`).
    pub runaways: u64,
    /// Strand steps that failed (state kept).
    pub failed: u64,
    /// The largest hand-over to the global layer so far: a let-go strand's largest shown displacement from its
    /// place carried by the global layer when it leaves the simulation (what the hand-over carries into the
    /// global layer, which the hold then brings back; [`active::HandedOver`]), m.
    pub(crate) handover_max: f64,
    /// Strands let go so far back in place (handed over to the global layer).
    pub(crate) handovers: u64,
    /// The same for the strands let go before they were back in place (after `HapticParams::max_relax_time`,
    /// or by the strand limit): the largest hand-over, m, and how many.
    pub(crate) early_handover_max: f64,
    pub(crate) early_handovers: u64,
    /// Wall-clock time of the last step's stages.
    pub(crate) timings: StepPhases,
}

/// One simulated guide's displacements staged for the next snapshot ([`HapticCore::stage_snapshot`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Staged {
    /// The guide.
    pub guide: usize,
    /// The haptic step they were mapped at.
    pub step: u64,
    /// Its samples' shown displacements, m.
    pub displacement: Vec<Vector3<f64>>,
}

/// Wall-clock time of the stages of one [`HapticCore::step`] (the numbered stages of the module
/// documentation), s. For profiling (bench/RESULTS.md); no result depends on it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepPhases {
    /// 1-2b: device, coupling, body, s.
    pub coupling: f64,
    /// 3-4: active set (choice and membership changes) and roots, s.
    pub active: f64,
    /// Of `active`: choosing the guides near the tool's path, s.
    pub choose: f64,
    /// Of `active`: moving the strands to a new membership, s.
    pub rebuild: f64,
    /// 5-6: wetness and tool actions, s.
    pub actions: f64,
    /// 7: the local interaction's step, s.
    pub interaction: f64,
    /// 8: tracking, s.
    pub tracking: f64,
    /// The local interaction's own phases.
    pub local: tools::interaction::StepTimings,
    /// Hair-hair contacts found (pairs of chords, before each strand keeps its deepest).
    pub hair_pairs: usize,
}

impl HapticCore {
    /// Moves the head to `head` (head frame to world): the simulated strands' roots follow it from the next
    /// step (`roots_follow`), and the body they rest on and the tool keeps out of moves with it. A pose with
    /// a non-finite part is ignored (returns false). The tool's device positions stay in the world frame.
    pub fn set_head_pose(&mut self, head: nalgebra::Isometry3<f64>) -> bool {
        let ok = crate::command::is_finite_pose(&head);
        if ok && head != self.head {
            self.head = head;
            if let Some((body, _)) = self.interaction.body.as_mut() {
                for (b, rest) in body.balls.iter_mut().zip(&self.scene.head.balls) {
                    b.centre = head * rest.centre;
                }
            }
        }
        ok
    }

    /// The head pose now (head frame to world).
    pub fn head_pose(&self) -> nalgebra::Isometry3<f64> {
        self.head
    }

    /// At rest with the comb selected.
    pub fn new(scene: Arc<Scene>, params: SessionParams) -> Result<Self, SessionError> {
        params.validate()?;
        let h = scene.hair_type;
        let strands = Self::build_strands(&scene, &h, 0.0, &params.haptic)?;
        let sets = strands.iter().map(|s| SetState::new(&s.model)).collect();
        let strands = strands.into_iter().map(Some).collect();
        let start = Vector3::from(params.haptic.start);
        let pose = ToolPose { position: start, rotation: Matrix3::identity() };
        let n = scene.guides.len();
        let shapes: Vec<tools::shape::ToolShape> = Tool::ALL.iter().map(|t| t.shape(params.global.nozzle_standoff)).collect();
        let mut interaction = resting_on(&scene, LocalInteraction::new(Vec::new(), shapes[Tool::Comb as usize].clone(), pose, Self::force_model(&params.haptic, &h, 0.0)));
        interaction.hold_distance = params.haptic.hold_distance;
        interaction.hold_gravity = scene.guides.first().map(|g| g.model.gravity.norm());
        let bounds = active::GuideBounds::new(&scene);
        let side = DeviceSide::new(params, shapes.clone(), (scene.head.clone(), scene.lattice.params.metaball.threshold));
        Ok(Self {
            scene, params, shapes, tool: Tool::Comb, hair_type: h, curliness: 0.0, combing_ease: 0.0, side, proxy: ProxyState::default(), anchors: 0, strands, active: Vec::new(), members: Vec::new(), handed: Vec::new(), references: Default::default(), staged: Default::default(), choice: None, bounds, queued: Vec::new(), max_tip_speed: 0.0, interaction,
            hair_force: HairReaction::none(), wetness: vec![0.0; n], wet_version: u64::MAX, wet_model: WetnessModel::default(), sets, cuts: 0, was_pressed: false, last_cut_at: None, step: 0, last_contacts: 0, last_select: None, clipped: false, strand_limit: params.max_active, head: nalgebra::Isometry3::identity(), rejected: 0, runaways: 0, failed: 0, handover_max: 0.0, handovers: 0, early_handover_max: 0.0, early_handovers: 0, timings: StepPhases::default(),
        })
    }

    /// Applies a viewer command.
    pub fn apply(&mut self, c: &Command) {
        self.wet_version = u64::MAX;
        match *c {
            Command::SelectTool(t) => {
                self.clear_active();
                self.tool = t;
                self.clipped = false;
                self.renew_interaction(Vec::new());
            }
            Command::SetHair { hair_type, curliness, combing_ease } => {
                let h = HairType::ALL.get(hair_type as usize).copied().unwrap_or(self.hair_type);
                let (c, e) = (if curliness.is_finite() { curliness.clamp(0.0, 1.0) } else { 0.0 }, if combing_ease.is_finite() { combing_ease.clamp(0.0, 1.0) } else { 0.0 });
                // The simulated strands go back to the store (and are rebuilt there for a new hair).
                self.clear_active();
                self.clipped = false;
                if h != self.hair_type || c != self.curliness {
                    if let Ok(s) = Self::build_strands(&self.scene, &h, c, &self.params.haptic) {
                        self.sets = s.iter().map(|s| SetState::new(&s.model)).collect();
                        self.strands = s.into_iter().map(Some).collect();
                    }
                }
                self.hair_type = h;
                self.curliness = c;
                self.combing_ease = e;
                self.renew_interaction(Vec::new());
            }
            Command::SetTreatment(t) => {
                // The frictions follow (`force_model`, `fibre_friction`); the strands keep their shape.
                self.clear_active();
                self.clipped = false;
                self.params.haptic.treatment = t;
                self.renew_interaction(Vec::new());
            }
            Command::SetHead { position, rotation } => {
                // Out of range or non-finite: ignored (the server checks and answers before).
                if let Some(head) = crate::command::head_pose(&position, &rotation) {
                    self.set_head_pose(head);
                }
            }
            Command::LimitStrands(n) => {
                let n = (n as usize).clamp(1, self.params.max_active);
                if n != self.strand_limit {
                    self.strand_limit = n;
                    // A new choice at the next step, of as many strands as the limit leaves room for; the
                    // strands beyond it are let go from the next step on (`HapticCore::update_active`).
                    self.last_select = None;
                }
            }
            Command::Reset => {
                // Back to the store first: if the rebuild fails, the store keeps every strand. A reset shows the
                // groom: no hand-over's offset is kept.
                self.clear_active();
                self.handed.clear();
                if let Ok(s) = Self::build_strands(&self.scene, &self.hair_type, self.curliness, &self.params.haptic) {
                    self.sets = s.iter().map(|s| SetState::new(&s.model)).collect();
                    self.strands = s.into_iter().map(Some).collect();
                }
                self.clipped = false;
                self.renew_interaction(Vec::new());
                self.wet_version = u64::MAX;
            }
        }
    }
    /// One haptic step of `dt` s with the device's latest `reading` (the mouse target) and the lattice
    /// snapshot `lattice`: [`HapticCore::step_rates`] with one device step per physics step. Returns the
    /// command for the device.
    pub fn step(&mut self, reading: Option<DeviceReading>, lattice: &LatticeSnapshot, dt: f64) -> DeviceCommand {
        let mut last = DeviceCommand::default();
        self.period(&[], &[reading], lattice, dt, dt, |_, c| last = *c);
        last
    }

    /// One physics period of `dt` s as the live session's two threads run it, on one thread: the device
    /// steps, one per reading of `readings`, each of the session's device period (`dt /
    /// SessionParams::device_steps`; a live period whose device loop lost ticks to a busy machine has fewer),
    /// render the local force model the previous physics step published (with its tool and head pose), while
    /// this period's physics step runs after the viewer `commands`, with the proxy's state at the period's
    /// start; its model is rendered in the next period (the live physics thread has the whole period to make
    /// it). `each(i, command)` sees each device step's command.
    pub fn step_rates(&mut self, commands: &[Command], readings: &[Option<DeviceReading>], lattice: &LatticeSnapshot, dt: f64, each: impl FnMut(usize, &DeviceCommand)) {
        let h = dt / self.params.device_steps() as f64;
        self.period(commands, readings, lattice, dt, h, each);
    }

    /// [`HapticCore::step_rates`] with device steps of `h` s.
    fn period(&mut self, commands: &[Command], readings: &[Option<DeviceReading>], lattice: &LatticeSnapshot, dt: f64, h: f64, mut each: impl FnMut(usize, &DeviceCommand)) {
        let published = self.published();
        let proxy = self.side.proxy_state();
        for (i, r) in readings.iter().enumerate() {
            let c = self.side.step(*r, h, &published);
            each(i, &c);
        }
        for c in commands {
            self.apply(c);
        }
        self.physics_step(&proxy, lattice, dt);
    }

    /// What the last physics step published for the device loop: its local force model, the tool and the head
    /// pose.
    pub fn published(&self) -> Published {
        Published { model: self.hair_force, step: self.step, tool: self.tool, head: self.head, anchors: self.anchors }
    }

    /// The physics step (stages 3-8) of `dt` s with the proxy's state `proxy` (from the device side) and the
    /// lattice snapshot `lattice`: the local strands step with the tool at the proxy's pose, and the hair's
    /// reaction linearised about that state becomes the model [`HapticCore::published`] gives.
    pub fn physics_step(&mut self, proxy: &ProxyState, lattice: &LatticeSnapshot, dt: f64) {
        self.step += 1;
        let clock = std::time::Instant::now();
        self.timings = StepPhases::default();
        self.proxy = *proxy;
        (self.rejected, self.runaways) = (proxy.rejected, proxy.runaways);
        if !proxy.present {
            // No device: nothing touches the hair (the next reading re-anchors the tool).
            self.hair_force = HairReaction::none();
            return;
        }
        if proxy.anchors != self.anchors {
            // Re-anchored: the tool's sweep starts where it is now.
            self.anchors = proxy.anchors;
            self.interaction.pose = ToolPose { position: proxy.position, rotation: proxy.rotation };
        }
        let (position, velocity, rotation) = (proxy.position, proxy.velocity, proxy.rotation);
        let t1 = clock.elapsed().as_secs_f64();
        self.timings.coupling = t1;
        // 3. Active set; 4. roots.
        self.update_active(&position, &velocity, &rotation, &lattice.positions, &lattice.head);
        self.roots_follow(dt);
        self.hold_in_place(lattice);
        let t2 = clock.elapsed().as_secs_f64();
        self.timings.active = t2 - t1;
        // 5. Wetness.
        self.apply_wetness(lattice);
        // 6. Tool actions (the primary button closes the scissors and the clip, blows the dryer).
        let pressed = proxy.buttons & 1 != 0;
        self.act(pressed, &position, &rotation);
        // 7. Local strands.
        let pose = ToolPose { position, rotation };
        let t3 = clock.elapsed().as_secs_f64();
        self.timings.actions = t3 - t2;
        match self.interaction.step(dt, pose) {
            Ok(res) => {
                self.timings.local = res.timings;
                self.timings.hair_pairs = res.hair_pairs;
                let n = self.hairs_per_guide();
                self.hair_force = HairReaction { force: res.force * n, damping: res.damping * n, velocity, position, stiffness: res.stiffness * n, torque: res.torque * n };
                self.last_contacts = res.contacts.len() as u32;
            }
            Err(_) => {
                self.failed += 1;
                self.hair_force = HairReaction::none();
                self.last_contacts = 0;
            }
        }
        let t4 = clock.elapsed().as_secs_f64();
        self.timings.interaction = t4 - t3;
        // 8. Tracking.
        self.track_active(dt, lattice);
        self.timings.tracking = clock.elapsed().as_secs_f64() - t4;
    }

    /// Real hairs each simulated guide stands for: the render strands times `hairs_per_render_strand`, shared
    /// among the guides (500 in the built-in scene), dimensionless, >= 1.
    pub fn hairs_per_guide(&self) -> f64 {
        (self.scene.render.strands() as f64 * self.params.hairs_per_render_strand / self.scene.guides.len().max(1) as f64).max(1.0)
    }

    /// What the global layer needs of the tool now.
    pub fn tool_input(&self) -> ToolInput {
        ToolInput { tool: self.tool, present: self.proxy.present, position: self.proxy.position, rotation: self.interaction.pose.rotation, pressed: self.was_pressed, cuts: self.cuts, head: self.head }
    }

    /// Stages the viewer's next snapshot, a share of it a step: the displacements of every
    /// `SessionParams::publish_every`-th simulated strand (this step's share of the slots) are mapped and kept,
    /// so that [`HapticCore::snapshot`] copies them rather than mapping every strand in the step that
    /// publishes (a cost that step alone would pay). Call once after each step where snapshots are
    /// published every `publish_every` steps; without it the snapshot maps every strand itself.
    pub fn stage_snapshot(&self, lattice: &LatticeSnapshot) {
        let every = self.params.publish_every.max(1);
        let share = (self.step % every) as usize;
        let ok = lattice.positions.len() == self.scene.lattice.node_count();
        let mut cache = self.references.borrow_mut();
        cache.use_nodes(&lattice.positions, &lattice.head);
        let mut staged = self.staged.borrow_mut();
        for slot in (share..self.active.len()).step_by(every as usize) {
            let g = self.active[slot];
            let i = match staged.iter().position(|e| e.guide == g) {
                Some(i) => i,
                None => {
                    staged.push(Staged { guide: g, step: 0, displacement: Vec::new() });
                    staged.len() - 1
                }
            };
            let e = &mut staged[i];
            e.step = self.step;
            e.displacement.clear();
            self.displacement_into(slot, g, &mut cache, ok, &mut e.displacement);
        }
    }

    /// Appends the shown displacement of simulated strand `slot` (guide `g`) to `out`: its samples minus their
    /// references mapped through the cache's nodes (`ok`: they are the lattice's), times its blend weight, m.
    fn displacement_into(&self, slot: usize, g: usize, cache: &mut reference::ReferenceCache, ok: bool, out: &mut Vec<Vector3<f64>>) {
        let s = &self.interaction.strands[slot];
        let weight = self.members.get(slot).map_or(1.0, |m| m.weight);
        let pts = samples_along(s, self.scene.guides[g].model.length, self.scene.samples());
        let bases = cache.bases(&self.scene, g, ok);
        for (p, base) in pts.into_iter().zip(bases) {
            out.push(self.shown((p - base) * weight));
        }
    }

    /// A displacement as the viewer may show it: zero if not finite or larger than
    /// `HapticParams::max_displacement` (a misbehaving strand must not throw the hairstyle across the scene).
    fn shown(&self, d: Vector3<f64>) -> Vector3<f64> {
        if d.iter().all(|x| x.is_finite()) && d.norm() < self.params.haptic.max_displacement { d } else { Vector3::zeros() }
    }

    /// Fills `out` with what the viewer needs. The simulated strands' displacements staged in the last
    /// `publish_every` steps ([`HapticCore::stage_snapshot`]) are copied, the others mapped now.
    pub fn snapshot(&self, lattice: &LatticeSnapshot, dt: f64, out: &mut HapticSnapshot) {
        out.step = self.step;
        out.time = self.step as f64 * dt;
        out.tool = self.tool as u8;
        out.tool_position = self.proxy.position;
        out.tool_rotation = self.interaction.pose.rotation;
        out.device_position = self.proxy.device;
        out.force = self.proxy.force;
        out.contacts = self.last_contacts;
        out.lattice_version = lattice.version;
        out.runaways = self.runaways;
        out.treatment = self.params.haptic.treatment;
        out.tool_friction = match self.interaction.model {
            tools::interaction::ForceModel::Constraint { friction, .. } => friction,
            _ => 0.0,
        };
        out.active.clear();
        out.displacement.clear();
        let ok = lattice.positions.len() == self.scene.lattice.node_count();
        let every = self.params.publish_every.max(1);
        let mut cache = self.references.borrow_mut();
        cache.use_nodes(&lattice.positions, &lattice.head);
        let mut staged = self.staged.borrow_mut();
        let turn = lattice.head.rotation;
        for (slot, &g) in self.active.iter().enumerate() {
            out.active.push(g as u32);
            let at = out.displacement.len();
            match staged.iter().find(|e| e.guide == g && e.step + every > self.step) {
                Some(e) => out.displacement.extend_from_slice(&e.displacement),
                None => self.displacement_into(slot, g, &mut cache, ok, &mut out.displacement),
            }
            // A guide simulated again while its hand-over's offset still relaxes shows both.
            if let Some(h) = self.handed.iter().find(|h| h.guide == g) {
                for (d, x) in out.displacement[at..].iter_mut().zip(&h.offset) {
                    *d = self.shown(*d + turn * x * h.weight);
                }
            }
        }
        // The handed-over guides: their offsets from their carried places, relaxing.
        for h in self.handed.iter().filter(|h| !self.active.contains(&h.guide)) {
            out.active.push(h.guide as u32);
            out.displacement.extend(h.offset.iter().map(|x| self.shown(turn * x * h.weight)));
        }
        cache.keep_only(&out.active);
        staged.retain(|e| self.active.contains(&e.guide));
    }

    /// Tool contacts of the last step.
    pub fn last_contacts(&self) -> u32 {
        self.last_contacts
    }
    /// Wall-clock time of the last step's stages.
    pub fn timings(&self) -> StepPhases {
        self.timings
    }
    /// Force last sent to the device, N (by the lockstep device side, [`HapticCore::side`]).
    pub fn force(&self) -> Vector3<f64> {
        self.side.coupling.force
    }
    /// Guide indices currently simulated.
    pub fn active(&self) -> &[usize] {
        &self.active
    }
    /// The virtual coupling between the device and the tool proxy (the lockstep device side's, after the last
    /// device step).
    pub fn coupling(&self) -> &Coupling {
        &self.side.coupling
    }
    /// The hair's reaction on the proxy from the last step (scaled to the real hairs), linearised.
    pub fn hair_reaction(&self) -> &HairReaction {
        &self.hair_force
    }
    /// The most strands simulated now ([`Command::LimitStrands`]; `SessionParams::max_active` unless limited).
    pub fn strand_limit(&self) -> usize {
        self.strand_limit
    }
    /// Wetness per guide as last read from the lattice snapshot.
    pub fn wetness(&self) -> &[f32] {
        &self.wetness
    }
    /// Fastest tip of the simulated strands over the last step, m/s.
    pub fn max_tip_speed(&self) -> f64 {
        self.max_tip_speed
    }
    /// The largest hand-over to the global layer so far, m: a let-go strand's largest shown displacement from
    /// its place carried by the global layer when it left the simulation (carried over as the guide's offset
    /// there, which the hold brings back: the hair drawn does not move at the hand-over; at most
    /// `HapticParams::handover_distance`: the strands let go before they were back in place are counted apart,
    /// [`HapticCore::early_handovers`]).
    pub fn handover_max(&self) -> f64 {
        self.handover_max
    }
    /// Strands let go back in place (handed over to the global layer) so far.
    pub fn handovers(&self) -> u64 {
        self.handovers
    }
    /// The strands let go before they were back in place (after `HapticParams::max_relax_time`, or by the strand
    /// limit, wherever they were, or by a command that empties the active set): their largest hand-over (as
    /// [`HapticCore::handover_max`], the displacement carried over), m, and how many so far.
    pub fn early_handovers(&self) -> (f64, u64) {
        (self.early_handover_max, self.early_handovers)
    }
    /// Length of each active strand, m (shorter than its guide's once cut).
    pub fn active_lengths(&self) -> Vec<f64> {
        self.interaction.strands.iter().map(|s| s.model.length).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::GlobalCore;
    use crate::params::InputKind;
    use crate::testing::{small_scene, test_rot};

    #[test]
    fn absurd_device_input_never_reaches_the_hand() {
        // (From the removed second live session, local_session.rs.) NaN readings in the middle of a comb
        // stroke: zero force on those steps, counted, and the stroke goes on with finite forces.
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let snap = GlobalCore::new(scene, &SessionParams::default()).snapshot();
        let mut forces = Vec::new();
        for n in 0..300 {
            let t = n as f64 * 1e-3;
            let p = if n == 50 || n == 80 { Vector3::new(f64::NAN, 0.0, 0.0) } else { Vector3::new(0.0, -0.118, 0.05 - 0.1 * t) };
            forces.push(core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3).force);
        }
        assert_eq!(core.rejected, 2);
        assert_eq!(forces[50], Vector3::zeros());
        assert_eq!(forces[80], Vector3::zeros());
        assert!(forces.iter().all(|f| f.iter().all(|x| x.is_finite())));
        assert!(forces[100..].iter().any(|f| f.norm() > 0.0), "the stroke goes on");
    }

    #[test]
    fn a_pointer_pressed_into_the_head_feels_the_hair_not_the_skull() {
        // The comb's target driven from behind the head (y = -0.2 m) at 0.24 m/s to 4 cm inside the cranium's
        // surface (its teeth 5.5 cm from the centre; the cranium's radius is 9 cm) and held there 0.7 s. A pointer's target is
        // kept out of the body as the tool is: the force stays that of the hair (below 1 N, never at the Omni's
        // 3.3 N clamp) and the tool is pressed onto the scalp's clearance, not into it. A device's target is a
        // hand's: the same path pulls it into the skull and it feels the clamp.
        let scene = small_scene();
        let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
        let run = |input: InputKind| {
            let params = SessionParams { input, ..SessionParams::default() };
            let mut core = HapticCore::new(scene.clone(), params).unwrap();
            let mut peak: f64 = 0.0;
            let mut inside: f64 = 0.0;
            for n in 0..1500 {
                let t = n as f64 * 1e-3;
                let y = (-0.2 + 0.24 * (t - 0.3).max(0.0)).min(-0.08);
                let r = DeviceReading { time: t, position: Vector3::new(0.0, y, 0.0), rotation: test_rot(), buttons: 0 };
                let f = core.step(Some(r), &snap, 1e-3).force.norm();
                peak = peak.max(f);
                if let (Some(dev), true) = (core.side.device.as_ref(), input == InputKind::Pointer) {
                    // How far the device point's tool would still have to move out (the push-out's tolerance is
                    // 1e-3 of the clearance).
                    let point = dev.point + core.side.out_of_body(&dev.point, &test_rot());
                    inside = inside.max(core.side.out_of_body(&point, &test_rot()).norm());
                }
            }
            (peak, inside)
        };
        let (pointer, inside) = run(InputKind::Pointer);
        let (device, _) = run(InputKind::Device);
        eprintln!("peak force: pointer {pointer} N (tool {inside} m inside the clearance), device {device} N");
        assert!(pointer > 1e-4 && pointer < 1.0, "pointer: {pointer} N");
        assert!(inside < 1e-5, "the pointer's tool {inside} m inside the clearance");
        assert!(device > 3.3 - 1e-9, "a device pressed into the head feels the clamp: {device} N");
    }

    #[test]
    fn a_runaway_proxy_is_put_back_on_the_device_with_zero_force() {
        // Issue 16's guard: whatever throws the proxy (here set by hand to 65 km, then to NaN) the next step
        // puts it back on the device at rest, sends zero force and counts it; the stroke then goes on.
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let snap = GlobalCore::new(scene, &SessionParams::default()).snapshot();
        let reading = |n: usize| DeviceReading { time: n as f64 * 1e-3, position: Vector3::new(0.0, -0.118, 0.05 - 1e-4 * n as f64), rotation: test_rot(), buttons: 0 };
        for n in 0..200 {
            if n == 100 {
                core.side.coupling.proxy = Vector3::new(6.5e4, 0.0, 0.0);
            }
            if n == 150 {
                core.side.coupling.proxy = Vector3::new(f64::NAN, 0.0, 0.0);
            }
            let f = core.step(Some(reading(n)), &snap, 1e-3).force;
            if n == 100 || n == 150 {
                assert_eq!(f, Vector3::zeros(), "step {n}");
                let device = core.side.device.as_ref().unwrap().point;
                assert!((core.side.coupling.proxy - device).norm() < 1e-12, "back on the device point at step {n}");
            }
            assert!(f.iter().all(|x| x.is_finite()) && f.norm() <= 3.3 + 1e-9);
        }
        assert_eq!(core.runaways, 2);
        // The viewer is told (FRAME carries the count).
        let mut hs = HapticSnapshot::default();
        core.snapshot(&snap, 1e-3, &mut hs);
        assert_eq!(hs.runaways, 2);
    }

    #[test]
    fn a_staged_snapshot_is_the_one_mapped_at_once_up_to_the_steps_between() {
        // The comb drawn down through the hair (0.1 m/s), the snapshot staged every step and written every
        // publish_every steps: the strands staged in the writing step itself give bit for bit what mapping every
        // strand at once gives; the others were staged at most publish_every - 1 = 4 ms earlier, so they differ
        // by at most how far a strand point moved meanwhile (under 2 mm here: the comb at 0.1 m/s moves 0.4 mm).
        let scene = small_scene();
        let params = SessionParams::default();
        let mut core = HapticCore::new(scene.clone(), params).unwrap();
        let snap = GlobalCore::new(scene, &params).snapshot();
        let (mut staged, mut fresh) = (HapticSnapshot::default(), HapticSnapshot::default());
        let (mut compared, mut exact) = (0, 0);
        for n in 0..900 {
            let t = n as f64 * 1e-3;
            let p = Vector3::new(0.0, -0.118, 0.05 - 0.1 * t);
            core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3);
            core.stage_snapshot(&snap);
            if core.step % params.publish_every == 0 && n > 300 {
                core.snapshot(&snap, 1e-3, &mut staged);
                let kept = core.staged.replace(Vec::new());
                core.snapshot(&snap, 1e-3, &mut fresh);
                core.staged.replace(kept);
                assert_eq!(staged.active, fresh.active);
                let k = core.scene.samples();
                for slot in 0..core.active().len() {
                    let (a, b) = (&staged.displacement[slot * k..(slot + 1) * k], &fresh.displacement[slot * k..(slot + 1) * k]);
                    let off = a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
                    if slot as u64 % params.publish_every == 0 {
                        assert_eq!(a, b, "slot {slot} staged in the writing step");
                    } else {
                        assert!(off < 2e-3, "slot {slot}: {off} m from the mapping at once");
                    }
                    exact += (off == 0.0) as usize;
                    compared += 1;
                }
            }
        }
        assert!(compared > 100 && exact < compared, "compared {compared} strands, {exact} equal: the strands moved");
    }

    #[test]
    fn combing_through_the_guides_gives_force_and_moves_them() {
        // Headless: the comb is dragged down the back of the head through the hair (0.1 m/s), stepping the
        // haptic core at 1 kHz on the rest lattice. The hand feels a force, the active guides leave their
        // reference shape, and nothing is rejected.
        let scene = small_scene();
        let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
        let snap = GlobalCore::new(scene, &SessionParams::default()).snapshot();
        let rot = Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)]);
        let mut peak: f64 = 0.0;
        let mut moved: f64 = 0.0;
        let mut hs = HapticSnapshot::default();
        for n in 0..1500 {
            let t = n as f64 * 1e-3;
            let p = Vector3::new(0.0, -0.118, 0.05 - 0.1 * t);
            let c = core.step(Some(DeviceReading { time: t, position: p, rotation: rot, buttons: 0 }), &snap, 1e-3);
            peak = peak.max(c.force.norm());
            if n % 50 == 0 {
                core.snapshot(&snap, 1e-3, &mut hs);
                moved = moved.max(hs.displacement.iter().map(|d| d.norm()).fold(0.0, f64::max));
            }
        }
        assert_eq!(core.rejected, 0);
        eprintln!("peak force {peak} N, largest displacement {moved} m");
        assert!(peak > 1e-3, "peak force {peak} N");
        assert!(peak <= 3.3 + 1e-12, "within the Omni's clamp: {peak} N");
        assert!(moved > 1e-3, "largest guide displacement {moved} m");
    }

    #[test]
    fn the_simulated_strands_rest_on_the_head_when_the_comb_presses_them() {
        // The comb pushed from the hair at the back of the head 6 cm towards the head's centre over 0.6 s,
        // then held. The simulated strands' centrelines (64 samples each) then lie no deeper than 2 mm inside
        // the body (depth to the surface; the contacts hold the collision pieces' ends, and the centreline may
        // dip between them: 1.3 mm measured); without the body contact the same push drives them 14.8 mm deep,
        // so the check can fail (asserted > 5 mm).
        let scene = small_scene();
        let deepest = |body: bool| {
            let mut core = HapticCore::new(scene.clone(), SessionParams::default()).unwrap();
            let snap = GlobalCore::new(scene.clone(), &SessionParams::default()).snapshot();
            let mut worst: f64 = 0.0;
            for n in 0..900 {
                let t = n as f64 * 1e-3;
                let p = Vector3::new(0.0, -0.13 + 0.06 * (t / 0.6).min(1.0), 0.0);
                core.step(Some(DeviceReading { time: t, position: p, rotation: test_rot(), buttons: 0 }), &snap, 1e-3);
                if !body {
                    core.interaction.body = None;
                    core.side.body = None;
                }
                if n % 100 == 99 {
                    let t = scene.lattice.params.metaball.threshold;
                    for s in &core.interaction.strands {
                        for (_, x) in strand::kinematics::centerline(&s.model, &s.state, 64) {
                            let q = scene.head.push_out(&x.into(), t, 0.0).coords;
                            worst = worst.max((q - x).norm());
                        }
                    }
                }
            }
            worst
        };
        let (with, without) = (deepest(true), deepest(false));
        eprintln!("deepest centreline point inside the body: {with} m with the body contact, {without} m without");
        assert!(with <= 2e-3, "{with} m inside the body");
        assert!(without > 5e-3, "without the body contact the check must be able to fail: {without} m");
    }
}
