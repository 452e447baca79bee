//! Four reduced strands stepped at once, lane-parallel (SIMD, `f64x4`).
//!
//! [`StrandBatch`] performs exactly the linearly implicit Euler step of [`Strand::step`] for up to
//! [`LANES`] reduced strands with the same number of segments and Gauss points: the same root-to-tip sweep
//! (closed-form helix, velocity-product terms, gravity, air drag, rotary inertia, point forces), the same
//! tip-to-root force sweep, elastic and damping forces, and the same O(N) articulated-body solve of
//! `(M (1 + h c) + (h tau + h^2) K + h^2 K_g) dqdot = h F - h^2 (K + K_g) qdot` (`K_g` the geometric stiffness
//! of the constraint loads the strand carries, `Dynamics::geometric_stiffness`). Each lane holds one strand's numbers; the lanes
//! never mix, so the strands may differ in length, section, material, rest shape, environment, root motion
//! and point forces. The results equal the scalar step's to round-off (the sine and cosine of the SIMD
//! library differ from the C library's in the last bits).
//!
//! The step is split as in the scalar constraint solver: [`StrandBatch::prepare`] evaluates the dynamics and
//! the unconstrained velocities of every lane and leaves each strand with a prepared step (its
//! `dynamics.frames` and `dynamics.points` sample the current centreline, as after [`Strand::prepare_step`]);
//! [`Strand::finish_step`] then commits it. A strand that turns out to need constraints gets the lane's solver
//! workspace with [`StrandBatch::hand_over`], so that `finish_step` with constraints runs without a second
//! evaluation. [`StrandBatch::step`] is prepare and commit in one.
//!
//! Speed needs 256-bit registers: build with AVX2 (the workspace's `.cargo/config.toml` sets
//! `target-cpu=x86-64-v3`); with SSE2 only, each `f64x4` operation is two 128-bit ones.

use crate::constraint::ConstraintOptions;
use crate::dynamics::{point_kinematics, wrench, PointForce};
use crate::error::{Result, StrandError};
use crate::integrator::{geometric_stiffness_kept, Integrator, Strand};
use crate::kinematics::{locate, Frame, Twists};
use crate::model::ModelKind;
use nalgebra::{DVector, Matrix3, Vector3};
use wide::{CmpGt, CmpLt};

mod lanes;

use lanes::*;

/// Strands per batch (SIMD lanes).
pub const LANES: usize = 4;

/// Per-segment workspace (every field one value per lane).
#[derive(Debug, Clone, Copy)]
struct Segment {
    /// Coordinates (twist, bend) and their rates.
    q: [L; 2],
    qdot: [L; 2],
    rest: [L; 2],
    /// Motion subspace: the two twists `(omega; v)` about the root position.
    motion: [L6; 2],
    q_own: [L; 2],
    f_own: [L6; 2],
    /// Own mass block `(00, 01, 11)`.
    m_own: [L; 3],
    wrench: L6,
    /// Rigid inertia: mass, first moment, rotational inertia about the origin (symmetric, see [`sym`]).
    mass: L,
    first: V3,
    inertia: L6,
    /// Generalized forces, then the right-hand side, then the velocity change.
    force: [L; 2],
    b: [L; 2],
    /// Articulated solve: `U` (two columns), `D^-1` `(00, 01, 11)`, `c`.
    u: [L6; 2],
    dinv: [L; 3],
    c: [L; 2],
}

impl Segment {
    fn zero() -> Self {
        let z = sp(0.0);
        Self {
            q: [z; 2],
            qdot: [z; 2],
            rest: [z; 2],
            motion: [[z; 6]; 2],
            q_own: [z; 2],
            f_own: [[z; 6]; 2],
            m_own: [z; 3],
            wrench: [z; 6],
            mass: z,
            first: V3::zero(),
            inertia: [z; 6],
            force: [z; 2],
            b: [z; 2],
            u: [[z; 6]; 2],
            dinv: [z; 3],
            c: [z; 2],
        }
    }
}

/// Workspace that steps up to [`LANES`] reduced strands of `segments` segments at once (see the module
/// documentation). Allocate once, reuse every step.
#[derive(Debug, Clone)]
pub struct StrandBatch {
    segments: usize,
    quadrature_points: usize,
    segs: Vec<Segment>,
    frames: Vec<(M3, V3)>,
    points: Vec<V3>,
    /// Each segment's geometric stiffness of its two coordinates (zero in lanes without constraint loads).
    geometric: Vec<[L; 2]>,
    /// Lanes filled by the last prepare.
    lanes: usize,
}

/// Why a set of strands cannot share a batch, or None.
fn batch_mismatch(segments: usize, quadrature_points: usize, strand: &Strand) -> Option<String> {
    if strand.model.kind != ModelKind::Reduced {
        return Some("only reduced strands can be batched".into());
    }
    if strand.integrator != Integrator::LinearlyImplicitEuler {
        return Some("batched strands use the linearly implicit Euler integrator".into());
    }
    if strand.model.segments != segments || strand.dynamics.quadrature_nodes().len() != quadrature_points {
        return Some(format!(
            "the batch is for {segments} segments and {quadrature_points} Gauss points, the strand has {} and {}",
            strand.model.segments,
            strand.dynamics.quadrature_nodes().len()
        ));
    }
    None
}

