//! How the stable grooms (`hairstyle::groom`) change the guides of a hairstyle, and what they cost: for the
//! default scene's configuration (200 guides x 8 segments) and the generator's defaults (300 x 12), the guides
//! kept in their combing plane, turned to hang down, or groomed in a plane nearer the vertical; how far each
//! moved from the combing-plane groom (largest distance of a centreline point, 33 samples); generation time of
//! the guides alone (10 render strands), best of 5. Run:
//! `cargo run --release -p coiffure-hairstyle --example guide_groom`
use hairstyle::groom::{groom_directions, groomed_state};
use hairstyle::{Hairstyle, HairstyleParams};
use rayon::prelude::*;
use std::time::Instant;

fn main() {
    for (guides, segments) in [(200, 8), (300, 12)] {
        let p = HairstyleParams { guide_count: guides, guide_segments: segments, render_count: 10, ..Default::default() };
        let mut best = f64::INFINITY;
        let mut h = None;
        for _ in 0..5 {
            let t = Instant::now();
            h = Some(Hairstyle::generate(&p).unwrap());
            best = best.min(t.elapsed().as_secs_f64());
        }
        let h = h.unwrap();
        // the cost of the combing-plane groom alone (the generator before the stable grooms), same threads
        let mut plane_only = f64::INFINITY;
        for _ in 0..5 {
            let t = Instant::now();
            let n: usize = h.guides.par_iter().map(|g| {
                let mut straight = g.model.clone();
                straight.rest.iter_mut().for_each(|r| *r = nalgebra::Vector3::zeros());
                let f0 = groom_directions(&p, &g.root, f64::INFINITY)[0];
                let s = groomed_state(&p, &h.head, &straight, &g.root, &f0, None).unwrap();
                strand::statics::sag_free_rest(&straight, &s, &[]).unwrap().1 as usize
            }).sum();
            plane_only = plane_only.min(t.elapsed().as_secs_f64());
            assert!(n <= guides);
        }
        let (mut kept, mut turned, mut other) = (0, 0, 0);
        let mut moved: Vec<f64> = Vec::new();
        for g in &h.guides {
            let mut straight = g.model.clone();
            straight.rest.iter_mut().for_each(|r| *r = nalgebra::Vector3::zeros());
            let f0 = groom_directions(&p, &g.root, f64::INFINITY)[0];
            let plane = groomed_state(&p, &h.head, &straight, &g.root, &f0, None).unwrap();
            let d = strand::kinematics::centerline(&straight, &plane, 33).iter().zip(g.samples(33)).map(|((_, a), b)| (a - b.coords).norm()).fold(0.0, f64::max);
            if d < 1e-12 {
                kept += 1;
            } else if g.state.q.iter().step_by(2).any(|t| *t != 0.0) {
                turned += 1;
            } else {
                other += 1;
            }
            moved.push(d);
        }
        moved.sort_by(|a, b| a.total_cmp(b));
        let changed: Vec<f64> = moved.iter().copied().filter(|d| *d > 1e-12).collect();
        let mean = changed.iter().sum::<f64>() / changed.len().max(1) as f64;
        let unstable = h.guides.iter().filter(|g| !g.stable).count();
        println!(
            "{guides} x {segments}: {unstable} unstable; {kept} in the combing plane, {turned} turned to hang down, {other} in a plane nearer the vertical (or relaxed); changed guides moved {:.1} cm on average, median {:.1} cm, largest {:.1} cm; hairstyle generated in {:.0} ms (best of 5, {} threads; the combing-plane grooms alone take {:.0} ms)",
            mean * 100.0,
            changed.get(changed.len() / 2).copied().unwrap_or(0.0) * 100.0,
            moved.last().copied().unwrap_or(0.0) * 100.0,
            best * 1e3,
            rayon::current_num_threads(),
            plane_only * 1e3
        );
    }
}
