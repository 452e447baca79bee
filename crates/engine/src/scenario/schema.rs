//! One summary schema for every scenario kind (issue 33): a quantity has one `summary.json` key wherever it
//! appears (patch, global, live and replay summaries, the CLI's `summary.json`, the Python binding's dict and
//! `coiffure.sweep`'s columns), and the key says its unit: it ends with an SI unit suffix
//! ([`UNIT_SUFFIXES`]) or it is one of the dimensionless quantities, counts and labels of [`UNITLESS_KEYS`].
//! docs/scenarios.md, "Summary keys", is the table of every key (unit, kinds, meaning);
//! `crates/engine/tests/summary_schema.rs` runs one scenario of each kind and checks the keys against this
//! module and that table.

/// Unit suffixes of summary keys and their units (the longest suffix first: `_m_s` before `_s`).
pub const UNIT_SUFFIXES: &[(&str, &str)] = &[("_m_s", "m/s"), ("_us", "us"), ("_kg", "kg"), ("_n", "N"), ("_m", "m"), ("_j", "J"), ("_s", "s")];

/// Summary keys without a unit suffix: dimensionless quantities (shares, coefficients, wetness), counts and
/// labels, plus the two nested objects (`stroke`, `per_stroke`, whose members follow the same rule). A key
/// of a nested object is checked by its last dotted part (`stroke.steps` is a count).
pub const UNITLESS_KEYS: &[&str] = &[
    // labels
    "kind",
    "treatment",
    // nested objects
    "stroke",
    "per_stroke",
    // counts
    "steps",
    "contact_steps",
    "strand_clamped_steps",
    "clamp_steps",
    "strokes",
    "guides",
    "render_strands",
    "render_cut",
    "clusters",
    "recovered_steps",
    "in_hair_steps",
    "stroke_steps",
    "handovers",
    "early_handovers",
    "rejected_readings",
    "failed_steps",
    // dimensionless
    "represents",
    "wetness",
    "wetness_before",
    "wetness_after",
    "wetness_range_after",
    "tool_friction",
    "hair_friction",
    "continuity",
    "max_step_change_rel",
    "in_hair_force_share",
    "stroke_force_share",
    "pieces_max_field",
];

/// Keys renamed by issue 33 (old name, new name): the tress (patch) and global summaries took the live one's
/// unit suffixes. The old names are no longer written (see docs/scenarios.md, "Summary keys").
pub const RENAMED_KEYS: &[(&str, &str)] = &[
    ("peak_force", "peak_force_n"),
    ("mean_force", "mean_force_n"),
    ("work", "work_j"),
    ("tress_mass", "tress_mass_kg"),
    ("hair_contact_distance", "hair_contact_distance_m"),
    ("clamped_steps", "strand_clamped_steps"),
    ("render_mass_before", "render_mass_before_kg"),
    ("render_mass_on_head", "render_mass_on_head_kg"),
    ("render_mass_cut", "render_mass_cut_kg"),
    ("render_length_before", "render_length_before_m"),
    ("render_length_after", "render_length_after_m"),
    ("cluster_energy", "cluster_energy_j"),
    ("lattice_max_displacement", "lattice_max_displacement_m"),
    ("lattice_end_displacement", "lattice_end_displacement_m"),
    ("lattice_peak_force", "lattice_peak_force_n"),
];

/// The unit of a summary key (dotted for nested keys: its last part counts): the unit of its suffix
/// ([`UNIT_SUFFIXES`]), "1" for a key of [`UNITLESS_KEYS`], None for a key outside the schema.
pub fn unit_of(key: &str) -> Option<&'static str> {
    let last = key.rsplit('.').next().unwrap_or(key);
    if UNITLESS_KEYS.contains(&last) {
        return Some("1");
    }
    UNIT_SUFFIXES.iter().find(|(s, _)| last.len() > s.len() && last.ends_with(s)).map(|(_, u)| *u)
}

/// A key without its unit suffix (the quantity's stem: `peak_force_n` and `peak_force` share `peak_force`).
pub fn stem(key: &str) -> &str {
    UNIT_SUFFIXES.iter().find_map(|(s, _)| key.strip_suffix(s).filter(|k| !k.is_empty())).unwrap_or(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_come_from_the_suffix_or_the_unitless_list() {
        assert_eq!(unit_of("peak_force_n"), Some("N"));
        assert_eq!(unit_of("in_hair_speed_m_s"), Some("m/s"));
        assert_eq!(unit_of("wall_time_s"), Some("s"));
        assert_eq!(unit_of("stroke.steps"), Some("1"));
        assert_eq!(unit_of("per_stroke.combing_work_j"), Some("J"));
        assert_eq!(unit_of("peak_force"), None);
        assert_eq!(unit_of("_n"), None);
        assert_eq!(stem("in_hair_speed_m_s"), "in_hair_speed");
        assert_eq!(stem("peak_force"), "peak_force");
        // Every new name is in the schema, no old one is.
        for (old, new) in RENAMED_KEYS {
            assert!(unit_of(new).is_some() && unit_of(old).is_none(), "{old} -> {new}");
        }
    }
}
