//! The code's layout (issue 33): no import circle inside any crate of the workspace. The check is
//! `scripts/import_circles.py` (file -> file edges from `use crate::` and `super::` paths, strongly connected
//! components), which a developer runs by hand too; this test fails with its list of circles.

#[test]
fn no_crate_has_an_import_circle() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = std::process::Command::new("python3")
        .arg(root.join("scripts/import_circles.py"))
        .arg(&root)
        .output()
        .expect("python3 runs scripts/import_circles.py");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert!(text.contains("0 import circle(s) inside a crate") && out.status.success(), "import circles:\n{text}{}", String::from_utf8_lossy(&out.stderr));
}
