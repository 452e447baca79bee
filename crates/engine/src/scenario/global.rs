//! Global-tool scenarios: scissors, dryer, sprayer on a generated hairstyle (docs/scenarios.md, "Global
//! tools").

use super::actions::Action;
use super::{default_dt, ScenarioError};
use hairstyle::cut::{cut_curves, cut_guide, polyline_length, Blade};
use hairstyle::{HairCurves, Hairstyle, HairstyleParams};
use lattice::cluster::{ClusterParams, ClusterSet, CutPiece};
use nalgebra::{Point3, Vector3};
use serde::Deserialize;
use strand::dynamics::PointForce;
use strand::kinematics::{frame_at, segment_frames};
use strand::styling::{SetModel, SetState};
use strand::{Strand, StrandError};
use tools::dryer::{Cone, HairDrag, HairDryer};
use tools::wetness::{WetnessField, WetnessModel};

/// A global-tool scenario file (TOML): a generated hairstyle on the built-in head, and timed actions of the
/// scissors, the hair dryer and the water sprayer. Told apart from a comb scenario by its `[[action]]` tables.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlobalScenario {
    /// Name (default: the file's stem).
    pub name: Option<String>,
    /// Guide strand time step, s (default 0.001).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Simulated time, s (default: the last action's end + 1 s).
    pub duration: Option<f64>,
    /// Period of the wetness, styling, material and falling-cluster updates, s (default 0.01, the global rate).
    #[serde(default = "default_global_dt")]
    pub global_dt: f64,
    /// Wetness of the whole hairstyle at the start, in [0, 1] (default 0).
    #[serde(default)]
    pub wetness: f64,
    /// Height of the floor the cut hair lands on, m, head frame (default -0.6).
    #[serde(default = "default_floor")]
    pub floor: f64,
    /// Hydrogen-bond share of the wet set, in [0, 1] (default 0.8; see docs/wetness.md).
    #[serde(default = "default_share")]
    pub hydrogen_share: f64,
    /// The hairstyle.
    #[serde(default)]
    pub hairstyle: HairstyleSpec,
    /// Timed actions.
    #[serde(rename = "action", default)]
    pub actions: Vec<Action>,
}

fn default_global_dt() -> f64 {
    0.01
}
fn default_floor() -> f64 {
    -0.6
}
fn default_share() -> f64 {
    0.8
}

/// The generated hairstyle of a global scenario (see `hairstyle::HairstyleParams`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HairstyleSpec {
    /// Hair type preset (default "caucasian").
    pub hair_type: String,
    /// Strand length, m (default 0.2).
    pub length: f64,
    /// Curliness in [0, 1] (default 0).
    pub curliness: f64,
    /// Guide strands (simulated Super-Helices) (default 48).
    pub guides: usize,
    /// Segments per guide (default 8).
    pub segments: usize,
    /// Render strands (default 2000).
    pub render_strands: usize,
    /// Vertices per render strand (default 16).
    pub render_vertices: usize,
    /// Random seed (default 1).
    pub seed: u64,
}

impl Default for HairstyleSpec {
    fn default() -> Self {
        Self {
            hair_type: "caucasian".into(),
            length: 0.2,
            curliness: 0.0,
            guides: 48,
            segments: 8,
            render_strands: 2000,
            render_vertices: 16,
            seed: 1,
        }
    }
}

/// One row of a global scenario's trace (every `global_dt`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalRow {
    /// Time, s.
    pub t: f64,
    /// Mean, minimum and maximum wetness over all guide segments.
    pub wetness: [f64; 3],
    /// Guide strands whose segments are in a dryer's or sprayer's cone this step.
    pub in_cone: usize,
    /// Total blowing force on the guides, N.
    pub blow_force: f64,
    /// Kinetic energy of the falling cut hair, J.
    pub cluster_energy: f64,
    /// Mean tip height of the guides, m.
    pub mean_tip_z: f64,
}

