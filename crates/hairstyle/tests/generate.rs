//! Head, scalp and hairstyle generation.

use hairstyle::generate::{CURL_RADIUS_MIN, CURL_RAMP, RENDER_GAP};
use hairstyle::{Curl, GenerateError, Hairstyle, HairstyleParams, Head, HeadParams};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use strand::{HairType, ModelKind, RootFrame, Strand, StrandModel, StrandState};

/// A strand's centreline at `n` points evenly spaced in arc length (m): `strand::kinematics::centerline`'s points.
fn sample_strand(model: &strand::StrandModel, state: &strand::StrandState, n: usize) -> Vec<nalgebra::Point3<f64>> {
    strand::kinematics::centerline(model, state, n).into_iter().map(|(_, p)| nalgebra::Point3::from(p)).collect()
}

fn small(curliness: f64, seed: u64) -> HairstyleParams {
    HairstyleParams {
        curliness,
        seed,
        guide_count: 80,
        render_count: 4000,
        ..Default::default()
    }
}

fn p64(p: &[f32; 3]) -> Point3<f64> {
    Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// The mesh lies on the collision surface (|F - T| / |grad F| < 1e-6 m after the f32 rounding
/// of positions, which is ~1e-8 m at 0.3 m), is closed (every edge shared by exactly two
/// triangles with opposite directions), is oriented outwards (each triangle's normal agrees with
/// its vertices' field normals) and has a few thousand triangles.
#[test]
fn head_mesh_lies_on_the_metaball_surface_closed_and_outward() {
    let head = Head::default();
    let mesh = head.mesh();
    let tris = mesh.triangle_count();
    assert!((2_000..20_000).contains(&tris), "{tris} triangles");
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        let x = p64(p);
        assert!(
            head.signed_distance(&x).abs() < 1e-6,
            "{x}: {}",
            head.signed_distance(&x)
        );
        let nf = head.normal(&x).unwrap();
        let n = Vector3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        assert!((n.norm() - 1.0).abs() < 1e-6 && (n - nf).norm() < 1e-5);
    }
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    let mut agree = 0;
    for t in mesh.indices.chunks(3) {
        for e in 0..3 {
            *edges.entry((t[e], t[(e + 1) % 3])).or_default() += 1;
        }
        let [a, b, c] = [
            p64(&mesh.positions[t[0] as usize]),
            p64(&mesh.positions[t[1] as usize]),
            p64(&mesh.positions[t[2] as usize]),
        ];
        let face = (b - a).cross(&(c - a));
        let vn: Vector3<f64> = t
            .iter()
            .map(|&i| {
                let n = mesh.normals[i as usize];
                Vector3::new(n[0] as f64, n[1] as f64, n[2] as f64)
            })
            .sum();
        if face.dot(&vn) > 0.0 {
            agree += 1;
        }
    }
    for (&(a, b), &count) in &edges {
        assert_eq!(count, 1, "edge {a}-{b} used {count} times in one direction");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no opposite");
    }
    // surface nets quads may fold slightly at sharp creases (neck/shoulder blends): allow 0.5 %
    assert!(
        agree as f64 >= 0.995 * tris as f64,
        "{agree} of {tris} triangles face outwards"
    );
    assert!(mesh
        .indices
        .iter()
        .all(|&i| (i as usize) < mesh.positions.len()));
}

/// The cranium is a sphere of the head radius where no other ball reaches; the hairline is at the
/// stated elevations (to 1 degree) at the front and back.
#[test]
fn head_radius_and_hairline() {
    let head = Head::default();
    let top = head.surface_along(&Vector3::z()).unwrap();
    assert!((top.position.z - 0.09).abs() < 1e-9, "{}", top.position);
    assert!((top.normal - Vector3::z()).norm() < 1e-9);
    let dir = |elev: f64, front: bool| {
        let e = elev.to_radians();
        Vector3::new(0.0, if front { e.cos() } else { -e.cos() }, e.sin())
    };
    let on = |d: Vector3<f64>| head.is_scalp(&head.surface_along(&d).unwrap().position);
    assert!(on(dir(36.0, true)) && !on(dir(34.0, true)));
    assert!(on(dir(-29.0, false)) && !on(dir(-31.0, false)));
    assert!(on(Vector3::z()) && !on(Vector3::new(0.0, 1.0, -0.3)));
    assert!(Head::new(HeadParams {
        head_radius: -1.0,
        ..Default::default()
    })
    .unwrap_err()
    .to_string()
    .contains("head_radius"));
}

