//! How the global layer moves: the built-in hairstyle's lattice under a hand-held dryer and a head turn.
//! Prints the largest displacement of the guides' points carried by the head and the lattice (relative to the head, m)
//! over time. Run: `cargo run --release -p coiffure-engine --example global_motion [-- STRANDS [side]]`
//! (`side`: the dryer at the right side of the head, the live-dryer scenario's place, instead of behind it).

use engine::global::GlobalCore;
use engine::params::SessionParams;
use engine::scene::{Scene, SceneOptions};
use engine::tool::{Tool, ToolInput};
use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use std::sync::Arc;

fn displacement(core: &GlobalCore, settled: &[Vector3<f64>]) -> f64 {
    let s = core.scene();
    let inv = core.head_pose().inverse();
    let head = core.head_pose();
    let pts = (0..s.guides.len()).flat_map(|g| s.guide_points(core.positions(), &head, g));
    pts.zip(settled).map(|(p, q)| ((inv * nalgebra::Point3::from(p)).coords - q).norm()).fold(0.0, f64::max)
}

fn main() {
    let strands: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(20000);
    let t0 = std::time::Instant::now();
    let scene = Arc::new(Scene::builtin(&SceneOptions { render_strands: strands, ..SceneOptions::default() }).unwrap());
    println!("scene: {} nodes (cell {:.3} m), hair weight {:.3} N, built in {:.2} s", scene.lattice.node_count(), scene.lattice.ffd.h, scene.lattice.total_mass() * 9.81, t0.elapsed().as_secs_f64());
    let params = SessionParams::default();
    let dt = 1.0 / params.global_rate_hz;
    let settled: Vec<Vector3<f64>> = scene.guides.iter().flat_map(|g| g.reference.iter().copied()).collect();
    // 1. rest: 5 s
    let mut core = GlobalCore::new(scene.clone(), &params);
    for _ in 0..(5.0 / dt) as usize {
        core.step(dt, &ToolInput::default());
    }
    println!("rest: after 5 s, largest guide-point distance from the groomed shape {:.4} m", displacement(&core, &settled));
    // 2. dryer behind the head (the live-dryer scenario's pose) 2 s on, 2.3 s off
    let mut core = GlobalCore::new(scene.clone(), &params);
    let side = std::env::args().nth(2).as_deref() == Some("side");
    let rot = if side { Rotation3::new(Vector3::new(2.2214415, 0.0, 2.2214415)).into_inner() } else { Rotation3::new(Vector3::new(0.0, 2.2214415, -2.2214415)).into_inner() };
    let mut input = ToolInput { tool: Tool::Dryer, present: true, position: if side { Vector3::new(0.118, 0.0, 0.0) } else { Vector3::new(0.0, -0.118, 0.0) }, rotation: rot, pressed: true, cuts: 0, ..ToolInput::default() };
    let (mut peak, mut line) = (0.0f64, String::new());
    for k in 0..(4.3 / dt) as usize {
        input.pressed = (k as f64) * dt < 2.0;
        core.step(dt, &input);
        let d = displacement(&core, &settled);
        peak = peak.max(d);
        if k % 20 == 19 {
            line += &format!(" {:.1}s:{:.1}mm/{:.3}N", (k + 1) as f64 * dt, d * 1e3, core.blow_force());
        }
    }
    println!("dryer 2 s: peak {:.4} m, final {:.4} m\n  {line}", peak, displacement(&core, &settled));
    // 3. head turn 30 deg about z in 0.3 s (smooth), then hold 2.7 s
    let mut core = GlobalCore::new(scene.clone(), &params);
    let (mut peak, mut line) = (0.0f64, String::new());
    for k in 0..(3.0 / dt) as usize {
        let t = (k + 1) as f64 * dt;
        let u = (t / 0.3).min(1.0);
        let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        let head = Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&Vector3::z_axis(), s * 30f64.to_radians()));
        core.step(dt, &ToolInput { head, ..ToolInput::default() });
        let d = displacement(&core, &settled);
        peak = peak.max(d);
        if k % 10 == 9 {
            line += &format!(" {:.1}s:{:.1}mm", t, d * 1e3);
        }
    }
    println!("head turn 30 deg in 0.3 s: peak {:.4} m, final {:.4} m\n  {line}", peak, displacement(&core, &settled));
}
