//! The layout's rules, read from the sources of every crate (DESIGN.md, "Layout"):
//! - no algorithm module imports a node of its crate (a node module is a file that declares nodes
//!   with `node!`; an algorithm module is any other file; importing a node means naming a struct a
//!   `node!` block declares, as `port!(Node, field)` does): algorithms return their own errors and
//!   the node's cook maps them to ports;
//! - no import cycle between the files of a crate, except the documented one: core's graph build
//!   and include flattening call each other (an include's graph is built as a graph).
//!
//! What counts as an import: `use` statements and inline `crate::`/`super::`/`self::` paths in
//! shipped code (text before the first `#[cfg(test)]`; files that only tests compile are skipped).
//! A path is followed to the file that defines the name it ends in, through `pub use` re-exports
//! (which are a facade's wiring, not imports of their own). Crate roots (`lib.rs`, `main.rs`)
//! wire every module together and are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use pyrograph_testing::workspace;

mod cook_side;
mod test_placement;

/// The documented exception: these files of `crates/core` may form one cycle between them.
const ALLOWED_CYCLE: &[&str] = &["crates/core/src/graph/build.rs", "crates/core/src/graph/include.rs"];

/// One module file of a crate.
#[derive(Debug, Default)]
struct ModFile {
    path: PathBuf,
    /// Shipped code (before the first `#[cfg(test)]`).
    text: String,
    /// Child modules declared with `mod name;` outside test code: name → module path.
    children: BTreeMap<String, Vec<String>>,
}

/// A crate's module tree, keyed by module path (`[]` is the crate root).
type Tree = BTreeMap<Vec<String>, ModFile>;

fn shipped(text: &str) -> String {
    // Comments (doc examples among them) are not code, nor is the text of a string literal.
    let code = pyrograph_testing::without_test_items(text);
    let code = code.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
    blank_strings(&code)
}

/// `code` with the contents of string literals (plain, escaped and raw) replaced by spaces, so a
/// message like "use at most 3" is not read as a `use` statement. Char literals are kept whole.
fn blank_strings(code: &str) -> String {
    let chars: Vec<char> = code.chars().collect();
    let mut out = String::with_capacity(code.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        // A char literal: 'x' or '\x' (a lifetime has no closing quote this close).
        if c == '\'' {
            let end = if chars.get(i + 1) == Some(&'\\') { i + 3 } else { i + 2 };
            if chars.get(end) == Some(&'\'') {
                out.extend(&chars[i..=end]);
                i = end + 1;
                continue;
            }
        }
        // A raw string: r"…", r#"…"#, br##"…"##.
        if c == 'r' && !chars.get(i.wrapping_sub(1)).is_some_and(|p| p.is_ascii_alphanumeric() || *p == '_') {
            let hashes = chars[i + 1..].iter().take_while(|&&h| h == '#').count();
            if chars.get(i + 1 + hashes) == Some(&'"') {
                let close: String = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
                let body_start = i + 2 + hashes;
                let rest: String = chars[body_start..].iter().collect();
                let len = rest.find(&close).map_or(chars.len() - body_start, |k| rest[..k].chars().count());
                out.push('"');
                out.extend(std::iter::repeat_n(' ', len));
                out.push('"');
                i = body_start + len + close.chars().count();
                continue;
            }
        }
        if c == '"' {
            out.push('"');
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
                out.push(' ');
            }
            out.push('"');
            i += 1;
            continue;
        }
        out.push(c);
        i += 1;
    }
    out
}