/// What a global scenario did.
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalSummary {
    /// Guide strands and render strands.
    pub guides: usize,
    /// Render strands.
    pub render_strands: usize,
    /// Guide steps run.
    pub steps: usize,
    /// Mean wetness at the start and at the end, and the end's minimum and maximum.
    pub wetness_before: f64,
    /// Mean wetness at the end.
    pub wetness_after: f64,
    /// Minimum and maximum wetness at the end.
    pub wetness_range_after: [f64; 2],
    /// Change of the rest coordinates of the guides that were not cut, from wet setting, rad/m (root mean square
    /// over their coordinates).
    pub rest_change: f64,
    /// Guides cut and render strands cut.
    pub guides_cut: usize,
    /// Render strands cut.
    pub render_cut: usize,
    /// Dry hair mass of the render strands, kg: just before the first cut (the render strands follow the guides
    /// until then, which changes their lengths slightly), or at the start if nothing is cut.
    pub render_mass_before: f64,
    /// Dry mass of what stays on the head, kg.
    pub render_mass_on_head: f64,
    /// Dry mass of the pieces cut off, kg.
    pub render_mass_cut: f64,
    /// Mean render strand length before and after, m.
    pub render_length_before: f64,
    /// Mean render strand length after, m.
    pub render_length_after: f64,
    /// Mean guide length before and after, m.
    pub guide_length_before: f64,
    /// Mean guide length after, m.
    pub guide_length_after: f64,
    /// Dry guide mass before, kg.
    pub guide_mass_before: f64,
    /// Dry guide mass on the head plus the guide pieces after, kg.
    pub guide_mass_after: f64,
    /// Falling clusters made and their kinetic energy at the end, J.
    pub clusters: usize,
    /// Kinetic energy of the clusters at the end, J.
    pub cluster_energy: f64,
    /// Largest metaball field value over the fallen pieces' points at the end (threshold 0.25: inside above).
    pub pieces_max_field: f64,
    /// Steps in which a guide's velocities were scaled down by the safety net.
    pub clamped_steps: u64,
    /// Drying pass on the lattice (only with dryer actions; 0 otherwise): largest distance between a node of
    /// a lattice blown by the dryers (`HairDryer::hair_force`, 4 cm lattice, `LatticeModel::step_with_forces`
    /// every `global_dt`, body collisions) and the same node of a twin lattice stepped alongside without the
    /// dryers, over the run, m: the dryers' effect alone.
    pub lattice_max_displacement: f64,
    /// The same distance at the end, m.
    pub lattice_end_displacement: f64,
    /// Largest total dryer force on the lattice at one time, N.
    pub lattice_peak_force: f64,
}

/// Everything a global scenario produces (the server writes it to files).
#[derive(Debug, Clone)]
pub struct GlobalOutput {
    /// Trace rows, every `global_dt`.
    pub rows: Vec<GlobalRow>,
    /// Summary.
    pub summary: GlobalSummary,
    /// The final hairstyle (render strands, m).
    pub hairstyle: HairCurves,
    /// The cut pieces where they came to rest (m).
    pub pieces: HairCurves,
}

fn global_err(what: &str, e: impl std::fmt::Display) -> ScenarioError {
    ScenarioError::Invalid(format!("{what}: {e}"))
}

/// Segment centres of a strand, m.
fn segment_centres(s: &Strand) -> Vec<Vector3<f64>> {
    let frames = segment_frames(&s.model, &s.state);
    let l = s.model.segment_length();
    (0..s.model.segments)
        .map(|k| frame_at(&s.model, &s.state.q, &frames, (k as f64 + 0.5) * l).position)
        .collect()
}

