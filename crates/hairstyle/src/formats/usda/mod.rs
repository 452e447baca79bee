//! USD `BasisCurves` as `.usda` text.
//!
//! [`write()`] produces a minimal valid layer as DCC tools expect it: `#usda 1.0`, the stage
//! metadata `defaultPrim = "hair"`, `metersPerUnit = 1` and `upAxis = "Z"` (Coiffure's head frame:
//! metres, z up), a `def Xform "hair"` holding one `def BasisCurves "strands"` (prim path
//! `/hair/strands`) with `uniform token type = "linear"`, `int[] curveVertexCounts`,
//! `point3f[] points`, and, when present, `float[] widths` (the thickness: one `constant` value when
//! every vertex has the same, else per vertex) and `color3f[] primvars:displayColor` (per vertex).
//! Transparency is not written. Numbers are written in Rust's shortest exact form, so reading back
//! gives the same `f32` values.
//!
//! [`read()`] is a small tolerant parser, not a full USD reader. Supported: the `#usda` header
//! line, `#` comments, layer metadata (`metersPerUnit` and `upAxis` are kept, see [`read_stage`];
//! the rest is skipped) and prim metadata in parentheses (skipped), any prim hierarchy
//! (`def`/`over`/`class`, typed or not, nested) containing one or more `BasisCurves` prims (their
//! curves are concatenated in file order), attributes with qualifiers (`uniform`, `custom`,
//! `varying`), `rel`s, any attribute values (lists, tuples, strings, numbers, `{...}`
//! dictionaries and time samples, which are skipped when not needed), free layout of whitespace
//! and commas (trailing commas allowed). From each `BasisCurves` prim it reads `type` (`linear` or
//! `cubic`, USD's fallback), `basis` (`bezier`, the fallback, `bspline` or `catmullRom`) and `wrap`
//! (`nonperiodic`, the fallback, `periodic` or `pinned`): cubic curves are evaluated to polylines
//! ([`basis`], [`basis::SAMPLES_PER_SEGMENT`] points per segment); `curveVertexCounts`, `points`
//! (default values only, not `.timeSamples`), `widths` and `primvars:displayColor` with
//! `constant`, `uniform`, `varying` or `vertex` interpolation (from the attribute metadata, else
//! inferred from the number of values), expanded to one value per polyline point. Transforms
//! (`xformOp`s) are not applied; other attributes are ignored. Binary `.usdc` and zipped `.usdz`
//! layers are not read (see [`super::FormatError::UnsupportedUsd`]).

use super::{FormatError, HairCurves};
use std::fmt::Write as _;
use syntax::{lex, Parser, Tok, Value};

pub mod basis;
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

/// Serialise curves as `.usda` text (UTF-8 bytes; positions in metres, z up, as the stage
/// metadata says). Errors if an attribute does not have one value per vertex.
pub fn write(curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
    curves.check_attributes(FORMAT)?;
    let vec3 = |p: &[f32; 3]| format!("({}, {}, {})", num(p[0]), num(p[1]), num(p[2]));
    let list = |items: Vec<String>| format!("[{}]", items.join(", "));
    let mut s = String::from(
        "#usda 1.0\n(\n    defaultPrim = \"hair\"\n    metersPerUnit = 1\n    upAxis = \"Z\"\n)\n\ndef Xform \"hair\"\n{\n    def BasisCurves \"strands\"\n    {\n",
    );
    s += "        uniform token type = \"linear\"\n";
    let counts = curves.strands.iter().map(|c| c.len().to_string()).collect();
    writeln!(s, "        int[] curveVertexCounts = {}", list(counts)).unwrap();
    let points = curves.strands.iter().flatten().map(vec3).collect();
    writeln!(s, "        point3f[] points = {}", list(points)).unwrap();
    let meta = |i: &str| format!(" (\n            interpolation = \"{i}\"\n        )");
    if let Some(w) = curves.thickness.as_ref().filter(|w| !w.is_empty()) {
        if w.iter().all(|x| x.to_bits() == w[0].to_bits()) {
            writeln!(s, "        float[] widths = [{}]{}", num(w[0]), meta("constant")).unwrap();
        } else {
            writeln!(s, "        float[] widths = {}{}", list(w.iter().map(|&x| num(x)).collect()), meta("vertex")).unwrap();
        }
    }
    if let Some(c) = &curves.color {
        let c = list(c.iter().map(vec3).collect());
        writeln!(s, "        color3f[] primvars:displayColor = {c}{}", meta("vertex")).unwrap();
    }
    s += "    }\n}\n";
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

/// Stage metadata of a `.usda` layer, as authored (None where the file does not say).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageMetadata {
    /// `metersPerUnit`: metres per scene unit. USD's fallback when unauthored is 0.01 (cm).
    pub meters_per_unit: Option<f64>,
    /// `upAxis`: `'Y'` or `'Z'`. USD's fallback when unauthored is Y.
    pub up_axis: Option<char>,
}

