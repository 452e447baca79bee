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

/// Quality figures of a tool stroke's force, computed in one place for every scenario kind that has a force
/// trace ([`StrokeMetrics::of`]). The stroke is the steps from the first to the last step with a contact (the
/// tool in the hair); the force is the magnitude of the force on the tool, N.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct StrokeMetrics {
    /// Steps of the stroke (first to last step with contact, inclusive).
    pub steps: usize,
    /// Largest force during the stroke, N.
    pub peak_n: f64,
    /// Median force during the stroke, N.
    pub median_n: f64,
    /// 90th percentile of the force during the stroke, N.
    pub p90_n: f64,
    /// Share of the stroke's steps with a force above 2 % of the peak (dimensionless, 0..1): the force's
    /// continuity (1: felt all along; a stroke of isolated spikes gives a small share).
    pub continuity: f64,
    /// Largest change of the force vector from one step to the next during the stroke, N.
    pub max_step_change_n: f64,
    /// The same as a share of the peak (dimensionless).
    pub max_step_change_rel: f64,
}

impl StrokeMetrics {
    /// Share of the peak above which a step counts as felt in [`StrokeMetrics::continuity`].
    pub const FELT: f64 = 0.02;

    /// The figures of `trace`'s stroke (all zero if no step has a contact).
    pub fn of(trace: &ForceTrace) -> Self {
        let Some(first) = trace.contacts.iter().position(|&c| c > 0) else { return Self::default() };
        let last = trace.contacts.iter().rposition(|&c| c > 0).unwrap_or(first);
        let mut f: Vec<f64> = (first..=last).map(|i| trace.force(i).norm()).collect();
        let max_step_change_n = (first + 1..=last).map(|i| (trace.force(i) - trace.force(i - 1)).norm()).fold(0.0, f64::max);
        let peak_n = f.iter().copied().fold(0.0, f64::max);
        let felt = f.iter().filter(|&&x| x > Self::FELT * peak_n).count();
        let steps = f.len();
        f.sort_by(f64::total_cmp);
        // Nearest-rank percentiles.
        let rank = |q: f64| f[((q * steps as f64).ceil() as usize).clamp(1, steps) - 1];
        Self {
            steps,
            peak_n,
            median_n: rank(0.5),
            p90_n: rank(0.9),
            continuity: felt as f64 / steps as f64,
            max_step_change_n,
            max_step_change_rel: if peak_n > 0.0 { max_step_change_n / peak_n } else { 0.0 },
        }
    }
}

/// What a force trace gives its summary (patch and live scenarios alike): peak and mean force, steps with
/// contact, steps at the device's force limit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ForceStats {
    /// Largest force magnitude, N.
    pub peak: f64,
    /// Mean force magnitude over the steps with contact, N (0 without contact).
    pub mean_in_contact: f64,
    /// Steps with at least one contact.
    pub contact_steps: usize,
    /// Steps at the force limit (magnitude within 1e-9 relative of it).
    pub clamp_steps: usize,
}

