//! The on-disk graph document (RON, versioned), its migrations, and atomic saving.
//!
//! The document is its own set of plain structs, separate from the runtime graph: it keeps node
//! order, string ids and parameters exactly as the author wrote them, so files diff and review well.
//! Older shapes load through explicit migration functions ([`migrate_v0`], [`migrate_v1`],
//! [`migrate_v2`], [`migrate_v3`], [`migrate_v4`], [`migrate_v5`]), never serde aliases. A document is written in
//! the oldest version that can hold it, so a graph without groups, comments, preset metadata,
//! animated parameters or bypassed nodes stays readable by releases that know only version 1.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Diagnostic, DiagnosticKind, Diagnostics, Location};

pub(crate) mod node_count;
mod param_serde;

/// The newest version this build reads and writes (2: canvas groups and comments; 3: preset
/// metadata; 4: animated parameters, `keys(…)` and `expr(…)`; 5: bypassed nodes, `bypass: true`;
/// 6: local subgraphs, `subgraphs: {…}`).
pub const CURRENT_VERSION: u32 = 6;

/// The version of documents with local subgraphs (an include's graph kept in the file).
pub const SUBGRAPH_VERSION: u32 = 6;

/// The version of documents with a bypassed node.
pub const BYPASS_VERSION: u32 = 5;

/// The version of documents with animated parameters (keyframes or expressions).
pub const ANIMATION_VERSION: u32 = 4;

/// The version of documents with canvas groups or comments and no preset metadata.
pub const CANVAS_VERSION: u32 = 2;

/// The version of documents with preset metadata.
pub const PRESET_VERSION: u32 = 3;

/// The version of documents without groups or comments (what older releases read).
pub const PLAIN_VERSION: u32 = 1;

/// A parameter value as written in a graph file; converted to a typed value against the port.
///
/// Besides literals, a value may be a *form*, `name(argument)`: `keys([(0, 0.2), (40, 1.5, ease)])`
/// (a keyframed channel), `expr("0.5 + 0.2 * sin(time)")` (an expression) and, inside a key,
/// `tangent(in, out)`. RON reads `name(x)` as the one-entry map `{"name": x}` (and `name(x, y)` as
/// `{"name": [x, y]}`), which is how forms are recognised; the `anim` module gives them meaning.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// `true` / `false`.
    Bool(bool),
    /// An integer literal.
    Int(i64),
    /// A float literal.
    Float(f64),
    /// A string (also paths, enum options and `#rrggbb` colours).
    String(String),
    /// A tuple or list (`(1.0, 0.5, 0.2)` for colours and vectors).
    List(Vec<ParamValue>),
    /// A form `name(argument)`: `keys(…)`, `expr(…)`, `tangent(…)`; several arguments arrive as
    /// one list.
    Call(String, Box<ParamValue>),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Bool(v) => write!(f, "{v}"),
            ParamValue::Int(v) => write!(f, "{v}"),
            ParamValue::Float(v) => write!(f, "{v:?}"),
            ParamValue::String(v) => write!(f, "{v:?}"),
            ParamValue::List(items) => {
                write!(f, "(")?;
                for (i, v) in items.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{v}")?;
                }
                write!(f, ")")
            }
            // A form reads as it is written in a file: `keys([(0, 0.2), (40, 1.5, ease)])`.
            ParamValue::Call(name, arg) => match ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::new().depth_limit(0)) {
                Ok(text) => f.write_str(&text),
                Err(_) => write!(f, "{name}({arg})"),
            },
        }
    }
}

impl ParamValue {
    /// Parses a value as typed on a command line (`0.5`, `"a b"`, `(1, 0, 0)`,
    /// `keys([(0, 1), (40, 2)])`); text that is not RON becomes a string, so
    /// `--set load.path=frames/a.png` needs no quotes. `expr(…)` takes the text between its
    /// parentheses as the expression, quoted or not (`--set 'wind.noise_c=expr(0.02 * sin(time))'`).
    pub fn parse_cli(text: &str) -> ParamValue {
        let trimmed = text.trim();
        if let Some(inner) = trimmed.strip_prefix("expr(").and_then(|t| t.strip_suffix(')')) {
            let quoted = ron::from_str::<String>(inner.trim()).ok();
            let expression = quoted.unwrap_or_else(|| inner.trim().to_string());
            return ParamValue::Call("expr".into(), Box::new(ParamValue::String(expression)));
        }
        ron::from_str::<ParamValue>(text).unwrap_or_else(|_| ParamValue::String(text.to_string()))
    }

