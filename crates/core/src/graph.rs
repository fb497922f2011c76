//! The runtime graph: a petgraph DAG built from a document, validated all at once.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use petgraph::algo::{tarjan_scc, toposort};
use petgraph::stable_graph::{NodeIndex, StableDiGraph};
use petgraph::visit::EdgeRef;

use crate::document::{GraphDoc, NodeDoc, ParamValue, split_endpoint};
use crate::error::{Diagnostic, DiagnosticKind, Diagnostics, Location};
use crate::node::{Node, PathRole, PortDesc, TimeDep};
use crate::registry::Registry;
use crate::value::{PortType, Value};

/// Options that change how a document's paths resolve.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Where relative output paths go (`--out`); the graph file's folder when `None`.
    pub output_dir: Option<PathBuf>,
}

/// Where an input's value comes from.
#[derive(Clone, Debug)]
pub enum InputSource {
    /// A constant: the parameter from the file, or the port's default.
    Const(Value),
    /// A required input that is neither set nor connected (only inside sub-graphs, whose
    /// interface inputs are fed when the include cooks; validation rejects it anywhere else).
    Missing,
    /// A parameter whose value was rejected (already reported; the graph does not build).
    Invalid,
    /// Output `port` of another node.
    Edge {
        /// The upstream node.
        from: NodeIndex,
        /// Its output port index.
        port: usize,
    },
}

/// A node placed in a graph.
#[derive(Clone)]
pub struct GraphNode {
    /// The readable id from the document.
    pub id: Arc<str>,
    /// The node type.
    pub node: Arc<dyn Node>,
    /// One source per input port, in description order.
    pub inputs: Vec<InputSource>,
    /// Whether a clip feeds a per-frame input, so the node runs once per frame.
    pub lifted: bool,
    /// Output types after lifting.
    pub out_types: Vec<PortType>,
}

/// A sub-graph's exposed ports, resolved to inner nodes.
#[derive(Clone, Debug, Default)]
pub struct Interface {
    /// Exposed input name → (inner node, input port).
    pub inputs: Vec<(String, NodeIndex, usize)>,
    /// Exposed output name → (inner node, output port).
    pub outputs: Vec<(String, NodeIndex, usize)>,
    /// Exposed parameter name → (inner node, input port).
    pub params: Vec<(String, NodeIndex, usize)>,
}

/// A validated, type-checked graph ready to cook.
#[derive(Clone)]
pub struct Graph {
    pub(crate) g: StableDiGraph<GraphNode, (usize, usize)>,
    ids: HashMap<Arc<str>, NodeIndex>,
    order: Vec<NodeIndex>,
    /// The folder relative input paths resolved against.
    pub dir: PathBuf,
    /// The file the graph came from, if any.
    pub file: Option<PathBuf>,
    /// Exposed ports, for graphs used as presets.
    pub interface: Option<Interface>,
}

/// What the loader carries while building a graph and its includes.
#[derive(Clone)]
pub(crate) struct LoadCtx<'a> {
    pub registry: &'a Registry,
    pub dir: PathBuf,
    pub options: &'a BuildOptions,
    /// Canonical paths of the files being included, outermost first (for cycle detection).
    pub include_stack: Vec<PathBuf>,
}