/// Parse `.usda` text (see the module documentation for what is supported).
pub fn read(bytes: &[u8]) -> Result<HairCurves, FormatError> {
    read_stage(bytes).map(|r| r.0)
}

fn token<'a>(p: &'a syntax::CurvesPrim, name: &str) -> Option<(&'a str, usize)> {
    p.attrs.iter().rev().find_map(|a| match &a.1 {
        Value::Str(s) if a.0 == name => Some((s.as_str(), a.2)),
        _ => None,
    })
}

/// A primvar as values per polyline point of each curve, from its interpolation (or its number
/// of values): `constant`, `uniform`, `varying` (one per segment end) or `vertex` (one per control
/// point, evaluated with the curve's basis).
fn primvar<const D: usize>(
    v: Vec<[f32; D]>,
    interp: Option<&str>,
    counts: &[usize],
    plans: &[Option<basis::Plan>],
    line: usize,
) -> Result<Vec<[f32; D]>, FormatError> {
    let np: usize = counts.iter().sum();
    let nv: usize = plans.iter().zip(counts).map(|(p, &c)| p.as_ref().map_or(c, |p| p.varying())).sum();
    let cubic = plans.iter().any(Option::is_some);
    let samples = |i: usize| plans[i].as_ref().map_or(counts[i], |p| p.samples());
    let per_point = |v: &[[f32; D]], varying: bool| {
        let mut out = Vec::new();
        let mut rest = v;
        for (i, &c) in counts.iter().enumerate() {
            let (k, f): (usize, Box<dyn Fn(&[[f32; D]]) -> Vec<[f32; D]>>) = match &plans[i] {
                None => (c, Box::new(|x: &[[f32; D]]| x.to_vec())),
                Some(p) if varying => (p.varying(), Box::new(move |x: &[[f32; D]]| p.eval_varying(x))),
                Some(p) => (c, Box::new(move |x: &[[f32; D]]| p.eval(x))),
            };
            out.extend(f(&rest[..k]));
            rest = &rest[k..];
        }
        out
    };
    match (interp, v.len()) {
        (Some("vertex") | None, n) if n == np => Ok(per_point(&v, false)),
        (Some("varying"), n) if n == nv => Ok(per_point(&v, true)),
        (None, n) if n == nv => Ok(per_point(&v, true)),
        (Some("constant") | None, 1) => Ok(vec![v[0]; (0..counts.len()).map(samples).sum()]),
        (Some("uniform") | None, n) if n == counts.len() => {
            Ok((0..n).flat_map(|i| vec![v[i]; samples(i)]).collect())
        }
        (i, n) => {
            let varying = if cubic { format!(", {nv} (varying)") } else { String::new() };
            Err(err(line, format!("{np} (vertex){varying}, {} (uniform) or 1 (constant) values for interpolation {i:?}, found {n}", counts.len())))
        }
    }
}

/// One BasisCurves prim's curves (polylines) and per-point widths and colours.
type PrimCurves = (Vec<Vec<[f32; 3]>>, Option<Vec<f32>>, Option<Vec<[f32; 3]>>);

