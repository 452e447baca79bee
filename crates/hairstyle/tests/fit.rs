//! Fit to the head: a Coiffure hairstyle moved to another tool's frame comes back; the real
//! TressFX mohawk lands on the scalp; the pieces (axes, similarity, options).
use hairstyle::fit::{axes_rotation, fit, fit_file, parse_units, transform_curves, Axis, FitOptions, FitParams, ScalpIndex, Similarity, Source};
use hairstyle::formats::{write_file, Format, HairCurves, Metadata};
use hairstyle::{Hairstyle, HairstyleParams, Head};
use nalgebra::{Matrix3, Point3, Rotation3, Vector3};

fn p64(p: &[f32; 3]) -> Point3<f64> {
    Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

fn quantile(mut d: Vec<f64>, q: f64) -> f64 {
    d.sort_by(f64::total_cmp);
    d[((q * (d.len() - 1) as f64).round() as usize).min(d.len() - 1)]
}

/// The acceptance test of issue 18: a hairstyle written by Coiffure, rotated to y up facing +z,
/// scaled to centimetres and moved, comes back onto the scalp with its roots within 5 mm
/// (median) and 15 mm (95th percentile) of where they were.
#[test]
fn a_coiffure_hairstyle_moved_to_y_up_centimetres_comes_back() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 3000, guide_count: 100, ..Default::default() }).unwrap();
    let original = h.to_curves();
    let to_file = Similarity {
        scale: 100.0, // m -> cm
        rotation: axes_rotation(Axis::PosY, Axis::PosZ).transpose(), // head frame -> y up, facing +z
        translation: Vector3::new(12.0, 150.0, -7.0), // cm: somewhere in another tool's scene
    };
    let mut moved = original.clone();
    transform_curves(&mut moved, &to_file);
    let dir = std::env::temp_dir().join(format!("coiffure-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("moved.hair");
    write_file(&path, &moved).unwrap();
    let (back, report) = fit_file(&path, &FitOptions::default()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!((report.up, report.front, report.orientation_source), (Axis::PosY, Axis::PosZ, Source::Detected));
    assert_eq!((report.meters_per_unit, report.units_source), (0.01, Source::Detected));
    let d: Vec<f64> = original.strands.iter().zip(&back.strands).map(|(a, b)| (p64(&a[0]) - p64(&b[0])).norm()).collect();
    let (median, p95) = (quantile(d.clone(), 0.5), quantile(d, 0.95));
    println!("round trip: root error median {:.2} mm, p95 {:.2} mm; report {:?}", 1e3 * median, 1e3 * p95, report.root_distance);
    assert!(median <= 0.005 && p95 <= 0.015, "root error median {median} m, p95 {p95} m");
    assert!(report.root_distance.median < 0.002, "{:?}", report.root_distance);
}

/// The final fit's free scale does not shrink a hairstyle that covers only part of the scalp: a
/// strip of a Coiffure hairstyle (roots within 2 cm of the mid-sagittal plane, a mohawk on a head of
/// our size), moved to y up, centimetres, comes back at its scale (0.01 m per unit within 2 %) with
/// its roots within 5 mm (median) and 15 mm (95th percentile) of where they were (measured 0.80 mm
/// and 0.83 mm).
#[test]
fn a_mohawk_strip_of_our_head_keeps_its_scale() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 3000, guide_count: 100, ..Default::default() }).unwrap();
    let all = h.to_curves();
    let strip = HairCurves::from_strands(all.strands.iter().filter(|s| s[0][0].abs() < 0.02).cloned().collect());
    assert!(strip.strands.len() > 300, "{}", strip.strands.len());
    let to_file = Similarity { scale: 100.0, rotation: axes_rotation(Axis::PosY, Axis::PosZ).transpose(), translation: Vector3::new(12.0, 150.0, -7.0) };
    let mut moved = strip.clone();
    transform_curves(&mut moved, &to_file);
    let (back, report) = fit(&moved, Some(Format::Hair), &Metadata::default(), &FitOptions::default(), &Head::default(), &FitParams::default()).unwrap();
    assert!((report.transform.scale / 0.01 - 1.0).abs() < 0.02, "scale {}", report.transform.scale);
    let d: Vec<f64> = strip.strands.iter().zip(&back.strands).map(|(a, b)| (p64(&a[0]) - p64(&b[0])).norm()).collect();
    let (median, p95) = (quantile(d.clone(), 0.5), quantile(d, 0.95));
    println!("strip: root error median {:.2} mm, p95 {:.2} mm", 1e3 * median, 1e3 * p95);
    assert!(median <= 0.005 && p95 <= 0.015, "root error median {median} m, p95 {p95} m");
}

