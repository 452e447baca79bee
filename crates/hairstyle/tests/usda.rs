//! USD `BasisCurves` `.usda`: hand-written fixture, round trips, tolerant parsing, errors.
mod common;
use common::*;
use hairstyle::formats::{usda, HairCurves};

const FIXTURE: &str = r#"#usda 1.0

def BasisCurves "hair"
{
    uniform token type = "linear"
    int[] curveVertexCounts = [2, 3]
    point3f[] points = [(0, 0, 0), (1, 2, 3), (0.5, -1, 2), (4, 5, 6), (-7, 8.25, 9)]
    float[] widths = [0.1, 0.2, 0.3, 0.4, 0.5] (
        interpolation = "vertex"
    )
}
"#;

/// What the writer gives for the fixture's curves: stage metadata (metres, z up, default prim) and
/// the curves under `/hair/strands`.
const WRITTEN: &str = r#"#usda 1.0
(
    defaultPrim = "hair"
    metersPerUnit = 1
    upAxis = "Z"
)

def Xform "hair"
{
    def BasisCurves "strands"
    {
        uniform token type = "linear"
        int[] curveVertexCounts = [2, 3]
        point3f[] points = [(0, 0, 0), (1, 2, 3), (0.5, -1, 2), (4, 5, 6), (-7, 8.25, 9)]
        float[] widths = [0.1, 0.2, 0.3, 0.4, 0.5] (
            interpolation = "vertex"
        )
    }
}
"#;

fn fixture_curves() -> HairCurves {
    let mut c = HairCurves::from_strands(two_strands());
    c.thickness = Some(vec![0.1, 0.2, 0.3, 0.4, 0.5]);
    c
}

#[test]
fn writer_matches_fixture_byte_for_byte_and_reader_parses_it() {
    assert_eq!(
        String::from_utf8(usda::write(&fixture_curves()).unwrap()).unwrap(),
        WRITTEN
    );
    assert_eq!(usda::read(FIXTURE.as_bytes()).unwrap(), fixture_curves());
    let (c, meta) = usda::read_stage(WRITTEN.as_bytes()).unwrap();
    assert_eq!(c, fixture_curves());
    assert_eq!((meta.meters_per_unit, meta.up_axis), (Some(1.0), Some('Z')));
    assert_eq!(usda::read_stage(FIXTURE.as_bytes()).unwrap().1, usda::StageMetadata::default());
    // equal widths are written as one constant value
    let mut same = fixture_curves();
    same.thickness = Some(vec![7e-5; 5]);
    let text = String::from_utf8(usda::write(&same).unwrap()).unwrap();
    assert!(text.contains("float[] widths = [0.00007] (\n            interpolation = \"constant\""), "{text}");
    assert_eq!(usda::read(text.as_bytes()).unwrap(), same);
}

