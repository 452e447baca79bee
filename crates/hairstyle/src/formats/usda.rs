//! USD `BasisCurves` as `.usda` text.
//!
//! [`write`] produces a minimal valid layer: `#usda 1.0` and one `def BasisCurves "hair"` with
//! `uniform token type = "linear"`, `int[] curveVertexCounts`, `point3f[] points`, and, when
//! present, `float[] widths` (the thickness, per vertex) and `color3f[] primvars:displayColor`
//! (per vertex). Transparency is not written. Numbers are written in Rust's shortest exact form,
//! so reading back gives the same `f32` values.
//!
//! [`read`] is a small tolerant parser, not a full USD reader. Supported: the `#usda` header
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

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Word(String), // identifiers, keywords, type names (with `[]`), numbers
    Str(String),
    Path,
    Punct(char),
}

fn lex(text: &str) -> Result<Vec<(Tok, usize)>, FormatError> {
    let b = text.as_bytes();
    let (mut i, mut line, mut toks) = (0, 1, Vec::new());
    while i < b.len() {
        let ch = b[i];
        let start_line = line;
        match ch {
            b'\n' => line += 1,
            b' ' | b'\t' | b'\r' => {}
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' | b'\'' => {
                let q: &[u8] = if b[i..].starts_with(b"\"\"\"") {
                    b"\"\"\""
                } else {
                    &b[i..i + 1]
                };
                let mut j = i + q.len();
                while j < b.len() && !b[j..].starts_with(q) {
                    if q.len() == 1 && b[j] == b'\n' {
                        return Err(err(
                            start_line,
                            "a closing quote on the same line for this string",
                        ));
                    }
                    line += (b[j] == b'\n') as usize;
                    j += if b[j] == b'\\' { 2 } else { 1 };
                }
                if j >= b.len() {
                    return Err(err(
                        start_line,
                        "a closing quote for this string, found the end of the file",
                    ));
                }
                toks.push((Tok::Str(text[i + q.len()..j].to_string()), start_line));
                i = j + q.len();
                continue;
            }
            b'<' => {
                let end = b[i..].iter().position(|&c| c == b'>' || c == b'\n');
                match end {
                    Some(e) if b[i + e] == b'>' => i += e,
                    _ => return Err(err(line, "a `>` closing this path")),
                }
                toks.push((Tok::Path, line));
            }
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b'=' | b',' | b':' => {
                toks.push((Tok::Punct(ch as char), line))
            }
            c if c.is_ascii_alphanumeric() || b"_-+.".contains(&c) => {
                let mut j = i + 1;
                while j < b.len()
                    && (b[j].is_ascii_alphanumeric()
                        || b"_.:".contains(&b[j])
                        || (b"+-".contains(&b[j]) && b"eE".contains(&b[j - 1])))
                {
                    j += 1;
                }
                if b[j..].starts_with(b"[]") {
                    j += 2;
                }
                toks.push((Tok::Word(text[i..j].to_string()), line));
                i = j;
                continue;
            }
            _ => {
                return Err(err(
                    line,
                    format!("a USD token, found `{}`", text[i..].chars().next().unwrap()),
                ))
            }
        }
        i += 1;
    }
    Ok(toks)
}

/// A parsed attribute value (only what the reader needs).
#[derive(Debug)]
enum Value {
    List(Vec<Value>),
    Tuple(Vec<Value>),
    Str(String),
    Word(String),
    Other,
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    i: usize,
    /// (value, line, interpolation) of the wanted attributes of the BasisCurves prim.
    attrs: Vec<(String, Value, usize, Option<String>)>,
    curves_line: Option<usize>,
}

