//! Fault handling of the UDP device over real sockets on loopback (docs/protocol.md, "Faults"): a lost
//! stream, rejected poses (non-finite, out of range, teleport, out of order, duplicate), malformed packets,
//! a second sender, a flood, and 10 % random loss with the coupling in a hard wall.

use haptics::coupling::{Coupling, CouplingParams};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::haptic_loop::HapticLoop;
use haptics::udp::{encode_force, Reject, UdpClient, UdpDevice, UdpParams, FLAG_REJECTED};
use haptics::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

const OMNI: DeviceProfile = DeviceProfile::PHANTOM_OMNI;

/// A device with the identity workspace (head frame = device frame) and a client connected to it.
fn pair() -> (UdpDevice, UdpClient) {
    let params = UdpParams { workspace: Workspace { scale: 1.0, offset: Vector3::zeros() }, wall_clock: false, ..UdpParams::for_profile(&OMNI) };
    let dev = UdpDevice::bind_with("127.0.0.1:0", params).unwrap();
    let client = UdpClient::connect(dev.local_addr().unwrap()).unwrap();
    (dev, client)
}

fn pose(t: f64, x: f64) -> DeviceReading {
    DeviceReading { time: t, position: Vector3::new(x, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 0 }
}

/// Reads at loop time `t` until `answers` more poses are waiting to be answered (packets on loopback take
/// a few microseconds), then answers them with `force`; returns the last reading.
fn step(dev: &mut UdpDevice, t: f64, force: f64, answers: u64) -> Option<DeviceReading> {
    let st = dev.status();
    let before = st.counts();
    let waiting = |c: haptics::udp::UdpCounts| c.accepted + c.rejected_total() - before.accepted - before.rejected_total();
    let deadline = Instant::now() + Duration::from_secs(2);
    let mut r = dev.read(t);
    while waiting(st.counts()) < answers && Instant::now() < deadline {
        std::thread::sleep(Duration::from_micros(100));
        r = dev.read(t);
    }
    assert!(waiting(st.counts()) >= answers, "{answers} poses did not arrive");
    dev.write(&DeviceCommand { force: Vector3::new(force, 0.0, 0.0), torque: Vector3::zeros() });
    r
}

#[test]
fn a_silent_stream_is_lost_after_50_ms_with_zero_force_and_resumes() {
    let (mut dev, mut c) = pair();
    let st = dev.status();
    c.send(&pose(0.0, 0.01)).unwrap();
    assert_eq!(step(&mut dev, 0.0, 0.5, 1).unwrap().position.x, 0.01);
    let (_, f, flags) = c.receive().unwrap();
    assert_eq!((f.force.x, flags), (0.5, 0));
    // Held for 50 ms of loop time without a packet (the loop uses the latest pose) ...
    assert!(dev.read(0.050).is_some());
    assert!(st.counts().connected);
    // ... and lost just after: no reading, so the loop computes no force (zero), and the status says so.
    assert!(dev.read(0.0501).is_none());
    let n = st.counts();
    assert!(!n.connected);
    assert_eq!(n.lost, 1);
    // A foreign sender could not take over while the stream was owned; now that it is lost, it may.
    // The first client resumes first, from anywhere in reach (a resume is not a teleport).
    c.send(&pose(1.0, 0.3)).unwrap();
    let r = step(&mut dev, 1.0, 0.25, 1).unwrap();
    assert_eq!(r.position.x, 0.3);
    assert!(st.counts().connected);
    assert_eq!(c.receive().unwrap().1.force.x, 0.25);
}

#[test]
fn only_the_first_sender_drives_the_tool_until_it_is_lost() {
    let (mut dev, mut owner) = pair();
    let mut intruder = UdpClient::connect(dev.local_addr().unwrap()).unwrap();
    intruder.set_timeout(Some(Duration::from_millis(30))).unwrap();
    owner.send(&pose(0.0, 0.01)).unwrap();
    step(&mut dev, 0.0, 1.0, 1);
    owner.receive().unwrap();
    intruder.send(&pose(0.001, 0.011)).unwrap();
    let deadline = Instant::now() + Duration::from_secs(2);
    while dev.status().counts().foreign == 0 && Instant::now() < deadline {
        assert_eq!(dev.read(0.001).unwrap().position.x, 0.01, "the intruder's pose is not used");
        std::thread::sleep(Duration::from_micros(100));
    }
    dev.write(&DeviceCommand { force: Vector3::new(2.0, 0.0, 0.0), torque: Vector3::zeros() });
    assert_eq!(dev.status().counts().foreign, 1);
    assert!(intruder.receive().is_err(), "the intruder gets no force stream");
    // After the owner has been silent for 50 ms the next valid sender owns the stream.
    assert!(dev.read(0.06).is_none());
    intruder.send(&pose(0.07, -0.02)).unwrap();
    assert_eq!(step(&mut dev, 0.07, 0.3, 1).unwrap().position.x, -0.02);
    assert_eq!(intruder.receive().unwrap().1.force.x, 0.3);
}

#[test]
fn bad_poses_are_answered_with_the_flag_and_zero_force_and_the_stream_goes_on() {
    let (mut dev, mut c) = pair();
    let st = dev.status();
    let mut t = 0.0;
    let mut x = 0.0;
    let good = |dev: &mut UdpDevice, c: &mut UdpClient, t: &mut f64, x: &mut f64| {
        *t += 1e-3;
        *x += 1e-4;
        let seq = c.send(&pose(*t, *x)).unwrap();
        assert_eq!(step(dev, *t, 1.5, 1).unwrap().position.x, *x);
        let (s, f, flags) = c.receive().unwrap();
        assert_eq!((s, f.force.x, flags), (seq, 1.5, 0), "a good pose gets the step's force");
        seq
    };
    good(&mut dev, &mut c, &mut t, &mut x);
    let last_good = x;
    let rot_bad = Matrix3::identity() * 2.0;
    let nan = DeviceReading { position: Vector3::new(f64::NAN, 0.0, 0.0), ..pose(t + 1e-3, 0.0) };
    let inf_time = DeviceReading { time: f64::INFINITY, ..pose(0.0, x) };
    let cases: Vec<(&str, DeviceReading, Reject)> = vec![
        ("NaN position", nan, Reject::Invalid),
        ("infinite time", inf_time, Reject::Invalid),
        ("1e30 m", pose(t + 1e-3, 1e30), Reject::Invalid),
        ("10 m teleport (out of reach)", pose(t + 1e-3, x + 10.0), Reject::Invalid),
        ("0.3 m in 1 ms (teleport)", pose(t + 1e-3, x + 0.3), Reject::Teleport),
        ("a rotation scaled by 2", DeviceReading { rotation: rot_bad, ..pose(t + 1e-3, x) }, Reject::Invalid),
        ("time going back", pose(t - 0.5, x), Reject::OutOfOrder),
    ];
    for (what, r, why) in cases {
        let before = st.counts().rejected[why as usize];
        let seq = c.send(&r).unwrap();
        let held = step(&mut dev, t, 1.5, 1).unwrap();
        assert_eq!(held.position.x, last_good, "{what}: the last good pose is kept");
        let (s, f, flags) = c.receive().unwrap();
        assert_eq!(s, seq, "{what}");
        assert_eq!(flags & FLAG_REJECTED, FLAG_REJECTED, "{what}: flag");
        assert_eq!(f.force, Vector3::zeros(), "{what}: zero force");
        assert_eq!(st.counts().rejected[why as usize], before + 1, "{what}: counted as {why:?}");
    }
    // Out-of-order and duplicate sequence numbers (times fine).
    let seq = good(&mut dev, &mut c, &mut t, &mut x);
    for (s, why) in [(seq, Reject::Duplicate), (seq.wrapping_sub(3), Reject::OutOfOrder)] {
        let before = st.counts().rejected[why as usize];
        c.send_seq(s, &pose(t + 1e-3, x)).unwrap();
        step(&mut dev, t, 1.5, 1);
        let (got, f, flags) = c.receive().unwrap();
        assert_eq!((got, f.force, flags), (s, Vector3::zeros(), FLAG_REJECTED), "{why:?}");
        assert_eq!(st.counts().rejected[why as usize], before + 1, "{why:?}");
    }
    // The stream goes on: good poses get forces again.
    good(&mut dev, &mut c, &mut t, &mut x);
    let n = st.counts();
    assert_eq!(n.rejected_total(), 9);
    assert_eq!(n.lost, 0, "rejected poses within 50 ms do not lose the stream");
}

#[test]
fn wrong_size_or_magic_is_counted_and_dropped() {
    let (mut dev, mut c) = pair();
    let good = haptics::udp::encode_pose(1, &pose(0.0, 0.0));
    let mut magic = good;
    magic[0..4].copy_from_slice(b"XXXX");
    c.send_raw(&good[..115]).unwrap();
    c.send_raw(&magic).unwrap();
    c.send_raw(&[good.as_slice(), &[0u8]].concat()).unwrap();
    c.send_raw(&encode_force(1, &DeviceCommand::default(), 0)).unwrap();
    c.send_raw(&[]).unwrap();
    let deadline = Instant::now() + Duration::from_secs(2);
    while dev.status().counts().malformed < 5 && Instant::now() < deadline {
        assert!(dev.read(0.0).is_none(), "no pose from malformed packets");
        std::thread::sleep(Duration::from_micros(100));
    }
    assert_eq!(dev.status().counts().malformed, 5);
    dev.write(&DeviceCommand::default());
    assert_eq!(dev.status().counts().answered, 0, "malformed packets are not answered");
    c.send(&pose(0.001, 0.0)).unwrap();
    assert!(step(&mut dev, 0.001, 0.1, 1).is_some(), "the stream goes on");
}

#[test]
fn a_flood_is_read_a_bounded_number_of_packets_per_step() {
    let (mut dev, mut c) = pair();
    let max = dev.params().max_packets_per_step as u64;
    for i in 0..200 {
        c.send(&pose(i as f64 * 1e-4, 0.0)).unwrap();
    }
    std::thread::sleep(Duration::from_millis(50));
    let t0 = Instant::now();
    dev.read(0.0);
    let took = t0.elapsed();
    dev.write(&DeviceCommand::default());
    let n = dev.status().counts();
    assert_eq!(n.accepted, max, "one step reads at most {max} packets");
    assert_eq!(n.deferred, 1);
    println!("one step read {max} of 200 waiting packets in {took:?}");
    let mut steps = 1;
    while dev.status().counts().accepted < 200 {
        dev.read(0.0);
        dev.write(&DeviceCommand::default());
        steps += 1;
        assert!(steps < 100);
    }
    assert_eq!(steps, 200u64.div_ceil(max), "the rest is read in the next steps");
}

/// A hard wall at x = 0.01 m acting on the proxy (20 kN/m penalty, far stiffer than the coupling).
fn wall(proxy: &Vector3<f64>) -> Vector3<f64> {
    if proxy.x > 0.01 { Vector3::new(-20000.0 * (proxy.x - 0.01), 0.0, 0.0) } else { Vector3::zeros() }
}

#[test]
fn ten_percent_random_loss_stays_stable_and_passive() {
    // A client streams a hand pushing in and out of a hard wall (2 cm amplitude, 2.5 Hz) at 1 kHz, dropping
    // 10 % of its poses at random (seeded); the device side runs the 1 kHz haptic loop with the coupling.
    // At every step: the port's energy stays >= 0 (1e-12 J round-off), |F| within the Omni's 3.3 N, every
    // force finite; every answer the client gets is finite and within the limit.
    let (dev, mut c) = pair();
    let mut coupling = Coupling::new(OMNI, CouplingParams::for_profile(&OMNI), Vector3::zeros());
    let seen = Arc::new(Mutex::new((0u64, f64::INFINITY, 0.0f64, 0u64)));
    let out = seen.clone();
    let step = move |r: Option<DeviceReading>, _t: f64, dt: f64| {
        let Some(r) = r else { return DeviceCommand::default() };
        let hair = wall(&coupling.proxy);
        let f = coupling.update(&r, dt, &hair).unwrap_or_default();
        let mut s = out.lock().unwrap();
        s.0 += 1;
        s.1 = s.1.min(coupling.energy);
        s.2 = s.2.max(if f.iter().all(|x| x.is_finite()) { f.norm() } else { f64::INFINITY });
        s.3 = coupling.clamp_activations;
        DeviceCommand { force: f, torque: Vector3::zeros() }
    };
    let lp = HapticLoop::spawn(1000.0, dev, step, None).unwrap();
    c.set_nonblocking(true).unwrap();
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let (mut sent, mut dropped, mut answers, mut worst) = (0u64, 0u64, 0u64, 0.0f64);
    let start = Instant::now();
    for k in 0..1500u32 {
        let t = k as f64 * 1e-3;
        let x = 0.01 - 0.02 * (0.5 - 0.5 * (2.0 * std::f64::consts::PI * 2.5 * t).cos()) * -1.0;
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        if rng % 10 == 0 {
            dropped += 1;
        } else {
            c.send(&pose(t, x)).unwrap();
            sent += 1;
        }
        while let Ok((_, f, _)) = c.receive() {
            answers += 1;
            worst = worst.max(if f.force.iter().all(|x| x.is_finite()) { f.force.norm() } else { f64::INFINITY });
        }
        let next = start + Duration::from_micros(1000 * (k as u64 + 1));
        if let Some(d) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    std::thread::sleep(Duration::from_millis(20));
    while let Ok((_, f, _)) = c.receive() {
        answers += 1;
        worst = worst.max(f.force.norm());
    }
    let (stats, dev) = lp.stop();
    let (steps, min_energy, max_force, clamps) = *seen.lock().unwrap();
    let n = dev.status().counts();
    println!("sent {sent} dropped {dropped} answered {answers} ({:.1} %), loop steps {} with a pose {steps}, min energy {min_energy:.3e} J, max force {max_force:.3} N (client saw {worst:.3} N), clamps {clamps}, lost {}", 100.0 * answers as f64 / sent as f64, stats.steps, n.lost);
    assert!(dropped > 100 && dropped < 200, "about 10 % dropped: {dropped}");
    assert!(steps > 1000, "the loop ran with poses: {steps}");
    assert!(min_energy >= -1e-12, "passive: {min_energy} J");
    assert!(max_force <= OMNI.max_force + 1e-12 && worst <= OMNI.max_force + 1e-12, "bounded: {max_force} N, {worst} N");
    assert!(max_force > 1.0, "the wall was felt: {max_force} N");
    assert!(answers > sent / 2, "answered {answers} of {sent}");
}
