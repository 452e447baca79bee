//! Benchmark of the haptic loop: a comb drawn at 0.2 m/s through N hanging strands of S segments (16 by default; full
//! model, constraint contacts), 1 kHz, one haptic thread. Prints step-time mean, p99, p99.9, max and deadline
//! misses, then the mean time per step of each phase of the interaction step. Run:
//! `cargo run --release -p coiffure-engine --example haptic_loop_bench [-- [full|reduced] [nobatch] [rt] [hair] [segments=S] [cap=C] N...]`
//! (default: full model, 16 segments, 16 32 64 strands). Reduced strands are prepared four at a time (SIMD batches,
//! `LocalInteraction::use_batches`) unless `nobatch` is given. With `hair`, the strands also touch each other
//! (`LocalInteraction::hair_contact`, each strand standing for 100 fibres: contact distance 1.3 mm, more than the
//! roots' spacing at 64 strands, so every strand is in hair-hair contact at every step: the worst case), and each
//! count is run twice in the same process, contact off then on, and the ratio printed; `cap=C` sets
//! `HairContact::max_per_strand`.
//! With `rt` (or under `chrt -f 10`; both need root or CAP_SYS_NICE) the haptic thread runs with real-time
//! FIFO priority, as a haptic application would run it (`haptics::realtime`); the tails then show the loop's
//! own cost rather than the scheduler's.

use haptics::backends::ScriptedDevice;
use haptics::coupling::{Coupling, CouplingParams};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::haptic_loop::{HapticLoop, LoopStats};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use nalgebra::{Matrix3, Vector3};
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel};
use tools::contact::ToolPose;
use tools::interaction::{ForceModel, LocalInteraction};
use tools::shape::ToolShape;

/// Counters shared with the haptic thread (atomics: readable without locking).
#[derive(Debug, Default)]
struct Counters {
    /// Steps with at least one contact.
    contact_steps: AtomicU64,
    /// Total wall time of the interaction steps' phases, ns (`tools::interaction::StepTimings`): strand
    /// dynamics and unconstrained solves, centreline sampling and tree refit, contact detection, strands with
    /// contacts, strands without.
    phase_ns: [AtomicU64; 5],
    /// Total strands with contacts over all steps.
    touched_strands: AtomicU64,
    /// Largest force of the hair on the tool in one step, as the bits of a non-negative f64 in N.
    peak_hair_force_bits: AtomicU64,
}

/// The loop under test: per step, device reading -> coupling (proxy pose, safe device force) -> local
/// interaction step -> the hair's reaction feeds the coupling at the next step. (The live session's
/// `HapticCore` adds the active set, roots on the lattice and the tools' actions around the same step.)
fn run<D: HapticDevice + 'static>(device: D, profile: DeviceProfile, mut interaction: LocalInteraction, steps: u64) -> (LoopStats, D, Arc<Counters>) {
    let counters = Arc::new(Counters::default());
    let shared = counters.clone();
    let mut coupling = Coupling::new(profile, CouplingParams::for_profile(&profile), interaction.pose.position);
    let mut hair = Vector3::zeros();
    let step = move |reading: Option<DeviceReading>, _t: f64, dt: f64| -> DeviceCommand {
        let Some(r) = reading else { return DeviceCommand::default() };
        let Ok(force) = coupling.update(&r, dt, &hair) else { return DeviceCommand::default() };
        let pose = ToolPose { position: coupling.proxy, rotation: r.rotation };
        if let Ok(res) = interaction.step(dt, pose) {
            hair = res.force;
            let t = &res.timings;
            for (slot, secs) in shared.phase_ns.iter().zip([t.dynamics, t.sample, t.detect, t.constrained, t.free]) {
                slot.fetch_add((secs * 1e9) as u64, Ordering::Relaxed);
            }
            shared.touched_strands.fetch_add(t.touched_strands as u64, Ordering::Relaxed);
            shared.peak_hair_force_bits.fetch_max(res.force.norm().to_bits(), Ordering::Relaxed);
            if !res.contacts.is_empty() {
                shared.contact_steps.fetch_add(1, Ordering::Relaxed);
            }
        }
        DeviceCommand { force, torque: Vector3::zeros() }
    };
    let lp = HapticLoop::spawn(1000.0, device, step, Some(steps)).expect("the haptic loop starts");
    let (stats, dev) = lp.join();
    (stats, dev, counters)
}

/// Per-step means of the interaction's phases (us) and the strands touched per step.
type Phases = ([f64; 5], f64);

