//! AMD TressFX 4 `.tfx`: hand-made fixtures from the specification, round trips, resampling,
//! malformed files.
mod common;
use common::*;
use hairstyle::formats::{tfx, FormatError, HairCurves};

fn strand(i: usize) -> Vec<[f32; 3]> {
    (0..4)
        .map(|j| [i as f32, j as f32 * 0.5, -(j as f32)])
        .collect()
}

/// Header from the specification: version, counts, 5 offsets, 32 reserved words.
fn header(ns: u32, offsets: [u32; 5]) -> Bytes {
    let b = Bytes::default().f32(4.0).u32(ns).u32(4);
    offsets.iter().fold(b, |b, &o| b.u32(o)).zeros(32 * 4)
}

fn positions(b: Bytes, ns: usize) -> Bytes {
    (0..ns).fold(b, |b, i| {
        strand(i)
            .iter()
            .enumerate()
            .fold(b, |b, (j, p)| b.f32s(p).f32(if j == 0 { 0.0 } else { 1.0 }))
    })
}

#[test]
fn header_size_adds_up() {
    assert_eq!(tfx::HEADER_SIZE, 4 + 4 + 4 + 5 * 4 + 32 * 4);
    assert_eq!(header(0, [0; 5]).0.len(), 160);
}

#[test]
fn positions_only_fixture() {
    let bytes = positions(header(2, [160, 0, 0, 0, 0]), 2).0;
    assert_eq!(bytes.len(), 160 + 2 * 4 * 16);
    let curves = HairCurves::from_strands(vec![strand(0), strand(1)]);
    assert_eq!(tfx::write(&curves).unwrap(), bytes);
    assert_eq!(tfx::read(&bytes).unwrap(), curves);
}

#[test]
fn thickness_and_colour_fixture_with_alignment_padding() {
    // 3 strands x 4 vertices: positions 160..352, thickness 352..364, pad to 368, colours 368..560.
    let b = positions(header(3, [160, 0, 0, 352, 368]), 3)
        .f32s(&[0.1, 0.2, 0.3])
        .zeros(4);
    let colours: Vec<[f32; 3]> = (0..12).map(|k| [k as f32 / 12.0, 0.5, 1.0]).collect();
    let bytes = colours.iter().fold(b, |b, c| b.f32s(c).f32(1.0)).0;
    assert_eq!(bytes.len(), 560);
    let curves = HairCurves {
        strands: (0..3).map(strand).collect(),
        thickness: Some([0.1, 0.2, 0.3].iter().flat_map(|&t| [t; 4]).collect()),
        transparency: None,
        color: Some(colours),
    };
    assert_eq!(tfx::write(&curves).unwrap(), bytes);
    assert_eq!(tfx::read(&bytes).unwrap(), curves);
    every_truncation_errors(&bytes, tfx::read);
    byte_mutations_do_not_panic(&bytes, tfx::read);
}

#[test]
fn reader_ignores_w_and_alpha_and_checks_uvs() {
    // Strand UVs at 288 (2 x 8 bytes) and vertex UVs at 304 (8 x 8 bytes); end 368.
    let b = positions(header(2, [160, 288, 304, 0, 0]), 2)
        .zeros(16 + 64)
        .0;
    assert_eq!(tfx::read(&b).unwrap().strands, vec![strand(0), strand(1)]);
    let e = tfx::read(&b[..367]).unwrap_err().to_string();
    assert!(
        e.starts_with(
            ".tfx file, byte 20: expected offset of the vertex UVs (64 bytes) from 304 inside"
        ),
        "{e}"
    );
}

#[test]
fn round_trips() {
    let mut c = random_curves(30, |_| 16, true);
    c.transparency = None; // not carried by .tfx
                           // Thickness is per strand in .tfx.
    let t: Vec<f32> = c
        .thickness
        .as_ref()
        .unwrap()
        .chunks(16)
        .flat_map(|s| [s[0]; 16])
        .collect();
    c.thickness = Some(t);
    assert_eq!(tfx::read(&tfx::write(&c).unwrap()).unwrap(), c);
    let empty = HairCurves::default();
    assert_eq!(tfx::read(&tfx::write(&empty).unwrap()).unwrap(), empty);
}

#[test]
fn unequal_or_out_of_range_strands_are_refused_unless_resampled() {
    let c = HairCurves::from_strands(two_strands());
    let e = tfx::write(&c).unwrap_err();
    assert!(matches!(e, FormatError::Unwritable { .. }));
    assert!(
        e.to_string().contains("strand 0 has 2 and strand 1 has 3"),
        "{e}"
    );
    let short = HairCurves::from_strands(vec![vec![[0.0; 3]; 3]]);
    assert!(tfx::write(&short)
        .unwrap_err()
        .to_string()
        .contains("3 vertices per strand"));

    let mut c = c;
    c.thickness = Some(vec![1.0, 3.0, 2.0, 2.0, 2.0]);
    let r = tfx::resample(&c, 5).unwrap();
    assert!(r.strands.iter().all(|s| s.len() == 5));
    let s0 = &r.strands[0];
    assert_eq!((s0[0], s0[4]), ([0.0; 3], [1.0, 2.0, 3.0]));
    assert!((s0[2][1] - 1.0).abs() < 1e-6); // half way along
    assert!((r.thickness.as_ref().unwrap()[2] - 2.0).abs() < 1e-6);
    assert_eq!(r.strands[1][4], [-7.0, 8.25, 9.0]);
    let back = tfx::read(&tfx::write(&r).unwrap()).unwrap();
    assert_eq!(back.strands, r.strands);
    assert!(tfx::resample(&c, 1).is_err());
}

#[test]
fn malformed_files_name_offset_and_expectation() {
    let good = positions(header(2, [160, 0, 0, 0, 0]), 2).0;
    let mut b = good.clone();
    b[8] = 3;
    assert_eq!(
        tfx::read(&b).unwrap_err().to_string(),
        ".tfx file, byte 8: expected 4 to 64 vertices per strand, found 3"
    );
    let mut b = good.clone();
    b[12] = 0;
    b[13] = 0;
    assert!(tfx::read(&b)
        .unwrap_err()
        .to_string()
        .contains("byte 12: expected a non-zero offset of the vertex positions"));
    let mut b = good;
    b[12] = 100; // inside the header
    assert!(tfx::read(&b)
        .unwrap_err()
        .to_string()
        .starts_with(".tfx file, byte 12:"));
}

#[test]
fn absurd_counts_error_before_allocating() {
    let mut b = header(u32::MAX, [160, 0, 0, 0, 0]).0;
    b.resize(200, 0);
    let e = tfx::read(&b).unwrap_err().to_string();
    assert!(
        e.starts_with(
            ".tfx file, byte 12: expected offset of the vertex positions (274877906880 bytes)"
        ),
        "{e}"
    );
}
