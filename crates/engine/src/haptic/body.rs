//! The tool against the body: the proxy's tool stays outside the head, neck and shoulders (a god-object for
//! the body). A comb pushed into the scalp would otherwise reach the hair's roots, where a strand barely moves
//! (a contact 4 mm from a root gave 4 N on the hand, 500 hairs per guide), and pinch strands against the
//! scalp; instead the hand feels the head through the coupling spring, as with a real head.

use super::HapticCore;
use nalgebra::{Matrix3, Vector3};

impl HapticCore {
    /// Stage 2b of the step: every end of the tool's capsules (turned by `rotation`) is kept
    /// `HapticParams::body_clearance` plus its radius outside the body: the proxy moves out by the deepest
    /// push-out, and loses its velocity into the body.
    pub(crate) fn keep_tool_out_of_body(&mut self, rotation: &Matrix3<f64>) {
        let Some((body, threshold)) = self.interaction.body.as_ref() else { return };
        let shape = &self.shapes[self.tool as usize];
        let proxy = self.coupling.proxy;
        let mut push = Vector3::zeros();
        for c in &shape.capsules {
            for end in [c.a, c.b] {
                let x = proxy + rotation * Vector3::from(end);
                let d = body.push_out(&x.into(), *threshold, self.params.haptic.body_clearance + c.radius).coords - x;
                if d.norm_squared() > push.norm_squared() && d.iter().all(|v| v.is_finite()) {
                    push = d;
                }
            }
        }
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
}