impl Graph {
    /// Loads, migrates, validates and type-checks a graph file.
    pub fn load(path: &Path, registry: &Registry, options: &BuildOptions) -> Result<(GraphDoc, Graph), Diagnostics> {
        let doc = GraphDoc::load(path)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let stack = vec![std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())];
        let ctx = LoadCtx { registry, dir, options, include_stack: stack };
        let mut graph = build(&doc, &ctx).map_err(|d| d.in_file(path))?;
        graph.file = Some(path.to_path_buf());
        Ok((doc, graph))
    }

    /// Validates and type-checks a document whose relative paths resolve against `dir`.
    pub fn build(doc: &GraphDoc, registry: &Registry, dir: &Path, options: &BuildOptions) -> Result<Graph, Diagnostics> {
        let ctx = LoadCtx { registry, dir: dir.to_path_buf(), options, include_stack: Vec::new() };
        build(doc, &ctx)
    }

    /// The node index of id `id`.
    pub fn index(&self, id: &str) -> Option<NodeIndex> {
        self.ids.get(id).copied()
    }

    /// The node at `idx`.
    pub fn node(&self, idx: NodeIndex) -> &GraphNode {
        &self.g[idx]
    }

    /// Node indices in topological order.
    pub fn topo_order(&self) -> &[NodeIndex] {
        &self.order
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.g.node_count()
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.g.edge_count()
    }

    /// Ids of the nodes whose type is a sink (writers), in topological order.
    pub fn sinks(&self) -> Vec<Arc<str>> {
        self.order.iter().filter(|i| self.g[**i].node.desc().time == TimeDep::Sink).map(|i| self.g[*i].id.clone()).collect()
    }

    /// Ids of the nodes with no downstream consumer, in topological order.
    pub fn leaves(&self) -> Vec<Arc<str>> {
        self.order
            .iter()
            .filter(|i| self.g.neighbors_directed(**i, petgraph::Direction::Outgoing).next().is_none())
            .map(|i| self.g[*i].id.clone())
            .collect()
    }

    /// Replaces input `port` of node `idx` by a constant (used to feed a sub-graph's inputs).
    pub fn set_const(&mut self, idx: NodeIndex, port: usize, value: Value) {
        self.g[idx].inputs[port] = InputSource::Const(value);
    }

    /// Upstream nodes of `idx` (the nodes feeding it directly).
    pub fn upstream(&self, idx: NodeIndex) -> impl Iterator<Item = NodeIndex> + '_ {
        self.g.neighbors_directed(idx, petgraph::Direction::Incoming)
    }
}

fn diag(kind: DiagnosticKind, location: Location, message: impl Into<String>) -> Diagnostic {
    Diagnostic::new(kind, location, message)
}

pub(crate) fn build(doc: &GraphDoc, ctx: &LoadCtx) -> Result<Graph, Diagnostics> {
    let mut diags = Vec::new();
    let mut g: StableDiGraph<GraphNode, (usize, usize)> = StableDiGraph::new();
    let mut ids: HashMap<Arc<str>, NodeIndex> = HashMap::new();
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
        let Some(node) = instantiate(id, nd, ctx, &mut diags) else { continue };
        let inputs = node_inputs(id, nd, node.as_ref(), ctx, &mut diags);
        let id: Arc<str> = Arc::from(id.as_str());
        let out_types = node.desc().outputs.iter().map(|p| p.ty.clone()).collect();
        let idx = g.add_node(GraphNode { id: id.clone(), node, inputs, lifted: false, out_types });
        ids.insert(id, idx);
    }

    let mut connected: HashSet<(NodeIndex, usize)> = HashSet::new();
    for (i, (from, to)) in doc.edges.iter().enumerate() {
        let loc = Location::Edge { index: i, text: format!("{from} -> {to}") };
        let Some((src, dst)) = resolve_edge(from, to, &loc, &g, &ids, &known, &mut diags) else { continue };
        if !connected.insert((dst.0, dst.1)) {
            let port = g[dst.0].node.desc().inputs[dst.1].name.clone();
            diags.push(diag(
                DiagnosticKind::DuplicateEdge,
                loc,
                format!("input '{}.{port}' already has an incoming edge; an input takes one connection", g[dst.0].id),
            ));
            continue;
        }
        g[dst.0].inputs[dst.1] = InputSource::Edge { from: src.0, port: src.1 };
        g.add_edge(src.0, dst.0, (src.1, dst.1));
    }

    let order = match check_cycles(&g, &mut diags) {
        true => toposort(&g, None).unwrap_or_default(),
        false => Vec::new(),
    };
    type_check(&mut g, &order, &mut diags);
    let interface = match &doc.interface {
        Some(iface) => resolve_interface(iface, &g, &ids, &mut diags),
        None => None,
    };
    let fed: HashSet<(NodeIndex, usize)> = interface.iter().flat_map(|i| i.inputs.iter().map(|(_, n, p)| (*n, *p))).collect();
    check_missing_inputs(&g, &fed, &mut diags);
    check_groups(doc, &known, &mut diags);

    if !diags.is_empty() {
        return Err(Diagnostics(diags));
    }
    Ok(Graph { g, ids, order, dir: ctx.dir.clone(), file: None, interface })
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
    if nd.type_name == crate::include::INCLUDE_TYPE {
        return match crate::include::instantiate(id, nd, ctx) {
            Ok(node) => Some(node),
            Err(mut d) => {
                diags.append(&mut d);
                None
            }
        };
    }
    match ctx.registry.get(&nd.type_name) {
        Some(node) => Some(node.clone()),
        None => {
            let hint = ctx.registry.suggest(&nd.type_name).map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default();
            diags.push(diag(
                DiagnosticKind::UnknownNodeType,
                Location::Node(id.to_string()),
                format!("unknown node type '{}'{hint}; `pyrograph nodes` lists them", nd.type_name),
            ));
            None
        }
    }
}

