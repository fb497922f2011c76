//! The core's modules form layers: no module reaches, directly or through others, back to
//! itself. A module is a file of `src/` or a folder with its files; `crate::x` paths outside
//! test code are its imports (macros refer to `$crate::x`, which is counted too).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Code without its `#[cfg(test)]` items: tests may import anything.
fn shipped(text: &str) -> String {
    pyrograph_testing::without_test_items(text)
}

fn imports(text: &str, into: &mut BTreeSet<String>) {
    for (i, _) in text.match_indices("crate::") {
        let name: String = text[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        // Lower-case names are modules; `crate::Graph` re-exports resolve to a module of their own.
        if name.chars().next().is_some_and(|c| c.is_ascii_lowercase()) {
            into.insert(name);
        }
    }
}

fn modules(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        if name == "lib" || name == "tests" {
            continue;
        }
        let mut deps = BTreeSet::new();
        let files: Vec<_> = if path.is_dir() {
            walk(&path)
        } else if path.extension().is_some_and(|e| e == "rs") {
            vec![path.clone()]
        } else {
            continue;
        };
        for f in files {
            imports(&shipped(&std::fs::read_to_string(&f).unwrap()), &mut deps);
        }
        deps.remove(&name);
        out.entry(name).or_insert_with(BTreeSet::new).extend(deps);
    }
    out
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        // A module's unit tests (`tests.rs`, or a `tests/` folder) are not its shipped code.
        let tests = p.file_stem().is_some_and(|n| n == "tests");
        if p.is_dir() && !tests {
            out.extend(walk(&p));
        } else if p.extension().is_some_and(|e| e == "rs") && !tests {
            out.push(p);
        }
    }
    out
}

/// A cycle through `start`, if any, as the list of modules along it.
fn cycle_from(start: &str, deps: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    let mut stack = vec![(start.to_string(), vec![start.to_string()])];
    let mut seen = BTreeSet::new();
    while let Some((m, path)) = stack.pop() {
        for d in deps.get(&m).into_iter().flatten() {
            if d == start {
                let mut c = path.clone();
                c.push(d.clone());
                return Some(c);
            }
            if seen.insert(d.clone()) {
                let mut p = path.clone();
                p.push(d.clone());
                stack.push((d.clone(), p));
            }
        }
    }
    None
}

#[test]
fn core_modules_have_no_import_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let deps = modules(&src);
    assert!(deps.contains_key("graph") && deps.contains_key("eval"), "found modules: {:?}", deps.keys());
    let cycles: Vec<String> = deps.keys().filter_map(|m| cycle_from(m, &deps)).map(|c| c.join(" -> ")).collect();
    assert!(cycles.is_empty(), "import cycles between core modules:\n{}", cycles.join("\n"));
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let deps: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a")]
        .into_iter()
        .map(|(m, d)| (m.to_string(), BTreeSet::from([d.to_string()])))
        .collect();
    assert_eq!(cycle_from("a", &deps), Some(vec!["a".into(), "b".into(), "c".into(), "a".into()]));
    assert_eq!(cycle_from("d", &deps), None);
}
