//! USC-HairSalon `.data`: hand-made fixture from the specification, round trips, malformed files.
mod common;
use common::*;
use hairstyle::formats::{usc, HairCurves};

fn fixture_bytes() -> Vec<u8> {
    Bytes::default()
        .i32(2) // strands
        .i32(2)
        .f32s(&[0.0, 0.0, 0.0, 1.0, 2.0, 3.0])
        .i32(3)
        .f32s(&[0.5, -1.0, 2.0, 4.0, 5.0, 6.0, -7.0, 8.25, 9.0])
        .0
}

#[test]
fn writer_matches_fixture_byte_for_byte_and_reader_parses_it() {
    let curves = HairCurves::from_strands(two_strands());
    assert_eq!(fixture_bytes().len(), 4 + 4 + 24 + 4 + 36);
    assert_eq!(usc::write(&curves).unwrap(), fixture_bytes());
    assert_eq!(usc::read(&fixture_bytes()).unwrap(), curves);
}

#[test]
fn round_trips_positions_and_drops_attributes() {
    let c = random_curves(40, |i| i % 5, false); // includes empty strands
    assert_eq!(usc::read(&usc::write(&c).unwrap()).unwrap(), c);
    let with = random_curves(3, |_| 4, true);
    let back = usc::read(&usc::write(&with).unwrap()).unwrap();
    assert_eq!(back, HairCurves::from_strands(with.strands));
    assert_eq!(usc::read(&[0, 0, 0, 0]).unwrap(), HairCurves::default());
}

#[test]
fn every_truncation_is_an_error_and_mutations_do_not_panic() {
    every_truncation_errors(&fixture_bytes(), usc::read);
    byte_mutations_do_not_panic(&fixture_bytes(), usc::read);
}

#[test]
fn malformed_files_name_offset_and_expectation() {
    let e = usc::read(&fixture_bytes()[..30]).unwrap_err().to_string();
    assert_eq!(e, ".data file, byte 8: expected points of strand 0 (3 x f32 each): 2 x 12 bytes, but only 22 bytes are left in the file");
    let e = usc::read(&Bytes::default().i32(-1).0)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        ".data file, byte 0: expected a non-negative number of strands, found -1"
    );
    let e = usc::read(&Bytes::default().i32(1).i32(-3).0)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        ".data file, byte 4: expected a non-negative number of points for strand 0, found -3"
    );
    let mut b = fixture_bytes();
    b.extend_from_slice(&[1, 2, 3]);
    assert_eq!(
        usc::read(&b).unwrap_err().to_string(),
        ".data file, byte 72: expected end of file, found 3 more bytes"
    );
    let e = usc::read(&[1, 0]).unwrap_err().to_string();
    assert_eq!(e, ".data file, byte 0: expected number of strands (i32) (4 bytes), but the file ends at byte 2");
}

#[test]
fn absurd_counts_error_before_allocating() {
    let mut b = Bytes::default().i32(i32::MAX).0;
    b.resize(200, 0);
    assert!(usc::read(&b)
        .unwrap_err()
        .to_string()
        .contains("byte 4: expected strand counts"));
    let mut b = Bytes::default().i32(1).i32(i32::MAX).0;
    b.resize(200, 0);
    assert!(usc::read(&b)
        .unwrap_err()
        .to_string()
        .contains("byte 8: expected points of strand 0"));
}