fn read_prim(prim: &syntax::CurvesPrim) -> Result<PrimCurves, FormatError> {
    let get = |name: &str| prim.attrs.iter().rev().find(|a| a.0 == name && !matches!(a.1, Value::Other));
    let required = |name: &str| {
        get(name).ok_or_else(|| err(prim.line, format!("a `{name}` attribute with a value in this BasisCurves prim")))
    };
    // USD's fallbacks: type cubic, basis bezier, wrap nonperiodic.
    let ty = token(prim, "type");
    let cubic = match ty {
        None | Some(("cubic", _)) => true,
        Some(("linear", _)) => false,
        Some((t, line)) => return Err(err(line, format!("type \"linear\" or \"cubic\", found \"{t}\""))),
    };
    let basis = match token(prim, "basis") {
        None | Some(("bezier", _)) => basis::Basis::Bezier,
        Some(("bspline", _)) => basis::Basis::Bspline,
        Some(("catmullRom", _)) => basis::Basis::CatmullRom,
        Some((b, line)) => return Err(err(line, format!("basis \"bezier\", \"bspline\" or \"catmullRom\", found \"{b}\""))),
    };
    let wrap = match token(prim, "wrap") {
        None | Some(("nonperiodic", _)) => basis::Wrap::Nonperiodic,
        Some(("periodic", _)) => basis::Wrap::Periodic,
        Some(("pinned", _)) => basis::Wrap::Pinned,
        Some((w, line)) => return Err(err(line, format!("wrap \"nonperiodic\", \"periodic\" or \"pinned\", found \"{w}\""))),
    };
    let (_, v, line, _) = required("curveVertexCounts")?;
    let counts = list(v, *line, |x, l| match x {
        Value::Word(w) => w.parse::<u32>().map(|n| n as usize).map_err(|_| {
            err(l, format!("a vertex count (integer from 0 to 2^32 - 1), found `{w}`"))
        }),
        x => Err(err(l, format!("a vertex count, found {x:?}"))),
    })?;
    let counts_line = *line;
    let (_, v, line, _) = required("points")?;
    let points = list(v, *line, vec3)?;
    let total: u64 = counts.iter().map(|&n| n as u64).sum();
    if points.len() as u64 != total {
        return Err(err(*line, format!("{total} points (the sum of curveVertexCounts), found {}", points.len())));
    }
    let plans: Vec<Option<basis::Plan>> = if cubic {
        counts
            .iter()
            .enumerate()
            .map(|(i, &n)| basis::Plan::new(basis, wrap, n).map(Some).map_err(|m| err(counts_line, format!("curve {i}: {m}"))))
            .collect::<Result<_, _>>()?
    } else {
        vec![None; counts.len()]
    };
    let mut strands = Vec::with_capacity(counts.len());
    let mut rest = &points[..];
    for (n, plan) in counts.iter().zip(&plans) {
        strands.push(match plan {
            Some(p) => p.eval(&rest[..*n]),
            None => rest[..*n].to_vec(),
        });
        rest = &rest[*n..];
    }
    let widths = get("widths")
        .map(|(_, v, line, i)| {
            let w = list(v, *line, number)?;
            if w.is_empty() {
                return Ok(Vec::new());
            }
            let w = primvar(w.into_iter().map(|x| [x]).collect(), i.as_deref(), &counts, &plans, *line)?;
            Ok(w.into_iter().map(|x| x[0]).collect())
        })
        .transpose()?;
    let color = get("primvars:displayColor")
        .map(|(_, v, line, i)| {
            let c = list(v, *line, vec3)?;
            if c.is_empty() {
                return Ok(c);
            }
            primvar(c, i.as_deref(), &counts, &plans, *line)
        })
        .transpose()?;
    Ok((strands, widths.filter(|w| !w.is_empty()), color.filter(|c| !c.is_empty())))
}

/// Parse `.usda` text, with the stage's authored `metersPerUnit` and `upAxis`.
pub fn read_stage(bytes: &[u8]) -> Result<(HairCurves, StageMetadata), FormatError> {
    if bytes.starts_with(b"PXR-USDC") || bytes.starts_with(b"PK\x03\x04") {
        return Err(FormatError::UnsupportedUsd { what: "the data".into() });
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()].iter().filter(|&&c| c == b'\n').count();
        err(line, format!("UTF-8 text, found an invalid byte at offset {}", e.valid_up_to()))
    })?;
    if !text.starts_with("#usda 1.") {
        return Err(err(1, "the header `#usda 1.0`"));
    }
    let mut p = Parser::new(lex(text)?);
    let mut meta = StageMetadata::default();
    if p.peek() == Some(&Tok::Punct('(')) {
        let line = p.line();
        for (key, v) in p.metadata()? {
            match (key.as_str(), v) {
                ("metersPerUnit", Tok::Word(w)) => {
                    let m: f64 = w.parse().ok().filter(|m: &f64| *m > 0.0 && m.is_finite()).ok_or_else(|| {
                        err(line, format!("metersPerUnit a positive number, found `{w}`"))
                    })?;
                    meta.meters_per_unit = Some(m);
                }
                ("upAxis", Tok::Str(a)) if a == "Y" || a == "Z" => meta.up_axis = a.chars().next(),
                ("upAxis", t) => return Err(err(line, format!("upAxis \"Y\" or \"Z\", found {t:?}"))),
                _ => {}
            }
        }
    }
    p.prims(None)?;
    if let Some(t) = p.peek() {
        return Err(err(p.line(), format!("`def` or the end of the file, found {t:?}")));
    }
    if p.curves.is_empty() {
        return Err(err(p.line(), "a `def BasisCurves` prim, found none"));
    }
    let prims: Vec<PrimCurves> = p.curves.iter().map(read_prim).collect::<Result<_, _>>()?;
    let all_widths = prims.iter().all(|p| p.1.is_some());
    let all_colors = prims.iter().all(|p| p.2.is_some());
    let mut out = HairCurves::default();
    let (mut w, mut c) = (Vec::new(), Vec::new());
    for (s, pw, pc) in prims {
        out.strands.extend(s);
        w.extend(pw.unwrap_or_default());
        c.extend(pc.unwrap_or_default());
    }
    out.thickness = (all_widths && !w.is_empty()).then_some(w);
    out.color = (all_colors && !c.is_empty()).then_some(c);
    Ok((out, meta))
}
