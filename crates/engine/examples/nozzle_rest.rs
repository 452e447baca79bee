//! Diagnostic (issue 12, open): the live dryer scenario (examples/scenarios/live-dryer.toml) with the dryer held
//! at the side of the hair but NOT blowing, with hair-hair contact off and on, and with the tool far away. Measured
//! 2026-11-24 22:30 UTC (stable grooms): off, guides move 8.4 mm (the lattice; the local strands do not move);
//! on, 13.4 cm (strand speed up to 0.8 m/s) and back within 4.9 mm at the end; tool far away, 8.5 um. The
//! simulated guides' groomed centrelines overlap (68 guide pairs of the default scene closer than 1.1 mm, the
//! contact distance of a 100-fibre wisp): activated together, their contacts push them apart. Run:
//! `cargo run --release -p coiffure-engine --example nozzle_rest`
use engine::scenario::live::LiveScenario;
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
}
