//! Benchmark of the haptic loop: a comb drawn at 0.2 m/s through N hanging strands of 16 segments (full
//! model, constraint contacts), 1 kHz, one haptic thread. Prints step-time mean, p99, p99.9, max and deadline
//! misses, then the mean time per step of each phase of the interaction step. Run:
//! `cargo run --release -p coiffure-engine --example haptic_loop_bench [-- [full|reduced] [nobatch] [rt] [hair] N...]`
//! (default: full model, 16 32 64 strands). Reduced strands are prepared four at a time (SIMD batches,
//! `LocalInteraction::use_batches`) unless `nobatch` is given. With `hair`, the strands also touch each other
//! (`LocalInteraction::hair_contact`, each strand standing for 100 fibres: contact distance 1.3 mm, more than the
//! roots' spacing at 64 strands, so every strand is in hair-hair contact at every step: the worst case).
//! With `rt` (or under `chrt -f 10`; both need root or CAP_SYS_NICE) the haptic thread runs with real-time
//! FIFO priority, as a haptic application would run it (`haptics::realtime`); the tails then show the loop's
//! own cost rather than the scheduler's.

use engine::local_session::run_local_session;
use haptics::backends::ScriptedDevice;
use haptics::device::{DeviceProfile, DeviceReading};
use nalgebra::{Matrix3, Vector3};
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};
use tools::contact::ToolPose;
use tools::interaction::{ForceModel, LocalInteraction};
use tools::shape::ToolShape;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = if args.iter().any(|a| a == "reduced") { ModelKind::Reduced } else { ModelKind::Full };
    let counts: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let counts = if counts.is_empty() { vec![16, 32, 64] } else { counts };
    let batches = !args.iter().any(|a| a == "nobatch");
    let hair = args.iter().any(|a| a == "hair");
    if args.iter().any(|a| a == "rt") {
        // Threads started from here inherit the policy (Linux default), so the haptic thread gets it too.
        if let Err(why) = haptics::realtime::request_realtime(10) {
            eprintln!("rt: {why}");
        }
    }
    println!("model: {kind:?}, batches: {batches}, hair-hair contact: {hair}, real-time priority: {}", haptics::realtime::is_realtime());
    println!("| strands x 16 segments | steps | step mean | p99 | p99.9 | max | misses | contact steps | peak device force | peak hair force |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut phases = Vec::new();
    for n in counts {
        let h = HairType::H1;
        let m = StrandModel::new(kind, 0.15, 16, h.section().unwrap(), h.material().unwrap()).unwrap();
        let strands: Vec<Strand> = (0..n)
            .map(|i| {
                let x = -0.03 + 0.06 * (i as f64 + 0.5) / n as f64;
                Strand::new(m.clone(), RootFrame::new(Vector3::new(x, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap()
            })
            .collect();
        let pose = ToolPose { position: Vector3::new(0.0004, -0.02, 0.22), rotation: Matrix3::identity() };
        let mut it = LocalInteraction::new(strands, ToolShape::builtin("comb").unwrap(), pose, ForceModel::Constraint { friction: h.friction_coefficient(), options: Default::default() });
        it.use_batches = batches;
        if hair {
            it.hair_contact = Some(tools::interaction::HairContact { fibres: 100.0, ..Default::default() });
        }
        let script = |t: f64| Some(DeviceReading { time: t, position: Vector3::new(0.0004, -0.02 + 0.2 * t, 0.22), rotation: Matrix3::identity(), buttons: 0 });
        let steps = 2000;
        let (s, dev, c) = run_local_session(1000.0, ScriptedDevice::new(script), DeviceProfile::PHANTOM_DESKTOP, it, steps).unwrap();
        let peak = dev.commands.iter().map(|c| c.force.norm()).fold(0.0, f64::max);
        let per_step = |i: usize| c.phase_ns[i].load(std::sync::atomic::Ordering::Relaxed) as f64 / s.steps as f64 / 1e3;
        phases.push((n, [per_step(0), per_step(1), per_step(2), per_step(3), per_step(4)], c.touched_strands.load(std::sync::atomic::Ordering::Relaxed) as f64 / s.steps as f64));
        println!(
            "| {n} | {} | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {} | {} | {:.2} N | {:.3e} N |",
            s.steps,
            s.step_mean * 1e6,
            s.step_p99 * 1e6,
            s.step_p999 * 1e6,
            s.step_max * 1e6,
            s.misses,
            c.contact_steps.load(std::sync::atomic::Ordering::Relaxed),
            peak,
            f64::from_bits(c.peak_hair_force_bits.load(std::sync::atomic::Ordering::Relaxed))
        );
    }
    println!();
    println!("Mean time per step of each phase:");
    println!("| strands | strand dynamics + free solve | sampling + tree refit | detection | strands with contacts (assembly, PGS, commit) | strands without (commit) | strands touched per step |");
    println!("|---|---|---|---|---|---|---|");
    for (n, p, touched) in phases {
        println!("| {n} | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {touched:.1} |", p[0], p[1], p[2], p[3], p[4]);
    }
}
