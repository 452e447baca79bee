//! Profile of the haptic step under the soak's controller (`crates/server/examples/soak.rs`), headless: the same
//! scripted input on the live session's two cores in lockstep on one thread (`Lockstep`; 100k render strands,
//! the server's defaults, pointer input), with the wall time of each haptic step (the viewer commands it applies,
//! at most `live::MAX_COMMANDS_PER_STEP`, and `HapticCore::step`) split by tool and by stage
//! (`haptic::StepPhases`). The controller, as the soak's: comb strokes with 2 mm jitter down the back of the head
//! at 120 Hz, every tool in turn (10 s each, the primary button held half of the time), a SET_HAIR every 15 s, a
//! RESET every 60 s, a 2 m teleport every 5 s (the NaN pose the server refuses before the loop), one burst of
//! 1,000 RESETs at a third of the run. Run:
//! Each traced step also takes what the live haptic thread adds to it: the tool input for the global thread and,
//! every `SessionParams::publish_every` steps, the snapshot for the viewers (`HapticCore::snapshot`).
//! `cargo run --release -p coiffure-engine --example soak_profile [-- [SECONDS] [rt] [hair=on|off] [slowest=N]]`
//! (default 60 s of simulated time; `rt`: SCHED_FIFO priority 10 for this thread).

use engine::command::Command;
use engine::haptic::StepPhases;
use engine::live::MAX_COMMANDS_PER_STEP;
use engine::lockstep::Lockstep;
use engine::params::SessionParams;
use engine::scene::{Scene, SceneOptions};
use engine::tool::Tool;
use haptics::device::DeviceReading;
use nalgebra::{Matrix3, Vector3};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

/// One traced haptic step: (step, tool, button, commands applied, commands' wall s, step's wall s, stages,
/// active strands).
struct Row {
    n: u64,
    tool: usize,
    pressed: bool,
    commands: usize,
    command_s: f64,
    /// The tool input and the snapshot, s.
    snapshot_s: f64,
    wall: f64,
    phases: StepPhases,
    active: usize,
}

