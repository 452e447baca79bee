//! Lagrangian dynamics of a strand: mass matrix, generalized forces and energies at one state.
//!
//! Pipeline of [`Dynamics::evaluate`] (world axes; spatial quantities about the root position):
//! 1. Root-to-tip sweep. For each segment the start frame's pose, velocity and velocity-product
//!    acceleration (the acceleration with `qddot = 0`) are known; each Gauss point of the segment gets its
//!    pose from the closed-form helix ([`crate::helix`]) and its velocity and velocity-product acceleration
//!    from the segment's derivatives `dE/dOmega`, `dp/dOmega` evaluated with dual numbers along `qdot`
//!    (which also gives their rates of change). Each point carries the mass `rho A w` and the rotary inertia
//!    of its slice of section, and a force (gravity, air drag, minus the velocity-product inertial force)
//!    and torque. Per segment this gathers: its own generalized forces, its own mass-matrix block, the
//!    momentum of its own motion, its total wrench and its rigid inertia; the motion subspace `S_Q` (spatial
//!    twists that unit `qdot_Q` gives to everything beyond) comes from the derivatives at the segment's end.
//! 2. Tip-to-root sweep with suffix sums (composite inertia `I^C`, wrench `W`):
//!    `Q_Q = own_Q + S_Q^T W_Q+1`, `F_Q = I^C_Q+1 S_Q + own momentum`, `M[Q,Q] = S_Q^T I^C_Q+1 S_Q + own block`.
//! 3. Off-diagonal blocks `M[P,Q] = S_P^T F_Q` for `P < Q` (O(N^2); everything else is O(N)).
//! 4. Elastic `-K (q - q_rest)` and internal damping `-tau K qdot` (K diagonal).
//!
//! Steps 1, 4 and the force half of step 2 are `Dynamics::sweep`; the mass half of step 2 and step 3 are
//! only done when the dense mass matrix is asked for. The linearly implicit step instead solves
//! `(scale M + stiffness K) x = b` from the per-segment sums of step 1 in O(N) (`Dynamics::solve_articulated`).
//!
//! Air drag acts on each point as `-nu w rdot`, with a matching rotary drag `-(nu / rho A) I_c omega`, so the
//! drag matrix is `(nu / rho A) M` and the integrator can treat it implicitly.

use crate::helix::segment_kinematics;
use crate::kinematics::{darboux, own_twists, point_velocity, Frame, Twists};
use crate::model::{gauss_legendre, StrandModel};
use crate::state::StrandState;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3xX, Matrix6, SMatrix, SVector, Vector3};

mod articulated;

pub(crate) type Vector6 = SVector<f64, 6>;

/// A force (and a torque) applied to the strand at arc length `s` (m from the root), world axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointForce {
    /// Arc length from the root, m (clamped to [0, L]).
    pub s: f64,
    /// Force on the centreline, N.
    pub force: Vector3<f64>,
    /// Torque on the cross-section, N m (e.g. friction acting on the hair's surface twists it).
    pub torque: Vector3<f64>,
}

impl PointForce {
    /// A force without torque.
    pub fn new(s: f64, force: Vector3<f64>) -> Self {
        Self { s, force, torque: Vector3::zeros() }
    }
}

/// Rigid inertia about the root origin of a set of points: mass, first moment, rotational inertia.
#[derive(Debug, Clone, Copy)]
struct Inertia {
    /// Mass, kg.
    m: f64,
    /// First moment `sum m x`, kg m.
    c: Vector3<f64>,
    /// Rotational inertia about the origin `sum (I_c - m [x]^2)`, kg m^2.
    j: Matrix3<f64>,
}

impl Inertia {
    fn zero() -> Self {
        Self { m: 0.0, c: Vector3::zeros(), j: Matrix3::zeros() }
    }

    /// Momentum (angular about the origin; linear) of a rigid motion with spatial twist `t = (omega; v)`.
    fn apply(&self, t: &Vector6) -> Vector6 {
        let w = Vector3::new(t[0], t[1], t[2]);
        let v = Vector3::new(t[3], t[4], t[5]);
        let a = self.j * w + self.c.cross(&v);
        let l = v * self.m - self.c.cross(&w);
        Vector6::new(a.x, a.y, a.z, l.x, l.y, l.z)
    }

    /// Adds a point of mass `m` at `x` whose rotary inertia is `rot diag(ic_local) rot^T`.
    fn add_point(&mut self, m: f64, rot: &Matrix3<f64>, ic_local: &Vector3<f64>, x: &Vector3<f64>) {
        self.m += m;
        self.c += x * m;
        // I_c - m [x]^2 = sum_k ic_k r_k r_k^T + m (|x|^2 1 - x x^T).
        let x2 = x.norm_squared();
        for b in 0..3 {
            for a in b..3 {
                let mut v = -m * x[a] * x[b];
                if a == b {
                    v += m * x2;
                }
                for k in 0..3 {
                    v += ic_local[k] * rot[(a, k)] * rot[(b, k)];
                }
                self.j[(a, b)] += v;
                if a != b {
                    self.j[(b, a)] += v;
                }
            }
        }
    }

    /// The 6x6 spatial inertia `[[J, [c]x], [-[c]x, m 1]]` (maps a twist to its momentum, as [`Inertia::apply`]).
    fn matrix(&self) -> Matrix6<f64> {
        let mut out = Matrix6::zeros();
        let cx = self.c.cross_matrix();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.j);
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&cx);
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&cx.transpose());
        out.fixed_view_mut::<3, 3>(3, 3).fill_diagonal(self.m);
        out
    }

    fn add(&mut self, o: &Inertia) {
        self.m += o.m;
        self.c += o.c;
        self.j += o.j;
    }
}

/// Kinematics of a frame: pose relative to the root origin, velocity and velocity-product acceleration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Motion {
    pub(crate) rot: Matrix3<f64>,
    pub(crate) x: Vector3<f64>,
    pub(crate) v: Vector3<f64>,
    pub(crate) a: Vector3<f64>,
    pub(crate) w: Vector3<f64>,
    pub(crate) alpha: Vector3<f64>,
}