impl Parser {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.i).map(|t| &t.0)
    }
    fn line(&self) -> usize {
        self.toks
            .get(self.i)
            .or(self.toks.last())
            .map_or(1, |t| t.1)
    }
    fn next(&mut self, expected: &str) -> Result<Tok, FormatError> {
        let t = self.toks.get(self.i).ok_or_else(|| {
            err(
                self.line(),
                format!("{expected}, found the end of the file"),
            )
        })?;
        self.i += 1;
        Ok(t.0.clone())
    }
    fn expect(&mut self, c: char) -> Result<(), FormatError> {
        let line = self.line();
        match self.next(&format!("`{c}`"))? {
            Tok::Punct(p) if p == c => Ok(()),
            t => Err(err(line, format!("`{c}`, found {t:?}"))),
        }
    }
    fn eat(&mut self, c: char) -> bool {
        let hit = self.peek() == Some(&Tok::Punct(c));
        self.i += hit as usize;
        hit
    }

    /// Prims and properties until `}` (inside a prim: `inside` is `Some(is_curves)`) or the end
    /// of the file (top level, `None`).
    fn prims(&mut self, inside: Option<bool>) -> Result<(), FormatError> {
        loop {
            let line = self.line();
            match (self.peek(), inside) {
                (None, Some(_)) => {
                    return Err(err(line, "`}` closing the prim, found the end of the file"))
                }
                (None, None) | (Some(Tok::Punct('}')), Some(_)) => return Ok(()),
                (Some(Tok::Word(w)), _) if ["def", "over", "class"].contains(&w.as_str()) => {
                    self.prim()?
                }
                (Some(_), Some(is_curves)) => self.property(is_curves)?,
                (Some(t), None) => return Err(err(line, format!("`def`, found {t:?}"))),
            }
        }
    }

    fn prim(&mut self) -> Result<(), FormatError> {
        self.i += 1; // specifier
        let line = self.line();
        let mut kind = String::new();
        if let Some(Tok::Word(w)) = self.peek() {
            kind = w.clone();
            self.i += 1;
        }
        match self.next("a prim name in quotes")? {
            Tok::Str(_) => {}
            t => return Err(err(line, format!("a prim name in quotes, found {t:?}"))),
        }
        if self.peek() == Some(&Tok::Punct('(')) {
            self.value()?; // prim metadata
        }
        self.expect('{')?;
        let is_curves = kind == "BasisCurves";
        if is_curves {
            if let Some(first) = self.curves_line {
                return Err(err(
                    line,
                    format!("one BasisCurves prim only (the first is at line {first})"),
                ));
            }
            self.curves_line = Some(line);
        }
        self.prims(Some(is_curves))?;
        self.expect('}')
    }

    /// `[qualifiers] type name [= value] [(metadata)]` inside a prim.
    fn property(&mut self, keep: bool) -> Result<(), FormatError> {
        let line = self.line();
        let mut words = Vec::new();
        while let Some(Tok::Word(w)) = self.peek() {
            words.push(w.clone());
            self.i += 1;
            if words.len() >= 2
                && !["uniform", "custom", "varying", "config"]
                    .contains(&words[words.len() - 2].as_str())
            {
                break;
            }
        }
        if words.len() < 2 {
            return Err(err(
                line,
                format!(
                    "an attribute (`type name = value`), found {:?}",
                    self.peek()
                ),
            ));
        }
        let value = if self.eat('=') {
            self.value()?
        } else {
            Value::Other
        };
        let mut interpolation = None;
        if self.peek() == Some(&Tok::Punct('(')) {
            let start = self.i;
            self.value()?;
            let meta = &self.toks[start..self.i];
            interpolation = meta
                .windows(3)
                .find_map(|w| match (&w[0].0, &w[1].0, &w[2].0) {
                    (Tok::Word(k), Tok::Punct('='), Tok::Str(v)) if k == "interpolation" => {
                        Some(v.clone())
                    }
                    _ => None,
                });
        }
        if keep {
            self.attrs
                .push((words.last().unwrap().clone(), value, line, interpolation));
        }
        Ok(())
    }

    fn value(&mut self) -> Result<Value, FormatError> {
        let line = self.line();
        match self.next("a value")? {
            Tok::Punct(open @ ('[' | '(' | '{')) => {
                let close = match open {
                    '[' => ']',
                    '(' => ')',
                    _ => '}',
                };
                let mut items = Vec::new();
                while !self.eat(close) {
                    items.push(self.value()?);
                    self.eat(',');
                    self.eat(':'); // dictionary / time-sample keys
                    self.eat('=');
                }
                Ok(match open {
                    '[' => Value::List(items),
                    '(' => Value::Tuple(items),
                    _ => Value::Other,
                })
            }
            Tok::Str(s) => Ok(Value::Str(s)),
            Tok::Word(w) => Ok(Value::Word(w)),
            Tok::Path => Ok(Value::Other),
            t => Err(err(line, format!("a value, found {t:?}"))),
        }
    }
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
            Ok(counts.iter().zip(v).flat_map(|(&c, x)| std::iter::repeat(x).take(c)).collect())
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
    let mut p = Parser {
        toks: lex(text)?,
        i: 0,
        attrs: Vec::new(),
        curves_line: None,
    };
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
    let counts = list(v, *line, |x, l| {
        let n = number(x, l)?;
        (n >= 0.0 && n.fract() == 0.0)
            .then_some(n as usize)
            .ok_or_else(|| err(l, format!("a vertex count, found {n}")))
    })?;
    let (_, v, line, _) = required("points")?;
    let points = list(v, *line, vec3)?;
    if points.len() != counts.iter().sum::<usize>() {
        return Err(err(
            *line,
            format!(
                "{} points (the sum of curveVertexCounts), found {}",
                counts.iter().sum::<usize>(),
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
