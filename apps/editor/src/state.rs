//! The editor's logic without any UI: the document and its edits, undo/redo, validation
//! mapped to nodes, the node palette, file handling and cook requests.
//!
//! Everything the UI does goes through [`Editor`] methods, so tests drive the editor directly.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use pyrograph_frontend::core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::graph::preset_desc;
use pyrograph_frontend::core::graph::value_to_param;
use pyrograph_frontend::core::{
    CookSettings, Diagnostic, Graph, GraphDoc, NodeDesc, NodeDoc, ParamValue, PortDesc, Registry, TimeDep,
};

use crate::cook::{CookOutcome, CookRequest, CookStatus, Cooker, Notify, Preview, PreviewRequest};
use crate::history::History;
pub use crate::layout::auto_layout;
use crate::layout::relative_path;

mod checks;
mod collapse;
mod files;
pub mod flow;
mod keyframes;
mod opening;
mod plugins;
mod preset_lib;
mod scope;
mod unpack;
pub mod vector_keys;
pub mod viewers;

pub use checks::{diagnostic_nodes, same_structure};
pub use keyframes::{AnimParam, value_text};
pub use opening::allow_outside_out;
pub use preset_lib::{SelectionPreset, filter_presets};
pub use scope::{Crumb, IncludeSetting, SetBy};

/// A message for the status bar.
#[derive(Clone, Debug)]
pub struct Status {
    /// The text.
    pub text: String,
    /// Whether it reports a problem (shown in red, and as a toast).
    pub error: bool,
    /// When it was set.
    pub at: Instant,
}

/// Validation state of the current document.
#[derive(Clone, Default)]
pub struct Validation {
    /// The built graph, when the document is valid.
    pub graph: Option<Arc<Graph>>,
    /// Every problem found, in the loader's order.
    pub diagnostics: Vec<Diagnostic>,
    /// Problems by node id (node, port and edge locations map to their node).
    pub by_node: BTreeMap<String, Vec<String>>,
}

/// One entry of the node palette.
#[derive(Clone, Debug, PartialEq)]
pub struct PaletteItem {
    /// The node type, or `graph.include` for presets.
    pub type_name: String,
    /// Palette category (`Imaging`, `Preset`, …).
    pub category: String,
    /// One-line summary.
    pub summary: String,
    /// The preset file, for presets.
    pub preset: Option<PathBuf>,
}