/// Initial input sources: parameters from the file, else defaults, else `Missing`.
fn node_inputs(id: &str, nd: &NodeDoc, node: &dyn Node, ctx: &LoadCtx, diags: &mut Vec<Diagnostic>) -> Vec<InputSource> {
    let desc = node.desc();
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

fn resolve_default(port: &PortDesc, ctx: &LoadCtx) -> Option<Value> {
    match (&port.default, port.path_role) {
        (Some(Value::Path(p)), Some(role)) => Some(Value::Path(resolve_path(p, role, ctx))),
        (d, _) => d.clone(),
    }
}

fn resolve_path(p: &Path, role: PathRole, ctx: &LoadCtx) -> PathBuf {
    if p.is_absolute() {
        return p.to_path_buf();
    }
    match (role, &ctx.options.output_dir) {
        (PathRole::Output, Some(out)) => out.join(p),
        _ => ctx.dir.join(p),
    }
}

/// Expands `${NAME}` from the environment; an unset variable is an error naming it.
pub fn expand_vars(text: &str) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("${") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        let end = after.find('}').ok_or_else(|| format!("unclosed '${{' in \"{text}\""))?;
        let name = &after[..end];
        match std::env::var(name) {
            Ok(v) if !v.is_empty() => out.push_str(&v),
            _ => {
                return Err(format!(
                    "environment variable {name} is not set (used in \"{text}\"); set it, e.g. `export {name}=/path`"
                ));
            }
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

fn number(pv: &ParamValue) -> Option<f64> {
    match pv {
        ParamValue::Int(v) => Some(*v as f64),
        ParamValue::Float(v) => Some(*v),
        _ => None,
    }
}

fn numbers<const N: usize>(pv: &ParamValue) -> Option<[f64; N]> {
    match pv {
        ParamValue::List(items) if items.len() == N => {
            let mut out = [0.0; N];
            for (o, item) in out.iter_mut().zip(items) {
                *o = number(item)?;
            }
            Some(out)
        }
        _ => None,
    }
}

/// Parses `#rrggbb` or `#rrggbbaa` into straight RGBA in 0..1.
pub fn parse_hex_color(s: &str) -> Option<[f32; 4]> {
    let hex = s.strip_prefix('#')?;
    if !(hex.len() == 6 || hex.len() == 8) || !hex.is_ascii() {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok().map(|b| b as f32 / 255.0);
    let a = if hex.len() == 8 { byte(6)? } else { 1.0 };
    Some([byte(0)?, byte(2)?, byte(4)?, a])
}

fn check_range(v: f64, port: &PortDesc) -> Result<(), (DiagnosticKind, String)> {
    match port.range {
        Some((lo, hi)) if !(lo..=hi).contains(&v) => {
            Err((DiagnosticKind::OutOfRange, format!("{v} is outside the range {lo}..={hi}")))
        }
        _ if v.is_nan() => Err((DiagnosticKind::OutOfRange, "NaN is not a valid value".to_string())),
        _ => Ok(()),
    }
}

/// Converts a parameter from a file to a typed value for `port`, checking kind and range.
pub(crate) fn param_to_value(pv: &ParamValue, port: &PortDesc, ctx: &LoadCtx) -> Result<Value, (DiagnosticKind, String)> {
    let wrong = |what: &str| (DiagnosticKind::WrongKind, format!("needs {what}, got {pv}"));
    match &port.ty {
        PortType::Float => {
            let v = number(pv).ok_or_else(|| wrong("a number"))?;
            check_range(v, port)?;
            Ok(Value::Float(v))
        }
        PortType::Int => {
            let ParamValue::Int(v) = pv else { return Err(wrong("an integer")) };
            check_range(*v as f64, port)?;
            Ok(Value::Int(*v))
        }
        PortType::Bool => match pv {
            ParamValue::Bool(b) => Ok(Value::Bool(*b)),
            _ => Err(wrong("true or false")),
        },
        PortType::Color => {
            let c = match pv {
                ParamValue::String(s) => parse_hex_color(s),
                _ => numbers::<4>(pv)
                    .map(|c| c.map(|v| v as f32))
                    .or_else(|| numbers::<3>(pv).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0])),
            };
            c.map(Value::Color).ok_or_else(|| wrong("a colour: (r, g, b), (r, g, b, a) or \"#rrggbb\""))
        }
        PortType::Vec2 => numbers::<2>(pv).map(Value::Vec2).ok_or_else(|| wrong("(x, y)")),
        PortType::Vec3 => numbers::<3>(pv).map(Value::Vec3).ok_or_else(|| wrong("(x, y, z)")),
        PortType::String => match pv {
            ParamValue::String(s) => Ok(Value::String(s.clone())),
            _ => Err(wrong("a string")),
        },
        PortType::Enum => match pv {
            ParamValue::String(s) if port.options.iter().any(|o| o == s) => Ok(Value::Enum(s.clone())),
            ParamValue::String(s) => {
                Err((DiagnosticKind::OutOfRange, format!("\"{s}\" is not one of: {}", port.options.join(", "))))
            }
            _ => Err(wrong(&format!("one of: {}", port.options.join(", ")))),
        },
        PortType::Path => match pv {
            ParamValue::String(s) => {
                let expanded = expand_vars(s).map_err(|m| (DiagnosticKind::UnsetVariable, m))?;
                Ok(Value::Path(resolve_path(Path::new(&expanded), port.path_role.unwrap_or(PathRole::Input), ctx)))
            }
            _ => Err(wrong("a path string")),
        },
        // Every data type (images, masks, clips, databases…): see `PortType::is_parameter`.
        _ => Err((
            DiagnosticKind::WrongKind,
            format!("is a {} input: connect another node's output to it instead of writing a value", port.ty),
        )),
    }
}

/// Converts a typed constant back to its file form (for presets and the editor).
pub fn value_to_param(v: &Value) -> Option<ParamValue> {
    Some(match v {
        Value::Float(x) => ParamValue::Float(*x),
        Value::Int(x) => ParamValue::Int(*x),
        Value::Bool(x) => ParamValue::Bool(*x),
        Value::Color(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x as f64)).collect()),
        Value::Vec2(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x)).collect()),
        Value::Vec3(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x)).collect()),
        Value::String(s) | Value::Enum(s) => ParamValue::String(s.clone()),
        Value::Path(p) => ParamValue::String(p.display().to_string()),
        Value::Image(_)
        | Value::Mask(_)
        | Value::Contours(_)
        | Value::WindField(_)
        | Value::Particles(_)
        | Value::ClothState(_)
        | Value::Basis(_)
        | Value::Weights(_)
        | Value::FrameList(_)
        | Value::ParamSeries(_)
        | Value::ArModel(_)
        | Value::FlameModel(_)
        | Value::Mesh(_)
        | Value::SpreadState(_)
        | Value::Clip(_) => {
            return None;
        }
    })
}

