//! The local force model over UDP (protocol version 2, issue 31): a version-2 client gets the model with every
//! answer and renders it at its own rate; a version-1 client keeps getting the 64-byte answer.

use haptics::coupling::{CouplingParams, HairReaction};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::haptic_loop::HapticLoop;
use haptics::local_model::FedModel;
use haptics::sim::{self, Faults, Hand, SimParams};
use haptics::udp::{UdpClient, UdpDevice, UdpParams, FORCE_BYTES};
use haptics::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};

const OMNI: DeviceProfile = DeviceProfile::PHANTOM_OMNI;

/// A wall of the hair's stiffness 300 N/m (head frame) at y = 0.01 m, pushing towards -y.
fn wall() -> FedModel {
    let hair = HairReaction { position: Vector3::new(0.0, 0.01, 0.0), stiffness: Matrix3::from_diagonal(&Vector3::new(0.0, 300.0, 0.0)), ..HairReaction::none() };
    FedModel { number: 1, valid_for: 1e-3, hair, coupling: CouplingParams::for_profile(&OMNI) }
}

/// A server answering at 1 kHz (zero force: what matters here is the model) with the wall model fed.
fn server() -> (std::net::SocketAddr, HapticLoop<UdpDevice>) {
    let params = UdpParams { workspace: Workspace { scale: 1.0, offset: Vector3::zeros() }, ..UdpParams::for_profile(&OMNI) };
    let mut dev = UdpDevice::bind_with("127.0.0.1:0", params).unwrap();
    let addr = dev.local_addr().unwrap();
    let mut feed = dev.model_feed().expect("the UDP device forwards models");
    feed.publish(wall());
    let lp = HapticLoop::spawn(1000.0, dev, move |_, _, _| DeviceCommand::default(), None).unwrap();
    (addr, lp)
}

#[test]
fn a_version_2_client_gets_the_model_and_a_version_1_client_the_old_answer() {
    let (addr, lp) = server();
    let pose = DeviceReading { time: 0.0, position: Vector3::new(0.0, 0.02, 0.0), rotation: Matrix3::identity(), buttons: 0 };
    let mut old = UdpClient::connect(addr).unwrap();
    old.send(&pose).unwrap();
    let (_, _, flags, model) = old.receive_model().unwrap();
    assert_eq!((flags, model), (0, None), "version 1: the 64-byte CFF1 answer (FORCE_BYTES = {FORCE_BYTES})");
    let mut new = UdpClient::connect(addr).unwrap();
    new.set_version(2);
    // (The first client owns the stream until it is lost: 50 ms.)
    std::thread::sleep(std::time::Duration::from_millis(120));
    new.send(&DeviceReading { time: 1.0, ..pose }).unwrap();
    let (_, _, flags, model) = new.receive_model().unwrap();
    let m = model.expect("version 2: the model");
    assert_eq!(flags, 0);
    assert_eq!(m.number, 1);
    assert_eq!(m.hair, wall().hair, "identity workspace: the model as fed");
    lp.stop();
}

#[test]
fn a_rendering_client_feels_the_wall_through_lost_packets_and_a_pause() {
    // device-sim's hand (a spring) pushes from the wall 2 cm into it and holds, sending 1 kHz poses of protocol version 2,
    // 20 % of them lost at random and none for 30 ms in the middle (jitter). It renders the model itself: the
    // force it feels is the coupling's against the wall, never above the Omni's 3.3 N, changing by at most the
    // Omni's rate limit per step (300 N/s x 1 ms, 1e-9 N), and held through the pause (the model holds 50 ms):
    // in the pause the felt force stays within 10 % of its value before it, while the answers stop.
    let (addr, lp) = server();
    let path = |t: f64| DeviceReading { time: t, position: Vector3::new(0.0, 0.01 + 0.02 * (t / 0.3).min(1.0), 0.0), rotation: Matrix3::identity(), buttons: 0 };
    let faults = Faults { loss: 0.2, seed: 3, pause: vec![(0.5, 0.03)], ..Faults::default() };
    let params = SimParams { rate_hz: 1000.0, duration: 0.8, hand: Hand::Spring { stiffness: 300.0, damping: 3.0 }, profile: OMNI, workspace: Workspace { scale: 1.0, offset: Vector3::zeros() }, faults, render: true };
    let rows = sim::run(addr, &path, &params).unwrap();
    lp.stop();
    let felt: Vec<(f64, f64)> = rows.iter().map(|r| (r.t, r.felt.norm())).collect();
    assert!(felt.iter().all(|(_, f)| f.is_finite() && *f <= OMNI.max_force + 1e-9));
    for w in rows.windows(2) {
        // Consecutive rows may be several ticks apart (lost poses are not rows): the rate limit per tick.
        let ticks = ((w[1].t - w[0].t) * 1000.0).round().max(1.0);
        assert!((w[1].felt - w[0].felt).norm() <= OMNI.max_force_rate * 1e-3 * ticks * 1.5 + 1e-9, "t {}: {:?} -> {:?}", w[1].t, w[0].felt, w[1].felt);
    }
    let before = felt.iter().filter(|(t, _)| (0.45..0.5).contains(t)).map(|x| x.1).fold(0.0, f64::max);
    let after = felt.iter().filter(|(t, _)| (0.53..0.56).contains(t)).map(|x| x.1).fold(f64::INFINITY, f64::min);
    eprintln!("felt before the pause {before:.3} N, just after it {after:.3} N; {} rows, {} answered", rows.len(), rows.iter().filter(|r| r.answered()).count());
    assert!(before > 0.5, "the wall is felt: {before} N");
    assert!((after - before).abs() <= 0.1 * before, "through the pause the felt force moved from {before} to {after} N");
}
