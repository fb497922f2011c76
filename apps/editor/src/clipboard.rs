//! Copy, cut and paste of nodes through the system clipboard, as RON text.
//!
//! The clipboard holds a small graph document: the copied nodes, the edges among them and the
//! groups wholly inside the copy. Any text editor can read it, and any pyrograph editor (this
//! window, another one, another graph) can paste it. Input paths that were relative to the
//! source graph's folder are written absolute on copy and made relative to the destination
//! graph's folder on paste when they lie inside it, so footage references survive the move.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::{GraphDoc, ParamValue};

use crate::layout::relative_path;
use crate::paths::{input_path_params, is_anchored, map_paths};
use crate::state::Editor;

impl Editor {
    /// The clipboard text for nodes `ids` (unknown ids are skipped); `None` when none is known.
    pub fn copy_text(&self, ids: &[String]) -> Option<String> {
        let chosen: HashSet<&str> = ids.iter().map(String::as_str).filter(|id| self.node_doc(id).is_some()).collect();
        if chosen.is_empty() {
            return None;
        }
        let base = self.base_dir();
        let mut clip = GraphDoc::new();
        for (id, nd) in &self.doc().nodes.0 {
            if !chosen.contains(id.as_str()) {
                continue;
            }
            let mut nd = nd.clone();
            for name in input_path_params(self.registry(), &nd.type_name) {
                if let Some(ParamValue::String(p)) = nd.params.get_mut(&name)
                    && !is_anchored(p)
                {
                    *p = base.join(&*p).display().to_string();
                }
            }
            clip.nodes.0.push((id.clone(), nd));
        }
        clip.edges = self
            .doc()
            .edges
            .iter()
            .filter(|(a, b)| {
                let inside = |e: &str| split_endpoint(e).is_some_and(|(n, _)| chosen.contains(n));
                inside(a) && inside(b)
            })
            .cloned()
            .collect();
        clip.groups = self
            .doc()
            .groups
            .iter()
            .filter(|g| !g.nodes.is_empty() && g.nodes.iter().all(|n| chosen.contains(n.as_str())))
            .cloned()
            .collect();
        for id in &chosen {
            if let Some(local) = self.doc().subgraphs.get(*id) {
                let mut local = local.clone();
                map_paths(&mut local, self.registry(), |p| {
                    if !is_anchored(p) {
                        *p = base.join(&*p).display().to_string();
                    }
                });
                clip.subgraphs.insert(id.to_string(), local);
            }
        }
        Some(clip.to_ron())
    }

