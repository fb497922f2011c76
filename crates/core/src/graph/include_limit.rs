//! The size a graph would have once its includes are flattened, computed from the files alone
//! (each read and parsed once) before anything is built. A graph that includes a file twice,
//! which includes another twice, and so on, doubles with every level; past the limit it is
//! refused here, naming the includes that make it big, instead of exhausting the machine.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::expand_vars;
use crate::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use crate::document::{GraphDoc, ParamValue};
use crate::error::{Diagnostic, DiagnosticKind, Diagnostics, Location};

/// The files met so far: each parsed document (with its folder) and flattened size.
#[derive(Default)]
struct Sizes {
    docs: HashMap<PathBuf, (GraphDoc, PathBuf)>,
    size: HashMap<PathBuf, u64>,
    /// How many local subgraphs the count is inside.
    depth: usize,
}

/// What an include node reads: its local subgraph, or a file (canonical path).
#[derive(Clone, PartialEq)]
enum Target {
    Local,
    File(PathBuf),
}

/// The include nodes of `doc` with a local subgraph or a file that exists, as (id, target); the
/// others are reported when the graph is built.
fn includes(doc: &GraphDoc, dir: &Path) -> Vec<(String, Target)> {
    let mut out = Vec::new();
    for (id, nd) in &doc.nodes.0 {
        if nd.type_name != INCLUDE_TYPE {
            continue;
        }
        if doc.subgraphs.contains_key(id) {
            out.push((id.clone(), Target::Local));
            continue;
        }
        let Some(ParamValue::String(raw)) = nd.params.get(INCLUDE_PATH) else { continue };
        let Ok(expanded) = expand_vars(raw) else { continue };
        // A file outside the read roots is not read here; building reports it.
        if crate::limits::may_read(&dir.join(&expanded)).is_err() {
            continue;
        }
        if let Ok(canon) = std::fs::canonicalize(dir.join(expanded)) {
            out.push((id.clone(), Target::File(canon)));
        }
    }
    out
}

/// Local subgraphs deeper than this are not counted (building refuses them).
const MAX_DEPTH: usize = 40;

/// Nodes of `doc` once flattened. Recursion here is once per level of distinct files or of
/// local subgraphs, as building is; a cycle adds nothing (building reports it).
fn size_of(doc: &GraphDoc, dir: &Path, sizes: &mut Sizes, stack: &mut Vec<PathBuf>) -> u64 {
    let own = doc.nodes.0.iter().filter(|(_, nd)| nd.type_name != INCLUDE_TYPE).count() as u64;
    includes(doc, dir)
        .into_iter()
        .fold(own, |n, (id, target)| n.saturating_add(target_size(doc, dir, &id, &target, sizes, stack)))
}

/// Nodes behind include `id` of `doc`.
fn target_size(doc: &GraphDoc, dir: &Path, id: &str, target: &Target, sizes: &mut Sizes, stack: &mut Vec<PathBuf>) -> u64 {
    match target {
        Target::File(canon) if stack.contains(canon) => 0,
        Target::File(canon) => file_size(canon, sizes, stack),
        Target::Local if sizes.depth >= MAX_DEPTH => 0,
        Target::Local => {
            let Some(local) = doc.subgraphs.get(id) else { return 0 };
            sizes.depth += 1;
            let s = size_of(local, dir, sizes, stack);
            sizes.depth -= 1;
            s
        }
    }
}

fn file_size(canon: &Path, sizes: &mut Sizes, stack: &mut Vec<PathBuf>) -> u64 {
    if let Some(s) = sizes.size.get(canon) {
        return *s;
    }
    let parsed = std::fs::read_to_string(canon).ok().and_then(|t| GraphDoc::from_ron(&t).ok());
    let Some(doc) = parsed else {
        sizes.size.insert(canon.to_path_buf(), 0);
        return 0;
    };
    let dir = canon.parent().map(Path::to_path_buf).unwrap_or_default();
    stack.push(canon.to_path_buf());
    let s = size_of(&doc, &dir, sizes, stack);
    stack.pop();
    sizes.docs.insert(canon.to_path_buf(), (doc, dir));
    sizes.size.insert(canon.to_path_buf(), s);
    s
}

fn short(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Refuses a document (in folder `dir`) whose flattened graph would exceed the node limit, with
/// an error at its biggest include naming the chain of biggest includes below it.
pub(super) fn check(doc: &GraphDoc, dir: &Path) -> Result<(), Diagnostics> {
    let limit = crate::limits::max_nodes();
    let mut sizes = Sizes::default();
    let total = size_of(doc, dir, &mut sizes, &mut Vec::new());
    if total <= limit {
        return Ok(());
    }
    // Follow the biggest include at each level, a few levels down.
    let mut chain = Vec::new();
    // Owned copies, since counting a local subgraph's size borrows the counts mutably (the
    // error path only).
    let (mut at, mut at_dir) = (doc.clone(), dir.to_path_buf());
    while chain.len() < 6 {
        let found = includes(&at, &at_dir);
        let sized: Vec<(String, Target, u64)> = found
            .iter()
            .map(|(id, t)| (id.clone(), t.clone(), target_size(&at, &at_dir, id, t, &mut sizes, &mut Vec::new())))
            .collect();
        // The first of the biggest (`max_by_key` keeps the last of equals, so walk backwards).
        let Some((id, target, size)) = sized.into_iter().rev().max_by_key(|(_, _, s)| *s) else { break };
        match target {
            Target::Local => {
                chain.push((id.clone(), format!("the local subgraph of '{id}' ({size} nodes)")));
                let Some(next) = at.subgraphs.remove(&id) else { break };
                at = next;
            }
            Target::File(canon) => {
                let count = found.iter().filter(|(_, t)| *t == Target::File(canon.clone())).count();
                chain.push((id, format!("{} ({size} nodes each, included {count}×)", short(&canon))));
                let Some((next, next_dir)) = sizes.docs.get(&canon).cloned() else { break };
                (at, at_dir) = (next, next_dir);
            }
        }
    }
    let hint = crate::limits::raise_hint("--max-nodes", "PYROGRAPH_MAX_NODES", total);
    let Some((first, _)) = chain.first() else {
        return Err(Diagnostics::one(Diagnostic::new(
            DiagnosticKind::Include,
            Location::File,
            format!("the graph has {total} nodes, more than the {limit} pyrograph builds; if it is meant to be this big, {hint}"),
        )));
    };
    let path: Vec<&str> = chain.iter().map(|(_, f)| f.as_str()).collect();
    Err(Diagnostics::one(Diagnostic::new(
        DiagnosticKind::Include,
        Location::Port { node: first.clone(), port: INCLUDE_PATH.into() },
        format!(
            "flattened, the graph would have {total} nodes, more than the {limit} pyrograph builds: {}; if it is meant \
             to be this big, {hint}",
            path.join(" → "),
        ),
    )))
}
