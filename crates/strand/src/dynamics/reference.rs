//! The dynamics sweep as it was before the fixed-size fast path (dynamic-size, dual-number kinematics), kept
//! verbatim as a test reference: the fast path must give the same step to 1e-12.

use super::*;
use crate::helix::{coefficient_derivatives, coefficients, SegmentPoint};
use nalgebra::Matrix3;

struct PointKinematics {
    motion: Motion,
    w_cols: Matrix3<f64>,
    u_cols: Matrix3<f64>,
}

fn segment_kinematics(omega: &Vector3<f64>, rate: &Vector3<f64>, sigma: f64) -> SegmentPoint {
    use num_dual::Dual64;
    let phi = omega * sigma;
    let phi_dot = rate * sigma;
    let nu = rate;
    let u = phi.norm_squared();
    let pn = phi.dot(nu);
    let u_dot = 2.0 * sigma * pn;
    let ud = Dual64::new(u, u_dot);
    let (a, b, c) = coefficients(ud);
    let (db, dc) = coefficient_derivatives(ud);
    let (a, b_dot, b) = (a.re, b.eps, b.re);
    let (c_dot, c) = (c.eps, c.re);
    let (db_dot, db) = (db.eps, db.re);
    let (dc_dot, dc) = (dc.eps, dc.re);
    let k = phi.cross_matrix();
    let k2 = k * k;
    let e0 = Vector3::x();
    let pe = phi.cross(&e0);
    let ppe = phi.cross(&pe);
    let rotation = Matrix3::identity() + k * a + k2 * b;
    let offset = (e0 + pe * b + ppe * c) * sigma;
    let angular = (Matrix3::identity() + k * b + k2 * c) * sigma;
    let e0x = e0.cross_matrix();
    let linear = ((pe * phi.transpose()) * (2.0 * db) - e0x * b + (ppe * phi.transpose()) * (2.0 * dc)
        - (pe.cross_matrix() + k * e0x) * c)
        * (sigma * sigma);
    let pnu = phi.cross(nu);
    let angular_bias = (pnu * b_dot + phi.cross(&pnu) * c_dot + nu.cross(&pnu) * (c * sigma)) * sigma;
    let p_dot = sigma * nu.norm_squared();
    let nue = nu.cross(&e0);
    let linear_bias = (pe * (2.0 * (db_dot * pn + db * p_dot))
        + phi_dot.cross(&e0) * (2.0 * db * pn)
        + nue * b_dot
        + ppe * (2.0 * (dc_dot * pn + dc * p_dot))
        + (phi_dot.cross(&pe) + phi.cross(&phi_dot.cross(&e0))) * (2.0 * dc * pn)
        + (nu.cross(&pe) + phi.cross(&nue)) * c_dot
        + nu.cross(&nue) * (2.0 * c * sigma))
        * (sigma * sigma);
    SegmentPoint { rotation, offset, angular, linear, angular_bias, linear_bias }
}

fn point_kinematics(start: &Motion, q: &Vector3<f64>, qdot: &Vector3<f64>, sigma: f64) -> PointKinematics {
    let sp = segment_kinematics(q, qdot, sigma);
    let r = start.rot * sp.offset;
    let w_loc = start.rot * (sp.angular * qdot);
    let v_loc = start.rot * (sp.linear * qdot);
    let motion = Motion {
        rot: start.rot * sp.rotation,
        x: start.x + r,
        v: start.v + start.w.cross(&r) + v_loc,
        a: start.a + start.alpha.cross(&r) + start.w.cross(&start.w.cross(&r)) + start.w.cross(&v_loc) * 2.0 + start.rot * sp.linear_bias,
        w: start.w + w_loc,
        alpha: start.alpha + start.w.cross(&w_loc) + start.rot * sp.angular_bias,
    };
    PointKinematics { motion, w_cols: start.rot * sp.angular, u_cols: start.rot * sp.linear }
}

fn twists_at(w_cols: &Matrix3<f64>, u_cols: &Matrix3<f64>, x: &Vector3<f64>) -> Twists {
    let mut t = Twists::zeros();
    for k in 0..3 {
        let w = w_cols.column(k).into_owned();
        let v = u_cols.column(k) - w.cross(x);
        t.fixed_view_mut::<3, 1>(0, k).copy_from(&w);
        t.fixed_view_mut::<3, 1>(3, k).copy_from(&v);
    }
    t
}

impl Dynamics {
    pub(super) fn sweep_reference(&mut self, model: &StrandModel, state: &StrandState, external: &[PointForce], with_sums: bool) {
        let with_mass = with_sums;
        let d = model.dofs_per_segment();
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
        self.kinetic_energy = 0.0;
        self.gravity_energy = 0.0;

        // Step 1: root-to-tip sweep.
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
                let pk = point_kinematics(&start, &q, &qdot, sigma);
                let p = &pk.motion;
                let m = rho_a * weight;
                // Rotary inertia `I_c = R diag(ic_local) R^T`, applied in the point's material frame.
                let ic_local = rot_inertia * weight;
                let ic_apply = |v: &Vector3<f64>| p.rot * ic_local.component_mul(&p.rot.tr_mul(v));
                let icw = ic_apply(&p.w);
                // Gravity, air drag and minus the velocity-product inertial force; torque about the point.
                let f = g * m - p.v * (drag_rate * m) - p.a * m;
                let tau = -icw * drag_rate - (ic_apply(&p.alpha) + p.w.cross(&icw));
                sums.q_own += pk.u_cols.tr_mul(&f) + pk.w_cols.tr_mul(&tau);
                sums.wrench += wrench(&f, &tau, &p.x);
                self.kinetic_energy += 0.5 * (m * p.v.norm_squared() + p.w.dot(&icw));
                self.gravity_energy -= m * g.dot(&(p.x + origin));
                if with_mass {
                    // The own columns in the material frame (rotary part) for a symmetric own block.
                    let mut w_local = [Vector3::zeros(); 3];
                    for a in 0..d {
                        w_local[a] = p.rot.tr_mul(&pk.w_cols.column(a));
                        let u = pk.u_cols.column(a) * m;
                        let ang = p.rot * ic_local.component_mul(&w_local[a]) + p.x.cross(&u);
                        let mut col = sums.f_own.column_mut(a);
                        col[0] += ang.x;
                        col[1] += ang.y;
                        col[2] += ang.z;
                        col[3] += u.x;
                        col[4] += u.y;
                        col[5] += u.z;
                        for b in 0..=a {
                            let v = m * pk.u_cols.column(b).dot(&pk.u_cols.column(a))
                                + w_local[b].dot(&ic_local.component_mul(&w_local[a]));
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
                    let pk = point_kinematics(&start, &q, &qdot, sigma);
                    sums.q_own += pk.u_cols.transpose() * pf.force + pk.w_cols.transpose() * pf.torque;
                    sums.wrench += wrench(&pf.force, &pf.torque, &pk.motion.x);
                }
            }
            let end = point_kinematics(&start, &q, &qdot, l);
            self.motion[i] = twists_at(&end.w_cols, &end.u_cols, &end.motion.x);
            // The reduced model has no third coordinate: keep its column zero.
            self.motion[i].columns_mut(d, 3 - d).fill(0.0);
            self.sums[i] = sums;
            start = end.motion;
        }
        self.frames.push(Frame { rotation: start.rot, position: start.x + origin });

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
}
