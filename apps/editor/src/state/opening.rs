//! Opening a file off the UI thread, and lookups by id that stay fast in big documents.
//!
//! Reading, parsing and validating a graph of 100,000 nodes (or an include bomb, refused by the
//! core's node limit) takes longer than a frame: a loader thread does it while the window keeps
//! drawing, and the editor adopts the result when it arrives ([`Editor::poll_open`]). The
//! document keeps its nodes in file order, a list; [`DocIndex`] maps ids to places in it, rebuilt
//! once per change, so the canvas and the inspector do not scan the list once per node drawn.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use pyrograph_frontend::core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_frontend::core::graph::{expand_vars, local_desc, preset_desc};
use pyrograph_frontend::core::{BuildOptions, Diagnostics, Graph, GraphDoc, NodeDesc, NodeDoc, ParamValue, Registry};

use super::Editor;
use crate::culling::Positions;

/// An open in progress: the file and the loader's answer to come.
pub struct Opening {
    path: PathBuf,
    rx: Receiver<Opened>,
    started: Instant,
}

/// What the loader thread found, and what it prepared so that adopting it costs the window no
/// pass over a big document: the copy kept as saved, the index and where each node is drawn.
struct Opened {
    doc: Result<GraphDoc, Diagnostics>,
    checked: Option<Checked>,
    saved: GraphDoc,
    index: DocIndex,
    positions: Positions,
}

/// A document validated: the graph or its problems, and every node's description.
pub(super) struct Checked {
    pub graph: Result<Graph, Diagnostics>,
    pub descs: HashMap<String, Arc<NodeDesc>>,
}

/// Validates `doc`, whose relative paths resolve against `dir`, and describes its nodes.
/// The editor preference for writers whose paths leave the graph's folder (`--allow-outside-out`
/// on the command line): off unless the user turns it on, for this session only, so a graph or
/// preset from elsewhere cannot write outside its folder because of a choice made last week.
static ALLOW_OUTSIDE_OUT: AtomicBool = AtomicBool::new(false);

/// Whether writers may write outside the graph's folder (the View menu's preference).
pub fn allow_outside_out() -> bool {
    ALLOW_OUTSIDE_OUT.load(Ordering::Relaxed)
}

impl Editor {
    /// Sets the preference for writes outside the graph's folder and validates the graph again
    /// under it.
    pub fn set_allow_outside_out(&mut self, allow: bool) {
        ALLOW_OUTSIDE_OUT.store(allow, Ordering::Relaxed);
        self.revalidate();
    }
}

pub(super) fn check(doc: &GraphDoc, registry: &Registry, dir: &Path) -> Checked {
    let options = BuildOptions { allow_outside_out: allow_outside_out(), ..BuildOptions::default() };
    let graph = Graph::build(doc, registry, dir, &options);
    let descs = resolve_descs(doc, registry, dir, graph.as_ref().ok());
    Checked { graph, descs }
}

/// Every node's description: its type's, or for an include the included file's interface (from
/// the built graph, else read on its own so a graph with problems still shows its pins).
fn resolve_descs(doc: &GraphDoc, registry: &Registry, dir: &Path, graph: Option<&Graph>) -> HashMap<String, Arc<NodeDesc>> {
    let mut by_type: HashMap<&str, Option<Arc<NodeDesc>>> = HashMap::new();
    let mut out = HashMap::with_capacity(doc.nodes.0.len());
    for (id, nd) in &doc.nodes.0 {
        let desc = if nd.type_name == INCLUDE_TYPE {
            include_desc(id, nd, doc.subgraphs.get(id), registry, dir, graph)
        } else {
            // One description per type, shared: a big graph has few types and many nodes.
            by_type
                .entry(&nd.type_name)
                .or_insert_with(|| registry.get(&nd.type_name).map(|n| Arc::new(n.desc().clone())))
                .clone()
        };
        if let Some(d) = desc {
            out.insert(id.clone(), d);
        }
    }
    out
}

fn include_desc(
    id: &str,
    nd: &NodeDoc,
    local: Option<&GraphDoc>,
    registry: &Registry,
    dir: &Path,
    graph: Option<&Graph>,
) -> Option<Arc<NodeDesc>> {
    if let Some(d) = graph.and_then(|g| g.desc(id)) {
        return Some(Arc::new(d.clone()));
    }
    if let Some(local) = local {
        return local_desc(local, registry, dir).ok().map(Arc::new);
    }
    match nd.params.get(INCLUDE_PATH) {
        Some(ParamValue::String(p)) => expand_vars(p).ok().and_then(|p| preset_desc(&dir.join(p), registry).ok()).map(Arc::new),
        _ => None,
    }
}

