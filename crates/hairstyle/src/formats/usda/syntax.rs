//! Lexer and tolerant parser for the `.usda` subset read by [`super::read()`].

use super::err;
use crate::formats::FormatError;

#[derive(Debug, Clone, PartialEq)]
pub(super) enum Tok {
    Word(String), // identifiers, keywords, type names (with `[]`), numbers
    Str(String),
    Path,
    Punct(char),
}

pub(super) fn lex(text: &str) -> Result<Vec<(Tok, usize)>, FormatError> {
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
pub(super) enum Value {
    List(Vec<Value>),
    Tuple(Vec<Value>),
    Str(String),
    Word(String),
    Other,
}

pub(super) struct Parser {
    toks: Vec<(Tok, usize)>,
    i: usize,
    /// The BasisCurves prims found, in file order.
    pub(super) curves: Vec<CurvesPrim>,
    /// Current nesting of brackets and prims, limited to [`MAX_DEPTH`].
    depth: usize,
}

/// One `BasisCurves` prim: its line and attributes (name, value, line, interpolation metadata).
pub(super) struct CurvesPrim {
    pub(super) line: usize,
    pub(super) attrs: Vec<(String, Value, usize, Option<String>)>,
}

/// Deepest nesting of brackets and prims accepted (guards the recursion against hostile files).
const MAX_DEPTH: usize = 100;

impl Parser {
    pub(super) fn new(toks: Vec<(Tok, usize)>) -> Self {
        Self {
            toks,
            i: 0,
            curves: Vec::new(),
            depth: 0,
        }
    }

    pub(super) fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.i).map(|t| &t.0)
    }
    pub(super) fn line(&self) -> usize {
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

    /// Prims and properties until `}` (inside a prim: `inside` is `Some(curves prim index)`) or
    /// the end of the file (top level, `None`).
    pub(super) fn prims(&mut self, inside: Option<Option<usize>>) -> Result<(), FormatError> {
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
        let curves = (kind == "BasisCurves").then(|| {
            self.curves.push(CurvesPrim {
                line,
                attrs: Vec::new(),
            });
            self.curves.len() - 1
        });
        self.enter(line)?;
        self.prims(Some(curves))?;
        self.depth -= 1;
        self.expect('}')
    }

    /// `[qualifiers] type name [= value] [(metadata)]` inside a prim.
    fn property(&mut self, keep: Option<usize>) -> Result<(), FormatError> {
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
        if let Some(k) = keep {
            self.curves[k]
                .attrs
                .push((words.last().unwrap().clone(), value, line, interpolation));
        }
        Ok(())
    }

    fn enter(&mut self, line: usize) -> Result<(), FormatError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(err(
                line,
                format!("at most {MAX_DEPTH} nested brackets or prims"),
            ));
        }
        Ok(())
    }

    /// `key = value` pairs at the top level of the metadata `( ... )` starting at the current
    /// token (layer metadata), as (key, value token); the metadata is consumed.
    pub(super) fn metadata(&mut self) -> Result<Vec<(String, Tok)>, FormatError> {
        let start = self.i;
        self.value()?;
        let toks = &self.toks[start..self.i];
        let mut depth = 0usize;
        let mut out = Vec::new();
        for (k, (t, _)) in toks.iter().enumerate() {
            match t {
                Tok::Punct('(' | '[' | '{') => depth += 1,
                Tok::Punct(')' | ']' | '}') => depth = depth.saturating_sub(1),
                Tok::Word(key) if depth == 1 => {
                    if let (Some((Tok::Punct('='), _)), Some((v, _))) = (toks.get(k + 1), toks.get(k + 2)) {
                        out.push((key.clone(), v.clone()));
                    }
                }
                _ => {}
            }
        }
        Ok(out)
    }

    pub(super) fn value(&mut self) -> Result<Value, FormatError> {
        let line = self.line();
        match self.next("a value")? {
            Tok::Punct(open @ ('[' | '(' | '{')) => {
                let close = match open {
                    '[' => ']',
                    '(' => ')',
                    _ => '}',
                };
                self.enter(line)?;
                let mut items = Vec::new();
                while !self.eat(close) {
                    items.push(self.value()?);
                    self.eat(',');
                    self.eat(':'); // dictionary / time-sample keys
                    self.eat('=');
                }
                self.depth -= 1;
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
