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
}

/// The include nodes of `doc` whose files exist, as (id, canonical path); the others are
/// reported when the graph is built.
fn includes(doc: &GraphDoc, dir: &Path) -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    for (id, nd) in &doc.nodes.0 {
        if nd.type_name != INCLUDE_TYPE {
            continue;
        }
        let Some(ParamValue::String(raw)) = nd.params.get(INCLUDE_PATH) else { continue };
        let Ok(expanded) = expand_vars(raw) else { continue };
        // A file outside the read roots is not read here; building reports it.
        if crate::limits::may_read(&dir.join(&expanded)).is_err() {
            continue;
        }
        if let Ok(canon) = std::fs::canonicalize(dir.join(expanded)) {
            out.push((id.clone(), canon));
        }
    }
    out
}

/// Nodes of `doc` once flattened. Recursion here is once per level of distinct files, as
/// building is; a cycle adds nothing (building reports it).
fn size_of(doc: &GraphDoc, dir: &Path, sizes: &mut Sizes, stack: &mut Vec<PathBuf>) -> u64 {
    let own = doc.nodes.0.iter().filter(|(_, nd)| nd.type_name != INCLUDE_TYPE).count() as u64;
    includes(doc, dir)
        .into_iter()
        .fold(own, |n, (_, canon)| if stack.contains(&canon) { n } else { n.saturating_add(file_size(&canon, sizes, stack)) })
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
    let (mut at, mut at_dir) = (doc, dir.to_path_buf());
    while chain.len() < 6 {
        // The first of the biggest (`max_by_key` keeps the last of equals, so walk backwards).
        let biggest = includes(at, &at_dir).into_iter().rev().max_by_key(|(_, c)| sizes.size.get(c).copied().unwrap_or(0));
        let Some((id, canon)) = biggest else { break };
        let count = includes(at, &at_dir).iter().filter(|(_, c)| *c == canon).count();
        chain.push((
            id,
            format!("{} ({} nodes each, included {count}×)", short(&canon), sizes.size.get(&canon).copied().unwrap_or(0)),
        ));
        let Some((next, next_dir)) = sizes.docs.get(&canon) else { break };
        (at, at_dir) = (next, next_dir.clone());
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
