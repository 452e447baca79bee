//! Cem Yuksel's `.hair`: hand-made fixtures from the specification, round trips, malformed files.
mod common;
use common::*;
use hairstyle::formats::{hair, FormatError, HairCurves};

fn info_text() -> Vec<u8> {
    let mut t = b"Coiffure".to_vec();
    t.resize(88, 0);
    t
}

fn fixture_curves() -> HairCurves {
    HairCurves {
        strands: two_strands(),
        thickness: Some(vec![0.1, 0.2, 0.3, 0.4, 0.5]),
        transparency: Some(vec![0.0, 0.25, 0.5, 0.75, 1.0]),
        color: Some(vec![
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.5],
            [0.25, 0.125, 1.0],
        ]),
    }
}

/// Written from the specification: header, then segments, points, thickness, transparency, colour.
fn fixture_bytes() -> Vec<u8> {
    Bytes::default()
        .raw(b"HAIR")
        .u32(2) // strands
        .u32(5) // points
        .u32(0b1_1111) // all five arrays
        .u32(0) // default segments
        .f32(1.0) // default thickness
        .f32(0.0) // default transparency
        .f32s(&[1.0, 1.0, 1.0]) // default colour
        .raw(&info_text())
        .u16(1)
        .u16(2) // segments: 2 and 3 points
        .f32s(&[0.0, 0.0, 0.0, 1.0, 2.0, 3.0])
        .f32s(&[0.5, -1.0, 2.0, 4.0, 5.0, 6.0, -7.0, 8.25, 9.0])
        .f32s(&[0.1, 0.2, 0.3, 0.4, 0.5])
        .f32s(&[0.0, 0.25, 0.5, 0.75, 1.0])
        .f32s(&[
            1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 0.25, 0.125, 1.0,
        ])
        .0
}

#[test]
fn header_is_128_bytes_and_fixture_size_adds_up() {
    assert_eq!(hair::HEADER_SIZE, 4 + 4 * 4 + 4 + 4 + 12 + 88);
    assert_eq!(fixture_bytes().len(), 128 + 2 * 2 + 5 * (12 + 4 + 4 + 12));
}

#[test]
fn writer_matches_fixture_byte_for_byte() {
    assert_eq!(hair::write(&fixture_curves()).unwrap(), fixture_bytes());
}

#[test]
fn reader_parses_fixture() {
    assert_eq!(hair::read(&fixture_bytes()).unwrap(), fixture_curves());
    let h = hair::read_header(&fixture_bytes()).unwrap();
    assert_eq!(
        (h.num_strands, h.num_points, h.flags, h.default_thickness),
        (2, 5, 31, 1.0)
    );
}

#[test]
fn positions_only_fixture() {
    let bytes = Bytes::default()
        .raw(b"HAIR")
        .u32(2)
        .u32(5)
        .u32(0b11)
        .u32(0)
        .f32(1.0)
        .f32(0.0)
        .f32s(&[1.0, 1.0, 1.0])
        .raw(&info_text())
        .u16(1)
        .u16(2)
        .f32s(&[
            0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 0.5, -1.0, 2.0, 4.0, 5.0, 6.0, -7.0, 8.25, 9.0,
        ])
        .0;
    let curves = HairCurves::from_strands(two_strands());
    assert_eq!(hair::write(&curves).unwrap(), bytes);
    assert_eq!(hair::read(&bytes).unwrap(), curves);
}

#[test]
fn default_segments_without_segments_array() {
    // Points array only; every strand has the default 2 segments (3 points); thickness default 0.5.
    let bytes = Bytes::default()
        .raw(b"HAIR")
        .u32(2)
        .u32(6)
        .u32(0b10)
        .u32(2)
        .f32(0.5)
        .f32(0.0)
        .f32s(&[1.0, 1.0, 1.0])
        .zeros(88)
        .f32s(&(0..18).map(|i| i as f32).collect::<Vec<_>>())
        .0;
    let c = hair::read(&bytes).unwrap();
    assert_eq!(c.strands.len(), 2);
    assert_eq!(
        c.strands[1],
        vec![[9.0, 10.0, 11.0], [12.0, 13.0, 14.0], [15.0, 16.0, 17.0]]
    );
    assert_eq!(c.thickness, None);
    assert_eq!(hair::read_header(&bytes).unwrap().default_thickness, 0.5);
}

