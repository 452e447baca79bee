//! Diagnostic (issue 12): the live dryer scenario (examples/scenarios/live-dryer.toml) with the dryer held at the
//! side of the hair but NOT blowing, with hair-hair contact off and on, and with the tool far away. Measured
//! 2026-11-24 22:30 UTC (stable grooms): off, guides move 8.4 mm (the lattice; the local strands do not move);
//! on, 13.4 cm (strand speed up to 0.8 m/s) and back within 4.9 mm at the end; tool far away, 8.5 um. The
//! simulated guides' groomed centrelines overlap (68 guide pairs of the default scene closer than 1.1 mm, the
//! contact distance of a 100-fibre wisp): activated together, their contacts pushed them apart. Checked without
//! the session: the 26 guides within 6 cm of the dryer's point, stepped alone from their grooms (no tool, no
//! body) in one `LocalInteraction`: 12 hair pairs at the first step and 9.9 cm displacement in 1.5 s with contact
//! (100 fibres per strand), 0 without. Fixed by `HapticParams::groomed_overlap` (default on): each joining strand's
//! groomed shape is its rest shape for hair-hair contact (`LocalInteraction::set_rest_shape`), overlapping wisps
//! keep their groomed overlap. Measured 22:57 UTC: contact on, 8.4 mm, as off; the 26 guides with rest shapes,
//! 0.0000 m. Run:
//! `cargo run --release -p coiffure-engine --example nozzle_rest`
use engine::scenario::live::LiveScenario;
use engine::scene::{Scene, SceneOptions};
use tools::interaction::{ForceModel, HairContact, LocalInteraction};
fn main() {
    let mut s: LiveScenario = toml::from_str(include_str!("../../../examples/scenarios/live-dryer.toml")).unwrap();
    s.tool.path.iter_mut().for_each(|w| w.pressed = false);
    for hc in [false, true] {
        s.live.hair_contact = hc;
        let (_, m) = s.run().unwrap();
        println!("hair_contact {hc}: {m:?}");
    }
    let mut none = s.clone();
    none.tool.path.iter_mut().for_each(|w| w.position[0] = 0.5);
    let (_, m) = none.run().unwrap();
    println!("tool far away, hair_contact {}: {m:?}", none.live.hair_contact);
    // the same guides alone, from their grooms, with and without hair-hair contact
    let opts = SceneOptions { render_strands: 20000, ..SceneOptions::default() };
    let scene = Scene::builtin(&opts).unwrap();
    // the guides whose points come within 6 cm of the dryer's tool point (0.13, 0, 0)
    let c = nalgebra::Vector3::new(0.13, 0.0, 0.0);
    let near: Vec<usize> = scene.guides.iter().enumerate().filter(|(_, g)| g.reference.iter().any(|p| (p - c).norm() < 0.06)).map(|(i, _)| i).take(64).collect();
    for (fibres, rest) in [(0.0, false), (100.0, false), (100.0, true)] {
        let strands: Vec<strand::Strand> = near.iter().map(|&i| { let g = &scene.guides[i]; let mut m = g.model.clone(); m.air_drag = m.air_drag.max(2e-5); let mut s = strand::Strand::new(m, g.state.root.clone()).unwrap(); s.state.q.copy_from(&g.state.q); s }).collect();
        let far = tools::contact::ToolPose { position: nalgebra::Vector3::new(5.0, 5.0, 5.0), rotation: nalgebra::Matrix3::identity() };
        let mut it = LocalInteraction::new(strands, tools::shape::ToolShape::builtin("comb").unwrap(), far, ForceModel::Constraint { friction: 0.2, options: Default::default() });
        if fibres > 0.0 { it.params.hair_contact = Some(HairContact { fibres, ..Default::default() }); }
        if rest { for k in 0..near.len() { let r = it.strands[k].clone(); it.set_rest_shape(k, &r); } }
        let mut worst = 0.0f64; let mut pairs = 0;
        for n in 0..1500 {
            let r = it.step(1e-3, far).unwrap();
            if n == 0 { pairs = r.hair_pairs; }
            if n % 10 == 9 { for (k, &i) in near.iter().enumerate() { let now = strand::kinematics::centerline(&it.strands[k].model, &it.strands[k].state, 16); for ((_, p), q) in now.iter().zip(&scene.guides[i].reference) { worst = worst.max((p - q).norm()); } } }
        }
        println!("{} guides near the dryer, fibres {fibres}, groomed rest shapes {rest}: {pairs} hair pairs at the first step; largest displacement in 1.5 s {worst:.4} m", near.len());
    }
}