/// A point inside segment `i` at arc length `sigma`: its motion and its own Jacobian columns
/// (angular `w_k` and linear `u_k` velocity per unit `qdot_k` of that segment; `D` = 2 or 3 coordinates).
pub(crate) struct PointKinematics<const D: usize> {
    pub(crate) motion: Motion,
    pub(crate) w_cols: SMatrix<f64, 3, D>,
    pub(crate) u_cols: SMatrix<f64, 3, D>,
}

/// Pose, velocity and acceleration of the point at `sigma` in a segment starting at `start`, for a segment
/// with `D` coordinates (`q`, `qdot` beyond `D` are zero).
#[inline(always)]
pub(crate) fn point_kinematics<const D: usize>(start: &Motion, q: &Vector3<f64>, qdot: &Vector3<f64>, sigma: f64) -> PointKinematics<D> {
    let sp = segment_kinematics(q, qdot, sigma);
    let r = start.rot * sp.offset;
    let qd = qdot.fixed_rows::<D>(0);
    let w_cols = start.rot * sp.angular.fixed_columns::<D>(0);
    let u_cols = start.rot * sp.linear.fixed_columns::<D>(0);
    let w_loc = w_cols * qd;
    let v_loc = u_cols * qd;
    let motion = Motion {
        rot: start.rot * sp.rotation,
        x: start.x + r,
        v: start.v + start.w.cross(&r) + v_loc,
        a: start.a + start.alpha.cross(&r) + start.w.cross(&(start.w.cross(&r) + v_loc * 2.0)) + start.rot * sp.linear_bias,
        w: start.w + w_loc,
        alpha: start.alpha + start.w.cross(&w_loc) + start.rot * sp.angular_bias,
    };
    PointKinematics { motion, w_cols, u_cols }
}

/// Spatial twists (about the origin) of the `D` columns `(w_k, u_k)` given at the point `x`; columns beyond
/// `D` are zero.
fn twists_at<const D: usize>(w_cols: &SMatrix<f64, 3, D>, u_cols: &SMatrix<f64, 3, D>, x: &Vector3<f64>) -> Twists {
    let mut t = Twists::zeros();
    for k in 0..D {
        let w = w_cols.column(k).into_owned();
        let v = u_cols.column(k) - w.cross(x);
        t.fixed_view_mut::<3, 1>(0, k).copy_from(&w);
        t.fixed_view_mut::<3, 1>(3, k).copy_from(&v);
    }
    t
}

/// What the root-to-tip sweep gathers about one segment.
#[derive(Debug, Clone, Copy)]
struct SegmentSums {
    /// Generalized forces from the segment's own points.
    q_own: Vector3<f64>,
    /// Momentum wrenches of the segment's own motion, one column per coordinate.
    f_own: Twists,
    /// The segment's own mass-matrix block.
    m_own: Matrix3<f64>,
    /// Total wrench of the segment's points about the origin.
    wrench: Vector6,
    /// Rigid inertia of the segment's points.
    inertia: Inertia,
}

/// Workspace of [`Dynamics::geometric_stiffness`], kept for its storage.
#[derive(Debug, Clone, Default)]
struct GeometricWorkspace {
    /// Each coordinate's twist `(w, v)` (rad/m, m/m).
    twists: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// The velocity each coordinate gives the load's point, `u = v + w x x` (m/s per coordinate rate).
    moved: Vec<Vector3<f64>>,
    /// Each coordinate's row sum of the loads' Hessian in magnitude (N m^3).
    bound: Vec<f64>,
}

/// Reusable workspace and results of a dynamics evaluation (allocated once per strand).
#[derive(Debug, Clone)]
pub struct Dynamics {
    /// Gauss points of a segment: (arc length from segment start in m, weight in m).
    nodes: Vec<(f64, f64)>,
    /// Segment start frames and the tip frame (N + 1), world coordinates.
    pub frames: Vec<Frame>,
    /// Centreline positions of the Gauss points, segment by segment from the root (world, m), at the state of
    /// the last evaluation; with [`Dynamics::frames`] they sample the centreline at no extra cost.
    pub points: Vec<Vector3<f64>>,
    /// Motion subspace S_Q of each segment (twists about the root position).
    motion: Vec<Twists>,
    /// Per-segment sums of the root-to-tip sweep.
    sums: Vec<SegmentSums>,
    /// Coupling blocks F_Q = I^C_Q+1 S_Q + own momentum.
    coupling: Vec<Twists>,
    /// Workspace of [`Dynamics::solve_articulated`], per segment: `U_Q`, `D_Q^-1` and `c_Q`.
    articulated: Vec<(Twists, Matrix3<f64>, Vector3<f64>)>,
    /// Mass matrix M(q): the kinetic energy (with a fixed root) is `qdot^T M qdot / 2`, J. Assembled only by
    /// `evaluate(.., with_mass = true)` (the linearly implicit step does not need it and leaves it stale).
    pub mass: DMatrix<f64>,
    /// All generalized forces at the evaluated state (elastic, damping, gravity, drag, point forces and
    /// minus the velocity-product terms), conjugate to q, so that `qdot . forces` is a power in W.
    pub forces: DVector<f64>,
    /// Diagonal geometric stiffness of the recent steps' constraint loads (the Gershgorin bound of their
    /// Hessian, the last step's or the earlier steps' fading, whichever is larger), per coordinate (N m^3, as the
    /// elastic `K`): see [`Dynamics::geometric_stiffness`]. Zero without loads.
    pub geometric: DVector<f64>,
    /// Workspace of [`Dynamics::geometric_stiffness`] (no allocation in the 1 kHz step).
    geometric_work: GeometricWorkspace,
    /// Kinetic energy, J.
    pub kinetic_energy: f64,
    /// Gravitational potential energy `-sum m g . r` (world origin as reference), J.
    pub gravity_energy: f64,
    /// Elastic energy `(q - q_rest)^T K (q - q_rest) / 2`, J.
    pub elastic_energy: f64,
}

pub(crate) fn wrench(force: &Vector3<f64>, torque: &Vector3<f64>, x: &Vector3<f64>) -> Vector6 {
    let t = x.cross(force) + torque;
    Vector6::new(t.x, t.y, t.z, force.x, force.y, force.z)
}

