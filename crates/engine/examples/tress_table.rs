//! The tress scenarios' quality table: runs `examples/scenarios/comb-{h1,h2,ga1,gc3}.toml` (a comb stroke down a
//! 4.75 g tress of each Table 1 hair type) dry (`[patch] wetness = 0`) and wet (1), and prints the stroke's
//! figures (`engine::scenario::output::StrokeMetrics`) as a markdown table, with the wet/dry peak ratio.
//! Run from the repository root:
//! `cargo run --release -p coiffure-engine --example tress_table [-- [ease] [key=value]...]`
//! With `dump`, each run's force trace is written to `/tmp/tress-NAME-WETNESS.csv`. With `ease`, also H1 dry at combing ease 0, 0.5 and 1. `key=value` overrides a `[patch]` or
//! `[tool]` number of every run (`packing=0.4`, `hair_friction=0.3`, `strands=32`, `segments=16`,
//! `entanglement_span=0.008`, `entanglement=0`, ...), for calibration experiments.

use engine::scenario::{run, ScenarioFile, ScenarioSummary};

fn load(name: &str, overrides: &[(String, f64)], wetness: f64, ease: f64) -> ScenarioFile {
    let path = format!("examples/scenarios/{name}.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e} (run from the repository root)"));
    let mut table: toml::Table = toml::from_str(&text).unwrap();
    let patch = table.get_mut("patch").and_then(|p| p.as_table_mut()).expect("[patch]");
    patch.insert("wetness".into(), toml::Value::Float(wetness));
    for (k, v) in overrides {
        if matches!(k.as_str(), "entanglement" | "hair_contact") {
            patch.insert(k.clone(), toml::Value::Boolean(*v != 0.0));
        } else if matches!(k.as_str(), "strands" | "segments") {
            patch.insert(k.clone(), toml::Value::Integer(*v as i64));
        } else if !matches!(k.as_str(), "friction" | "combing_ease") {
            patch.insert(k.clone(), toml::Value::Float(*v));
        }
    }
    let tool = table.get_mut("tool").and_then(|p| p.as_table_mut()).expect("[tool]");
    tool.insert("combing_ease".into(), toml::Value::Float(ease));
    for (k, v) in overrides.iter().filter(|(k, _)| matches!(k.as_str(), "friction" | "combing_ease")) {
        tool.insert(k.clone(), toml::Value::Float(*v));
    }
    ScenarioFile::from_toml(&toml::to_string(&table).unwrap()).unwrap()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let overrides: Vec<(String, f64)> = args.iter().filter_map(|a| a.split_once('=').map(|(k, v)| (k.to_string(), v.parse().expect("a number")))).collect();
    println!("overrides: {overrides:?}");
    println!("| hair type | wetness | peak | median | p90 | continuity (> 2 % of peak) | largest step change (share of peak) | wet/dry peak | hair contact distance | clamped steps | wall time |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let dump = args.iter().any(|a| a == "dump");
    let summary = |f: &ScenarioFile| {
        let o = run(f).unwrap();
        if dump {
            let ScenarioFile::Patch(p) = f else { unreachable!() };
            let path = format!("/tmp/tress-{}-{}.csv", p.name.clone().unwrap_or_default(), p.patch.wetness);
            std::fs::write(&path, o.force.to_csv()).unwrap();
        }
        match o.summary {
            ScenarioSummary::Patch(s) => s,
            _ => unreachable!(),
        }
    };
    for name in ["comb-h1", "comb-h2", "comb-ga1", "comb-gc3"] {
        let mut dry_peak = 0.0;
        for w in [0.0, 1.0] {
            let s = summary(&load(name, &overrides, w, 0.0));
            let m = s.stroke;
            if w == 0.0 {
                dry_peak = m.peak_n;
            }
            println!(
                "| {} | {w} | {:.3} N | {:.3} N | {:.3} N | {:.0} % | {:.3} N ({:.0} %) | {} | {:.2} mm | {} | {:.1} s |",
                name.trim_start_matches("comb-").to_uppercase(),
                m.peak_n,
                m.median_n,
                m.p90_n,
                100.0 * m.continuity,
                m.max_step_change_n,
                100.0 * m.max_step_change_rel,
                if w > 0.0 { format!("{:.2}", m.peak_n / dry_peak) } else { "-".into() },
                s.hair_contact_distance_m * 1e3,
                s.strand_clamped_steps,
                s.wall_time_s
            );
        }
    }
    if args.iter().any(|a| a == "ease") {
        for ease in [0.0, 0.5, 1.0] {
            let s = summary(&load("comb-h1", &overrides, 0.0, ease));
            println!("H1 dry, combing ease {ease}: peak {:.4} N, median {:.4} N", s.stroke.peak_n, s.stroke.median_n);
        }
    }
}