/// Cubic curves (USD's fallback type) of each basis, evaluated to polylines: end points and
/// interpolated points where the basis passes through control points, and the known values in
/// between; widths per control point evaluated with the same basis.
#[test]
fn cubic_curves_of_every_basis() {
    let stage = |body: &str| format!("#usda 1.0\n(\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\ndef Xform \"root\" {{\n def Xform \"group\" {{\n  def BasisCurves \"c\" {{\n{body}\n  }}\n }}\n}}\n");
    // bezier (the fallback basis, type unauthored = cubic): 7 control points, 2 segments
    let bez = stage("int[] curveVertexCounts = [7]\npoint3f[] points = [(0,0,0),(1,0,0),(2,0,0),(3,0,0),(3,1,0),(3,2,0),(3,3,0)]\nfloat[] widths = [1,1,1,1,3,3,3]");
    let (c, meta) = usda::read_stage(bez.as_bytes()).unwrap();
    assert_eq!((meta.meters_per_unit, meta.up_axis), (Some(0.01), Some('Y')));
    let s = &c.strands[0];
    assert_eq!(s.len(), 2 * usda::basis::SAMPLES_PER_SEGMENT + 1);
    assert_eq!((s[0], s[4], s[8]), ([0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 3.0, 0.0]));
    assert_eq!(s[2], [1.5, 0.0, 0.0]); // middle of a straight segment with evenly spaced control points
    let w = c.thickness.unwrap();
    assert_eq!((w[0], w[4], w[6], w[8]), (1.0, 1.0, 2.75, 3.0)); // (1 + 3 x 3 + 3 x 3 + 3) / 8 at t = 1/2
    // bspline, nonperiodic: 5 points, 2 segments, starting at (P0 + 4 P1 + P2) / 6
    let bs = stage("uniform token type = \"cubic\"\nuniform token basis = \"bspline\"\nint[] curveVertexCounts = [5]\npoint3f[] points = [(0,0,0),(6,0,0),(6,6,0),(0,6,0),(0,12,0)]");
    let s = usda::read(bs.as_bytes()).unwrap().strands[0].clone();
    assert_eq!((s.len(), s[0], s[8]), (9, [5.0, 1.0, 0.0], [1.0, 7.0, 0.0])); // ends at (P2 + 4 P3 + P4) / 6
    // bspline, pinned: passes through both ends
    let pinned = bs.replace("\"bspline\"", "\"bspline\"\nuniform token wrap = \"pinned\"");
    let s = usda::read(pinned.as_bytes()).unwrap().strands[0].clone();
    assert_eq!((s.len(), s[0], s[16]), (17, [0.0, 0.0, 0.0], [0.0, 12.0, 0.0]));
    // catmullRom: passes through P1 .. Pn-2
    let cr = bs.replace("bspline", "catmullRom");
    let s = usda::read(cr.as_bytes()).unwrap().strands[0].clone();
    assert_eq!((s[0], s[4], s[8]), ([6.0, 0.0, 0.0], [6.0, 6.0, 0.0], [0.0, 6.0, 0.0]));
    // the control point count must suit the basis
    let e = usda::read(bez.replace("[7]", "[6]").replace("(3,3,0)]", "]").as_bytes()).unwrap_err().to_string();
    assert!(e.contains("curve 0: a nonperiodic bezier curve needs 4 + 3k control points, found 6"), "{e}");
    let e = usda::read(bs.replace("bspline", "hermite").as_bytes()).unwrap_err().to_string();
    assert!(e.contains("basis \"bezier\", \"bspline\" or \"catmullRom\""), "{e}");
}

#[test]
fn binary_and_zipped_usd_are_refused_naming_the_workaround() {
    let e = usda::read(b"PXR-USDC\0\0\0\0").unwrap_err().to_string();
    assert!(e.contains("usdcat") && e.contains("rustc 1.96"), "{e}");
    let e = hairstyle::formats::read_file("no/such/file.usdz").unwrap_err().to_string();
    assert!(e.starts_with("no/such/file.usdz: binary (.usdc) and zipped (.usdz) USD cannot be read"), "{e}");
}

#[test]
fn round_trips() {
    let mut c = random_curves(20, |i| 1 + i % 6, true);
    c.transparency = None; // not written to .usda
    let back = usda::read(&usda::write(&c).unwrap()).unwrap();
    assert_eq!(back, c);
    assert_eq!(back.strands[0][0][0].to_bits(), (-0.0f32).to_bits());
    let empty = HairCurves::default();
    assert_eq!(usda::read(&usda::write(&empty).unwrap()).unwrap(), empty);
}

#[test]
fn reasonably_formatted_equivalents() {
    let text = r#"#usda 1.0
(
    defaultPrim = "root"
    metersPerUnit = 0.01
    upAxis = "Y"
    doc = """multi
line"""
)

# a comment
def Xform "root" (
    kind = "component"
)
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]
    def Scope "looks" {}

    def BasisCurves "hair" (prepend apiSchemas = ["MaterialBindingAPI"])
    {
        rel material:binding = </root/looks/mat>
        float3[] extent = [(-7, -1, 0), (4, 8.25, 9)]
        int[] curveVertexCounts = [
            2,
            3,
        ]
        point3f[] points.timeSamples = { 0: [(9, 9, 9)], 1: [(8, 8, 8)] }
        point3f[] points = [(0,0,0),(1,2,3),
                            (0.5,-1,2),(4,5,6),(-7,8.25,9e0)]  # trailing comment
        custom uniform token type = "linear"
        uniform token wrap = "nonperiodic"
        float[] widths = [0.25] (interpolation = "constant")
        color3f[] primvars:displayColor = [(1, 0, 0), (0, 0, 1)] (
            interpolation = "uniform"
            elementSize = 1
        )
    }
}
"#;
    let c = usda::read(text.as_bytes()).unwrap();
    assert_eq!(c.strands, two_strands());
    assert_eq!(c.thickness, Some(vec![0.25; 5]));
    let (r, b) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    assert_eq!(c.color, Some(vec![r, r, b, b, b]));
}

