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

/// AMD's TressFX sample hairstyle (Ratboy's mohawk, ../shared/data, 2,228 strands x 32 points,
/// metres, y up, facing +z; the root is each strand's first point, the one TressFX holds fixed).
/// What the file is: a rat character's mane. Its roots run from the top of Ratboy's long head
/// (file z 0.18 m at the front to -0.02 m where the head meets the neck, y 0.78-0.91 m) down his
/// neck and back to y = 0.22 m, the back strands sticking out backwards. Only the head part
/// (roots above y = 0.8 m, the kink between head and neck in the roots' profile: 437 strands,
/// 20 %) can be on a scalp; the mane on the back (roots below y = 0.7 m) is not on a head at all.
///
/// Asserted, measured independently of the report from the written strands:
/// - y up, facing +z (the format's convention; the roots alone fit ear to ear as well), metres;
/// - the scale (0.8, the end of `FitParams::scale_freedom`'s range: a head 1.25 times ours)
///   within 15 % of an independent size estimate, our scalp's front-to-back extent over the
///   head part's (0.164 m / 0.183 m = 0.90; 0.82 with the head cut from the neck at y = 0.78 m
///   instead: the estimate is as rough as that cut);
/// - the head part's roots on the scalp: median < 5 mm and 95th percentile < 15 mm (measured
///   0.50 mm and 8.6 mm after the push-out, which moves the roots the fit put inside the head
///   onto its skin; before it 4.8 mm and 12.6 mm: Ratboy's head is longer and flatter than ours);
/// - the report's rooted strands are the head part: at least 90 % of the head part's roots
///   rooted, at most 5 % of the mane's; no hair point inside the body.
#[test]
fn the_tressfx_mohawk_lands_on_the_scalp() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tressfx/Ratboy_mohawk.tfx");
    assert!(path.is_file(), "the test hairstyle {} is missing (../shared/data beside the repository)", path.display());
    let (file, _, _) = hairstyle::formats::read_file_with_metadata(&path).unwrap();
    let (out, report) = fit_file(&path, &FitOptions::default()).unwrap();
    println!("mohawk: {report:?}");
    assert_eq!(out.strands.len(), 2228);
    assert_eq!((report.up, report.front), (Axis::PosY, Axis::PosZ));
    assert_eq!(report.meters_per_unit, 1.0);
    let head = Head::default();
    let index = ScalpIndex::new(&head, FitParams::default().scalp_samples);
    let extent = |v: Vec<f64>| v.iter().copied().fold(f64::NEG_INFINITY, f64::max) - v.iter().copied().fold(f64::INFINITY, f64::min);
    let head_part = |s: &Vec<[f32; 3]>| s[0][1] > 0.8;
    let mane = |s: &Vec<[f32; 3]>| s[0][1] < 0.7;
    let file_length = extent(file.strands.iter().filter(|s| head_part(s)).map(|s| s[0][2] as f64).collect());
    let scalp_length = extent(index.samples().iter().map(|p| p.position.y).collect());
    let expected = scalp_length / file_length;
    println!("scale {:.3}; size estimate {:.3} m / {:.3} m = {:.3}", report.transform.scale, scalp_length, file_length, expected);
    assert!((report.transform.scale / expected - 1.0).abs() < 0.15, "scale {} against {expected}", report.transform.scale);
    let distances = |keep: &dyn Fn(&Vec<[f32; 3]>) -> bool| -> Vec<f64> {
        file.strands.iter().zip(&out.strands).filter(|(f, _)| keep(f)).map(|(_, s)| index.nearest(&p64(&s[0])).distance).collect()
    };
    let on_head = distances(&head_part);
    let before: Vec<f64> = file.strands.iter().filter(|s| head_part(s)).map(|s| index.nearest(&report.transform.apply(&p64(&s[0]))).distance).collect();
    let (median, p95) = (quantile(on_head.clone(), 0.5), quantile(on_head.clone(), 0.95));
    println!(
        "head part ({} roots): median {:.2} mm, p95 {:.2} mm from the scalp (before the push-out {:.2} / {:.2} mm); rooted {:.1} % of all: {:?}, loose {:?}",
        on_head.len(), 1e3 * median, 1e3 * p95, 1e3 * quantile(before.clone(), 0.5), 1e3 * quantile(before, 0.95), 100.0 * report.rooted, report.rooted_distance, report.loose_distance
    );
    assert!(median < 0.005 && p95 < 0.015, "head part's roots: median {median} m, p95 {p95} m");
    let rooted = |d: &[f64]| d.iter().filter(|&&x| x <= FitParams::default().inlier_distance).count() as f64 / d.len() as f64;
    let on_mane = distances(&mane);
    println!("rooted: head part {:.1} %, mane {:.1} %", 100.0 * rooted(&on_head), 100.0 * rooted(&on_mane));
    assert!(rooted(&on_head) >= 0.9 && rooted(&on_mane) <= 0.05, "head part {} mane {}", rooted(&on_head), rooted(&on_mane));
    let all: Vec<f64> = out.strands.iter().map(|s| index.nearest(&p64(&s[0])).distance).collect();
    assert!((report.rooted - rooted(&all)).abs() < 1e-12, "{} against {}", report.rooted, rooted(&all));
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
    // composition: (a after b)(x) = a(b(x))
    let a = Similarity { scale: 0.37, rotation: *Rotation3::from_euler_angles(0.3, -1.1, 2.0).matrix(), translation: Vector3::new(0.1, -2.0, 0.5) };
    let b = Similarity { scale: 2.0, rotation: axes_rotation(Axis::PosY, Axis::NegX), translation: Vector3::new(1.0, 0.0, -3.0) };
    let x = Point3::new(0.3, -0.7, 1.9);
    assert!((a.after(&b).apply(&x) - a.apply(&b.apply(&x))).norm() < 1e-12);
}

