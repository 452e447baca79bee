//! The lattice carrying a hairstyle: node masses and attachment.

use hairstyle::{Hairstyle, HairstyleParams};
use lattice::lattice::{CarryParams, LatticeParams};

fn style() -> Hairstyle {
    Hairstyle::generate(&HairstyleParams {
        guide_count: 80,
        render_count: 3000,
        seed: 21,
        ..Default::default()
    })
    .unwrap()
}

/// Node masses carry the hair: their sum is the hair's mass (render vertex masses; the B-spline
/// weights sum to 1) plus the small empty-node mass, to 1e-12 relative; nodes inside the head are
/// fully attached and nodes far from it free.
#[test]
fn lattice_carries_the_hair_mass() {
    let h = style();
    let carry = CarryParams::default();
    let hl = h.lattice(&carry, LatticeParams::default()).unwrap();
    let hair: f64 = h.render_vertex_masses().unwrap().iter().sum();
    let n = hl.model.node_count();
    let expected = hair + n as f64 * carry.empty_node_mass;
    assert!((hl.model.total_mass() - expected).abs() < 1e-12 * expected);
    // 3000 caucasian hairs of ~0.19 m: about 3000 x 0.19 x 1300 x pi (40e-6)^2 ~ 4e-3 kg
    assert!(hair > 1e-3 && hair < 1e-2, "{hair} kg");
    let t = hl.model.params.metaball.threshold;
    let mut inside = 0;
    for (x, a) in hl.model.rest.iter().zip(&hl.model.attachment) {
        if h.head.body.field(x) > t {
            assert_eq!(*a, 1.0);
            inside += 1;
        }
        if h.head.signed_distance(x) > carry.attach_distance + carry.attach_falloff {
            assert_eq!(*a, 0.0);
        }
    }
    assert!(inside > 10);
    assert_eq!(hl.binding.len(), h.render.positions.len());
}
