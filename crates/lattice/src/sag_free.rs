//! Sag-free rest: the groomed shape as the lattice's equilibrium under gravity.
//!
//! A lattice built at the groomed positions with springs at rest there sags under gravity until
//! its springs carry the hair's weight: by about m g / k per node, i.e. sub-millimetre with stiff
//! springs (k_s = 20 N/m) but centimetres with springs soft enough for a dryer to blow the hair.
//! [`LatticeModel::make_sag_free`] removes the sag without removing gravity: it pre-stresses the
//! springs, moving every attachment target and every stiffener's rest length (as if the lattice had
//! been built at "virtual" rest positions X above the groomed ones) so that the groomed positions
//! are the equilibrium of the exact forces under gravity. Gravity still acts during motion: the
//! pre-stressed springs carry the weight, so a blown wisp swings back like a hanging one, and a
//! tilted head makes the hair hang a little differently, as it should. (This is the idea of the
//! strand crate's sag-free Super-Helices and of Hsu et al. 2023, "Sag-Free Initialization for
//! Strand-Based Hybrid Hair Simulation", applied to the lattice's springs.)
//!
//! Method: a fixed-point iteration on X. With X = rest, solve the static equilibrium x(X) under
//! gravity (quasi-static relaxation: repeated linearly implicit steps of `relax_dt` from zero
//! velocity, which is a Richardson iteration preconditioned by the step's constant matrix, whose
//! fixed points are exactly the zeros of the force); then X <- X - (x(X) - rest), until the largest
//! |x(X) - rest| is below `tolerance`. For linear springs one update is exact; the springs'
//! rotations make it converge in a few. The head is upright (identity pose) while solving.

use crate::lattice::{LatticeError, LatticeModel, LatticeState, LatticeWorkspace};
use crate::metaball::MetaballSet;
use nalgebra::{Isometry3, Point3, Vector3};

/// A stiffener's virtual rest length may not fall below this fraction of its length at rest (else the
/// springs are too soft to carry the weight and the solve fails).
const MIN_REST_FRACTION: f64 = 0.25;

/// Parameters of the sag-free rest solve ([`LatticeModel::make_sag_free`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagFreeParams {
    /// Largest distance of the equilibrium from the groomed position at which the solve stops, m.
    /// Default 1e-5 (10 um: far below what a viewer sees, and below the 2 mm the acceptance allows).
    pub tolerance: f64,
    /// Largest number of updates of the virtual rest positions. Default 10.
    pub max_updates: usize,
    /// Step of the quasi-static relaxation, s (larger converges faster; any value is stable).
    /// Default 0.1.
    pub relax_dt: f64,
    /// Largest number of relaxation steps per equilibrium solve. Default 3000.
    pub max_relax_steps: usize,
}

impl Default for SagFreeParams {
    fn default() -> Self {
        Self { tolerance: 1e-5, max_updates: 10, relax_dt: 0.1, max_relax_steps: 3000 }
    }
}

/// What [`LatticeModel::make_sag_free`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagFreeReport {
    /// Largest sag of the lattice as built (its equilibrium under gravity from the groomed shape), m.
    pub sag_before: f64,
    /// Largest distance of the final equilibrium from the groomed shape, m.
    pub residual: f64,
    /// Updates of the virtual rest positions made.
    pub updates: usize,
    /// Largest distance of an attachment target from its node's rest position after the solve, m.
    pub max_anchor_shift: f64,
}

