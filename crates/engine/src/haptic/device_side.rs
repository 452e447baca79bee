//! The device loop's side of the haptic layer: stages 1-2c of the haptic step, run at the device's rate
//! (`SessionParams::device_rate_hz`, 4 kHz by default) against the **local force model** the last physics step
//! published ([`Published`]: the hair's reaction linearised about the proxy's state, `HairReaction`, valid
//! until the next model). One device step, in order:
//! 1. **Device**: the device point follows the pointer's target or the device's samples (`haptics::target`;
//!    a non-finite target is rejected; no reading: zero force, and the next re-anchors the tool);
//! 2. **Coupling**: `haptics::coupling::Coupling::update_implicit` against the model (the same law at any
//!    rate; its passivity observer runs at this rate), giving the force and torque on the hand;
//!    2b. **Body**: the tool stays outside the head, neck and shoulders (a god-object for the body,
//!    [`DeviceSide::out_of_body`]). A comb pushed into the scalp would otherwise reach the hair's roots, where
//!    a strand barely moves (a contact 4 mm from a root gave 4 N on the hand, 500 hairs per guide), and pinch
//!    strands against the scalp; instead the hand feels the head through the coupling spring, as with a real
//!    head. A pointer (the mouse) is no hand: its target, a heuristic depth under the cursor (the viewer's
//!    pressed plane), is kept out of the body in the same way, so that its coupling spring stretches against
//!    the hair, not into the skull;
//!    2c. **Runaway guard**: a proxy non-finite or too far from the device goes back on it with zero force.
//!
//! The physics step (stages 3-8, [`super::HapticCore::physics_step`]) reads what this side did through a
//! [`ProxyState`]. In lockstep ([`super::HapticCore::step_rates`]) both run on one thread; in the live session
//! on two threads with the same schedule (`crate::live`).

use crate::params::{InputKind, SessionParams};
use crate::tool::Tool;
use haptics::coupling::{Coupling, CouplingParams, HairReaction};
use haptics::device::{DeviceCommand, DeviceReading};
use haptics::model_blend::ModelBlend;
use haptics::target::TargetFilter;
use lattice::metaball::MetaballSet;
use nalgebra::{Isometry3, Matrix3, Vector3};
use tools::shape::ToolShape;

/// What a physics step publishes for the device loop: the local force model and what the device side needs of
/// the session's state (the tool's shape and the head's pose for the body contact).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Published {
    /// The hair's reaction on the tool proxy, linearised about the proxy's state the physics step used (scaled
    /// to the real hairs), N, N/m, N s/m, N m.
    pub model: HairReaction,
    /// The physics step that made it (0: none yet).
    pub step: u64,
    /// The selected tool.
    pub tool: Tool,
    /// The head pose (head frame to world).
    pub head: Isometry3<f64>,
    /// The device side's re-anchorings the physics step had seen (`ProxyState::anchors`): the model holds about
    /// the proxy of that anchoring only.
    pub anchors: u64,
}

impl Default for Published {
    fn default() -> Self {
        Self { model: HairReaction::none(), step: 0, tool: Tool::Comb, head: Isometry3::identity(), anchors: 0 }
    }
}

/// What the physics step reads of the device side: the proxy's state after the latest device step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProxyState {
    /// A device or pointer is being followed (false before the first reading and after the stream is lost).
    pub present: bool,
    /// Tool proxy position, m.
    pub position: Vector3<f64>,
    /// Tool proxy velocity, m/s.
    pub velocity: Vector3<f64>,
    /// Tool rotation (tool frame to world): the device's.
    pub rotation: Matrix3<f64>,
    /// The device's buttons (bit 0: primary).
    pub buttons: u32,
    /// The device point the proxy is coupled to, m.
    pub device: Vector3<f64>,
    /// Force last sent to the device, N.
    pub force: Vector3<f64>,
    /// Torque last sent to the device, N m.
    pub torque: Vector3<f64>,
    /// Device readings rejected so far (NaN, teleport).
    pub rejected: u64,
    /// Device steps so far in which the runaway guard put the proxy back on the device.
    pub runaways: u64,
    /// Times the tool was re-anchored on the device (first reading, first after none, runaway reset): the
    /// physics step restarts the tool's sweep where it is when this changes.
    pub anchors: u64,
}

impl Default for ProxyState {
    fn default() -> Self {
        let z = Vector3::zeros();
        Self { present: false, position: z, velocity: z, rotation: Matrix3::identity(), buttons: 0, device: z, force: z, torque: z, rejected: 0, runaways: 0, anchors: 0 }
    }
}

