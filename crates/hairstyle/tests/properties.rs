//! Property-based tests of every hair-file reader (issue 16), with `proptest`: arbitrary bytes and mutated
//! valid files never panic and either read or give an error naming the format and where (byte offset or
//! line); what a writer writes, its reader reads back unchanged. Case counts are modest (the suite runs on
//! two cores); a failing case is shrunk and printed by proptest.

use hairstyle::formats::{hair, tfx, usc, usda, Format, FormatError, HairCurves};
use proptest::prelude::*;

const FORMATS: [(Format, &str); 4] = [(Format::Hair, ".hair"), (Format::Usc, ".data"), (Format::Tfx, ".tfx"), (Format::Usda, ".usda")];

fn config() -> ProptestConfig {
    ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() }
}

/// A point with finite coordinates, including negative zero and tiny and large magnitudes.
fn point() -> impl Strategy<Value = [f32; 3]> {
    let x = prop_oneof![4 => -10.0f32..10.0, 1 => Just(-0.0f32), 1 => Just(1e-40f32), 1 => Just(-3.4e38f32)];
    [x.clone(), x.clone(), x]
}

/// Strands of `len` points each (a range), up to 6 strands.
fn strands(len: std::ops::Range<usize>) -> impl Strategy<Value = Vec<Vec<[f32; 3]>>> {
    prop::collection::vec(prop::collection::vec(point(), len), 0..6)
}

/// Curves with (optionally) every per-vertex attribute (none on curves without points: an empty attribute
/// is not written, so it reads back as absent).
fn curves(len: std::ops::Range<usize>) -> impl Strategy<Value = HairCurves> {
    (strands(len), any::<bool>()).prop_flat_map(|(s, attributes)| {
        let n: usize = s.iter().map(Vec::len).sum();
        let unit = 0.0f32..=1.0;
        let len = if attributes { n } else { 0 };
        (Just(s), prop::collection::vec((unit.clone(), unit.clone(), [unit.clone(), unit.clone(), unit]), len..=len)).prop_map(move |(s, a)| {
            let mut c = HairCurves::from_strands(s);
            if attributes && n > 0 {
                c.thickness = Some(a.iter().map(|x| x.0 * 1e-4).collect());
                c.transparency = Some(a.iter().map(|x| x.1).collect());
                c.color = Some(a.iter().map(|x| x.2).collect());
            }
            c
        })
    })
}

/// A reader's answer to any bytes: curves, or an error that names the format and the place.
fn check_answer(format: Format, name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    match format.read(bytes) {
        Ok(c) => {
            for k in [c.thickness.as_ref().map(Vec::len), c.transparency.as_ref().map(Vec::len), c.color.as_ref().map(Vec::len)].into_iter().flatten() {
                prop_assert_eq!(k, c.num_points(), "{}: an attribute without one value per vertex", name);
            }
        }
        Err(e) => {
            let text = e.to_string();
            match &e {
                FormatError::Binary { format, .. } => prop_assert!(*format == name && text.contains(", byte ") && text.contains("expected"), "{}", text),
                FormatError::Text { format, .. } => prop_assert!(*format == name && text.contains(", line "), "{}", text),
                FormatError::UnsupportedUsd { .. } => prop_assert!(name == ".usda" && text.contains("usdcat"), "{}", text),
                other => prop_assert!(false, "{}: unexpected error kind from bytes: {:?}", name, other),
            }
        }
    }
    Ok(())
}

/// One edit of a file: overwrite a byte, insert one, remove one, or cut the file.
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Remove(usize),
    Truncate(usize),
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Insert(i, b)),
        1 => any::<usize>().prop_map(Edit::Remove),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ];
    prop::collection::vec(edit, 1..6)
}

fn apply(mut b: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let n = b.len().max(1);
        match *e {
            Edit::Set(i, x) if !b.is_empty() => b[i % n] = x,
            Edit::Insert(i, x) => b.insert(i % (b.len() + 1), x),
            Edit::Remove(i) if !b.is_empty() => {
                b.remove(i % n);
            }
            Edit::Truncate(i) => b.truncate(i % n),
            _ => {}
        }
    }
    b
}

/// `.tfx` keeps thickness per strand and no transparency: the curves it can carry unchanged.
fn tfx_curves() -> impl Strategy<Value = HairCurves> {
    (4usize..10).prop_flat_map(|nv| curves(nv..nv + 1)).prop_map(|mut c| {
        c.transparency = None;
        let per_strand: Vec<usize> = c.strands.iter().map(Vec::len).collect();
        if let Some(t) = c.thickness.as_mut() {
            let mut at = 0;
            for len in per_strand {
                let root = t[at];
                t[at..at + len].iter_mut().for_each(|x| *x = root);
                at += len;
            }
        }
        c
    })
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn arbitrary_bytes_never_panic_and_errors_name_format_and_place(bytes in prop::collection::vec(any::<u8>(), 0..400), which in 0usize..4) {
        let (format, name) = FORMATS[which];
        check_answer(format, name, &bytes)?;
    }

    #[test]
    fn text_like_bytes_never_panic_the_usda_reader(text in "#usda 1.0\n(\\PC|[\\[\\](){}=\",;\n ]){0,300}") {
        check_answer(Format::Usda, ".usda", text.as_bytes())?;
    }

    #[test]
    fn mutated_files_never_panic_and_errors_name_format_and_place(c in tfx_curves(), which in 0usize..4, e in edits()) {
        let (format, name) = FORMATS[which];
        let good = format.write(&c).map_err(|e| TestCaseError::fail(e.to_string()))?;
        check_answer(format, name, &apply(good, &e))?;
    }

    #[test]
    fn hair_round_trips(c in curves(1..8)) {
        prop_assert_eq!(hair::read(&hair::write(&c).unwrap()).unwrap(), c);
    }

    #[test]
    fn usc_round_trips_positions(c in curves(0..8)) {
        prop_assert_eq!(usc::read(&usc::write(&c).unwrap()).unwrap(), HairCurves::from_strands(c.strands));
    }

    #[test]
    fn tfx_round_trips(c in tfx_curves()) {
        prop_assert_eq!(tfx::read(&tfx::write(&c).unwrap()).unwrap(), c);
    }

    #[test]
    fn usda_round_trips(c in curves(1..8)) {
        let c = HairCurves { transparency: None, ..c };
        prop_assert_eq!(usda::read(&usda::write(&c).unwrap()).unwrap(), c);
    }
}