    /// The arguments of `keys(…)` when there are several: the key list and what follows it. RON
    /// reads `keys([k, …])` as the key list itself (`None` here) and `keys([k, …], cycle)` as
    /// `[[k, …], cycle]`, which the first item (a list of lists) tells apart.
    pub fn key_args(items: &[ParamValue]) -> Option<(&[ParamValue], &[ParamValue])> {
        match items.first() {
            Some(ParamValue::List(list)) if list.iter().all(|k| matches!(k, ParamValue::List(_))) => Some((list, &items[1..])),
            _ => None,
        }
    }

    /// Whether the value is, or holds, a form (an animated parameter). `face(…)`, a place in a
    /// point list, is a form that does not animate.
    pub fn is_animated(&self) -> bool {
        match self {
            ParamValue::Call(name, _) => name != "face",
            ParamValue::List(items) => items.iter().any(ParamValue::is_animated),
            _ => false,
        }
    }
}

/// One node in a document.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodeDoc {
    /// The registered node type (`imaging.to_gray`) or `graph.include`.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Parameters by port name; ports not listed keep their defaults.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, ParamValue>,
    /// Editor position, when the graph was laid out by hand.
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub pos: Option<(f32, f32)>,
    /// Bypassed (version 5): each output passes the node's first input of its type through,
    /// and a writer writes nothing.
    #[serde(default, skip_serializing_if = "is_false")]
    pub bypass: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl NodeDoc {
    /// A node of `type_name` with default parameters.
    pub fn new(type_name: &str) -> Self {
        NodeDoc { type_name: type_name.to_string(), params: BTreeMap::new(), pos: None, bypass: false }
    }

    /// Sets one parameter.
    pub fn param(mut self, name: &str, value: ParamValue) -> Self {
        self.params.insert(name.to_string(), value);
        self
    }
}

/// Nodes in file order. Deserialized by hand so that a duplicated id is reported, not silently
/// dropped as a map would do.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeList(pub Vec<(String, NodeDoc)>);

impl Serialize for NodeList {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (id, node) in &self.0 {
            map.serialize_entry(id, node)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for NodeList {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NodeList;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map from node id to node")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NodeList, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = map.next_entry::<String, NodeDoc>()? {
                    out.push((k, v));
                }
                Ok(NodeList(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// What a graph file exposes when it is used as one node through `graph.include`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InterfaceDoc {
    /// Input name → the inner input port it feeds (`"blur.image"`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, String>,
    /// Output name → the inner output port it reads (`"gray.image"`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub outputs: BTreeMap<String, String>,
    /// Exposed parameter name → the inner parameter it sets (`"crop.width"`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, String>,
}

impl InterfaceDoc {
    /// Whether nothing is exposed.
    pub fn is_empty(&self) -> bool {
        self.inputs.is_empty() && self.outputs.is_empty() && self.params.is_empty()
    }
}

/// A titled, coloured frame around nodes on the canvas (a Houdini network box, a Nuke backdrop).
/// Its box is computed from its nodes, so it follows them; moving the group moves them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupDoc {
    /// The title shown on the frame's bar.
    pub title: String,
    /// `"#rrggbb"`; the editor's default colour when absent.
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub color: Option<String>,
    /// The ids of the nodes inside, in the order they were grouped.
    #[serde(default)]
    pub nodes: Vec<String>,
}

/// A sticky comment on the canvas: free text at a canvas position.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CommentDoc {
    /// The comment's text (may span lines).
    pub text: String,
    /// Canvas position of the comment's top-left corner.
    pub pos: (f32, f32),
    /// `"#rrggbb"`; the editor's default colour when absent.
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub color: Option<String>,
}

/// What a preset library shows of a preset (version 3): the catalogue's name, text and tags, the
/// preset's own revision, who made it under which licence, its thumbnail, and the inputs it cannot
/// cook without.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PresetDoc {
    /// The name the preset is listed and found by (the file stem when empty).
    #[serde(default)]
    pub name: String,
    /// What the preset makes, in a sentence or two.
    #[serde(default)]
    pub description: String,
    /// Search tags, e.g. `["fire", "candle", "footage"]`.
    #[serde(default)]
    pub tags: Vec<String>,
    /// The preset's own revision, raised when its exposed ports or look change.
    #[serde(default)]
    pub revision: u32,
    /// Author or studio.
    #[serde(default)]
    pub author: String,
    /// Licence of the preset file.
    #[serde(default)]
    pub licence: String,
    /// Thumbnail image, relative to the preset file.
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub thumbnail: Option<String>,
    /// Interface inputs that must be connected (footage, a mesh, ...).
    #[serde(default)]
    pub requires: Vec<String>,
    /// An example source for each required input, for thumbnails and tests: input name → a graph
    /// file (its first output is fed in) or an image, a video or a folder of frames; relative to
    /// the preset file, `${VAR}` allowed.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub samples: BTreeMap<String, String>,
    /// The output thumbnails and `pyrograph preset` show (default: `clip`, `image` or `sheet`,
    /// else the first picture output).
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub preview: Option<String>,
    /// The frame of the preview clip thumbnails show (default: the middle one).
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub thumbnail_frame: Option<u32>,
    /// Node types from Python plugins the preset uses (`["studio.heat_haze"]`): a graph that
    /// includes it without those plugins is told which are missing.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plugins: Vec<String>,
}