/// Every guide and render root lies on the metaball iso-surface (|F - T| / |grad F| below
/// 1e-6 m: f32 positions at 0.1 m round at ~4e-9 m), on the scalp, and the guides' root tangent is
/// the surface normal (to 1e-9).
#[test]
fn roots_lie_on_the_scalp() {
    let h = Hairstyle::generate(&small(0.3, 7)).unwrap();
    assert_eq!(h.guides.len(), 80);
    assert_eq!(h.render.len(), 4000);
    for g in &h.guides {
        let r = Point3::from(g.state.root.position);
        assert!(h.head.signed_distance(&r).abs() < 1e-9);
        assert!(h.head.is_scalp(&r));
        let n = h.head.normal(&r).unwrap();
        assert!((g.state.root.rotation.column(0) - n).norm() < 1e-9);
    }
    for i in 0..h.render.len() {
        let r = p64(&h.render.strand(i)[0]);
        assert!(
            h.head.signed_distance(&r).abs() < 1e-6,
            "strand {i}: {}",
            h.head.signed_distance(&r)
        );
        assert!(h.head.is_scalp(&r));
    }
}

/// Render strands start on the scalp and go outwards: no vertex after the root is inside the body
/// or closer to it than RENDER_GAP (less 1e-6 m for the first-order distance estimate and f32);
/// the guides' centrelines (64 samples) are outside the body too (first-order distance > -1e-4 m).
#[test]
fn strands_do_not_start_or_run_inside_the_head() {
    for c in [0.0, 1.0] {
        let h = Hairstyle::generate(&small(c, 3)).unwrap();
        for i in 0..h.render.len() {
            for (j, p) in h.render.strand(i).iter().enumerate().skip(1) {
                let d = h.head.signed_distance(&p64(p));
                assert!(
                    d > RENDER_GAP - 1e-6,
                    "curliness {c} strand {i} vertex {j}: distance {d}"
                );
            }
        }
        let mut worst: f64 = f64::INFINITY;
        for g in h.guide_samples() {
            for p in g.iter().skip(1) {
                worst = worst.min(h.head.signed_distance(p));
            }
        }
        assert!(worst > -1e-4, "curliness {c}: guide point at {worst} m");
    }
}

/// The sag-free rest shape holds the groomed guides under gravity: 0.3 s of simulation at 1 ms
/// from the groomed state moves the tip of a guide whose equilibrium is stable by under 1e-4 m
/// (the step's own error, not a sag: without the sag-free rest it falls by centimetres, checked).
#[test]
fn guides_are_in_equilibrium_under_gravity() {
    let h = Hairstyle::generate(&small(0.0, 5)).unwrap();
    let stable: Vec<_> = h.guides.iter().filter(|g| g.stable).collect();
    assert!(stable.len() >= 5, "only {} stable guides", stable.len());
    for g in stable.iter().take(5) {
        let tip0 = sample_strand(&g.model, &g.state, 2)[1];
        let mut s = Strand::new(g.model.clone(), g.state.root.clone()).unwrap();
        s.state = g.state.clone();
        for _ in 0..300 {
            s.step(1e-3, &[]).unwrap();
        }
        let moved = (sample_strand(&s.model, &s.state, 2)[1] - tip0).norm();
        assert!(moved < 1e-4, "tip moved {moved} m");
        // the same strand with a straight rest shape sags
        let mut straight = g.model.clone();
        straight.rest.iter_mut().for_each(|r| *r = Vector3::zeros());
        let mut s = Strand::new(straight, g.state.root.clone()).unwrap();
        s.state = g.state.clone();
        for _ in 0..300 {
            s.step(1e-3, &[]).unwrap();
        }
        assert!((sample_strand(&s.model, &s.state, 2)[1] - tip0).norm() > 1e-2);
    }
}