/// One run: N strands of `segments` segments hanging in a row along x (6 cm wide), the comb drawn through them.
/// Prints its table row; returns the loop's statistics and the phases.
fn bench(n: usize, segments: usize, kind: ModelKind, batches: bool, hair: bool, cap: usize) -> (LoopStats, Phases) {
    let h = HairType::H1;
    let m = StrandModel::new(kind, 0.15, segments, h.section().unwrap(), h.material().unwrap()).unwrap();
    let strands: Vec<Strand> = (0..n)
        .map(|i| {
            let x = -0.03 + 0.06 * (i as f64 + 0.5) / n as f64;
            Strand::new(m.clone(), RootFrame::new(Vector3::new(x, 0.0, 0.3), -Vector3::z(), Vector3::x()).unwrap()).unwrap()
        })
        .collect();
    let pose = ToolPose { position: Vector3::new(0.0004, -0.02, 0.22), rotation: Matrix3::identity() };
    let mut it = LocalInteraction::new(strands, ToolShape::builtin("comb").unwrap(), pose, ForceModel::Constraint { friction: h.friction_coefficient(), options: Default::default() });
    it.params.use_batches = batches;
    if hair {
        it.params.hair_contact = Some(tools::interaction::HairContact { fibres: 100.0, max_per_strand: cap, ..Default::default() });
    }
    let script = |t: f64| Some(DeviceReading { time: t, position: Vector3::new(0.0004, -0.02 + 0.2 * t, 0.22), rotation: Matrix3::identity(), buttons: 0 });
    let steps = 2000;
    let (s, dev, c) = run(ScriptedDevice::new(script), DeviceProfile::PHANTOM_DESKTOP, it, steps);
    let peak = dev.commands.iter().map(|c| c.force.norm()).fold(0.0, f64::max);
    let per_step = |i: usize| c.phase_ns[i].load(Ordering::Relaxed) as f64 / s.steps as f64 / 1e3;
    println!(
        "| {n} x {segments} | {} | {} | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {} | {} | {:.2} N | {:.3e} N |",
        if hair { "on" } else { "off" },
        s.steps,
        s.step_mean * 1e6,
        s.step_p99 * 1e6,
        s.step_p999 * 1e6,
        s.step_max * 1e6,
        s.misses,
        c.contact_steps.load(Ordering::Relaxed),
        peak,
        f64::from_bits(c.peak_hair_force_bits.load(Ordering::Relaxed))
    );
    let touched = c.touched_strands.load(Ordering::Relaxed) as f64 / s.steps as f64;
    (s, ([per_step(0), per_step(1), per_step(2), per_step(3), per_step(4)], touched))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = if args.iter().any(|a| a == "reduced") { ModelKind::Reduced } else { ModelKind::Full };
    let counts: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let counts = if counts.is_empty() { vec![16, 32, 64] } else { counts };
    let segments = args.iter().find_map(|a| a.strip_prefix("segments=").and_then(|v| v.parse().ok())).unwrap_or(16);
    let cap = args.iter().find_map(|a| a.strip_prefix("cap=").and_then(|v| v.parse().ok())).unwrap_or(tools::interaction::HairContact::default().max_per_strand);
    let batches = !args.iter().any(|a| a == "nobatch");
    let hair = args.iter().any(|a| a == "hair");
    if args.iter().any(|a| a == "rt") {
        // Threads started from here inherit the policy (Linux default), so the haptic thread gets it too.
        if let Err(why) = haptics::realtime::request_realtime(10) {
            eprintln!("rt: {why}");
        }
    }
    println!("model: {kind:?}, batches: {batches}, hair-hair contact: {hair} (at most {cap} per strand), real-time priority: {}", haptics::realtime::is_realtime());
    println!("| strands x segments | hair-hair | steps | step mean | p99 | p99.9 | max | misses | contact steps | peak device force | peak hair force |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let mut phases = Vec::new();
    let mut ratios = Vec::new();
    for n in counts {
        // With `hair`, the contact-off baseline first, in the same run, then hair-hair contact on.
        let off = hair.then(|| bench(n, segments, kind, batches, false, cap));
        let (on, p) = bench(n, segments, kind, batches, hair, cap);
        phases.push((n, hair, p));
        if let Some((off, p_off)) = off {
            phases.push((n, false, p_off));
            ratios.push((n, on.step_mean / off.step_mean, on.step_p999 / off.step_p999));
        }
    }
    println!();
    println!("Mean time per step of each phase:");
    println!("| strands | hair-hair | strand dynamics + free solve | sampling + tree refit | detection | strands with contacts (assembly, PGS, commit) | strands without (commit) | strands touched per step |");
    println!("|---|---|---|---|---|---|---|---|");
    for (n, on, (p, touched)) in phases {
        println!("| {n} | {} | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {:.0} us | {touched:.1} |", if on { "on" } else { "off" }, p[0], p[1], p[2], p[3], p[4]);
    }
    for (n, mean, p999) in ratios {
        println!("hair-hair contact on / off, {n} strands: step mean x{mean:.2}, p99.9 x{p999:.2}");
    }
}