/// The device loop's state: the device point, the coupling and the model it renders.
#[derive(Debug, Clone)]
pub struct DeviceSide {
    params: SessionParams,
    /// Each tool's shape (by wire id).
    shapes: Vec<ToolShape>,
    /// The head's metaballs at rest (head frame), and now (at `head`) with the body surface's threshold
    /// (None: no body, the tool goes anywhere).
    rest_body: MetaballSet,
    pub(crate) body: Option<(MetaballSet, f64)>,
    head: Isometry3<f64>,
    tool: Tool,
    /// The virtual coupling between the device and the tool proxy.
    pub coupling: Coupling,
    /// Device point following the pointer's target or the device's samples; None while no reading.
    pub device: Option<TargetFilter>,
    /// The local force model rendered (the newest phased in over a physics period, `haptics::model_blend`), and
    /// the physics step that published the newest.
    model: ModelBlend,
    model_step: u64,
    rotation: Matrix3<f64>,
    buttons: u32,
    anchors: u64,
    /// Rejected device readings (NaN, teleport).
    pub rejected: u64,
    /// Device steps in which the runaway guard put the proxy back on the device (`HapticParams::max_proxy_lag`).
    pub runaways: u64,
}

impl DeviceSide {
    /// At rest at `HapticParams::start`, the comb selected, `body` (the head's metaballs, head frame, with the
    /// surface threshold) at the identity pose.
    pub fn new(params: SessionParams, shapes: Vec<ToolShape>, body: (MetaballSet, f64)) -> Self {
        let start = Vector3::from(params.haptic.start);
        let coupling = Coupling::new(params.profile, CouplingParams::for_profile(&params.profile), start);
        Self {
            params,
            shapes,
            rest_body: body.0.clone(),
            body: Some(body),
            head: Isometry3::identity(),
            tool: Tool::Comb,
            coupling,
            device: None,
            model: ModelBlend::new(HairReaction::none()),
            model_step: 0,
            rotation: Matrix3::identity(),
            buttons: 0,
            anchors: 0,
            rejected: 0,
            runaways: 0,
        }
    }

    /// Takes what the physics published: a newer model replaces the one rendered; the tool and head pose are
    /// followed.
    fn take(&mut self, p: &Published) {
        if p.step != self.model_step {
            self.model_step = p.step;
            // A model made about the proxy before its last re-anchoring (the device came back elsewhere after a
            // loss, a runaway put it back on the device) holds nowhere near the proxy now: no hair until the next
            // one. (Seen when a late physics step published the hair's reaction at the old place after the device
            // came back 12 cm away: 0.78 N at once.)
            // The newest model is phased in over this physics period's device steps: contacts that came or went
            // in the physics step change its force, felt as a step at every model if rendered at once.
            if p.anchors == self.anchors {
                self.model.take(p.model, self.params.device_steps() as u32);
            } else {
                self.model.reset(HairReaction::none());
            }
        }
        self.tool = p.tool;
        if p.head != self.head && crate::command::is_finite_pose(&p.head) {
            self.head = p.head;
            if let Some((body, _)) = self.body.as_mut() {
                for (b, rest) in body.balls.iter_mut().zip(&self.rest_body.balls) {
                    b.centre = p.head * rest.centre;
                }
            }
        }
    }

    /// One device step of `dt` s with the device's latest `reading` against the model in `published`.
    /// Returns the command for the device.
    pub fn step(&mut self, reading: Option<DeviceReading>, dt: f64, published: &Published) -> DeviceCommand {
        self.take(published);
        let Some(r) = reading else {
            // No reading: before the first, or a device's stream lost. Zero force; the next reading
            // re-anchors device, proxy and tool where the device is (`follow`).
            if self.device.take().is_some() {
                self.coupling.force = Vector3::zeros();
                self.coupling.torque = Vector3::zeros();
            }
            return DeviceCommand::default();
        };
        // 1. Device.
        let Some(reading) = self.follow(&r, dt) else { return DeviceCommand::default() };
        self.rotation = r.rotation;
        self.buttons = r.buttons;
        // 2. Coupling.
        let model = self.model.advance();
        let force = match self.coupling.update_implicit(&reading, dt, &model) {
            Ok(f) => f,
            Err(_) => {
                self.rejected += 1;
                self.model.reset(HairReaction::none());
                return DeviceCommand::default();
            }
        };
        // 2b. Body.
        self.keep_tool_out_of_body(&r.rotation);
        // 2c. Runaway guard: a proxy that is non-finite or too far from the device goes back on it, at rest,
        // with zero force (counted). It never should; if the physics ever throws it, the hand feels nothing.
        let lag = (self.coupling.proxy - reading.position).norm();
        if !(lag <= self.params.haptic.max_proxy_lag) {
            self.runaways += 1;
            self.coupling.put_proxy_at(reading.position);
            self.model.reset(HairReaction::none());
            self.anchors += 1;
            return DeviceCommand::default();
        }
        DeviceCommand { force, torque: self.coupling.torque }
    }

