//! The simulated device and hand (`haptics::sim`, `coiffure device-sim`) over loopback against a UDP device
//! answering a constant force: the spring-pulled hand settles where the hand's spring balances the force
//! (analytic), the rigid hand follows the path exactly, and injected faults are answered as documented.

use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::sim::{self, Faults, Hand, Sent, SimParams, SimSummary};
use haptics::udp::{UdpDevice, UdpParams, FLAG_REJECTED};
use haptics::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

const OMNI: DeviceProfile = DeviceProfile::PHANTOM_OMNI;
const IDENTITY: Workspace = Workspace { scale: 1.0, offset: Vector3::new(0.0, 0.0, 0.0) };

/// A UDP device answering every pose with `force` (N) from a thread polling every 200 us; returns its address
/// and a stop flag.
fn constant_force_server(force: Vector3<f64>) -> (std::net::SocketAddr, Arc<AtomicBool>, std::thread::JoinHandle<()>) {
    let mut dev = UdpDevice::bind_with("127.0.0.1:0", UdpParams { workspace: IDENTITY, ..UdpParams::for_profile(&OMNI) }).unwrap();
    let addr = dev.local_addr().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let h = std::thread::spawn(move || {
        while !s.load(Ordering::Relaxed) {
            dev.read(0.0);
            dev.write(&DeviceCommand { force, torque: Vector3::zeros() });
            std::thread::sleep(Duration::from_micros(200));
        }
    });
    (addr, stop, h)
}

fn hold(p: Vector3<f64>) -> impl Fn(f64) -> DeviceReading {
    move |t| DeviceReading { time: t, position: p, rotation: Matrix3::identity(), buttons: 0 }
}

#[test]
fn a_spring_pulled_hand_settles_where_its_spring_balances_the_force() {
    // Path held at p0; the server pushes with F = 0.6 N along +x. Steady state of
    // m a = k_h (p0 - x) - (b_h + b_d) v + F: x = p0 + F / k_h = p0 + 2 mm (k_h 300 N/m). The hand is damped
    // (zeta 0.41, settling time about 0.12 s); after 0.4 s the positions sent agree within 2 % of the 2 mm.
    let f = Vector3::new(0.6, 0.0, 0.0);
    let (addr, stop, h) = constant_force_server(f);
    let p0 = Vector3::new(0.01, -0.02, 0.03);
    let params = SimParams { rate_hz: 1000.0, duration: 0.6, hand: Hand::Spring { stiffness: 300.0, damping: 3.0 }, profile: OMNI, workspace: IDENTITY, faults: Faults::default(), render: false };
    let rows = sim::run(addr, &hold(p0), &params).unwrap();
    stop.store(true, Ordering::Relaxed);
    h.join().unwrap();
    let late: Vec<_> = rows.iter().filter(|r| r.t > 0.4).collect();
    let expected = p0 + f / 300.0;
    let worst = late.iter().map(|r| (r.position - expected).norm()).fold(0.0, f64::max);
    println!("{}; settled within {worst:.2e} m of p0 + F/k = {expected:?}", SimSummary::of(&rows));
    assert!(late.len() > 150);
    assert!(worst < 0.02 * 0.002, "{worst} m from the analytic rest point");
    assert!(late.iter().all(|r| r.answered() && (r.force - f).norm() < 1e-12));
}

#[test]
fn the_rigid_hand_follows_the_path_and_faults_are_flagged() {
    let (addr, stop, h) = constant_force_server(Vector3::new(0.1, 0.0, 0.0));
    let path = |t: f64| DeviceReading { time: t, position: Vector3::new(0.05 * t, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 1 };
    let faults = Faults { nan_at: vec![0.1], teleport_at: vec![0.2], duplicate_at: vec![0.3], pause: vec![(0.35, 0.1)], ..Faults::default() };
    let params = SimParams { rate_hz: 500.0, duration: 0.5, hand: Hand::Rigid, profile: OMNI, workspace: IDENTITY, faults, render: false };
    let rows = sim::run(addr, &path, &params).unwrap();
    stop.store(true, Ordering::Relaxed);
    h.join().unwrap();
    let s = SimSummary::of(&rows);
    println!("{s}");
    for r in rows.iter().filter(|r| r.kind == Sent::Pose) {
        assert!((r.position.x - 0.05 * r.t).abs() < 1e-12, "rigid: exactly on the path");
    }
    for kind in [Sent::Nan, Sent::Teleport, Sent::Duplicate] {
        let r = rows.iter().find(|r| r.kind == kind).unwrap_or_else(|| panic!("{kind:?} sent"));
        assert!(r.answered() && r.flags & FLAG_REJECTED != 0 && r.force == Vector3::zeros(), "{kind:?}: {r:?}");
    }
    assert_eq!(s.rejected, 3);
    // (A row's t is when it was sent: a tick just before the pause may go out a little late on a busy machine.)
    assert!(rows.iter().all(|r| !(r.t >= 0.375 && r.t < 0.445)), "nothing sent during the pause");
    // 250 ticks less the 50 paused, all answered.
    assert!(s.sent >= 195 && s.sent <= 205, "{}", s.sent);
    assert_eq!(s.answered, s.sent);
    let csv = sim::to_csv(&rows);
    assert!(csv.starts_with("t,x,y,z,fx,fy,fz,latency_us,flags,hx,hy,hz\n") && csv.lines().count() == rows.len() + 1);
}