/// A graph document, version 4 (version 1 plus canvas groups and comments, then preset metadata,
/// then animated parameters).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraphDoc {
    /// Always [`CURRENT_VERSION`] after loading.
    pub version: u32,
    /// Optional one-line description.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// For preset files: what the graph exposes as a node.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interface: Option<InterfaceDoc>,
    /// For preset files: catalogue metadata (version 3).
    #[serde(default, skip_serializing_if = "Option::is_none", serialize_with = "bare_some")]
    pub preset: Option<PresetDoc>,
    /// Nodes by readable id, in file order.
    pub nodes: NodeList,
    /// Edges as `("from_node.output", "to_node.input")`.
    #[serde(default)]
    pub edges: Vec<(String, String)>,
    /// Canvas groups (version 2).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<GroupDoc>,
    /// Canvas comments (version 2).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub comments: Vec<CommentDoc>,
    /// Local subgraphs (version 6), by the id of the `graph.include` node that uses each: that
    /// node cooks this graph instead of reading its `path`, which then only says what the copy
    /// was made from (Houdini's unlocked asset, Nuke's group). Relative paths inside resolve
    /// against this document's folder.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub subgraphs: BTreeMap<String, GraphDoc>,
}

impl Default for GraphDoc {
    fn default() -> Self {
        GraphDoc {
            version: CURRENT_VERSION,
            description: None,
            interface: None,
            preset: None,
            nodes: NodeList::default(),
            edges: Vec::new(),
            groups: Vec::new(),
            comments: Vec::new(),
            subgraphs: BTreeMap::new(),
        }
    }
}

impl GraphDoc {
    /// An empty document.
    pub fn new() -> Self {
        GraphDoc::default()
    }

    /// Adds (or replaces) a node.
    pub fn add_node(&mut self, id: &str, node: NodeDoc) -> &mut Self {
        match self.nodes.0.iter_mut().find(|(k, _)| k == id) {
            Some(slot) => slot.1 = node,
            None => self.nodes.0.push((id.to_string(), node)),
        }
        self
    }

    /// Adds an edge `from` (`node.output`) → `to` (`node.input`).
    pub fn connect(&mut self, from: &str, to: &str) -> &mut Self {
        self.edges.push((from.to_string(), to.to_string()));
        self
    }

    /// The node with id `id`.
    pub fn node(&self, id: &str) -> Option<&NodeDoc> {
        self.nodes.0.iter().find(|(k, _)| k == id).map(|(_, n)| n)
    }

    /// The node with id `id`, mutably.
    pub fn node_mut(&mut self, id: &str) -> Option<&mut NodeDoc> {
        self.nodes.0.iter_mut().find(|(k, _)| k == id).map(|(_, n)| n)
    }