impl GlobalScenario {
    /// Checks the values, naming the first bad key.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let bad = |m: String| Err(ScenarioError::Invalid(m));
        if !(self.dt.is_finite() && self.dt > 0.0 && self.dt <= 0.01) {
            return bad(format!("dt must be in (0, 0.01] s, got {}", self.dt));
        }
        if !(self.global_dt.is_finite() && self.global_dt >= self.dt && self.global_dt <= 0.1) {
            return bad(format!("global_dt must be in [dt, 0.1] s, got {}", self.global_dt));
        }
        if !(self.wetness.is_finite() && (0.0..=1.0).contains(&self.wetness)) {
            return bad(format!("wetness must be in [0, 1], got {}", self.wetness));
        }
        if !(self.hydrogen_share.is_finite() && (0.0..=1.0).contains(&self.hydrogen_share)) {
            return bad(format!("hydrogen_share must be in [0, 1], got {}", self.hydrogen_share));
        }
        if !self.floor.is_finite() {
            return bad("floor must be finite".into());
        }
        if let Some(d) = self.duration {
            if !(d.is_finite() && d > 0.0 && d < 3600.0) {
                return bad(format!("duration must be in (0, 3600) s, got {d}"));
            }
        }
        for (i, a) in self.actions.iter().enumerate() {
            match a {
                Action::Cut(c) => {
                    if !(c.t.is_finite() && c.t >= 0.0) {
                        return bad(format!("action {i} (cut): t must be >= 0 s, got {}", c.t));
                    }
                    Blade {
                        point: c.point,
                        normal: c.normal,
                        radius: c.radius,
                    }
                    .validate()
                    .map_err(|e| global_err(&format!("action {i} (cut)"), e))?;
                }
                Action::Dry(c) => {
                    c.validate("dry", i)?;
                    c.dryer(c.start)
                        .validate()
                        .map_err(|e| global_err(&format!("action {i} (dry)"), e))?;
                }
                Action::Spray(c) => {
                    c.validate("spray", i)?;
                    c.sprayer(c.start)
                        .validate()
                        .map_err(|e| global_err(&format!("action {i} (spray)"), e))?;
                }
            }
        }
        Ok(())
    }

    /// Simulated time: `duration`, or the last action's end + 1 s.
    pub fn total_time(&self) -> f64 {
        self.duration.unwrap_or_else(|| {
            self.actions
                .iter()
                .map(|a| match a {
                    Action::Cut(c) => c.t,
                    Action::Dry(c) | Action::Spray(c) => c.start + c.duration,
                })
                .fold(0.0, f64::max)
                + 1.0
        })
    }

    /// The hairstyle parameters of `[hairstyle]`.
    pub fn hairstyle_params(&self) -> HairstyleParams {
        let h = &self.hairstyle;
        HairstyleParams {
            hair_type: h.hair_type.clone(),
            length: h.length,
            curliness: h.curliness,
            guide_count: h.guides,
            guide_segments: h.segments,
            render_count: h.render_strands,
            render_vertices: h.render_vertices,
            seed: h.seed,
            ..HairstyleParams::default()
        }
    }

    /// Runs the scenario. Deterministic.
    ///
    /// Every `dt` the guide strands (Super-Helices) are stepped under gravity with the active dryers' blowing
    /// forces at their segment centres. Every `global_dt`: dryers and sprayers change the wetness of every
    /// guide segment; each guide's material follows its mean wetness (`WetnessModel`); its rest shape follows
    /// the wet-set law (`strand::styling`); cut clusters fall. A cut shortens guides and render strands at
    /// once and turns the render pieces into falling clusters. Render strands follow the guides (the
    /// hairstyle's binding) until the first cut; after it they keep their cut shapes.
    pub fn run(&self) -> Result<GlobalOutput, ScenarioError> {
        self.validate()?;
        let params = self.hairstyle_params();
        let style = Hairstyle::generate(&params).map_err(|e| global_err("hairstyle", e))?;
        let hair = params.hair().map_err(|e| global_err("hairstyle", e))?;
        let inv = |e: StrandError| global_err("guides", e);
        let mut guides: Vec<Strand> = style
            .guides
            .iter()
            .map(|g| {
                let mut s = Strand::new(g.model.clone(), g.state.root.clone())?;
                s.state = g.state.clone();
                Ok(s)
            })
            .collect::<Result<_, StrandError>>()
            .map_err(inv)?;
        let dry_material = hair.material().map_err(inv)?;
        let area = hair.section().map_err(inv)?.area();
        let dry_friction = hair.friction_coefficient();
        let wet_model = WetnessModel::default();
        let set_model = SetModel {
            hydrogen_share: self.hydrogen_share,
        };
        let segs: Vec<usize> = guides.iter().map(|g| g.model.segments).collect();
        let mut wet = WetnessField::uniform(&segs, self.wetness).map_err(|e| global_err("wetness", e))?;
        let mut sets: Vec<SetState> = guides.iter().map(|g| SetState::new(&g.model)).collect();
        let rest0: Vec<DVectorF> = guides.iter().map(|g| g.model.rest_coordinates()).collect();
        let apply_wetness = |g: &mut Strand, set: &mut SetState, w: &[f64]| -> Result<(), ScenarioError> {
            let mean = w.iter().sum::<f64>() / w.len() as f64;
            g.model.material = wet_model
                .wet(&dry_material, dry_friction, area, mean)
                .map_err(|e| global_err("wetness", e))?
                .material();
            set.update(&set_model, &mut g.model, &g.state.q, w)
                .map_err(|e| global_err("wet set", e))
        };
        for (i, g) in guides.iter_mut().enumerate() {
            apply_wetness(g, &mut sets[i], &wet.values[i])?;
        }
        let wetness_before = wet.mean();
        let lambda = dry_material.density * area;
        let mut curves = style.to_curves();
        let render_len = |c: &HairCurves| -> Vec<f64> {
            c.strands
                .iter()
                .map(|s| polyline_length(&s.iter().map(|p| p.map(f64::from)).collect::<Vec<_>>()))
                .collect()
        };
        let mut len0 = render_len(&curves);
        let mut render_mass_before = lambda * len0.iter().sum::<f64>();
        let guide_mass_before: f64 = guides.iter().map(|g| lambda * g.model.length).sum(); // dry mass
        let guide_length_before = guides.iter().map(|g| g.model.length).sum::<f64>() / guides.len().max(1) as f64;
        let cluster_params = ClusterParams {
            floor: self.floor,
            ..ClusterParams::default()
        };
        let body = &style.head.body;
        let mut clusters: Vec<ClusterSet> = vec![];
        let (mut guides_cut, mut render_cut, mut render_mass_cut, mut guide_piece_mass, mut was_cut) =
            (0, 0, 0.0, 0.0, false);
        let mut cuts_done = vec![false; self.actions.len()];
        let mut guide_was_cut = vec![false; guides.len()];
        let total = self.total_time();
        let steps = (total / self.dt).round() as usize;
        let every = ((self.global_dt / self.dt).round() as usize).max(1);
        let mut rows = vec![];
        let mut forces: Vec<PointForce> = vec![];
        // Drying pass on the lattice: the dryers' drag on the hair each node carries (head still: head frame =
        // world), against a twin lattice without the dryers (settled 1 s under gravity first, both).
        let still = nalgebra::Isometry3::identity();
        let mut dry_lattice = None;
        if self.actions.iter().any(|a| matches!(a, Action::Dry(_))) {
            let carry = lattice::lattice::CarryParams { cell: 0.04, ..Default::default() };
            let hl = style
                .lattice(&carry, lattice::lattice::LatticeParams::default())
                .map_err(|e| global_err("lattice", e))?;
            let mut ls = hl.model.rest_state(&still);
            for _ in 0..((1.0 / self.global_dt).round() as usize).max(1) {
                hl.model.step(&mut ls, self.global_dt, &still, Some(body));
            }
            let lengths: Vec<f64> = hl
                .model
                .masses
                .iter()
                .map(|m| (m - carry.empty_node_mass).max(0.0) / (dry_material.density * area))
                .collect();
            dry_lattice = Some((hl, ls.clone(), ls, lengths, carry.cell * carry.cell));
        }
        let drag = HairDrag { hair_diameter: 2.0 * (area / std::f64::consts::PI).sqrt(), ..HairDrag::default() };
        let (mut lattice_max, mut lattice_peak_force) = (0.0f64, 0.0f64);
        let mut node_forces: Vec<Vector3<f64>> = vec![];
        for n in 1..=steps {
            let t = n as f64 * self.dt;
            // Cuts due by now.
            for (i, a) in self.actions.iter().enumerate() {
                let Action::Cut(c) = a else { continue };
                if cuts_done[i] || c.t > t {
                    continue;
                }
                cuts_done[i] = true;
                if !was_cut {
                    // The render strands follow the guides until the first cut: "before" is just before it.
                    follow_guides(&style, &guides, &mut curves)?;
                    len0 = render_len(&curves);
                    render_mass_before = lambda * len0.iter().sum::<f64>();
                }
                was_cut = true;
                let blade = Blade {
                    point: c.point,
                    normal: c.normal,
                    radius: c.radius,
                };
                for (gi, g) in guides.iter_mut().enumerate() {
                    if let Some((m, s, piece)) =
                        cut_guide(&g.model, &g.state, &blade, 4, gi).map_err(|e| global_err("cut", e))?
                    {
                        let l_old = g.model.segment_length();
                        let kept_len = m.length;
                        let n_new = m.segments;
                        let old = |k: usize| {
                            (((k as f64 + 0.5) * kept_len / n_new as f64 / l_old) as usize).min(g.model.segments - 1)
                        };
                        let w_new: Vec<f64> = (0..n_new).map(|k| wet.values[gi][old(k)]).collect();
                        guide_piece_mass += lambda * piece.mass / piece.linear_density; // dry mass
                        let integrator = g.integrator;
                        let clamped = g.clamped_steps;
                        *g = Strand::new(m, s.root.clone()).map_err(inv)?;
                        g.state = s;
                        g.integrator = integrator;
                        g.clamped_steps = clamped;
                        sets[gi] = SetState::new(&g.model);
                        sets[gi].wetness = w_new.clone();
                        wet.values[gi] = w_new;
                        guides_cut += 1;
                        guide_was_cut[gi] = true;
                    }
                }
                let pieces = cut_curves(&mut curves, lambda, &blade).map_err(|e| global_err("cut", e))?;
                render_cut += pieces.len();
                render_mass_cut += pieces.iter().map(|p| p.mass).sum::<f64>();
                let cp: Vec<CutPiece> = pieces
                    .iter()
                    .map(|p| CutPiece {
                        points: p.points.iter().map(|x| Point3::from(*x)).collect(),
                        mass: p.mass,
                    })
                    .collect();
                if !cp.is_empty() {
                    clusters.push(ClusterSet::new(&cp, &cluster_params).map_err(|e| global_err("clusters", e))?);
                }
            }
            // Guide step with the dryers' blowing forces.
            let dryers: Vec<HairDryer> = self
                .actions
                .iter()
                .filter_map(|a| {
                    if let Action::Dry(c) = a {
                        c.active(t).then(|| c.dryer(t))
                    } else {
                        None
                    }
                })
                .collect();
            let mut blow = 0.0;
            for g in guides.iter_mut() {
                forces.clear();
                if !dryers.is_empty() {
                    let l = g.model.segment_length();
                    for (k, x) in segment_centres(g).iter().enumerate() {
                        let f: Vector3<f64> = dryers.iter().map(|d| d.force(x, g.model.air_drag * l)).sum();
                        if f != Vector3::zeros() {
                            blow += f.norm();
                            forces.push(PointForce::new((k as f64 + 0.5) * l, f));
                        }
                    }
                }
                g.step(self.dt, &forces)
                    .map_err(|e| ScenarioError::Simulation { time: t, source: e })?;
            }
            if n % every == 0 || n == steps {
                let h = every as f64 * self.dt;
                let centres: Vec<Vec<Vector3<f64>>> = guides.iter().map(segment_centres).collect();
                let mut in_cone = vec![false; guides.len()];
                for a in &self.actions {
                    match a {
                        Action::Dry(c) if c.active(t) => {
                            let d = c.dryer(t);
                            d.dry(&mut wet, &centres, h).map_err(|e| global_err("dryer", e))?;
                            mark(&mut in_cone, &centres, &d.cone);
                        }
                        Action::Spray(c) if c.active(t) => {
                            let s = c.sprayer(t);
                            s.spray(&mut wet, &centres, h).map_err(|e| global_err("sprayer", e))?;
                            mark(&mut in_cone, &centres, &s.cone);
                        }
                        _ => {}
                    }
                }
                for (i, g) in guides.iter_mut().enumerate() {
                    apply_wetness(g, &mut sets[i], &wet.values[i])?;
                }
                for c in clusters.iter_mut() {
                    c.step(&cluster_params, body, h)
                        .map_err(|e| global_err("clusters", e))?;
                }
                if let Some((hl, ls, twin, lengths, face)) = dry_lattice.as_mut() {
                    node_forces.clear();
                    node_forces.resize(hl.model.node_count(), Vector3::zeros());
                    for a in &self.actions {
                        if let Action::Dry(c) = a {
                            if c.active(t) {
                                let d = c.dryer(t);
                                for (i, f) in node_forces.iter_mut().enumerate() {
                                    *f += d
                                        .hair_force(&ls.positions[i].coords, lengths[i], *face, &drag)
                                        .map_err(|e| global_err("dryer", e))?;
                                }
                            }
                        }
                    }
                    lattice_peak_force = lattice_peak_force.max(node_forces.iter().sum::<Vector3<f64>>().norm());
                    hl.model
                        .step_with_forces(ls, h, &still, Some(body), &node_forces)
                        .map_err(|e| global_err("lattice", e))?;
                    hl.model.step(twin, h, &still, Some(body));
                    let disp =
                        ls.positions.iter().zip(twin.positions.iter()).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
                    lattice_max = lattice_max.max(disp);
                }
                let (lo, hi) = wet
                    .values
                    .iter()
                    .flatten()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &w| (a.min(w), b.max(w)));
                let tips: f64 = guides
                    .iter()
                    .map(|g| strand::statics::tip(&g.model, &g.state, &g.state.q).z)
                    .sum::<f64>()
                    / guides.len().max(1) as f64;
                rows.push(GlobalRow {
                    t,
                    wetness: [wet.mean(), lo, hi],
                    in_cone: in_cone.iter().filter(|&&b| b).count(),
                    blow_force: blow,
                    cluster_energy: clusters.iter().map(|c| c.kinetic_energy()).sum::<f64>() + 0.0,
                    mean_tip_z: tips,
                });
            }
        }
        if !was_cut {
            follow_guides(&style, &guides, &mut curves)?;
        }
        let len1 = render_len(&curves);
        let mut piece_curves = vec![];
        let mut max_field: f64 = 0.0;
        for c in &clusters {
            for p in c.piece_points(&cluster_params, body) {
                max_field = p.iter().map(|x| body.field(x)).fold(max_field, f64::max);
                piece_curves.push(p.iter().map(|x| [x.x as f32, x.y as f32, x.z as f32]).collect());
            }
        }
        let coords = guides
            .iter()
            .zip(&rest0)
            .zip(&guide_was_cut)
            .filter(|(_, &c)| !c)
            .map(|((g, r0), _)| {
                let r = g.model.rest_coordinates();
                ((r - r0).norm_squared(), r0.len())
            });
        let (sq, cnt) = coords.fold((0.0, 0usize), |(a, b), (s, n)| (a + s, b + n));
        let (lo, hi) = wet
            .values
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &w| (a.min(w), b.max(w)));
        let summary = GlobalSummary {
            guides: guides.len(),
            render_strands: curves.strands.len(),
            steps,
            wetness_before,
            wetness_after: wet.mean(),
            wetness_range_after: [lo, hi],
            rest_change: if cnt > 0 { (sq / cnt as f64).sqrt() } else { 0.0 },
            guides_cut,
            render_cut,
            render_mass_before,
            render_mass_on_head: lambda * len1.iter().sum::<f64>(),
            render_mass_cut,
            render_length_before: len0.iter().sum::<f64>() / len0.len().max(1) as f64,
            render_length_after: len1.iter().sum::<f64>() / len1.len().max(1) as f64,
            guide_length_before,
            guide_length_after: guides.iter().map(|g| g.model.length).sum::<f64>() / guides.len().max(1) as f64,
            guide_mass_before,
            guide_mass_after: guides.iter().map(|g| lambda * g.model.length).sum::<f64>() + guide_piece_mass,
            clusters: clusters.iter().map(|c| c.clusters.len()).sum(),
            cluster_energy: clusters.iter().map(|c| c.kinetic_energy()).sum::<f64>() + 0.0,
            pieces_max_field: max_field,
            clamped_steps: guides.iter().map(|g| g.clamped_steps).sum(),
            lattice_max_displacement: lattice_max,
            lattice_end_displacement: dry_lattice
                .as_ref()
                .map(|(_, ls, twin, _, _)| {
                    ls.positions.iter().zip(twin.positions.iter()).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max)
                })
                .unwrap_or(0.0),
            lattice_peak_force,
        };
        Ok(GlobalOutput {
            rows,
            summary,
            hairstyle: curves,
            pieces: HairCurves::from_strands(piece_curves),
        })
    }
}

