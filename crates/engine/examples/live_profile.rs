//! Profile of the live haptic step: a `[live]` scenario (default examples/scenarios/live-comb.toml) run as
//! `coiffure run` runs it (both cores in lockstep on one thread, `LiveScenario`'s schedule), with the wall time
//! of each stage of `HapticCore::step` (`haptic::StepPhases`) for every traced step. Prints the step-time
//! percentiles, the mean of each stage, and the stages of the slowest steps. As in the live server's haptic thread,
//! each step stages a share of the viewer's snapshot (`HapticCore::stage_snapshot`) and every
//! `SessionParams::publish_every`-th step writes it (`HapticCore::snapshot`), timed together as "publish" and
//! counted in the step's wall time. Run:
//! `cargo run --release -p coiffure-engine --example live_profile [-- [FILE.toml] [rt] [pace|pace=spin] [slowest=N] [hair=on|off] [entanglement=on|off] [max_active=N] [steps=FILE.csv]]`
//! (`rt`: SCHED_FIFO priority 10 for this thread, needs root or CAP_SYS_NICE; `hair=`: `HapticParams::hair_contact`,
//! default the scenario's `[live] hair_contact`; `entanglement=`: `HapticParams::entanglement`, default the
//! scenario's `[live] entanglement`; `max_active=`: `SessionParams::max_active`; `pace`: each step waits for
//! its period on the wall clock, as the live physics thread does, instead of running back to back; `pace=spin`: the same
//! with a spin-wait instead of a sleep; `steps=`: every traced step's stages, counts, CPU time and page faults as CSV).
//!
//! The tail's make-up: each step's thread CPU time is measured beside its wall time (a step whose wall time exceeds its
//! CPU time was preempted: the host's, not the step's), and the mean stages and counts (strands joining and leaving,
//! rows, hair-hair links) of the median steps, the slowest 1 % and the slowest 0.1 % by CPU time are printed. The
//! steps are the same in every run (the scenario is deterministic), so the per-step minimum of the CPU time over
//! several runs' `steps=` files is the step's own cost with the host's noise taken out.