/// The folder a file's relative paths resolve against, as [`Editor::base_dir`] gives it.
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::env::current_dir().unwrap_or_default(),
    }
}

fn load(path: &Path, registry: &Registry) -> Opened {
    let doc = GraphDoc::load(path);
    let checked = doc.as_ref().ok().map(|doc| check(doc, registry, &folder_of(path)));
    let (saved, index, positions) = match &doc {
        Ok(d) => (d.clone(), DocIndex::build(d, 0), Positions::build(d, 0)),
        Err(_) => (GraphDoc::new(), DocIndex::default(), Positions::default()),
    };
    Opened { doc, checked, saved, index, positions }
}

impl Editor {
    /// Where the current document's nodes are drawn, when the loader prepared it.
    pub fn prepared_positions(&self) -> Option<Arc<Positions>> {
        self.positions.as_ref().filter(|p| p.is_of(self.revision)).cloned()
    }

    /// Starts opening `path` on a loader thread; the window keeps drawing, and
    /// [`Editor::poll_open`] adopts the document when it is read and validated.
    pub fn begin_open(&mut self, path: &Path) {
        self.cooker.cancel();
        self.plugins_for(path.parent());
        let (tx, rx) = std::sync::mpsc::channel();
        let (file, registry) = (path.to_path_buf(), self.registry.clone());
        let spawned = std::thread::Builder::new().name("pyrograph-open".into()).spawn(move || {
            let _ = tx.send(load(&file, &registry));
        });
        if spawned.is_err() {
            // No thread to spare: read it here (the window waits, but the file opens).
            let opened = load(path, &self.registry);
            let _ = self.adopt(path, opened);
            return;
        }
        self.opening = Some(Opening { path: path.to_path_buf(), rx, started: Instant::now() });
        self.set_status(format!("opening {}…", path.display()), false);
    }

    /// The file being opened and for how long, while a loader thread reads it.
    pub fn opening(&self) -> Option<(&Path, Duration)> {
        self.opening.as_ref().map(|o| (o.path.as_path(), o.started.elapsed()))
    }

    /// Adopts the document of an open that has finished: `Some` with its outcome (as
    /// [`Editor::open`] returns it) on the call that adopts it, `None` otherwise.
    pub fn poll_open(&mut self) -> Option<Result<(), String>> {
        let opening = self.opening.as_ref()?;
        let opened = match opening.rx.try_recv() {
            Ok(opened) => opened,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => {
                let path = self.opening.take().map(|o| o.path).unwrap_or_default();
                let msg = format!("cannot open {}: the loader stopped before it finished", path.display());
                self.set_status(msg.clone(), true);
                return Some(Err(msg));
            }
        };
        let path = self.opening.take().map(|o| o.path).unwrap_or_default();
        Some(self.adopt(&path, opened))
    }

    /// Opens a graph file and waits for it. A file that does not parse leaves an empty document
    /// and reports why; a file that parses but does not validate opens with its problems on the
    /// nodes (and the first of them in the status line).
    pub fn open(&mut self, path: &Path) -> Result<(), String> {
        self.begin_open(path);
        // Without a loader thread the file was opened in place.
        let Some(o) = self.opening.take() else { return Ok(()) };
        match o.rx.recv() {
            Ok(opened) => self.adopt(&o.path, opened),
            Err(_) => Err(format!("cannot open {}: the loader stopped before it finished", o.path.display())),
        }
    }

    fn adopt(&mut self, path: &Path, opened: Opened) -> Result<(), String> {
        let (doc, err) = match opened.doc {
            Ok(doc) => (doc, None),
            Err(d) => (GraphDoc::new(), Some(d)),
        };
        // A file that does not parse is not adopted: saving must never overwrite it with nothing.
        self.path = err.is_none().then(|| path.to_path_buf());
        self.saved = opened.saved;
        self.saves += 1;
        self.scope.clear();
        self.doc = doc;
        self.history.clear();
        self.selection.clear();
        self.preview = None;
        self.preview_req = None;
        self.cook_errors.clear();
        self.cook_warnings.clear();
        self.revision += 1;
        self.index = opened.index.at(self.revision);
        self.positions = Some(Arc::new(opened.positions.at(self.revision)));
        // The saved copy is the document as read: not modified, known without comparing them.
        self.dirty.set(Some((self.revision, self.saves, false)));
        match opened.checked {
            Some(checked) => self.apply_validation(checked),
            None => self.revalidate(),
        }
        self.push_recent(path);
        if let Some(d) = err {
            self.validation.diagnostics = d.0.clone();
            self.validation.graph = None;
            let text = d.to_string();
            self.set_status(format!("cannot open {}: {text}", path.display()), true);
            return Err(text);
        }
        match self.validation.diagnostics.first() {
            None => self.set_status(format!("opened {}", path.display()), false),
            Some(first) => {
                let n = self.validation.diagnostics.len();
                let more = if n > 1 { format!(" (and {} more: see the red badges)", n - 1) } else { String::new() };
                self.set_status(
                    format!("opened {} with {n} problem(s): {}: {}{more}", path.display(), first.location, first.message),
                    true,
                )
            }
        }
        Ok(())
    }
}