impl LatticeModel {
    /// Pre-stresses the springs so that the rest positions are the equilibrium under gravity with
    /// the head upright (module docs), with the optional `obstacles` (head frame, e.g. the body) in
    /// the equilibrium. Changes `anchors` and the stiffeners' rest lengths only.
    ///
    /// Errors: bad parameters ([`LatticeError::InvalidParameter`]), or an equilibrium that does not
    /// converge (e.g. a node with no attachment and no stiffener; the model is then unchanged).
    pub fn make_sag_free(&mut self, params: &SagFreeParams, obstacles: Option<&MetaballSet>) -> Result<SagFreeReport, LatticeError> {
        let bad = |what: &str, v: f64| Err(LatticeError::InvalidParameter(format!("sag-free {what} must be > 0 and finite, got {v}")));
        if !(params.tolerance > 0.0 && params.tolerance.is_finite()) {
            return bad("tolerance (m)", params.tolerance);
        }
        if !(params.relax_dt > 0.0 && params.relax_dt.is_finite()) {
            return bad("relax_dt (s)", params.relax_dt);
        }
        let original = self.clone();
        let mut virtual_rest = self.rest.clone();
        let mut workspace = LatticeWorkspace::default();
        let mut x = self.rest.clone();
        let (mut sag_before, mut residual, mut updates) = (0.0, f64::INFINITY, 0);
        for round in 0..=params.max_updates {
            x = match self.equilibrium(&x, &mut workspace, params, obstacles) {
                Some(x) => x,
                None => {
                    *self = original;
                    return Err(LatticeError::InvalidParameter("sag-free rest: the equilibrium under gravity did not converge".into()));
                }
            };
            residual = x.iter().zip(&self.rest).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            if round == 0 {
                sag_before = residual;
            }
            if residual <= params.tolerance || round == params.max_updates {
                break;
            }
            for ((v, xi), r) in virtual_rest.iter_mut().zip(&x).zip(&self.rest) {
                *v -= xi - r;
            }
            self.set_virtual_rest(&virtual_rest);
            updates += 1;
            // Springs too soft for the weight: they would need (nearly) no rest length to carry it.
            if let Some((s, o)) = self.stiffeners.iter().zip(&original.stiffeners).find(|(s, o)| s.rest_length < MIN_REST_FRACTION * o.rest_length) {
                let msg = format!(
                    "sag-free rest: the springs are too soft to carry the hair's weight (stiffener {}-{} would need a rest length of {:.4} m for {:.4} m)",
                    s.i, s.j, s.rest_length, o.rest_length
                );
                *self = original;
                return Err(LatticeError::InvalidParameter(msg));
            }
        }
        if residual > 10.0 * params.tolerance {
            let msg = format!("sag-free rest: no convergence after {updates} updates (residual {residual:.3e} m, tolerance {:.1e} m)", params.tolerance);
            *self = original;
            return Err(LatticeError::InvalidParameter(msg));
        }
        let max_anchor_shift = self.anchors.iter().zip(&self.rest).map(|(a, r)| (a - r).norm()).fold(0.0, f64::max);
        Ok(SagFreeReport { sag_before, residual, updates, max_anchor_shift })
    }

    /// Attachment targets at `x` and stiffener rest lengths from `x` (m, head frame).
    fn set_virtual_rest(&mut self, x: &[Point3<f64>]) {
        self.anchors.copy_from_slice(x);
        for s in self.stiffeners.iter_mut() {
            s.rest_length = (x[s.j] - x[s.i]).norm();
        }
    }

