//! Stepping into an included graph (Houdini's dive into a subnet or an unlocked asset, Nuke's
//! group tab), with a breadcrumb back out.
//!
//! Inside an include the canvas, the inspector and every edit work on the included graph, while
//! the document, the undo history, saving and cooking stay those of the whole file: each level
//! keeps the document one level up (`parent`), and an edit inside writes the level into its
//! parent's `subgraphs` table, level by level up to the top. An include that reads a preset file
//! becomes a local copy at its first edit (the file is never written: "Save into preset" does
//! that, asked for and confirmed); one already local is edited in place. Undo restores whole
//! top-level documents and the levels are read again from them, so an undo that removes the
//! local copy shows the preset file's graph again, and one that removes the include steps out.
//!
//! Previews inside cook the top-level graph and show the include's inner node (`calm/noise`),
//! so what the canvas shows is what the include feeds the graph around it.

use std::path::{Path, PathBuf};

use pyrograph_frontend::core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_frontend::core::graph::expand_vars;
use pyrograph_frontend::core::{GraphDoc, ParamValue};

use super::Editor;
use crate::cook::PreviewRequest;
use crate::paths::rebase_paths;

/// One level stepped into.
pub(super) struct Level {
    /// The include's id in the level above.
    id: String,
    /// The document one level up, its `subgraphs` in step with the edits made below.
    pub(super) parent: GraphDoc,
    /// The include's file as this level shows it before any edit (paths rebased onto the
    /// document's folder), when it has a file that loads.
    pristine: Option<GraphDoc>,
    /// That file.
    origin: Option<PathBuf>,
    /// The selection and preview one level up, given back on the way out.
    selection: Vec<String>,
    preview: Option<PreviewRequest>,
}

/// How the include one level up sets one of this level's parameters (see
/// [`Editor::set_by_include`]): Houdini shows such a parameter as driven by the asset's.
#[derive(Clone, Debug, PartialEq)]
pub struct IncludeSetting {
    /// The include's id one level up.
    pub include: String,
    /// Its exposed parameter that maps to the inner one.
    pub exposed: String,
    /// What sets that exposed parameter on the include.
    pub by: SetBy,
}

/// What sets an include's exposed parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum SetBy {
    /// A value (or keys, or an expression) in the include's parameters.
    Value(ParamValue),
    /// A connection into the include's parameter port, from this output (`"noise.value"`).
    Connection(String),
}

/// One step of the breadcrumb.
#[derive(Clone, Debug, PartialEq)]
pub struct Crumb {
    /// The include's id in the level above.
    pub id: String,
    /// Whether its graph is a local copy kept in the document (else the preset file, unedited).
    pub local: bool,
    /// The preset file it reads, or was copied from.
    pub origin: Option<PathBuf>,
}

impl Editor {
    /// The includes stepped into, outermost first (empty at the top level).
    pub fn scope(&self) -> Vec<Crumb> {
        let mut out = Vec::with_capacity(self.scope.len());
        for level in &self.scope {
            let local = level.parent.subgraphs.contains_key(&level.id);
            out.push(Crumb { id: level.id.clone(), local, origin: level.origin.clone() });
        }
        out
    }

    /// What the ids of this level are called in the cooked graph: `calm/` inside `calm`.
    pub fn scope_prefix(&self) -> String {
        self.scope.iter().map(|l| format!("{}/", l.id)).collect()
    }

    /// The whole document (what is saved and cooked), whatever level is shown.
    pub fn root_doc(&self) -> &GraphDoc {
        self.scope.first().map_or(&self.doc, |l| &l.parent)
    }

    /// Whether include `id` of this level keeps its graph in the document.
    pub fn is_local(&self, id: &str) -> bool {
        self.doc.subgraphs.contains_key(id)
    }

