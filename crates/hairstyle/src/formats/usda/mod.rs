//! USD `BasisCurves` as `.usda` text.
//!
//! [`write()`] produces a minimal valid layer: `#usda 1.0` and one `def BasisCurves "hair"` with
//! `uniform token type = "linear"`, `int[] curveVertexCounts`, `point3f[] points`, and, when
//! present, `float[] widths` (the thickness, per vertex) and `color3f[] primvars:displayColor`
//! (per vertex). Transparency is not written. Numbers are written in Rust's shortest exact form,
//! so reading back gives the same `f32` values.
//!
//! [`read()`] is a small tolerant parser, not a full USD reader. Supported: the `#usda` header
//! line, `#` comments, layer and prim metadata in parentheses (skipped), any prim hierarchy
//! (`def`/`over`/`class`, typed or not) containing exactly one `BasisCurves` prim, attributes
//! with qualifiers (`uniform`, `custom`, `varying`), `rel`s, any attribute values (lists, tuples,
//! strings, numbers, `{...}` dictionaries and time samples, which are skipped when not needed),
//! free layout of whitespace and commas (trailing commas allowed). From the `BasisCurves` prim it
//! reads `type` (required, must be `"linear"`: USD's fallback is cubic, which is not supported),
//! `curveVertexCounts`, `points` (default values only, not `.timeSamples`), `widths` and
//! `primvars:displayColor` with `constant`, `uniform` or `vertex`/`varying` interpolation
//! (from the attribute metadata, else inferred from the number of values), expanded to one value
//! per vertex. Transforms are not applied; other attributes are ignored.

use super::{FormatError, HairCurves};
use std::fmt::Write as _;
use syntax::{lex, Parser, Tok, Value};

mod syntax;

const FORMAT: &str = ".usda";

fn err(line: usize, message: impl Into<String>) -> FormatError {
    FormatError::Text {
        format: FORMAT,
        line,
        message: message.into(),
    }
}

fn num(x: f32) -> String {
    if x.is_nan() {
        "nan".into()
    } else {
        format!("{x}") // "inf", "-inf" or the shortest exact decimal
    }
}

/// Serialise curves as `.usda` text (UTF-8 bytes). Errors if an attribute does not have one
/// value per vertex.
pub fn write(curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
    curves.check_attributes(FORMAT)?;
    let vec3 = |p: &[f32; 3]| format!("({}, {}, {})", num(p[0]), num(p[1]), num(p[2]));
    let list = |items: Vec<String>| format!("[{}]", items.join(", "));
    let mut s = String::from("#usda 1.0\n\ndef BasisCurves \"hair\"\n{\n");
    s += "    uniform token type = \"linear\"\n";
    let counts = curves.strands.iter().map(|c| c.len().to_string()).collect();
    writeln!(s, "    int[] curveVertexCounts = {}", list(counts)).unwrap();
    let points = curves.strands.iter().flatten().map(vec3).collect();
    writeln!(s, "    point3f[] points = {}", list(points)).unwrap();
    let meta = " (\n        interpolation = \"vertex\"\n    )";
    if let Some(w) = &curves.thickness {
        writeln!(
            s,
            "    float[] widths = {}{meta}",
            list(w.iter().map(|&x| num(x)).collect())
        )
        .unwrap();
    }
    if let Some(c) = &curves.color {
        let c = list(c.iter().map(vec3).collect());
        writeln!(s, "    color3f[] primvars:displayColor = {c}{meta}").unwrap();
    }
    s += "}\n";
    Ok(s.into_bytes())
}

fn number(v: &Value, line: usize) -> Result<f32, FormatError> {
    match v {
        Value::Word(w) => w
            .parse()
            .map_err(|_| err(line, format!("a number, found `{w}`"))),
        v => Err(err(line, format!("a number, found {v:?}"))),
    }
}

fn vec3(v: &Value, line: usize) -> Result<[f32; 3], FormatError> {
    match v {
        Value::Tuple(t) if t.len() == 3 => Ok([
            number(&t[0], line)?,
            number(&t[1], line)?,
            number(&t[2], line)?,
        ]),
        v => Err(err(line, format!("a tuple of 3 numbers, found {v:?}"))),
    }
}

