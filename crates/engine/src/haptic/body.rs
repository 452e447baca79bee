//! The tool against the body: the proxy's tool stays outside the head, neck and shoulders (a god-object for
//! the body). A comb pushed into the scalp would otherwise reach the hair's roots, where a strand barely moves
//! (a contact 4 mm from a root gave 4 N on the hand, 500 hairs per guide), and pinch strands against the
//! scalp; instead the hand feels the head through the coupling spring, as with a real head. A pointer (the
//! mouse) is no hand: its target, a heuristic depth under the cursor (the viewer's pressed plane), is kept out
//! of the body in the same way, so that its coupling spring stretches against the hair, not into the skull
//! (`HapticCore::follow`).

use super::HapticCore;
use nalgebra::{Matrix3, Vector3};

impl HapticCore {
    /// Stage 2b of the step: every end of the tool's capsules (turned by `rotation`) is kept
    /// `HapticParams::body_clearance` plus its radius outside the body: the proxy moves out by the deepest
    /// push-out, and loses its velocity into the body.
    pub(crate) fn keep_tool_out_of_body(&mut self, rotation: &Matrix3<f64>) {
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
    pub(crate) fn out_of_body(&self, point: &Vector3<f64>, rotation: &Matrix3<f64>) -> Vector3<f64> {
        let Some((body, threshold)) = self.interaction.body.as_ref() else { return Vector3::zeros() };
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