    /// What overrides parameter `param` of node `id` of this level when the whole graph cooks:
    /// the include one level up, when it sets (or a connection drives) the exposed parameter
    /// that maps to it. Editing the inner value then changes nothing until that is unset.
    pub fn set_by_include(&self, id: &str, param: &str) -> Option<IncludeSetting> {
        let level = self.scope.last()?;
        let target = format!("{id}.{param}");
        let (exposed, _) = self.doc.interface.as_ref()?.params.iter().find(|(_, inner)| **inner == target)?;
        let port = format!("{}.{exposed}", level.id);
        let by = match level.parent.edges.iter().find(|(_, to)| *to == port) {
            Some((from, _)) => SetBy::Connection(from.clone()),
            None => SetBy::Value(level.parent.node(&level.id)?.params.get(exposed)?.clone()),
        };
        Some(IncludeSetting { include: level.id.clone(), exposed: exposed.clone(), by })
    }

    /// Shows the graph of include `id` in place of this level's (its breadcrumb leads back).
    pub fn step_into(&mut self, id: &str) -> Result<(), String> {
        let nd = self.node_doc(id).cloned().ok_or_else(|| format!("no node '{id}' to step into"))?;
        if nd.type_name != INCLUDE_TYPE {
            return Err(format!("'{id}' is a {}, not an included graph: it has no graph inside", nd.type_name));
        }
        let origin = match nd.params.get(INCLUDE_PATH) {
            Some(ParamValue::String(p)) => expand_vars(p).ok().map(|p| self.base_dir().join(p)),
            _ => None,
        };
        let pristine = origin.as_deref().and_then(|f| GraphDoc::load(f).ok()).map(|mut inner| {
            let from = origin.as_deref().and_then(Path::parent).unwrap_or(Path::new("."));
            rebase_paths(&mut inner, &self.registry, from, &self.base_dir());
            inner
        });
        let inner = match (self.doc.subgraphs.get(id), &pristine) {
            (Some(local), _) => local.clone(),
            (None, Some(file)) => file.clone(),
            (None, None) => {
                let why = origin.map_or("it names no graph file".into(), |f| format!("{} does not load", f.display()));
                return Err(format!("cannot step into '{id}': {why}"));
            }
        };
        let parent = std::mem::replace(&mut self.doc, inner);
        let selection = std::mem::take(&mut self.selection);
        let preview = self.preview_req.take();
        self.scope.push(Level { id: id.to_string(), parent, pristine, origin, selection, preview });
        self.after_scope_change();
        self.set_status(format!("inside {id}: {}", self.scope_note(id)), false);
        Ok(())
    }

    fn scope_note(&self, id: &str) -> String {
        let crumb = self.scope().pop();
        match crumb {
            Some(Crumb { local: true, origin: Some(f), .. }) => format!("a local copy of {}", file_name(&f)),
            Some(Crumb { local: true, origin: None, .. }) => "a local subgraph, kept in this file".into(),
            Some(Crumb { origin: Some(f), .. }) => {
                format!("{} (edits make a local copy for this graph; the file stays as it is)", file_name(&f))
            }
            _ => id.to_string(),
        }
    }

    /// Goes one level up; false at the top.
    pub fn step_out(&mut self) -> bool {
        let depth = self.scope.len();
        depth > 0 && self.step_to(depth - 1)
    }

    /// Goes up to `depth` levels inside (0: the top level); false when already there or above.
    pub fn step_to(&mut self, depth: usize) -> bool {
        if depth >= self.scope.len() {
            return false;
        }
        let mut id = String::new();
        while self.scope.len() > depth {
            let Some(level) = self.scope.pop() else { break };
            self.doc = level.parent;
            self.selection = level.selection;
            self.preview_req = level.preview;
            id = level.id;
        }
        self.after_scope_change();
        if self.node_doc(&id).is_some() {
            self.set_selection(vec![id.clone()]);
        }
        self.set_status(if depth == 0 { "top level".to_string() } else { format!("inside {}", self.scope_prefix()) }, false);
        true
    }

    /// Drops include `id`'s local copy: it reads its preset file again (one undo step).
    pub fn revert_local(&mut self, id: &str) -> Result<(), String> {
        let has_file = matches!(self.node_doc(id).and_then(|n| n.params.get(INCLUDE_PATH)), Some(ParamValue::String(_)));
        if !self.is_local(id) {
            return Err(format!("'{id}' has no local copy"));
        }
        if !has_file {
            return Err(format!("'{id}' was made in this graph and has no preset file to go back to; unpack it instead"));
        }
        self.edit(None, |d| d.subgraphs.remove(id));
        self.seal();
        self.set_status(format!("{id} reads its preset file again"), false);
        Ok(())
    }

