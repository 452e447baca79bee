//! The code's layout (issue 33): no import circle inside any crate of the workspace, and no source file over
//! [`MAX_SOURCE_LINES`] lines of non-test code. The check is
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

/// Most lines of non-test code (everything before a file's first `#[cfg(test)]`, comments and blank lines
/// included) in one Rust source file under `crates/*/src` (issue 33: a newcomer reads a file as one concept).
const MAX_SOURCE_LINES: usize = 700;

#[test]
fn no_source_file_is_over_700_lines_of_non_test_code() {
    let crates = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    let mut dirs: Vec<_> = std::fs::read_dir(&crates).unwrap().flatten().map(|e| e.path().join("src")).filter(|p| p.is_dir()).collect();
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    assert!(files.len() > 50, "found the sources: {}", files.len());
    let mut sizes: Vec<(usize, String)> = files.iter().map(|f| {
        let text = std::fs::read_to_string(f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        (code.lines().count(), f.strip_prefix(&crates).unwrap().display().to_string())
    }).collect();
    sizes.sort();
    let largest = sizes.last().unwrap();
    println!("{} source files; largest {} lines of non-test code ({})", sizes.len(), largest.0, largest.1);
    let over: Vec<_> = sizes.iter().filter(|(n, _)| *n > MAX_SOURCE_LINES).collect();
    assert!(over.is_empty(), "files over {MAX_SOURCE_LINES} lines of non-test code: {over:?}");
}