#[test]
fn round_trips() {
    for attributes in [false, true] {
        let c = random_curves(50, |i| 1 + i % 7, attributes);
        let back = hair::read(&hair::write(&c).unwrap()).unwrap();
        assert_eq!(back, c);
        assert_eq!(back.strands[0][0][0].to_bits(), (-0.0f32).to_bits());
    }
    let empty = HairCurves::default();
    assert_eq!(hair::read(&hair::write(&empty).unwrap()).unwrap(), empty);
}

#[test]
fn every_truncation_is_an_error_and_mutations_do_not_panic() {
    every_truncation_errors(&fixture_bytes(), hair::read);
    byte_mutations_do_not_panic(&fixture_bytes(), hair::read);
}

fn message(e: FormatError) -> String {
    e.to_string()
}

#[test]
fn malformed_files_name_offset_and_expectation() {
    let mut b = fixture_bytes();
    b[0] = b'X';
    assert_eq!(
        message(hair::read(&b).unwrap_err()),
        ".hair file, byte 0: expected signature \"HAIR\""
    );

    let t = message(hair::read(&fixture_bytes()[..200]).unwrap_err());
    assert!(
        t.starts_with(".hair file, byte 4: expected") && t.contains("72 bytes after it"),
        "{t}"
    );

    let mut b = fixture_bytes();
    b.push(0);
    let t = message(hair::read(&b).unwrap_err());
    assert_eq!(
        t,
        ".hair file, byte 292: expected end of file, found 1 more bytes"
    );

    let mut b = fixture_bytes();
    b[128] = 7; // first strand claims 8 points
    assert!(message(hair::read(&b).unwrap_err())
        .starts_with(".hair file, byte 128: expected segments adding up to 5"));

    let mut b = fixture_bytes();
    b[12] = 0b1_1101; // points bit clear
    assert!(message(hair::read(&b).unwrap_err()).contains("byte 12"));
    b[12] = 0xff; // unknown bits
    assert!(message(hair::read(&b).unwrap_err()).contains("bits 0 to 4 only"));
}

#[test]
fn absurd_counts_error_before_allocating() {
    // 4 billion points in a 200-byte file.
    let mut b = Bytes::default()
        .raw(b"HAIR")
        .u32(1)
        .u32(4_000_000_000)
        .u32(0b11)
        .u32(0)
        .f32(1.0)
        .f32(0.0)
        .f32s(&[1.0; 3])
        .zeros(88)
        .0;
    b.resize(200, 0);
    assert!(message(hair::read(&b).unwrap_err()).starts_with(".hair file, byte 4:"));
    // 4 billion strands without a segments array (default segments), no points.
    let b = Bytes::default()
        .raw(b"HAIR")
        .u32(u32::MAX)
        .u32(0)
        .u32(0b10)
        .u32(u32::MAX)
        .f32(1.0)
        .f32(0.0)
        .f32s(&[1.0; 3])
        .zeros(88)
        .0;
    assert!(hair::read(&b).is_err());
    let b = Bytes::default()
        .raw(b"HAIR")
        .u32(u32::MAX)
        .u32(u32::MAX)
        .u32(0b1_1111)
        .u32(0)
        .f32(1.0)
        .f32(0.0)
        .f32s(&[1.0; 3])
        .zeros(88)
        .0;
    assert!(hair::read(&b).is_err());
}

#[test]
fn unwritable_data_is_refused() {
    let mut c = HairCurves::from_strands(vec![vec![]]);
    assert!(matches!(
        hair::write(&c),
        Err(FormatError::Unwritable { .. })
    ));
    c = HairCurves::from_strands(two_strands());
    c.thickness = Some(vec![1.0]);
    assert!(hair::write(&c)
        .unwrap_err()
        .to_string()
        .contains("thickness has 1 values for 5 vertices"));
}
