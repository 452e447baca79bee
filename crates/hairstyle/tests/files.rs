//! `read_file` / `write_file` by extension, and `info`.
mod common;
use common::*;
use hairstyle::formats::{info, read_file, write_file, Format, FormatError, HairCurves};

#[test]
fn files_round_trip_by_extension() {
    let dir = std::env::temp_dir().join(format!("coiffure-hairstyle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let c = HairCurves::from_strands(vec![vec![[0.0, 1.0, 2.0]; 4], vec![[3.0, 4.0, 5.0]; 4]]);
    for name in ["a.hair", "a.data", "a.tfx", "a.usda", "A.HAIR"] {
        let path = dir.join(name);
        write_file(&path, &c).unwrap();
        assert_eq!(read_file(&path).unwrap(), c, "{name}");
    }
    let e = write_file(dir.join("a.obj"), &c).unwrap_err();
    assert!(matches!(e, FormatError::UnknownExtension(_)));
    assert!(!dir.join("a.obj").exists());
    let e = read_file(dir.join("missing.hair")).unwrap_err();
    assert!(matches!(e, FormatError::Io { .. }) && e.to_string().contains("missing.hair"));
    // Nothing is written when the data cannot be written in the format.
    let unequal = HairCurves::from_strands(two_strands());
    assert!(write_file(dir.join("b.tfx"), &unequal).is_err());
    assert!(!dir.join("b.tfx").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn format_from_path() {
    assert_eq!(Format::from_path("x/y.usda".as_ref()), Some(Format::Usda));
    assert_eq!(Format::from_path("y.Data".as_ref()), Some(Format::Usc));
    assert_eq!(Format::from_path("y".as_ref()), None);
}

#[test]
fn info_counts_and_bounds() {
    let (ns, np, min, max) = info(&HairCurves::from_strands(two_strands()));
    assert_eq!((ns, np), (2, 5));
    assert_eq!(min, [-7.0, -1.0, 0.0]);
    assert_eq!(max, [4.0, 8.25, 9.0]);
    assert_eq!(info(&HairCurves::default()), (0, 0, [0.0; 3], [0.0; 3]));
}