use engine::command::Command;
use engine::haptic::StepPhases;
use engine::lockstep::Lockstep;
use engine::params::SessionParams;
use engine::scenario::LiveScenario;
use engine::scene::Scene;
use std::sync::Arc;
use std::time::Instant;
use strand::HairType;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args.iter().find(|a| a.ends_with(".toml")).cloned().unwrap_or_else(|| "examples/scenarios/live-comb.toml".into());
    let slowest: usize = args.iter().find_map(|a| a.strip_prefix("slowest=").and_then(|v| v.parse().ok())).unwrap_or(12);
    if args.iter().any(|a| a == "rt") {
        if let Err(why) = haptics::realtime::request_realtime(10) {
            eprintln!("rt: {why}");
        }
    }
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let s: LiveScenario = toml::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
    let (profile, tool, hair) = s.validate().expect("a valid scenario");
    let scene = Arc::new(Scene::builtin(&s.scene_options()).expect("the built-in scene"));
    let mut params = SessionParams { profile, ..SessionParams::default() };
    params.haptic.hair_contact = s.live.hair_contact;
    if let Some(on) = args.iter().find_map(|a| a.strip_prefix("hair=")) {
        params.haptic.hair_contact = on == "on";
    }
    params.haptic.entanglement = s.live.entanglement;
    if let Some(on) = args.iter().find_map(|a| a.strip_prefix("entanglement=")) {
        params.haptic.entanglement = on == "on";
    }
    if args.iter().any(|a| a == "input=device") {
        params.input = engine::params::InputKind::Device;
    }
    if let Some(n) = args.iter().find_map(|a| a.strip_prefix("max_active=").and_then(|v| v.parse().ok())) {
        params.max_active = n;
        params.max_chosen = params.max_chosen.min(n);
    }
    let mut ls = Lockstep::new(scene, params, params.haptic_rate_hz).expect("the session");
    ls.global.set_wetness(s.live.wetness);
    let hair_index = HairType::ALL.iter().position(|h| *h == hair).unwrap_or(0) as u8;
    let mut commands = vec![Command::SelectTool(tool), Command::SetHair { hair_type: hair_index, curliness: s.live.curliness, combing_ease: s.live.combing_ease }];
    let every = ((params.haptic_rate_hz / params.global_rate_hz).round() as u64).max(1);
    let settle = (s.settle / ls.dt).round() as u64;
    let steps = settle + (s.run_time() / ls.dt).round() as u64;
    let mut rows: Vec<Row> = Vec::new();
    let per_step = args.iter().find_map(|a| a.strip_prefix("steps="));
    let mut snapshot = engine::snapshot::HapticSnapshot::default();
    let (mut tip, mut peak, mut jump, mut last) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    // trace=FILE: per traced step the force sent (N), the device's and the proxy's position and velocity
    // (m, m/s), the hair's reaction on the proxy (N) and its damping's trace (N s/m), the passivity
    // controller's and the clamps' activations so far, contacts and simulated strands.
    let mut trace = args.iter().find_map(|a| a.strip_prefix("trace=")).map(|f| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(f).expect("the trace file"));
        use std::io::Write;
        writeln!(w, "t,fx,fy,fz,dev_y,dev_z,dev_vy,dev_vz,proxy_y,proxy_z,proxy_vy,proxy_vz,hair_fy,hair_fz,hair_d,passive,clamped,contacts,active").unwrap();
        w
    });
    // `pace`: each step starts on the wall clock's next period (sleeping between steps as the live physics thread
    // waits for its next period), instead of back to back: shows what an idle gap between steps costs the step.
    let pace = args.iter().any(|a| a == "pace" || a == "pace=spin");
    let spin = args.iter().any(|a| a == "pace=spin");
    let clock = Instant::now();
    for n in 0..steps {
        if pace {
            let due = clock + std::time::Duration::from_secs_f64(n as f64 * ls.dt);
            let now = Instant::now();
            if due > now && spin {
                while Instant::now() < due {
                    std::hint::spin_loop();
                }
            } else if due > now {
                std::thread::sleep(due - now);
            }
        }
        if n % every == 0 {
            ls.global_step_live();
        }
        let t = (n as f64 - settle as f64) * ls.dt;
        let k = params.device_steps();
        let readings: Vec<_> = (0..k).map(|i| (n >= settle).then(|| s.reading(t + i as f64 * ls.dt / k as f64))).collect();
        let before = ls.haptic.active().to_vec();
        let faults0 = if per_step.is_some() { minor_faults() } else { 0 };
        let cpu0 = haptics::realtime::thread_cpu_time().unwrap_or(0.0);
        let t0 = Instant::now();
        let cmd = ls.haptic_step(&std::mem::take(&mut commands), &readings);
        tip = tip.max(ls.haptic.max_tip_speed());
        peak = peak.max(cmd.force.norm());
        jump = jump.max((cmd.force.norm() - last).abs());
        last = cmd.force.norm();
        let t1 = Instant::now();
        if let (Some(w), true) = (trace.as_mut(), n >= settle) {
            use std::io::Write;
            let c = ls.haptic.coupling();
            let h = ls.haptic.hair_reaction();
            let f = cmd.force;
            writeln!(w, "{t:.4},{:.5},{:.5},{:.5},{:.6},{:.6},{:.5},{:.5},{:.6},{:.6},{:.5},{:.5},{:.5},{:.5},{:.4},{},{},{},{}", f.x, f.y, f.z, c.device.y, c.device.z, c.device_velocity.y, c.device_velocity.z, c.proxy.y, c.proxy.z, c.proxy_velocity.y, c.proxy_velocity.z, h.force.y, h.force.z, h.damping.trace(), c.passivity_activations, c.clamp_activations, ls.haptic.last_contacts(), ls.haptic.active().len()).unwrap();
        }
        ls.haptic.stage_snapshot(&ls.lattice);
        if (n + 1) % params.publish_every == 0 {
            ls.haptic.snapshot(&ls.lattice, ls.dt, &mut snapshot);
        }
        let publish = t1.elapsed().as_secs_f64();
        let wall = t0.elapsed().as_secs_f64();
        let cpu = haptics::realtime::thread_cpu_time().unwrap_or(0.0) - cpu0;
        if n >= settle {
            let now = ls.haptic.active();
            let (joined, left) = (now.iter().filter(|g| !before.contains(g)).count(), before.iter().filter(|g| !now.contains(g)).count());
            let faults = if per_step.is_some() { minor_faults() - faults0 } else { 0 };
            rows.push(Row { step: n - settle, wall, cpu, p: ls.haptic.timings(), active: now.len(), contacts: ls.haptic.last_contacts(), publish, joined, left, faults });
        }
    }
    if let Some(f) = per_step {
        write_steps(f, &rows);
    }
    let mut times: Vec<f64> = rows.iter().map(|r| r.wall).collect();
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((p * times.len() as f64).ceil() as usize).clamp(1, times.len()) - 1] * 1e6;
    let misses = times.iter().filter(|&&t| t > 1e-3).count();
    println!("{file}: {} traced steps, real-time priority: {}, hair-hair contact: {}, entanglement: {}, at most {} strands simulated", times.len(), haptics::realtime::is_realtime(), params.haptic.hair_contact, params.haptic.entanglement, params.max_active);
    println!("peak force {peak:.3} N, largest one-step change of |F| {jump:.3} N, fastest strand tip {tip:.2} m/s");
    println!("step: p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us, mean {:.0} us, {misses} steps over 1 ms", q(0.5), q(0.99), q(0.999), q(1.0), times.iter().sum::<f64>() / times.len() as f64 * 1e6);
    let n = rows.len() as f64;
    let mean = |f: &dyn Fn(&StepPhases) -> f64| rows.iter().map(|r| f(&r.p)).sum::<f64>() / n * 1e6;
    println!(
        "mean per stage: coupling {:.0} us, active set {:.0} us, actions {:.0} us, interaction {:.0} us (dynamics {:.0}, sample {:.0}, detect {:.0} (hair-hair {:.0}), constrained {:.0} (body contacts {:.0}), free {:.0}), tracking {:.0} us",
        mean(&|p| p.coupling),
        mean(&|p| p.active),
        mean(&|p| p.actions),
        mean(&|p| p.interaction),
        mean(&|p| p.local.dynamics),
        mean(&|p| p.local.sample),
        mean(&|p| p.local.detect),
        mean(&|p| p.local.hair_detect),
        mean(&|p| p.local.constrained),
        mean(&|p| p.local.body),
        mean(&|p| p.local.free),
        mean(&|p| p.tracking)
    );
    let count = |f: &dyn Fn(&StepPhases) -> usize| rows.iter().map(|r| f(&r.p) as f64).sum::<f64>() / n;
    println!(
        "constrained: solve {:.0} us mean; rows {:.0}, rows of the largest strand {:.1}, hair-hair links {:.1}, sweeps {:.1} a step on average",
        mean(&|p| p.local.solve),
        count(&|p| p.local.rows),
        count(&|p| p.local.strand_rows),
        count(&|p| p.local.links),
        count(&|p| p.local.sweeps)
    );
    let mut published: Vec<f64> = rows.iter().map(|r| r.publish).collect();
    published.sort_by(f64::total_cmp);
    let pq = |p: f64| published.get(((p * published.len() as f64) as usize).min(published.len().saturating_sub(1))).copied().unwrap_or(0.0) * 1e6;
    println!("publish (staged every step, written every {} steps): mean {:.0} us, p50 {:.0} us, p90 {:.0} us, p99 {:.0} us, max {:.0} us", params.publish_every, published.iter().sum::<f64>() / published.len().max(1) as f64 * 1e6, pq(0.5), pq(0.9), pq(0.99), pq(1.0));
    tail_make_up(&mut rows);
    rows.sort_by(|a, b| b.wall.total_cmp(&a.wall));
    println!("| step | wall us | coupling | active set (choose, rebuild) | actions | interaction | dynamics | sample | detect (hair) | constrained (body) | free | tracking | active | contacts | publish | solve us (rows, largest, links, sweeps) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for Row { step: k, wall: w, p, active: a, contacts: c, publish, .. } in rows.iter().take(slowest) {
        let us = |x: f64| format!("{:.0}", x * 1e6);
        println!("| {k} | {} | {} | {} ({}, {}) | {} | {} | {} | {} | {} ({}) | {} ({}) | {} | {} | {a} | {c} | {} | {} ({}, {}, {}, {}) |", us(*w), us(p.coupling), us(p.active), us(p.choose), us(p.rebuild), us(p.actions), us(p.interaction), us(p.local.dynamics), us(p.local.sample), us(p.local.detect), us(p.local.hair_detect), us(p.local.constrained), us(p.local.body), us(p.local.free), us(p.tracking), us(*publish), us(p.local.solve), p.local.rows, p.local.strand_rows, p.local.links, p.local.sweeps);
    }
}

