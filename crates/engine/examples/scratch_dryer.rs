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