impl Dynamics {
    /// Workspace for strands of this model's size and quadrature.
    pub fn new(model: &StrandModel) -> Self {
        let l = model.segment_length();
        let nodes = gauss_legendre(model.quadrature_points)
            .into_iter()
            .map(|(x, w)| (0.5 * l * (1.0 + x), 0.5 * l * w))
            .collect::<Vec<_>>();
        let n = model.segments;
        let dofs = model.dofs();
        let empty = SegmentSums {
            q_own: Vector3::zeros(),
            f_own: Twists::zeros(),
            m_own: Matrix3::zeros(),
            wrench: Vector6::zeros(),
            inertia: Inertia::zero(),
        };
        Self {
            nodes,
            frames: Vec::with_capacity(n + 1),
            points: Vec::with_capacity(n * model.quadrature_points),
            motion: vec![Twists::zeros(); n],
            sums: vec![empty; n],
            coupling: vec![Twists::zeros(); n],
            articulated: vec![(Twists::zeros(), Matrix3::zeros(), Vector3::zeros()); n],
            mass: DMatrix::zeros(dofs, dofs),
            forces: DVector::zeros(dofs),
            geometric: DVector::zeros(dofs),
            geometric_work: GeometricWorkspace::default(),
            kinetic_energy: 0.0,
            gravity_energy: 0.0,
            elastic_energy: 0.0,
        }
    }

    /// Sets segment `i`'s motion subspace (its twists about the root position, as the sweep leaves them), for
    /// [`Dynamics::geometric_stiffness`] after a batched sweep.
    pub(crate) fn set_segment_motion(&mut self, i: usize, motion: Twists) {
        self.motion[i] = motion;
    }

    /// Sets segment `i`'s motion subspace and articulated-solve workspace `(U, D^-1, c)` (padded to 3 columns),
    /// as [`Dynamics::sweep`] and [`Dynamics::solve_articulated`] would have left them; used by
    /// [`crate::batch::StrandBatch`] to hand a lane's prepared step to the scalar constraint solver.
    pub(crate) fn set_segment_solver(&mut self, i: usize, motion: Twists, articulated: (Twists, Matrix3<f64>, Vector3<f64>)) {
        self.motion[i] = motion;
        self.articulated[i] = articulated;
    }