    /// [`DeviceSide::step`] with `reading` after `carried` device steps with `before` (the reading from before a
    /// loss of device ticks; each step `dt` s): a device loop that lost more ticks than its period had room for
    /// runs the rest here, so the device side's clock keeps the hand's pace (dropped, the follower caught up through
    /// the coupling's damper: a force pulse). Returns the last step's command (the others are not sent).
    pub fn step_after(&mut self, before: Option<DeviceReading>, carried: u32, reading: Option<DeviceReading>, dt: f64, published: &Published) -> DeviceCommand {
        for _ in 0..carried {
            self.step(before, dt, published);
        }
        self.step(reading, dt, published)
    }

    /// The proxy's state now, for the physics step.
    pub fn proxy_state(&self) -> ProxyState {
        let c = &self.coupling;
        ProxyState {
            present: self.device.is_some(),
            position: c.proxy,
            velocity: c.proxy_velocity,
            rotation: self.rotation,
            buttons: self.buttons,
            device: self.device.as_ref().map_or(c.proxy, |d| d.point),
            force: c.force,
            torque: c.torque,
            rejected: self.rejected,
            runaways: self.runaways,
            anchors: self.anchors,
        }
    }

    /// The local force model rendered now (the newest, phased in over the physics period).
    pub fn model(&self) -> HairReaction {
        self.model.current()
    }

    /// The device point following the pointer's target or the device's samples `r` (interpolated between
    /// them, `SessionParams::input`; a pointer's kept out of the body, [`DeviceSide::out_of_body`]), as a
    /// reading; None (counted) for a non-finite target. The first reading (and the first after none) puts
    /// device, proxy and tool where the pointer or device is, at rest.
    fn follow(&mut self, r: &DeviceReading, dt: f64) -> Option<DeviceReading> {
        let target = r.position;
        if !target.iter().all(|x| x.is_finite()) {
            self.rejected += 1;
            return None;
        }
        if self.device.is_none() {
            self.coupling = Coupling::new(self.params.profile, CouplingParams::for_profile(&self.params.profile), target);
            self.model.reset(HairReaction::none());
            self.anchors += 1;
        }
        let follow = match self.params.input {
            InputKind::Pointer => self.params.pointer,
            InputKind::Device => self.params.device_follow,
        };
        let dev = self.device.get_or_insert_with(|| TargetFilter::new(follow, target));
        let mut point = dev.follow(&target, r.time, dt);
        if self.params.input == InputKind::Pointer {
            // The pointer's depth is the viewer's guess (its pressed plane): the device point is kept out of the
            // body as the tool is, so that pressing near a bulge of the head does not pull the hand into the
            // skull at the device's force limit (3.3 N, seen pressing and drawing at once before the tool had
            // come over the head).
            point += self.out_of_body(&point, &r.rotation);
        }
        Some(DeviceReading { position: point, ..*r })
    }

    /// Stage 2b: every end of the tool's capsules (turned by `rotation`) is kept `HapticParams::body_clearance`
    /// plus its radius outside the body: the proxy moves out by the deepest push-out, and loses its velocity
    /// into the body.
    fn keep_tool_out_of_body(&mut self, rotation: &Matrix3<f64>) {
        let push = self.out_of_body(&self.coupling.proxy, rotation);
        let depth = push.norm();
        if depth > 0.0 {
            let n = push / depth;
            self.coupling.proxy += push;
            let into = self.coupling.proxy_velocity.dot(&n);
            if into < 0.0 {
                self.coupling.proxy_velocity -= n * into;
            }
        }
    }

    /// The move that takes the selected tool at `point` (m), turned by `rotation`, out of the body: every end of
    /// its capsules `HapticParams::body_clearance` plus its radius outside (the deepest end's push-out), m; zero
    /// if none is within that, or without a body.
    pub fn out_of_body(&self, point: &Vector3<f64>, rotation: &Matrix3<f64>) -> Vector3<f64> {
        let Some((body, threshold)) = self.body.as_ref() else { return Vector3::zeros() };
        let shape = &self.shapes[self.tool as usize];
        let mut push = Vector3::zeros();
        for c in &shape.capsules {
            for end in [c.a, c.b] {
                let x = point + rotation * Vector3::from(end);
                let d = body.push_out(&x.into(), *threshold, self.params.haptic.body_clearance + c.radius).coords - x;
                if d.norm_squared() > push.norm_squared() && d.iter().all(|v| v.is_finite()) {
                    push = d;
                }
            }
        }
        push
    }
}
