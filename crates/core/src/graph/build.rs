//! Building a graph from a document: nodes, edges, types, lifting and the checks that report
//! every problem at once.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use petgraph::algo::{kosaraju_scc, toposort};
use petgraph::stable_graph::{NodeIndex, StableDiGraph};
use petgraph::visit::EdgeRef;

use super::convert::{param_to_value, parse_hex_color, resolve_default};
use super::{Graph, GraphNode, Included, InputSource, Interface, LoadCtx, PATH_SEP, PortRef};
use crate::builtin::INCLUDE_TYPE;
use crate::document::{GraphDoc, InterfaceDoc, NodeDoc, split_endpoint};
use crate::error::{Diagnostic, DiagnosticKind, Diagnostics, Location};
use crate::node::{Node, NodeDesc, TimeDep};
use crate::value::{PortType, Value};

pub(super) fn diag(kind: DiagnosticKind, location: Location, message: impl Into<String>) -> Diagnostic {
    Diagnostic::new(kind, location, message)
}

/// The graph under construction: its nodes (an include's among them, as `inc/id`) and the
/// document's include nodes with the inner ports they stand for.
#[derive(Default)]
pub(super) struct Parts {
    pub g: StableDiGraph<GraphNode, (usize, usize)>,
    pub ids: HashMap<Arc<str>, NodeIndex>,
    pub includes: HashMap<Arc<str>, Included>,
}

impl Parts {
    /// How to name input `r` in a message: the include port that exposes it, else the node's own.
    fn input_label(&self, r: PortRef) -> (String, String) {
        for (id, inc) in &self.includes {
            if let Some(i) = inc.inputs.iter().position(|x| *x == Some(r)) {
                return (id.to_string(), inc.desc.inputs[i].name.clone());
            }
        }
        (self.g[r.0].id.to_string(), self.g[r.0].node.desc().inputs[r.1].name.clone())
    }

    /// Port `port` of node or include `node` as an inner port, or why not (for messages).
    fn endpoint(&self, node: &str, port: &str, output: bool) -> Result<PortRef, Option<(&NodeDesc, &'static str)>> {
        let side = if output { "output" } else { "input" };
        if let Some(&idx) = self.ids.get(node) {
            let desc = self.g[idx].node.desc();
            let found = if output { desc.output_index(port) } else { desc.input_index(port) };
            return found.map(|p| (idx, p)).ok_or(Some((desc, side)));
        }
        let inc = self.includes.get(node).ok_or(None)?;
        let found = if output { inc.desc.output_index(port) } else { inc.desc.input_index(port) };
        let inner = match found {
            Some(p) if output => inc.outputs.get(p).copied(),
            Some(p) => inc.inputs.get(p).copied().flatten(),
            None => None,
        };
        inner.ok_or(Some((&inc.desc, side)))
    }
}