impl ForceStats {
    /// From each step's force magnitude (N) and whether it had a contact; `max_force` is the device's force
    /// limit, N (`f64::INFINITY`: none).
    pub fn of(steps: impl IntoIterator<Item = (f64, bool)>, max_force: f64) -> Self {
        let (mut s, mut sum) = (Self::default(), 0.0);
        for (f, contact) in steps {
            s.peak = s.peak.max(f);
            if contact {
                s.contact_steps += 1;
                sum += f;
            }
            if f >= max_force * (1.0 - 1e-9) {
                s.clamp_steps += 1;
            }
        }
        s.mean_in_contact = if s.contact_steps > 0 { sum / s.contact_steps as f64 } else { 0.0 };
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
    /// The tool's path while in the hair (its proxy's, summed over the in-hair steps), m.
    pub in_hair_path_m: f64,
    /// The stroke's speed: the tool's (proxy's) mean speed over the in-hair steps in which it moves (faster than
    /// `ContinuityParams::moving_speed`, 0.01 m/s), m/s (0 if none). Issue 12's stroke is 0.1-0.2 m/s.
    pub in_hair_speed_m_s: f64,
    /// The stroke's steps: the in-hair steps in which the tool moves (as for `in_hair_speed_m_s`).
    pub stroke_steps: usize,
    /// Share of the stroke's steps with a force above `ContinuityParams::force_floor` (5 mN), in [0, 1] (0
    /// without one): `in_hair_force_share` without the steps in which the tool rests in the hair, where a still
    /// comb feels only the hair's static push (5-10 mN).
    pub stroke_force_share: f64,
    /// Largest change of the force between two consecutive steps, N.
    pub max_force_change_n: f64,
    /// Fastest tip of a simulated strand over the run, m/s.
    pub max_strand_speed_m_s: f64,
    /// The largest hand-over of a local strand to the global layer: its shown displacement from its place
    /// carried by the global layer when it left the simulation (carried over into the global layer as the guide's
    /// offset, which the hold brings back: `max_handover_change_m` is what the hair drawn moves), m; at most
    /// `HapticParams::handover_distance` (the strands let go before they were back in place are counted apart).
    pub max_handover_m: f64,
    /// Local strands let go back in place (handed over to the global layer) over the run.
    pub handovers: u64,
    /// The largest early hand-over: of a strand let go before it was back in place (after
    /// `HapticParams::max_relax_time`, or by the strand limit), wherever it was (not bounded; carried over as
    /// `max_handover_m` is), m, and how many such strands.
    pub max_early_handover_m: f64,
    pub early_handovers: u64,
    /// The largest change of any guide point drawn across a hand-over to the global layer (early ones included):
    /// a leaving strand's shown displacement from its carried place the step before it was let go against the step
    /// it was, m. The hand-over carries the displacement over into the global layer, which the hold then brings
    /// back (`HapticCore`'s handed-over guides), so this is one step of that motion.
    pub max_handover_change_m: f64,
    /// Deepest render vertex inside the head and body at any measure as the viewer shows it (every 25th
    /// strand sampled; the lattice's FFD, then the viewer's push-out), m; 0 if none.
    pub max_depth_in_body_m: f64,
    /// The same before the push-out (the lattice's FFD alone: 5 cm cells put vertices near the scalp a few
    /// millimetres inside even at rest), m.
    pub max_depth_before_push_out_m: f64,
    /// Median of the haptic step's wall time, microseconds (this machine, one thread).
    pub haptic_step_p50_us: f64,
    /// 99th percentile of the haptic step's wall time, microseconds.
    pub haptic_step_p99_us: f64,
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
    /// `dt`: the haptic step, s.
    pub(crate) fn new(trace: &ForceTrace, max_force: f64, dt: f64, meter: &super::meter::Meter, timing: &mut [f64], rejected: u64, failed: u64, wall: f64) -> Self {
        let stats = ForceStats::of((0..trace.len()).map(|i| (trace.force(i).norm(), trace.contacts[i] > 0)), max_force);
        // Continuity: the steps with the tool in the hair and their share above the force floor; the largest
        // change between consecutive steps over the whole run.
        let (mut in_hair, mut felt, mut change) = (0usize, 0usize, 0.0f64);
        let (mut moving, mut felt_moving) = (0usize, 0usize);
        for i in 0..trace.len() {
            let above = trace.force(i).norm() > meter.force_floor();
            if meter.in_hair.get(i) == Some(&true) {
                in_hair += 1;
                felt += above as usize;
            }
            if meter.moving.get(i) == Some(&true) {
                moving += 1;
                felt_moving += above as usize;
            }
            if i > 0 {
                change = change.max((trace.force(i) - trace.force(i - 1)).norm());
            }
        }
        timing.sort_by(f64::total_cmp);
        let pct = |q: f64| if timing.is_empty() { 0.0 } else { timing[((timing.len() as f64 * q).ceil() as usize).clamp(1, timing.len()) - 1] };
        let (p50, p99, p999) = (pct(0.5), pct(0.99), pct(0.999));
        let mean = timing.iter().sum::<f64>() / timing.len().max(1) as f64;
        Self {
            steps: trace.len(),
            peak_force_n: stats.peak,
            mean_force_n: stats.mean_in_contact,
            contact_steps: stats.contact_steps,
            clamp_steps: stats.clamp_steps,
            max_displacement_m: meter.max,
            final_max_displacement_m: meter.last,
            stroke_max_displacement_m: meter.stroke_max,
            in_hair_steps: in_hair,
            in_hair_force_share: if in_hair > 0 { felt as f64 / in_hair as f64 } else { 0.0 },
            in_hair_path_m: meter.in_hair_path,
            in_hair_speed_m_s: if moving > 0 { meter.moving_path / (moving as f64 * dt) } else { 0.0 },
            stroke_steps: moving,
            stroke_force_share: if moving > 0 { felt_moving as f64 / moving as f64 } else { 0.0 },
            max_force_change_n: change,
            max_strand_speed_m_s: meter.max_tip_speed,
            max_handover_m: meter.handover,
            handovers: meter.handovers,
            max_early_handover_m: meter.early_handover,
            early_handovers: meter.early_handovers,
            max_handover_change_m: meter.handover_change,
            max_depth_in_body_m: meter.max_depth,
            max_depth_before_push_out_m: meter.max_depth_raw,
            haptic_step_p50_us: p50 * 1e6,
            haptic_step_p99_us: p99 * 1e6,
            haptic_step_p999_us: p999 * 1e6,
            haptic_step_mean_us: mean * 1e6,
            rejected_readings: rejected,
            failed_steps: failed,
            wall_time_s: wall,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stroke_metrics_of_a_known_trace() {
        // 2 steps before the stroke and 1 after it without contact (ignored, however large), 10 stroke steps with
        // forces 1..10 N along x except the 5th at 0.1 N (1 % of the 10 N peak, not felt).
        // Stroke: 10 steps, peak 10 N, sorted forces 0.1, 1, 2, 3, 4, 6, 7, 8, 9, 10: median (rank 5) 4 N, p90
        // (rank 9) 9 N; continuity 9 / 10; largest step change |6 - 0.1| = 5.9 N.
        let mut t = ForceTrace::default();
        let z = Vector3::zeros();
        t.push(0.0, &Vector3::new(50.0, 0.0, 0.0), &z, 0, &z);
        t.push(0.001, &z, &z, 0, &z);
        for i in 1..=10 {
            let f = if i == 5 { 0.1 } else { i as f64 };
            t.push(0.001 * (i + 1) as f64, &Vector3::new(f, 0.0, 0.0), &z, 1, &z);
        }
        t.push(0.02, &Vector3::new(80.0, 0.0, 0.0), &z, 0, &z);
        let m = StrokeMetrics::of(&t);
        assert_eq!(m.steps, 10);
        assert_eq!(m.peak_n, 10.0);
        assert_eq!(m.median_n, 4.0);
        assert_eq!(m.p90_n, 9.0);
        assert!((m.continuity - 0.9).abs() < 1e-15);
        assert!((m.max_step_change_n - 5.9).abs() < 1e-12);
        assert!((m.max_step_change_rel - 0.59).abs() < 1e-12);
        assert_eq!(StrokeMetrics::of(&ForceTrace::default()), StrokeMetrics::default());
    }

    #[test]
    fn force_stats_of_a_short_trace() {
        // Peak 3.3 (at the limit, counted once), mean over the two contact steps (1 + 3.3) / 2.
        let s = ForceStats::of([(1.0, true), (0.5, false), (3.3, true)], 3.3);
        assert_eq!((s.peak, s.contact_steps, s.clamp_steps), (3.3, 2, 1));
        assert!((s.mean_in_contact - 2.15).abs() < 1e-15, "{s:?}");
        assert_eq!(ForceStats::of([(1.0, false)], f64::INFINITY).mean_in_contact, 0.0);
    }
}