/// Curliness 0 is straight hair: no curl, and each render strand lies on its wisp axis shifted to
/// its root (offset constant along the strand) wherever it was not pushed off the head.
#[test]
fn curliness_zero_is_straight() {
    assert_eq!(Curl::from_curliness(0.0).unwrap(), None);
    let h = Hairstyle::generate(&small(0.0, 2)).unwrap();
    assert!(h.curl.is_none());
    let samples = h.guide_samples();
    let v = h.render.vertices_per_strand;
    let mut on_axis = 0;
    let mut total = 0;
    for i in 0..h.render.len() {
        let shift = p64(&h.render.strand(i)[0]) - h.render.axis_point(&samples, i, 0);
        for j in 1..v {
            total += 1;
            let axis = h.render.axis_point(&samples, i, j) + shift;
            if (p64(&h.render.strand(i)[j]) - axis).norm() < 1e-6 {
                on_axis += 1;
            }
        }
    }
    assert!(
        on_axis as f64 > 0.95 * total as f64,
        "{on_axis} of {total} vertices on the axis"
    );
    // its guides are groomed without twist but where one turns out of its grooming plane to hang down
    // (hairstyle::groom): then in one straight segment (the sag-free rest may twist where gravity twists)
    for g in &h.guides {
        let twisted: Vec<usize> = (0..g.model.segments).filter(|&i| g.state.q[2 * i] != 0.0).collect();
        assert!(twisted.len() <= 1 && twisted.iter().all(|&i| g.state.q[2 * i + 1] == 0.0), "twisted segments {twisted:?}: {:?}", g.state.q);
    }
}

/// Curliness 1 maps to the tightest natural curl, radius 0.6 cm; the Super-Helix with the mapped
/// rest twist and bend is a helix of that radius (closed-form kinematics of the strand crate:
/// every centreline point at distance R from the axis R0 Omega/|Omega| through root + R N, to 1e-9 m)
/// and curl index CI (arc length over axial length, to 1e-9); render strands curl at distance R
/// (to 1e-5 m, f32) about their wisp axis beyond the fade-in.
#[test]
fn curliness_one_gives_helices_of_the_mapped_radius() {
    let c = Curl::from_curliness(1.0).unwrap().unwrap();
    assert!((c.radius - CURL_RADIUS_MIN).abs() < 1e-15);
    assert!((c.darboux_radius() - c.radius).abs() < 1e-12);
    for curl in (1..=10).map(|i| Curl::from_curliness(i as f64 / 10.0).unwrap().unwrap()) {
        assert!((curl.darboux_radius() - curl.radius).abs() < 1e-12 * curl.radius);
        let w = (curl.twist.powi(2) + curl.bend.powi(2)).sqrt();
        // curl index of the helix: |Omega| / twist
        assert!((w / curl.twist - curl.curl_index).abs() < 1e-9);
    }
    let hair = HairType::CAUCASIAN;
    let length = 3.0 * c.pitch * c.curl_index; // three turns
    let model = StrandModel::new(
        ModelKind::Reduced,
        length,
        8,
        hair.section().unwrap(),
        hair.material().unwrap(),
    )
    .unwrap()
    .with_uniform_rest(c.twist, c.bend, 0.0);
    let root = RootFrame::new(
        Vector3::new(0.01, 0.02, 0.03),
        Vector3::new(0.3, -0.2, 0.9),
        Vector3::x(),
    )
    .unwrap();
    let state = StrandState::at_rest(&model, root.clone());
    let pts = sample_strand(&model, &state, 200);
    let r0 = root.rotation;
    let axis = (r0 * Vector3::new(c.twist, c.bend, 0.0)).normalize();
    let centre = root.position - c.radius * r0.column(2); // principal normal at the root is -n2
    for p in &pts {
        let d = (p.coords - centre).cross(&axis).norm();
        assert!((d - c.radius).abs() < 1e-9, "distance {d} vs {}", c.radius);
    }
    let axial = (pts[199] - pts[0]).dot(&axis);
    assert!((length / axial - c.curl_index).abs() < 1e-9);

    let h = Hairstyle::generate(&small(1.0, 4)).unwrap();
    let samples = h.guide_samples();
    let v = h.render.vertices_per_strand;
    let (mut good, mut total) = (0, 0);
    for i in 0..h.render.len() {
        let shift = p64(&h.render.strand(i)[0]) - h.render.axis_point(&samples, i, 0);
        let guide_len = h.guides[h.render.guide_indices[i * h.render.guides_per_strand] as usize]
            .model
            .length;
        for j in 1..v {
            let z = h.render.span[i] as f64 * guide_len * j as f64 / (v - 1) as f64;
            if z < CURL_RAMP {
                continue;
            }
            total += 1;
            let d = (p64(&h.render.strand(i)[j]) - (h.render.axis_point(&samples, i, j) + shift))
                .norm();
            if (d - c.radius).abs() < 1e-5 {
                good += 1;
            }
        }
    }
    assert!(
        good as f64 > 0.95 * total as f64,
        "{good} of {total} vertices at the curl radius"
    );
    // guides are the wisp axes: L / CI long
    assert!((h.guides[0].model.length - h.params.length / c.curl_index).abs() < 1e-12);
}

