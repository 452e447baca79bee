//! Helpers shared by the format tests: explicit little-endian byte building (independent of the
//! writers), sample data, and fuzz-like checks.
#![allow(dead_code)]

use hairstyle::formats::{FormatError, HairCurves};

/// Bytes built by explicit little-endian pushes.
#[derive(Default)]
pub struct Bytes(pub Vec<u8>);

impl Bytes {
    pub fn u16(mut self, v: u16) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn u32(mut self, v: u32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn i32(mut self, v: i32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn f32(mut self, v: f32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn f32s(self, vs: &[f32]) -> Self {
        vs.iter().fold(self, |b, &v| b.f32(v))
    }
    pub fn raw(mut self, bytes: &[u8]) -> Self {
        self.0.extend_from_slice(bytes);
        self
    }
    pub fn zeros(mut self, n: usize) -> Self {
        self.0.resize(self.0.len() + n, 0);
        self
    }
}

/// Two strands of 2 and 3 points.
pub fn two_strands() -> Vec<Vec<[f32; 3]>> {
    vec![
        vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]],
        vec![[0.5, -1.0, 2.0], [4.0, 5.0, 6.0], [-7.0, 8.25, 9.0]],
    ]
}

/// Deterministic pseudo-random curves: `ns` strands of `len(i)` points, with awkward values.
pub fn random_curves(ns: usize, len: impl Fn(usize) -> usize, attributes: bool) -> HairCurves {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.6
    };
    let mut strands: Vec<Vec<[f32; 3]>> = (0..ns)
        .map(|i| (0..len(i)).map(|_| [next(), next(), next()]).collect())
        .collect();
    if let Some(p) = strands.first_mut().and_then(|s| s.first_mut()) {
        *p = [-0.0, 1e-40, 3.4e38]; // negative zero, subnormal, huge
    }
    let n: usize = strands.iter().map(Vec::len).sum();
    let mut curves = HairCurves::from_strands(strands);
    if attributes {
        curves.thickness = Some((0..n).map(|_| next().abs() * 1e-4).collect());
        curves.transparency = Some((0..n).map(|_| next().abs()).collect());
        curves.color = Some(
            (0..n)
                .map(|_| [next().abs(), next().abs(), next().abs()])
                .collect(),
        );
    }
    curves
}

/// Every strict truncation of `bytes` must be an error (and must not panic).
pub fn every_truncation_errors(bytes: &[u8], read: fn(&[u8]) -> Result<HairCurves, FormatError>) {
    for len in 0..bytes.len() {
        assert!(
            read(&bytes[..len]).is_err(),
            "truncation to {len} of {} bytes was accepted",
            bytes.len()
        );
    }
}

/// Overwriting any single byte with a few values must not panic (errors or data are both fine).
pub fn byte_mutations_do_not_panic(
    bytes: &[u8],
    read: fn(&[u8]) -> Result<HairCurves, FormatError>,
) {
    for i in 0..bytes.len() {
        for v in [0x00, 0x01, 0x7f, 0x80, 0xff, b'"', b'[', b'}'] {
            let mut b = bytes.to_vec();
            b[i] = v;
            let _ = read(&b);
        }
    }
}