fn list<T>(
    v: &Value,
    line: usize,
    f: impl Fn(&Value, usize) -> Result<T, FormatError>,
) -> Result<Vec<T>, FormatError> {
    match v {
        Value::List(items) => items.iter().map(|x| f(x, line)).collect(),
        v => Err(err(line, format!("a list `[...]`, found {v:?}"))),
    }
}

/// Expand a primvar to one value per vertex, from its interpolation or number of values.
fn per_vertex<T: Clone>(
    v: Vec<T>,
    interp: Option<&str>,
    counts: &[usize],
    line: usize,
) -> Result<Vec<T>, FormatError> {
    let np: usize = counts.iter().sum();
    if v.is_empty() {
        return Ok(v); // `[]`: treated as absent
    }
    match (interp, v.len()) {
        (Some("vertex" | "varying") | None, n) if n == np => Ok(v),
        (Some("constant") | None, 1) => Ok(vec![v[0].clone(); np]),
        (Some("uniform") | None, n) if n == counts.len() => {
            Ok(counts.iter().zip(v).flat_map(|(&c, x)| vec![x; c]).collect())
        }
        (i, n) => Err(err(line, format!("{np} (vertex), {} (uniform) or 1 (constant) values for interpolation {i:?}, found {n}", counts.len()))),
    }
}

/// Parse `.usda` text (see the module documentation for what is supported).
pub fn read(bytes: &[u8]) -> Result<HairCurves, FormatError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&c| c == b'\n')
            .count();
        err(
            line,
            format!(
                "UTF-8 text, found an invalid byte at offset {}",
                e.valid_up_to()
            ),
        )
    })?;
    if !text.starts_with("#usda 1.") {
        return Err(err(1, "the header `#usda 1.0`"));
    }
    let mut p = Parser::new(lex(text)?);
    if p.peek() == Some(&Tok::Punct('(')) {
        p.value()?; // layer metadata
    }
    p.prims(None)?;
    if let Some(t) = p.peek() {
        return Err(err(
            p.line(),
            format!("`def` or the end of the file, found {t:?}"),
        ));
    }
    let Some(curves_line) = p.curves_line else {
        return Err(err(p.line(), "a `def BasisCurves` prim, found none"));
    };
    let get = |name: &str| {
        p.attrs
            .iter()
            .rev()
            .find(|a| a.0 == name && !matches!(a.1, Value::Other))
    };
    let required = |name: &str| {
        get(name).ok_or_else(|| {
            err(
                curves_line,
                format!("a `{name}` attribute with a value in this BasisCurves prim"),
            )
        })
    };
    let (_, ty, line, _) = required("type")?;
    if !matches!(ty, Value::Str(s) if s == "linear") {
        return Err(err(
            *line,
            format!("type \"linear\" (only linear curves are supported), found {ty:?}"),
        ));
    }
    let (_, v, line, _) = required("curveVertexCounts")?;
    let counts = list(v, *line, |x, l| match x {
        Value::Word(w) => w.parse::<u32>().map(|n| n as usize).map_err(|_| {
            err(
                l,
                format!("a vertex count (integer from 0 to 2^32 - 1), found `{w}`"),
            )
        }),
        x => Err(err(l, format!("a vertex count, found {x:?}"))),
    })?;
    let (_, v, line, _) = required("points")?;
    let points = list(v, *line, vec3)?;
    let total: u64 = counts.iter().map(|&n| n as u64).sum();
    if points.len() as u64 != total {
        return Err(err(
            *line,
            format!(
                "{total} points (the sum of curveVertexCounts), found {}",
                points.len()
            ),
        ));
    }
    let mut strands = Vec::with_capacity(counts.len());
    let mut rest = &points[..];
    for &n in &counts {
        strands.push(rest[..n].to_vec());
        rest = &rest[n..];
    }
    let widths = get("widths")
        .map(|(_, v, line, i)| per_vertex(list(v, *line, number)?, i.as_deref(), &counts, *line))
        .transpose()?;
    let color = get("primvars:displayColor")
        .map(|(_, v, line, i)| per_vertex(list(v, *line, vec3)?, i.as_deref(), &counts, *line))
        .transpose()?;
    Ok(HairCurves {
        strands,
        thickness: widths.filter(|w| !w.is_empty()),
        transparency: None,
        color: color.filter(|c| !c.is_empty()),
    })
}
