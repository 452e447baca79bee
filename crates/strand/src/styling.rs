//! Wet styling: a shape held while hair dries becomes its rest shape ("water set", hydrogen-bond setting).
//!
//! A fibre's rest curvature and twist are held partly by covalent disulfide bonds (permanent: only chemistry
//! changes them) and partly by hydrogen bonds and salt links, which water breaks and which re-form, in whatever
//! shape the fibre has, as it dries (Robbins, "Chemical and Physical Behavior of Human Hair", water setting).
//! The model keeps, per generalized coordinate, a permanent rest value `p` (the strand's rest shape when the
//! set state was made) and a set value `c` (the shape the hydrogen bonds hold), and the rest shape is
//!
//! `q_rest = p + h (c - p)`, h = [`SetModel::hydrogen_share`].
//!
//! When a segment's wetness falls from w to w' < w, the fraction `(w - w') / w` of the bonds still broken
//! re-forms in the current shape: `c <- c + (w - w')/w (q - c)`. Dried completely (w' = 0) while held at q,
//! `c = q` exactly. When wetness rises from w to w' > w, the fraction `(w' - w)/(1 - w)` of the bonds still
//! formed breaks and their memory goes back to the permanent shape: `c <- c + (w' - w)/(1 - w) (p - c)`;
//! soaked (w' = 1), the set is forgotten, `c = p`. Dry hair (w constant) never changes its rest shape.
//! Wetness comes from outside (the tools crate's wetness field: one value per segment, in [0, 1]).

use crate::error::{Result, StrandError};
use crate::model::StrandModel;
use nalgebra::DVector;

/// Parameters of wet setting (immutable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetModel {
    /// Share h of the rest shape held by hydrogen bonds and salt links, dimensionless in [0, 1]: the fraction
    /// of a held shape kept after drying. Default 0.8 (a model choice giving a strong but incomplete water
    /// set; Robbins reports water sets as largely kept until the hair is wetted again, without one figure).
    pub hydrogen_share: f64,
}

impl Default for SetModel {
    fn default() -> Self {
        Self { hydrogen_share: 0.8 }
    }
}

/// The set state of one strand (mutable): permanent and set shapes and the wetness last seen per segment.
#[derive(Debug, Clone, PartialEq)]
pub struct SetState {
    /// Permanent (disulfide) rest coordinates p, rad/m (2N or 3N).
    pub permanent: DVector<f64>,
    /// Shape held by hydrogen bonds c, rad/m (2N or 3N).
    pub set: DVector<f64>,
    /// Wetness per segment at the last update, dimensionless in [0, 1].
    pub wetness: Vec<f64>,
}

impl SetState {
    /// A dry strand whose current rest shape is its permanent shape.
    pub fn new(model: &StrandModel) -> Self {
        let p = model.rest_coordinates();
        Self {
            set: p.clone(),
            permanent: p,
            wetness: vec![0.0; model.segments],
        }
    }