    /// Writes this level's document into the levels above (after an edit). Moving nodes or
    /// comments inside an include that still reads its preset file only rearranges the view: it
    /// makes no local copy (nothing in the file changes, so the graph is not marked edited and
    /// the moves are not kept), as Houdini asks for an explicit unlock before an asset's
    /// contents change.
    pub(super) fn sync_scope(&mut self) {
        let mut cur = self.doc.clone();
        let mut moved_only = false;
        for (depth, level) in self.scope.iter_mut().rev().enumerate() {
            let local = level.parent.subgraphs.contains_key(&level.id)
                || !level.pristine.as_ref().is_some_and(|p| same_but_layout(p, &cur));
            if !local {
                // Unedited below here: the levels above are unchanged too.
                moved_only = depth == 0 && level.pristine.as_ref() != Some(&cur);
                break;
            }
            level.parent.subgraphs.insert(level.id.clone(), cur);
            cur = level.parent.clone();
        }
        if moved_only {
            self.set_status("moves inside a preset are not kept: edit a value to make a local copy", false);
        }
    }

    /// The graph files besides this one that include preset `file` (searched in this graph's
    /// folder tree and the preset folders, at most a few thousand files): who a change to the
    /// preset reaches.
    pub fn preset_users(&self, file: &Path) -> Vec<PathBuf> {
        let Ok(target) = std::fs::canonicalize(file) else { return Vec::new() };
        let own = self.path.as_ref().and_then(|p| std::fs::canonicalize(p).ok());
        let mut roots = vec![self.base_dir()];
        roots.extend(self.preset_dirs.iter().cloned());
        let mut seen = std::collections::HashSet::new();
        let mut users = Vec::new();
        for root in roots {
            let walk = walkdir::WalkDir::new(root).max_depth(6).into_iter().filter_map(Result::ok).take(5000);
            for entry in walk.filter(|e| e.path().extension().is_some_and(|x| x == "ron")) {
                let Ok(path) = std::fs::canonicalize(entry.path()) else { continue };
                if path == target || own.as_ref() == Some(&path) || !seen.insert(path.clone()) {
                    continue;
                }
                let dir = path.parent().unwrap_or(Path::new("."));
                let includes_it = GraphDoc::load(&path).is_ok_and(|doc| {
                    doc.nodes.0.iter().any(|(id, nd)| {
                        nd.type_name == INCLUDE_TYPE
                            && !doc.subgraphs.contains_key(id)
                            && matches!(nd.params.get(INCLUDE_PATH), Some(ParamValue::String(p))
                                if expand_vars(p).ok().and_then(|p| std::fs::canonicalize(dir.join(p)).ok()).as_ref() == Some(&target))
                    })
                });
                if includes_it {
                    users.push(path);
                }
            }
        }
        users.sort();
        users
    }

    /// Writes include `id`'s local copy over the preset file it was copied from (atomically,
    /// its paths made relative to the preset's folder again) and drops the copy, so the include
    /// reads the file again. The file write cannot be undone; dropping the copy can.
    pub fn save_into_preset(&mut self, id: &str) -> Result<PathBuf, String> {
        let local = self.doc.subgraphs.get(id).cloned().ok_or_else(|| format!("'{id}' has no local copy to save"))?;
        let file = match self.node_doc(id).and_then(|n| n.params.get(INCLUDE_PATH)) {
            Some(ParamValue::String(p)) => self.base_dir().join(expand_vars(p)?),
            _ => return Err(format!("'{id}' was made in this graph: it has no preset file (use Save selection as preset)")),
        };
        let mut out = local;
        rebase_paths(&mut out, &self.registry, &self.base_dir(), file.parent().unwrap_or(Path::new(".")));
        out.save(&file, true).map_err(|e| format!("cannot write {}: {e}", file.display()))?;
        self.edit(None, |d| d.subgraphs.remove(id));
        self.seal();
        self.revalidate();
        self.set_status(format!("saved {id}'s graph into {}", file.display()), false);
        Ok(file)
    }