impl StrandBatch {
    /// A workspace for reduced strands of `segments` segments and `quadrature_points` Gauss points per segment
    /// (the model's `quadrature_points`).
    pub fn new(segments: usize, quadrature_points: usize) -> Self {
        let n = segments.max(1);
        Self {
            segments,
            quadrature_points,
            segs: vec![Segment::zero(); n],
            frames: Vec::with_capacity(n + 1),
            points: Vec::with_capacity(n * quadrature_points),
            geometric: vec![[sp(0.0); 2]; n],
            lanes: 0,
        }
    }

    /// A workspace sized for `strand` (its segments and Gauss points).
    pub fn for_strand(strand: &Strand) -> Self {
        Self::new(strand.model.segments, strand.dynamics.quadrature_nodes().len())
    }

    /// Whether `strand` can be a lane of this batch: reduced model, linearly implicit Euler, the batch's
    /// segments and Gauss points.
    pub fn accepts(&self, strand: &Strand) -> bool {
        batch_mismatch(self.segments, self.quadrature_points, strand).is_none()
    }

    /// One linearly implicit Euler step of `h` seconds (s) for every strand, each with its own point forces
    /// (`external[j]` for strand `j`; an empty slice of slices for none). Equal to [`Strand::step`] on each.
    /// A strand whose step fails keeps its state; the others step; the first error is returned.
    pub fn step(&mut self, h: f64, strands: &mut [&mut Strand], external: &[&[PointForce]]) -> Result<()> {
        let mut first = self.prepare(h, strands, external).err();
        for s in strands.iter_mut() {
            if s.has_prepared_step() {
                if let Err(e) = s.finish_step(&[], &ConstraintOptions::default()) {
                    first.get_or_insert(e);
                }
            }
        }
        first.map_or(Ok(()), Err)
    }