    /// Sets `node.param = value`; an error names a missing node.
    pub fn set_param(&mut self, node: &str, param: &str, value: ParamValue) -> Result<(), String> {
        let n = self.node_mut(node).ok_or_else(|| format!("no node '{node}' in the graph"))?;
        n.params.insert(param.to_string(), value);
        Ok(())
    }

    /// Parses a document from RON text, migrating older versions.
    pub fn from_ron(text: &str) -> Result<GraphDoc, Diagnostics> {
        node_count::check_text(text.as_bytes())?;
        GraphDoc::parse_versioned(text).and_then(local_versions)
    }

    fn parse_versioned(text: &str) -> Result<GraphDoc, Diagnostics> {
        let probe: VersionProbe = ron_options().from_str(text).map_err(syntax_error)?;
        match probe.version {
            0 => {
                let old: v0::GraphDocV0 = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v0(old))
            }
            1 => {
                let old: GraphDoc = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v1(old))
            }
            2 => {
                let old: GraphDoc = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v2(old))
            }
            3 => {
                let old: GraphDoc = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v3(old))
            }
            4 => {
                let old: GraphDoc = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v4(old))
            }
            5 => {
                let old: GraphDoc = ron_options().from_str(text).map_err(syntax_error)?;
                Ok(migrate_v5(old))
            }
            6 => ron_options().from_str(text).map_err(syntax_error),
            v => Err(too_new(v, "graph")),
        }
    }

    /// Reads and parses a graph file.
    pub fn load(path: &Path) -> Result<GraphDoc, Diagnostics> {
        // A file of too many nodes is refused before it is read whole.
        node_count::check_file(path)?;
        let text = std::fs::read_to_string(path).map_err(|e| {
            Diagnostics::one(Diagnostic::new(DiagnosticKind::Io, Location::File, format!("cannot read graph: {e}"))).in_file(path)
        })?;
        GraphDoc::from_ron(&text).map_err(|d| d.in_file(path))
    }

    /// The oldest version that holds this document: 6 with a local subgraph, 5 with a bypassed
    /// node, 4 with animated parameters, 3 with preset metadata, else 2 with groups or comments,
    /// else 1.
    pub fn needed_version(&self) -> u32 {
        if !self.subgraphs.is_empty() {
            SUBGRAPH_VERSION
        } else if self.nodes.0.iter().any(|(_, n)| n.bypass) {
            BYPASS_VERSION
        } else if self.nodes.0.iter().any(|(_, n)| n.params.values().any(ParamValue::is_animated)) {
            ANIMATION_VERSION
        } else if self.preset.is_some() {
            PRESET_VERSION
        } else if self.groups.is_empty() && self.comments.is_empty() {
            PLAIN_VERSION
        } else {
            CANVAS_VERSION
        }
    }

    /// The document as pretty RON, in the oldest version that holds it ([`GraphDoc::needed_version`]).
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::new().depth_limit(4).indentor("    ").struct_names(false);
        let mut doc = std::borrow::Cow::Borrowed(self);
        if self.version != self.needed_version() {
            doc.to_mut().version = self.needed_version();
        }
        // Each local subgraph says its own version too, so it can be copied out to a file as is.
        // Walked with a stack: nesting is as deep as the file's includes of includes.
        if doc.subgraphs.values().any(|g| g.version != g.needed_version() || !g.subgraphs.is_empty()) {
            let mut stack: Vec<&mut GraphDoc> = doc.to_mut().subgraphs.values_mut().collect();
            while let Some(g) = stack.pop() {
                g.version = g.needed_version();
                stack.extend(g.subgraphs.values_mut());
            }
        }
        // Serializing plain structs, maps and strings cannot fail.
        ron::ser::to_string_pretty(&*doc, config).unwrap_or_default() + "\n"
    }

    /// Removes node `id` from every group (after the node was deleted); empty groups stay, as
    /// an artist's empty network box does.
    pub fn ungroup_node(&mut self, id: &str) {
        for g in &mut self.groups {
            g.nodes.retain(|n| n != id);
        }
    }

    /// Writes the document atomically (temp file + rename). Refuses to replace an existing file
    /// unless `overwrite` is set.
    pub fn save(&self, path: &Path, overwrite: bool) -> std::io::Result<()> {
        write_atomic(path, self.to_ron().as_bytes(), overwrite)
    }
}

