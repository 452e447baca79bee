//! The load of a hairstyle file as `coiffure serve`'s LOAD does it (issue 34): read, placed on the head
//! (`hairstyle::fit`), guides fitted to its strands and follow strands (`Scene::load`), with the time of each
//! stage. The file: a generated groom of STRANDS strands of 32 points (25 cm, wavy), written as TressFX in
//! centimetres, y up (Maya's frame), as a guide-only TressFX file.
//!
//! `cargo run --release -p coiffure-engine --example load_bench -- [STRANDS=10000] [GUIDES=200] [RENDER=100000]`
use engine::scene::{Scene, SceneOptions};
use hairstyle::fit::{axes_rotation, read_and_fit, transform_curves, Axis, FitOptions, Similarity};
use hairstyle::formats::Format;
use std::time::Instant;

fn main() {
    let arg = |i: usize, d: usize| std::env::args().nth(i).map_or(d, |a| a.parse().expect("a count"));
    let (strands, guides, render) = (arg(1, 10_000), arg(2, 200), arg(3, 100_000));
    let h = hairstyle::Hairstyle::generate(&hairstyle::HairstyleParams { render_count: strands, guide_count: 100, render_vertices: 32, length: 0.25, curliness: 0.2, ..Default::default() }).unwrap();
    let mut curves = h.to_curves();
    transform_curves(&mut curves, &Similarity { scale: 100.0, rotation: axes_rotation(Axis::PosY, Axis::PosZ).transpose(), translation: nalgebra::Vector3::new(3.0, 160.0, -2.0) });
    let bytes = Format::Tfx.write(&curves).unwrap();
    let opts = SceneOptions { guides, render_strands: render, ..SceneOptions::default() };
    let t0 = Instant::now();
    let (placed, fit) = read_and_fit(Format::Tfx, &bytes, &FitOptions::default(), &opts.load).unwrap();
    let t_fit = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let (scene, report) = Scene::load(&placed, &opts).unwrap();
    let t_scene = t1.elapsed().as_secs_f64();
    let total = t0.elapsed().as_secs_f64();
    println!("file: {strands} strands x 32 points, {} bytes (.tfx, cm, y up); units {} m/unit, {:.1} % rooted", bytes.len(), fit.meters_per_unit, 100.0 * fit.rooted);
    println!("scene: {} drawn strands, {} guides, {} lattice nodes; {}", scene.render.strands(), scene.guides.len(), scene.lattice.node_count(), report.summary());
    println!("time: read + fit to the head {t_fit:.2} s, scene (guides, follow strands, binding, lattice) {t_scene:.2} s, total {total:.2} s (LoadLimits: {} strands, {} s)", opts.load.max_strands, opts.load.max_seconds);
}
