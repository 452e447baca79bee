//! Replay of a recorded live session, headless and deterministic.

use crate::error::SessionError;
use crate::lockstep::Lockstep;
use crate::params::SessionParams;
use crate::record::Record;
use crate::scene::Scene;
use nalgebra::Vector3;
use std::sync::Arc;

/// Re-runs a recorded session in lockstep on this thread ([`Lockstep::replay`]): the global core is stepped up to the lattice
/// version each haptic step used (applying the recorded lattice resets), the recorded commands are applied,
/// the global steps read the recorded tool inputs (dryer jet, sprayer and dryer wetness, scissors cuts, the tool
/// pushing the lattice), and the haptic core steps with the recorded reading. Returns the force of every step.
pub fn replay(scene: Arc<Scene>, params: SessionParams, record: &Record) -> Result<Vec<Vector3<f64>>, SessionError> {
    let mut ls = Lockstep::new(scene, params, record.rate_hz)?;
    let mut out = Vec::with_capacity(record.steps.len());
    ls.replay(record, |_, cmd| {
        if let Some(c) = cmd {
            out.push(c.force);
        }
    });
    Ok(out)
}

/// [`replay`], giving the force of every device step (N), by haptic step: the forces the device was sent,
/// several per haptic step when the device loop runs faster than the physics (`SessionParams::device_steps`).
pub fn replay_device_steps(scene: Arc<Scene>, params: SessionParams, record: &Record) -> Result<Vec<Vec<Vector3<f64>>>, SessionError> {
    let mut ls = Lockstep::new(scene, params, record.rate_hz)?;
    let mut out = Vec::with_capacity(record.steps.len());
    ls.replay(record, |ls, cmd| {
        if cmd.is_some() {
            out.push(ls.device_commands.iter().map(|c| c.force).collect());
        }
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::live::Session;
    use crate::testing::{read_record, record_file, small_scene, test_rot};
    use crate::tool::Tool;
    use std::time::Duration;
    use haptics::device::DeviceReading;

    #[test]
    fn a_recorded_live_session_replays_to_the_same_forces() {
        // A live session (both threads, real time) is driven through the virtual device by this thread: a
        // comb stroke down the back of the head at 0.1 m/s, then the sprayer held on the hair, then the
        // scissors closed once, and a reset on the way. Its record (streamed to a file as the session ran)
        // replayed in lockstep on one thread gives every haptic step's force
        // again within 1e-9 N (in fact bit for bit), although the live threads' timing was whatever the
        // machine gave them.
        let scene = small_scene();
        let params = SessionParams::default();
        let (path, sink) = record_file("replay-stroke", &params);
        let (session, mut io) = Session::start_recording(scene.clone(), params, None, Some(sink)).unwrap();
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
        eprintln!("live: {:?}, global steps {}, record {:?}", report.haptic, report.global_steps, report.record);
        let written = report.record.expect("recorded");
        // The file streamed while the session ran, read back whole.
        let rec = read_record(&path);
        assert_eq!((written.steps, written.global_steps, written.stopped.as_deref()), (rec.steps.len() as u64, rec.global_inputs.len() as u64, None));
        // (A physics period's record is whole at the next hand-over: the record holds the periods before the
        // last one run.)
        assert!(rec.steps.len() >= 1799, "{} steps", rec.steps.len());
        assert_eq!(rec.global_resets.len(), 1, "one lattice reset recorded");
        // The viewer's three commands (and whatever the strand budget decided on this machine, replayed too).
        assert_eq!(rec.steps.iter().flat_map(|s| &s.commands).filter(|c| !matches!(c, Command::LimitStrands(_))).count(), 3);
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

    #[test]
    fn the_strand_budgets_changes_are_recorded_and_replayed_to_the_same_forces() {
        // A live session whose strand budget finds every step too slow (target 0.1 % of the period, a change
        // allowed every 20 ms) while the comb strokes down the back hair: its limit falls to the floor
        // (`BudgetParams::min_strands`) at once (lowered in proportion to the excess, hundreds of times; the limit then bound the
        // stroke), and the change is in the record as a LimitStrands command;
        // the record replayed in lockstep, where nothing is timed, gives every force again to the bit.
        use crate::budget::BudgetParams;
        let scene = small_scene();
        let budget = BudgetParams { target: 0.001, hold: 0.02, start: 56, ..BudgetParams::default() };
        let params = SessionParams { budget, ..SessionParams::default() };
        let (path, sink) = record_file("replay-budget", &params);
        let (session, mut io) = Session::start_recording(scene.clone(), params, None, Some(sink)).unwrap();
        let rot = test_rot();
        loop {
            let step = io.haptic.read().step;
            if step >= 1500 {
                break;
            }
            let t = step as f64 * 1e-3;
            io.device.push(DeviceReading { time: t, position: Vector3::new(0.0, -0.118, 0.04 - 0.1 * t), rotation: rot, buttons: 0 });
            std::thread::sleep(Duration::from_micros(500));
        }
        let report = session.stop();
        let rec = read_record(&path);
        let limits: Vec<u32> = rec.steps.iter().flat_map(|s| &s.commands).filter_map(|c| match c {
            Command::LimitStrands(n) => Some(*n),
            _ => None,
        }).collect();
        eprintln!("budget {:?}, limits recorded {limits:?}", report.budget);
        let floor = budget.min_strands;
        assert_eq!(limits, vec![floor as u32], "lowered to the floor at once");
        assert_eq!((report.budget.changes, report.budget.lowest, report.budget.last), (1, floor, floor));
        assert!(report.budget.limited_steps > 0 && report.budget.limited_steps < report.budget.steps);
        let back = Record::from_bytes(&rec.to_bytes()).unwrap();
        assert_eq!(back, rec);
        let forces = replay(scene, params, &back).unwrap();
        assert_eq!(forces.len(), rec.steps.len());
        // A physics stall (a step later than a full period plus `device_loop::PHYSICS_STALL`: the device loop goes on
        // with the model it has, and the record stops matching its replay there) is named in the failure.
        for (i, (f, s)) in forces.iter().zip(&rec.steps).enumerate() {
            assert!(f.iter().zip(s.force.iter()).all(|(a, b)| a.to_bits() == b.to_bits()), "step {i}: {f:?} vs {:?}; physics {:?}", s.force, report.physics);
        }
        let peak = rec.steps.iter().map(|s| s.force.norm()).fold(0.0, f64::max);
        assert!(peak > 1e-4, "the stroke was felt: peak {peak} N");
    }

    #[test]
    fn a_live_session_fed_a_live_scenarios_device_inputs_gives_its_trace_to_the_bit() {
        // Issue 11's acceptance for [live] scenarios. The threaded live session (`coiffure serve`'s code) is
        // fed the device readings of a [live] scenario's path (`LiveScenario::reading`, as `coiffure run`
        // feeds its lockstep cores). Its record replayed through the scenarios' door for records
        // (`scenario::live::replay_record`, what `coiffure replay` writes to force.csv) gives every force the
        // live session sent to the device, to the bit; and the scenario run's own record replays to its
        // trace to the bit (`a_live_scenario_replays_through_the_live_sessions_replay_to_the_bit`). The live
        // threads' schedule (which lattice version each haptic step reads) is the machine's, so the two
        // traces are compared through their records, not with each other.
        let scene = small_scene();
        let text = crate::testing::LIVE_COMB.replace("settle = 0.2", "settle = 0.0");
        let s: crate::scenario::LiveScenario = toml::from_str(&text).unwrap();
        let params = SessionParams::default();
        let (path, sink) = record_file("replay-live-scenario", &params);
        let (session, mut io) = Session::start_recording(scene.clone(), params, None, Some(sink)).unwrap();
        loop {
            let step = io.haptic.read().step;
            if step >= 800 {
                break;
            }
            io.device.push(s.reading(step as f64 * 1e-3));
            std::thread::sleep(Duration::from_micros(300));
        }
        let report = session.stop();
        eprintln!("device loop {:?}\nphysics {:?}", report.haptic, report.physics);
        let rec = read_record(&path);
        let (trace, summary, device) = crate::scenario::live::replay_record(scene, params, &rec).unwrap();
        assert_eq!(trace.len(), rec.steps.len());
        for (i, st) in rec.steps.iter().enumerate() {
            let f = trace.force(i);
            assert!(f.iter().zip(st.force.iter()).all(|(a, b)| a.to_bits() == b.to_bits()), "step {i}: {f:?} vs {:?}", st.force);
        }
        // The device-rate trace: one line per recorded device step (each period's readings), stamped with its
        // reading's time, and each period's last device step is the force the record kept for it.
        let readings: Vec<_> = rec.steps.iter().flat_map(|s| s.readings()).collect();
        assert_eq!(device.time.len(), readings.len());
        assert!(readings.len() > rec.steps.len(), "the device loop ran faster than the physics: {} device steps, {} periods", readings.len(), rec.steps.len());
        for (i, r) in readings.iter().enumerate() {
            assert_eq!(device.time[i].to_bits(), r.map_or(f64::NAN, |r| r.time).to_bits(), "device step {i}");
        }
        for (i, st) in rec.steps.iter().enumerate() {
            let last = device.period.iter().rposition(|&p| p == i).expect("every period has device steps");
            assert!(device.force[last].iter().zip(st.force.iter()).all(|(a, b)| a.to_bits() == b.to_bits()), "period {i}");
        }
        eprintln!("{} steps, {summary:?}", trace.len());
        assert!(summary.peak_force_n > 1e-4 && summary.contact_steps > 0, "the comb met the hair: {summary:?}");
    }
}
