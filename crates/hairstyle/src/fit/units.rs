//! Units of a hair file: parsed from a name or a number, and named for people.

/// Parses a unit: "m", "cm", "mm", "in" (inch), "ft", or a number of metres per unit.
pub fn parse_units(s: &str) -> Result<f64, String> {
    let v = match s.trim().to_ascii_lowercase().as_str() {
        "m" => 1.0,
        "dm" => 0.1,
        "cm" => 0.01,
        "mm" => 0.001,
        "in" | "inch" => 0.0254,
        "ft" => 0.3048,
        t => t.parse::<f64>().map_err(|_| format!("units `{s}`: expected m, cm, mm, in, ft or metres per unit (a number)"))?,
    };
    if !(v > 0.0 && v.is_finite()) {
        return Err(format!("units `{s}`: metres per unit must be a positive number"));
    }
    Ok(v)
}

/// Metres per file unit written for people: a unit [`parse_units`] knows by name ("cm (0.01 m)") when within
/// 1e-6 of it (a file's f32 gives 0.009999999776 for 0.01), else the number to 4 significant digits ("0.02 m").
pub fn units_name(meters_per_unit: f64) -> String {
    for (name, v) in [("m", 1.0), ("dm", 0.1), ("cm", 0.01), ("mm", 0.001), ("in", 0.0254), ("ft", 0.3048)] {
        if (meters_per_unit / v - 1.0).abs() < 1e-6 {
            return if name == "m" { "m".into() } else { format!("{name} ({v} m)") };
        }
    }
    let digits = 3 - meters_per_unit.abs().log10().floor() as i32;
    format!("{} m", format!("{:.*}", digits.clamp(0, 12) as usize, meters_per_unit).parse::<f64>().unwrap_or(meters_per_unit))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_are_named_for_people() {
        // Every named unit, also through a file's f32, comes back by name; other values to 4 significant digits.
        for (name, v) in [("m", 1.0), ("cm (0.01 m)", 0.01), ("mm (0.001 m)", 0.001), ("in (0.0254 m)", 0.0254), ("ft (0.3048 m)", 0.3048)] {
            assert_eq!(units_name(v), name);
            assert_eq!(units_name(v as f32 as f64), name);
        }
        assert_eq!(units_name(0.02), "0.02 m");
        assert_eq!(units_name(0.0123456), "0.01235 m");
        assert_eq!(units_name(12.5), "12.5 m");
    }
}