fn quantiles(mut t: Vec<f64>) -> (f64, f64, f64, f64, f64, usize) {
    if t.is_empty() {
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    }
    t.sort_by(f64::total_cmp);
    let q = |p: f64| t[((p * t.len() as f64).ceil() as usize).clamp(1, t.len()) - 1] * 1e6;
    let misses = t.iter().filter(|&&x| x > 1e-3).count();
    (t.iter().sum::<f64>() / t.len() as f64 * 1e6, q(0.5), q(0.99), q(0.999), q(1.0), misses)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seconds: f64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(60.0);
    let slowest: usize = args.iter().find_map(|a| a.strip_prefix("slowest=").and_then(|v| v.parse().ok())).unwrap_or(12);
    if args.iter().any(|a| a == "rt") {
        if let Err(why) = haptics::realtime::request_realtime(10) {
            eprintln!("rt: {why}");
        }
    }
    let scene = Arc::new(Scene::builtin(&SceneOptions::default()).expect("the built-in scene"));
    let mut params = SessionParams::default();
    if let Some(on) = args.iter().find_map(|a| a.strip_prefix("hair=")) {
        params.haptic.hair_contact = on == "on";
    }
    let mut ls = Lockstep::new(scene, params, params.haptic_rate_hz).expect("the session");
    let every = ((params.haptic_rate_hz / params.global_rate_hz).round() as u64).max(1);
    let steps = (seconds / ls.dt).round() as u64;
    // The soak's controller: the tool's x axis along x, y along z, z along -y.
    let rot = Matrix3::from_columns(&[Vector3::x(), Vector3::z(), -Vector3::y()]);
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut noise = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let pose_period = 1.0 / 120.0;
    let (mut next_pose, mut target) = (0.0, Vector3::new(0.0, -0.115, 0.08));
    let (mut last_tool, mut last_hair, mut last_reset, mut last_fault, mut burst_done) = (usize::MAX, 0u64, 0u64, 0u64, false);
    let mut teleport_until = -1.0;
    let mut queue: VecDeque<Command> = VecDeque::new();
    let mut rows: Vec<Row> = Vec::with_capacity(steps as usize);
    let mut burst = (u64::MAX, 0u64);
    let mut snapshot = engine::snapshot::HapticSnapshot::default();
    for n in 0..steps {
        let t = n as f64 * ls.dt;
        if n % every == 0 {
            ls.global_step_live();
            // Idle a little, as the live loops do between their periods: a SCHED_FIFO thread that never sleeps is
            // throttled by the kernel (50 ms in every second), which would show as 50 ms steps.
            std::thread::sleep(std::time::Duration::from_micros(1000));
        }
        let tool = ((t / 10.0) as usize) % 6;
        let pressed = (t / 5.0) as u64 % 2 == 1;
        if t >= next_pose {
            next_pose += pose_period;
            if tool != last_tool {
                last_tool = tool;
                queue.push_back(Command::SelectTool(Tool::ALL[tool]));
            }
            let phase = (t / 1.5).fract();
            let x = 0.04 * (t / 7.0).sin();
            target = Vector3::new(x + 0.002 * noise(), -0.115 + 0.002 * noise(), 0.08 - 0.14 * phase + 0.002 * noise());
            let s = t as u64;
            if s / 15 != last_hair {
                last_hair = s / 15;
                queue.push_back(Command::SetHair { hair_type: (last_hair % 4) as u8, curliness: 0.5 * (last_hair % 3) as f64, combing_ease: 0.5 });
            }
            if s / 60 != last_reset {
                last_reset = s / 60;
                queue.push_back(Command::Reset);
            }
            if s / 5 != last_fault {
                last_fault = s / 5;
                teleport_until = t + pose_period;
            }
            if !burst_done && t > seconds / 3.0 {
                burst_done = true;
                burst.0 = n;
                queue.extend(std::iter::repeat(Command::Reset).take(1000));
            }
        }
        let position = if t < teleport_until { Vector3::new(0.0, -2.0, 0.0) } else { target };
        let reading = DeviceReading { time: t, position, rotation: rot, buttons: pressed as u32 };
        let t0 = Instant::now();
        let mut applied = 0;
        while applied < MAX_COMMANDS_PER_STEP {
            let Some(c) = queue.pop_front() else { break };
            ls.haptic.apply(&c);
            applied += 1;
        }
        let command_s = t0.elapsed().as_secs_f64();
        ls.haptic_step(&[], &vec![Some(reading); params.device_steps()]);
        // What the live haptic thread also does in its step: the tool input for the global thread, and every
        // `publish_every` steps the snapshot for the viewers.
        let t1 = t0.elapsed().as_secs_f64();
        let _ = ls.haptic.tool_input();
        if (n + 1) % params.publish_every == 0 {
            ls.haptic.snapshot(&ls.lattice, ls.dt, &mut snapshot);
        }
        let wall = t0.elapsed().as_secs_f64();
        let snapshot_s = wall - t1;
        if burst.0 != u64::MAX && burst.1 == 0 && queue.is_empty() {
            burst.1 = n;
        }
        rows.push(Row { n, tool, pressed, commands: applied, command_s, snapshot_s, wall, phases: ls.haptic.timings(), active: ls.haptic.active().len() });
    }
    println!("soak_profile: {seconds} s ({} steps), real-time priority: {}, hair-hair contact: {}, load average {}", rows.len(), haptics::realtime::is_realtime(), params.haptic.hair_contact, std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim());
    let line = |name: &str, sel: &dyn Fn(&Row) -> bool| {
        let set: Vec<&Row> = rows.iter().filter(|r| sel(r)).collect();
        if set.is_empty() {
            return;
        }
        let (mean, p50, p99, p999, max, misses) = quantiles(set.iter().map(|r| r.wall).collect());
        let m = set.len() as f64;
        let avg = |f: &dyn Fn(&Row) -> f64| set.iter().map(|r| f(r)).sum::<f64>() / m * 1e6;
        println!(
            "| {name} | {} | {mean:.0} | {p50:.0} | {p99:.0} | {p999:.0} | {max:.0} | {misses} ({:.2} %) | {:.0} | {:.0} | {:.0} ({:.0}, {:.0}) | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} ({:.0}) | {:.0} ({:.0}) | {:.0} | {:.1} | {:.1} | {:.0} | {:.0} |",
            set.len(),
            100.0 * misses as f64 / m,
            avg(&|r| r.command_s),
            avg(&|r| r.phases.coupling),
            avg(&|r| r.phases.active),
            avg(&|r| r.phases.choose),
            avg(&|r| r.phases.rebuild),
            avg(&|r| r.phases.actions),
            avg(&|r| r.phases.interaction),
            avg(&|r| r.phases.local.dynamics),
            avg(&|r| r.phases.local.sample),
            avg(&|r| r.phases.local.detect),
            avg(&|r| r.phases.local.hair_detect),
            avg(&|r| r.phases.local.constrained),
            avg(&|r| r.phases.local.body),
            avg(&|r| r.phases.local.free),
            set.iter().map(|r| r.active as f64).sum::<f64>() / m,
            set.iter().map(|r| r.phases.local.sweeps as f64).sum::<f64>() / m,
            set.iter().map(|r| r.phases.local.rows as f64).sum::<f64>() / m,
            avg(&|r| r.snapshot_s),
        );
    };
    println!("| steps | n | mean us | p50 | p99 | p99.9 | max | misses | commands | coupling | active (choose, rebuild) | actions | interaction | dynamics | sample | detect (hair) | constrained (body) | free | active strands | sweeps | rows | snapshot us |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    line("all", &|_| true);
    for (k, t) in Tool::ALL.iter().enumerate() {
        line(&format!("{} up", t.name()), &|r| r.tool == k && !r.pressed);
        line(&format!("{} pressed", t.name()), &|r| r.tool == k && r.pressed);
    }
    line("with commands", &|r| r.commands > 0);
    line("RESET burst", &|r| r.n >= burst.0 && r.n <= burst.1);
    line("without commands", &|r| r.commands == 0);
    let mut slow: Vec<&Row> = rows.iter().collect();
    slow.sort_by(|a, b| b.wall.total_cmp(&a.wall));
    println!("| step | tool | pressed | commands | wall us | commands us | coupling | active (choose, rebuild) | actions | interaction | dynamics | sample | detect (hair) | constrained (body) | free | tracking | active |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let us = |x: f64| format!("{:.0}", x * 1e6);
    for r in slow.iter().take(slowest) {
        let p = &r.phases;
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} ({}, {}) | {} | {} | {} | {} | {} ({}) | {} ({}) | {} | {} | {} |",
            r.n, Tool::ALL[r.tool].name(), r.pressed, r.commands, us(r.wall), us(r.command_s), us(p.coupling), us(p.active), us(p.choose), us(p.rebuild), us(p.actions), us(p.interaction), us(p.local.dynamics), us(p.local.sample), us(p.local.detect), us(p.local.hair_detect), us(p.local.constrained), us(p.local.body), us(p.local.free), us(p.tracking), r.active
        );
    }
}