fn ident_at(text: &str, at: usize) -> String {
    text[at..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect()
}

/// Reads the module tree reachable from `root` (a `lib.rs` or `main.rs`) through `mod x;`.
fn read_tree(root: &Path) -> Tree {
    let mut tree = Tree::new();
    let mut todo = vec![(Vec::<String>::new(), root.to_path_buf())];
    while let Some((modpath, file)) = todo.pop() {
        let text = shipped(&std::fs::read_to_string(&file).unwrap_or_default());
        // A file's children live in the folder named after it, or beside it for lib.rs/main.rs/mod.rs.
        let dir = match file.file_name().and_then(|n| n.to_str()) {
            Some("lib.rs" | "main.rs" | "mod.rs") => file.parent().unwrap().to_path_buf(),
            _ => file.with_extension(""),
        };
        let mut children = BTreeMap::new();
        for line in text.lines() {
            let l = line.trim_start();
            let l = l.strip_prefix("pub(crate) ").or_else(|| l.strip_prefix("pub ")).unwrap_or(l);
            let Some(rest) = l.strip_prefix("mod ") else { continue };
            let name = ident_at(rest, 0);
            if name.is_empty() || !rest[name.len()..].trim_start().starts_with(';') {
                continue; // an inline module belongs to this file
            }
            let (a, b) = (dir.join(format!("{name}.rs")), dir.join(&name).join("mod.rs"));
            let Some(child) = [a, b].into_iter().find(|p| p.exists()) else { continue };
            let mut p = modpath.clone();
            p.push(name.clone());
            children.insert(name, p.clone());
            todo.push((p, child));
        }
        tree.insert(modpath, ModFile { path: file, text, children });
    }
    tree
}

/// Splits `use` statements into full paths, braces expanded: `use a::{b, c::d};` → `a::b`, `a::c::d`.
/// The flag says whether the statement re-exports (`pub use`).
fn use_paths(text: &str) -> Vec<(bool, Vec<String>)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = find_use(rest) {
        let public = rest[..i].trim_end().ends_with("pub") || rest[..i].trim_end().ends_with(')');
        let body_start = i + 4;
        let Some(end) = rest[body_start..].find(';') else { break };
        let body: String = rest[body_start..body_start + end].chars().filter(|c| !c.is_whitespace()).collect();
        for p in expand(&body) {
            let segs: Vec<String> = p.split("::").map(|s| s.split(" as ").next().unwrap_or(s).to_string()).collect();
            out.push((public, segs));
        }
        rest = &rest[body_start + end..];
    }
    out
}

/// The byte index of the next `use ` statement keyword that starts a line's statement.
fn find_use(text: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = text[from..].find("use ") {
        let at = from + i;
        let before = text[..at].trim_end_matches([' ', '\t']);
        let word_start = before.is_empty()
            || before.ends_with(['\n', ';', '{', '}'])
            || before.ends_with("pub")
            || before.ends_with("pub(crate)");
        if word_start {
            return Some(at);
        }
        from = at + 4;
    }
    None
}

fn expand(body: &str) -> Vec<String> {
    let Some(open) = body.find('{') else { return vec![body.to_string()] };
    let close = body.rfind('}').unwrap_or(body.len());
    let prefix = &body[..open];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, open + 1);
    for (i, c) in body[open + 1..close].char_indices() {
        let i = i + open + 1;
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&body[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&body[start..close]);
    parts
        .into_iter()
        .filter(|p| !p.is_empty())
        .flat_map(expand)
        .map(|p| if p == "self" { prefix.trim_end_matches("::").to_string() } else { format!("{prefix}{p}") })
        .collect()
}

/// Inline `crate::a::b` / `super::a` / `self::a` paths in code (outside `use` statements).
fn inline_paths(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for kw in ["crate::", "super::", "self::"] {
        for (i, _) in text.match_indices(kw) {
            let prev = text[..i].chars().next_back();
            if prev.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '$' || c == ':') {
                continue;
            }
            let mut segs = vec![kw.trim_end_matches(':').to_string()];
            let mut at = i + kw.len();
            loop {
                let id = ident_at(text, at);
                if id.is_empty() {
                    break;
                }
                at += id.len();
                segs.push(id);
                if !text[at..].starts_with("::") {
                    break;
                }
                at += 2;
            }
            out.push(segs);
        }
    }
    out
}

/// `path` (as written in module `at`) made absolute: `crate::`, `super::` and `self::` resolved,
/// and a first segment naming a child module of `at` taken as relative. `None` for other crates.
fn absolute(tree: &Tree, at: &[String], path: &[String]) -> Option<Vec<String>> {
    let mut base: Vec<String> = at.to_vec();
    let mut segs = path;
    match segs.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            segs = &segs[1..];
        }
        Some("self") => segs = &segs[1..],
        Some("super") => {
            while segs.first().map(String::as_str) == Some("super") {
                base.pop();
                segs = &segs[1..];
            }
        }
        Some(first) if tree.get(at).is_some_and(|m| m.children.contains_key(first)) => {}
        _ => return None,
    }
    base.extend(segs.iter().cloned());
    Some(base)
}