    /// First half of the step for every strand (as [`Strand::prepare_step`] on each): evaluates the dynamics
    /// at the current states and solves the unconstrained velocities. Afterwards each strand has a prepared step
    /// ([`Strand::has_prepared_step`]) and its `dynamics` holds the frames, Gauss points, generalized forces and
    /// energies of the current state; complete it with [`Strand::finish_step`] (with constraints only after
    /// [`StrandBatch::hand_over`]). Errors: more than [`LANES`] or no strands, a strand the batch does not
    /// accept, bad time step or point forces (then nothing is prepared); a lane whose step matrix is not
    /// positive definite is left unprepared and its error returned, the other lanes are prepared.
    pub fn prepare(&mut self, h: f64, strands: &mut [&mut Strand], external: &[&[PointForce]]) -> Result<()> {
        let lanes = strands.len();
        if lanes == 0 || lanes > LANES {
            return Err(StrandError::InvalidParameter { field: "batch", reason: format!("needs 1 to {LANES} strands, got {lanes}") });
        }
        if !(external.is_empty() || external.len() == lanes) {
            return Err(StrandError::InvalidParameter { field: "point force", reason: format!("one list per strand ({lanes}) or none, got {}", external.len()) });
        }
        for (j, s) in strands.iter_mut().enumerate() {
            s.prepared = None;
            if let Some(reason) = batch_mismatch(self.segments, self.quadrature_points, s) {
                return Err(StrandError::InvalidParameter { field: "batch", reason: format!("strand {j}: {reason}") });
            }
            s.check_step_input(h, external.get(j).copied().unwrap_or(&[]))?;
        }
        self.lanes = lanes;
        let n = self.segments;
        let nq = self.quadrature_points;
        // Unused lanes repeat the first strand (their results are dropped).
        let pick = |j: usize| if j < lanes { j } else { 0 };
        let per_lane = |f: &dyn Fn(&Strand) -> f64| L::from(std::array::from_fn::<f64, LANES, _>(|j| f(&*strands[pick(j)])));
        let per_lane3 = |f: &dyn Fn(&Strand) -> Vector3<f64>| V3::gather(std::array::from_fn(|j| f(&*strands[pick(j)])));
        let l = per_lane(&|s| s.model.segment_length());
        let rho_a = per_lane(&|s| s.model.linear_density());
        let rot_inertia = per_lane3(&|s| s.model.rotary_inertia());
        let drag_rate = per_lane(&|s| s.model.air_drag / s.model.linear_density());
        let gravity = per_lane3(&|s| s.model.gravity);
        let origin = per_lane3(&|s| s.state.root.position);
        let rig_l = per_lane3(&|s| s.model.rigidities() * s.model.segment_length());
        let rig_step = per_lane3(&|s| s.model.rigidities() * (s.model.segment_length() * (h * s.model.damping + h * h)));
        let damping = per_lane(&|s| s.model.damping);
        let scale = per_lane(&|s| 1.0 + h * (s.model.air_drag / s.model.linear_density()));
        let nodes: Vec<(L, L)> = (0..nq).map(|g| (per_lane(&|s| s.dynamics.quadrature_nodes()[g].0), per_lane(&|s| s.dynamics.quadrature_nodes()[g].1))).collect();
        for (i, seg) in self.segs.iter_mut().enumerate().take(n) {
            for k in 0..2 {
                seg.q[k] = per_lane(&|s| s.state.q[2 * i + k]);
                seg.qdot[k] = per_lane(&|s| s.state.qdot[2 * i + k]);
                seg.rest[k] = per_lane(&|s| s.model.rest[i][k]);
            }
        }
        let root = |f: &dyn Fn(&crate::state::RootFrame) -> Vector3<f64>| per_lane3(&|s| f(&s.state.root));
        let mut start = MotionL {
            rot: M3::gather(std::array::from_fn(|j| strands[pick(j)].state.root.rotation)),
            x: V3::zero(),
            v: root(&|r| r.velocity),
            a: root(&|r| r.acceleration),
            w: root(&|r| r.angular_velocity),
            alpha: root(&|r| r.angular_acceleration),
        };
        let has_external = external.iter().any(|e| !e.is_empty());

        // Step 1: root-to-tip sweep.
        self.frames.clear();
        self.points.clear();
        let zero = sp(0.0);
        let half = sp(0.5);
        let mut kinetic = zero;
        let mut gravity_energy = zero;
        for i in 0..n {
            self.frames.push((start.rot, start.x + origin));
            let seg = &mut self.segs[i];
            let omega = V3::new(seg.q[0], seg.q[1], zero);
            let rate = V3::new(seg.qdot[0], seg.qdot[1], zero);
            seg.q_own = [zero; 2];
            seg.f_own = [[zero; 6]; 2];
            seg.m_own = [zero; 3];
            seg.wrench = [zero; 6];
            seg.mass = zero;
            seg.first = V3::zero();
            seg.inertia = [zero; 6];
            for &(sigma, weight) in &nodes {
                let pk = point_kinematics_l(&start, omega, rate, sigma);
                let p = &pk.motion;
                self.points.push(p.x + origin);
                let m = rho_a * weight;
                let ic = rot_inertia * weight;
                let w_l = p.rot.tr_mul_v(p.w);
                let icw_l = ic.cmul(w_l);
                let f = gravity * m - p.v * (drag_rate * m) - p.a * m;
                let tau_l = -(icw_l * drag_rate) - (ic.cmul(p.rot.tr_mul_v(p.alpha)) + w_l.cross(icw_l));
                let tau = p.rot.mul_v(tau_l);
                for k in 0..2 {
                    seg.q_own[k] += pk.u_cols[k].dot(f) + pk.w_cols[k].dot(tau);
                }
                let t = p.x.cross(f) + tau;
                for (w, x) in seg.wrench.iter_mut().zip([t.x, t.y, t.z, f.x, f.y, f.z]) {
                    *w += x;
                }
                kinetic += half * (m * p.v.norm_squared() + w_l.dot(icw_l));
                gravity_energy -= m * gravity.dot(p.x + origin);
                // Own momentum columns and own mass block (rotary part in the material frame).
                let w_local = [p.rot.tr_mul_v(pk.w_cols[0]), p.rot.tr_mul_v(pk.w_cols[1])];
                for a in 0..2 {
                    let icwa = ic.cmul(w_local[a]);
                    let u = pk.u_cols[a] * m;
                    let ang = p.rot.mul_v(icwa) + p.x.cross(u);
                    for (c, x) in seg.f_own[a].iter_mut().zip([ang.x, ang.y, ang.z, u.x, u.y, u.z]) {
                        *c += x;
                    }
                    for b in 0..=a {
                        seg.m_own[a + b] += m * pk.u_cols[b].dot(pk.u_cols[a]) + w_local[b].dot(icwa);
                    }
                }
                // Rigid inertia of the point: I_c - m [x]^2 = sum_k ic_k r_k r_k^T + m (|x|^2 1 - x x^T).
                seg.mass += m;
                seg.first += p.x * m;
                let x = [p.x.x, p.x.y, p.x.z];
                let x2 = p.x.norm_squared();
                let icv = [ic.x, ic.y, ic.z];
                for b in 0..3 {
                    for a in b..3 {
                        let mut v = -(m * x[a] * x[b]);
                        if a == b {
                            v += m * x2;
                        }
                        for k in 0..3 {
                            v += icv[k] * p.rot.r[a][k] * p.rot.r[b][k];
                        }
                        seg.inertia[sym(a, b)] += v;
                    }
                }
            }
            if has_external {
                // Point forces, lane by lane with the scalar kinematics (few, and only where they act).
                for (j, forces) in external.iter().enumerate() {
                    let model = &strands[j].model;
                    for pf in forces.iter() {
                        let (seg_index, sigma) = locate(model, pf.s);
                        if seg_index != i {
                            continue;
                        }
                        let q = Vector3::new(lane(seg.q[0], j), lane(seg.q[1], j), 0.0);
                        let qdot = Vector3::new(lane(seg.qdot[0], j), lane(seg.qdot[1], j), 0.0);
                        let pk = point_kinematics::<2>(&start.lane(j), &q, &qdot, sigma);
                        let q_own = pk.u_cols.tr_mul(&pf.force) + pk.w_cols.tr_mul(&pf.torque);
                        for k in 0..2 {
                            seg.q_own[k].as_array_mut()[j] += q_own[k];
                        }
                        let wr = wrench(&pf.force, &pf.torque, &pk.motion.x);
                        for k in 0..6 {
                            seg.wrench[k].as_array_mut()[j] += wr[k];
                        }
                    }
                }
            }
            let end = point_kinematics_l(&start, omega, rate, l);
            let x = end.motion.x;
            for k in 0..2 {
                let w = end.w_cols[k];
                let v = end.u_cols[k] - w.cross(x);
                seg.motion[k] = [w.x, w.y, w.z, v.x, v.y, v.z];
            }
            start = end.motion;
        }
        self.frames.push((start.rot, start.x + origin));

        // Step 1b: the geometric stiffness of the constraint loads a lane's strand carries (its last step's, and
        // earlier ones fading: `Dynamics::geometric_stiffness`), lane by lane with the scalar code on the lane's
        // frames and motion subspaces (it needs them at the current state, as after the scalar sweep). Zero
        // in lanes without loads.
        let kept = geometric_stiffness_kept(h);
        let geometric = &mut self.geometric[..n];
        geometric.fill([zero; 2]);
        for (j, s) in strands.iter_mut().enumerate() {
            if !s.takes_geometric_stiffness() {
                continue;
            }
            let dy = &mut s.dynamics;
            dy.frames.clear();
            dy.frames.extend(self.frames.iter().map(|(rot, x)| Frame { rotation: rot.lane(j), position: x.lane(j) }));
            for (i, seg) in self.segs[..n].iter().enumerate() {
                dy.set_segment_motion(i, lane_twists(&seg.motion, j));
            }
            dy.geometric_stiffness(&s.model, &s.state, &s.constraint_loads, kept);
            for (i, g) in geometric.iter_mut().enumerate() {
                for k in 0..2 {
                    g[k].as_array_mut()[j] = s.dynamics.geometric[2 * i + k];
                }
            }
        }

        // Step 2 (forces): tip-to-root suffix sums of the wrenches; step 4: elasticity and damping; the
        // right-hand side h F - h^2 K qdot.
        let mut suffix = [zero; 6];
        for seg in self.segs[..n].iter_mut().rev() {
            for k in 0..2 {
                seg.force[k] = seg.q_own[k] + dot6(&seg.motion[k], &suffix);
            }
            for (s, w) in suffix.iter_mut().zip(seg.wrench) {
                *s += w;
            }
        }
        let hh = sp(h);
        let rig = [rig_l.x, rig_l.y];
        let mut elastic = zero;
        for (seg, g) in self.segs[..n].iter_mut().zip(&self.geometric[..n]) {
            for k in 0..2 {
                let dq = seg.q[k] - seg.rest[k];
                elastic += half * rig[k] * dq * dq;
                seg.force[k] = seg.force[k] - rig[k] * (dq + damping * seg.qdot[k]);
                seg.b[k] = hh * seg.force[k] - hh * hh * (rig[k] + g[k]) * seg.qdot[k];
            }
        }

        // The articulated-body solve (see `Dynamics::solve_articulated`): elimination from the tip.
        let rig_s = [rig_step.x, rig_step.y];
        let mut ia = [[zero; 6]; 6];
        let mut pa = [zero; 6];
        let mut ok = sp(0.0).cmp_lt(sp(1.0)); // all lanes true
        for (seg, g) in self.segs[..n].iter_mut().zip(&self.geometric[..n]).rev() {
            let s = &seg.motion;
            let mut ia_s = [[zero; 6]; 2];
            for k in 0..2 {
                for (r, row) in ia.iter().enumerate() {
                    ia_s[k][r] = dot6(row, &s[k]);
                }
            }
            let mut u = [[zero; 6]; 2];
            for k in 0..2 {
                for r in 0..6 {
                    u[k][r] = seg.f_own[k][r] * scale + ia_s[k][r];
                }
            }
            let d00 = seg.m_own[0] * scale + dot6(&s[0], &ia_s[0]) + rig_s[0] + hh * hh * g[0];
            let d01 = seg.m_own[1] * scale + dot6(&s[0], &ia_s[1]);
            let d10 = seg.m_own[1] * scale + dot6(&s[1], &ia_s[0]);
            let d11 = seg.m_own[2] * scale + dot6(&s[1], &ia_s[1]) + rig_s[1] + hh * hh * g[1];
            let c = [-dot6(&s[0], &pa) - seg.b[0], -dot6(&s[1], &pa) - seg.b[1]];
            let det = d00 * d11 - d01 * d10;
            ok = ok & d00.cmp_gt(zero) & det.cmp_gt(zero) & det.is_finite();
            let inv = sp(1.0) / det;
            let dinv = [d11 * inv, -d10 * inv, d00 * inv];
            let mut u_dinv = [[zero; 6]; 2];
            for r in 0..6 {
                u_dinv[0][r] = u[0][r] * dinv[0] + u[1][r] * dinv[1];
                u_dinv[1][r] = u[0][r] * dinv[1] + u[1][r] * dinv[2];
            }
            // I^A += scale I_own - U D^-1 U^T, with I_own = [[J, [c]x], [[c]x^T, m 1]].
            let cv = seg.first;
            let cx = [[zero, -cv.z, cv.y], [cv.z, zero, -cv.x], [-cv.y, cv.x, zero]];
            for r in 0..6 {
                for cc in 0..6 {
                    let own = match (r < 3, cc < 3) {
                        (true, true) => seg.inertia[sym(r, cc)],
                        (true, false) => cx[r][cc - 3],
                        (false, true) => cx[cc][r - 3],
                        (false, false) => {
                            if r == cc {
                                seg.mass
                            } else {
                                zero
                            }
                        }
                    };
                    ia[r][cc] += own * scale - (u_dinv[0][r] * u[0][cc] + u_dinv[1][r] * u[1][cc]);
                }
                pa[r] += u_dinv[0][r] * c[0] + u_dinv[1][r] * c[1];
            }
            seg.u = u;
            seg.dinv = dinv;
            seg.c = c;
        }
        // Back-substitution from the root: x_Q = -D^-1 (U^T V + c), V += S_Q x_Q.
        let mut v = [zero; 6];
        for seg in self.segs[..n].iter_mut() {
            let t = [dot6(&seg.u[0], &v) + seg.c[0], dot6(&seg.u[1], &v) + seg.c[1]];
            let x = [-(seg.dinv[0] * t[0] + seg.dinv[1] * t[1]), -(seg.dinv[1] * t[0] + seg.dinv[2] * t[1])];
            for r in 0..6 {
                v[r] += seg.motion[0][r] * x[0] + seg.motion[1][r] * x[1];
            }
            seg.b = x;
            ok = ok & x[0].is_finite() & x[1].is_finite();
        }

        // Scatter: each lane's prepared step and the sweep's results into its strand.
        let ok = ok.move_mask();
        let mut first = None;
        for (j, s) in strands.iter_mut().enumerate() {
            if ok & (1 << j) == 0 {
                first.get_or_insert(StrandError::NotPositiveDefinite { what: "step matrix" });
                continue;
            }
            let segs = &self.segs[..n];
            let v_new = DVector::from_fn(2 * n, |r, _| s.state.qdot[r] + lane(segs[r / 2].b[r % 2], j));
            let dy = &mut s.dynamics;
            dy.frames.clear();
            dy.frames.extend(self.frames.iter().map(|(rot, x)| Frame { rotation: rot.lane(j), position: x.lane(j) }));
            dy.points.clear();
            dy.points.extend(self.points.iter().map(|x| x.lane(j)));
            for (r, f) in dy.forces.iter_mut().enumerate() {
                *f = lane(segs[r / 2].force[r % 2], j);
            }
            dy.kinetic_energy = lane(kinetic, j);
            dy.gravity_energy = lane(gravity_energy, j);
            dy.elastic_energy = lane(elastic, j);
            s.prepared = Some((h, v_new));
        }
        first.map_or(Ok(()), Err)
    }

