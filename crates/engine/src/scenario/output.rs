//! What a scenario produces, in memory (the CLI writes it to files; the Python binding hands it over as
//! arrays): the force trace as columns, the summary of its kind, serde-serialisable.

use nalgebra::Vector3;
use serde::Serialize;

/// A force trace as columns, one entry per haptic step (the force on the hand, N; the torque, N m; the
/// contacts; the tool position, m). `force.csv` has these columns in this order.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ForceTrace {
    /// Time, s (from the start of the tool's path).
    pub t: Vec<f64>,
    /// Force x, N.
    pub fx: Vec<f64>,
    /// Force y, N.
    pub fy: Vec<f64>,
    /// Force z, N.
    pub fz: Vec<f64>,
    /// Torque x, N m.
    pub tx: Vec<f64>,
    /// Torque y, N m.
    pub ty: Vec<f64>,
    /// Torque z, N m.
    pub tz: Vec<f64>,
    /// Contacts in the step.
    pub contacts: Vec<u32>,
    /// Tool position x, m.
    pub tool_x: Vec<f64>,
    /// Tool position y, m.
    pub tool_y: Vec<f64>,
    /// Tool position z, m.
    pub tool_z: Vec<f64>,
}

impl ForceTrace {
    /// Appends one step.
    pub fn push(&mut self, t: f64, force: &Vector3<f64>, torque: &Vector3<f64>, contacts: u32, tool: &Vector3<f64>) {
        self.t.push(t);
        self.fx.push(force.x);
        self.fy.push(force.y);
        self.fz.push(force.z);
        self.tx.push(torque.x);
        self.ty.push(torque.y);
        self.tz.push(torque.z);
        self.contacts.push(contacts);
        self.tool_x.push(tool.x);
        self.tool_y.push(tool.y);
        self.tool_z.push(tool.z);
    }
    /// Steps.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// No step.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    /// Force of step `i`, N.
    pub fn force(&self, i: usize) -> Vector3<f64> {
        Vector3::new(self.fx[i], self.fy[i], self.fz[i])
    }
    /// The CSV text: header `t,fx,fy,fz,tx,ty,tz,contacts,tool_x,tool_y,tool_z`, one line per step.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(self.len() * 120 + 64);
        s.push_str("t,fx,fy,fz,tx,ty,tz,contacts,tool_x,tool_y,tool_z\n");
        for i in 0..self.len() {
            s.push_str(&format!(
                "{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{:.6e},{:.6e},{:.6e}\n",
                self.t[i], self.fx[i], self.fy[i], self.fz[i], self.tx[i], self.ty[i], self.tz[i], self.contacts[i], self.tool_x[i], self.tool_y[i], self.tool_z[i]
            ));
        }
        s
    }
}

/// Summary of a `[live]` scenario or a replayed record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LiveSummary {
    /// Haptic steps traced.
    pub steps: usize,
    /// Largest force sent to the device, N.
    pub peak_force_n: f64,
    /// Mean force magnitude over the steps with contact, N (0 without contact).
    pub mean_force_n: f64,
    /// Steps with at least one contact.
    pub contact_steps: usize,
    /// Steps at the device's force limit (|F| within 1e-9 relative of `max_force`).
    pub clamp_steps: usize,
    /// Largest distance of any guide point (as shown: lattice motion plus local strand motion) from its
    /// settled position over the run (measured at every global step and at the end), m.
    pub max_displacement_m: f64,
    /// The same at the last step, m.
    pub final_max_displacement_m: f64,
    /// The same over the stroke only (the measures while the tool is in the hair), m.
    pub stroke_max_displacement_m: f64,
    /// Steps with the tool in the hair (a capsule of the tool within `ContinuityParams::in_hair_distance` of a
    /// guide point's settled position).
    pub in_hair_steps: usize,
    /// Share of the in-hair steps with a force above `ContinuityParams::force_floor` (5 mN), in [0, 1]
    /// (0 without an in-hair step).
    pub in_hair_force_share: f64,
    /// Largest change of the force between two consecutive steps, N.
    pub max_force_change_n: f64,
    /// Fastest tip of a simulated strand over the run, m/s.
    pub max_strand_speed_m_s: f64,
    /// 99.9th percentile of the haptic step's wall time, microseconds (this machine, one thread).
    pub haptic_step_p999_us: f64,
    /// Mean haptic step wall time, microseconds.
    pub haptic_step_mean_us: f64,
    /// Rejected device readings.
    pub rejected_readings: u64,
    /// Strand steps that failed (state kept).
    pub failed_steps: u64,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
}

impl LiveSummary {
    pub(crate) fn new(trace: &ForceTrace, max_force: f64, meter: &super::live::Meter, timing: &mut [f64], rejected: u64, failed: u64, wall: f64) -> Self {
        let (mut peak, mut sum, mut contact, mut clamp) = (0.0f64, 0.0, 0usize, 0usize);
        let (mut in_hair, mut felt, mut change) = (0usize, 0usize, 0.0f64);
        for i in 0..trace.len() {
            let f = trace.force(i).norm();
            if meter.in_hair.get(i) == Some(&true) {
                in_hair += 1;
                felt += (f > meter.force_floor()) as usize;
            }
            if i > 0 {
                change = change.max((trace.force(i) - trace.force(i - 1)).norm());
            }
            peak = peak.max(f);
            if trace.contacts[i] > 0 {
                contact += 1;
                sum += f;
            }
            if f >= max_force * (1.0 - 1e-9) {
                clamp += 1;
            }
        }
        timing.sort_by(f64::total_cmp);
        let p999 = if timing.is_empty() { 0.0 } else { timing[((timing.len() as f64 * 0.999).ceil() as usize).clamp(1, timing.len()) - 1] };
        let mean = timing.iter().sum::<f64>() / timing.len().max(1) as f64;
        Self {
            steps: trace.len(),
            peak_force_n: peak,
            mean_force_n: if contact > 0 { sum / contact as f64 } else { 0.0 },
            contact_steps: contact,
            clamp_steps: clamp,
            max_displacement_m: meter.max,
            final_max_displacement_m: meter.last,
            stroke_max_displacement_m: meter.stroke_max,
            in_hair_steps: in_hair,
            in_hair_force_share: if in_hair > 0 { felt as f64 / in_hair as f64 } else { 0.0 },
            max_force_change_n: change,
            max_strand_speed_m_s: meter.max_tip_speed,
            haptic_step_p999_us: p999 * 1e6,
            haptic_step_mean_us: mean * 1e6,
            rejected_readings: rejected,
            failed_steps: failed,
            wall_time_s: wall,
        }
    }
}