/// Same seed, same hairstyle (bit for bit); another seed, another one.
#[test]
fn generation_is_deterministic() {
    let a = Hairstyle::generate(&small(0.5, 11)).unwrap();
    let b = Hairstyle::generate(&small(0.5, 11)).unwrap();
    assert_eq!(a, b);
    let c = Hairstyle::generate(&small(0.5, 12)).unwrap();
    assert_ne!(a.render.positions, c.render.positions);
}

/// Render strands follow the guides: at the generated guide shapes `follow` gives the strands
/// back (to 1e-6 m, f32), and a rigid translation of every guide translates every vertex.
#[test]
fn render_strands_follow_their_guides() {
    let h = Hairstyle::generate(&small(0.4, 9)).unwrap();
    let samples = h.guide_samples();
    let mut out = Vec::new();
    h.render.follow(&samples, &mut out).unwrap();
    for (a, b) in out.iter().zip(&h.render.positions) {
        assert!((p64(a) - p64(b)).norm() < 1e-6);
    }
    let t = Vector3::new(0.01, -0.02, 0.005);
    let moved: Vec<Vec<Point3<f64>>> = samples
        .iter()
        .map(|g| g.iter().map(|p| p + t).collect())
        .collect();
    h.render.follow(&moved, &mut out).unwrap();
    for (a, b) in out.iter().zip(&h.render.positions) {
        assert!((p64(a) - p64(b) - t).norm() < 1e-6);
    }
    let err = h.render.follow(&samples[..3], &mut out).unwrap_err();
    assert!(err.to_string().contains("guide"), "{err}");
}

