//! The runtime graph: a petgraph DAG built from a document, validated all at once.
//!
//! Included graph files are flattened while building, as Graphite flattens nested networks: the
//! nodes of an include `fire` join the graph as `fire/<inner id>`, edges to and from the include's
//! ports are rewired to the inner ports they expose, and `fire` itself remains only as an
//! [`Included`] record (its description and port map), so there is one graph and one evaluator.

mod build;
mod bypass;
mod convert;
mod include;
mod include_limit;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use petgraph::stable_graph::{NodeIndex, StableDiGraph};

use crate::document::GraphDoc;
use crate::error::Diagnostics;
use crate::node::{Node, NodeDesc, TimeDep};
use crate::registry::Registry;
use crate::value::{PortType, Value};

pub(crate) use build::build;
pub use convert::{expand_vars, parse_hex_color, value_to_param};
pub use include::{local_desc, preset_desc};

/// Separates an include's id from the ids of the nodes it brought in (`fire/noise`).
pub const PATH_SEP: char = '/';

/// Options that change how a document's paths resolve.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Where relative output paths go (`--out`); the graph file's folder when `None`.
    pub output_dir: Option<PathBuf>,
    /// Let writers' paths leave the output folder (`--allow-outside-out`). Off, a writer path
    /// that is absolute or climbs out with `..` is refused when the graph loads, so a preset
    /// from a library cannot write anywhere on a farm node.
    pub allow_outside_out: bool,
    /// Build only to describe the graph (a preset's ports for a listing): a path parameter
    /// naming an unset environment variable keeps its text instead of failing, since the
    /// environment it cooks in (a farm's footage folder) need not be this one.
    pub describe_only: bool,
}

/// Where an input's value comes from.
#[derive(Clone, Debug)]
pub enum InputSource {
    /// A constant: the parameter from the file, or the port's default.
    Const(Value),
    /// A required input that is neither set nor connected (only at a graph's interface inputs,
    /// which the including graph sets or connects when it flattens the include; validation
    /// rejects it anywhere else).
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
    /// The document's include nodes, flattened into the graph, by id.
    includes: HashMap<Arc<str>, Included>,
}

/// An include node after flattening: its description and the inner ports its ports stand for.
#[derive(Clone)]
pub struct Included {
    /// The ports the included file exposes.
    pub desc: Arc<NodeDesc>,
    /// Per input of `desc`: the inner node and input port it feeds (`None` for `path`).
    pub inputs: Vec<Option<PortRef>>,
    /// Per output of `desc`: the inner node and output port it reads.
    pub outputs: Vec<PortRef>,
}

/// A node and one of its ports.
pub type PortRef = (NodeIndex, usize);

/// What the loader carries while building a graph and its includes.
#[derive(Clone)]
pub(crate) struct LoadCtx<'a> {
    pub registry: &'a Registry,
    pub dir: PathBuf,
    pub options: &'a BuildOptions,
    /// The folder writers must stay inside: `--out`, else the top graph file's folder.
    pub root: PathBuf,
    /// Canonical paths of the files being included, outermost first (for cycle detection).
    pub include_stack: Vec<PathBuf>,
    /// Whether this builds an included file (checks that depend on how the includer connects
    /// it, such as where animated parameters are sampled, wait for the whole graph).
    pub nested: bool,
    /// How many local subgraphs this build is inside.
    pub local_depth: usize,
    /// The included files built so far in this load, shared by every level.
    pub includes: std::rc::Rc<IncludeCache>,
}

/// Each included file's build, by canonical path: a file included many times (at any depth) is
/// read, parsed and built once per load, and a broken one reported in full once.
#[derive(Default)]
pub(crate) struct IncludeCache {
    pub built: std::cell::RefCell<HashMap<PathBuf, IncludeBuild>>,
}

/// An included file's build and description, or the id of the include whose report has its
/// problems.
pub(crate) type IncludeBuild = Result<std::rc::Rc<(Graph, NodeDesc)>, String>;