fn defines(text: &str, name: &str) -> bool {
    ["fn ", "struct ", "enum ", "trait ", "const ", "static ", "type ", "macro_rules! "].iter().any(|kw| {
        text.match_indices(&format!("{kw}{name}")).any(|(i, m)| {
            let after = text[i + m.len()..].chars().next();
            !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
        })
    })
}

/// The module file that defines the item an absolute path names, following `pub use`; a path
/// that ends in a module, or whose item is not found, names the last module reached.
fn resolve(tree: &Tree, path: &[String]) -> Option<(Vec<String>, Option<String>)> {
    let mut cur: Vec<String> = Vec::new();
    for (k, seg) in path.iter().enumerate() {
        let m = tree.get(&cur)?;
        if let Some(child) = m.children.get(seg) {
            cur = child.clone();
            continue;
        }
        let at = find_item(tree, &cur, seg, &path[k + 1..], 0).unwrap_or(cur);
        return Some((at, Some(seg.clone())));
    }
    Some((cur, None))
}

/// The module that defines `name`, looked up in module `at` and through its `pub use` lines.
fn find_item(tree: &Tree, at: &[String], name: &str, rest: &[String], depth: usize) -> Option<Vec<String>> {
    let m = tree.get(at)?;
    if defines(&m.text, name) {
        return Some(at.to_vec());
    }
    if depth > 8 {
        return None;
    }
    for (public, u) in use_paths(&m.text) {
        let Some(abs) = absolute(tree, at, &u).filter(|_| public) else { continue };
        let (last, module) = abs.split_last()?;
        if last == name || last == "*" {
            let mut full = module.to_vec();
            full.push(if last == "*" { name.to_string() } else { last.clone() });
            full.extend(rest.iter().cloned());
            let (item_at, item) = locate(tree, &full)?;
            if let Some(found) = find_item(tree, &item_at, &item, &[], depth + 1) {
                return Some(found);
            }
            if last == name {
                return Some(item_at);
            }
        }
    }
    None
}

/// The deepest module along `path` and the name that follows it.
fn locate(tree: &Tree, path: &[String]) -> Option<(Vec<String>, String)> {
    let mut cur: Vec<String> = Vec::new();
    for seg in path {
        match tree.get(&cur)?.children.get(seg) {
            Some(child) => cur = child.clone(),
            None => return Some((cur, seg.clone())),
        }
    }
    None
}

/// File → files it imports, with the names it takes from each, within one crate (crate roots
/// left out). A name is `None` where a path ends in a module (`use super::io;`).
type Edges = BTreeMap<PathBuf, BTreeMap<PathBuf, BTreeSet<Option<String>>>>;

fn edges(tree: &Tree) -> Edges {
    let mut out = Edges::new();
    for (at, m) in tree {
        if at.is_empty() {
            continue;
        }
        let mut paths: Vec<Vec<String>> = use_paths(&m.text).into_iter().filter(|(public, _)| !public).map(|(_, p)| p).collect();
        paths.extend(inline_paths(&m.text));
        let set = out.entry(m.path.clone()).or_default();
        for p in paths {
            let Some(abs) = absolute(tree, at, &p) else { continue };
            let Some((target, name)) = resolve(tree, &abs) else { continue };
            if target.is_empty() || &target == at || at.starts_with(&target) {
                continue; // the crate root, the file itself, or a parent module's own items
            }
            set.entry(tree[&target].path.clone()).or_default().insert(name);
        }
    }
    out
}

/// The bodies of a file's `node! { ... }` blocks.
fn node_blocks(text: &str) -> Vec<&str> {
    macro_blocks(text, "node!")
}

/// The bodies of a file's `name { ... }` macro calls (`node!`, `ports!`).
fn macro_blocks<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices(name) {
        let rest = &text[i + name.len()..];
        let Some(open) = rest.find('{').filter(|&o| rest[..o].trim().is_empty()) else { continue };
        out.push(&rest[open..open + closing(&rest[open..])]);
    }
    out
}