/// Save and load through a hair file: the loaded render strands keep their roots and tips (to
/// f32 precision) and follow the loaded guides.
#[test]
fn hairstyle_round_trips_through_a_hair_file() {
    let h = Hairstyle::generate(&small(0.2, 1)).unwrap();
    let dir = std::env::temp_dir().join(format!("coiffure-gen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("style.hair");
    hairstyle::write_file(&path, &h.to_curves()).unwrap();
    let curves = hairstyle::read_file(&path).unwrap();
    let g = Hairstyle::from_curves(&curves, &h.params).unwrap();
    assert_eq!(g.render.len(), h.render.len());
    for i in 0..h.render.len() {
        let (a, b) = (h.render.strand(i), g.render.strand(i));
        assert!((p64(&a[0]) - p64(&b[0])).norm() < 1e-7);
        assert!((p64(a.last().unwrap()) - p64(b.last().unwrap())).norm() < 1e-6);
    }
    let mut out = Vec::new();
    g.render.follow(&g.guide_samples(), &mut out).unwrap();
    for (a, b) in out.iter().zip(&g.render.positions) {
        assert!((p64(a) - p64(b)).norm() < 1e-6);
    }
    // a strand with a single point is refused, naming it
    let mut bad = curves.clone();
    bad.strands[5].truncate(1);
    bad.thickness = None;
    bad.transparency = None;
    bad.color = None;
    let err = Hairstyle::from_curves(&bad, &h.params).unwrap_err();
    assert!(
        matches!(err, GenerateError::BadStrand { strand: 5, .. }),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad parameters give errors naming the field.
#[test]
fn bad_parameters_are_named() {
    let cases: Vec<(HairstyleParams, &str)> = vec![
        (
            HairstyleParams {
                hair_type: "purple".into(),
                ..Default::default()
            },
            "hair_type",
        ),
        (
            HairstyleParams {
                length: -0.1,
                ..Default::default()
            },
            "length",
        ),
        (
            HairstyleParams {
                curliness: 1.5,
                ..Default::default()
            },
            "curliness",
        ),
        (
            HairstyleParams {
                curliness: f64::NAN,
                ..Default::default()
            },
            "curliness",
        ),
        (
            HairstyleParams {
                guide_count: 0,
                ..Default::default()
            },
            "guide_count",
        ),
        (
            HairstyleParams {
                render_vertices: 1,
                ..Default::default()
            },
            "render_vertices",
        ),
        (
            HairstyleParams {
                flow: Vector3::zeros(),
                ..Default::default()
            },
            "flow",
        ),
    ];
    for (p, field) in cases {
        let err = Hairstyle::generate(&p).unwrap_err().to_string();
        assert!(err.contains(field), "{field}: {err}");
    }
}

/// Render vertices (after the root) in front of the face: |x| < 4.5 cm (the outer corners of the eyes),
/// from the chin (z = -10 cm) to the brows (z = 2 cm), more than 5 cm in front of the head centre.
fn vertices_over_the_face(h: &Hairstyle) -> usize {
    let v = h.render.vertices_per_strand;
    h.render
        .positions
        .iter()
        .enumerate()
        .filter(|(k, p)| k % v != 0 && p[0].abs() < 0.045 && p[1] > 0.05 && (-0.1..0.02).contains(&p[2]))
        .count()
}

/// The default hairstyle leaves the face free: the fringe is combed to the sides (a centre parting,
/// `fringe_flow`), so no render strand hangs in front of the face, straight or curly. Combed away from the
/// sides' flow point above the hairline instead (`fringe_flow: None`), the roots in front of that point
/// fall over the eyes: the measure sees them (541 of 124,000 vertices).
#[test]
fn the_fringe_leaves_the_face_free() {
    for c in [0.0, 0.5, 1.0] {
        let h = Hairstyle::generate(&small(c, 5)).unwrap();
        let n = vertices_over_the_face(&h);
        assert_eq!(n, 0, "curliness {c}: {n} render vertices in front of the face");
    }
    let p = small(0.0, 5);
    let fringe = Hairstyle::generate(&HairstyleParams { fringe_flow: None, ..p }).unwrap();
    let n = vertices_over_the_face(&fringe);
    assert!(n > 100, "the forward fringe puts only {n} render vertices in front of the face");
}

/// Issue 12: every groomed guide is a stable equilibrium of its sag-free model (the statics' Hessian is
/// positive definite), for the default scene's configuration (200 guides of 8 segments; 112 were not
/// with the grooming plane of the combing direction alone), the generator's defaults (300 x 12) and
/// curly hair. Each of those guides stays in the plane of its root normal (the groom is planar).
#[test]
fn every_groomed_guide_is_stable() {
    for (guides, segments, curliness) in [(200, 8, 0.0), (300, 12, 0.0), (200, 8, 0.6)] {
        let p = HairstyleParams { guide_count: guides, guide_segments: segments, curliness, render_count: 10, ..Default::default() };
        let h = Hairstyle::generate(&p).unwrap();
        let unstable: Vec<usize> = (0..guides).filter(|&i| !h.guides[i].stable).collect();
        assert!(unstable.is_empty(), "{guides} x {segments}, curliness {curliness}: unstable guides {unstable:?}");
    }
}