impl Graph {
    /// Loads, migrates, validates and type-checks a graph file.
    pub fn load(path: &Path, registry: &Registry, options: &BuildOptions) -> Result<(GraphDoc, Graph), Diagnostics> {
        let doc = GraphDoc::load(path)?;
        let graph = Graph::build_file(&doc, path, registry, options)?;
        Ok((doc, graph))
    }

    /// Builds `doc` as the document of file `path` (perhaps edited since it was read): relative
    /// paths resolve against the file's folder, diagnostics name the file and an include of the
    /// file itself is a cycle.
    pub fn build_file(doc: &GraphDoc, path: &Path, registry: &Registry, options: &BuildOptions) -> Result<Graph, Diagnostics> {
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let stack = vec![std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())];
        let root = options.output_dir.clone().unwrap_or_else(|| dir.clone());
        include_limit::check(doc, &dir).map_err(|d| d.in_file(path))?;
        let ctx = LoadCtx {
            registry,
            dir,
            options,
            include_stack: stack,
            root,
            nested: false,
            local_depth: 0,
            includes: Default::default(),
        };
        let mut graph = build(doc, &ctx).map_err(|d| d.in_file(path))?;
        graph.file = Some(path.to_path_buf());
        Ok(graph)
    }

    /// Validates and type-checks a document whose relative paths resolve against `dir`.
    pub fn build(doc: &GraphDoc, registry: &Registry, dir: &Path, options: &BuildOptions) -> Result<Graph, Diagnostics> {
        let root = options.output_dir.clone().unwrap_or_else(|| dir.to_path_buf());
        include_limit::check(doc, dir)?;
        let ctx = LoadCtx {
            registry,
            dir: dir.to_path_buf(),
            options,
            include_stack: Vec::new(),
            root,
            nested: false,
            local_depth: 0,
            includes: Default::default(),
        };
        build(doc, &ctx)
    }

    /// The node index of id `id` (a node of the graph, or of an included file as `inc/id`; an
    /// include itself has no index: see [`Graph::included`]).
    pub fn index(&self, id: &str) -> Option<NodeIndex> {
        self.ids.get(id).copied()
    }

    /// The include node `id` of the document, flattened.
    pub fn included(&self, id: &str) -> Option<&Included> {
        self.includes.get(id)
    }

    /// Ids of the document's include nodes.
    pub fn include_ids(&self) -> impl Iterator<Item = &Arc<str>> {
        self.includes.keys()
    }

    /// The description of node or include `id`.
    pub fn desc(&self, id: &str) -> Option<&NodeDesc> {
        match self.index(id) {
            Some(i) => Some(self.g[i].node.desc()),
            None => self.includes.get(id).map(|inc| &*inc.desc),
        }
    }

    /// The inner node and output port that output `port` of node or include `id` reads.
    pub fn output_ref(&self, id: &str, port: usize) -> Option<PortRef> {
        match self.index(id) {
            Some(i) => (port < self.g[i].out_types.len()).then_some((i, port)),
            None => self.includes.get(id)?.outputs.get(port).copied(),
        }
    }

    /// The type output `port` of node or include `id` carries after lifting.
    pub fn output_type(&self, id: &str, port: usize) -> Option<&PortType> {
        let (idx, p) = self.output_ref(id, port)?;
        self.g[idx].out_types.get(p)
    }

    /// The nodes to cook for target `id`: the node, or the inner nodes behind an include's outputs.
    pub fn roots(&self, id: &str) -> Option<Vec<NodeIndex>> {
        match self.index(id) {
            Some(i) => Some(vec![i]),
            None => self.includes.get(id).map(|inc| inc.outputs.iter().map(|(i, _)| *i).collect()),
        }
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

    /// Replaces input `port` of node `idx` by a constant (to feed a graph built on its own, as a
    /// test feeds a preset's interface inputs).
    pub fn set_const(&mut self, idx: NodeIndex, port: usize, value: Value) {
        self.g[idx].inputs[port] = InputSource::Const(value);
    }

    /// Upstream nodes of `idx` (the nodes feeding it directly).
    pub fn upstream(&self, idx: NodeIndex) -> impl Iterator<Item = NodeIndex> + '_ {
        self.g.neighbors_directed(idx, petgraph::Direction::Incoming)
    }
}
