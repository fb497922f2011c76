//! `graph.include`: a graph file that declares an interface, used as one node (preset libraries).

use std::path::Path;
use std::sync::{Arc, Mutex};

use crate::ctx::CookCtx;
use crate::document::{GraphDoc, NodeDoc, ParamValue};
use crate::error::{Diagnostic, DiagnosticKind, Location, NodeError};
use crate::eval::Evaluator;
use crate::fingerprint::Fingerprinter;
use crate::graph::{self, Graph, InputSource, LoadCtx, expand_vars};
use crate::node::{Inputs, Node, NodeDesc, PathRole, PortDesc, TimeDep};
use crate::value::{PortType, Value};

/// The type name of include nodes.
pub const INCLUDE_TYPE: &str = "graph.include";

/// The description listed in the registry (ports are added per included file).
pub fn include_desc() -> NodeDesc {
    NodeDesc::new(
        INCLUDE_TYPE,
        "Graph",
        TimeDep::WholeClip,
        "Uses another graph file as one node: its declared interface inputs, outputs and exposed \
         parameters become this node's ports. The path resolves against the including file's folder.",
    )
    .input(PortDesc::path("path", PathRole::Input, None, "Graph file to include (RON with an `interface`)."))
}

/// The registry's placeholder: include nodes are built by the graph loader, which knows the file.
pub(crate) struct IncludePlaceholder(pub NodeDesc);

impl Node for IncludePlaceholder {
    fn desc(&self) -> &NodeDesc {
        &self.0
    }
    fn cook(&self, _: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
        Err(NodeError::msg("graph.include must be created by the graph loader"))
    }
}

/// An included graph.
struct IncludeNode {
    desc: NodeDesc,
    sub: Arc<Graph>,
    doc_hash: u64,
    eval: Mutex<Evaluator>,
}

fn include_diag(id: &str, message: String) -> Diagnostic {
    Diagnostic::new(DiagnosticKind::Include, Location::Port { node: id.to_string(), port: "path".into() }, message)
}

pub(crate) fn instantiate(id: &str, nd: &NodeDoc, ctx: &LoadCtx) -> Result<Arc<dyn Node>, Vec<Diagnostic>> {
    let raw = match nd.params.get("path") {
        Some(ParamValue::String(s)) => s,
        Some(other) => return Err(vec![include_diag(id, format!("needs a path string, got {other}"))]),
        None => return Err(vec![include_diag(id, "graph.include needs a 'path' parameter naming the graph file".into())]),
    };
    let expanded = expand_vars(raw).map_err(|m| vec![include_diag(id, m)])?;
    let path = ctx.dir.join(&expanded);
    let canon = std::fs::canonicalize(&path)
        .map_err(|e| vec![include_diag(id, format!("cannot open included graph {}: {e}", path.display()))])?;
    if ctx.include_stack.contains(&canon) {
        let chain: Vec<String> = ctx.include_stack.iter().chain([&canon]).map(|p| short(p)).collect();
        return Err(vec![include_diag(id, format!("include cycle: {}", chain.join(" -> ")))]);
    }
    let text =
        std::fs::read_to_string(&canon).map_err(|e| vec![include_diag(id, format!("cannot read {}: {e}", canon.display()))])?;
    let doc = GraphDoc::from_ron(&text).map_err(|d| nested(id, &canon, d.0))?;
    let mut stack = ctx.include_stack.clone();
    stack.push(canon.clone());
    let child = LoadCtx { dir: canon.parent().map(Path::to_path_buf).unwrap_or_default(), include_stack: stack, ..ctx.clone() };
    let mut sub = graph::build(&doc, &child).map_err(|d| nested(id, &canon, d.0))?;
    sub.file = Some(canon.clone());
    let desc = describe(&doc, &sub).map_err(|m| vec![include_diag(id, format!("{}: {m}", canon.display()))])?;
    let mut h = Fingerprinter::new();
    std::hash::Hash::hash(&text, &mut h);
    let doc_hash = std::hash::Hasher::finish(&h);
    Ok(Arc::new(IncludeNode { desc, sub: Arc::new(sub), doc_hash, eval: Mutex::new(Evaluator::new()) }))
}

/// The node description a graph file would have when included (its exposed ports), for preset
/// listings; problems in the file come back as diagnostics.
pub fn preset_desc(path: &Path, registry: &crate::Registry) -> Result<NodeDesc, crate::Diagnostics> {
    let options = graph::BuildOptions::default();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let ctx = LoadCtx { registry, dir, options: &options, include_stack: Vec::new() };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let nd = NodeDoc::new(INCLUDE_TYPE).param("path", ParamValue::String(name));
    instantiate("preset", &nd, &ctx).map(|n| n.desc().clone()).map_err(|d| crate::Diagnostics(d).in_file(path))
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

impl Node for IncludeNode {
    fn desc(&self) -> &NodeDesc {
        &self.desc
    }

    fn fingerprint_salt(&self) -> u64 {
        self.doc_hash
    }

    fn cook(&self, inputs: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let Some(iface) = &self.sub.interface else { return Err(NodeError::msg("included graph has no interface")) };
        let mut g = (*self.sub).clone();
        for (name, idx, port) in iface.inputs.iter().chain(&iface.params) {
            g.set_const(*idx, *port, inputs.get(name)?.clone());
        }
        let mut targets: Vec<&str> = iface.outputs.iter().map(|(_, idx, _)| &*g.node(*idx).id).collect();
        targets.dedup();
        // Per-frame includes may cook from several threads at once; only one can use the
        // persistent (incremental) evaluator, the others cook with a fresh one.
        let mut fresh;
        let mut guard = self.eval.try_lock();
        let eval = match guard.as_mut() {
            Ok(e) => &mut **e,
            Err(_) => {
                fresh = Evaluator::new();
                &mut fresh
            }
        };
        let result = eval.cook(&g, &targets, ctx)?;
        iface
            .outputs
            .iter()
            .map(|(_, idx, port)| {
                let id = &g.node(*idx).id;
                let port_name = &g.node(*idx).node.desc().outputs[*port].name;
                result.output(&g, id, port_name)
            })
            .collect()
    }
}