    /// Gives `strand`, lane `lane` of the last [`StrandBatch::prepare`] (and not changed since), that lane's
    /// motion subspaces and articulated elimination, so that [`Strand::finish_step`] can solve constraints as
    /// after [`Strand::prepare_step`]. Errors if the lane is out of range or the strand has no prepared step
    /// or another size.
    pub fn hand_over(&self, lane_index: usize, strand: &mut Strand) -> Result<()> {
        if lane_index >= self.lanes || !strand.has_prepared_step() || strand.model.segments != self.segments {
            return Err(StrandError::InvalidParameter {
                field: "batch",
                reason: format!("lane {lane_index} of {} was not prepared for this strand", self.lanes),
            });
        }
        let j = lane_index;
        for (i, seg) in self.segs[..self.segments].iter().enumerate() {
            let (motion, u) = (lane_twists(&seg.motion, j), lane_twists(&seg.u, j));
            let (d00, d01, d11) = (lane(seg.dinv[0], j), lane(seg.dinv[1], j), lane(seg.dinv[2], j));
            let dinv = Matrix3::new(d00, d01, 0.0, d01, d11, 0.0, 0.0, 0.0, 1.0);
            let c = Vector3::new(lane(seg.c[0], j), lane(seg.c[1], j), 0.0);
            strand.dynamics.set_segment_solver(i, motion, (u, dinv, c));
        }
        Ok(())
    }
}