/// One traced step: its wall and thread CPU time (s), stages, simulated strands, tool contacts, publish time (s),
/// strands that joined and left the active set in it, and minor page faults (with `steps=` only).
struct Row {
    step: u64,
    wall: f64,
    cpu: f64,
    p: StepPhases,
    active: usize,
    contacts: u32,
    publish: f64,
    joined: usize,
    left: usize,
    faults: u64,
}

/// Prints the step's CPU-time percentiles and the mean stages and counts of the median steps (45-55 %), of all, of
/// the slowest 1 % and of the slowest 0.1 % by CPU time (sorts `rows` so).
fn tail_make_up(rows: &mut [Row]) {
    if rows.is_empty() {
        return;
    }
    rows.sort_by(|a, b| a.cpu.total_cmp(&b.cpu));
    let n = rows.len();
    let q = |p: f64| rows[((p * n as f64).ceil() as usize).clamp(1, n) - 1].cpu * 1e6;
    let preempted = rows.iter().filter(|r| r.wall - r.cpu > 1e-4).count();
    println!("step CPU time: p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us; {preempted} steps preempted (wall over CPU time by > 100 us)", q(0.5), q(0.99), q(0.999), q(1.0));
    println!("| steps by CPU time | CPU us | active set (rebuild) | dynamics | sample | detect (hair) | constrained (solve) | publish | joined | left | contacts | rows | links |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let groups = [("median (45-55 %)", &rows[n * 45 / 100..(n * 55 / 100).max(n * 45 / 100 + 1)]), ("all", &rows[..]), ("slowest 1 %", &rows[n - (n / 100).max(1)..]), ("slowest 0.1 %", &rows[n - (n / 1000).max(1)..])];
    for (name, g) in groups {
        let m = |f: &dyn Fn(&Row) -> f64| g.iter().map(f).sum::<f64>() / g.len() as f64;
        let us = |f: &dyn Fn(&Row) -> f64| m(f) * 1e6;
        println!(
            "| {name}, {} | {:.0} | {:.0} ({:.0}) | {:.0} | {:.0} | {:.0} ({:.0}) | {:.0} ({:.0}) | {:.0} | {:.1} | {:.1} | {:.1} | {:.0} | {:.0} |",
            g.len(),
            us(&|r| r.cpu),
            us(&|r| r.p.active),
            us(&|r| r.p.rebuild),
            us(&|r| r.p.local.dynamics),
            us(&|r| r.p.local.sample),
            us(&|r| r.p.local.detect),
            us(&|r| r.p.local.hair_detect),
            us(&|r| r.p.local.constrained),
            us(&|r| r.p.local.solve),
            us(&|r| r.publish),
            m(&|r| r.joined as f64),
            m(&|r| r.left as f64),
            m(&|r| r.contacts as f64),
            m(&|r| r.p.local.rows as f64),
            m(&|r| r.p.local.links as f64)
        );
    }
}

/// Writes every traced step (in step order) to the CSV file `path`: wall and CPU time and stages in us, counts.
fn write_steps(path: &str, rows: &[Row]) {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).expect("the steps file"));
    writeln!(w, "step,wall,cpu,coupling,active,choose,rebuild,actions,interaction,dynamics,sample,detect,hair_detect,constrained,body,free,solve,tracking,publish,strands,joined,left,touched,contacts,rows,strand_rows,links,sweeps,hair_pairs,faults").unwrap();
    for r in rows {
        let p = &r.p;
        let us: Vec<String> = [r.wall, r.cpu, p.coupling, p.active, p.choose, p.rebuild, p.actions, p.interaction, p.local.dynamics, p.local.sample, p.local.detect, p.local.hair_detect, p.local.constrained, p.local.body, p.local.free, p.local.solve, p.tracking, r.publish].iter().map(|x| format!("{:.1}", x * 1e6)).collect();
        writeln!(w, "{},{},{},{},{},{},{},{},{},{},{},{},{}", r.step, us.join(","), r.active, r.joined, r.left, p.local.touched_strands, r.contacts, p.local.rows, p.local.strand_rows, p.local.links, p.local.sweeps, p.hair_pairs, r.faults).unwrap();
    }
}

/// Minor page faults of this thread so far (`/proc/thread-self/stat`'s tenth field; 0 where it cannot be read).
fn minor_faults() -> u64 {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").unwrap_or_default();
    // The fields after the command's closing parenthesis: the state is the third field, minflt the tenth.
    stat.rsplit_once(')').and_then(|(_, rest)| rest.split_whitespace().nth(7)).and_then(|v| v.parse().ok()).unwrap_or(0)
}
