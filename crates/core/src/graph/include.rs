//! `graph.include`: another graph file used as one node. Its nodes are flattened into the
//! including graph under the include's id (`fire/noise`), so they cook, cache and report errors
//! like any other node; the include keeps only its description and the inner ports behind it.

use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

use super::build::{Parts, build, diag, node_inputs};
use super::{BuildOptions, Graph, GraphNode, Included, InputSource, LoadCtx, PATH_SEP, PortRef, expand_vars};
use crate::builtin::{INCLUDE_PATH, INCLUDE_TYPE, include_desc};
use crate::document::{GraphDoc, NodeDoc, ParamValue};
use crate::error::{Diagnostic, DiagnosticKind, Diagnostics, Location};

use crate::node::{NodeDesc, PortDesc, TimeDep};
use crate::registry::Registry;
use crate::value::PortType;

fn include_diag(id: &str, message: String) -> Diagnostic {
    diag(DiagnosticKind::Include, Location::Port { node: id.to_string(), port: INCLUDE_PATH.into() }, message)
}

/// Loads and builds the file include `id` names, with its description: once per file and load
/// (later includes of the same file share the build, or get a one-line error pointing at the
/// first one's report).
fn load(id: &str, nd: &NodeDoc, ctx: &LoadCtx) -> Result<Rc<(Graph, NodeDesc)>, Vec<Diagnostic>> {
    let raw = match nd.params.get(INCLUDE_PATH) {
        Some(ParamValue::String(s)) => s,
        Some(other) => return Err(vec![include_diag(id, format!("needs a path string, got {other}"))]),
        None => return Err(vec![include_diag(id, "graph.include needs a 'path' parameter naming the graph file".into())]),
    };
    let expanded = expand_vars(raw).map_err(|m| vec![include_diag(id, m)])?;
    let path = ctx.dir.join(&expanded);
    crate::limits::may_read(&path).map_err(|m| vec![include_diag(id, m)])?;
    let canon = std::fs::canonicalize(&path)
        .map_err(|e| vec![include_diag(id, format!("cannot open included graph {}: {e}", path.display()))])?;
    if ctx.include_stack.contains(&canon) {
        let chain: Vec<String> = ctx.include_stack.iter().chain([&canon]).map(|p| short(p)).collect();
        return Err(vec![include_diag(id, format!("include cycle: {}", chain.join(" -> ")))]);
    }
    let cached = ctx.includes.built.borrow().get(&canon).cloned();
    match cached {
        Some(Ok(built)) => return Ok(built),
        Some(Err(first)) => {
            return Err(vec![include_diag(
                id,
                format!("{} does not build: see the problems reported for '{first}'", short(&canon)),
            )]);
        }
        None => {}
    }
    let built = load_file(id, &canon, ctx).map(Rc::new);
    let entry = built.as_ref().map(Rc::clone).map_err(|_| id.to_string());
    ctx.includes.built.borrow_mut().insert(canon, entry);
    built
}

/// Reads, parses and builds included file `canon`.
fn load_file(id: &str, canon: &Path, ctx: &LoadCtx) -> Result<(Graph, NodeDesc), Vec<Diagnostic>> {
    crate::document::node_count::check_file(canon).map_err(|d| nested(id, canon, d.0))?;
    let text =
        std::fs::read_to_string(canon).map_err(|e| vec![include_diag(id, format!("cannot read {}: {e}", canon.display()))])?;
    if !looks_like_a_graph(&text) {
        // Say no more than that: the parser's message would quote the file, and an include may
        // name any file a service can read (`/etc/passwd`).
        return Err(vec![include_diag(
            id,
            format!("{} is not a graph file (RON starting with `(version: ...`, as pyrograph saves)", canon.display()),
        )]);
    }
    let doc = GraphDoc::from_ron(&text).map_err(|d| nested(id, canon, d.0))?;
    missing_plugins(id, canon, &doc, ctx)?;
    let mut stack = ctx.include_stack.clone();
    stack.push(canon.to_path_buf());
    let child = LoadCtx {
        dir: canon.parent().map(Path::to_path_buf).unwrap_or_default(),
        include_stack: stack,
        nested: true,
        ..ctx.clone()
    };
    let mut sub = build(&doc, &child).map_err(|d| nested(id, canon, d.0))?;
    sub.file = Some(canon.to_path_buf());
    let desc = describe(&doc, &sub).map_err(|m| vec![include_diag(id, format!("{}: {m}", canon.display()))])?;
    Ok((sub, desc))
}

/// Refuses a preset whose recorded plugin node types this registry lacks, naming them and where
/// plugins are looked for (before its build would call each one an unknown type).
fn missing_plugins(id: &str, file: &Path, doc: &GraphDoc, ctx: &LoadCtx) -> Result<(), Vec<Diagnostic>> {
    let needs = doc.preset.as_ref().map(|p| p.plugins.as_slice()).unwrap_or_default();
    let missing: Vec<&str> = needs.iter().filter(|t| ctx.registry.get(t).is_none()).map(String::as_str).collect();
    if missing.is_empty() {
        return Ok(());
    }
    let problems: String =
        ctx.registry.extension().map(|f| f.problems.iter().map(|p| format!("; {p}")).collect()).unwrap_or_default();
    Err(vec![include_diag(
        id,
        format!(
            "preset {} needs the Python plugin node type{} '{}', which no plugin folder provides: put the plugin file in a \
             folder named by --plugins or PYROGRAPH_PLUGIN_PATH, or in plugins/ beside the graph{problems}",
            file.display(),
            if missing.len() > 1 { "s" } else { "" },
            missing.join("', '")
        ),
    )])
}