/// `what` is "graph" or "local subgraph 'x'".
fn too_new(v: u32, what: &str) -> Diagnostics {
    Diagnostics::one(Diagnostic::new(
        DiagnosticKind::Version,
        Location::File,
        format!("{what} version {v} is newer than this pyrograph understands (up to {CURRENT_VERSION}); upgrade pyrograph"),
    ))
}

/// Local subgraphs are read in their own versions (each no newer than its document's) and are
/// [`CURRENT_VERSION`] in memory, as the document is. Walked with a stack: nesting is as deep as
/// the file's includes of includes.
fn local_versions(mut doc: GraphDoc) -> Result<GraphDoc, Diagnostics> {
    let mut stack: Vec<(String, &mut GraphDoc)> = doc.subgraphs.iter_mut().map(|(k, g)| (k.clone(), g)).collect();
    while let Some((name, g)) = stack.pop() {
        if g.version > CURRENT_VERSION {
            return Err(too_new(g.version, &format!("local subgraph '{name}':")));
        }
        g.version = CURRENT_VERSION;
        stack.extend(g.subgraphs.iter_mut().map(|(k, g)| (format!("{name}/{k}"), g)));
    }
    Ok(doc)
}

/// Writes `Some(x)` as plain `x`, matching how authors write optional fields.
fn bare_some<S: Serializer, T: Serialize>(v: &Option<T>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(x) => x.serialize(s),
        None => s.serialize_none(),
    }
}

/// RON options for reading: optional fields may be written bare (`pos: (1, 2)`, not `Some(..)`).
fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

#[derive(Deserialize)]
struct VersionProbe {
    /// 0 when absent: the unversioned pre-release shape.
    #[serde(default)]
    version: u32,
}

fn syntax_error(e: ron::error::SpannedError) -> Diagnostics {
    let location = Location::Text { line: e.span.start.line, column: e.span.start.col };
    let message = match e.code {
        // RON's own words name its options and a stack overflow it just prevented.
        ron::Error::ExceededRecursionLimit => {
            "brackets nested too deep (a graph's values nest a few levels; this nests over 128)".to_string()
        }
        code => in_user_terms(code.to_string()),
    };
    Diagnostics::one(Diagnostic::new(DiagnosticKind::Syntax, location, format!("malformed graph: {message}")))
}

/// The reader's message with the document's internal type names (which RON quotes: "Expected
/// opening `(` for struct `VersionProbe`") replaced by what the file should hold there.
fn in_user_terms(message: String) -> String {
    const TERMS: &[(&str, &str)] = &[
        ("VersionProbe", "a graph, (version: 4, nodes: {...}, edges: [...])"),
        ("GraphDocV0", "a graph, (version: 4, nodes: {...}, edges: [...])"),
        ("GraphDoc", "a graph, (version: 4, nodes: {...}, edges: [...])"),
        ("NodeV0", "a node, (type: \"...\", params: {...})"),
        ("NodeDoc", "a node, (type: \"...\", params: {...})"),
        ("NodeList", "the nodes, {\"id\": (type: \"...\"), ...}"),
        ("LinkV0", "a link"),
        ("InterfaceDoc", "the interface"),
        ("GroupDoc", "a group, (title: \"...\", nodes: [...])"),
        ("CommentDoc", "a comment, (text: \"...\", pos: (x, y))"),
        ("PresetDoc", "the preset's metadata"),
    ];
    TERMS.iter().fold(message, |m, (name, term)| m.replace(&format!("struct `{name}`"), term).replace(&format!("`{name}`"), term))
}

/// The pre-release (unversioned) document shape, kept so old files still open.
pub mod v0 {
    use std::collections::BTreeMap;

    use serde::Deserialize;

    use super::ParamValue;

    /// A node in the old shape: ids inside the node, `kind` and `settings`, flat `x`/`y`.
    #[derive(Deserialize)]
    pub struct NodeV0 {
        /// Node id.
        pub id: String,
        /// Node type.
        pub kind: String,
        /// Parameters.
        #[serde(default)]
        pub settings: BTreeMap<String, ParamValue>,
        /// Editor x.
        #[serde(default)]
        pub x: Option<f32>,
        /// Editor y.
        #[serde(default)]
        pub y: Option<f32>,
    }