/// The offset of the brace that closes the one `text` opens with (its length when unclosed).
fn closing(text: &str) -> usize {
    let mut depth = 0;
    let bytes = text.as_bytes();
    for (j, c) in text.char_indices() {
        // A brace in a char literal ('{') is not one.
        if j > 0 && bytes[j - 1] == b'\'' && bytes.get(j + 1) == Some(&b'\'') {
            continue;
        }
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return j;
                }
            }
            _ => {}
        }
    }
    text.len()
}

/// The structs a file declares inside `node! { ... }` blocks: node types and their outputs.
fn node_structs(text: &str) -> BTreeSet<String> {
    node_blocks(text).into_iter().flat_map(structs_in).collect()
}

/// The names of the structs declared in a piece of code.
fn structs_in(code: &str) -> Vec<String> {
    code.match_indices("struct ").map(|(k, m)| ident_at(code, k + m.len())).filter(|n| !n.is_empty()).collect()
}

/// The output structs of a file's `node!` blocks that hold one field: a node with one output
/// declares it `-> name: Type` instead. Each as (struct name, field).
fn single_output_structs(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for block in node_blocks(text) {
        let structs: Vec<usize> = block.match_indices("struct ").map(|(k, m)| k + m.len()).collect();
        let [_, at] = structs[..] else { continue };
        let body_start = at + block[at..].find('{').unwrap_or(block.len() - at);
        let body = &block[body_start..body_start + closing(&block[body_start..])];
        // A field is a name followed by one colon (not a path's `::`) at the top level of the body.
        let fields: Vec<String> = body
            .lines()
            .filter_map(|l| l.trim().split_once(':').filter(|(_, ty)| !ty.starts_with(':')).map(|(n, _)| n))
            .filter(|n| !n.is_empty() && n.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '#'))
            .map(str::to_string)
            .collect();
        if let [field] = &fields[..] {
            out.push((ident_at(block, at), field.clone()));
        }
    }
    out
}

/// Strongly connected groups of more than one file (iterative Tarjan: no recursion per file).
fn cycles(graph: &Edges) -> Vec<Vec<PathBuf>> {
    let nodes: Vec<&PathBuf> = graph.keys().collect();
    let index_of: BTreeMap<&PathBuf, usize> = nodes.iter().enumerate().map(|(i, p)| (*p, i)).collect();
    let succ: Vec<Vec<usize>> =
        nodes.iter().map(|p| graph[*p].keys().filter_map(|q| index_of.get(q).copied()).collect()).collect();
    let n = nodes.len();
    let (mut index, mut low, mut on) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut next, mut out) = (Vec::new(), 0, Vec::new());
    for s in 0..n {
        if index[s] != usize::MAX {
            continue;
        }
        let mut work = vec![(s, 0usize)];
        while let Some(&mut (v, ref mut child)) = work.last_mut() {
            if *child == 0 && index[v] == usize::MAX {
                index[v] = next;
                low[v] = next;
                next += 1;
                stack.push(v);
                on[v] = true;
            }
            if let Some(&w) = succ[v].get(*child) {
                *child += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(parent, _)) = work.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut group = Vec::new();
                while let Some(w) = stack.pop() {
                    on[w] = false;
                    group.push(nodes[w].clone());
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 {
                    group.sort();
                    out.push(group);
                }
            }
        }
    }
    out
}

/// The file graph lifted to modules: where a file of module `a::x::…` imports one of `a::y::…`,
/// the sibling modules `a::x` and `a::y` depend on each other's side, so a circle between two
/// folders (`io` → `video` → `io`) shows even when no two files import each other. Module paths
/// are written `io::files` as the nodes' names.
fn module_edges(tree: &Tree, files: &Edges) -> Edges {
    let module_of: BTreeMap<&PathBuf, &Vec<String>> = tree.iter().map(|(m, f)| (&f.path, m)).collect();
    let name = |m: &[String]| PathBuf::from(m.join("::"));
    let mut out = Edges::new();
    for (from, targets) in files {
        let Some(a) = module_of.get(from) else { continue };
        for to in targets.keys() {
            let Some(b) = module_of.get(to) else { continue };
            let common = a.iter().zip(b.iter()).take_while(|(x, y)| x == y).count();
            // A file inside the module it imports from (or its parent) is no circle of siblings.
            if common >= a.len() || common >= b.len() {
                continue;
            }
            let edge = out.entry(name(&a[..=common])).or_default();
            edge.entry(name(&b[..=common])).or_default();
        }
    }
    out
}