pub(crate) fn build(doc: &GraphDoc, ctx: &LoadCtx) -> Result<Graph, Diagnostics> {
    let mut diags = Vec::new();
    let mut parts = Parts::default();
    let mut known: HashSet<&str> = HashSet::new();

    for (id, nd) in &doc.nodes.0 {
        if !known.insert(id) {
            diags.push(diag(
                DiagnosticKind::DuplicateNode,
                Location::Node(id.clone()),
                "duplicate node id: every node needs its own id",
            ));
            continue;
        }
        if id.contains(PATH_SEP) || id.is_empty() {
            diags.push(diag(
                DiagnosticKind::BadId,
                Location::Node(id.clone()),
                format!(
                    "node id \"{id}\" must be non-empty and free of '{PATH_SEP}', which joins an include's id to its nodes' ids"
                ),
            ));
            continue;
        }
        if nd.type_name == INCLUDE_TYPE {
            if nd.bypass {
                diags.push(diag(
                    DiagnosticKind::Bypass,
                    Location::Node(id.clone()),
                    "an included graph cannot be bypassed; bypass the node that takes its output, or nodes inside it",
                ));
                continue;
            }
            if let Err(mut d) = super::include::flatten(id, nd, doc.subgraphs.get(id), ctx, &mut parts) {
                diags.append(&mut d);
            }
            continue;
        }
        let Some(mut node) = instantiate(id, nd, ctx, &mut diags) else { continue };
        if nd.bypass {
            match super::bypass::bypassed(node) {
                Ok(b) => node = b,
                Err(message) => {
                    diags.push(diag(DiagnosticKind::Bypass, Location::Node(id.clone()), message));
                    continue;
                }
            }
        }
        let inputs = node_inputs(id, nd, node.desc(), ctx, &mut diags);
        let id: Arc<str> = Arc::from(id.as_str());
        let out_types = node.desc().outputs.iter().map(|p| p.ty.clone()).collect();
        let idx = parts.g.add_node(GraphNode { id: id.clone(), node, inputs, lifted: false, out_types });
        parts.ids.insert(id, idx);
    }

    let mut connected: HashSet<(NodeIndex, usize)> = HashSet::new();
    for (i, (from, to)) in doc.edges.iter().enumerate() {
        let loc = Location::Edge { index: i, text: format!("{from} -> {to}") };
        let Some((src, dst)) = resolve_edge(from, to, &loc, &parts, &known, &mut diags) else { continue };
        if !connected.insert((dst.0, dst.1)) {
            let (node, port) = parts.input_label(dst);
            diags.push(diag(
                DiagnosticKind::DuplicateEdge,
                loc,
                format!("input '{node}.{port}' already has an incoming edge; an input takes one connection"),
            ));
            continue;
        }
        parts.g[dst.0].inputs[dst.1] = InputSource::Edge { from: src.0, port: src.1 };
        parts.g.add_edge(src.0, dst.0, (src.1, dst.1));
    }

    let order = match check_cycles(&parts.g, &mut diags) {
        true => toposort(&parts.g, None).unwrap_or_default(),
        false => Vec::new(),
    };
    type_check(&mut parts, &order, &mut diags);
    let interface = match &doc.interface {
        Some(iface) => resolve_interface(iface, &parts, &mut diags),
        None => None,
    };
    let fed: HashSet<(NodeIndex, usize)> = interface.iter().flat_map(|i| i.inputs.iter().map(|(_, n, p)| (*n, *p))).collect();
    check_missing_inputs(&parts, &fed, &mut diags);
    if !ctx.nested {
        check_animated(&parts, &mut diags);
    }
    check_groups(doc, &known, &mut diags);
    check_subgraphs(doc, &mut diags);

    if !diags.is_empty() {
        return Err(Diagnostics(diags));
    }
    let Parts { g, ids, includes } = parts;
    Ok(Graph { g, ids, order, dir: ctx.dir.clone(), file: None, interface, includes })
}

/// Every local subgraph belongs to an include node of the same id.
fn check_subgraphs(doc: &GraphDoc, diags: &mut Vec<Diagnostic>) {
    for id in doc.subgraphs.keys() {
        let why = match doc.node(id) {
            None => "there is no node with that id",
            Some(nd) if nd.type_name != INCLUDE_TYPE => "that node is not a graph.include",
            Some(_) => continue,
        };
        diags.push(diag(
            DiagnosticKind::Include,
            Location::Node(id.clone()),
            format!("local subgraph '{id}' belongs to no included graph ({why}); delete it from `subgraphs` or rename it"),
        ));
    }
}