#[test]
fn every_truncation_errors_or_only_loses_trailing_whitespace() {
    let full = FIXTURE.as_bytes();
    let last = FIXTURE.rfind('}').unwrap();
    for len in 0..full.len() {
        match usda::read(&full[..len]) {
            Ok(c) => assert!(
                len > last && c == fixture_curves(),
                "truncation to {len} accepted"
            ),
            Err(_) => assert!(len <= last, "truncation to {len} refused"),
        }
    }
    byte_mutations_do_not_panic(full, usda::read);
}

fn error(text: &str) -> String {
    usda::read(text.as_bytes()).unwrap_err().to_string()
}

#[test]
fn malformed_files_name_the_line_and_expectation() {
    assert_eq!(error("#usda"), ".usda file, line 1: the header `#usda 1.0`");
    assert_eq!(
        error("#usda 1.0\n"),
        ".usda file, line 1: a `def BasisCurves` prim, found none"
    );
    let cubic = FIXTURE.replace("\"linear\"", "\"quintic\"");
    assert_eq!(
        error(&cubic),
        ".usda file, line 5: type \"linear\" or \"cubic\", found \"quintic\""
    );
    // an unauthored type is USD's fallback, cubic (bezier): 2 points are not a bezier curve
    let untyped = FIXTURE.replace("    uniform token type = \"linear\"\n", "");
    assert_eq!(
        error(&untyped),
        ".usda file, line 5: curve 0: a nonperiodic bezier curve needs 4 + 3k control points, found 2"
    );
    let points = FIXTURE.replace("    point3f[] points", "    point3f[] other");
    assert_eq!(
        error(&points),
        ".usda file, line 3: a `points` attribute with a value in this BasisCurves prim"
    );
    let counts = FIXTURE.replace("[2, 3]", "[2, 4]");
    assert_eq!(
        error(&counts),
        ".usda file, line 7: 6 points (the sum of curveVertexCounts), found 5"
    );
    let bad = FIXTURE.replace("8.25", "8.2.5");
    assert_eq!(error(&bad), ".usda file, line 7: a number, found `8.2.5`");
    let widths = FIXTURE.replace("0.4, 0.5]", "0.4]");
    assert!(error(&widths)
        .starts_with(".usda file, line 8: 5 (vertex), 2 (uniform) or 1 (constant) values"));
    let unterminated = FIXTURE.replace("\"hair\"", "\"hair");
    assert!(
        error(&unterminated).starts_with(".usda file, line 3: a closing quote on the same line")
    );
    // several BasisCurves prims: their curves one after the other
    let two = format!("{FIXTURE}{}", &FIXTURE[FIXTURE.find("def").unwrap()..]);
    let c = usda::read(two.as_bytes()).unwrap();
    assert_eq!(c.strands.len(), 4);
    assert_eq!(c.thickness.unwrap().len(), 10);
    let mut bytes = FIXTURE.as_bytes().to_vec();
    bytes[FIXTURE.find("uniform").unwrap()] = 0xff;
    assert!(usda::read(&bytes)
        .unwrap_err()
        .to_string()
        .starts_with(".usda file, line 5: UTF-8 text"));
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let deep = format!("#usda 1.0\n({}", "[".repeat(100_000));
    assert!(error(&deep).contains("at most 100 nested"));
    let prims = format!("#usda 1.0\n{}", "def \"a\" {\n".repeat(100_000));
    assert!(error(&prims).contains("at most 100 nested"));
}

#[test]
fn huge_or_fractional_counts_are_errors() {
    let huge = FIXTURE.replace("[2, 3]", "[4294967295, 4294967295, 4294967295]");
    assert!(
        error(&huge).contains("line 7: 12884901885 points"),
        "{}",
        error(&huge)
    );
    let frac = FIXTURE.replace("[2, 3]", "[2.5, 2.5]");
    assert_eq!(
        error(&frac),
        ".usda file, line 6: a vertex count (integer from 0 to 2^32 - 1), found `2.5`"
    );
}
