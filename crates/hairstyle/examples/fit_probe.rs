//! Fits a hair file onto the head and prints the report (diagnostics):
//! `cargo run --release -p coiffure-hairstyle --example fit_probe -- FILE`, or with `--roundtrip`
//! a generated hairstyle moved to y up, facing +z, centimetres.
use hairstyle::fit::{fit, Axis, FitOptions, FitParams, Similarity};
use hairstyle::{Hairstyle, HairstyleParams, Head};
use nalgebra::{Point3, Vector3};
fn main() {
    let arg = std::env::args().nth(1).expect("a hair file or --roundtrip");
    let (c, format, meta, truth) = if arg == "--roundtrip" {
        let h = Hairstyle::generate(&HairstyleParams { render_count: 3000, guide_count: 100, ..Default::default() }).unwrap();
        let c = h.to_curves();
        let r = hairstyle::fit::axes_rotation(Axis::PosY, Axis::PosZ).transpose();
        let t = Similarity { scale: 100.0, rotation: r, translation: Vector3::new(12.0, 150.0, -7.0) };
        let mut moved = c.clone();
        hairstyle::fit::transform_curves(&mut moved, &t);
        (moved, hairstyle::formats::Format::Hair, Default::default(), Some(c))
    } else {
        let (c, f, m) = hairstyle::formats::read_file_with_metadata(&arg).unwrap();
        (c, f, m, None)
    };
    let t0 = std::time::Instant::now();
    let mut opts = FitOptions::default();
    if let Some(u) = std::env::args().nth(2) {
        opts.up = Some(Axis::parse(&u).unwrap());
        opts.front = Some(Axis::parse(&std::env::args().nth(3).unwrap()).unwrap());
    }
    let (out, r) = fit(&c, Some(format), &meta, &opts, &Head::default(), &FitParams::default()).unwrap();
    println!("{r:#?}\n{:.2} s", t0.elapsed().as_secs_f64());
    if let Some(truth) = truth {
        let mut d: Vec<f64> = truth.strands.iter().zip(&out.strands).map(|(a, b)| {
            (Point3::new(a[0][0] as f64, a[0][1] as f64, a[0][2] as f64) - Point3::new(b[0][0] as f64, b[0][1] as f64, b[0][2] as f64)).norm()
        }).collect();
        d.sort_by(f64::total_cmp);
        println!("root error vs original: median {:.2} mm, p95 {:.2} mm, max {:.2} mm", 1e3 * d[d.len() / 2], 1e3 * d[d.len() * 95 / 100], 1e3 * d[d.len() - 1]);
    }
}