/// Groups name nodes that exist, each node in at most one group, and colours parse.
fn check_groups(doc: &GraphDoc, known: &HashSet<&str>, diags: &mut Vec<Diagnostic>) {
    let mut owner: HashMap<&str, usize> = HashMap::new();
    for (i, group) in doc.groups.iter().enumerate() {
        let loc = Location::Group { index: i, title: group.title.clone() };
        for n in &group.nodes {
            if !known.contains(n.as_str()) {
                diags.push(diag(
                    DiagnosticKind::MissingNode,
                    loc.clone(),
                    format!("group names node '{n}', which is not in the graph"),
                ));
            } else if let Some(first) = owner.insert(n, i)
                && first != i
            {
                diags.push(diag(
                    DiagnosticKind::DuplicateNode,
                    loc.clone(),
                    format!("node '{n}' is already in group #{first}; a node belongs to one group"),
                ));
            }
        }
        if let Some(c) = &group.color
            && parse_hex_color(c).is_none()
        {
            diags.push(diag(DiagnosticKind::WrongKind, loc.clone(), format!("colour \"{c}\" is not of the form \"#rrggbb\"")));
        }
    }
    for (i, c) in doc.comments.iter().enumerate() {
        if let Some(col) = &c.color
            && parse_hex_color(col).is_none()
        {
            diags.push(diag(
                DiagnosticKind::WrongKind,
                Location::File,
                format!("comment #{i}: colour \"{col}\" is not of the form \"#rrggbb\""),
            ));
        }
    }
}

fn instantiate(id: &str, nd: &NodeDoc, ctx: &LoadCtx, diags: &mut Vec<Diagnostic>) -> Option<Arc<dyn Node>> {
    match ctx.registry.get(&nd.type_name) {
        Some(node) => Some(node.clone()),
        None => {
            let hint = ctx.registry.suggest(&nd.type_name).map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default();
            // A plugin that failed to load (or plugins turned off) may be why: say so.
            let problems = ctx.registry.extension().map(|f| f.problems.as_slice()).unwrap_or_default();
            let broken: String = problems.iter().map(|p| format!("; {p}")).collect();
            diags.push(diag(
                DiagnosticKind::UnknownNodeType,
                Location::Node(id.to_string()),
                format!(
                    "unknown node type '{}'{hint}; `pyrograph nodes` lists them{broken}",
                    crate::error::shortened(&nd.type_name)
                ),
            ));
            None
        }
    }
}

/// Initial input sources: parameters from the file, else defaults, else `Missing`.
pub(super) fn node_inputs(
    id: &str,
    nd: &NodeDoc,
    desc: &NodeDesc,
    ctx: &LoadCtx,
    diags: &mut Vec<Diagnostic>,
) -> Vec<InputSource> {
    let mut inputs: Vec<Option<Value>> = desc.inputs.iter().map(|p| resolve_default(p, ctx)).collect();
    let mut invalid = vec![false; desc.inputs.len()];
    for (name, pv) in &nd.params {
        let loc = Location::Port { node: id.to_string(), port: name.clone() };
        let Some(i) = desc.input_index(name) else {
            let names: Vec<&str> = desc.inputs.iter().filter(|p| p.ty.is_parameter()).map(|p| p.name.as_str()).collect();
            diags.push(diag(
                DiagnosticKind::UnknownPort,
                loc,
                format!("'{}' has no parameter '{name}' (it has: {})", desc.type_name, names.join(", ")),
            ));
            continue;
        };
        match param_to_value(pv, &desc.inputs[i], ctx) {
            Ok(v) => inputs[i] = Some(v),
            Err((kind, message)) => {
                invalid[i] = true;
                diags.push(diag(kind, loc, message));
            }
        }
    }
    inputs
        .into_iter()
        .zip(invalid)
        .map(|(v, bad)| match (v, bad) {
            (_, true) => InputSource::Invalid,
            (Some(v), false) => InputSource::Const(v),
            (None, false) => InputSource::Missing,
        })
        .collect()
}

