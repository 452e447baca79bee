//! The CHAI3D bridge (bridges/chai3d, C++), built two ways:
//! - with its simulated device (`-DCOIFFURE_SIMULATED_DEVICE=ON`, no CHAI3D needed) and run against a UDP
//!   device on loopback: its packets are well formed and accepted, it gets its answers, and it applies the
//!   force with its safety ramp;
//! - against the real CHAI3D 3.3.0 device layer (`-DCHAI3D_SOURCE_DIR=../shared/vendor/chai3d-3.3.0`, with
//!   Force Dimension's libdrd) and run with no device attached: it must say that CHAI3D found no haptic device
//!   and exit non-zero.
//!
//! Needs cmake, a C++17 compiler and libusb-1.0's development files (`.ci/run` installs them), and
//! `../shared` beside the repository.

use haptics::coupling::{Coupling, CouplingParams, HairReaction};
use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading};
use haptics::haptic_loop::HapticLoop;
use haptics::udp::UdpDevice;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Configures and builds bridges/chai3d in `CARGO_TARGET_TMPDIR/<dir>` with the CMake options `defines`;
/// returns the bridge's path and CMake's configure output.
fn build_bridge(dir: &str, defines: &[String]) -> (PathBuf, String) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bridges/chai3d");
    let build = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    let run = |c: &mut Command, what: &str| -> String {
        let out = c.output().unwrap_or_else(|e| panic!("{what}: cannot run it ({e}); install cmake and a C++17 compiler (g++), e.g. with .ci/run"));
        let text = format!("{}\n{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success(), "{what} failed:\n{text}");
        text
    };
    let configured = run(Command::new("cmake").arg("-S").arg(&src).arg("-B").arg(&build).args(defines).arg("-DCMAKE_BUILD_TYPE=Release"), "cmake configure");
    run(Command::new("cmake").arg("--build").arg(&build).args(["-j", "2"]), "cmake --build");
    (build.join("coiffure-chai3d-bridge"), configured)
}