    /// Takes `root` as the whole document (undo, redo) and reads the levels from it, stepping
    /// out of those whose include is gone; returns the document this level now shows.
    pub(super) fn set_root(&mut self, root: GraphDoc) -> GraphDoc {
        let mut doc = root;
        for i in 0..self.scope.len() {
            let level = &self.scope[i];
            let is_include = doc.node(&level.id).is_some_and(|n| n.type_name == INCLUDE_TYPE);
            let inner = match doc.subgraphs.get(&level.id) {
                Some(local) if is_include => Some(local.clone()),
                _ if is_include => level.pristine.clone(),
                _ => None,
            };
            let Some(inner) = inner else {
                let gone = level.id.clone();
                self.scope.truncate(i);
                self.set_status(format!("stepped out: '{gone}' is no longer an included graph"), false);
                return doc;
            };
            self.scope[i].parent = doc;
            doc = inner;
        }
        doc
    }

    /// After the shown level changed: the views, validation and preview follow.
    fn after_scope_change(&mut self) {
        self.clear_b();
        self.preview = None;
        self.revision += 1;
        self.reindex();
        self.revalidate();
        if self.auto_cook {
            self.request_preview();
        }
    }
}

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Whether two documents differ at most in where their nodes and comments sit on the canvas.
fn same_but_layout(a: &GraphDoc, b: &GraphDoc) -> bool {
    if a == b {
        return true;
    }
    let unplaced = |d: &GraphDoc| {
        let mut d = d.clone();
        d.nodes.0.iter_mut().for_each(|(_, n)| n.pos = None);
        d.comments.iter_mut().for_each(|c| c.pos = (0.0, 0.0));
        d
    };
    unplaced(a) == unplaced(b)
}

#[cfg(test)]
pub(super) mod tests {
    use std::time::Duration;

    use pyrograph_frontend::core::{GraphDoc, ParamValue};

    use super::SetBy;
    use crate::Editor;