/// Partial hairstyles: the back half and the right half of a Coiffure hairstyle (roots behind,
/// or right of, the head's centre), rotated to y up facing +z, scaled to centimetres and moved,
/// in a format without an axis convention (`.hair`), come back with the orientation detected
/// from the roots alone and the roots within 5 mm (median) and 15 mm (95th percentile) of where
/// they were (measured 0.50 mm: the push-out skin). The front half's roots fit the back of the
/// scalp as well as the front (the hairline's open face is not in it), so there the format's
/// convention decides: as a `.tfx` (y up facing +z) it comes back within the same bounds.
#[test]
fn partial_hairstyles_come_back_with_their_orientation() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 3000, guide_count: 100, ..Default::default() }).unwrap();
    let all = h.to_curves();
    let to_file = Similarity { scale: 100.0, rotation: axes_rotation(Axis::PosY, Axis::PosZ).transpose(), translation: Vector3::new(12.0, 150.0, -7.0) };
    type Keep = fn(&Vec<[f32; 3]>) -> bool;
    let cases: [(&str, Keep, Format); 3] = [("back half", |s| s[0][1] < 0.0, Format::Hair), ("right half", |s| s[0][0] > 0.0, Format::Hair), ("front half", |s| s[0][1] > 0.0, Format::Tfx)];
    for (name, keep, format) in cases {
        let part = HairCurves::from_strands(all.strands.iter().filter(|s| keep(s)).cloned().collect());
        assert!(part.strands.len() > 500, "{name}: {}", part.strands.len());
        let mut moved = part.clone();
        transform_curves(&mut moved, &to_file);
        let (back, report) = fit(&moved, Some(format), &Metadata::default(), &FitOptions::default(), &Head::default(), &FitParams::default()).unwrap();
        let d: Vec<f64> = part.strands.iter().zip(&back.strands).map(|(a, b)| (p64(&a[0]) - p64(&b[0])).norm()).collect();
        let (median, p95) = (quantile(d.clone(), 0.5), quantile(d, 0.95));
        println!("{name} ({} strands, {format:?}): up {} front {}, scale {:.5}, scores {:?}; root error median {:.2} mm, p95 {:.2} mm", part.strands.len(), report.up.name(), report.front.name(), report.transform.scale, report.scores, 1e3 * median, 1e3 * p95);
        assert_eq!((report.up, report.front, report.meters_per_unit), (Axis::PosY, Axis::PosZ, 0.01), "{name}");
        assert!(median <= 0.005 && p95 <= 0.015, "{name}: root error median {median} m, p95 {p95} m");
    }
}

/// A hairstyle Coiffure saved as `.tfx` or `.data` is in its own head frame (metres, z up, facing
/// +y), against those formats' y-up convention: the roots' fit to the scalp outweighs the
/// convention's preference, and the hairstyle comes back where it was (within 5 mm / 15 mm;
/// measured 0.50 mm, the push-out skin).
#[test]
fn our_own_z_up_tfx_and_data_files_come_back_z_up() {
    let h = Hairstyle::generate(&HairstyleParams { render_count: 2000, guide_count: 100, ..Default::default() }).unwrap();
    let ours = h.to_curves();
    for format in [Format::Tfx, Format::Usc] {
        let (back, report) = fit(&ours, Some(format), &Metadata::default(), &FitOptions::default(), &Head::default(), &FitParams::default()).unwrap();
        let d: Vec<f64> = ours.strands.iter().zip(&back.strands).map(|(a, b)| (p64(&a[0]) - p64(&b[0])).norm()).collect();
        let (median, p95) = (quantile(d.clone(), 0.5), quantile(d, 0.95));
        println!("{format:?}: up {} front {} scores {:?}; root error median {:.2} mm, p95 {:.2} mm", report.up.name(), report.front.name(), report.scores, 1e3 * median, 1e3 * p95);
        assert_eq!((report.up, report.front, report.meters_per_unit), (Axis::PosZ, Axis::PosY, 1.0), "{format:?}");
        assert!(median <= 0.005 && p95 <= 0.015, "{format:?}: median {median} m, p95 {p95} m");
    }
}

/// Degenerate hairstyles (one strand; every root at one point; every root on a line) are fitted
/// without panicking, to a finite transform within the scale range.
#[test]
fn degenerate_hairstyles_fit_to_a_finite_transform() {
    let one = HairCurves::from_strands(vec![vec![[0.0, 1.0, 0.0], [0.0, 0.8, 0.05]]]);
    let same = HairCurves::from_strands((0..10).map(|i| vec![[0.0, 1.0, 0.0], [0.01 * i as f32, 0.8, 0.05]]).collect());
    let line = HairCurves::from_strands((0..50).map(|i| vec![[0.0, 1.0, 0.002 * i as f32], [0.0, 0.8, 0.002 * i as f32]]).collect());
    for (name, c) in [("one", one), ("same", same), ("line", line)] {
        let (out, r) = fit(&c, Some(Format::Tfx), &Metadata::default(), &FitOptions::default(), &Head::default(), &FitParams::default()).unwrap();
        let t = &r.transform;
        assert!(t.scale.is_finite() && t.translation.iter().all(|x| x.is_finite()) && out.strands.iter().flatten().flatten().all(|x| x.is_finite()), "{name}: {r:?}");
        let f = FitParams::default().scale_freedom;
        assert!(t.scale >= r.meters_per_unit / f - 1e-12 && t.scale <= r.meters_per_unit * f + 1e-12, "{name}: {r:?}");
    }
}