#[test]
fn the_simulated_chai3d_bridge_streams_and_applies_ramped_forces() {
    let (exe, _) = build_bridge("chai3d-bridge", &["-DCOIFFURE_SIMULATED_DEVICE=ON".to_string()]);
    // The Coiffure side: a 1 kHz loop with the coupling; the 'hair' is a wall 1 cm in front of where the
    // simulated hand holds the device (head frame y > -0.12 m, 2 kN/m), so the bridge gets a force back.
    let dev = UdpDevice::bind("127.0.0.1:0").unwrap();
    let addr = dev.local_addr().unwrap();
    let status = dev.status();
    let p = DeviceProfile::PHANTOM_OMNI;
    let mut c: Option<Coupling> = None;
    let step = move |r: Option<DeviceReading>, _t: f64, dt: f64| {
        let Some(r) = r else {
            c = None;
            return DeviceCommand::default();
        };
        let c = c.get_or_insert_with(|| Coupling::new(p, CouplingParams::for_profile(&p), r.position));
        // The wall as a local force model (its stiffness taken implicitly, as the engine renders hair): an explicit
        // 2 kN/m penalty chattered against the proxy when the loop caught up after a stall on a loaded host.
        let inside = c.proxy.y + 0.12 > 0.0;
        let wall = Vector3::new(0.0, -2000.0 * (c.proxy.y + 0.12).max(0.0), 0.0);
        let stiffness = if inside { nalgebra::Matrix3::from_diagonal(&Vector3::new(0.0, 2000.0, 0.0)) } else { nalgebra::Matrix3::zeros() };
        let hair = HairReaction { force: wall, position: c.proxy, velocity: c.proxy_velocity, stiffness, ..HairReaction::none() };
        let f = c.update_implicit(&r, dt, &hair).unwrap_or_default();
        DeviceCommand { force: f, torque: Vector3::zeros() }
    };
    let lp = HapticLoop::spawn(1000.0, dev, step, None).unwrap();
    let log = Path::new(env!("CARGO_TARGET_TMPDIR")).join("chai3d-bridge.csv");
    let mut child = Command::new(&exe)
        .args(["--server", &addr.to_string(), "--rate", "1000", "--duration", "1.5", "--ramp", "0.5", "--log"])
        .arg(&log)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The bridge must end by itself after its 1.5 s; 60 s is a hang.
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the bridge did not stop after --duration 1.5");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let (stats, _) = lp.stop();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    println!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success());
    let n = status.counts();
    println!("coiffure side: {n:?}; loop {stats:?}");
    let num = |key: &str| -> f64 { text.split(key).nth(1).and_then(|s| s.trim_start().split([' ', ',']).next()).and_then(|s| s.parse().ok()).unwrap_or_else(|| panic!("{key} in {text}")) };
    let (sent, answered) = (num("sent"), num("answered"));
    assert!(sent >= 1200.0, "about 1500 poses in 1.5 s at 1 kHz: {sent}");
    assert!(answered >= 0.9 * sent, "answered {answered} of {sent}");
    assert_eq!((num("rejected"), num("malformed")), (0.0, 0.0), "well-formed, plausible poses");
    assert_eq!(n.rejected_total() + n.malformed + n.foreign, 0, "{n:?}");
    assert!(n.accepted as f64 >= 0.95 * sent, "{n:?}");
    // The ramp: the applied force never exceeds ramp x the Omni's 3.3 N, starts at zero, and the wall is felt
    // once the ramp is done (tolerance 3e-6 N for the log's rounding to 1e-6: 3.3 x 5e-7 for the ramp, 5e-7
    // for each force component).
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(&log).unwrap().lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    let force = |r: &Vec<f64>| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt();
    assert_eq!(force(&rows[0]), 0.0);
    for r in &rows {
        assert!(force(r) <= r[7] * 3.3 + 3e-6, "t {}: {} N with ramp {}", r[0], force(r), r[7]);
    }
    let late = rows.iter().filter(|r| r[0] > 0.6).map(force).fold(0.0, f64::max);
    assert!(late > 0.1, "the wall is felt after the ramp: {late} N");
    // The force points towards the user (protocol y < 0): the wall pushes the tool back.
    assert!(rows.iter().filter(|r| r[0] > 0.6 && force(r) > 0.05).all(|r| r[5] < 0.0));
}

#[test]
fn the_bridge_built_on_the_real_chai3d_reports_that_no_device_is_attached() {
    // ../shared beside the repository holds CHAI3D 3.3.0's sources (read-only: the build is out of tree).
    let chai3d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/vendor/chai3d-3.3.0");
    assert!(
        chai3d.join("src/devices/CHapticDeviceHandler.cpp").exists(),
        "CHAI3D 3.3.0's sources are expected at {} (../shared beside the repository)",
        chai3d.display()
    );
    let chai3d = chai3d.canonicalize().unwrap();
    let (exe, configured) = build_bridge("chai3d-bridge-real", &[format!("-DCHAI3D_SOURCE_DIR={}", chai3d.display())]);
    assert!(configured.contains("CHAI3D's device layer from the sources"), "built against CHAI3D, not the simulated device:\n{configured}");
    // No device on this machine: CHAI3D's handler finds none, and the bridge says so and fails, before it
    // opens a socket (nothing listens on the port given).
    let started = std::time::Instant::now();
    let out = Command::new(&exe).args(["--server", "127.0.0.1:9", "--duration", "1"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("exit {:?} after {:?}: {stderr}", out.status.code(), started.elapsed());
    assert!(!out.status.success(), "no device attached, yet the bridge exited successfully");
    assert_eq!(out.status.code(), Some(1), "the bridge's exit code for a device it cannot open");
    assert!(stderr.contains("CHAI3D found no haptic device"), "the message names the cause: {stderr}");
    assert!(started.elapsed() < std::time::Duration::from_secs(30), "CHAI3D's device search must not hang");
}
