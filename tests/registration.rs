//! A node type declared but not registered is a node no graph can use, and nothing else would
//! notice. This test reads every `node!` declaration's type name from the sources of core and the
//! node crates and asks the registry the front ends use for each one.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use pyrograph_testing::workspace;

/// Every `#[node("family.name", ...)]` in shipped code (test items left out) under `dir`.
fn declared(dir: &Path, out: &mut BTreeSet<(String, PathBuf)>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            declared(&path, out);
            continue;
        }
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        // Files only tests compile declare test nodes, not pyrograph's.
        if !name.ends_with(".rs") || name == "tests.rs" || name == "testing.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let shipped = pyrograph_testing::without_test_items(&text);
        for line in shipped.lines().filter(|l| !l.trim_start().starts_with("//")) {
            if let Some(rest) = line.trim_start().strip_prefix("#[node(\"") {
                let name = rest.split('"').next().unwrap_or_default();
                out.insert((name.to_string(), path.clone()));
            }
        }
    }
}

#[test]
fn every_declared_node_type_is_registered() {
    let ws = workspace();
    let mut found = BTreeSet::new();
    declared(&ws.join("crates/core/src"), &mut found);
    for family in std::fs::read_dir(ws.join("nodes")).unwrap().flatten() {
        declared(&family.path().join("src"), &mut found);
    }
    // The declarations the registry's own tests make are not pyrograph's nodes.
    found.retain(|(name, _)| !name.is_empty());
    assert!(found.len() >= 80, "found only {} declarations: {found:?}", found.len());
    let registry = pyrograph_frontend::registry();
    let missing: Vec<String> = found
        .iter()
        .filter(|(name, _)| registry.desc(name).is_none())
        .map(|(name, file)| format!("{name} ({})", file.strip_prefix(&ws).unwrap_or(file).display()))
        .collect();
    assert!(missing.is_empty(), "declared but not registered:\n{}", missing.join("\n"));
}