    /// A link in the old shape.
    #[derive(Deserialize)]
    pub struct LinkV0 {
        /// `node.port` source.
        pub from: String,
        /// `node.port` destination.
        pub to: String,
    }

    /// The whole old document: a node list and a link list, no version field.
    #[derive(Deserialize)]
    pub struct GraphDocV0 {
        /// Nodes in order.
        pub nodes: Vec<NodeV0>,
        /// Links in order.
        #[serde(default)]
        pub links: Vec<LinkV0>,
    }
}

/// Migrates the unversioned pre-release shape to version 1.
pub fn migrate_v0(old: v0::GraphDocV0) -> GraphDoc {
    let nodes = old
        .nodes
        .into_iter()
        .map(|n| {
            let pos = n.x.zip(n.y);
            (n.id, NodeDoc { type_name: n.kind, params: n.settings, pos, bypass: false })
        })
        .collect();
    let edges = old.links.into_iter().map(|l| (l.from, l.to)).collect();
    GraphDoc { nodes: NodeList(nodes), edges, ..GraphDoc::default() }
}

/// Migrates version 1 to the current version: the shape is the same, version 2 only adds the
/// optional `groups` and `comments` and version 3 the optional `preset`, so the migration is the
/// version number.
pub fn migrate_v1(mut old: GraphDoc) -> GraphDoc {
    old.version = CURRENT_VERSION;
    old
}

/// Migrates version 2 to version 3: version 3 only adds the optional `preset` metadata.
pub fn migrate_v2(mut old: GraphDoc) -> GraphDoc {
    old.version = CURRENT_VERSION;
    old
}

/// Migrates version 3 to version 4: version 4 only adds animated parameter values (`keys(…)`,
/// `expr(…)`), which no version 3 file holds.
pub fn migrate_v3(mut old: GraphDoc) -> GraphDoc {
    old.version = CURRENT_VERSION;
    old
}

/// Migrates version 4 to version 5: version 5 only adds the optional `bypass` flag of a node.
pub fn migrate_v4(mut old: GraphDoc) -> GraphDoc {
    old.version = CURRENT_VERSION;
    old
}

/// Migrates version 5 to version 6: version 6 only adds the optional `subgraphs` table.
pub fn migrate_v5(mut old: GraphDoc) -> GraphDoc {
    old.version = CURRENT_VERSION;
    old
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so readers
/// never see a half-written file: a full disk or any other failure leaves no file under the
/// final name and no temporary behind. With `overwrite` false an existing file is an error (and
/// one appearing meanwhile is not replaced).
///
/// The temporary is made by `tempfile`: a random name opened with `O_EXCL`, so it cannot follow
/// a link planted under a predictable name, and writers on several threads never share one.
pub fn write_atomic(path: &Path, bytes: &[u8], overwrite: bool) -> std::io::Result<()> {
    use std::io::Write;
    let exists = || {
        std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("{} exists; refusing to overwrite it (ask for overwrite to replace it)", path.display()),
        )
    };
    if !overwrite && path.exists() {
        return Err(exists());
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let prefix = format!(".{name}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // tempfile makes its files private (0600); a frame or a graph is shared like any file the
    // user writes: 0666 less the umask, as `File::create` gives.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir)?;
    // Through the plain file: `NamedTempFile`'s own writes add the temporary's name to errors.
    tmp.as_file_mut().write_all(bytes)?;
    tmp.as_file().sync_all()?;
    let persisted = if overwrite { tmp.persist(path) } else { tmp.persist_noclobber(path) };
    persisted.map(drop).map_err(|e| if e.error.kind() == std::io::ErrorKind::AlreadyExists { exists() } else { e.error })
}

/// Parses `node.port` into its two halves.
pub fn split_endpoint(text: &str) -> Option<(&str, &str)> {
    let (node, port) = text.rsplit_once('.')?;
    (!node.is_empty() && !port.is_empty()).then_some((node, port))
}

#[cfg(test)]
mod tests;