    /// Pastes clipboard text: its nodes get fresh ids where theirs are taken, keep their
    /// connections among themselves, and land with their top-left at `at` (else offset from
    /// where they were). Selects and returns the new ids. Text that is not a pyrograph graph is
    /// an error and changes nothing.
    pub fn paste_text(&mut self, text: &str, at: Option<(f32, f32)>) -> Result<Vec<String>, String> {
        let clip = GraphDoc::from_ron(text).map_err(|d| {
            format!("the clipboard holds no pyrograph nodes ({})", d.0.first().map_or("", |x| x.message.as_str()))
        })?;
        if clip.nodes.0.is_empty() {
            return Err("the clipboard holds no pyrograph nodes".into());
        }
        // Offset: the pasted block's top-left goes to `at`.
        let (min_x, min_y) = clip
            .nodes
            .0
            .iter()
            .filter_map(|(_, n)| n.pos)
            .fold((f32::INFINITY, f32::INFINITY), |(x, y), (px, py)| (x.min(px), y.min(py)));
        let offset = match at {
            Some((ax, ay)) if min_x.is_finite() => (ax - min_x, ay - min_y),
            _ => (40.0, 40.0),
        };
        let base = self.base_dir();
        let mut taken: HashSet<String> = self.doc().nodes.0.iter().map(|(id, _)| id.clone()).collect();
        let mut rename: HashMap<String, String> = HashMap::new();
        let mut nodes = Vec::new();
        for (id, nd) in &clip.nodes.0 {
            let new_id = if taken.contains(id) {
                let stem = id.trim_end_matches(|c: char| c.is_ascii_digit());
                let stem = if stem.is_empty() { id.as_str() } else { stem };
                (2..).map(|i| format!("{stem}{i}")).find(|c| !taken.contains(c)).unwrap_or_else(|| format!("{id}_copy"))
            } else {
                id.clone()
            };
            taken.insert(new_id.clone());
            rename.insert(id.clone(), new_id.clone());
            let mut nd = nd.clone();
            nd.pos = Some(match nd.pos {
                Some((x, y)) => ((x + offset.0).round(), (y + offset.1).round()),
                None => at.unwrap_or((40.0, 40.0)),
            });
            for name in input_path_params(self.registry(), &nd.type_name) {
                if let Some(ParamValue::String(p)) = nd.params.get_mut(&name)
                    && Path::new(p.as_str()).is_absolute()
                    && !p.contains("${")
                {
                    *p = relative_path(&PathBuf::from(&*p), &base);
                }
            }
            nodes.push((new_id, nd));
        }
        let remap = |e: &str| -> Option<String> {
            let (n, p) = split_endpoint(e)?;
            Some(format!("{}.{p}", rename.get(n)?))
        };
        let edges: Vec<(String, String)> = clip.edges.iter().filter_map(|(a, b)| Some((remap(a)?, remap(b)?))).collect();
        let mut groups = clip.groups.clone();
        for g in &mut groups {
            g.nodes = g.nodes.iter().filter_map(|n| rename.get(n).cloned()).collect();
        }
        let ids: Vec<String> = nodes.iter().map(|(id, _)| id.clone()).collect();
        let mut locals = Vec::new();
        for (id, local) in &clip.subgraphs {
            let Some(new_id) = rename.get(id) else { continue };
            let mut local = local.clone();
            map_paths(&mut local, self.registry(), |p| {
                if Path::new(p.as_str()).is_absolute() && !p.contains("${") {
                    *p = relative_path(&PathBuf::from(&*p), &base);
                }
            });
            locals.push((new_id.clone(), local));
        }
        self.edit(None, |d| {
            for (id, nd) in nodes {
                d.add_node(&id, nd);
            }
            d.edges.extend(edges);
            d.subgraphs.extend(locals);
            d.groups.extend(groups.into_iter().filter(|g| !g.nodes.is_empty()));
        });
        self.set_selection(ids.clone());
        self.set_status(format!("pasted {} node(s)", ids.len()), false);
        Ok(ids)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paste_into_another_document_keeps_internal_edges_and_renames_clashes() {
        let mut a = Editor::with_default_registry();
        a.auto_cook = false;
        let x = a.add_node("value.float", (100.0, 100.0)).unwrap();
        let add = a.add_node("math.add", (300.0, 100.0)).unwrap();
        let outside = a.add_node("value.float", (100.0, 300.0)).unwrap();
        a.connect(&x, "value", &add, "a").unwrap();
        a.connect(&outside, "value", &add, "b").unwrap();
        let text = a.copy_text(&[x.clone(), add.clone()]).unwrap();

        let mut b = Editor::with_default_registry();
        b.auto_cook = false;
        b.add_node("value.float", (0.0, 0.0)).unwrap(); // takes the id "float"
        let ids = b.paste_text(&text, Some((500.0, 500.0))).unwrap();
        assert_eq!(ids, vec!["float2".to_string(), "add".to_string()]);
        assert_eq!(b.doc().edges, vec![("float2.value".to_string(), "add.a".to_string())], "the edge from outside is not copied");
        assert_eq!(b.doc().node("float2").unwrap().pos, Some((500.0, 500.0)));
        assert_eq!(b.doc().node("add").unwrap().pos, Some((700.0, 500.0)));
        assert_eq!(b.selection(), ids.as_slice());
        assert!(b.validation().diagnostics.iter().all(|d| !d.message.contains("float2")), "{:?}", b.validation().diagnostics);
        // One undo step removes the whole paste.
        b.undo();
        assert_eq!(b.doc().nodes.0.len(), 1);
    }

    #[test]
    fn text_that_is_not_a_graph_changes_nothing() {
        let mut b = Editor::with_default_registry();
        let err = b.paste_text("hello", None).unwrap_err();
        assert!(err.contains("no pyrograph nodes"), "{err}");
        assert!(b.doc().nodes.0.is_empty());
        assert!(!b.can_undo());
    }

    #[test]
    fn relative_input_paths_follow_the_move_between_folders() {
        let dir = tempfile::tempdir().unwrap();
        let src_dir = dir.path().join("shots/a");
        std::fs::create_dir_all(src_dir.join("frames")).unwrap();
        let mut a = Editor::with_default_registry();
        a.auto_cook = false;
        a.save_as(&src_dir.join("a.ron")).unwrap();
        let load = a.add_node("imaging.load_sequence", (0.0, 0.0)).unwrap();
        a.set_param(&load, "path", ParamValue::String("frames".into())).unwrap();
        let text = a.copy_text(std::slice::from_ref(&load)).unwrap();
        assert!(text.contains(&src_dir.join("frames").display().to_string()), "{text}");

        // Pasted into a graph one folder up, the path becomes relative to that folder.
        let mut b = Editor::with_default_registry();
        b.auto_cook = false;
        b.save_as(&dir.path().join("shots/b.ron")).unwrap();
        b.paste_text(&text, None).unwrap();
        assert_eq!(b.doc().node(&load).unwrap().params["path"], ParamValue::String("a/frames".into()));
    }
}