    /// Takes the new wetness of every segment (`wetness`, one value per segment in [0, 1]) with the strand at
    /// coordinates `q`, updates the set shape by the law of the module docs, and writes the resulting rest
    /// shape into `model`. Errors (nothing changed) name a wrong length or a value outside [0, 1] or NaN.
    pub fn update(
        &mut self,
        params: &SetModel,
        model: &mut StrandModel,
        q: &DVector<f64>,
        wetness: &[f64],
    ) -> Result<()> {
        let h = params.hydrogen_share;
        if !(h.is_finite() && (0.0..=1.0).contains(&h)) {
            return Err(StrandError::InvalidParameter {
                field: "hydrogen_share",
                reason: format!("must be in [0, 1], got {h}"),
            });
        }
        let d = model.dofs_per_segment();
        if wetness.len() != model.segments
            || self.wetness.len() != model.segments
            || q.len() != model.dofs()
            || self.set.len() != model.dofs()
        {
            return Err(StrandError::InvalidParameter {
                field: "wetness",
                reason: format!(
                    "needs one value per segment ({}), got {} (and q of length {})",
                    model.segments,
                    wetness.len(),
                    model.dofs()
                ),
            });
        }
        for (i, &w) in wetness.iter().enumerate() {
            if !(w.is_finite() && (0.0..=1.0).contains(&w)) {
                return Err(StrandError::InvalidParameter {
                    field: "wetness",
                    reason: format!("segment {i}: must be in [0, 1], got {w}"),
                });
            }
            if !q.rows(i * d, d).iter().all(|x| x.is_finite()) {
                return Err(StrandError::InvalidParameter {
                    field: "q",
                    reason: format!("segment {i} is not finite"),
                });
            }
        }
        for (i, &w_new) in wetness.iter().enumerate() {
            let w_old = self.wetness[i];
            for k in i * d..(i + 1) * d {
                if w_new < w_old {
                    let f = (w_old - w_new) / w_old;
                    self.set[k] += f * (q[k] - self.set[k]);
                } else if w_new > w_old {
                    let f = (w_new - w_old) / (1.0 - w_old);
                    self.set[k] += f * (self.permanent[k] - self.set[k]);
                }
            }
            self.wetness[i] = w_new;
        }
        let rest = &self.permanent + (&self.set - &self.permanent) * h;
        model.set_rest_coordinates(&rest);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{HairType, ModelKind, RootFrame, Strand};
    use nalgebra::Vector3;

    /// Holds a straight H1 strand in a curl (bend 25 rad/m, twist 5 rad/m) for 1 s while its wetness goes from
    /// `w0` to 0, then releases it without gravity for 3 s and returns (final q, held q).
    fn hold_dry_release(w0: f64) -> (DVector<f64>, DVector<f64>) {
        let h = HairType::H1;
        let mut model =
            StrandModel::new(ModelKind::Reduced, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
        model.gravity = Vector3::zeros();
        let root = RootFrame::new(Vector3::zeros(), Vector3::x(), Vector3::y()).unwrap();
        let mut strand = Strand::new(model, root).unwrap();
        let params = SetModel::default();
        let mut set = SetState::new(&strand.model);
        let held = DVector::from_fn(16, |i, _| if i % 2 == 0 { 5.0 } else { 25.0 });
        set.update(&params, &mut strand.model, &strand.state.q, &[w0; 8])
            .unwrap();
        for n in 1..=1000 {
            strand.state.q = held.clone(); // held, e.g. wrapped on a roller
            strand.state.qdot.fill(0.0);
            let w = w0 * (1.0 - n as f64 / 1000.0);
            set.update(&params, &mut strand.model, &strand.state.q, &[w; 8])
                .unwrap();
        }
        for _ in 0..3000 {
            strand.step(1e-3, &[]).unwrap();
        }
        (strand.state.q.clone(), held)
    }

    #[test]
    fn a_shape_held_while_drying_is_kept_and_a_dry_one_springs_back() {
        // Released, the strand settles on its rest shape: h = 0.8 of the held curl if it dried while held
        // (tolerance 1e-3 of the held curvature: the settling), the straight shape if it was dry.
        let (q_wet, held) = hold_dry_release(1.0);
        let err = (&q_wet - &held * 0.8).norm() / held.norm();
        assert!(err < 1e-3, "wet-set strand: relative error {err}");
        let (q_dry, held) = hold_dry_release(0.0);
        let back = q_dry.norm() / held.norm();
        assert!(back < 1e-3, "dry-held strand kept {back} of the curl");
    }

    #[test]
    fn rewetting_forgets_the_set_and_bad_input_is_named() {
        let h = HairType::GA1;
        let mut model =
            StrandModel::new(ModelKind::Full, 0.05, 4, h.section().unwrap(), h.material().unwrap()).unwrap();
        let mut set = SetState::new(&model);
        let p = SetModel { hydrogen_share: 1.0 };
        let q = DVector::from_element(12, 10.0);
        set.update(&p, &mut model, &q, &[0.6; 4]).unwrap();
        set.update(&p, &mut model, &q, &[0.0; 4]).unwrap(); // dried while at q: set = q
        assert_eq!(model.rest_coordinates(), q);
        set.update(&p, &mut model, &DVector::zeros(12), &[0.5; 4]).unwrap(); // half wet: half forgotten
        assert!((model.rest_coordinates() - &q * 0.5).norm() < 1e-12);
        set.update(&p, &mut model, &DVector::zeros(12), &[1.0; 4]).unwrap(); // soaked: all forgotten
        assert_eq!(model.rest_coordinates(), DVector::zeros(12));
        let before = set.clone();
        let e = set.update(&p, &mut model, &q, &[0.5, 0.5, f64::NAN, 0.5]).unwrap_err();
        assert!(
            e.to_string().contains("wetness") && e.to_string().contains("segment 2"),
            "{e}"
        );
        assert!(set.update(&p, &mut model, &q, &[0.5; 3]).is_err());
        assert!(set
            .update(&SetModel { hydrogen_share: 1.5 }, &mut model, &q, &[0.5; 4])
            .unwrap_err()
            .to_string()
            .contains("hydrogen_share"));
        assert_eq!(set, before, "nothing changed on error");
    }
}
