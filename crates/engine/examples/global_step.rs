//! Cost of the live session's global step (`engine::session::GlobalCore`) at a given number of render strands:
//! the lattice step alone, with the comb pushing the lattice, with the dryer's jet and drying, with the
//! sprayer wetting, one scissors cut of the render strands, and the step with the falling clusters after it.
//!
//! `cargo run --release -p coiffure-engine --example global_step -- [render strands, default 100000] [steps, default 200]`
//!
//! Wall times on whatever the machine gives (other work on it shows in them); medians and means over `steps`.

use engine::session::{GlobalCore, Scene, SceneOptions, SessionParams, Tool, ToolInput};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;
use std::time::Instant;

fn stats(mut t: Vec<f64>) -> (f64, f64, f64) {
    t.sort_by(f64::total_cmp);
    let mean = t.iter().sum::<f64>() / t.len().max(1) as f64;
    (t[t.len() / 2] * 1e3, mean * 1e3, t[t.len() * 95 / 100] * 1e3)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let strands: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    let t0 = Instant::now();
    let scene = Arc::new(Scene::builtin(&SceneOptions { render_strands: strands, ..SceneOptions::default() }).expect("scene"));
    println!("scene: {} render strands x {} vertices, {} guides, {} lattice nodes, built in {:.1} s", scene.render.strands(), scene.render.vertices_per_strand, scene.guides.len(), scene.lattice.node_count(), t0.elapsed().as_secs_f64());
    // Tool frame of the viewer looking at the back of the head: y down the hair, z towards the camera (-y).
    let rot = Matrix3::from_columns(&[Vector3::new(-1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, -1.0), Vector3::new(0.0, -1.0, 0.0)]);
    let params = SessionParams::default();
    let dt = 0.01;
    let at = |tool: Tool, pressed: bool, y: f64| ToolInput { tool, present: true, position: Vector3::new(0.0, y, -0.02), rotation: rot, pressed, cuts: 0, ..ToolInput::default() };
    let cases = [
        ("lattice only (no tool)", ToolInput::default()),
        ("comb in the hair (lattice obstacle)", at(Tool::Comb, false, -0.13)),
        ("dryer blowing and drying", at(Tool::Dryer, true, -0.15)),
        ("sprayer wetting", at(Tool::Sprayer, true, -0.15)),
    ];
    println!("{:<40} {:>10} {:>10} {:>10}", "global step (dt 10 ms)", "median ms", "mean ms", "p95 ms");
    for (name, input) in cases {
        let mut g = GlobalCore::new(scene.clone(), &params);
        let mut t = Vec::with_capacity(steps);
        for _ in 0..steps {
            let s = Instant::now();
            let _ = g.step(dt, &input);
            t.push(s.elapsed().as_secs_f64());
        }
        let (med, mean, p95) = stats(t);
        println!("{name:<40} {med:>10.2} {mean:>10.2} {p95:>10.2}");
    }
    // One scissors cut (through the hair at the back), then the steps with the clusters falling.
    let mut g = GlobalCore::new(scene.clone(), &params);
    for _ in 0..20 {
        g.step(dt, &ToolInput::default());
    }
    let cut = ToolInput { tool: Tool::Scissors, present: true, position: Vector3::new(0.0, -0.12, -0.06), rotation: rot, pressed: true, cuts: 1, ..ToolInput::default() };
    let s = Instant::now();
    let _ = g.step(dt, &cut);
    let with_cut = s.elapsed().as_secs_f64();
    let rep = g.last_cut.expect("cut");
    println!("scissors cut: {} strands cut, {} pieces to clusters, cut {:.2} ms, whole step with the cut {:.2} ms; mass before {:.3e} kg = kept {:.3e} + pieces {:.3e} (rel. error {:.1e})",
        rep.strands, rep.pieces, rep.seconds * 1e3, with_cut * 1e3, rep.mass_before, rep.mass_kept, rep.mass_pieces, ((rep.mass_kept + rep.mass_pieces) / rep.mass_before - 1.0).abs());
    let mut t = Vec::with_capacity(steps);
    let idle = ToolInput { cuts: 1, present: false, ..cut };
    for _ in 0..steps {
        let s = Instant::now();
        let _ = g.step(dt, &idle);
        t.push(s.elapsed().as_secs_f64());
    }
    let (med, mean, p95) = stats(t);
    let snap = g.snapshot();
    let points: usize = snap.chains.iter().map(|c| c.len()).sum();
    println!("{:<40} {med:>10.2} {mean:>10.2} {p95:>10.2}", "with the falling clusters");
    println!("falling chains: {} chains, {} points ({} bytes in FRAME); cluster energy after {:.1} s: {:.3e} J", snap.chains.len(), points, 4 * snap.chains.len() + 12 * points, steps as f64 * dt, g.cluster_energy());
}
