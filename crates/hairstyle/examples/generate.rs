//! Generates the default hairstyle and prints counts, timing and checks; optionally writes it.
//! `cargo run --release -p coiffure-hairstyle --example generate [-- OUT.hair [curliness]]`
use hairstyle::{Hairstyle, HairstyleParams};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut params = HairstyleParams::default();
    if let Some(c) = args.get(2) {
        params.curliness = c.parse().expect("curliness must be a number");
    }
    let t = Instant::now();
    let mesh = hairstyle::Head::new(params.head).unwrap().mesh();
    println!(
        "head mesh: {} vertices, {} triangles in {:.3} s",
        mesh.positions.len(),
        mesh.triangle_count(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let h = match Hairstyle::generate(&params) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let el = t.elapsed().as_secs_f64();
    let unstable = h.guides.iter().filter(|g| !g.stable).count();
    let (lo, hi) = h.bounds();
    println!(
        "{} guides ({} unstable), {} render strands x {} vertices in {:.2} s on {} threads; bounds {:?} .. {:?}",
        h.guides.len(),
        unstable,
        h.render.len(),
        h.render.vertices_per_strand,
        el,
        rayon::current_num_threads(),
        lo.coords.as_slice(),
        hi.coords.as_slice()
    );
    if let Some(out) = args.get(1) {
        hairstyle::write_file(std::path::Path::new(out), &h.to_curves()).expect("write");
        println!("wrote {out}");
    }
}