/// AMD's TressFX sample hairstyle (Ratboy's mohawk, 2,228 strands, y up, metres) from
/// ../shared/data: detected as y up facing +z by the format's convention and shape; its roots (a
/// strip 0.7 m long from Ratboy's forehead over his head and down his neck and back) land on our
/// scalp with the final fit's scale free within `FitParams::scale_range` (a head of another size):
/// the scale goes to the range's lower end, 0.3 (the strip then runs from the forehead to the nape;
/// no scale fits all of an L-shaped strip onto a round cap). Measured: 57 % of the roots within
/// 10 mm, root-to-scalp median 2.8 mm, 95th percentile 77 mm (the lowest part of the strip, from
/// Ratboy's back, below the nape). Asserted: median < 5 mm, p95 < 100 mm, more than half of the
/// roots within 10 mm, and no hair point left inside the body.
#[test]
fn the_tressfx_mohawk_lands_on_the_scalp() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tressfx/Ratboy_mohawk.tfx");
    assert!(path.is_file(), "the test hairstyle {} is missing (../shared/data beside the repository)", path.display());
    let (out, report) = fit_file(&path, &FitOptions::default()).unwrap();
    println!("mohawk: {report:?}");
    assert_eq!(out.strands.len(), 2228);
    assert_eq!((report.up, report.front), (Axis::PosY, Axis::PosZ));
    assert_eq!(report.meters_per_unit, 1.0);
    let range = FitParams::default().scale_range;
    assert!(report.transform.scale >= range.0 - 1e-9 && report.transform.scale < 0.5, "scale {}", report.transform.scale);
    assert!(report.inliers > 0.5, "{}", report.inliers);
    let head = Head::default();
    let index = ScalpIndex::new(&head, FitParams::default().scalp_samples);
    // distances measured independently of the report, from the written strands
    let d: Vec<f64> = out.strands.iter().map(|s| index.nearest(&p64(&s[0])).distance).collect();
    let (median, p95) = (quantile(d.clone(), 0.5), quantile(d.clone(), 0.95));
    let near = d.iter().filter(|&&x| x < 0.01).count() as f64 / d.len() as f64;
    println!("mohawk roots: median {:.2} mm, p95 {:.1} mm from the scalp, {:.1} % within 10 mm", 1e3 * median, 1e3 * p95, 100.0 * near);
    assert!(median < 0.005, "root-to-scalp median {median} m");
    assert!(p95 < 0.1, "root-to-scalp 95th percentile {p95} m");
    assert!(near > 0.5, "fraction of roots within 10 mm of the scalp {near}");
    let inside = out.strands.iter().flatten().filter(|p| head.inside(&p64(p))).count();
    assert_eq!(inside, 0, "points inside the body after the push-out");
}

