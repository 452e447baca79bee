//! Torque from the hair to the hand (issue 31): a `[live]` scenario holds the brush in the back hair, its handle
//! upright and its bristles into the hair, and twists it about its handle one way and back. The hand must feel a
//! torque that opposes the twist, within the 6-DOF profile's limit, and none on a 3-DOF profile.

use engine::scenario::{LiveScenario, LiveSpec, LiveTool, LiveWaypoint};
use engine::scene::Scene;
use haptics::device::DeviceProfile;
use nalgebra::{Matrix3, Rotation3, Vector3};
use std::sync::Arc;

/// The brush's rest orientation: its handle (tool x) upright along world +z, its bristles (tool -z) along +y
/// into the back hair, tool y along -x.
fn upright() -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[Vector3::z(), -Vector3::x(), -Vector3::y()]))
}

/// The twist's schedule, s: in the hair at `IN`, twisted by `angle` from `TWIST` over `length` s, held,
/// twisted back over as long from `back`, then held to the end.
const IN: f64 = 0.25;
const TWIST: f64 = 0.35;

/// A scenario on `device` and `hair`: the brush comes into the hair 11 cm behind the head's centre (bristle tips
/// at 9.5 cm) and is turned about its handle by `angle` rad at `rate` rad/s, held 0.15 s, turned back, held.
fn twist(device: &str, hair: &str, angle: f64, rate: f64) -> (LiveScenario, f64, f64) {
    let length = angle.abs() / rate;
    let back = TWIST + length + 0.15;
    let end = back + length + 0.15;
    let at = |t: f64| -> f64 {
        if t <= TWIST {
            0.0
        } else if t <= TWIST + length {
            angle * (t - TWIST) / length
        } else if t <= back {
            angle
        } else if t <= back + length {
            angle * (1.0 - (t - back) / length)
        } else {
            0.0
        }
    };
    let point = [0.0, -0.11, 0.0];
    let mut path = vec![LiveWaypoint { t: 0.0, position: [0.0, -0.16, 0.0], rotation: upright().scaled_axis().into(), pressed: false }];
    // Waypoints every 5 ms: the rotation vectors are interpolated linearly between them, close to the twist.
    let mut t = IN;
    while t <= end + 1e-9 {
        let r = upright() * Rotation3::from_axis_angle(&Vector3::x_axis(), at(t));
        path.push(LiveWaypoint { t, position: point, rotation: r.scaled_axis().into(), pressed: false });
        t += 0.005;
    }
    let live = LiveSpec { render_strands: 2000, guides: 60, device: device.into(), hair_type: hair.into(), ..LiveSpec::default() };
    let s = LiveScenario { name: Some("brush-twist".into()), settle: 0.2, duration: Some(end + 0.05), live, tool: LiveTool { shape: "brush".into(), path } };
    (s, length, back)
}

#[test]
fn a_brush_twisted_in_the_hair_gives_a_torque_opposing_the_twist() {
    // Family: three hair types x both directions x two twist rates (2 and 6 rad/s, 0.5 rad each way) on the
    // Phantom Premium 1.5 6-DOF profile. In each twisting phase the torque about the handle (world z) opposes
    // the turning: its mean has the opposite sign to the angular velocity, and the work the hand does on the hair
    // (minus the integral of torque . angular velocity) is positive. Every step's torque is within the profile's
    // 0.188 N m. The same runs on the 3-DOF Phantom Omni and omega.3 send no torque at all (exactly zero) while
    // their forces are those of a brush in the hair (peak above 1 mN).
    let p6 = DeviceProfile::PHANTOM_PREMIUM_6DOF;
    let mut weakest: f64 = f64::INFINITY;
    let mut peak: f64 = 0.0;
    for hair in ["caucasian", "asian", "african"] {
        let (probe, _, _) = twist("phantom-premium-6dof", hair, 0.5, 2.0);
        let scene: Arc<Scene> = Arc::new(probe.scene_in(std::path::Path::new(".")).unwrap());
        for angle in [0.5, -0.5] {
            for rate in [2.0, 6.0] {
                let (s, length, back) = twist("phantom-premium-6dof", hair, angle, rate);
                let (trace, summary) = s.run_on(scene.clone()).unwrap();
                assert_eq!((summary.rejected_readings, summary.failed_steps), (0, 0));
                let dt = trace.t[1] - trace.t[0];
                for phase in [(TWIST, angle.signum()), (back, -angle.signum())] {
                    let (from, sign) = phase;
                    let steps: Vec<usize> = (0..trace.len()).filter(|&i| trace.t[i] > from + dt && trace.t[i] < from + length).collect();
                    assert!(steps.len() >= 5, "{hair} {angle} {rate}: {} twisting steps", steps.len());
                    let axial: f64 = steps.iter().map(|&i| trace.tz[i]).sum::<f64>() / steps.len() as f64;
                    let work: f64 = steps.iter().map(|&i| -trace.tz[i] * sign * rate * dt).sum();
                    eprintln!("{hair} angle {angle} rate {rate} phase at {from:.3} s: mean axial torque {axial:.3e} N m (twist sign {sign}), work on the hair {work:.3e} J");
                    assert!(axial * sign < 0.0, "{hair} angle {angle} rate {rate}: the torque {axial} N m does not oppose the twist ({sign})");
                    assert!(work > 0.0, "{hair} angle {angle} rate {rate}: work {work} J");
                    weakest = weakest.min(-axial * sign);
                }
                for i in 0..trace.len() {
                    let tau = Vector3::new(trace.tx[i], trace.ty[i], trace.tz[i]).norm();
                    assert!(tau <= p6.max_torque + 1e-12, "{hair}: {tau} N m at step {i}");
                    peak = peak.max(tau);
                }
            }
        }
        for device in ["phantom-omni", "omega3"] {
            let (s, _, _) = twist(device, hair, 0.5, 6.0);
            let (trace, _) = s.run_on(scene.clone()).unwrap();
            assert!(trace.tx.iter().chain(&trace.ty).chain(&trace.tz).all(|&x| x == 0.0), "{device}: a 3-DOF device gets no torque");
            let f = (0..trace.len()).map(|i| trace.force(i).norm()).fold(0.0, f64::max);
            assert!(f > 1e-3, "{device} {hair}: the brush in the hair gives a force ({f} N)");
        }
    }
    eprintln!("weakest mean opposing torque {weakest:.3e} N m, peak torque {peak:.3e} N m (limit {} N m)", p6.max_torque);
}
