//! Issue 33: one summary schema for every scenario kind. Runs a shipped patch (tress), global and `[live]`
//! example, made small, through the one door (`engine::scenario::run`, as the CLI and the Python binding do), takes their
//! `summary.json` keys (`summary_json`, nested keys dotted) and checks that
//! - every key has a unit: an SI unit suffix or the documented unitless list (`engine::scenario::schema`);
//! - no quantity has two names: no two keys of any kinds differ only by a unit suffix (`peak_force` against
//!   `peak_force_n`), and the quantities the kinds share are under the same key in each;
//! - docs/scenarios.md's "Summary keys" table lists exactly the keys each kind writes, with the unit the schema
//!   gives them.

use engine::scenario::schema::{stem, unit_of, RENAMED_KEYS};
use engine::scenario::{run, summary_json, ScenarioFile};
use std::collections::{BTreeMap, BTreeSet};

/// A shipped example made small: each `(from, to)` replaced once (asserted, so the example's text is still
/// what the test expects).
fn small(example: &str, edits: &[(&str, &str)]) -> String {
    let mut text = example.to_string();
    for (from, to) in edits {
        assert_eq!(text.matches(from).count(), 1, "{from:?} in the example");
        text = text.replace(from, to);
    }
    text
}

/// examples/scenarios/comb-h1.toml with 6 strands, 0.2 s of its stroke.
fn patch() -> String {
    small(include_str!("../../../examples/scenarios/comb-h1.toml"), &[("strands = 24", "strands = 6"), ("settle = 0.5", "settle = 0.1\nduration = 0.2")])
}

/// examples/scenarios/cut.toml with 600 render strands, 0.3 s (the cut is at 0.1 s).
fn global() -> String {
    small(include_str!("../../../examples/scenarios/cut.toml"), &[("render_strands = 2000", "render_strands = 600"), ("duration = 1.5", "duration = 0.3")])
}

/// examples/scenarios/live-comb.toml with 2000 render strands, 0.4 s (the comb reaches the hair).
fn live() -> String {
    small(include_str!("../../../examples/scenarios/live-comb.toml"), &[("render_strands = 100000", "render_strands = 2000"), ("duration = 2.65", "duration = 0.4"), ("settle = 0.5", "settle = 0.2")])
}

/// The keys of a `summary.json` value: nested objects' members dotted, arrays as one key.
fn keys(v: &serde_json::Value, prefix: &str, out: &mut BTreeSet<String>) {
    for (k, v) in v.as_object().expect("a summary is an object") {
        let key = format!("{prefix}{k}");
        if v.is_object() {
            keys(v, &format!("{key}."), out);
        } else {
            out.insert(key);
        }
    }
}

fn summary_keys(toml: &str, kind: &str) -> BTreeSet<String> {
    let file = ScenarioFile::from_toml(toml).unwrap();
    assert_eq!(file.kind(), kind);
    let out = run(&file).unwrap_or_else(|e| panic!("{kind}: {e}"));
    let mut k = BTreeSet::new();
    keys(&summary_json(&out), "", &mut k);
    k
}

/// docs/scenarios.md's "Summary keys" table: key -> (unit, kinds).
fn documented() -> BTreeMap<String, (String, BTreeSet<String>)> {
    let text = include_str!("../../../docs/scenarios.md");
    let start = text.find("## Summary keys").expect("docs/scenarios.md has a \"Summary keys\" section");
    let section = &text[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |e| e + 3)];
    let mut table = BTreeMap::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() != 6 {
            continue; // not a row of the key table (the renamed keys' table has three columns)
        }
        let key = cells[1].trim_matches('`').to_string();
        let kinds = cells[3].split(',').map(|k| k.trim().to_string()).collect();
        assert!(table.insert(key.clone(), (cells[2].to_string(), kinds)).is_none(), "{key} is listed twice");
    }
    table
}

#[test]
fn every_scenario_kind_names_a_quantity_the_same_way_with_its_unit() {
    let kinds = [("patch", summary_keys(&patch(), "patch")), ("global", summary_keys(&global(), "global")), ("live", summary_keys(&live(), "live"))];
    let all: BTreeSet<&String> = kinds.iter().flat_map(|(_, k)| k.iter()).collect();
    println!("{} keys over {} kinds", all.len(), kinds.len());
    // Every key has a unit (suffix or the unitless list); no old name is written.
    for (kind, k) in &kinds {
        for key in k {
            assert!(unit_of(key).is_some(), "{kind}: summary key {key:?} has no unit suffix and is not in schema::UNITLESS_KEYS");
            assert!(!RENAMED_KEYS.iter().any(|(old, _)| key.rsplit('.').next() == Some(old)), "{kind}: old key {key:?}");
        }
    }
    // No quantity under two names: keys differing only by a unit suffix (one kind with `peak_force`, another
    // with `peak_force_n`).
    let mut by_stem: BTreeMap<&str, BTreeSet<&String>> = BTreeMap::new();
    for key in &all {
        by_stem.entry(stem(key)).or_default().insert(key);
    }
    for (s, names) in &by_stem {
        assert!(names.len() == 1, "the quantity {s:?} has several names: {names:?}");
    }
    // The quantities the kinds share, under one key in each.
    let shared: [(&str, &[&str]); 5] = [
        ("peak_force_n", &["patch", "live"]),
        ("mean_force_n", &["patch", "live"]),
        ("contact_steps", &["patch", "live"]),
        ("steps", &["patch", "global", "live"]),
        ("wall_time_s", &["patch", "global", "live"]),
    ];
    for (key, with) in shared {
        for (kind, k) in &kinds {
            if with.contains(kind) {
                assert!(k.contains(key), "{kind} has no {key:?}: {k:?}");
            }
        }
    }
    // The docs table lists exactly each kind's keys, with the schema's unit.
    let docs = documented();
    for (kind, k) in &kinds {
        let listed: BTreeSet<String> = docs.iter().filter(|(_, (_, ks))| ks.contains(*kind)).map(|(key, _)| key.clone()).collect();
        assert_eq!(&listed, k, "docs/scenarios.md's Summary keys table against the {kind} summary: listed but not written {:?}, written but not listed {:?}", listed.difference(k).collect::<Vec<_>>(), k.difference(&listed).collect::<Vec<_>>());
    }
    for (key, (unit, _)) in &docs {
        assert_eq!(Some(unit.as_str()), unit_of(key), "docs/scenarios.md gives {key} the unit {unit}");
    }
}
