//! Issue 34 in the hairstyle crate: guides chosen among a file's strands, and follow strands around them.
use hairstyle::fit::{FitParams, ScalpIndex};
use hairstyle::fitted::{guides_from_curves, spread_over, GuideFitParams};
use hairstyle::follow::{follow_strands, FollowParams};
use hairstyle::formats::HairCurves;
use hairstyle::{Hairstyle, HairstyleParams, Head};
use nalgebra::{Point3, Vector3};

fn p64(p: &[f32; 3]) -> Point3<f64> {
    Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// Farthest-point sampling over a 30 x 30 grid of 1 cm spacing: every budget from 1 to 60 gives distinct
/// points, all of them when the budget is as large, and spreads them: the largest distance from any grid point
/// to the nearest chosen one is at most twice that of a square grid of the budget's size (a grid of
/// sqrt(budget) points a side covers the square to half its cell's diagonal): farthest-point sampling is
/// within twice the best covering (Gonzalez 1985), which is no worse than that grid's.
#[test]
fn guides_are_spread_over_the_roots() {
    let roots: Vec<Point3<f64>> = (0..900).map(|i| Point3::new((i % 30) as f64 * 0.01, (i / 30) as f64 * 0.01, 0.0)).collect();
    let all: Vec<usize> = (0..900).collect();
    for budget in [4, 9, 16, 25, 36, 49] {
        let chosen = spread_over(&roots, &all, budget);
        let mut sorted = chosen.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), budget);
        let cover = roots.iter().map(|r| chosen.iter().map(|&c| (roots[c] - r).norm()).fold(f64::INFINITY, f64::min)).fold(0.0, f64::max);
        let side = (budget as f64).sqrt();
        let ideal = 0.29 / side / 2.0 * 2f64.sqrt();
        assert!(cover <= 2.0 * ideal, "budget {budget}: covering radius {cover} m, a grid's {ideal} m");
    }
    assert_eq!(spread_over(&roots, &all[..10], 20), (0..10).collect::<Vec<_>>());
    assert!(spread_over(&roots, &all, 0).is_empty());
}

/// Loose strands (roots 5 cm off the scalp) and too short ones are never guides; the rooted strands of a
/// generated hairstyle are, up to the budget, and each guide starts at its strand's root (1e-9 m) with the
/// strand's length (1e-9 relative).
#[test]
fn only_strands_rooted_on_the_scalp_become_guides() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 200, guide_count: 30, render_vertices: 16, ..Default::default() }).unwrap();
    let mut curves = h.to_curves();
    let rooted = curves.strands.len();
    for k in 0..40 {
        let mut s = curves.strands[k].clone();
        let n = p64(&s[0]).coords.normalize() * 0.05;
        for p in &mut s {
            *p = [p[0] + n.x as f32, p[1] + n.y as f32, p[2] + n.z as f32];
        }
        curves.strands.push(s);
    }
    curves.strands.push(vec![curves.strands[0][0], curves.strands[0][0]]);
    let head = Head::default();
    let params = HairstyleParams { guide_segments: 8, ..Default::default() };
    for budget in [20, 1000] {
        let fitted = guides_from_curves(&curves, &params, &head, &GuideFitParams { budget, ..Default::default() }).unwrap();
        assert_eq!(fitted.len(), budget.min(rooted), "budget {budget}");
        for f in &fitted {
            assert!(f.strand < rooted, "strand {} is loose or empty", f.strand);
            let s = &curves.strands[f.strand];
            let length: f64 = s.windows(2).map(|w| (p64(&w[1]) - p64(&w[0])).norm()).sum();
            assert!((f.guide.state.root.position - p64(&s[0]).coords).norm() < 1e-9);
            assert!((f.guide.model.length - length).abs() < 1e-9 * length);
        }
    }
}

/// Follow strands of a generated hairstyle's strands: `per_strand` around each strand rooted on the scalp
/// (none around a loose one), each root within the strand's share of the scalp (radius sqrt(A / (pi n))) of
/// its strand's root and at its height over the scalp (0.5 mm), no vertex inside the body, and the offset from
/// the strand growing to (1 + tip_spread) times the root's at the tip where nothing pushed it (tips outside the
/// body by 5 mm, within 0.5 mm). Deterministic for a seed.
#[test]
fn follow_strands_surround_their_strand_and_fan_out() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 100, guide_count: 30, render_vertices: 12, ..Default::default() }).unwrap();
    let mut curves: HairCurves = h.to_curves();
    let loose: Vec<[f32; 3]> = curves.strands[0].iter().map(|p| [p[0], p[1], p[2] + 0.06]).collect();
    curves.strands.push(loose);
    let head = Head::default();
    let scalp = ScalpIndex::new(&head, FitParams::default().scalp_samples);
    let p = FollowParams { per_strand: 5, tip_spread: 1.0, seed: 3 };
    let f = follow_strands(&curves.strands, &head, &scalp, 0.01, &p);
    assert_eq!(f.len(), 100 * 5, "five around each rooted strand, none around the loose one");
    assert_eq!(f, follow_strands(&curves.strands, &head, &scalp, 0.01, &p));
    let area = scalp.spacing * scalp.spacing * scalp.samples().len() as f64;
    let radius = (area / (std::f64::consts::PI * 100.0)).sqrt();
    let mut checked = 0;
    for (i, s) in curves.strands[..100].iter().enumerate() {
        for fs in &f[i * 5..(i + 1) * 5] {
            let (r, fr) = (p64(&s[0]), p64(&fs[0]));
            assert!((fr - r).norm() <= radius * 1.05 + 1e-3, "strand {i}: follow root {} m away, radius {radius} m", (fr - r).norm());
            assert!((head.signed_distance(&fr) - head.signed_distance(&r)).abs() < 5e-4, "strand {i}: root height");
            assert!(fs.iter().skip(1).all(|q| !head.inside(&p64(q))), "strand {i}: inside the body");
            let (tip, ftip) = (p64(s.last().unwrap()), p64(fs.last().unwrap()));
            if head.signed_distance(&ftip) > 5e-3 && head.signed_distance(&tip) > 5e-3 {
                let root_offset: Vector3<f64> = fr - r;
                let tangential = root_offset - scalp.nearest(&r).sample.normal * scalp.nearest(&r).sample.normal.dot(&root_offset);
                let want = tip + (fr - r) + tangential * p.tip_spread;
                assert!((ftip - want).norm() < 5e-4, "strand {i}: tip {} m from the fanned-out tip", (ftip - want).norm());
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked} tips checked");
}
