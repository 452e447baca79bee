//! The local interaction's settings: the body the strands rest on, its friction, the hair volume's hold, the
//! contact between strands, the entanglement drag and the batching. The caller sets them; no step changes them.

use super::{Entanglement, HairContact};

/// Settings of a [`super::LocalInteraction`] (SI units). The defaults: no body, no hold, no hair-hair contact, no
/// entanglement, batched preparation.
#[derive(Debug, Clone)]
pub struct InteractionParams {
    /// Constraint model: prepare the steps of reduced strands four at a time ([`strand::StrandBatch`], SIMD lanes)
    /// instead of one by one. Same results to round-off; default true.
    pub use_batches: bool,
    /// Constraint model: the body the strands rest on (the head, neck and shoulders as metaballs, world
    /// frame) and its iso-surface threshold. Each strand's sampled points that are inside it, or within a
    /// hair's radius of its surface, get a contact pushing them out with Coulomb friction
    /// `body_friction` (the tool does not feel it). Default None (no body).
    pub body: Option<(lattice::metaball::MetaballSet, f64)>,
    /// Constraint model: Coulomb friction coefficient of the body contacts (dimensionless, >= 0): a strand
    /// lies on the scalp and on the hair beneath it, and without friction a strand resting on the curved
    /// head is free to slide round it. Default 0 (frictionless).
    pub body_friction: f64,
    /// The hold's displacement scale, m: the unsimulated neighbours pull a held strand back towards its place
    /// with a spring per unit length that carries the strand's own weight at this displacement,
    /// `k = lambda |g| / hold_distance` (N/m per m of strand, [`super::hold_rate`]), applied explicitly at
    /// [`super::HOLD_LOADS`] points per strand. Infinite: no hold. Default infinite.
    pub hold_distance: f64,
    /// The gravity |g| the hold's spring is scaled with, m/s^2; None: each strand model's own. A caller whose
    /// strands carry no weight of their own (the hair volume carries it, e.g. the live session's local strands,
    /// whose models have no gravity) gives the scene's. Default None.
    pub hold_gravity: Option<f64>,
    /// Constraint model: contact and friction between the simulated strands ([`HairContact`]). Default None
    /// (strands pass through each other).
    pub hair_contact: Option<HairContact>,
    /// Constraint model: the drag of the tool's capsules through the wisps they pass through, against the
    /// fibres they part ([`Entanglement`]; the wisp's radius is [`HairContact`]'s, the fibre's without hair
    /// contact). Default None (a tool touches a strand only at the fibre's radius).
    pub entanglement: Option<Entanglement>,
}

impl Default for InteractionParams {
    fn default() -> Self {
        Self { use_batches: true, body: None, body_friction: 0.0, hold_distance: f64::INFINITY, hold_gravity: None, hair_contact: None, entanglement: None }
    }
}