type DVectorF = nalgebra::DVector<f64>;

/// Marks the strands with a segment centre inside `cone`.
fn mark(in_cone: &mut [bool], centres: &[Vec<Vector3<f64>>], cone: &Cone) {
    for (m, xs) in in_cone.iter_mut().zip(centres) {
        *m |= xs.iter().any(|x| cone.weight(x).0 > 0.0);
    }
}

/// Moves the render strands with the guides (the hairstyle's binding).
fn follow_guides(style: &Hairstyle, guides: &[Strand], curves: &mut HairCurves) -> Result<(), ScenarioError> {
    let samples: Vec<Vec<Point3<f64>>> = guides
        .iter()
        .map(|g| hairstyle::generate::sample_strand(&g.model, &g.state, style.render.guide_samples))
        .collect();
    let mut out = vec![];
    style
        .render
        .follow(&samples, &mut out)
        .map_err(|e| global_err("render strands", e))?;
    let v = style.render.vertices_per_strand;
    *curves = HairCurves::from_strands(out.chunks(v).map(|s| s.to_vec()).collect());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GLOBAL: &str = r#"
        duration = 0.4
        [hairstyle]
        guides = 12
        segments = 6
        render_strands = 200
        render_vertices = 8
        [[action]]
        kind = "spray"
        start = 0.0
        duration = 0.2
        rate = 5.0
        path = [ { t = 0.0, apex = [0.0, -0.35, 0.0], axis = [0.0, 1.0, 0.0] } ]
        [[action]]
        kind = "dry"
        start = 0.2
        duration = 0.1
        rate = 5.0
        range = 0.5
        path = [ { t = 0.0, apex = [0.0, -0.3, 0.0], axis = [0.0, 1.0, 0.0] } ]
        [[action]]
        kind = "cut"
        t = 0.3
        point = [0.0, -0.05, -0.08]
        normal = [0.0, 0.0, 1.0]
        radius = 0.25
    "#;

    #[test]
    fn a_global_scenario_wets_dries_cuts_and_conserves_mass() {
        let s: GlobalScenario = toml::from_str(GLOBAL).unwrap();
        let a = s.run().unwrap();
        let b = s.run().unwrap();
        assert_eq!(a.rows, b.rows, "deterministic");
        assert_eq!(a.summary, b.summary);
        let m = &a.summary;
        // Mean wetness over the guide segments: up while spraying (to 0.2 s), down while drying (to 0.3 s, just
        // before the cut, which removes dry tips and so changes what the mean is taken over).
        let at = |t: f64| a.rows.iter().find(|r| (r.t - t).abs() < 1e-9).unwrap().wetness[0];
        assert!(at(0.1) > at(0.05) && at(0.2) > at(0.1), "sprayed");
        assert!(at(0.29) < 0.98 * at(0.2), "dried from {} to {}", at(0.2), at(0.29));
        assert!(m.guides_cut > 0 && m.render_cut > 0);
        assert!(((m.guide_mass_after - m.guide_mass_before) / m.guide_mass_before).abs() < 1e-12);
        // Render strands on the head are measured in f32 (their cut vertex is rounded): 1e-6.
        let after = m.render_mass_on_head + m.render_mass_cut;
        assert!(((after - m.render_mass_before) / m.render_mass_before).abs() < 1e-6);
        assert!(m.render_length_after < m.render_length_before && m.guide_length_after < m.guide_length_before);
        assert_eq!(a.pieces.strands.len(), m.render_cut);
    }

    #[test]
    fn bad_global_values_are_named() {
        let mut s: GlobalScenario = toml::from_str(GLOBAL).unwrap();
        s.wetness = f64::NAN;
        assert!(s.validate().unwrap_err().to_string().contains("wetness"));
        let s: GlobalScenario = toml::from_str(&GLOBAL.replace("radius = 0.25", "radius = -1.0")).unwrap();
        assert!(s.validate().unwrap_err().to_string().contains("action 2 (cut)"));
        assert!(toml::from_str::<GlobalScenario>(&GLOBAL.replace("kind = \"cut\"", "kind = \"comb\"")).is_err());
    }

}
