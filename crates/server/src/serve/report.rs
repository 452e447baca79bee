//! The report `coiffure serve` prints when it stops: frames, the haptic and device loops, the strand budget,
//! the device's counters and the record.

use super::app::App;
use super::config::ServeArgs;
use super::pump::PumpStats;
use engine::live::SessionReport;

/// Prints the end-of-run report of a server run with `args`.
pub(super) fn print(args: &ServeArgs, app: &App, st: &PumpStats, report: &SessionReport) {
    let params = &app.params;
    let f = st.frames.max(1) as f64;
    println!(
        "frames sent: {} ({:.1} us CPU and {:.0} bytes per frame; {} more than a period late, the latest {:.1} ms behind, built in at most {:.1} ms); haptic loop: {} steps at {} Hz, step mean {:.1} us, p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us (to the model's publication; then the record and the viewers' snapshot: mean {:.1} us, max {:.0} us), the step's CPU time mean {:.1} us, p99.9 {:.0} us ({} steps preempted), {} over the period, {} periods extended for a late physics step ({} stalls), {} step panics, {} runaways; device loop: {} steps at {} Hz, step mean {:.1} us, p99.9 {:.0} us, max {:.0} us, {} misses ({:.3} %, {} periods skipped; {} late starts, {} preempted, {} slow steps; wake-up lateness p99.9 {:.0} us, max {:.0} us), {} step panics, real-time priority: {}, CPU wake-up latency held at 0: {}; global: {} steps, mean {:.2} ms; delivery: {}",
        st.frames, 1e6 * st.encode_seconds / f, st.bytes as f64 / f, st.late, 1e3 * st.max_late, 1e3 * st.max_build,
        report.physics.steps, args.haptic_rate, 1e6 * report.physics.step_mean, 1e6 * report.physics.step_p50, 1e6 * report.physics.step_p99, 1e6 * report.physics.step_p999, 1e6 * report.physics.step_max, 1e6 * report.physics.chores_mean, 1e6 * report.physics.chores_max, 1e6 * report.physics.step_cpu_mean, 1e6 * report.physics.step_cpu_p999, report.physics.preempted, report.physics.over, report.physics.extended, report.physics.stalls, report.physics.panics, st.runaways,
        report.haptic.steps, args.device_rate, 1e6 * report.haptic.step_mean, 1e6 * report.haptic.step_p999, 1e6 * report.haptic.step_max, report.haptic.misses, 100.0 * report.haptic.misses as f64 / report.haptic.steps.max(1) as f64, report.haptic.skipped, report.haptic.misses_late_start, report.haptic.misses_preempted, report.haptic.misses_slow, 1e6 * report.haptic.wake_p999, 1e6 * report.haptic.wake_max, report.haptic.panics, report.haptic.realtime, report.cpu_latency_held,
        report.global_steps, 1e3 * report.global_step_mean, app.delivery.summary()
    );
    let b = &report.budget;
    if b.enabled {
        println!(
            "strand budget: {} changes, lowest {} strands, {} at the end (of {}), {:.1} % of {} steps limited",
            b.changes, b.lowest, b.last, params.max_active, 100.0 * b.limited_steps as f64 / b.steps.max(1) as f64, b.steps
        );
    } else {
        println!("strand budget: off");
    }
    if let Some((_, status)) = &app.udp {
        let c = status.counts();
        println!(
            "device: {} poses accepted, rejected {} (invalid {}, teleport {}, out of order {}, duplicate {}), {} malformed, {} from another sender, lost {} times, {} forces sent",
            c.accepted, c.rejected_total(), c.rejected[0], c.rejected[1], c.rejected[2], c.rejected[3], c.malformed, c.foreign, c.lost, c.answered
        );
    }
    if let Some(r) = &report.record {
        let secs = r.steps as f64 / args.haptic_rate;
        match &r.stopped {
            None => println!("record: {} haptic steps ({secs:.1} s), {} global steps, {} bytes written to {}", r.steps, r.global_steps, r.bytes, r.name),
            Some(why) => println!("record: stopped early, {} haptic steps ({secs:.1} s) in {} ({} bytes); {} steps after it not recorded: {why}", r.steps, r.name, r.bytes, r.unrecorded),
        }
    }
}