/// How deep local subgraphs may nest (a subgraph in a subgraph …): far beyond any graph made by
/// hand or by collapsing, and well short of the stack a deeper build would need.
const MAX_LOCAL_DEPTH: usize = 32;

/// Builds include `id`'s local subgraph `local` (kept in the including document, its paths
/// relative to that document's folder), with its description.
fn load_local(id: &str, local: &GraphDoc, ctx: &LoadCtx) -> Result<Rc<(Graph, NodeDesc)>, Vec<Diagnostic>> {
    let at = |message: String| diag(DiagnosticKind::Include, Location::Node(id.to_string()), message);
    if ctx.local_depth >= MAX_LOCAL_DEPTH {
        return Err(vec![at(format!("local subgraphs nest more than {MAX_LOCAL_DEPTH} deep here; unpack some of them"))]);
    }
    let child = LoadCtx { nested: true, local_depth: ctx.local_depth + 1, ..ctx.clone() };
    let sub = build(local, &child).map_err(|d| {
        d.0.into_iter()
            .map(|d| {
                let what = if d.kind == DiagnosticKind::Include { d.message } else { format!("{}: {}", d.location, d.message) };
                at(format!("in its local subgraph: {what}"))
            })
            .collect::<Vec<_>>()
    })?;
    let desc = describe(local, &sub).map_err(|m| vec![at(format!("its local subgraph {m}"))])?;
    Ok(Rc::new((sub, desc)))
}

/// The node description include `id` would have with local subgraph `local`, built on its own
/// (for an editor showing pins while the graph around it has problems).
pub fn local_desc(local: &GraphDoc, registry: &Registry, dir: &Path) -> Result<NodeDesc, Diagnostics> {
    let options = BuildOptions { describe_only: true, ..BuildOptions::default() };
    let ctx = LoadCtx {
        registry,
        root: dir.to_path_buf(),
        dir: dir.to_path_buf(),
        options: &options,
        include_stack: Vec::new(),
        nested: false,
        local_depth: 0,
        includes: Default::default(),
    };
    load_local("subgraph", local, &ctx).map(|built| built.1.clone()).map_err(Diagnostics)
}

/// Adds the nodes of the graph include `id` names (its local subgraph `local`, else its file)
/// to `parts` as `id/<inner id>`, sets the inner ports its parameters stand for, and records the
/// include's port map, and those of the includes inside it as `id/<inner include>`.
pub(super) fn flatten(
    id: &str,
    nd: &NodeDoc,
    local: Option<&GraphDoc>,
    ctx: &LoadCtx,
    parts: &mut Parts,
) -> Result<(), Vec<Diagnostic>> {
    let built = match local {
        Some(local) => load_local(id, local, ctx)?,
        None => load(id, nd, ctx)?,
    };
    let (sub, desc) = (&built.0, &built.1);
    let mut diags = Vec::new();
    let sources = node_inputs(id, nd, desc, ctx, &mut diags);
    if !diags.is_empty() {
        return Err(diags);
    }
    let Some(iface) = &sub.interface else { return Err(vec![include_diag(id, "included graph has no interface".into())]) };
    let mut map = std::collections::HashMap::new();
    for old in sub.g.node_indices() {
        let inner = &sub.g[old];
        let new_id: Arc<str> = Arc::from(format!("{id}{PATH_SEP}{}", inner.id));
        let idx = parts.g.add_node(GraphNode { id: new_id.clone(), ..inner.clone() });
        parts.ids.insert(new_id, idx);
        map.insert(old, idx);
    }
    for idx in map.values() {
        for src in &mut parts.g[*idx].inputs {
            if let InputSource::Edge { from, .. } = src {
                *from = map[from];
            }
        }
    }
    for e in sub.g.edge_indices() {
        if let (Some((a, b)), Some(w)) = (sub.g.edge_endpoints(e), sub.g.edge_weight(e)) {
            parts.g.add_edge(map[&a], map[&b], *w);
        }
    }
    for (inner_id, inc) in &sub.includes {
        let moved = Included {
            desc: inc.desc.clone(),
            inputs: inc.inputs.iter().map(|r| r.map(|(i, p)| (map[&i], p))).collect(),
            outputs: inc.outputs.iter().map(|(i, p)| (map[i], *p)).collect(),
        };
        parts.includes.insert(Arc::from(format!("{id}{PATH_SEP}{inner_id}")), moved);
    }
    let remap = |(_, idx, port): &(String, _, usize)| (map[idx], *port);
    // The include's own `path` input comes first and stands for no inner port.
    let own = include_desc().inputs.len();
    let inner_inputs = iface.inputs.iter().chain(&iface.params).map(|p| Some(remap(p)));
    let inputs: Vec<Option<PortRef>> = std::iter::repeat_n(None, own).chain(inner_inputs).collect();
    let outputs: Vec<_> = iface.outputs.iter().map(remap).collect();
    for (target, source) in inputs.iter().zip(sources) {
        if let Some((idx, port)) = target {
            parts.g[*idx].inputs[*port] = source;
        }
    }
    parts.includes.insert(Arc::from(id), Included { desc: Arc::new(desc.clone()), inputs, outputs });
    Ok(())
}

