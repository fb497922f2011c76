//! One placement for unit tests: a module's unit tests are its `tests` module (and a
//! `proptests` one for property tests), written inline at the end of the file
//! (`#[cfg(test)] mod tests { .. }`) or, when long, in the module's own folder (`#[cfg(test)]
//! mod tests;`, which reads `<module>/tests.rs` or `<module>/tests/mod.rs`). Not a `*_tests.rs`
//! file beside the module and not a `#[path]` to one: a reader finds a module's tests in one place.

use std::path::{Path, PathBuf};

/// The problems of one source file: a `*_tests.rs` name, or a test module brought in by `#[path]`.
pub fn misplaced(file: &str, text: &str) -> Vec<String> {
    let mut out = Vec::new();
    if file.ends_with("_tests.rs") {
        out.push(format!(
            "{file}: unit tests go in the module's `tests` (inline, or tests.rs in its folder), not a *_tests.rs file"
        ));
    }
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    for (i, _) in lines.iter().enumerate().filter(|(_, l)| **l == "#[cfg(test)]") {
        // The attributes between `#[cfg(test)]` and the item it guards.
        let attrs = lines[i + 1..].iter().take_while(|l| l.starts_with("#["));
        if let Some(path) = attrs.into_iter().find(|l| l.starts_with("#[path")) {
            out.push(format!(
                "{file}:{}: a test module at {path}: unit tests go in the module's `tests` (inline, or tests.rs in its folder)",
                i + 1
            ));
        }
    }
    out
}

/// Every `.rs` file below `dir` (no recursion per folder: a list of folders to visit).
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let (mut out, mut todo) = (Vec::new(), vec![dir.to_path_buf()]);
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = entry.path();
            if p.is_dir() {
                todo.push(p);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn misplaced_tests_are_found_and_the_two_placements_pass() {
    let inline = "pub fn f() {}\n\n#[cfg(test)]\nmod tests {\n    #[test]\n    fn t() {}\n}\n";
    let folder = "pub fn f() {}\n\n#[cfg(test)]\nmod tests;\n";
    assert!(misplaced("src/a.rs", inline).is_empty());
    assert!(misplaced("src/a.rs", folder).is_empty());
    assert!(misplaced("src/a/tests.rs", "#[test]\nfn t() {}\n").is_empty());
    let pathed = "pub fn f() {}\n\n#[cfg(test)]\n#[path = \"a_tests.rs\"]\nmod tests;\n";
    assert_eq!(
        misplaced("src/a.rs", pathed),
        vec![
            "src/a.rs:3: a test module at #[path = \"a_tests.rs\"]: unit tests go in the module's `tests` (inline, or tests.rs in its folder)"
        ]
    );
    assert_eq!(misplaced("src/a_tests.rs", "#[test]\nfn t() {}\n").len(), 1);
}
