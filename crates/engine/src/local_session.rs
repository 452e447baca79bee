//! A live local session: a haptic device drives a tool through a patch of strands in the fixed-rate haptic
//! loop. Per step: device reading -> coupling (proxy pose, safe device force) -> local interaction step ->
//! the hair's reaction feeds the coupling at the next step.

use haptics::coupling::{Coupling, CouplingParams};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::haptic_loop::{HapticLoop, LoopStats};
use nalgebra::Vector3;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use tools::contact::ToolPose;
use tools::interaction::LocalInteraction;

/// Counters the session shares with other threads (atomics: readable at any time without locking).
#[derive(Debug, Default)]
pub struct SessionCounters {
    /// Device readings rejected (NaN, teleport).
    pub rejected_inputs: AtomicU64,
    /// Steps in which a strand step failed (its state was kept).
    pub failed_steps: AtomicU64,
    /// Steps with at least one contact.
    pub contact_steps: AtomicU64,
    /// Total wall time of the interaction steps' phases, ns (see [`tools::interaction::StepTimings`]): strand
    /// dynamics and unconstrained solves, centreline sampling and tree refit, contact detection, strands with
    /// contacts, strands without.
    pub phase_ns: [AtomicU64; 5],
    /// Total strands with contacts over all steps.
    pub touched_strands: AtomicU64,
    /// Largest force the hair exerted on the tool in one step (before the coupling limits what the device
    /// renders), as the bits of a non-negative f64 in N (`f64::from_bits`).
    pub peak_hair_force_bits: AtomicU64,
}

/// Starts the haptic loop at `rate_hz` with `device` driving the tool of `interaction`.
pub fn spawn_local_session<D: HapticDevice + 'static>(
    rate_hz: f64,
    device: D,
    profile: DeviceProfile,
    mut interaction: LocalInteraction,
    max_steps: Option<u64>,
) -> Result<(HapticLoop<D>, Arc<SessionCounters>), String> {
    let counters = Arc::new(SessionCounters::default());
    let shared = counters.clone();
    let mut coupling = Coupling::new(profile, CouplingParams::for_profile(&profile), interaction.pose.position);
    let mut hair = Vector3::zeros();
    let step = move |reading: Option<DeviceReading>, _t: f64, dt: f64| -> DeviceCommand {
        let Some(r) = reading else { return DeviceCommand::default() };
        let force = match coupling.update(&r, dt, &hair) {
            Ok(f) => f,
            Err(_) => {
                shared.rejected_inputs.fetch_add(1, Ordering::Relaxed);
                hair = Vector3::zeros();
                return DeviceCommand::default();
            }
        };
        let pose = ToolPose { position: coupling.proxy, rotation: r.rotation };
        match interaction.step(dt, pose) {
            Ok(res) => {
                hair = res.force;
                let t = &res.timings;
                for (slot, secs) in shared.phase_ns.iter().zip([t.dynamics, t.sample, t.detect, t.constrained, t.free]) {
                    slot.fetch_add((secs * 1e9) as u64, Ordering::Relaxed);
                }
                shared.touched_strands.fetch_add(t.touched_strands as u64, Ordering::Relaxed);
                // Non-negative floats order as their bit patterns.
                shared.peak_hair_force_bits.fetch_max(res.force.norm().to_bits(), Ordering::Relaxed);
                if !res.contacts.is_empty() {
                    shared.contact_steps.fetch_add(1, Ordering::Relaxed);
                }
            }
            Err(_) => {
                shared.failed_steps.fetch_add(1, Ordering::Relaxed);
                hair = Vector3::zeros();
            }
        }
        DeviceCommand { force, torque: Vector3::zeros() }
    };
    let lp = HapticLoop::spawn(rate_hz, device, step, max_steps)?;
    Ok((lp, counters))
}

/// Runs a session to completion and returns the loop statistics and counters.
pub fn run_local_session<D: HapticDevice + 'static>(
    rate_hz: f64,
    device: D,
    profile: DeviceProfile,
    interaction: LocalInteraction,
    steps: u64,
) -> Result<(LoopStats, D, Arc<SessionCounters>), String> {
    let (lp, c) = spawn_local_session(rate_hz, device, profile, interaction, Some(steps))?;
    let (stats, dev) = lp.join();
    Ok((stats, dev, c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use haptics::backends::ScriptedDevice;
    use nalgebra::Matrix3;
    use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};
    use tools::interaction::ForceModel;
    use tools::shape::ToolShape;

    fn interaction(n: usize) -> LocalInteraction {
        let h = HairType::H1;
        let m = StrandModel::new(ModelKind::Full, 0.1, 8, h.section().unwrap(), h.material().unwrap()).unwrap();
        let strands = (0..n)
            .map(|i| Strand::new(m.clone(), RootFrame::new(Vector3::new(-0.01 + 0.02 * i as f64 / n as f64, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap())
            .collect();
        let pose = ToolPose { position: Vector3::new(0.0004, -0.02, 0.25), rotation: Matrix3::identity() };
        LocalInteraction::new(strands, ToolShape::builtin("comb").unwrap(), pose, ForceModel::Constraint { friction: 0.2, options: Default::default() })
    }

    #[test]
    fn a_scripted_stroke_through_the_loop_is_felt_and_deterministic() {
        // The comb is drawn through 4 strands at 0.2 m/s by a scripted device in the 1 kHz loop. The device
        // feels the hair (some non-zero force), never more than the Omni's 3.3 N, and the same script gives the
        // same force trace twice (the loop's timing does not enter the physics).
        let script = |t: f64| Some(DeviceReading { time: t, position: Vector3::new(0.0004, -0.02 + 0.2 * t, 0.25), rotation: Matrix3::identity(), buttons: 0 });
        let run = || {
            let (stats, dev, c) = run_local_session(1000.0, ScriptedDevice::new(script), DeviceProfile::PHANTOM_OMNI, interaction(4), 200).unwrap();
            assert_eq!(stats.steps, 200);
            assert_eq!(c.rejected_inputs.load(Ordering::Relaxed), 0);
            assert!(c.contact_steps.load(Ordering::Relaxed) > 0);
            dev.commands
        };
        let a = run();
        let b = run();
        assert_eq!(a, b);
        assert!(a.iter().any(|c| c.force.norm() > 0.0));
        assert!(a.iter().all(|c| c.force.norm() <= 3.3 + 1e-12));
    }

    #[test]
    fn absurd_device_input_never_reaches_the_hand() {
        // NaN and teleporting readings in the middle of a stroke: zero force on those steps, counted, and the
        // session goes on.
        let script = |t: f64| {
            let n = (t * 1000.0).round() as i64;
            let x = match n {
                50 => Vector3::new(f64::NAN, 0.0, 0.0),
                80 => Vector3::new(5.0, 5.0, 5.0),
                _ => Vector3::new(0.0004, -0.02 + 0.2 * t, 0.25),
            };
            Some(DeviceReading { time: t, position: x, rotation: Matrix3::identity(), buttons: 0 })
        };
        let (stats, dev, c) = run_local_session(1000.0, ScriptedDevice::new(script), DeviceProfile::PHANTOM_OMNI, interaction(2), 120).unwrap();
        assert_eq!(stats.steps, 120);
        assert_eq!(c.rejected_inputs.load(Ordering::Relaxed), 2);
        assert_eq!(dev.commands[50].force, Vector3::zeros());
        assert_eq!(dev.commands[80].force, Vector3::zeros());
        assert!(dev.commands.iter().all(|c| c.force.iter().all(|x| x.is_finite())));
    }
}