    /// Total energy (kinetic + gravitational + elastic), J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_energy + self.gravity_energy + self.elastic_energy
    }

    /// Evaluates energies and generalized forces at `state` (and the mass matrix if `with_mass`),
    /// with `external` point forces applied. See the module documentation for the pipeline.
    pub fn evaluate(&mut self, model: &StrandModel, state: &StrandState, external: &[PointForce], with_mass: bool) {
        self.sweep(model, state, external, with_mass);
        if with_mass {
            self.assemble_mass(model);
        }
    }

    /// Steps 1, 2 (forces) and 4 of the pipeline: frames, energies, generalized forces and (if `with_sums`)
    /// the per-segment inertial sums and motion subspaces that the mass matrix and
    /// [`Dynamics::solve_articulated`] are built from.
    pub(crate) fn sweep(&mut self, model: &StrandModel, state: &StrandState, external: &[PointForce], with_sums: bool) {
        if model.dofs_per_segment() == 2 {
            self.sweep_points::<2>(model, state, external, with_sums);
        } else {
            self.sweep_points::<3>(model, state, external, with_sums);
        }
        self.sweep_forces(model, state);
    }

    /// Step 1 (root-to-tip sweep) for segments of `D` coordinates: frames, energies (but the elastic one) and
    /// the per-segment sums.
    fn sweep_points<const D: usize>(&mut self, model: &StrandModel, state: &StrandState, external: &[PointForce], with_mass: bool) {
        let n = model.segments;
        let l = model.segment_length();
        let origin = state.root.position;
        let rho_a = model.linear_density();
        let rot_inertia = model.rotary_inertia();
        let drag_rate = model.air_drag / rho_a;
        let g = model.gravity;
        let root = &state.root;
        let mut start = Motion {
            rot: root.rotation,
            x: Vector3::zeros(),
            v: root.velocity,
            a: root.acceleration,
            w: root.angular_velocity,
            alpha: root.angular_acceleration,
        };
        self.frames.clear();
        self.points.clear();
        let mut kinetic = 0.0;
        let mut gravity = 0.0;
        for i in 0..n {
            self.frames.push(Frame { rotation: start.rot, position: start.x + origin });
            let q = darboux(model, &state.q, i);
            let qdot = darboux(model, &state.qdot, i);
            let mut sums = SegmentSums {
                q_own: Vector3::zeros(),
                f_own: Twists::zeros(),
                m_own: Matrix3::zeros(),
                wrench: Vector6::zeros(),
                inertia: Inertia::zero(),
            };
            for &(sigma, weight) in &self.nodes {
                let pk = point_kinematics::<D>(&start, &q, &qdot, sigma);
                let p = &pk.motion;
                self.points.push(p.x + origin);
                let m = rho_a * weight;
                // Rotary inertia `I_c = R diag(ic_local) R^T`, applied in the point's material frame.
                let ic_local = rot_inertia * weight;
                let w_l = p.rot.tr_mul(&p.w);
                let icw_l = ic_local.component_mul(&w_l);
                // Gravity, air drag and minus the velocity-product inertial force; torque about the point.
                let f = g * m - p.v * (drag_rate * m) - p.a * m;
                let tau_l = -icw_l * drag_rate - (ic_local.component_mul(&p.rot.tr_mul(&p.alpha)) + w_l.cross(&icw_l));
                let tau = p.rot * tau_l;
                let q_own = pk.u_cols.tr_mul(&f) + pk.w_cols.tr_mul(&tau);
                for k in 0..D {
                    sums.q_own[k] += q_own[k];
                }
                sums.wrench += wrench(&f, &tau, &p.x);
                kinetic += 0.5 * (m * p.v.norm_squared() + w_l.dot(&icw_l));
                gravity -= m * g.dot(&(p.x + origin));
                if with_mass {
                    // The own columns in the material frame (rotary part) for a symmetric own block.
                    let w_local = p.rot.tr_mul(&pk.w_cols);
                    for a in 0..D {
                        let wa = w_local.column(a);
                        let icwa = ic_local.component_mul(&wa);
                        let u = pk.u_cols.column(a) * m;
                        let ang = p.rot * icwa + p.x.cross(&u);
                        let mut col = sums.f_own.column_mut(a);
                        col[0] += ang.x;
                        col[1] += ang.y;
                        col[2] += ang.z;
                        col[3] += u.x;
                        col[4] += u.y;
                        col[5] += u.z;
                        for b in 0..=a {
                            let v = m * pk.u_cols.column(b).dot(&pk.u_cols.column(a)) + w_local.column(b).dot(&icwa);
                            sums.m_own[(b, a)] += v;
                            if b != a {
                                sums.m_own[(a, b)] += v;
                            }
                        }
                    }
                    sums.inertia.add_point(m, &p.rot, &ic_local, &p.x);
                }
            }
            for pf in external {
                let (j, sigma) = crate::kinematics::locate(model, pf.s);
                if j == i {
                    let pk = point_kinematics::<D>(&start, &q, &qdot, sigma);
                    let q_own = pk.u_cols.tr_mul(&pf.force) + pk.w_cols.tr_mul(&pf.torque);
                    for k in 0..D {
                        sums.q_own[k] += q_own[k];
                    }
                    sums.wrench += wrench(&pf.force, &pf.torque, &pk.motion.x);
                }
            }
            let end = point_kinematics::<D>(&start, &q, &qdot, l);
            // The reduced model has no third coordinate: its column stays zero.
            self.motion[i] = twists_at(&end.w_cols, &end.u_cols, &end.motion.x);
            self.sums[i] = sums;
            start = end.motion;
        }
        self.frames.push(Frame { rotation: start.rot, position: start.x + origin });
        self.kinetic_energy = kinetic;
        self.gravity_energy = gravity;
    }

    /// Steps 2 (forces) and 4 of the pipeline from the sums of [`Dynamics::sweep_points`].
    fn sweep_forces(&mut self, model: &StrandModel, state: &StrandState) {
        let d = model.dofs_per_segment();
        let n = model.segments;
        let l = model.segment_length();
        // Step 2 (forces): tip-to-root sweep with the suffix sum of the wrenches.
        let mut suffix_wrench = Vector6::zeros();
        for i in (0..n).rev() {
            let sums = &self.sums[i];
            let q_block = sums.q_own + self.motion[i].tr_mul(&suffix_wrench);
            for k in 0..d {
                self.forces[i * d + k] = q_block[k];
            }
            suffix_wrench += sums.wrench;
        }
        // Step 4: elasticity and internal damping (K diagonal).
        let rig = model.rigidities() * l;
        self.elastic_energy = 0.0;
        for i in 0..n {
            for k in 0..d {
                let j = i * d + k;
                let dq = state.q[j] - model.rest[i][k];
                self.elastic_energy += 0.5 * rig[k] * dq * dq;
                self.forces[j] -= rig[k] * (dq + model.damping * state.qdot[j]);
            }
        }
    }

    /// The diagonal geometric stiffness of point loads `loads` (arc length from the root, m; force on the strand,
    /// N) held fixed in space, at the state of the last [`Dynamics::sweep`] with sums, into
    /// [`Dynamics::geometric`]: the Gershgorin bound of the loads' Hessian `H = -sum f . d2x/dq2` (N m^3 per
    /// (rad/m)^2), each coordinate's row summed in magnitude, `K_g[a] = sum_b |H_ab|`, with `d2x / dq_a dq_b =
    /// w_a x (w_b x x + v_b)` for the twists `(w, v)` of the coordinates (`a` the inner one; the part of the strand
    /// beyond a coordinate's segment turning rigidly with the segment's end). `K_g - H` is then positive
    /// semidefinite: the linearly implicit step adds `h^2` times it to its matrix, as it does the elastic `K`, and
    /// takes every mode of the loads' stiffness implicitly, the couplings of a curled strand's twist and bends
    /// included (Andrews, Teichmann and Kry, "Geometric stiffness for real-time constrained multibody dynamics",
    /// Computer Graphics Forum 36(2), 2017, take a diagonal of the same stiffness). Without it, a contact's or
    /// tool's load on a curled strand whose twist is soft (wet hair: shear modulus x 0.1) is an explicit stiffness
    /// far above the elastic one on a coordinate of little inertia, and the step diverges; with the diagonal
    /// `|H_aa|` alone, a tooth's drag on a heavy wet wavy tress still did (docs/physics.md).
    ///
    /// `kept` (in [0, 1)) is the share of the previous value kept when it is above the new one: a load taken from
    /// the last step is explicit in a step where it appears or grows, and a contact that comes and goes from one
    /// step to the next (a wet fibre chattering on a neighbour near the root) would be implicit in every other
    /// step only; the previous steps' stiffness fading by `kept` a step covers it
    /// ([`crate::integrator::GEOMETRIC_STIFFNESS_MEMORY`]). 0: the last step's loads alone. A coordinate's value
    /// that has faded below a hundredth of its elastic stiffness is dropped (zero).
    pub fn geometric_stiffness(&mut self, model: &StrandModel, state: &StrandState, loads: &[(f64, Vector3<f64>)], kept: f64) {
        if kept > 0.0 {
            let d = model.dofs_per_segment();
            let rig = model.rigidities() * model.segment_length();
            for (j, g) in self.geometric.iter_mut().enumerate() {
                *g *= kept;
                if *g < 1e-2 * rig[j % d] {
                    *g = 0.0;
                }
            }
        } else {
            self.geometric.fill(0.0);
        }
        if loads.is_empty() || self.frames.len() != model.segments + 1 {
            return;
        }
        let d = model.dofs_per_segment();
        let dofs = self.geometric.len();
        let GeometricWorkspace { mut twists, mut moved, mut bound } = std::mem::take(&mut self.geometric_work);
        bound.clear();
        bound.resize(dofs, 0.0);
        // Each coordinate's twist `(w_j, v_j)` (the sweep's motion subspaces), taken once for all loads.
        twists.clear();
        twists.extend((0..model.segments * d).map(|j| {
            let col = self.motion[j / d].column(j % d);
            (Vector3::new(col[0], col[1], col[2]), Vector3::new(col[3], col[4], col[5]))
        }));
        // A load that is not finite cannot be linearized (the step that applied it has already been checked).
        for (s, f) in loads.iter().filter(|(s, f)| s.is_finite() && f.iter().all(|x| x.is_finite())) {
            let x = crate::kinematics::frame_at(model, &state.q, &self.frames, *s).position - state.root.position;
            let (seg, _) = crate::kinematics::locate(model, *s);
            // Each coordinate's row of the loads' second derivative, summed in magnitude: the coordinates up to
            // the load's segment, `a` the inner one of a pair, f . d2 x / dq_a dq_b = f . w_a x (w_b x x + v_b)
            // = (f x w_a) . u_b with u_b = v_b + w_b x x, the velocity coordinate b gives the load's point
            // (taken once per load). Each pair a < b is taken once for both rows (H is symmetric).
            let m = (seg.min(model.segments - 1) + 1) * d;
            moved.clear();
            moved.extend(twists[..m].iter().map(|(w, v)| v + w.cross(&x)));
            for a in 0..m {
                let g = f.cross(&twists[a].0);
                let mut row = g.dot(&moved[a]).abs();
                for (b, u) in moved.iter().enumerate().skip(a + 1) {
                    let h = g.dot(u).abs();
                    row += h;
                    bound[b] += h;
                }
                bound[a] += row;
            }
        }
        for (g, b) in self.geometric.iter_mut().zip(&bound) {
            *g = g.max(*b);
        }
        self.geometric_work = GeometricWorkspace { twists, moved, bound };
    }

    /// Jacobian `dr(s)/dq` (3 x 2N or 3 x 3N, m per (rad/m)) of the centreline point at arc length `s` and its
    /// position (world, m), at the state of the last [`Dynamics::sweep`] with sums: from that sweep's frames and
    /// motion subspaces, so only the point's own segment is evaluated. Equal to [`crate::kinematics::jacobian`].
    pub fn point_jacobian(&self, model: &StrandModel, state: &StrandState, s: f64) -> (Matrix3xX<f64>, Vector3<f64>) {
        let mut jac = Matrix3xX::zeros(model.dofs());
        let (x, _) = self.point_jacobian_into(model, state, s, jac.as_mut_slice());
        (jac, x)
    }

    /// [`Dynamics::point_jacobian`] written into `jac` (3 x dofs, column-major: 3 entries per column, at least
    /// `3 dofs` long). Returns the point's position (m) and the number of leading columns that can be nonzero
    /// (the dofs of the segments from the root to the point's own; the others are set to zero).
    pub fn point_jacobian_into(&self, model: &StrandModel, state: &StrandState, s: f64, jac: &mut [f64]) -> (Vector3<f64>, usize) {
        let d = model.dofs_per_segment();
        let origin = state.root.position;
        let (i, sigma) = crate::kinematics::locate(model, s);
        let (own, f) = own_twists(&self.frames[i], &darboux(model, &state.q, i), sigma, &origin);
        let x = f.position - origin;
        let span = (i + 1) * d;
        let mut put = |col: usize, v: Vector3<f64>| jac[3 * col..3 * col + 3].copy_from_slice(v.as_slice());
        for j in 0..i {
            for k in 0..d {
                put(j * d + k, point_velocity(&self.motion[j].column(k).into_owned(), &x));
            }
        }
        for k in 0..d {
            put(i * d + k, point_velocity(&own.column(k).into_owned(), &x));
        }
        jac[3 * span..3 * model.dofs()].fill(0.0);
        (f.position, span)
    }

    /// Gauss points of a segment: (arc length from the segment's start in m, weight in m); the positions in
    /// [`Dynamics::points`] follow this order within each segment.
    pub fn quadrature_nodes(&self) -> &[(f64, f64)] {
        &self.nodes
    }

    /// Steps 2 (mass) and 3 of the pipeline: the dense mass matrix from the sums of [`Dynamics::sweep`].
    fn assemble_mass(&mut self, model: &StrandModel) {
        let d = model.dofs_per_segment();
        let n = model.segments;
        let mut suffix_inertia = Inertia::zero();
        for i in (0..n).rev() {
            let s_i = self.motion[i];
            let sums = &self.sums[i];
            let mut couple = sums.f_own;
            for k in 0..d {
                let c = suffix_inertia.apply(&s_i.column(k).into_owned());
                couple.set_column(k, &(couple.column(k) + c));
            }
            let diag = sums.m_own + s_i.transpose() * (couple - sums.f_own);
            for a in 0..d {
                for b in 0..d {
                    self.mass[(i * d + a, i * d + b)] = diag[(a, b)];
                }
            }
            self.coupling[i] = couple;
            suffix_inertia.add(&sums.inertia);
        }
        // Step 3: off-diagonal blocks.
        for i in 0..n {
            for j in 0..i {
                let blk = self.motion[j].transpose() * self.coupling[i];
                for a in 0..d {
                    for b in 0..d {
                        self.mass[(j * d + a, i * d + b)] = blk[(a, b)];
                        self.mass[(i * d + b, j * d + a)] = blk[(a, b)];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod reference;

#[cfg(test)]
mod tests {
    use super::articulated::spd_inverse;
    use super::*;
    use crate::kinematics::{frame_at, jacobian, segment_frames};
    use crate::material::Material;
    use crate::model::ModelKind;
    use crate::section::CrossSection;
    use crate::state::RootFrame;

    #[test]
    fn spd_inverse_holds_over_diagonals_far_apart_and_refuses_indefinite_matrices() {
        // A family of SPD matrices L L^T + diag, every nonempty subset of the diagonal raised by 10^e for e in
        // 0..300 (the geometric stiffness of a huge load on a segment's coordinates): the inverse is found and
        // A A^-1 = 1 within 1e-9 relative on each entry scaled by its diagonals (the unscaled cofactors overflow
        // once two raised entries multiply past 1e308).
        // An indefinite matrix (a negative eigenvalue) and a non-finite one are refused at every scale.
        let l = Matrix3::new(1.0, 0.0, 0.0, 0.4, 0.8, 0.0, -0.3, 0.2, 0.5);
        let base = l * l.transpose();
        let mut worst = 0.0f64;
        for k in 1..8usize {
            for e in (0..=300).step_by(7) {
                let mut a = base;
                for i in (0..3).filter(|i| k & (1 << i) != 0) {
                    a[(i, i)] += 10f64.powi(e);
                }
                let inv = spd_inverse(&a).unwrap_or_else(|| panic!("refused: entries {k:03b} raised by 1e{e}"));
                let r = a * inv - Matrix3::identity();
                for i in 0..3 {
                    for j in 0..3 {
                        worst = worst.max((r[(i, j)] * (a[(j, j)] / a[(i, i)]).sqrt()).abs());
                    }
                }
                let mut bad = a;
                bad[(0, 1)] = 2.0 * (a[(0, 0)] * a[(1, 1)]).sqrt();
                bad[(1, 0)] = bad[(0, 1)];
                assert!(spd_inverse(&bad).is_none(), "indefinite accepted: entries {k:03b} raised by 1e{e}");
                let mut nan = a;
                nan[(2, 2)] = f64::NAN;
                assert!(spd_inverse(&nan).is_none());
            }
        }
        println!("worst scaled residual {worst:.2e}");
        assert!(worst < 1e-9, "residual {worst}");
    }

    fn curly(kind: ModelKind) -> (StrandModel, StrandState) {
        let mut m = StrandModel::new(kind, 0.1, 5, CrossSection::new(45e-6, 33e-6).unwrap(), Material::default()).unwrap();
        m.quadrature_points = 6;
        let root = RootFrame::new(Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.3, 0.1, -1.0), Vector3::y()).unwrap();
        let mut st = StrandState::at_rest(&m, root);
        for i in 0..m.dofs() {
            st.q[i] = 25.0 * ((i as f64) * 1.3).sin() + 4.0;
            st.qdot[i] = 40.0 * ((i as f64) * 0.7).cos();
        }
        (m, st)
    }

    #[test]
    fn fast_sweep_gives_the_old_step() {
        // The fixed-size sweep (const-generic D, closed-form matrices) against the old dynamic-size one kept
        // in dynamics/reference.rs: forces, energies and the solved velocity change agree to 1e-12 relative
        // (round-off only), with a point force and a moving root, both models.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, mut st) = curly(kind);
            st.root.velocity = Vector3::new(0.1, -0.2, 0.05);
            st.root.angular_velocity = Vector3::new(1.0, 0.5, -2.0);
            st.root.acceleration = Vector3::new(-0.3, 0.2, 1.0);
            let pf = [PointForce { s: 0.043, force: Vector3::new(1e-4, -2e-4, 5e-5), torque: Vector3::new(1e-9, 3e-9, -2e-9) }];
            let mut fast = Dynamics::new(&m);
            let mut old = Dynamics::new(&m);
            fast.sweep(&m, &st, &pf, true);
            old.sweep_reference(&m, &st, &pf, true);
            let close = |a: &DVector<f64>, b: &DVector<f64>| (a - b).norm() <= 1e-12 * b.norm();
            assert!(close(&fast.forces, &old.forces), "{kind:?}: forces {} vs {}", fast.forces, old.forces);
            assert!((fast.kinetic_energy - old.kinetic_energy).abs() <= 1e-12 * old.kinetic_energy);
            assert!((fast.gravity_energy - old.gravity_energy).abs() <= 1e-12 * old.gravity_energy.abs());
            assert!((fast.elastic_energy - old.elastic_energy).abs() <= 1e-12 * old.elastic_energy);
            let b = DVector::from_fn(m.dofs(), |i, _| 1e-6 * (i as f64 * 0.9).sin());
            let (mut xf, mut xo) = (b.clone(), b.clone());
            assert!(fast.solve_articulated(&m, 1.01, 2e-6, 0.0, &mut xf));
            assert!(old.solve_articulated(&m, 1.01, 2e-6, 0.0, &mut xo));
            assert!(close(&xf, &xo), "{kind:?}: solve {} vs {}", xf, xo);
            fast.evaluate(&m, &st, &pf, true);
            old.sweep_reference(&m, &st, &pf, true);
            old.assemble_mass(&m);
            assert!((&fast.mass - &old.mass).norm() <= 1e-12 * old.mass.norm(), "{kind:?}: mass matrix");
        }
    }

    #[test]
    fn the_geometric_stiffness_bounds_the_loads_hessian() {
        // The loads' potential V(q) = -sum f . x(s) has the Hessian H (central differences of the kinematic
        // Jacobian, step 1e-6 1/m); the diagonal K_g bounds each row of it, K_g[a] >= sum_b |H_ab| (Gershgorin: K_g
        // - H is positive semidefinite, so the implicit K_g damps every mode the loads' stiffness can drive), to
        // 1e-6 relative; and it is not loose by more than the row's count of terms.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            let mut dy = Dynamics::new(&m);
            dy.sweep(&m, &st, &[], true);
            let loads = [(0.043, Vector3::new(1e-3, -2e-3, 5e-4)), (0.1, Vector3::new(-2e-3, 1e-3, 3e-3)), (0.02, Vector3::new(0.0, 4e-3, -1e-3))];
            dy.geometric_stiffness(&m, &st, &loads, 0.0);
            let n = m.dofs();
            let eps = 1e-6;
            let grad = |q: &DVector<f64>| {
                let mut at = st.clone();
                at.q.copy_from(q);
                let mut g = DVector::zeros(n);
                for (s, f) in &loads {
                    let j = jacobian(&m, &at, *s);
                    g -= j.transpose() * f;
                }
                g
            };
            let mut rows = DVector::<f64>::zeros(n);
            for a in 0..n {
                let (mut qp, mut qm) = (st.q.clone(), st.q.clone());
                qp[a] += eps;
                qm[a] -= eps;
                let column = (grad(&qp) - grad(&qm)) / (2.0 * eps);
                for b in 0..n {
                    rows[b] += column[b].abs();
                }
            }
            for a in 0..n {
                assert!(dy.geometric[a] >= rows[a] * (1.0 - 1e-6) - 1e-12, "{kind:?} coordinate {a}: {} < {}", dy.geometric[a], rows[a]);
                assert!(dy.geometric[a] <= n as f64 * rows[a].max(1e-12), "{kind:?} coordinate {a}: {} vs {}", dy.geometric[a], rows[a]);
            }
        }
    }

    #[test]
    fn sweep_jacobian_equals_the_kinematic_one() {
        // point_jacobian (motion subspaces of the sweep) and kinematics::jacobian (frames recomputed): 1e-12.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            let mut dy = Dynamics::new(&m);
            dy.sweep(&m, &st, &[], true);
            for s in [0.0, 0.013, 0.05, 0.0799, 0.1] {
                let (j, x) = dy.point_jacobian(&m, &st, s);
                let reference = jacobian(&m, &st, s);
                assert!((&j - &reference).norm() <= 1e-12 * reference.norm().max(1e-12), "{kind:?} s={s}");
                assert!((x - frame_at(&m, &st.q, &segment_frames(&m, &st), s).position).norm() < 1e-15);
            }
        }
    }

    #[test]
    fn resolving_reuses_the_elimination_exactly() {
        // A second right-hand side solved by resolve_articulated equals a fresh solve_articulated (1e-12).
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            let mut dy = Dynamics::new(&m);
            dy.sweep(&m, &st, &[], true);
            let n = m.dofs();
            let mut b1 = DVector::from_fn(n, |i, _| (i as f64 * 0.9).sin());
            assert!(dy.solve_articulated(&m, 1.3, 2e-6, 0.0, &mut b1));
            let b2 = DVector::from_fn(n, |i, _| (i as f64 * 0.4).cos() * 1e-3);
            let mut fresh = b2.clone();
            assert!(dy.solve_articulated(&m, 1.3, 2e-6, 0.0, &mut fresh));
            let mut b1 = DVector::from_fn(n, |i, _| (i as f64 * 0.9).sin());
            assert!(dy.solve_articulated(&m, 1.3, 2e-6, 0.0, &mut b1));
            let mut again = b2.clone();
            assert!(dy.resolve_articulated1(&m, again.as_mut_slice()));
            assert!((&again - &fresh).norm() <= 1e-12 * fresh.norm(), "{kind:?}");
        }
    }

    #[test]
    fn reduced_right_hand_sides_give_the_delassus_blocks_of_the_dense_matrix() {
        // W_12 = J_1 A^-1 J_2^T from the tip-to-root half alone (sum_m c1[m] e2[m]^T over the columns both points
        // have) against the dense A = scale M + stiffness K solved by LU, for points in the same segment, in
        // different segments and at the root: equal to 1e-9 of the largest block entry (round-off of the two
        // factorizations of a matrix whose condition number reaches 1e6).
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            let mut dy = Dynamics::new(&m);
            dy.evaluate(&m, &st, &[], true);
            let (scale, stiffness) = (1.3, 2e-6);
            let n = m.dofs();
            let d = m.dofs_per_segment();
            let mut b = DVector::from_fn(n, |i, _| (i as f64 * 0.9).sin());
            assert!(dy.solve_articulated(&m, scale, stiffness, 0.0, &mut b));
            let rig = m.rigidities() * (m.segment_length() * stiffness);
            let mut a = &dy.mass * scale;
            for j in 0..n {
                a[(j, j)] += rig[j % d];
            }
            let lu = a.lu();
            let points = [0.0, 0.003, 0.013, 0.014, 0.05, 0.0799, 0.1];
            let reduced: Vec<(Matrix3xX<f64>, Vec<f64>, Vec<f64>, usize)> = points
                .iter()
                .map(|&s| {
                    let (j, _) = dy.point_jacobian(&m, &st, s);
                    let (_, span) = dy.point_jacobian_into(&m, &st, s, &mut vec![0.0; 3 * n]);
                    let (mut c, mut e) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
                    assert!(dy.reduce_articulated3(&m, j.as_slice(), span / d, &mut c, &mut e));
                    (j, c, e, span)
                })
                .collect();
            for (j1, c1, _, span1) in &reduced {
                for (j2, _, e2, span2) in &reduced {
                    let dense = j1 * lu.solve(&j2.transpose()).expect("A is invertible");
                    let mut w = Matrix3::zeros();
                    for (cm, em) in c1[..3 * span1.min(span2)].chunks_exact(3).zip(e2.chunks_exact(3)) {
                        w += Vector3::new(cm[0], cm[1], cm[2]) * nalgebra::RowVector3::new(em[0], em[1], em[2]);
                    }
                    let err = (w - &dense).amax();
                    assert!(err <= 1e-9 * dense.amax().max(1e-300), "{kind:?}: {err} of {}", dense.amax());
                }
            }
            // The response to impulses at every point, A^-1 sum_c J_c^T p_c, from the reduced columns summed and
            // one back-substitution: equal to the dense solve to 1e-9 of its largest entry.
            let impulses: Vec<Vector3<f64>> = (0..points.len()).map(|c| Vector3::new(1.0 + c as f64, -0.5 * c as f64, 0.3)).collect();
            let mut summed = vec![0.0; n];
            let mut load = DVector::zeros(n);
            for ((j, c, _, span), p) in reduced.iter().zip(&impulses) {
                for (m, l) in c[..3 * span].chunks_exact(3).enumerate() {
                    summed[m] += l[0] * p.x + l[1] * p.y + l[2] * p.z;
                }
                load += j.transpose() * p;
            }
            assert!(dy.back_substitute1(&m, &mut summed));
            let dense = lu.solve(&load).expect("A is invertible");
            let err = (DVector::from_vec(summed) - &dense).amax();
            assert!(err <= 1e-9 * dense.amax(), "{kind:?}: response {err} of {}", dense.amax());
        }
    }

    /// Mass matrix by brute force: sum over a fine rule of rho A J^T J (translation only) with the
    /// finite-difference-checked Jacobian of kinematics.rs, plus rotary inertia from finite differences.
    fn brute_mass(m: &StrandModel, st: &StrandState, points: usize) -> DMatrix<f64> {
        let n = m.dofs();
        let mut mass = DMatrix::zeros(n, n);
        let ds = m.length / points as f64;
        for p in 0..points {
            let s = (p as f64 + 0.5) * ds;
            let jac = jacobian(m, st, s);
            mass += jac.transpose() * &jac * (m.linear_density() * ds);
        }
        mass
    }

    #[test]
    fn mass_matrix_matches_brute_force_integral() {
        // The translational part dominates; rotary inertia of a 90 um fibre adds ~1e-9 relative.
        // Midpoint rule with 4000 points vs 6 Gauss points per segment: agreement to 1e-6 relative.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (m, st) = curly(kind);
            let mut dynamics = Dynamics::new(&m);
            dynamics.evaluate(&m, &st, &[], true);
            let brute = brute_mass(&m, &st, 4000);
            let err = (&dynamics.mass - &brute).norm() / brute.norm();
            assert!(err < 1e-6, "{kind:?}: relative error {err}");
            assert!((&dynamics.mass - dynamics.mass.transpose()).norm() < 1e-14 * brute.norm());
        }
    }

    #[test]
    fn kinetic_energy_is_quadratic_form_of_mass() {
        // With a fixed root, T = qdot^T M qdot / 2 exactly (same quadrature): 1e-12 relative.
        let (m, st) = curly(ModelKind::Full);
        let mut dynamics = Dynamics::new(&m);
        dynamics.evaluate(&m, &st, &[], true);
        let t = 0.5 * st.qdot.dot(&(&dynamics.mass * &st.qdot));
        assert!((t - dynamics.kinetic_energy).abs() < 1e-12 * t, "{t} vs {}", dynamics.kinetic_energy);
    }

    #[test]
    fn static_forces_are_minus_the_energy_gradient() {
        // At rest, forces = -d(U + V_g)/dq; central differences with step 1e-5 agree to 1e-7 relative.
        let (mut m, mut st) = curly(ModelKind::Reduced);
        m.rest = (0..m.segments).map(|i| Vector3::new(3.0, 10.0 - i as f64, 0.0)).collect();
        st.qdot.fill(0.0);
        let mut dynamics = Dynamics::new(&m);
        dynamics.evaluate(&m, &st, &[], false);
        let forces = dynamics.forces.clone();
        for j in 0..m.dofs() {
            let h = 1e-5;
            let mut energy = |dq: f64| {
                let mut s = st.clone();
                s.q[j] += dq;
                dynamics.evaluate(&m, &s, &[], false);
                dynamics.gravity_energy + dynamics.elastic_energy
            };
            let grad = (energy(h) - energy(-h)) / (2.0 * h);
            assert!((forces[j] + grad).abs() < 1e-7 * (forces.amax() + grad.abs()), "j={j}: {} vs {}", forces[j], -grad);
        }
    }

    #[test]
    fn velocity_product_terms_match_the_lagrangian() {
        // With no gravity, drag, damping or elastic force, forces = -C with
        // C = (dM/dt) qdot - d(qdot^T M qdot / 2)/dq; both derivatives by central differences (step 1e-6),
        // agreement to 1e-6 relative.
        for kind in [ModelKind::Reduced, ModelKind::Full] {
            let (mut m, st) = curly(kind);
            m.gravity = Vector3::zeros();
            m.air_drag = 0.0;
            m.damping = 0.0;
            m.set_rest_coordinates(&st.q);
            let mut dynamics = Dynamics::new(&m);
            dynamics.evaluate(&m, &st, &[], true);
            let forces = dynamics.forces.clone();
            let mut mass_at = |q: &DVector<f64>| {
                let mut s = st.clone();
                s.q = q.clone();
                dynamics.evaluate(&m, &s, &[], true);
                dynamics.mass.clone()
            };
            let h = 1e-6;
            let mdot = (mass_at(&(&st.q + &st.qdot * h)) - mass_at(&(&st.q - &st.qdot * h))) / (2.0 * h);
            let mut c = &mdot * &st.qdot;
            for j in 0..m.dofs() {
                let mut qp = st.q.clone();
                let mut qm = st.q.clone();
                qp[j] += h;
                qm[j] -= h;
                let tp = 0.5 * st.qdot.dot(&(mass_at(&qp) * &st.qdot));
                let tm = 0.5 * st.qdot.dot(&(mass_at(&qm) * &st.qdot));
                c[j] -= (tp - tm) / (2.0 * h);
            }
            let err = (&forces + &c).norm() / c.norm();
            assert!(err < 1e-6, "{kind:?}: relative error {err}");
        }
    }

    #[test]
    fn point_force_maps_through_the_jacobian_transpose() {
        // Generalized force of a point force equals J(s)^T f: 1e-12 relative.
        let (m, st) = weightless_at_rest();
        let mut dynamics = Dynamics::new(&m);
        let pf = PointForce::new(0.073, Vector3::new(1e-3, -2e-3, 5e-4));
        dynamics.evaluate(&m, &st, &[pf], false);
        let expected = jacobian(&m, &st, pf.s).transpose() * pf.force;
        assert!((&dynamics.forces - &expected).norm() < 1e-12 * expected.norm());
    }

    /// The curly full-model strand at its rest shape and at rest, without gravity or air drag.
    fn weightless_at_rest() -> (StrandModel, StrandState) {
        let (mut m, mut st) = curly(ModelKind::Full);
        m.gravity = Vector3::zeros();
        m.air_drag = 0.0;
        st.qdot.fill(0.0);
        st.q = m.rest_coordinates();
        (m, st)
    }

    #[test]
    fn point_torque_maps_through_the_angular_jacobian() {
        // The generalized force of a torque tau on the section at s is tau . d(theta)/dq, the rotation of the
        // section per unit coordinate, here by central differences of the frame (step 1e-6): 1e-7 relative.
        let (m, st) = weightless_at_rest();
        let mut dynamics = Dynamics::new(&m);
        let pf = PointForce { s: 0.061, force: Vector3::zeros(), torque: Vector3::new(2e-9, -1e-9, 3e-9) };
        dynamics.evaluate(&m, &st, &[pf], false);
        let r0 = frame_at(&m, &st.q, &segment_frames(&m, &st), pf.s).rotation;
        for j in 0..m.dofs() {
            let h = 1e-6;
            let rot = |dq: f64| {
                let mut t = st.clone();
                t.q[j] += dq;
                frame_at(&m, &t.q, &segment_frames(&m, &t), pf.s).rotation
            };
            let w = (rot(h) - rot(-h)) / (2.0 * h) * r0.transpose();
            let dtheta = Vector3::new(w[(2, 1)] - w[(1, 2)], w[(0, 2)] - w[(2, 0)], w[(1, 0)] - w[(0, 1)]) * 0.5;
            let expected = pf.torque.dot(&dtheta);
            assert!((dynamics.forces[j] - expected).abs() < 1e-7 * pf.torque.norm() * (1.0 + dtheta.norm()), "j={j}: {} vs {expected}", dynamics.forces[j]);
        }
    }
}
