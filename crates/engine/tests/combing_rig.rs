//! The combing instrument of tress scenarios (`profile.csv`, the combing figures of `summary.json`) and
//! repeated strokes (`[tool] strokes`), on small generated tresses: every hair preset, dry and wet, short and
//! long, slow and fast strokes. The figures are checked against what the force trace (`force.csv`'s columns)
//! gives when integrated here independently, and the strokes against the path they must follow.

use engine::scenario::{run, write_output, ScenarioFile, ScenarioOutput, ScenarioSummary, Summary};

/// A small tress (8 strands) of `hair`, `length` m, wetness `w`, combed from 1 cm below the roots to 2 cm below
/// the tips at `speed` m/s, `strokes` times.
fn scenario(hair: &str, length: f64, w: f64, speed: f64, strokes: u32) -> String {
    let (z0, z1) = (0.29, 0.3 - length - 0.02);
    format!(
        r#"
        dt = 0.001
        settle = 0.2
        [patch]
        hair_type = "{hair}"
        strands = 8
        length = {length}
        segments = 8
        extent = [0.008, 0.004]
        tress_mass = 2.0e-3
        wetness = {w}
        [tool]
        shape = "comb"
        strokes = {strokes}
        path = [ {{ t = 0.0, position = [0.0004, -0.012, {z0}], rotation = [1.5707963, 0.0, 0.0] }},
                 {{ t = {t1}, position = [0.0004, -0.012, {z1}], rotation = [1.5707963, 0.0, 0.0] }} ]
        "#,
        t1 = (z0 - z1) / speed
    )
}

fn patch(o: &ScenarioOutput) -> &Summary {
    match &o.summary {
        ScenarioSummary::Patch(s) => s,
        other => panic!("not a patch summary: {other:?}"),
    }
}

fn run_text(text: &str) -> ScenarioOutput {
    run(&ScenarioFile::from_toml(text).unwrap()).unwrap()
}

/// `int |F| ds` over the trace's rows with `stroke` (from the tool's z and the force columns), J: the rig's work
/// computed here from the raw trace.
fn work_from_trace(o: &ScenarioOutput, rows: &[usize]) -> f64 {
    let f = &o.force;
    let mag = |i: usize| (f.fx[i] * f.fx[i] + f.fy[i] * f.fy[i] + f.fz[i] * f.fz[i]).sqrt();
    rows.windows(2).map(|w| 0.5 * (mag(w[0]) + mag(w[1])) * (f.tool_z[w[1]] - f.tool_z[w[0]]).abs()).sum()
}

#[test]
fn the_combing_figures_are_the_integral_of_the_force_trace_over_a_family_of_tresses() {
    // Every preset, dry and wet, 10 and 20 cm, 0.1 and 0.5 m/s (alternating, 28 runs): the work is the trace's
    // |F| integrated over the comb's travel along the tress (to 1e-12 relative), the peak the trace's largest
    // |F|, the fifths' path their fifth of the tress length, and the fifths' work is within the whole.
    let mut worst = 0.0f64;
    let mut n = 0;
    for (i, hair) in ["H1", "H2", "GA1", "GC3", "asian", "caucasian", "african"].iter().enumerate() {
        for w in [0.0, 1.0] {
            for (j, length) in [0.1, 0.2].into_iter().enumerate() {
                let speed = if (i + j) % 2 == 0 { 0.5 } else { 0.1 };
                let o = run_text(&scenario(hair, length, w, speed, 1));
                let s = patch(&o);
                let all: Vec<usize> = (0..o.force.len()).collect();
                let work = work_from_trace(&o, &all);
                let rel = (s.combing.combing_work_j - work).abs() / work;
                worst = worst.max(rel);
                assert!(rel < 1e-12, "{hair} w {w} L {length}: {} vs {work}", s.combing.combing_work_j);
                let peak = (0..o.force.len()).map(|i| o.force.force(i).norm()).fold(0.0, f64::max);
                assert_eq!(s.combing.combing_peak_n, peak);
                assert!(s.combing.combing_work_j > 0.0 && s.combing.combing_mean_n > 0.0);
                let inside: f64 = s.combing.work_fifths_j.iter().sum();
                assert!(inside <= s.combing.combing_work_j * (1.0 + 1e-12) && inside > 0.5 * s.combing.combing_work_j, "{:?}", s.combing);
                // Mean force by position times each fifth's length is the fifth's work (the comb passes the fifths
                // below the first, which it enters 1 cm below the roots, once each).
                for k in 1..5 {
                    let m = s.combing.mean_force_fifths_n[k] * length / 5.0;
                    assert!((m - s.combing.work_fifths_j[k]).abs() <= 1e-9 * s.combing.work_fifths_j[k].max(1e-12), "{hair} fifth {k}: {:?}", s.combing);
                }
                assert_eq!(o.profile.len(), o.force.len(), "one stroke: every step is in the profile");
                assert_eq!((s.strokes, s.per_stroke.combing_work_j.len()), (1, 1));
                n += 1;
            }
        }
    }
    println!("{n} tresses: worst relative difference of the combing work from the trace's integral {worst:.2e}");
}