fn resolve_edge(
    from: &str,
    to: &str,
    loc: &Location,
    parts: &Parts,
    known: &HashSet<&str>,
    diags: &mut Vec<Diagnostic>,
) -> Option<(PortRef, PortRef)> {
    let mut endpoint = |text: &str, output: bool| -> Option<PortRef> {
        let Some((node, port)) = split_endpoint(text) else {
            diags.push(diag(DiagnosticKind::MalformedEdge, loc.clone(), format!("'{text}' is not of the form node.port")));
            return None;
        };
        match parts.endpoint(node, port, output) {
            Ok(r) => Some(r),
            // A node that exists but failed to instantiate already has its own diagnostic.
            Err(None) if known.contains(node) => None,
            Err(None) => {
                diags.push(diag(
                    DiagnosticKind::MissingNode,
                    loc.clone(),
                    format!("edge names node '{node}', which is not in the graph"),
                ));
                None
            }
            Err(Some((desc, side))) => {
                let ports = if output { &desc.outputs } else { &desc.inputs };
                let names: Vec<&str> = ports.iter().map(|p| p.name.as_str()).collect();
                diags.push(diag(
                    DiagnosticKind::UnknownPort,
                    Location::Port { node: node.to_string(), port: port.to_string() },
                    format!(
                        "'{}' has no {side} '{port}' (its {side}s: {}) — in edge {from} -> {to}",
                        desc.type_name,
                        names.join(", ")
                    ),
                ));
                None
            }
        }
    };
    let src = endpoint(from, true);
    let dst = endpoint(to, false);
    Some((src?, dst?))
}

/// Reports every cycle, naming its nodes; returns whether the graph is acyclic.
fn check_cycles(g: &StableDiGraph<GraphNode, (usize, usize)>, diags: &mut Vec<Diagnostic>) -> bool {
    let mut acyclic = true;
    // Kosaraju, not Tarjan: petgraph's Tarjan recurses once per node of a chain (a 100,000-node
    // chain overflowed the stack); its Kosaraju walks with explicit stacks.
    for scc in kosaraju_scc(g) {
        let self_loop = scc.len() == 1 && g.contains_edge(scc[0], scc[0]);
        if scc.len() > 1 || self_loop {
            acyclic = false;
            let mut names: Vec<&str> = scc.iter().map(|i| &*g[*i].id).collect();
            names.sort_unstable();
            let first = names[0].to_string();
            // A cycle through a huge graph names a few of its nodes, not all of them.
            const NAMED: usize = 8;
            let mut listed = names.iter().take(NAMED).map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ");
            if names.len() > NAMED {
                listed = format!("{} nodes ({listed}, …)", names.len());
            }
            diags.push(diag(
                DiagnosticKind::Cycle,
                Location::Node(first),
                format!("cycle through nodes {listed}: a graph must not feed a node's output back into itself"),
            ));
        }
    }
    acyclic
}

/// Checks each edge's types in topological order, deciding lifting as it goes.
fn type_check(parts: &mut Parts, order: &[NodeIndex], diags: &mut Vec<Diagnostic>) {
    for &idx in order {
        let g = &parts.g;
        let mut lifted = false;
        let incoming: Vec<(NodeIndex, usize, usize)> =
            g.edges_directed(idx, petgraph::Direction::Incoming).map(|e| (e.source(), e.weight().0, e.weight().1)).collect();
        for (src, out_port, in_port) in incoming {
            let have = &g[src].out_types[out_port];
            let desc = g[idx].node.desc();
            let want = &desc.inputs[in_port].ty;
            if have == want {
                continue;
            }
            if have.clip_element() == Some(want) && desc.time == TimeDep::PerFrame {
                lifted = true;
                continue;
            }
            let hint = if have.clip_element() == Some(want) {
                format!(" ('{}' is a {} node, so it cannot run once per frame)", desc.type_name, desc.time.name())
            } else {
                String::new()
            };
            let (node, port) = parts.input_label((idx, in_port));
            diags.push(diag(
                DiagnosticKind::TypeMismatch,
                Location::Port { node, port },
                format!(
                    "type mismatch: needs {want}, got {have} from '{}.{}'{hint}",
                    g[src].id,
                    g[src].node.desc().outputs[out_port].name
                ),
            ));
        }
        let node = &mut parts.g[idx];
        node.lifted = lifted;
        // Decided afresh: an included graph's nodes were type-checked on their own before their
        // include's inputs were connected.
        node.out_types = node.node.desc().outputs.iter().map(|p| p.ty.clone()).collect();
        if lifted {
            node.out_types = node.node.desc().outputs.iter().map(|p| PortType::clip_of(p.ty.clone())).collect();
        }
    }
}