    const PRESET: &str = r#"(
    version: 1,
    interface: Some((outputs: {"y": "add.value"}, params: {"offset": "add.b"})),
    nodes: {
        "t": (type: "time.frame", params: {"frames": 4}),
        "add": (type: "math.add", params: {"b": 10.0}),
    },
    edges: [("t.frame", "add.a")],
)
"#;

    const MAIN: &str = r#"(
    version: 1,
    nodes: {
        "p": (type: "graph.include", params: {"path": "presets/p.ron"}, pos: (0, 0)),
        "q": (type: "graph.include", params: {"path": "presets/p.ron"}, pos: (0, 200)),
        "mul": (type: "math.multiply", params: {"b": 2.0}, pos: (300, 0)),
    },
    edges: [("p.y", "mul.a")],
)
"#;

    /// What the preview says of `node` at `frame` once cooked (a number's value).
    pub(in crate::state) fn cooked(ed: &mut Editor, node: &str, frame: usize) -> String {
        ed.select(node);
        ed.set_frame(frame);
        ed.request_preview();
        assert!(ed.wait_idle(Duration::from_secs(20)));
        let p = ed.preview().expect("a preview");
        assert!(p.error.is_none(), "{node}@{frame}: {:?}", p.error);
        p.summary.clone()
    }

    #[test]
    fn an_edit_inside_makes_a_local_copy_the_preset_file_keeps_its_bytes_and_undo_walks_back() {
        let (_dir, main, preset) = project();
        let mut ed = Editor::with_default_registry();
        ed.open(&main).unwrap();
        assert_eq!(cooked(&mut ed, "mul", 3), "26");

        ed.step_into("p").unwrap();
        assert_eq!(ed.scope_prefix(), "p/");
        assert!(ed.doc().node("add").is_some() && ed.doc().node("mul").is_none());
        assert!(!ed.scope()[0].local && !ed.is_dirty(), "looking inside changes nothing");
        // Inside, the preview is the inner node as the graph cooks it.
        assert_eq!(cooked(&mut ed, "add", 3), "13");
        ed.set_param("add", "b", ParamValue::Float(20.0)).unwrap();
        ed.seal();
        assert!(ed.scope()[0].local && ed.is_dirty());
        assert_eq!(cooked(&mut ed, "add", 3), "23");
        assert!(ed.step_out());
        assert_eq!(ed.selection(), ["p"]);
        assert!(ed.is_local("p") && !ed.is_local("q"));
        assert_eq!(cooked(&mut ed, "mul", 3), "46");
        ed.save().unwrap();
        assert_eq!(std::fs::read_to_string(&preset).unwrap(), PRESET, "the preset file is not written");

        let mut again = Editor::with_default_registry();
        again.open(&main).unwrap();
        assert_eq!(cooked(&mut again, "mul", 3), "46", "the local copy was saved in the graph");
        assert_eq!(cooked(&mut again, "q", 3), "13", "the other include still reads the file");

        // Undo inside: back to the file's graph; undo past the include's local copy from outside.
        ed.step_into("p").unwrap();
        assert!(ed.undo());
        assert!(!ed.scope()[0].local, "the local copy is gone with the edit that made it");
        assert_eq!(ed.doc().node("add").unwrap().params["b"], ParamValue::Float(10.0));
        assert!(ed.redo());
        assert!(ed.step_to(0));
        assert!(ed.undo());
        assert_eq!(ed.doc().to_ron(), GraphDoc::from_ron(MAIN).unwrap().to_ron());
        assert!(ed.is_dirty(), "the file saved has the copy");
    }

    #[test]
    fn undoing_the_include_away_steps_out_and_a_node_that_is_no_include_is_refused() {
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        let a = ed.add_node("math.add", (0.0, 0.0)).unwrap();
        let err = ed.step_into(&a).unwrap_err();
        assert!(err.contains("not an included graph"), "{err}");
        let sub = ed.collapse(std::slice::from_ref(&a)).unwrap();
        ed.step_into(&sub).unwrap();
        assert_eq!(ed.scope().len(), 1);
        assert!(ed.scope()[0].local && ed.scope()[0].origin.is_none());
        ed.set_param(&a, "b", ParamValue::Float(3.0)).unwrap();
        ed.seal();
        assert!(ed.undo() && ed.undo(), "the edit inside, then the collapse");
        assert!(ed.scope().is_empty(), "the include is gone: the editor steps out");
        assert!(ed.doc().node(&a).is_some());
    }

    #[test]
    fn a_parameter_the_include_sets_is_marked_with_its_value_or_its_connection() {
        let (_dir, main, _preset) = project();
        let mut ed = Editor::with_default_registry();
        ed.open(&main).unwrap();
        assert_eq!(ed.set_by_include("add", "b"), None, "not inside an include");
        ed.step_into("p").unwrap();
        assert_eq!(ed.set_by_include("add", "b"), None, "the include leaves `offset` unset");
        assert!(ed.step_out());
        ed.set_param("p", "offset", ParamValue::Float(5.0)).unwrap();
        ed.seal();
        ed.step_into("p").unwrap();
        let set = ed.set_by_include("add", "b").expect("`offset` maps to add.b");
        assert_eq!((set.include.as_str(), set.exposed.as_str()), ("p", "offset"));
        assert_eq!(set.by, SetBy::Value(ParamValue::Float(5.0)));
        assert_eq!(ed.set_by_include("t", "frames"), None, "not exposed");
        assert_eq!(ed.set_by_include("add", "a"), None, "not exposed");
        // What the mark says is what cooks: the include's 5, not the inner 10.
        assert_eq!(cooked(&mut ed, "add", 3), "8");

        assert!(ed.step_out());
        let c = ed.add_node("value.float", (0.0, 400.0)).unwrap();
        ed.connect(&c, "value", "p", "offset").unwrap();
        ed.step_into("p").unwrap();
        assert_eq!(ed.set_by_include("add", "b").unwrap().by, SetBy::Connection(format!("{c}.value")));
    }

    #[test]
    fn moving_nodes_inside_a_preset_makes_no_local_copy_and_no_undo_step_a_value_does() {
        let (_dir, main, _preset) = project();
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        ed.open(&main).unwrap();
        let opened = ed.doc().to_ron();
        ed.step_into("p").unwrap();
        ed.move_node("add", (300.0, 120.0));
        ed.seal();
        assert_eq!(ed.doc().node("add").unwrap().pos, Some((300.0, 120.0)), "the view shows the move");
        assert!(!ed.scope()[0].local && !ed.is_dirty(), "a move is no edit of the preset");
        assert!(ed.status().unwrap().text.contains("not kept"), "{:?}", ed.status());
        assert!(!ed.undo(), "nothing to undo");
        ed.set_param("add", "b", ParamValue::Float(20.0)).unwrap();
        ed.seal();
        assert!(ed.scope()[0].local && ed.is_dirty(), "a value makes the local copy, moves and all");
        assert_eq!(ed.root_doc().subgraphs["p"].node("add").unwrap().pos, Some((300.0, 120.0)));
        ed.move_node("t", (10.0, 10.0));
        ed.seal();
        assert_eq!(ed.root_doc().subgraphs["p"].node("t").unwrap().pos, Some((10.0, 10.0)), "moves in a copy are kept");
        assert!(ed.undo() && ed.undo());
        assert!(ed.step_to(0) || ed.scope().is_empty());
        assert_eq!(ed.doc().to_ron(), opened);
    }

    /// An editor on `main` (no automatic cooks) whose include `p` has been made a local copy by
    /// an edit inside it (`add.b` = 20), stepped back out.
    fn with_local_copy_of_p(main: &std::path::Path) -> Editor {
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        ed.open(main).unwrap();
        ed.step_into("p").unwrap();
        ed.set_param("add", "b", ParamValue::Float(20.0)).unwrap();
        ed.step_out();
        ed
    }

    fn project() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("presets")).unwrap();
        let preset = dir.path().join("presets/p.ron");
        std::fs::write(&preset, PRESET).unwrap();
        let main = dir.path().join("main.ron");
        std::fs::write(&main, MAIN).unwrap();
        (dir, main, preset)
    }

    #[test]
    fn save_into_preset_names_the_other_users_writes_the_file_and_drops_the_copy() {
        let (dir, main, preset) = project();
        std::fs::create_dir_all(dir.path().join("shots")).unwrap();
        let other = dir.path().join("shots/other.ron");
        std::fs::write(&other, r#"(version: 1, nodes: {"x": (type: "graph.include", params: {"path": "../presets/p.ron"})})"#)
            .unwrap();
        let mut ed = with_local_copy_of_p(&main);
        let users = ed.preset_users(&preset);
        assert_eq!(users, [std::fs::canonicalize(&other).unwrap()], "main.ron itself is not listed");
        let file = ed.save_into_preset("p").unwrap();
        assert_eq!(file, preset);
        let written = GraphDoc::load(&preset).unwrap();
        assert_eq!(written.node("add").unwrap().params["b"], ParamValue::Float(20.0));
        assert!(!ed.is_local("p"), "the include reads the file again");
        assert_eq!(cooked(&mut ed, "q", 3), "23", "and so does every include of it");
        let err = ed.save_into_preset("q").unwrap_err();
        assert!(err.contains("no local copy"), "{err}");
        assert!(ed.undo() && ed.is_local("p"), "undo brings the copy back (the file stays written)");
    }

    #[test]
    fn a_local_copy_goes_with_duplicate_copy_and_paste_and_away_with_delete() {
        let (_dir, main, _preset) = project();
        let mut ed = with_local_copy_of_p(&main);
        let copies = ed.duplicate(&["p".into()]);
        assert_eq!(copies, ["p_copy"]);
        assert_eq!(ed.doc().subgraphs["p_copy"], ed.doc().subgraphs["p"]);
        let text = ed.copy_text(&["p".into()]).unwrap();
        let mut other = Editor::with_default_registry();
        other.auto_cook = false;
        let pasted = other.paste_text(&text, None).unwrap();
        assert_eq!(other.doc().subgraphs.keys().collect::<Vec<_>>(), [&pasted[0]]);
        assert!(other.validation().graph.is_some(), "{:?}", other.validation().diagnostics);
        ed.remove_nodes(&["p".into(), "p_copy".into()]);
        assert!(ed.doc().subgraphs.is_empty());
        assert!(ed.validation().graph.is_some(), "{:?}", ed.validation().diagnostics);
    }
}
