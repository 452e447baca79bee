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

fn fixture_curves() -> HairCurves {
    let mut c = HairCurves::from_strands(two_strands());
    c.thickness = Some(vec![0.1, 0.2, 0.3, 0.4, 0.5]);
    c
}

#[test]
fn writer_matches_fixture_byte_for_byte_and_reader_parses_it() {
    assert_eq!(
        String::from_utf8(usda::write(&fixture_curves()).unwrap()).unwrap(),
        FIXTURE
    );
    assert_eq!(usda::read(FIXTURE.as_bytes()).unwrap(), fixture_curves());
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
    let cubic = FIXTURE.replace("\"linear\"", "\"cubic\"");
    assert!(
        error(&cubic).starts_with(".usda file, line 5: type \"linear\""),
        "{}",
        error(&cubic)
    );
    let untyped = FIXTURE.replace("    uniform token type = \"linear\"\n", "");
    assert_eq!(
        error(&untyped),
        ".usda file, line 3: a `type` attribute with a value in this BasisCurves prim"
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
    let two = format!("{FIXTURE}def BasisCurves \"more\" {{}}\n");
    assert_eq!(
        error(&two),
        ".usda file, line 12: one BasisCurves prim only (the first is at line 3)"
    );
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