/// An animated parameter needs something that samples it over time: the evaluator, for a
/// per-frame node fed a clip (it cooks frame `f` with the value at `f`), or the node itself, for
/// a parameter it declares as sampled per step. Anywhere else the animation would be read once
/// and silently frozen, so it is refused with what would make it follow time.
fn check_animated(parts: &Parts, diags: &mut Vec<Diagnostic>) {
    for idx in parts.g.node_indices() {
        let node = &parts.g[idx];
        let desc = node.node.desc();
        for (i, (src, port)) in node.inputs.iter().zip(&desc.inputs).enumerate() {
            if !matches!(src, InputSource::Const(Value::Anim(_))) || port.sampled_by_node || node.lifted {
                continue;
            }
            let why = match desc.time {
                TimeDep::PerFrame => format!(
                    "'{}' is not fed a clip here, so it cooks once rather than per frame; connect a clip to one of its inputs",
                    node.id
                ),
                t => format!(
                    "'{}' is a {} node and reads '{}' once for the whole clip (`pyrograph nodes` marks the parameters it samples per step)",
                    desc.type_name,
                    t.name(),
                    port.name
                ),
            };
            let (node_id, name) = parts.input_label((idx, i));
            diags.push(diag(
                DiagnosticKind::Animation,
                Location::Port { node: node_id, port: name.clone() },
                format!("'{name}' is animated, but nothing samples it over time: {why}, or set a constant"),
            ));
        }
    }
}

fn check_missing_inputs(parts: &Parts, fed: &HashSet<(NodeIndex, usize)>, diags: &mut Vec<Diagnostic>) {
    let g = &parts.g;
    for idx in g.node_indices() {
        let node = &g[idx];
        for (i, (src, port)) in node.inputs.iter().zip(&node.node.desc().inputs).enumerate() {
            if matches!(src, InputSource::Missing) && !fed.contains(&(idx, i)) {
                let how =
                    if port.ty.is_parameter() { "set it in params or connect a node" } else { "connect a node's output to it" };
                let (node, name) = parts.input_label((idx, i));
                diags.push(diag(
                    DiagnosticKind::MissingInput,
                    Location::Port { node, port: name.clone() },
                    format!("required input '{name}' ({}) is not set: {how}", port.ty),
                ));
            }
        }
    }
}

fn resolve_interface(iface: &InterfaceDoc, parts: &Parts, diags: &mut Vec<Diagnostic>) -> Option<Interface> {
    let mut out = Interface::default();
    let mut ok = true;
    let mut resolve =
        |name: &str, target: &str, output: bool, list: &mut Vec<(String, NodeIndex, usize)>| match split_endpoint(target)
            .and_then(|(n, p)| parts.endpoint(n, p, output).ok())
        {
            Some((idx, port)) => list.push((name.to_string(), idx, port)),
            None => {
                ok = false;
                diags.push(diag(
                    DiagnosticKind::Include,
                    Location::File,
                    format!(
                        "interface '{name}' points at '{target}', which is not a {} port of a node in this graph",
                        if output { "output" } else { "input" }
                    ),
                ));
            }
        };
    for (name, target) in &iface.inputs {
        resolve(name, target, false, &mut out.inputs);
    }
    for (name, target) in &iface.outputs {
        resolve(name, target, true, &mut out.outputs);
    }
    for (name, target) in &iface.params {
        resolve(name, target, false, &mut out.params);
    }
    ok.then_some(out)
}