fn same_folder(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// The editor session.
pub struct Editor {
    doc: GraphDoc,
    path: Option<PathBuf>,
    saved: GraphDoc,
    registry: Arc<Registry>,
    history: History,
    validation: Validation,
    descs: HashMap<String, Arc<NodeDesc>>,
    revision: u64,
    cooker: Cooker,
    /// The B viewer of an A/B compare.
    compare: viewers::Compare,
    /// Cook errors per node from the latest finished cook.
    cook_errors: BTreeMap<String, String>,
    cook_warnings: BTreeMap<String, Vec<String>>,
    last_outcome: Option<CookOutcome>,
    preview: Option<Preview>,
    preview_req: Option<PreviewRequest>,
    preview_serial: u64,
    selection: Vec<String>,
    status: Option<Status>,
    recent: Vec<PathBuf>,
    recent_file: Option<PathBuf>,
    preset_dirs: Vec<PathBuf>,
    /// Outcomes received since the last call to [`Editor::take_outcomes`] (tests read logs here).
    received: Vec<CookOutcome>,
    /// Keys copied by [`Editor::copy_keys`], frames relative to the first.
    key_clipboard: Vec<crate::keys::KeyDoc>,
    /// Whether preview cooks are requested automatically after edits.
    pub auto_cook: bool,
    /// A file being read and validated on a loader thread.
    opening: Option<opening::Opening>,
    /// Lookups by id into `doc`, as of a revision.
    index: opening::DocIndex,
    /// Where every node is drawn, as the loader prepared it, and the revision it is of.
    positions: Option<Arc<crate::culling::Positions>>,
    /// Whether the document differs from the saved one, as of (revision, saves).
    dirty: std::cell::Cell<Option<(u64, u64, bool)>>,
    /// Saves so far (a save changes what "dirty" compares with, not the revision).
    saves: u64,
    /// The includes stepped into, outermost first; `doc` is then the innermost one's graph.
    scope: Vec<scope::Level>,
    /// Where Python plugin nodes come from, when the session takes them (`registry` then holds
    /// the plugins for the open document's folder).
    plugins: Option<Arc<pyrograph_frontend::plugins::PluginRegistries>>,
}

impl Editor {
    /// A session with an empty document and the given node registry.
    pub fn new(registry: Arc<Registry>) -> Self {
        // The CLI's search path (a studio's PYROGRAPH_PRESET_PATH, then pyrograph's own), after
        // the working folder's graphs/presets; the open graph's presets/ goes first on open.
        let mut preset_dirs = Vec::new();
        if let Ok(cwd) = std::env::current_dir() {
            preset_dirs.push(cwd.join("graphs").join("presets"));
        }
        let env = std::env::var_os(pyrograph_frontend::presets::PRESET_PATH_VAR);
        let builtin = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/presets");
        for d in pyrograph_frontend::presets::search_path(None, env.as_deref(), &builtin) {
            if !preset_dirs.iter().any(|x| same_folder(x, &d)) {
                preset_dirs.push(d);
            }
        }
        let mut ed = Editor {
            doc: GraphDoc::new(),
            path: None,
            saved: GraphDoc::new(),
            registry,
            history: History::new(),
            validation: Validation::default(),
            descs: HashMap::new(),
            revision: 1,
            cooker: Cooker::new(),
            compare: viewers::Compare::default(),
            cook_errors: BTreeMap::new(),
            cook_warnings: BTreeMap::new(),
            last_outcome: None,
            preview: None,
            preview_req: None,
            preview_serial: 0,
            selection: Vec::new(),
            status: None,
            recent: Vec::new(),
            recent_file: None,
            preset_dirs,
            received: Vec::new(),
            key_clipboard: Vec::new(),
            auto_cook: true,
            opening: None,
            index: opening::DocIndex::default(),
            positions: None,
            dirty: std::cell::Cell::new(None),
            saves: 0,
            scope: Vec::new(),
            plugins: None,
        };
        ed.revalidate();
        ed
    }

    /// A session with every node type pyrograph ships.
    pub fn with_default_registry() -> Self {
        Editor::new(Arc::new(pyrograph_frontend::registry()))
    }

    // ----- accessors -----

    /// The current document.
    pub fn doc(&self) -> &GraphDoc {
        &self.doc
    }

    /// The file the document was opened from or saved to.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Whether the document differs from the file.
    pub fn is_dirty(&self) -> bool {
        // Asked every frame (title, status line): compared once per change, since comparing a
        // big document costs milliseconds.
        let key = (self.revision, self.saves);
        match self.dirty.get() {
            Some((r, s, dirty)) if (r, s) == key => dirty,
            _ => {
                let dirty = *self.root_doc() != self.saved;
                self.dirty.set(Some((key.0, key.1, dirty)));
                dirty
            }
        }
    }

    /// The window title: file name, a `*` when dirty.
    pub fn title(&self) -> String {
        let name = self.path.as_ref().and_then(|p| p.file_name()).map_or("untitled".into(), |n| n.to_string_lossy().into_owned());
        format!("{}{name} — pyrograph editor", if self.is_dirty() { "* " } else { "" })
    }

    /// The node registry.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// Changes whenever the document changes (views resync on it).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Validation results.
    pub fn validation(&self) -> &Validation {
        &self.validation
    }

    /// The description of node `id` (for includes: the included file's interface).
    pub fn desc(&self, id: &str) -> Option<&Arc<NodeDesc>> {
        self.descs.get(id)
    }

    /// Every problem attached to node `id`: validation first, then its cook error (control
    /// characters escaped, overlong runs cut, as the status line shows them).
    pub fn node_problems(&self, id: &str) -> Vec<String> {
        let mut v = self.validation.by_node.get(id).cloned().unwrap_or_default();
        if let Some(e) = self.cook_errors.get(&self.runtime_id(id)) {
            v.push(e.clone());
        }
        v.into_iter().map(|p| pyrograph_frontend::core::text::printable(&p).into_owned()).collect()
    }

    /// Warnings node `id` reported when it last cooked (kept while the cache serves it); for a
    /// preset, those of the nodes inside it too, each named.
    pub fn node_warnings(&self, id: &str) -> Vec<String> {
        let id = self.runtime_id(id);
        let inner = format!("{id}/");
        self.cook_warnings
            .iter()
            .filter(|(k, _)| **k == id || k.starts_with(&inner))
            .flat_map(|(k, ws)| {
                let own = *k == id;
                ws.iter().map(move |w| if own { w.clone() } else { format!("{k}: {w}") })
            })
            .collect()
    }

    /// What node `id` of the shown level is called in the cooked graph (`calm/noise` inside
    /// `calm`).
    pub fn runtime_id(&self, id: &str) -> String {
        match self.scope.is_empty() {
            true => id.to_string(),
            false => format!("{}{id}", self.scope_prefix()),
        }
    }

    /// Cook errors of the latest cook by node.
    pub fn cook_errors(&self) -> &BTreeMap<String, String> {
        &self.cook_errors
    }

    /// The latest status message.
    pub fn status(&self) -> Option<&Status> {
        self.status.as_ref()
    }

    /// Sets the status message, its control characters escaped and overlong runs cut (a node id or
    /// path in it comes from the user's file).
    pub fn set_status(&mut self, text: impl Into<String>, error: bool) {
        let text = pyrograph_frontend::core::text::printable(&text.into()).into_owned();
        self.status = Some(Status { text, error, at: Instant::now() });
    }

    /// The selected node ids.
    pub fn selection(&self) -> &[String] {
        &self.selection
    }

    /// The latest preview.
    pub fn preview(&self) -> Option<&Preview> {
        self.preview.as_ref()
    }

    /// Changes whenever a new preview arrives (views re-upload textures on it).
    pub fn preview_serial(&self) -> u64 {
        self.preview_serial
    }

    /// What the preview shows (node, output, frame).
    pub fn preview_request(&self) -> Option<&PreviewRequest> {
        self.preview_req.as_ref()
    }

    /// The latest finished cook.
    pub fn last_outcome(&self) -> Option<&CookOutcome> {
        self.last_outcome.as_ref()
    }

    /// Cook outcomes received since the last call (oldest first).
    pub fn take_outcomes(&mut self) -> Vec<CookOutcome> {
        std::mem::take(&mut self.received)
    }

    /// Whether a cook is queued or running.
    pub fn is_cooking(&self) -> bool {
        self.cooker.is_busy()
    }

    /// Progress of the running cook.
    pub fn cook_status(&self) -> CookStatus {
        self.cooker.status()
    }

    /// Sets the callback the cook worker calls when it has news.
    pub fn set_notify(&self, notify: Notify) {
        self.cooker.set_notify(notify);
    }

    /// Whether undo / redo are possible.
    pub fn can_undo(&self) -> bool {
        self.history.can_undo()
    }

    /// Whether redo is possible.
    pub fn can_redo(&self) -> bool {
        self.history.can_redo()
    }

    /// Folders searched for presets.
    pub fn preset_dirs(&self) -> &[PathBuf] {
        &self.preset_dirs
    }

    /// Adds a folder searched for presets (first).
    pub fn add_preset_dir(&mut self, dir: PathBuf) {
        self.preset_dirs.insert(0, dir);
    }

    /// The folder relative paths resolve against: the file's folder, else the working folder.
    pub fn base_dir(&self) -> PathBuf {
        match self.path.as_ref().and_then(|p| p.parent()) {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => std::env::current_dir().unwrap_or_default(),
        }
    }

    // ----- edits -----

    /// Applies `f` to the document as one undoable edit. Edits with the same `key` coalesce
    /// until [`Editor::seal`]. Returns `f`'s result; an edit that changes nothing records nothing.
    pub fn edit<R>(&mut self, key: Option<&str>, f: impl FnOnce(&mut GraphDoc) -> R) -> R {
        let before = self.doc.clone();
        let r = f(&mut self.doc);
        if self.doc != before {
            // History keeps whole top-level documents, whatever level was edited (a move inside
            // an unedited preset changes none: see `sync_scope`).
            let top = self.scope.first().map(|top| top.parent.clone());
            self.sync_scope();
            match top {
                Some(top) if self.scope.first().is_some_and(|now| now.parent != top) => self.history.record(&top, key),
                Some(_) => {}
                None => self.history.record(&before, key),
            }
            self.after_change(&before);
        }
        r
    }

    /// Ends a coalescing run (a slider drag or typing): the next edit is its own undo step.
    pub fn seal(&mut self) {
        self.history.seal();
    }

    /// Undoes the last edit.
    pub fn undo(&mut self) -> bool {
        let current = self.scope.first().map_or(&self.doc, |top| &top.parent);
        let Some(root) = self.history.undo(current) else { return false };
        let doc = self.set_root(root);
        let before = std::mem::replace(&mut self.doc, doc);
        self.after_change(&before);
        self.set_status("undo", false);
        true
    }

    /// Redoes the last undone edit.
    pub fn redo(&mut self) -> bool {
        let current = self.scope.first().map_or(&self.doc, |top| &top.parent);
        let Some(root) = self.history.redo(current) else { return false };
        let doc = self.set_root(root);
        let before = std::mem::replace(&mut self.doc, doc);
        self.after_change(&before);
        self.set_status("redo", false);
        true
    }

    fn after_change(&mut self, before: &GraphDoc) {
        self.revision += 1;
        self.reindex();
        let (index, doc, revision) = (&self.index, &self.doc, self.revision);
        self.selection.retain(|id| index.node(doc, revision, id).is_some());
        if self.preview_req.as_ref().is_some_and(|p| self.node_doc(&p.node).is_none()) {
            self.preview_req = None;
            self.preview = None;
        }
        if !same_structure(before, &self.doc) {
            self.revalidate();
            if self.auto_cook {
                self.request_preview();
            }
        }
    }

    /// A fresh node id derived from `base` (`blur`, `blur2`, …).
    pub fn unique_id(&self, base: &str) -> String {
        let base: String = base.chars().map(|c| if c.is_alphanumeric() || c == '_' || c == '-' { c } else { '_' }).collect();
        let base = if base.is_empty() { "node".to_string() } else { base };
        if self.doc.node(&base).is_none() {
            return base;
        }
        (2..).map(|i| format!("{base}{i}")).find(|id| self.doc.node(id).is_none()).unwrap_or(base)
    }

    /// Adds a node of `type_name` at `pos`; returns its id.
    pub fn add_node(&mut self, type_name: &str, pos: (f32, f32)) -> Result<String, String> {
        if type_name == INCLUDE_TYPE {
            return Err("add presets with add_preset".into());
        }
        if self.registry.get(type_name).is_none() {
            return Err(format!("unknown node type '{type_name}'"));
        }
        let base = type_name.rsplit('.').next().unwrap_or(type_name);
        let id = self.unique_id(base);
        let mut nd = NodeDoc::new(type_name);
        nd.pos = Some(round_pos(pos));
        self.edit(None, |d| {
            d.add_node(&id, nd);
        });
        self.set_status(format!("added {id} ({type_name})"), false);
        Ok(id)
    }

    /// Adds a `graph.include` node for the preset file `file` at `pos`; returns its id.
    pub fn add_preset(&mut self, file: &Path, pos: (f32, f32)) -> Result<String, String> {
        preset_desc(file, &self.registry).map_err(|d| d.to_string())?;
        let base = self.base_dir();
        let rel = relative_path(file, &base);
        let stem = file.file_stem().map_or("preset".into(), |s| s.to_string_lossy().replace('-', "_"));
        let id = self.unique_id(&stem);
        let mut nd = NodeDoc::new(INCLUDE_TYPE).param(INCLUDE_PATH, ParamValue::String(rel));
        nd.pos = Some(round_pos(pos));
        self.edit(None, |d| {
            d.add_node(&id, nd);
        });
        self.set_status(format!("inserted preset {id}"), false);
        Ok(id)
    }

    /// Removes nodes and every edge touching them.
    pub fn remove_nodes(&mut self, ids: &[String]) {
        let set: HashSet<&str> = ids.iter().map(String::as_str).collect();
        self.edit(None, |d| {
            for id in &set {
                d.ungroup_node(id);
            }
            d.nodes.0.retain(|(id, _)| !set.contains(id.as_str()));
            d.subgraphs.retain(|id, _| !set.contains(id.as_str()));
            d.edges.retain(|(a, b)| {
                let na = split_endpoint(a).map(|x| x.0);
                let nb = split_endpoint(b).map(|x| x.0);
                !na.is_some_and(|n| set.contains(n)) && !nb.is_some_and(|n| set.contains(n))
            });
        });
    }

    /// Copies nodes (with the edges among them), offset a little; returns the new ids.
    pub fn duplicate(&mut self, ids: &[String]) -> Vec<String> {
        let mut mapping: Vec<(String, String)> = Vec::new();
        let mut new_nodes = Vec::new();
        for id in ids {
            let Some(nd) = self.doc.node(id) else { continue };
            let mut copy = nd.clone();
            let taken: HashSet<&str> = mapping.iter().map(|(_, n)| n.as_str()).collect();
            let mut new_id = self.unique_id(&format!("{id}_copy"));
            let mut k = 2;
            while taken.contains(new_id.as_str()) {
                new_id = self.unique_id(&format!("{id}_copy{k}"));
                k += 1;
            }
            copy.pos = copy.pos.map(|(x, y)| (x + 40.0, y + 40.0)).or(Some((40.0, 40.0)));
            mapping.push((id.clone(), new_id.clone()));
            new_nodes.push((new_id, copy));
        }
        let map: HashMap<&str, &str> = mapping.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
        let mut new_edges = Vec::new();
        for (a, b) in &self.doc.edges {
            if let (Some((na, pa)), Some((nb, pb))) = (split_endpoint(a), split_endpoint(b))
                && let (Some(ma), Some(mb)) = (map.get(na), map.get(nb))
            {
                new_edges.push((format!("{ma}.{pa}"), format!("{mb}.{pb}")));
            }
        }
        let out: Vec<String> = new_nodes.iter().map(|(id, _)| id.clone()).collect();
        // A local subgraph goes with its copy: the two are edited apart from then on.
        let locals: Vec<(String, GraphDoc)> =
            mapping.iter().filter_map(|(old, new)| Some((new.clone(), self.doc.subgraphs.get(old)?.clone()))).collect();
        self.edit(None, |d| {
            for (id, nd) in new_nodes {
                d.add_node(&id, nd);
            }
            d.edges.extend(new_edges);
            d.subgraphs.extend(locals);
        });
        out
    }

    /// Moves a node (coalesces with other moves of the same drag).
    pub fn move_node(&mut self, id: &str, pos: (f32, f32)) {
        let pos = round_pos(pos);
        self.edit(Some("move"), |d| {
            if let Some(n) = d.node_mut(id) {
                n.pos = Some(pos);
            }
        });
    }

    /// Sets a parameter (coalesces with further changes of the same parameter until sealed).
    pub fn set_param(&mut self, node: &str, param: &str, value: ParamValue) -> Result<(), String> {
        let key = format!("param:{node}.{param}");
        self.edit(Some(&key), |d| d.set_param(node, param, value))
    }

    /// Removes a parameter from the document so the port's default applies.
    pub fn reset_param(&mut self, node: &str, param: &str) {
        self.edit(None, |d| {
            if let Some(n) = d.node_mut(node) {
                n.params.remove(param);
            }
        });
    }

    /// The edge feeding input `port` of `node`, as `"from.port"`.
    pub fn incoming(&self, node: &str, port: &str) -> Option<&str> {
        self.index.incoming(&self.doc, self.revision, node, port)
    }

    /// Checks whether `from_node.from_port -> to_node.to_port` may be made, with the type checker
    /// of the core; returns the document that would result, or the reason it is refused.
    pub fn check_connect(&self, from_node: &str, from_port: &str, to_node: &str, to_port: &str) -> Result<GraphDoc, String> {
        if from_node == to_node {
            return Err(format!("cannot connect '{from_node}' to itself"));
        }
        let from_desc = self.descs.get(from_node).ok_or_else(|| format!("node '{from_node}' has no known ports"))?;
        let to_desc = self.descs.get(to_node).ok_or_else(|| format!("node '{to_node}' has no known ports"))?;
        if from_desc.output_index(from_port).is_none() {
            return Err(format!("'{from_node}' has no output '{from_port}'"));
        }
        if to_desc.input_index(to_port).is_none() {
            return Err(format!("'{to_node}' has no input '{to_port}'"));
        }
        let from = format!("{from_node}.{from_port}");
        let to = format!("{to_node}.{to_port}");
        let mut cand = self.doc.clone();
        cand.edges.retain(|(_, b)| *b != to);
        cand.edges.push((from.clone(), to.clone()));
        match self.refusal(&cand) {
            Some(why) => Err(format!("cannot connect {from} -> {to}: {why}")),
            None => Ok(cand),
        }
    }

    /// Connects two ports if the type checker accepts it (replacing the input's current edge);
    /// otherwise leaves the document alone, puts the reason in the status bar and returns it.
    pub fn connect(&mut self, from_node: &str, from_port: &str, to_node: &str, to_port: &str) -> Result<(), String> {
        match self.check_connect(from_node, from_port, to_node, to_port) {
            Ok(cand) => {
                self.edit(None, |d| *d = cand);
                self.set_status(format!("connected {from_node}.{from_port} -> {to_node}.{to_port}"), false);
                Ok(())
            }
            Err(reason) => {
                self.set_status(reason.clone(), true);
                Err(reason)
            }
        }
    }

    /// Removes the edge `from -> to` (both `node.port`).
    pub fn disconnect(&mut self, from: &str, to: &str) {
        self.edit(None, |d| d.edges.retain(|(a, b)| !(a == from && b == to)));
    }

    /// Removes every edge into input `node.port`.
    pub fn disconnect_input(&mut self, node: &str, port: &str) {
        let to = format!("{node}.{port}");
        self.edit(None, |d| d.edges.retain(|(_, b)| *b != to));
    }

    /// Removes every edge out of output `node.port`.
    pub fn disconnect_output(&mut self, node: &str, port: &str) {
        let from = format!("{node}.{port}");
        self.edit(None, |d| d.edges.retain(|(a, _)| *a != from));
    }

    /// The current value of a parameter: the document's, else the port's default.
    pub fn param_value(&self, node: &str, port: &PortDesc) -> Option<ParamValue> {
        if let Some(v) = self.doc.node(node).and_then(|n| n.params.get(&port.name)) {
            return Some(v.clone());
        }
        port.default.as_ref().and_then(value_to_param)
    }

    // ----- selection and preview -----

    /// Sets the selection; the inspector and preview follow the current node, the last one.
    pub fn set_selection(&mut self, ids: Vec<String>) {
        if ids == self.selection {
            return;
        }
        self.selection = ids;
        if let Some(current) = self.current().map(str::to_string)
            && self.preview_req.as_ref().is_none_or(|p| p.node != current)
        {
            self.preview_req = Some(PreviewRequest { node: current, output: 0, frame: self.current_frame() });
            if self.auto_cook {
                self.request_preview();
            }
        }
    }

    /// The current node: the one clicked last, whose parameters the inspector shows.
    pub fn current(&self) -> Option<&str> {
        self.selection.last().map(String::as_str)
    }

    /// Selects one node.
    pub fn select(&mut self, id: &str) {
        self.set_selection(vec![id.to_string()]);
    }

    fn current_frame(&self) -> usize {
        self.preview_req.as_ref().map_or(0, |p| p.frame)
    }

    /// Shows output `output` of the previewed node.
    pub fn set_preview_output(&mut self, output: usize) {
        if let Some(p) = &mut self.preview_req
            && p.output != output
        {
            p.output = output;
            self.request_preview();
        }
    }

    /// Shows frame `frame` of a clip preview.
    pub fn set_frame(&mut self, frame: usize) {
        if let Some(p) = &mut self.preview_req
            && p.frame != frame
        {
            p.frame = frame;
            self.follow_with_b(frame);
            self.request_preview();
        }
    }

    /// Queues a cook of the previewed node's cone (never of sinks: they write files).
    pub fn request_preview(&mut self) -> Option<u64> {
        let graph = self.validation.graph.clone()?;
        let req = self.preview_req.clone()?;
        let desc = self.descs.get(&req.node)?;
        if desc.time == TimeDep::Sink {
            self.preview = Some(Preview {
                request: Some(req),
                error: Some("a writer: it runs only when you press Render".into()),
                ..Preview::default()
            });
            return None;
        }
        let output = req.output.min(desc.outputs.len().saturating_sub(1));
        // Inside an include, the top-level graph cooks and its inner node is shown.
        let req = PreviewRequest { output, node: self.runtime_id(&req.node), ..req };
        let compare = self.compare_target().map(|b| PreviewRequest { node: self.runtime_id(&b.node), ..b });
        let targets = std::iter::once(req.node.clone()).chain(compare.iter().map(|b| b.node.clone())).collect();
        Some(self.cooker.submit(CookRequest { graph, targets, preview: Some(req), compare, render: None }))
    }

    /// Cooks the writers (sinks): the render button.
    pub fn render(&mut self) -> Result<u64, String> {
        let graph = self.validation.graph.clone().ok_or("the graph has errors; fix them before rendering")?;
        let sinks: Vec<String> = graph.sinks().iter().map(|s| s.to_string()).collect();
        if sinks.is_empty() {
            return Err("the graph has no writer nodes to render".into());
        }
        self.set_status(format!("rendering {}", sinks.join(", ")), false);
        let render = Some(CookSettings::default());
        Ok(self.cooker.submit(CookRequest { graph, targets: sinks, preview: None, compare: None, render }))
    }

    /// Cancels the running cook.
    pub fn cancel(&mut self) {
        self.cooker.cancel();
        self.set_status("cancelling…", false);
    }

    /// Takes finished cooks from the worker; returns whether anything arrived.
    pub fn poll(&mut self) -> bool {
        let mut any = false;
        while let Some(mut outcome) = self.cooker.poll() {
            any = true;
            let prefix = self.scope_prefix();
            for p in [&mut outcome.preview, &mut outcome.compare].into_iter().flatten() {
                if let Some(r) = &mut p.request
                    && let Some(id) = r.node.strip_prefix(&prefix)
                {
                    r.node = id.to_string();
                }
            }
            self.cook_errors = outcome.node_errors.clone();
            // A node that cooked again says its warnings afresh; one the cache served keeps its own.
            for id in &outcome.log {
                self.cook_warnings.remove(id);
            }
            for (id, w) in &outcome.node_warnings {
                self.cook_warnings.insert(id.clone(), w.clone());
            }
            if let Some(p) = &outcome.preview
                && !(outcome.cancelled && p.image.is_none() && p.contours.is_empty())
            {
                self.preview = Some(p.clone());
                self.preview_serial += 1;
            }
            self.receive_compare(&outcome);
            if outcome.cancelled {
                self.set_status("cook cancelled", false);
            } else if outcome.render {
                match outcome.node_errors.is_empty() {
                    true => self.set_status(format!("render finished in {:.2} s", outcome.elapsed.as_secs_f64()), false),
                    false => self.set_status("render failed: see the node badges", true),
                }
            }
            self.received.push(outcome.clone());
            self.last_outcome = Some(outcome);
        }
        any
    }

    /// Waits (polling) until no cook is queued or running, or `timeout` passes; for tests and
    /// scripts. Returns whether the worker went idle.
    pub fn wait_idle(&mut self, timeout: Duration) -> bool {
        let start = Instant::now();
        loop {
            self.poll();
            if !self.is_cooking() {
                return true;
            }
            if start.elapsed() > timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// Rebuilds the lookups by id, unless they are of the current revision.
    fn reindex(&mut self) {
        if !self.index.is_of(self.revision) {
            self.index = opening::DocIndex::build(&self.doc, self.revision);
        }
    }

    /// Node `id` of the document (found through the index: the document is a list).
    pub fn node_doc(&self, id: &str) -> Option<&NodeDoc> {
        self.index.node(&self.doc, self.revision, id)
    }
}

/// Positions rounded to whole units, so files diff well.
fn round_pos(p: (f32, f32)) -> (f32, f32) {
    (p.0.round(), p.1.round())
}
