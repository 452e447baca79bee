//! The lattice's step workspace, kept apart from its state ([`crate::lattice::LatticeState`]):
//! the cached factorisation of the implicit matrix (rebuilt when the step size or the model
//! changes) and the step's scratch buffers. Two workspaces are never compared: they hold no
//! physical state, only what makes the next step cheaper.

use crate::model::LatticeModel;
use crate::params::{BendingJacobian, FactorPrecision, FillOrdering, LatticeParams};
use crate::solver::{Factor, StepWork};

/// The workspace of a lattice's steps (see the module docs): give every step of one state the same
/// workspace, or a fresh one (`LatticeWorkspace::default()`: the first step factorises again).
#[derive(Debug, Clone, Default)]
pub struct LatticeWorkspace {
    pub(crate) cache: StepCache,
    pub(crate) work: StepWork,
}

impl LatticeWorkspace {
    /// Stored values of the cached Cholesky factor L (its fill), if factorised yet.
    pub fn factor_nonzeros(&self) -> Option<usize> {
        self.cache.factor_nonzeros()
    }

    /// Bytes of the cached Cholesky factor's values (4 or 8 per value, by
    /// [`LatticeParams::factor_precision`]), if factorised yet.
    pub fn factor_bytes(&self) -> Option<usize> {
        self.cache.factor_bytes()
    }
}

/// The factorisation kept between steps, rebuilt when the step size or the model changes.
#[derive(Default, Clone)]
pub(crate) struct StepCache {
    key: Option<(u64, u64)>,
    factor: Option<std::sync::Arc<Factor>>,
}

impl std::fmt::Debug for StepCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StepCache")
            .field("factorised", &self.factor.is_some())
            .finish()
    }
}

impl StepCache {
    /// Stored values of the cached Cholesky factor L (its fill), if factorised yet.
    pub(crate) fn factor_nonzeros(&self) -> Option<usize> {
        self.factor.as_ref().map(|f| f.factor_len())
    }

    /// Bytes of the cached Cholesky factor's values (4 or 8 per value, by
    /// [`LatticeParams::factor_precision`]), if factorised yet.
    pub(crate) fn factor_bytes(&self) -> Option<usize> {
        self.factor.as_ref().map(|f| f.factor_bytes())
    }

    pub(crate) fn factor(&mut self, model: &LatticeModel, dt: f64) -> std::sync::Arc<Factor> {
        let key = (dt.to_bits(), model.fingerprint());
        if self.key != Some(key) || self.factor.is_none() {
            self.factor = Some(std::sync::Arc::new(Factor::new(model, dt)));
            self.key = Some(key);
        }
        self.factor.clone().expect("just built")
    }
}

impl LatticeModel {
    /// A hash of everything the implicit matrix depends on (masses, attachment, stiffeners,
    /// parameters), to know when a cached factorisation is stale.
    pub(crate) fn fingerprint(&self) -> u64 {
        // a multiply-xor hash (FxHash's mixing step) in four independent lanes: this runs every
        // step over every stiffener, where SipHash took a noticeable part of the step
        let step = |h: u64, x: u64| (h.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
        let mut lanes = [1u64, 2, 3, 4];
        for (q, m) in self.masses.iter().chain(&self.attachment).enumerate() {
            lanes[q % 4] = step(lanes[q % 4], m.to_bits());
        }
        for s in &self.stiffeners {
            lanes[0] = step(lanes[0], s.i as u64);
            lanes[1] = step(lanes[1], s.j as u64);
            lanes[2] = step(lanes[2], s.stiffness.to_bits());
            lanes[3] = step(lanes[3], s.damping.to_bits());
        }
        let mut h = step(self.masses.len() as u64, self.stiffeners.len() as u64);
        h = step(h, p_bits(&self.params));
        for l in lanes {
            h = step(h, l);
        }
        let mut mix = |x: u64| h = step(h, x);
        let p = &self.params;
        for x in [p.attachment_stiffness, p.attachment_damping] {
            mix(x.to_bits());
        }
        mix(match p.fill_ordering {
            FillOrdering::Auto => 0,
            FillOrdering::Amd => 1,
            FillOrdering::NestedDissection => 2,
        });
        h
    }
}

/// The matrix-shaping enum parameters as bits for the fingerprint.
fn p_bits(p: &LatticeParams) -> u64 {
    let b = match p.bending_jacobian {
        BendingJacobian::Laplacian => 0,
        BendingJacobian::DiagonalBound => 1,
        BendingJacobian::PathBound => 2,
    };
    let f = match p.factor_precision {
        FactorPrecision::F64 => 0,
        FactorPrecision::F32 => 1,
    };
    b | (f << 4)
}