    /// The static equilibrium under gravity with the head upright, from `start` (m): quasi-static
    /// relaxation until a step moves no node by more than a tenth of the tolerance. None if it
    /// does not converge or leaves finite numbers.
    fn equilibrium(&self, start: &[Point3<f64>], workspace: &mut LatticeWorkspace, params: &SagFreeParams, obstacles: Option<&MetaballSet>) -> Option<Vec<Point3<f64>>> {
        let head = Isometry3::identity();
        let n = self.node_count();
        let mut state = LatticeState { positions: start.to_vec(), velocities: vec![Vector3::zeros(); n], last_cg_iterations: 0, rejected_steps: 0 };
        for _ in 0..params.max_relax_steps {
            let before = state.positions.clone();
            state.velocities.iter_mut().for_each(|v| *v = Vector3::zeros());
            self.step(&mut state, workspace, params.relax_dt, &head, obstacles);
            if state.rejected_steps > 0 {
                return None;
            }
            let moved = state.positions.iter().zip(&before).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            if moved <= 0.1 * params.tolerance {
                return Some(state.positions);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffd::FfdLattice;
    use crate::lattice::LatticeParams;

    /// A 6 x 6 x 5 lattice of 2 cm cells hanging from its top layer (attached), soft springs.
    fn hanging(params: LatticeParams) -> LatticeModel {
        let ffd = FfdLattice::new(Point3::new(-0.05, -0.05, -0.08), 0.02, [6, 6, 5]).unwrap();
        let n = ffd.node_count();
        let attachment = (0..n).map(|q| if ffd.rest_positions()[q].z > 0.0 - 1e-9 { 1.0 } else { 0.0 }).collect();
        LatticeModel::new(ffd, vec![2e-4; n], attachment, params).unwrap()
    }

    fn soft() -> LatticeParams {
        LatticeParams { stiffener_stiffness: 0.5, bending_stiffness: 0.1, attachment_stiffness: 0.5, ..LatticeParams::default() }
    }

    #[test]
    fn a_soft_lattice_sags_and_the_sag_free_rest_removes_it() {
        // Without compensation the soft lattice sags by centimetres under gravity (checked against the
        // order of magnitude m g / k); with it, a dynamic run of 5 s from the groomed shape stays within
        // 0.1 mm of it (the solve's tolerance is 10 um; the dynamics' drift must not add more).
        let mut m = hanging(soft());
        let head = Isometry3::identity();
        let mut w = LatticeWorkspace::default();
        let mut s = m.rest_state(&head);
        for _ in 0..500 {
            m.step(&mut s, &mut w, 0.01, &head, None);
        }
        let sag = s.positions.iter().zip(&m.rest).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        let report = m.make_sag_free(&SagFreeParams::default(), None).unwrap();
        eprintln!("sag as built {sag:.4} m (solve: {report:?})");
        assert!(sag > 5e-3, "the soft lattice sags visibly: {sag} m");
        assert!((report.sag_before - sag).abs() < 0.05 * sag, "the solve's sag {} agrees with the dynamic one {sag}", report.sag_before);
        assert!(report.residual <= 1e-5 && report.updates >= 1);
        let mut s = m.rest_state(&head);
        let mut w = LatticeWorkspace::default();
        let mut worst = 0.0f64;
        for _ in 0..500 {
            m.step(&mut s, &mut w, 0.01, &head, None);
            worst = worst.max(s.positions.iter().zip(&m.rest).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max));
        }
        eprintln!("sag-free: largest distance from the groomed shape over 5 s {worst:.2e} m");
        assert!(worst < 1e-4, "sag-free rest holds the groomed shape: {worst} m");
    }

    #[test]
    fn sag_free_keeps_gravity_a_displaced_lattice_swings_back_to_the_groomed_shape() {
        // Gravity still acts: a sideways kick of the sag-free lattice dies out and it comes back to the
        // groomed shape (within 0.1 mm after 10 s), and its weight is still carried by the springs: the
        // attachment targets sit above the rest positions (the top layer holds the weight).
        let mut m = hanging(soft());
        m.make_sag_free(&SagFreeParams::default(), None).unwrap();
        let lifted = m.anchors.iter().zip(&m.rest).zip(&m.attachment).filter(|(_, &a)| a > 0.0).all(|((x, r), _)| x.z > r.z);
        assert!(lifted, "the attached layer's targets are above the rest positions");
        let head = Isometry3::identity();
        let mut w = LatticeWorkspace::default();
        let mut s = m.rest_state(&head);
        s.velocities.iter_mut().for_each(|v| *v = Vector3::new(0.2, 0.0, 0.0));
        let mut swing = 0.0f64;
        for _ in 0..1000 {
            m.step(&mut s, &mut w, 0.01, &head, None);
            swing = swing.max(s.positions.iter().zip(&m.rest).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max));
        }
        let back = s.positions.iter().zip(&m.rest).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        eprintln!("kicked at 0.2 m/s: swing {swing:.4} m, after 10 s {back:.2e} m");
        assert!(swing > 5e-3 && back < 1e-4, "swing {swing} m, back to {back} m");
    }

    #[test]
    fn springs_too_soft_for_the_weight_are_refused_and_the_model_is_kept() {
        // 400 times softer than `soft()`: the weight would need rest lengths below a quarter of the cells.
        let p = soft();
        let mut m = hanging(LatticeParams { stiffener_stiffness: p.stiffener_stiffness / 400.0, bending_stiffness: p.bending_stiffness / 400.0, attachment_stiffness: p.attachment_stiffness / 400.0, ..p });
        let before = m.clone();
        let e = m.make_sag_free(&SagFreeParams::default(), None).unwrap_err();
        assert!(e.to_string().contains("sag-free rest"), "{e}");
        assert_eq!(m, before, "the model is unchanged");
    }

    #[test]
    fn bad_parameters_are_named() {
        let mut m = hanging(soft());
        let e = m.make_sag_free(&SagFreeParams { tolerance: -1.0, ..Default::default() }, None).unwrap_err();
        assert!(e.to_string().contains("tolerance"), "{e}");
    }
}