#[test]
fn repeated_strokes_return_out_of_the_hair_and_are_figured_each() {
    // Three strokes down a 15 cm tress of each of three presets (straight, wavy, curly), dry and wet: every
    // stroke starts at the first pose; the return (stroke 0 in the trace) leaves the tress sideways and rises
    // beside it without a contact (while the teeth are 3.5 cm or more from the tress's axis) until it slides
    // back in at the start height; the per-stroke arrays have
    // three entries whose work adds up to the whole; each stroke combs the tress again (its work within a
    // factor 4 of the first's: a comb that missed the tress would feel nothing; the first stroke of wavy hair
    // may differ by 2x, its wisps sticking and letting go before the tress is combed).
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for hair in ["H1", "caucasian", "african"] {
        for w in [0.0, 1.0] {
            let o = run_text(&scenario(hair, 0.15, w, 0.25, 3));
            let s = patch(&o);
            let p = &s.per_stroke;
            assert_eq!((s.strokes, p.combing_work_j.len(), p.work_fifths_j.len(), p.mean_force_fifths_n.len()), (3, 3, 3, 3));
            let sum: f64 = p.combing_work_j.iter().sum();
            assert!((sum - s.combing.combing_work_j).abs() <= 1e-12 * sum);
            assert_eq!(s.combing.combing_peak_n, p.combing_peak_n.iter().copied().fold(0.0, f64::max));
            for k in 1..3 {
                let r = p.combing_work_j[k] / p.combing_work_j[0];
                (lo, hi) = (lo.min(r), hi.max(r));
                assert!((0.25..4.0).contains(&r), "{hair} w {w}: stroke {} work {r:.2} x the first's: {p:?}", k + 1);
            }
            // The return: stroke 0 rows between the strokes; out and up without contact, above the stroke's end.
            let f = &o.force;
            let stroke_of: Vec<u32> = o.force.t.iter().map(|&t| o.profile.t.binary_search_by(|x| x.total_cmp(&t)).map(|i| o.profile.stroke[i]).unwrap_or(0)).collect();
            let returning: Vec<usize> = (0..f.len()).filter(|&i| stroke_of[i] == 0).collect();
            assert!(!returning.is_empty());
            // Out: the teeth's tips (2.5 cm ahead of the comb's origin) 3.5 cm or more from the tress's axis.
            let out_and_up: Vec<usize> = returning.iter().copied().filter(|&i| f.tool_y[i] < -0.06).collect();
            assert!(out_and_up.len() > returning.len() / 2, "the return is mostly out of the tress");
            assert!(out_and_up.iter().all(|&i| f.contacts[i] == 0), "{hair} w {w}: a contact while the comb is out of the tress");
            for n in 1..=3u32 {
                let r = o.profile.stroke_rows(n);
                assert!((o.profile.position_m[r.start] - 0.01).abs() < 1e-3, "stroke {n} starts 1 cm below the roots: {}", o.profile.position_m[r.start]);
                assert!(r.clone().any(|i| o.force.contacts[o.force.t.partition_point(|&t| t < o.profile.t[i])] > 0), "stroke {n} touches the hair");
            }
        }
    }
    println!("later strokes' work over the first's: {lo:.2} to {hi:.2}");
}

#[test]
fn the_profile_and_the_figures_reach_the_files() {
    let file = ScenarioFile::from_toml(&scenario("H1", 0.1, 0.0, 0.5, 2)).unwrap();
    let o = run(&file).unwrap();
    let dir = std::env::temp_dir().join(format!("coiffure-combing-rig-{}", std::process::id()));
    let text = write_output(&file, &o, "rig", &dir).unwrap();
    let csv = std::fs::read_to_string(dir.join("profile.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("stroke,t,position_m,force_n"));
    assert_eq!(lines.count(), o.profile.len());
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in ["combing_work_j", "combing_peak_n", "combing_mean_n"] {
        assert!(json[key].as_f64().unwrap() > 0.0, "{key}: {json}");
        assert_eq!(json["per_stroke"][key].as_array().unwrap().len(), 2, "{key}");
    }
    assert_eq!(json["work_fifths_j"].as_array().unwrap().len(), 5);
    assert_eq!(json["per_stroke"]["work_fifths_j"][1].as_array().unwrap().len(), 5);
    assert_eq!(json["strokes"], 2);
    assert!(text.contains("combing") && text.contains("stroke 2") && text.contains("profile.csv"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_stroke_count_is_named() {
    for bad in ["0", "1001"] {
        let text = scenario("H1", 0.1, 0.0, 0.5, 1).replace("strokes = 1", &format!("strokes = {bad}"));
        let e = run(&ScenarioFile::from_toml(&text).unwrap()).unwrap_err().to_string();
        assert!(e.contains("tool.strokes"), "{e}");
    }
    let e = ScenarioFile::from_toml(&scenario("H1", 0.1, 0.0, 0.5, 1).replace("strokes = 1", "strokes = -2")).unwrap_err().to_string();
    assert!(e.contains("strokes"), "{e}");
}
