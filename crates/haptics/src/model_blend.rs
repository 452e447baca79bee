//! Phasing a new local force model in over a physics period. The device loop renders the hair's reaction
//! linearised about the proxy ([`HairReaction`]) at several device steps per physics step; each physics step
//! publishes a new linearisation, and where contacts came or went in that step the new model's force differs
//! from the old one's at the same proxy state by tens of mN: rendered at once, a force step the hand feels at
//! every model change (bench/RESULTS.md). As in Mark et al.'s
//! intermediate representation (SIGGRAPH 1996, the planes' "recovery" between simulation updates), the device
//! renders a blend `(1 - a) old + a new` with `a` rising linearly from `1/n` to 1 over the `n` device steps of
//! one physics period, so the force changes by at most its difference over a period, spread over the period.
//! A blend of two linear models is one linear model (stiffness and damping the blend of theirs, positive
//! semi-definite if theirs are), so the coupling renders it as it renders any model.

use crate::coupling::HairReaction;

/// `(1 - a) from + a to` as one model, exactly: the force at every position and velocity is the blend of the
/// two models' (`a` in [0, 1]).
pub fn blend(from: &HairReaction, to: &HairReaction, a: f64) -> HairReaction {
    let b = 1.0 - a;
    HairReaction {
        force: from.force_at(&to.position, &to.velocity) * b + to.force * a,
        damping: from.damping * b + to.damping * a,
        velocity: to.velocity,
        position: to.position,
        stiffness: from.stiffness * b + to.stiffness * a,
        torque: from.torque * b + to.torque * a,
    }
}

/// The model rendered at each device step while the newest one is phased in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelBlend {
    from: HairReaction,
    to: HairReaction,
    /// Device steps the newest model is phased in over (>= 1).
    steps: u32,
    /// Device steps rendered since it came.
    done: u32,
}

impl ModelBlend {
    /// Rendering `model` as it is.
    pub fn new(model: HairReaction) -> Self {
        Self { from: model, to: model, steps: 1, done: 1 }
    }

    /// Takes a new model, phased in over `steps` device steps (1: at once) from what is rendered now.
    pub fn take(&mut self, model: HairReaction, steps: u32) {
        self.from = self.current();
        self.to = model;
        self.steps = steps.max(1);
        self.done = 0;
    }

    /// Renders `model` at once (no hair after a re-anchoring or a rejected reading; the first model).
    pub fn reset(&mut self, model: HairReaction) {
        *self = Self::new(model);
    }

    /// The model rendered now.
    pub fn current(&self) -> HairReaction {
        if self.done >= self.steps {
            self.to
        } else {
            blend(&self.from, &self.to, self.done as f64 / self.steps as f64)
        }
    }

    /// Advances one device step and returns the model to render in it.
    pub fn advance(&mut self) -> HairReaction {
        self.done = (self.done + 1).min(self.steps);
        self.current()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    fn model(seed: f64) -> HairReaction {
        let m = Matrix3::new(2.0, 0.3, 0.1, 0.3, 1.0, 0.2, 0.1, 0.2, 3.0) * seed;
        HairReaction { force: Vector3::new(0.1, -0.2, 0.05) * seed, damping: m * 0.01, velocity: Vector3::new(0.1, 0.0, -0.05) * seed, position: Vector3::new(0.01, 0.02, -0.01) * seed, stiffness: m * 100.0, torque: Vector3::new(0.0, 1e-3, 0.0) * seed }
    }

    #[test]
    fn a_blend_is_the_blend_of_the_forces_everywhere() {
        // At random positions and velocities, the blended model's force equals (1 - a) F_old + a F_new to
        // 1e-12 N, for a in {0, 0.25, 0.5, 1}.
        let (a0, b0) = (model(1.0), model(-0.7));
        for a in [0.0, 0.25, 0.5, 1.0] {
            let m = blend(&a0, &b0, a);
            for k in 0..20 {
                let x = Vector3::new((k as f64 * 0.37).sin(), (k as f64 * 0.71).cos(), (k as f64 * 1.3).sin()) * 0.05;
                let v = Vector3::new((k as f64 * 0.5).cos(), (k as f64 * 0.9).sin(), 0.3) * 0.2;
                let want = a0.force_at(&x, &v) * (1.0 - a) + b0.force_at(&x, &v) * a;
                assert!((m.force_at(&x, &v) - want).norm() < 1e-12, "a {a}: {} vs {want}", m.force_at(&x, &v));
            }
        }
    }

    #[test]
    fn a_new_model_comes_in_over_the_steps_in_equal_parts() {
        // At a fixed proxy state, the force rendered moves from the old model's to the new one's in `n` equal
        // steps (n = 4: a quarter of the difference each), reaching the new model at the n-th step and staying;
        // a model taken mid-way starts from what was rendered.
        let (x, v) = (Vector3::new(0.0, 0.01, 0.0), Vector3::zeros());
        let (old, new) = (model(1.0), model(2.0));
        let mut b = ModelBlend::new(old);
        b.take(new, 4);
        let (f0, f1) = (old.force_at(&x, &v), new.force_at(&x, &v));
        for i in 1..=6 {
            let f = b.advance().force_at(&x, &v);
            let want = f0 + (f1 - f0) * (i.min(4) as f64 / 4.0);
            assert!((f - want).norm() < 1e-12, "step {i}: {f} vs {want}");
        }
        let mut b = ModelBlend::new(old);
        b.take(new, 4);
        b.advance();
        let mid = b.current().force_at(&x, &v);
        b.take(old, 4);
        assert!((b.current().force_at(&x, &v) - mid).norm() < 1e-12, "no step when a model comes mid-way");
    }
}
