//! Lagrangian dynamics of a strand: mass matrix, generalized forces and energies at one state.
//!
//! Pipeline of [`Dynamics::evaluate`] (all in world axes, spatial quantities about the root position):
//! 1. Forward pass with second-order dual numbers in time (`q + t qdot`, root pose to second order):
//!    segment frames, and at each Gauss point its position, velocity and velocity-product acceleration
//!    (the acceleration it would have with `qddot = 0`), its rotation, angular velocity and acceleration.
//! 2. Motion subspaces `S_Q` (spatial twists that unit `qdot_Q` gives to everything beyond segment Q) and
//!    each Gauss point's own twists `Psi` (closed-form derivatives of the helix, [`crate::helix`]).
//! 3. One sweep from tip to root accumulates composite spatial inertias and wrenches (suffix sums):
//!    `M[P,Q] = S_P^T (I^C_Q+1 S_Q + sum_k I_k Psi_k)` for `P < Q`, the diagonal blocks, and the generalized
//!    forces `Q_P = sum_k Psi_k^T w_k + S_P^T W_P+1`. Assembly is O(N^2) (O(N) for the forces).
//! 4. Elastic `-K (q - q_rest)` and internal damping `-tau K qdot` are added (K diagonal).
//!
//! The wrench `w_k` of a Gauss point gathers gravity `m g`, air drag `-nu w rdot` (and a matching rotary drag
//! `-(nu / rho A) I_c omega`), and minus the velocity-product inertial force (Coriolis and centrifugal terms,
//! including those from the root's motion). Each Gauss point carries its mass `rho A w` and the rotary inertia
//! of its slice of cross-section, so twisting a straight segment is not massless.

use crate::helix::segment_transform;
use crate::kinematics::{darboux, own_twists, Frame, Twists};
use crate::model::{gauss_legendre, StrandModel};
use crate::state::StrandState;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, SVector, Vector3};
use num_dual::Dual2_64;

type Jet = Dual2_64;
type Vector6 = SVector<f64, 6>;

/// A force applied to the centreline at arc length `s` (m from the root), in N (world axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointForce {
    /// Arc length from the root, m (clamped to [0, L]).
    pub s: f64,
    /// Force, N.
    pub force: Vector3<f64>,
}

/// What one evaluation knows about a Gauss point.
#[derive(Debug, Clone, Copy)]
struct Sample {
    /// Position relative to the root, m.
    x: Vector3<f64>,
    /// Velocity, m/s.
    v: Vector3<f64>,
    /// Velocity-product acceleration, m/s^2.
    a: Vector3<f64>,
    /// Material frame.
    rot: Matrix3<f64>,
    /// Angular velocity, rad/s.
    w: Vector3<f64>,
    /// Velocity-product angular acceleration, rad/s^2.
    alpha: Vector3<f64>,
}

/// Reusable workspace and results of a dynamics evaluation (allocated once per strand).
#[derive(Debug, Clone)]
pub struct Dynamics {
    /// Gauss points of a segment: (arc length from segment start in m, weight in m).
    nodes: Vec<(f64, f64)>,
    samples: Vec<Sample>,
    /// Segment start frames and the tip frame (N + 1), world coordinates.
    pub frames: Vec<Frame>,
    /// Motion subspace S_Q of each segment (twists about the root position).
    motion: Vec<Twists>,
    /// Coupling blocks F_Q = I^C_Q+1 S_Q + sum_k I_k Psi_k.
    coupling: Vec<Twists>,
    /// Mass matrix M(q), kg m^2 per (rad/m)^2 ... i.e. kinetic energy is `qdot^T M qdot / 2` in J.
    pub mass: DMatrix<f64>,
    /// All generalized forces at the evaluated state (elastic, damping, gravity, drag, point forces and minus
    /// the velocity-product terms), conjugate to q: N m^2 per ... so that `qdot^T forces` is a power in W.
    pub forces: DVector<f64>,
    /// Kinetic energy, J.
    pub kinetic_energy: f64,
    /// Gravitational potential energy `-sum m g . r` (world origin as reference), J.
    pub gravity_energy: f64,
    /// Elastic energy `(q - q_rest)^T K (q - q_rest) / 2`, J.
    pub elastic_energy: f64,
}

fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    0.5 * Vector3::new(m[(2, 1)] - m[(1, 2)], m[(0, 2)] - m[(2, 0)], m[(1, 0)] - m[(0, 1)])
}

fn spatial_inertia(m: f64, ic: &Matrix3<f64>, x: &Vector3<f64>) -> Matrix6<f64> {
    let xc = x.cross_matrix();
    let mut i6 = Matrix6::zeros();
    i6.fixed_view_mut::<3, 3>(0, 0).copy_from(&(ic - xc * xc * m));
    i6.fixed_view_mut::<3, 3>(0, 3).copy_from(&(xc * m));
    i6.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-xc * m));
    i6.fixed_view_mut::<3, 3>(3, 3).copy_from(&(Matrix3::identity() * m));
    i6
}

fn wrench(force: &Vector3<f64>, torque: &Vector3<f64>, x: &Vector3<f64>) -> Vector6 {
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
        Self {
            samples: Vec::with_capacity(n * nodes.len()),
            nodes,
            frames: Vec::with_capacity(n + 1),
            motion: vec![Twists::zeros(); n],
            coupling: vec![Twists::zeros(); n],
            mass: DMatrix::zeros(dofs, dofs),
            forces: DVector::zeros(dofs),
            kinetic_energy: 0.0,
            gravity_energy: 0.0,
            elastic_energy: 0.0,
        }
    }

    /// Total energy (kinetic + gravitational + elastic), J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_energy + self.gravity_energy + self.elastic_energy
    }

    /// Step 1: forward pass in second-order dual numbers (value, d/dt, d^2/dt^2 with qddot = 0).
    fn forward_pass(&mut self, model: &StrandModel, state: &StrandState) {
        let d = model.dofs_per_segment();
        let l = model.segment_length();
        let root = &state.root;
        let wx = root.angular_velocity.cross_matrix();
        let dr = wx * root.rotation;
        let ddr = (root.angular_acceleration.cross_matrix() + wx * wx) * root.rotation;
        let mut rot: Matrix3<Jet> = Matrix3::from_fn(|r, c| Jet::new(root.rotation[(r, c)], dr[(r, c)], ddr[(r, c)]));
        let mut pos: Vector3<Jet> = Vector3::from_fn(|r, _| Jet::new(0.0, root.velocity[r], root.acceleration[r]));
        self.samples.clear();
        self.frames.clear();
        let re_frame = |rot: &Matrix3<Jet>, pos: &Vector3<Jet>| Frame {
            rotation: rot.map(|x| x.re),
            position: pos.map(|x| x.re) + root.position,
        };
        for i in 0..model.segments {
            self.frames.push(re_frame(&rot, &pos));
            let omega: Vector3<Jet> = Vector3::from_fn(|k, _| {
                if k < d { Jet::new(state.q[i * d + k], state.qdot[i * d + k], 0.0) } else { Jet::from(0.0) }
            });
            for &(sigma, _) in &self.nodes {
                let (e, p) = segment_transform(&omega, sigma);
                let r = rot * e;
                let x = pos + rot * p;
                let (r0, r1, r2) = (r.map(|v| v.re), r.map(|v| v.v1), r.map(|v| v.v2));
                self.samples.push(Sample {
                    x: x.map(|v| v.re),
                    v: x.map(|v| v.v1),
                    a: x.map(|v| v.v2),
                    rot: r0,
                    w: vee(&(r1 * r0.transpose())),
                    alpha: vee(&(r2 * r0.transpose() + r1 * r1.transpose())),
                });
            }
            let (e, p) = segment_transform(&omega, l);
            pos += rot * p;
            rot *= e;
        }
        self.frames.push(re_frame(&rot, &pos));
    }

    /// Evaluates energies and generalized forces at `state` (and the mass matrix if `with_mass`),
    /// with `external` point forces applied. See the module documentation for the pipeline.
    pub fn evaluate(&mut self, model: &StrandModel, state: &StrandState, external: &[PointForce], with_mass: bool) {
        let d = model.dofs_per_segment();
        let n = model.segments;
        let l = model.segment_length();
        let origin = state.root.position;
        let rho_a = model.linear_density();
        let rot_inertia = model.rotary_inertia();
        let drag_rate = model.air_drag / rho_a;
        let g = model.gravity;

        self.forward_pass(model, state);
        self.forces.fill(0.0);
        if with_mass {
            self.mass.fill(0.0);
        }
        self.kinetic_energy = 0.0;
        self.gravity_energy = 0.0;

        // Step 3: sweep from the tip, with suffix sums of wrenches and composite inertias.
        let mut suffix_wrench = Vector6::zeros();
        let mut suffix_inertia = Matrix6::zeros();
        let nq = self.nodes.len();
        for i in (0..n).rev() {
            let start = self.frames[i];
            let omega = darboux(model, &state.q, i);
            let (s_i, _) = own_twists(&start, &omega, l, &origin);
            self.motion[i] = s_i;
            let mut q_block = s_i.transpose() * suffix_wrench;
            let mut couple = suffix_inertia * s_i;
            let mut diag = s_i.transpose() * couple;
            let mut seg_wrench = Vector6::zeros();
            let mut seg_inertia = Matrix6::zeros();
            for (g_idx, &(sigma, weight)) in self.nodes.iter().enumerate() {
                let smp = self.samples[i * nq + g_idx];
                let (psi, _) = own_twists(&start, &omega, sigma, &origin);
                let m = rho_a * weight;
                let ic = smp.rot * Matrix3::from_diagonal(&(rot_inertia * weight)) * smp.rot.transpose();
                let icw = ic * smp.w;
                // Gravity, air drag and minus the velocity-product inertial force.
                let f = g * m - smp.v * (drag_rate * m) - smp.a * m;
                let tau = -icw * drag_rate - (ic * smp.alpha + smp.w.cross(&icw));
                let wr = wrench(&f, &tau, &smp.x);
                q_block += psi.transpose() * wr;
                seg_wrench += wr;
                self.kinetic_energy += 0.5 * (m * smp.v.norm_squared() + smp.w.dot(&icw));
                self.gravity_energy -= m * g.dot(&(smp.x + origin));
                if with_mass {
                    let i6 = spatial_inertia(m, &ic, &smp.x);
                    let i_psi = i6 * psi;
                    couple += i_psi;
                    diag += psi.transpose() * i_psi;
                    seg_inertia += i6;
                }
            }
            for pf in external {
                let (j, sigma) = crate::kinematics::locate(model, pf.s);
                if j != i {
                    continue;
                }
                let (psi, f) = own_twists(&start, &omega, sigma, &origin);
                let wr = wrench(&pf.force, &Vector3::zeros(), &(f.position - origin));
                q_block += psi.transpose() * wr;
                seg_wrench += wr;
            }
            for k in 0..d {
                self.forces[i * d + k] = q_block[k];
            }
            suffix_wrench += seg_wrench;
            if with_mass {
                self.coupling[i] = couple;
                for a in 0..d {
                    for b in 0..d {
                        self.mass[(i * d + a, i * d + b)] = diag[(a, b)];
                    }
                }
                suffix_inertia += seg_inertia;
            }
        }
        if with_mass {
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
        // Step 4: elasticity and internal damping (K diagonal).
        let k = model.stiffness();
        let dq = &state.q - model.rest_coordinates();
        self.elastic_energy = 0.5 * dq.component_mul(&k).dot(&dq);
        for j in 0..model.dofs() {
            self.forces[j] -= k[j] * (dq[j] + model.damping * state.qdot[j]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{frame_at, jacobian, segment_frames};
    use crate::material::Material;
    use crate::model::ModelKind;
    use crate::section::CrossSection;
    use crate::state::RootFrame;

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
        let (mut m, mut st) = curly(ModelKind::Full);
        m.gravity = Vector3::zeros();
        m.air_drag = 0.0;
        st.qdot.fill(0.0);
        st.q = m.rest_coordinates();
        let mut dynamics = Dynamics::new(&m);
        let pf = PointForce { s: 0.073, force: Vector3::new(1e-3, -2e-3, 5e-4) };
        dynamics.evaluate(&m, &st, &[pf], false);
        let expected = jacobian(&m, &st, pf.s).transpose() * pf.force;
        assert!((&dynamics.forces - &expected).norm() < 1e-12 * expected.norm());
        let _ = frame_at(&m, &st.q, &segment_frames(&m, &st), 0.0);
    }
}
