//! Replay of a recorded live session, headless and deterministic.

use crate::error::SessionError;
use crate::global::GlobalCore;
use crate::haptic::HapticCore;
use crate::params::SessionParams;
use crate::record::Record;
use crate::scene::Scene;
use nalgebra::Vector3;
use std::sync::Arc;
use std::time::Duration;

/// Re-runs a recorded session in lockstep on this thread: the global core is stepped up to the lattice
/// version each haptic step used (applying the recorded lattice resets), the recorded commands are applied,
/// the global steps read the recorded tool inputs (dryer jet, sprayer and dryer wetness, scissors cuts, the tool
/// pushing the lattice), and the haptic core steps with the recorded reading. Returns the force of every step.
pub fn replay(scene: Arc<Scene>, params: SessionParams, record: &Record) -> Result<Vec<Vector3<f64>>, SessionError> {
    let mut core = HapticCore::new(scene.clone(), params)?;
    let mut global = GlobalCore::new(scene, &params);
    let mut snap = global.snapshot();
    // The same step lengths as the live threads (which go through Duration).
    let gdt = Duration::from_secs_f64(1.0 / params.global_rate_hz).as_secs_f64();
    let dt = Duration::from_secs_f64(1.0 / record.rate_hz).as_secs_f64();
    let mut out = Vec::with_capacity(record.steps.len());
    for s in &record.steps {
        while snap.version < s.lattice_version {
            if record.global_resets.contains(&(global.version + 1)) {
                global.reset();
            }
            // The tool input that global step read (none in a version-1 record).
            let input = record.global_inputs.get(global.version as usize).copied().unwrap_or_default();
            snap = global.step(gdt, &input).0;
        }
        for c in &s.commands {
            core.apply(c);
        }
        out.push(core.step(s.reading, &snap, dt).force);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::live::Session;
    use crate::testing::{small_scene, test_rot};
    use crate::tool::Tool;
    use haptics::device::DeviceReading;

    #[test]
    fn a_recorded_live_session_replays_to_the_same_forces() {
        // A live session (both threads, real time) is driven through the virtual device by this thread: a
        // comb stroke down the back of the head at 0.1 m/s, then the sprayer held on the hair, then the
        // scissors closed once, and a reset on the way. Its record (through the file format, version 2 with
        // the global steps' tool inputs) replayed in lockstep on one thread gives every haptic step's force
        // again within 1e-9 N (in fact bit for bit), although the live threads' timing was whatever the
        // machine gave them.
        let scene = small_scene();
        let params = SessionParams { record: true, ..SessionParams::default() };
        let (session, mut io) = Session::start(scene.clone(), params).unwrap();
        let rot = test_rot();
        // The path follows the haptic thread's own step count (published every 5 steps), so the test does
        // not depend on how fast this machine runs the threads.
        let (mut sprayer, mut scissors, mut reset) = (false, false, false);
        loop {
            let step = io.haptic.read().step;
            if step >= 1800 {
                break;
            }
            let t = step as f64 * 1e-3;
            let z = 0.05 - 0.1 * t.min(1.0);
            let buttons = ((700..1000).contains(&step) || (1200..1300).contains(&step)) as u32;
            io.device.push(DeviceReading { time: t, position: Vector3::new(0.0, -0.118, z), rotation: rot, buttons });
            if step > 650 && !sprayer {
                io.commands.send(Command::SelectTool(Tool::Sprayer)).unwrap();
                sprayer = true;
            }
            if step > 1100 && !scissors {
                io.commands.send(Command::SelectTool(Tool::Scissors)).unwrap();
                scissors = true;
            }
            if step > 1500 && !reset {
                io.commands.send(Command::Reset).unwrap();
                reset = true;
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        let report = session.stop();
        eprintln!("live: {:?}, global steps {}", report.haptic, report.global_steps);
        let rec = report.record.expect("recorded");
        assert!(rec.steps.len() >= 1800, "{} steps", rec.steps.len());
        assert_eq!(rec.global_resets.len(), 1, "one lattice reset recorded");
        assert_eq!(rec.steps.iter().map(|s| s.commands.len()).sum::<usize>(), 3);
        assert_eq!(rec.global_inputs.len() as u64, report.global_steps);
        assert!(rec.global_inputs.iter().any(|g| g.tool == Tool::Sprayer && g.pressed), "the sprayer sprayed");
        assert_eq!(rec.global_inputs.last().map(|g| g.cuts), Some(1), "one scissors close");
        let peak = rec.steps.iter().map(|s| s.force.norm()).fold(0.0, f64::max);
        assert!(peak > 1e-4, "the stroke was felt: peak {peak} N");
        let back = Record::from_bytes(&rec.to_bytes()).unwrap();
        assert_eq!(back, rec);
        let forces = replay(scene, params, &back).unwrap();
        assert_eq!(forces.len(), rec.steps.len());
        let worst = forces.iter().zip(&rec.steps).map(|(f, s)| (f - s.force).norm()).fold(0.0, f64::max);
        eprintln!("replayed {} steps, peak {peak} N, largest difference {worst} N", forces.len());
        assert!(worst <= 1e-9, "largest force difference {worst} N");
    }
}