#[test]
fn overrides_and_no_fit() {
    let c = HairCurves::from_strands(vec![vec![[0.0, 10.0, 0.0], [0.0, 5.0, 1.0]], vec![[1.0, 9.0, 0.0], [1.0, 4.0, 2.0]]]);
    let head = Head::default();
    let opts = FitOptions { units: Some(0.01), up: Some(Axis::PosY), front: Some(Axis::PosZ), fit: false };
    let (out, r) = fit(&c, Some(Format::Hair), &Metadata::default(), &opts, &head, &FitParams::default()).unwrap();
    assert_eq!((r.units_source, r.orientation_source), (Source::Option, Source::Option));
    // y up facing +z: file (x, y, z) -> head (-x, z, y), in metres
    assert_eq!(out.strands[1][1], [-0.01, 0.02, 0.04]);
    let (same, r) = fit(&c, None, &Metadata::default(), &FitOptions { fit: false, ..Default::default() }, &head, &FitParams::default()).unwrap();
    assert_eq!((same.strands.clone(), r.units_source, r.orientation_source), (c.strands.clone(), Source::Assumed, Source::Assumed));
    let meta = Metadata { meters_per_unit: Some(0.01), up_axis: Some('Y') };
    let (_, r) = fit(&c, Some(Format::Usda), &meta, &FitOptions { fit: false, front: Some(Axis::PosZ), ..Default::default() }, &head, &FitParams::default()).unwrap();
    assert_eq!((r.meters_per_unit, r.units_source, r.up, r.orientation_source), (0.01, Source::Metadata, Axis::PosY, Source::Metadata));
    let bad = FitOptions { up: Some(Axis::PosY), front: Some(Axis::NegY), ..Default::default() };
    assert!(fit(&c, None, &Metadata::default(), &bad, &head, &FitParams::default()).unwrap_err().to_string().contains("perpendicular"));
    let nan = HairCurves::from_strands(vec![vec![[0.0, f32::NAN, 0.0]]]);
    assert!(fit(&nan, None, &Metadata::default(), &FitOptions::default(), &head, &FitParams::default()).unwrap_err().to_string().contains("not finite"));
    assert!(fit(&HairCurves::default(), None, &Metadata::default(), &FitOptions::default(), &head, &FitParams::default()).is_err());
}

#[test]
fn axes_units_and_similarity() {
    assert_eq!(Axis::parse("Y"), Ok(Axis::PosY));
    assert_eq!(Axis::parse("-z"), Ok(Axis::NegZ));
    assert!(Axis::parse("w").is_err());
    assert_eq!(parse_units("cm"), Ok(0.01));
    assert_eq!(parse_units("0.0254"), Ok(0.0254));
    assert!(parse_units("-1").is_err() && parse_units("furlong").is_err());
    for u in Axis::ALL {
        for f in Axis::ALL.into_iter().filter(|f| f.vector().dot(&u.vector()) == 0.0) {
            let r = axes_rotation(u, f);
            assert!((r.determinant() - 1.0).abs() < 1e-12 && (r * r.transpose() - Matrix3::identity()).norm() < 1e-12);
            assert_eq!(r * u.vector(), Vector3::z());
            assert_eq!(r * f.vector(), Vector3::y());
        }
    }
    // Umeyama recovers a known similarity from exact pairs
    let truth = Similarity { scale: 0.37, rotation: *Rotation3::from_euler_angles(0.3, -1.1, 2.0).matrix(), translation: Vector3::new(0.1, -2.0, 0.5) };
    let a: Vec<Point3<f64>> = (0..20).map(|i| Point3::new((i as f64 * 0.7).sin(), (i as f64 * 1.3).cos(), i as f64 * 0.1)).collect();
    let b: Vec<Point3<f64>> = a.iter().map(|p| truth.apply(p)).collect();
    let t = Similarity::fit(&a, &b, (0.0, f64::INFINITY)).unwrap();
    assert!((t.scale - truth.scale).abs() < 1e-12 && (t.rotation - truth.rotation).norm() < 1e-10 && (t.translation - truth.translation).norm() < 1e-10);
    let clamped = Similarity::fit(&a, &b, (0.5, 2.0)).unwrap();
    assert_eq!(clamped.scale, 0.5);
}