/// Every rule broken in the crate rooted at `root`, as messages with paths relative to `base`.
fn problems(root: &Path, base: &Path) -> Vec<String> {
    let tree = read_tree(root);
    let graph = edges(&tree);
    let rel = |p: &Path| p.strip_prefix(base).unwrap_or(p).to_string_lossy().replace('\\', "/");
    let nodes: BTreeMap<&PathBuf, BTreeSet<String>> =
        tree.values().map(|m| (&m.path, node_structs(&m.text))).filter(|(_, n)| !n.is_empty()).collect();
    let mut out = Vec::new();
    for (from, to) in &graph {
        if nodes.contains_key(from) {
            continue;
        }
        for (t, names) in to {
            let Some(declared) = nodes.get(t) else { continue };
            for name in names.iter().flatten().filter(|n| declared.contains(*n)) {
                out.push(format!("algorithm module {} imports node {name} of {}", rel(from), rel(t)));
            }
        }
    }
    // The per-function rule applies to node crates, whose roots only wire modules and register.
    if root.components().any(|c| c.as_os_str() == "nodes") {
        let side = cook_side::CookSide::of(tree.values().map(|m| m.text.as_str()), |t| {
            (node_structs(t), macro_blocks(t, "ports!").iter().flat_map(|b| structs_in(b)).collect())
        });
        for (modpath, m) in &tree {
            if !modpath.is_empty() {
                out.extend(side.outside_cooks(&rel(&m.path), &m.text));
            }
        }
    }
    for m in tree.values() {
        for (name, field) in single_output_structs(&m.text) {
            out.push(format!("{} declares the one output of a node as struct {name}: write `-> {field}: ..`", rel(&m.path)));
        }
    }
    for group in cycles(&graph) {
        let names: Vec<String> = group.iter().map(|p| rel(p)).collect();
        if names.iter().all(|n| ALLOWED_CYCLE.contains(&n.as_str())) {
            continue;
        }
        out.push(format!("import cycle between {}", names.join(", ")));
    }
    let crate_dir = rel(root.parent().and_then(Path::parent).unwrap_or(root));
    for group in cycles(&module_edges(&tree, &graph)) {
        let names: Vec<String> = group.iter().map(|p| p.to_string_lossy().to_string()).collect();
        // A circle of single files is the file cycle reported above (or the documented one);
        // this reports the circles that run through a folder module.
        let is_folder = |name: &String| {
            tree.get(&name.split("::").map(String::from).collect::<Vec<_>>()).is_some_and(|m| !m.children.is_empty())
        };
        if names.iter().any(is_folder) {
            out.push(format!("module cycle in {crate_dir} between {}", names.join(", ")));
        }
    }
    out
}

/// Every crate root of the workspace: the CLI's library and binary, and each member's.
fn crate_roots(ws: &Path) -> Vec<PathBuf> {
    let mut roots = vec![ws.join("src/lib.rs"), ws.join("src/main.rs"), ws.join("frontend/src/lib.rs")];
    for group in ["crates", "nodes", "apps"] {
        let Ok(entries) = std::fs::read_dir(ws.join(group)) else { continue };
        for e in entries.flatten() {
            for root in ["src/lib.rs", "src/main.rs"] {
                let p = e.path().join(root);
                if p.exists() {
                    roots.push(p);
                }
            }
        }
    }
    roots.sort();
    roots
}

#[test]
fn algorithms_do_not_import_nodes_and_files_form_no_cycle() {
    let ws = workspace();
    let roots = crate_roots(&ws);
    assert!(roots.len() >= 10, "found crate roots: {roots:?}");
    let all: Vec<String> = roots.iter().flat_map(|r| problems(r, &ws)).collect();
    assert!(all.is_empty(), "layout rules broken ({}):\n{}", all.len(), all.join("\n"));
}