/// Where each node and each connected input is in the document, as of one revision.
#[derive(Default)]
pub struct DocIndex {
    revision: Option<u64>,
    nodes: HashMap<String, usize>,
    /// `node.port` of an input → the index of the edge that feeds it.
    incoming: HashMap<String, usize>,
}

impl DocIndex {
    /// Indexes `doc` as of `revision`.
    pub fn build(doc: &GraphDoc, revision: u64) -> DocIndex {
        // The first of a duplicated id wins, as the document's own lookup finds it.
        let mut nodes = HashMap::with_capacity(doc.nodes.0.len());
        for (i, (id, _)) in doc.nodes.0.iter().enumerate() {
            nodes.entry(id.clone()).or_insert(i);
        }
        let mut incoming = HashMap::with_capacity(doc.edges.len());
        for (i, (_, to)) in doc.edges.iter().enumerate() {
            incoming.entry(to.clone()).or_insert(i);
        }
        DocIndex { revision: Some(revision), nodes, incoming }
    }

    /// The index, declared to be of `revision` (built on a loader thread before the document
    /// it indexes was adopted).
    fn at(mut self, revision: u64) -> DocIndex {
        self.revision = Some(revision);
        self
    }

    /// Whether the index is of `revision`.
    pub fn is_of(&self, revision: u64) -> bool {
        self.revision == Some(revision)
    }

    /// Node `id` of `doc`, when the index is of `revision` (else by a scan of the list).
    pub fn node<'d>(&self, doc: &'d GraphDoc, revision: u64, id: &str) -> Option<&'d NodeDoc> {
        if self.revision != Some(revision) {
            return doc.node(id);
        }
        let i = *self.nodes.get(id)?;
        doc.nodes.0.get(i).filter(|(k, _)| k == id).map(|(_, n)| n).or_else(|| doc.node(id))
    }

    /// The output feeding input `node.port` of `doc` (by a scan when the index is stale).
    pub fn incoming<'d>(&self, doc: &'d GraphDoc, revision: u64, node: &str, port: &str) -> Option<&'d str> {
        let target = format!("{node}.{port}");
        if self.revision != Some(revision) {
            return doc.edges.iter().find(|(_, b)| *b == target).map(|(a, _)| a.as_str());
        }
        let i = *self.incoming.get(&target)?;
        let scan = || doc.edges.iter().find(|(_, b)| *b == target).map(|(a, _)| a.as_str());
        doc.edges.get(i).filter(|(_, b)| *b == target).map(|(a, _)| a.as_str()).or_else(scan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_index_finds_what_a_scan_finds_and_falls_back_when_stale() {
        let mut doc = GraphDoc::new();
        for i in 0..50 {
            doc.add_node(&format!("n{i}"), NodeDoc::new("math.add"));
            if i > 0 {
                doc.connect(&format!("n{}.value", i - 1), &format!("n{i}.a"));
            }
        }
        let index = DocIndex::build(&doc, 7);
        for i in 0..50 {
            let id = format!("n{i}");
            assert_eq!(index.node(&doc, 7, &id).map(|n| &n.type_name), doc.node(&id).map(|n| &n.type_name));
            let expect = (i > 0).then(|| format!("n{}.value", i - 1));
            assert_eq!(index.incoming(&doc, 7, &id, "a"), expect.as_deref());
            assert_eq!(index.incoming(&doc, 7, &id, "b"), None);
        }
        assert!(index.node(&doc, 7, "missing").is_none());
        // An edit the index has not seen: answers come from the document itself.
        doc.nodes.0.remove(0);
        assert_eq!(index.node(&doc, 8, "n1").map(|n| n.type_name.as_str()), Some("math.add"));
        assert!(index.node(&doc, 8, "n0").is_none());
        assert!(index.node(&doc, 7, "n0").is_none(), "a moved entry is not mistaken for another id");
        assert_eq!(index.node(&doc, 7, "n1").map(|n| n.type_name.as_str()), Some("math.add"));
    }
}
