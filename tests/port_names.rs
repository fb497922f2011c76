//! A port's name is written once, in its `node!`/`ports!` declaration. A string literal equal
//! to a port name anywhere else in a node crate's code is a port read or an error message that
//! would silently go stale when the port is renamed (use the typed field, or `port!(Node, field)`).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use pyrograph_testing::workspace;

/// Source files of the node crates and the core, without test modules and test files.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if path.is_dir() {
            if name != "tests" {
                sources(&path, out);
            }
        } else if name.ends_with(".rs") && name != "tests.rs" {
            out.push(path);
        }
    }
}

/// The simple string literals (`"snake_case"`) of a line of code, except option names of a
/// `choice!` variant (`Cloth = "cloth"`), which name options, not ports.
fn literals(line: &str) -> Vec<&str> {
    let code = line.trim_start();
    if code.starts_with("//") {
        return Vec::new();
    }
    let choice_variant = code
        .split_once(" = \"")
        .is_some_and(|(lhs, _)| lhs.chars().next().is_some_and(|c| c.is_ascii_uppercase()) && !lhs.contains(' '));
    if choice_variant {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(start) = rest.find('"') {
        let after = &rest[start + 1..];
        let Some(end) = after.find('"') else { break };
        let lit = &after[..end];
        if !lit.is_empty() && lit.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_') {
            out.push(lit);
        }
        rest = &after[end + 1..];
    }
    out
}

/// Literals that equal a port name but are not one: `(file, literal, why)`.
const NOT_PORTS: &[(&str, &str, &str)] = &[
    ("crates/core/src/node.rs", "source", "the name of TimeDep::Source in listings"),
    (
        "crates/core/src/builtin.rs",
        "path",
        "INCLUDE_PATH: graph.include is built by the loader from its file, not declared with node!",
    ),
    ("nodes/flame-model/src/arp/sampler.rs", "height", "a column name of a parameter series"),
    ("nodes/flame-model/src/model/fit.rs", "height", "a column name of a parameter series"),
    ("nodes/flame-model/src/arp/mod.rs", "log_likelihood", "the column name of the likelihood series"),
    ("nodes/flame-model/src/model/mod.rs", "frame", "a column name of the fit's quality series"),
    ("nodes/particles/src/wind.rs", "k_g", "a field of a connected wind value, named in its validation error"),
    ("nodes/particles/src/wind.rs", "k_p", "a field of a connected wind value, named in its validation error"),
    ("nodes/particles/src/wind.rs", "k_s", "a field of a connected wind value, named in its validation error"),
    ("nodes/particles/src/wind.rs", "height_unit", "a field of a connected wind value, named in its validation error"),
    ("nodes/particles/src/wind.rs", "gravity", "a field of a connected wind value, named in its validation error"),
    ("nodes/imaging/src/video/probe.rs", "width", "a key of ffprobe's output"),
    ("nodes/imaging/src/video/probe.rs", "height", "a key of ffprobe's output"),
    ("nodes/imaging/src/preprocess/hsv.rs", "blend", "the hand-written Field impl of an HSV layer is its declaration"),
    ("crates/core/src/anim/channel.rs", "frame", "a key's frame, named in its error"),
    ("crates/core/src/anim/channel.rs", "value", "a key's value, named in its error"),
    ("crates/core/src/anim/mod.rs", "alpha", "a colour component, named in errors"),
    ("crates/core/src/anim/mod.rs", "x", "a vector component, named in errors"),
    ("crates/core/src/anim/mod.rs", "y", "a vector component, named in errors"),
    ("crates/core/src/anim/expr.rs", "frame", "an expression variable"),
    ("crates/core/src/anim/expr.rs", "fps", "an expression variable"),
    ("crates/core/src/anim/expr.rs", "time", "an expression variable"),
    ("crates/core/src/builtin_time.rs", "frame", "a salt of the frame clip's fingerprint"),
    ("crates/core/src/anim/expr.rs", "clamp", "an expression function"),
    ("crates/core/src/anim/expr.rs", "char", "a kind of rhai token, named in a parse error"),
    ("nodes/particles/src/usd/mod.rs", "flames", "the default name of the USD prim written"),
    ("nodes/particles/src/usd/scene.rs", "points", "the point attribute's name in the USD schemas"),
    ("nodes/particles/src/usd/scene.rs", "mesh", "the name of the USD prim the mesh becomes"),
    ("nodes/particles/src/usd/scene.rs", "roots", "the name of the USD prim the spread's flame roots become"),
    ("nodes/cloth/src/usd.rs", "cloth", "the default name of the USD prim written"),
    ("nodes/cloth/src/usd.rs", "points", "the point attribute's name in the USD Mesh schema"),
    ("nodes/volume/src/vdb/nodes.rs", "volume", "the name of the USD Volume prim written"),
    ("nodes/volume/src/vdb/write.rs", "name", "OpenVDB's grid metadata key for the grid's name"),
];

#[test]
fn no_port_name_is_a_string_literal_outside_its_declaration() {
    let registry = pyrograph_frontend::registry();
    let ports: BTreeSet<String> =
        registry.descs().flat_map(|d| d.inputs.iter().chain(&d.outputs).map(|p| p.name.clone())).collect();
    let root = workspace();
    let mut files = Vec::new();
    for dir in ["crates/core/src", "crates/render/src", "nodes"] {
        sources(&root.join(dir), &mut files);
    }
    files.retain(|f| !f.components().any(|c| c.as_os_str() == "benches" || c.as_os_str() == "examples"));
    assert!(files.len() > 50, "found only {} source files", files.len());
    let mut hits = Vec::new();
    for file in &files {
        // Test items are blanked, lines kept, so the numbers below are the file's.
        let text = pyrograph_testing::without_test_items(&std::fs::read_to_string(file).unwrap());
        for (n, line) in text.lines().enumerate() {
            for lit in literals(line) {
                let rel = file.strip_prefix(&root).unwrap_or(file).to_string_lossy().replace('\\', "/");
                if ports.contains(lit) && !NOT_PORTS.iter().any(|(f, l, _)| *f == rel && *l == lit) {
                    hits.push(format!("{rel}:{}: \"{lit}\"", n + 1));
                }
            }
        }
    }
    assert!(hits.is_empty(), "{} port names written as strings outside their declarations:\n{}", hits.len(), hits.join("\n"));
}

#[test]
fn the_scan_finds_a_string_port_read() {
    assert_eq!(literals(r#"    let x = i.float("turbulence")? as f32;"#), ["turbulence"]);
    assert_eq!(literals(r#"        Cloth = "cloth","#), Vec::<&str>::new());
    assert_eq!(literals(r#"    // i.float("turbulence")"#), Vec::<&str>::new());
    assert_eq!(literals(r#"NodeError::port("a", "b c")"#), ["a"]);
}