/// The checker itself, on a made-up crate that breaks both rules: it must say so.
#[test]
fn the_checker_finds_an_algorithm_importing_a_node_a_cycle_and_a_one_field_output_struct() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    for folder in ["io", "video"] {
        std::fs::create_dir_all(src.join(folder)).unwrap();
    }
    let files = [
        ("lib.rs", "pub mod io;\npub mod blur;\npub mod a;\npub mod b;\npub mod video;\n"),
        ("io/mod.rs", "mod files;\npub mod nodes;\nmod sequence;\npub use files::*;\npub use nodes::*;\n"),
        ("io/files.rs", "use crate::io::LoadSequence;\npub fn read() { port!(LoadSequence, path); }\n"),
        (
            "io/nodes.rs",
            concat!(
                "node! {\n    pub struct LoadSequence { path: u8 }\n    pub struct Out { clip: u8, fps: f64 }\n}\n",
                "node! {\n    pub struct Write { clip: u8 }\n    pub struct WriteOut {\n        frames: std::num::NonZeroU8,\n    }\n}\n",
                "node! {\n    pub struct Blur { image: u8 }\n    -> image: u8\n}\n",
            ),
        ),
        ("blur.rs", "use super::io::read;\npub fn blur() { read() }\n#[cfg(test)]\nuse crate::io::nodes::LoadSequence;\n"),
        ("a.rs", "use crate::b::{self, helper};\npub fn f() { helper() }\n"),
        ("b.rs", "pub fn helper() { crate::a::f() }\npub fn text() -> &'static str { \"; use at most {n}; \" }\n"),
        // Two folders that lean on each other through different files: no file cycle, a module one.
        ("io/sequence.rs", "use crate::video::open;\npub fn seq() { open() }\n"),
        ("video/mod.rs", "mod probe;\npub use probe::*;\npub fn open() {}\n"),
        ("video/probe.rs", "use crate::io::files::read;\npub fn probe() { read() }\n"),
    ];
    for (name, text) in files {
        std::fs::write(src.join(name), text).unwrap();
    }
    let found = problems(&src.join("lib.rs"), dir.path());
    assert!(
        found.contains(&"algorithm module src/io/files.rs imports node LoadSequence of src/io/nodes.rs".to_string()),
        "{found:?}"
    );
    assert!(found.contains(&"import cycle between src/a.rs, src/b.rs".to_string()), "{found:?}");
    assert!(found.iter().any(|f| f.starts_with("module cycle in ") && f.ends_with(" between io, video")), "{found:?}");
    assert!(
        found
            .contains(&"src/io/nodes.rs declares the one output of a node as struct WriteOut: write `-> frames: ..`".to_string()),
        "{found:?}"
    );
    // blur.rs reaches files.rs (an algorithm) only; its test code is not counted.
    assert_eq!(found.len(), 4, "{found:?}");
}

/// The folders of the workspace from the bottom layer up: a crate may depend on crates in its own
/// folder or a lower one. Programs (apps/ and the CLI at the root) are one layer and never depend
/// on each other.
const LAYERS: &[&str] = &["crates", "nodes", "frontend", "apps"];

/// A crate's layer: the index of its top folder in `LAYERS`; the root package (the CLI) is a
/// program, as apps/ are.
fn layer(ws: &Path, dir: &Path) -> Result<usize, String> {
    let rel = dir.strip_prefix(ws).map_err(|_| format!("{} is outside the workspace", dir.display()))?;
    let Some(top) = rel.components().next() else { return Ok(LAYERS.len() - 1) };
    let top = top.as_os_str().to_string_lossy();
    LAYERS
        .iter()
        .position(|l| *l == top)
        .ok_or_else(|| format!("{}: a crate outside the layer folders {LAYERS:?}", rel.display()))
}