type PortRef = (NodeIndex, usize);

#[allow(clippy::too_many_arguments)]
fn resolve_edge(
    from: &str,
    to: &str,
    loc: &Location,
    g: &StableDiGraph<GraphNode, (usize, usize)>,
    ids: &HashMap<Arc<str>, NodeIndex>,
    known: &HashSet<&str>,
    diags: &mut Vec<Diagnostic>,
) -> Option<(PortRef, PortRef)> {
    let mut endpoint = |text: &str, output: bool| -> Option<PortRef> {
        let Some((node, port)) = split_endpoint(text) else {
            diags.push(diag(DiagnosticKind::MalformedEdge, loc.clone(), format!("'{text}' is not of the form node.port")));
            return None;
        };
        let Some(&idx) = ids.get(node) else {
            // A node that exists but failed to instantiate already has its own diagnostic.
            if !known.contains(node) {
                diags.push(diag(
                    DiagnosticKind::MissingNode,
                    loc.clone(),
                    format!("edge names node '{node}', which is not in the graph"),
                ));
            }
            return None;
        };
        let desc = g[idx].node.desc();
        let (found, side, names) = if output {
            (desc.output_index(port), "output", desc.outputs.iter().map(|p| p.name.as_str()).collect::<Vec<_>>())
        } else {
            (desc.input_index(port), "input", desc.inputs.iter().map(|p| p.name.as_str()).collect::<Vec<_>>())
        };
        if found.is_none() {
            diags.push(diag(
                DiagnosticKind::UnknownPort,
                Location::Port { node: node.to_string(), port: port.to_string() },
                format!(
                    "'{}' has no {side} '{port}' (its {side}s: {}) — in edge {from} -> {to}",
                    desc.type_name,
                    names.join(", ")
                ),
            ));
        }
        found.map(|i| (idx, i))
    };
    let src = endpoint(from, true);
    let dst = endpoint(to, false);
    Some((src?, dst?))
}