/// The node description a graph file would have when included (its exposed ports), for preset
/// listings; problems in the file come back as diagnostics.
pub fn preset_desc(path: &Path, registry: &Registry) -> Result<NodeDesc, Diagnostics> {
    let options = BuildOptions { describe_only: true, ..BuildOptions::default() };
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // A preset listing builds the file as an include: refuse an include bomb before that, as a
    // graph's load does (a file that does not parse is reported by the build below).
    if let Ok(doc) = GraphDoc::load(path) {
        super::include_limit::check(&doc, &dir).map_err(|d| d.in_file(path))?;
    }
    let ctx = LoadCtx {
        registry,
        root: dir.clone(),
        dir,
        options: &options,
        include_stack: Vec::new(),
        nested: false,
        local_depth: 0,
        includes: Default::default(),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let nd = NodeDoc::new(INCLUDE_TYPE).param(INCLUDE_PATH, ParamValue::String(name));
    load("preset", &nd, &ctx).map(|built| built.1.clone()).map_err(|d| Diagnostics(d).in_file(path))
}

/// Whether `text` starts as a graph document does: blanks and comments, then `(` or `#![`
/// (RON's extensions), or the unversioned shape's `(` as well.
fn looks_like_a_graph(text: &str) -> bool {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(after) = rest.strip_prefix("//") {
            rest = after.split_once('\n').map_or("", |(_, r)| r);
        } else if let Some(after) = rest.strip_prefix("/*") {
            rest = after.split_once("*/").map_or("", |(_, r)| r);
        } else {
            return rest.starts_with('(') || rest.starts_with("#![") || rest.starts_with("GraphDoc");
        }
    }
}

fn short(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

fn nested(id: &str, file: &Path, inner: Vec<Diagnostic>) -> Vec<Diagnostic> {
    inner
        .into_iter()
        .map(|d| {
            let what = if d.kind == DiagnosticKind::Include { d.message } else { format!("{}: {}", d.location, d.message) };
            include_diag(id, format!("in included graph {}: {what}", file.display()))
        })
        .collect()
}

/// Ports of an include node, read from the sub-graph's interface and inner port descriptions.
fn describe(doc: &GraphDoc, sub: &Graph) -> Result<NodeDesc, String> {
    let iface = sub.interface.as_ref().ok_or("has no `interface`, so it cannot be used as a node")?;
    let mut desc = include_desc();
    if let Some(text) = &doc.description {
        desc.doc = text.clone();
    }
    let mut only_per_frame = sub.topo_order().iter().all(|i| {
        let n = sub.node(*i);
        !n.lifted && matches!(n.node.desc().time, TimeDep::Source | TimeDep::PerFrame)
    });
    for (name, idx, port) in &iface.inputs {
        let inner = &sub.node(*idx).node.desc().inputs[*port];
        only_per_frame &= !matches!(inner.ty, PortType::Clip(_));
        let default = match &sub.node(*idx).inputs[*port] {
            InputSource::Const(v) => Some(v.clone()),
            _ => None,
        };
        desc.inputs.push(PortDesc {
            name: name.clone(),
            default,
            doc: format!("Feeds {}.{}. {}", sub.node(*idx).id, inner.name, inner.doc),
            ..inner.clone()
        });
    }
    for (name, idx, port) in &iface.params {
        let inner = &sub.node(*idx).node.desc().inputs[*port];
        if !inner.ty.is_parameter() {
            return Err(format!("exposed parameter '{name}' points at a {} input; expose it under `inputs`", inner.ty));
        }
        let current = match &sub.node(*idx).inputs[*port] {
            InputSource::Const(v) => Some(v.clone()),
            _ => return Err(format!("exposed parameter '{name}' is connected inside the graph")),
        };
        desc.inputs.push(PortDesc {
            name: name.clone(),
            default: current,
            doc: format!("Sets {}.{}. {}", sub.node(*idx).id, inner.name, inner.doc),
            ..inner.clone()
        });
    }
    for (name, idx, port) in &iface.outputs {
        let ty = sub.node(*idx).out_types[*port].clone();
        only_per_frame &= !matches!(ty, PortType::Clip(_));
        desc.outputs.push(PortDesc::new(
            name,
            ty,
            &format!("Output {}.{}", sub.node(*idx).id, sub.node(*idx).node.desc().outputs[*port].name),
        ));
    }
    desc.time = if only_per_frame { TimeDep::PerFrame } else { TimeDep::WholeClip };
    Ok(desc)
}