/// Every dependency between workspace crates that runs up a layer (or between two programs), as
/// (crate folder, dependency folder) pairs relative to the workspace.
fn upward(ws: &Path, deps: &[(PathBuf, PathBuf)]) -> Vec<String> {
    let programs = LAYERS.len() - 1;
    let mut out = Vec::new();
    for (from, to) in deps {
        let name = |p: &Path| match p.strip_prefix(ws) {
            Ok(r) if r.as_os_str().is_empty() => "the CLI (the root package)".to_string(),
            Ok(r) => r.display().to_string(),
            Err(_) => p.display().to_string(),
        };
        let (lf, lt) = match (layer(ws, from), layer(ws, to)) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(e), _) | (_, Err(e)) => {
                out.push(e);
                continue;
            }
        };
        if lt > lf {
            out.push(format!("{} depends on {}, a higher layer ({} above {})", name(from), name(to), LAYERS[lt], LAYERS[lf]));
        } else if lf == programs && lt == programs {
            out.push(format!("{} depends on {}: programs do not depend on each other", name(from), name(to)));
        }
    }
    out
}

/// (crate folder, dependency folder) for every dependency of a workspace crate on another, from
/// `cargo metadata` (normal, build and dev dependencies alike).
fn workspace_deps(ws: &Path) -> Vec<(PathBuf, PathBuf)> {
    let out = std::process::Command::new(env!("CARGO"))
        .args(["metadata", "--no-deps", "--format-version", "1", "--offline"])
        .current_dir(ws)
        .output()
        .expect("cargo metadata runs");
    assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let dir = |manifest: &str| Path::new(manifest).parent().expect("a manifest has a folder").to_path_buf();
    let mut deps = Vec::new();
    for pkg in meta["packages"].as_array().expect("packages") {
        let from = dir(pkg["manifest_path"].as_str().expect("manifest_path"));
        for dep in pkg["dependencies"].as_array().expect("dependencies") {
            if let Some(path) = dep["path"].as_str() {
                deps.push((from.clone(), PathBuf::from(path)));
            }
        }
    }
    deps
}

/// Every crate's unit tests sit in one of the two placements (`test_placement.rs`).
#[test]
fn unit_tests_have_one_placement() {
    let ws = workspace();
    let mut found = Vec::new();
    for root in crate_roots(&ws) {
        let src = root.parent().expect("a crate root is in its src folder");
        for file in test_placement::rust_files(src) {
            let rel = file.strip_prefix(&ws).unwrap_or(&file).to_string_lossy().replace('\\', "/");
            found.extend(test_placement::misplaced(&rel, &std::fs::read_to_string(&file).unwrap_or_default()));
        }
    }
    found.sort();
    found.dedup();
    assert!(found.is_empty(), "unit tests out of place ({}):\n{}", found.len(), found.join("\n"));
}

#[test]
fn crates_depend_only_on_their_own_layer_or_lower() {
    let ws = workspace();
    let deps = workspace_deps(&ws);
    assert!(deps.len() >= 30, "found {} dependencies between workspace crates", deps.len());
    let wrong = upward(&ws, &deps);
    assert!(wrong.is_empty(), "layers broken:\n{}", wrong.join("\n"));
}

/// The check itself, on made-up arrows: a node crate on the front-end library, a library on a node
/// crate, and the editor on the Python module must each be caught; downward arrows must not.
#[test]
fn the_layer_check_finds_an_upward_dependency() {
    let ws = Path::new("/ws");
    let arrow = |a: &str, b: &str| (ws.join(a), ws.join(b));
    let deps = [
        arrow("nodes/imaging", "frontend"),
        arrow("crates/render", "nodes/particles"),
        arrow("apps/editor", "apps/python"),
        arrow("frontend", "nodes/volume"),
        arrow("apps/editor", "frontend"),
        arrow("nodes/flame-model", "nodes/eigen"),
        arrow("", "frontend"),
        arrow("frontend", ""),
    ];
    let wrong = upward(ws, &deps);
    assert_eq!(wrong.len(), 4, "{wrong:#?}");
    assert!(wrong[0].starts_with("nodes/imaging depends on frontend, a higher layer"), "{}", wrong[0]);
    assert!(wrong[1].starts_with("crates/render depends on nodes/particles"), "{}", wrong[1]);
    assert!(wrong[2].contains("programs do not depend on each other"), "{}", wrong[2]);
    assert!(wrong[3].starts_with("frontend depends on the CLI (the root package), a higher layer"), "{}", wrong[3]);
}