/// Reports every cycle, naming its nodes; returns whether the graph is acyclic.
fn check_cycles(g: &StableDiGraph<GraphNode, (usize, usize)>, diags: &mut Vec<Diagnostic>) -> bool {
    let mut acyclic = true;
    for scc in tarjan_scc(g) {
        let self_loop = scc.len() == 1 && g.contains_edge(scc[0], scc[0]);
        if scc.len() > 1 || self_loop {
            acyclic = false;
            let mut names: Vec<&str> = scc.iter().map(|i| &*g[*i].id).collect();
            names.sort_unstable();
            let first = names[0].to_string();
            diags.push(diag(
                DiagnosticKind::Cycle,
                Location::Node(first),
                format!(
                    "cycle through nodes {}: a graph must not feed a node's output back into itself",
                    names.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
    }
    acyclic
}

/// Checks each edge's types in topological order, deciding lifting as it goes.
fn type_check(g: &mut StableDiGraph<GraphNode, (usize, usize)>, order: &[NodeIndex], diags: &mut Vec<Diagnostic>) {
    for &idx in order {
        let mut lifted = false;
        let incoming: Vec<(NodeIndex, usize, usize)> =
            g.edges_directed(idx, petgraph::Direction::Incoming).map(|e| (e.source(), e.weight().0, e.weight().1)).collect();
        for (src, out_port, in_port) in incoming {
            let have = g[src].out_types[out_port].clone();
            let node = &g[idx];
            let desc = node.node.desc();
            let want = &desc.inputs[in_port].ty;
            if &have == want {
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
            diags.push(diag(
                DiagnosticKind::TypeMismatch,
                Location::Port { node: node.id.to_string(), port: desc.inputs[in_port].name.clone() },
                format!(
                    "type mismatch: needs {want}, got {have} from '{}.{}'{hint}",
                    g[src].id,
                    g[src].node.desc().outputs[out_port].name
                ),
            ));
        }
        let node = &mut g[idx];
        node.lifted = lifted;
        if lifted {
            node.out_types = node.node.desc().outputs.iter().map(|p| PortType::clip_of(p.ty.clone())).collect();
        }
    }
}

fn check_missing_inputs(
    g: &StableDiGraph<GraphNode, (usize, usize)>,
    fed: &HashSet<(NodeIndex, usize)>,
    diags: &mut Vec<Diagnostic>,
) {
    for idx in g.node_indices() {
        let node = &g[idx];
        for (i, (src, port)) in node.inputs.iter().zip(&node.node.desc().inputs).enumerate() {
            if matches!(src, InputSource::Missing) && !fed.contains(&(idx, i)) {
                let how =
                    if port.ty.is_parameter() { "set it in params or connect a node" } else { "connect a node's output to it" };
                diags.push(diag(
                    DiagnosticKind::MissingInput,
                    Location::Port { node: node.id.to_string(), port: port.name.clone() },
                    format!("required input '{}' ({}) is not set: {how}", port.name, port.ty),
                ));
            }
        }
    }
}

fn resolve_interface(
    iface: &crate::document::InterfaceDoc,
    g: &StableDiGraph<GraphNode, (usize, usize)>,
    ids: &HashMap<Arc<str>, NodeIndex>,
    diags: &mut Vec<Diagnostic>,
) -> Option<Interface> {
    let mut out = Interface::default();
    let mut ok = true;
    let mut resolve = |name: &str, target: &str, output: bool, list: &mut Vec<(String, NodeIndex, usize)>| {
        let found = split_endpoint(target).and_then(|(n, p)| {
            let idx = *ids.get(n)?;
            let desc = g[idx].node.desc();
            let port = if output { desc.output_index(p) } else { desc.input_index(p) }?;
            Some((idx, port))
        });
        match found {
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