/// Lane `j` of a segment's two lane-wise 6-vectors (its motion subspace's twists, or the articulated solve's
/// `U`), as the scalar code's 6x2 matrix.
fn lane_twists(t: &[L6; 2], j: usize) -> Twists {
    let mut out = Twists::zeros();
    for k in 0..2 {
        for r in 0..6 {
            out[(r, k)] = lane(t[k][r], j);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraint::{ConstraintKind, PointConstraint};
    use crate::hair_type::HairType;
    use crate::model::StrandModel;
    use crate::state::RootFrame;

    /// Four different strands of 16 segments: hair types, lengths, rest curls, root poses and root motions
    /// all differ; one is straight (its segments use the series branch of the helix coefficients), the curly
    /// ones use the closed form, so a batch mixes both branches.
    fn strands() -> Vec<Strand> {
        let specs = [
            (HairType::H1, 0.10, false, Vector3::new(0.0, 0.0, 0.3), -Vector3::z(), Vector3::new(0.02, 0.0, 0.0), Vector3::zeros()),
            (HairType::CAUCASIAN, 0.25, true, Vector3::new(0.01, 0.0, 0.3), Vector3::new(0.3, 0.0, -1.0), Vector3::new(0.05, -0.02, 0.0), Vector3::new(0.0, 0.0, 1.5)),
            (HairType::AFRICAN, 0.12, true, Vector3::new(-0.02, 0.01, 0.28), Vector3::new(0.0, 0.4, -1.0), Vector3::zeros(), Vector3::new(2.0, -1.0, 0.5)),
            (HairType::GC3, 0.18, true, Vector3::new(0.0, -0.01, 0.31), Vector3::new(-0.2, 0.1, -1.0), Vector3::new(-0.1, 0.0, 0.03), Vector3::zeros()),
        ];
        specs
            .iter()
            .map(|&(h, len, curly, pos, tangent, vel, omega)| {
                let mut m = StrandModel::new(ModelKind::Reduced, len, 16, h.section().unwrap(), h.material().unwrap()).unwrap();
                if curly {
                    let (tw, bd) = h.rest_curvature();
                    m = m.with_uniform_rest(tw.max(5.0), bd.max(20.0), 0.0);
                }
                let mut root = RootFrame::new(pos, tangent, Vector3::y()).unwrap();
                root.velocity = vel;
                root.angular_velocity = omega;
                root.acceleration = -vel * 0.5;
                Strand::new(m, root).unwrap()
            })
            .collect()
    }

    fn forces_for(k: usize, step: usize) -> Vec<PointForce> {
        // Lane 1 and 3 get point forces (lane 3 a force and a torque) during part of the run.
        match k {
            1 if step % 3 != 0 => vec![PointForce::new(0.11, Vector3::new(2e-5, -1e-5, 1e-5))],
            3 if step > 50 => vec![PointForce { s: 0.07, force: Vector3::new(-1e-5, 0.0, 2e-5), torque: Vector3::new(0.0, 1e-10, -2e-10) }],
            _ => vec![],
        }
    }

    fn max_difference(a: &Strand, b: &Strand) -> f64 {
        let dq = (&a.state.q - &b.state.q).amax() / (1.0 + b.state.q.amax());
        let dv = (&a.state.qdot - &b.state.qdot).amax() / (1.0 + b.state.qdot.amax());
        dq.max(dv)
    }

    /// Steps `scalar` one by one and `batched` (the same strands) in `batch`, by 1 ms with step `step`'s point
    /// forces ([`forces_for`]).
    fn step_alongside(scalar: &mut [Strand], batched: &mut [Strand], batch: &mut StrandBatch, step: usize) {
        let forces: Vec<Vec<PointForce>> = (0..scalar.len()).map(|k| forces_for(k, step)).collect();
        for (s, f) in scalar.iter_mut().zip(&forces) {
            s.step(1e-3, f).unwrap();
        }
        let ext: Vec<&[PointForce]> = forces.iter().map(|f| f.as_slice()).collect();
        let mut refs: Vec<&mut Strand> = batched.iter_mut().collect();
        batch.step(1e-3, &mut refs, &ext).unwrap();
    }

    /// The first `lanes` of [`strands`] twice (to step one by one and in a batch) and a batch for them.
    fn alongside(lanes: usize) -> (Vec<Strand>, Vec<Strand>, StrandBatch) {
        let scalar: Vec<Strand> = strands().into_iter().take(lanes).collect();
        let batch = StrandBatch::for_strand(&scalar[0]);
        (scalar.clone(), scalar, batch)
    }

    #[test]
    fn batch_steps_equal_scalar_steps() {
        // 300 steps of 1 ms for 4 different strands, full and partly filled batches (1 to 4 lanes): q and qdot
        // equal the scalar step's to 1e-10 (relative to 1 + max |q|, 1 + max |qdot|); only round-off differs
        // (SIMD sine and cosine, summation order).
        for lanes in 1..=LANES {
            let (mut scalar, mut batched, mut batch) = alongside(lanes);
            for step in 0..300 {
                step_alongside(&mut scalar, &mut batched, &mut batch, step);
            }
            for (k, (a, b)) in batched.iter().zip(&scalar).enumerate() {
                let d = max_difference(a, b);
                assert!(d < 1e-10, "{lanes} lanes, strand {k}: difference {d:e}");
                assert_eq!(a.state.time, b.state.time);
                assert!((a.state.root.position - b.state.root.position).norm() < 1e-15);
                // The strand moved (the comparison is not between two resting strands).
                assert!(b.state.qdot.amax() > 1e-3, "strand {k} at rest");
            }
        }
    }

    #[test]
    fn lanes_carrying_constraint_loads_take_their_geometric_stiffness_as_the_scalar_step() {
        // 200 steps of 1 ms for 1 to 4 different strands, each given constraint loads (a tooth's pull at two
        // places, 0.2-2 mN) in two steps of three and none in the third, so that their geometric stiffness is
        // taken from the last step's loads, or from earlier ones fading (`GEOMETRIC_STIFFNESS_MEMORY`). q, qdot
        // and the remembered stiffness equal the scalar step's to 1e-10 (relative), lane by lane.
        for lanes in 1..=LANES {
            let (mut scalar, mut batched, mut batch) = alongside(lanes);
            let mut carried = 0;
            for step in 0..200 {
                for (k, (a, b)) in scalar.iter_mut().zip(batched.iter_mut()).enumerate() {
                    let len = a.model.length;
                    let loads = if (step + k) % 3 == 2 {
                        Vec::new()
                    } else {
                        let f = 2e-3 * (0.1 + ((step * 7 + k * 13) % 10) as f64 / 10.0);
                        vec![(0.45 * len, Vector3::new(f, -0.5 * f, 0.2 * f)), (0.9 * len, Vector3::new(-0.3 * f, f, 0.0))]
                    };
                    a.constraint_loads = loads.clone();
                    b.constraint_loads = loads;
                    carried += b.takes_geometric_stiffness() as usize;
                }
                step_alongside(&mut scalar, &mut batched, &mut batch, step);
            }
            assert!(carried >= 100 * lanes, "{lanes} lanes: only {carried} strand-steps took a geometric stiffness");
            for (k, (a, b)) in batched.iter().zip(&scalar).enumerate() {
                let d = max_difference(a, b);
                assert!(d < 1e-10, "{lanes} lanes, strand {k}: difference {d:e}");
                let g = (&a.dynamics.geometric - &b.dynamics.geometric).amax() / (1.0 + b.dynamics.geometric.amax());
                assert!(g < 1e-10, "{lanes} lanes, strand {k}: geometric stiffness differs by {g:e}");
                assert!(b.dynamics.geometric.amax() > 0.0, "strand {k}: no geometric stiffness at the end");
                assert!(b.state.qdot.amax() > 1e-3, "strand {k} at rest");
            }
        }
    }

    #[test]
    fn prepared_lanes_expose_the_scalar_sweep() {
        // After prepare, each strand's frames, Gauss points, forces and energies equal those of its own
        // prepare_step (1e-12 m, 1e-10 relative), and the prepared velocities agree to 1e-10.
        let mut scalar = strands();
        let mut batched = scalar.clone();
        for s in scalar.iter_mut() {
            s.prepare_step(1e-3, &[]).unwrap();
        }
        let mut batch = StrandBatch::new(16, 2);
        let mut refs: Vec<&mut Strand> = batched.iter_mut().collect();
        batch.prepare(1e-3, &mut refs, &[]).unwrap();
        for (a, b) in batched.iter().zip(&scalar) {
            assert_eq!(a.dynamics.frames.len(), b.dynamics.frames.len());
            assert_eq!(a.dynamics.points.len(), b.dynamics.points.len());
            for (fa, fb) in a.dynamics.frames.iter().zip(&b.dynamics.frames) {
                assert!((fa.position - fb.position).norm() < 1e-12 && (fa.rotation - fb.rotation).norm() < 1e-12);
            }
            for (pa, pb) in a.dynamics.points.iter().zip(&b.dynamics.points) {
                assert!((pa - pb).norm() < 1e-12);
            }
            assert!((&a.dynamics.forces - &b.dynamics.forces).norm() <= 1e-10 * b.dynamics.forces.norm());
            let e = |s: &Strand| (s.dynamics.kinetic_energy, s.dynamics.gravity_energy, s.dynamics.elastic_energy);
            let (ea, eb) = (e(a), e(b));
            assert!((ea.0 - eb.0).abs() <= 1e-10 * eb.0.abs().max(1e-30) && (ea.1 - eb.1).abs() <= 1e-10 * eb.1.abs() && (ea.2 - eb.2).abs() <= 1e-10 * eb.2.abs().max(1e-30));
            let (va, vb) = (&a.prepared.as_ref().unwrap().1, &b.prepared.as_ref().unwrap().1);
            assert!((va - vb).amax() <= 1e-10 * (1.0 + vb.amax()));
        }
    }

    #[test]
    fn a_handed_over_lane_solves_constraints_like_the_scalar_step() {
        // A contact pressed into lane 2's strand: batch prepare + hand_over + finish_step with the contact (from
        // the second step with the geometric stiffness of the contact's load, in the lane) gives the same impulse
        // and state as the scalar step_constrained (1e-9 relative), over 50 steps.
        let mut scalar = strands();
        let mut batched = scalar.clone();
        let mut batch = StrandBatch::new(16, 2);
        let opts = ConstraintOptions::default();
        for step in 0..50 {
            let contact = PointConstraint {
                s: 0.06,
                kind: ConstraintKind::Contact { normal: Vector3::new(0.0, 1.0, 0.0), depth: 1e-5 * step as f64, friction: 0.3 },
                velocity: Vector3::new(0.0, 0.05, 0.01),
            };
            let ps = scalar[2].step_constrained(1e-3, &[], &[contact], &opts).unwrap();
            for (k, s) in scalar.iter_mut().enumerate() {
                if k != 2 {
                    s.step(1e-3, &[]).unwrap();
                }
            }
            // From the second step the strand carries the contact's load: its lane takes the geometric stiffness.
            let mut refs: Vec<&mut Strand> = batched.iter_mut().collect();
            batch.prepare(1e-3, &mut refs, &[]).unwrap();
            batch.hand_over(2, &mut batched[2]).unwrap();
            let pb = batched[2].finish_step(&[contact], &opts).unwrap();
            for (k, s) in batched.iter_mut().enumerate() {
                if k != 2 {
                    s.finish_step(&[], &opts).unwrap();
                }
            }
            assert!((pb[0] - ps[0]).norm() <= 1e-9 * ps[0].norm().max(1e-12), "step {step}: impulse {} vs {}", pb[0], ps[0]);
        }
        assert!(scalar[2].state.qdot.amax() > 1e-3);
        for (k, (a, b)) in batched.iter().zip(&scalar).enumerate() {
            let d = max_difference(a, b);
            assert!(d < 1e-9, "strand {k}: difference {d:e}");
        }
    }

    #[test]
    fn reduced_kinematics_equal_the_general_ones() {
        // The reduced segment kinematics (zero terms left out) against the general lane-wise formulas, on both
        // branches of the coefficients (u below and above 0.1): 1e-13 relative.
        let o0 = L::from([0.0, 30.0, -300.0, 1e-3]);
        let o1 = L::from([0.0, 80.0, 25.0, 2e-3]);
        let n0 = L::from([3.0, -40.0, 100.0, 50.0]);
        let n1 = L::from([-2.0, 7.0, 300.0, 10.0]);
        let sigma = L::from([0.013, 0.01, 0.02, 0.005]);
        let z = sp(0.0);
        let a = segment_kinematics_reduced(o0, o1, n0, n1, sigma);
        let b = segment_kinematics(V3::new(o0, o1, z), V3::new(n0, n1, z), sigma);
        for j in 0..LANES {
            let close = |x: V3, y: V3| (x.lane(j) - y.lane(j)).norm() <= 1e-13 * (1.0 + y.lane(j).norm());
            assert!((a.rotation.lane(j) - b.rotation.lane(j)).norm() < 1e-14, "lane {j}");
            assert!(close(a.offset, b.offset) && close(a.angular_bias, b.angular_bias) && close(a.linear_bias, b.linear_bias), "lane {j}");
            for k in 0..2 {
                assert!(close(a.angular[k], b.angular[k]) && close(a.linear[k], b.linear[k]), "lane {j} column {k}");
            }
        }
    }

    #[test]
    fn bad_batches_are_refused_with_a_reason() {
        let mut s = strands();
        let mut batch = StrandBatch::new(16, 2);
        // Five strands.
        let mut five: Vec<Strand> = s.iter().cloned().chain(std::iter::once(s[0].clone())).collect();
        let mut refs: Vec<&mut Strand> = five.iter_mut().collect();
        assert!(matches!(batch.prepare(1e-3, &mut refs, &[]), Err(StrandError::InvalidParameter { field: "batch", .. })));
        // No strand.
        assert!(batch.prepare(1e-3, &mut [], &[]).is_err());
        // Another segment count, the full model, another integrator.
        let h = HairType::H1;
        let other = |kind, n| Strand::new(StrandModel::new(kind, 0.1, n, h.section().unwrap(), h.material().unwrap()).unwrap(), RootFrame::new(Vector3::zeros(), -Vector3::z(), Vector3::x()).unwrap()).unwrap();
        for mut bad in [other(ModelKind::Reduced, 8), other(ModelKind::Full, 16), {
            let mut m = other(ModelKind::Reduced, 16);
            m.integrator = Integrator::ImplicitMidpoint;
            m
        }] {
            assert!(!batch.accepts(&bad));
            let mut refs: Vec<&mut Strand> = vec![&mut s[0], &mut bad];
            let err = batch.prepare(1e-3, &mut refs, &[]).unwrap_err();
            assert!(err.to_string().contains("strand 1"), "{err}");
        }
        // Bad time step and non-finite force: refused, nothing prepared, states unchanged.
        let before = s[0].state.clone();
        let mut refs: Vec<&mut Strand> = s.iter_mut().collect();
        assert!(batch.step(f64::NAN, &mut refs, &[]).is_err());
        let nan = [PointForce::new(0.05, Vector3::new(f64::NAN, 0.0, 0.0))];
        let ext: Vec<&[PointForce]> = vec![&[], &nan, &[], &[]];
        assert!(batch.step(1e-3, &mut refs, &ext).is_err());
        assert!(!refs[0].has_prepared_step());
        assert_eq!(s[0].state, before);
        // hand_over of a lane that was not prepared.
        assert!(batch.hand_over(3, &mut s[3]).is_err());
    }
}
