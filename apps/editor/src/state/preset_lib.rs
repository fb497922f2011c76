//! The preset library as the editor sees it (issue 30): the presets on the search path for the
//! browser, and "Save selection as preset", which turns selected nodes into a preset file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use pyrograph_frontend::core::builtin::INCLUDE_PATH;
use pyrograph_frontend::core::document::{InterfaceDoc, PresetDoc, split_endpoint};
use pyrograph_frontend::core::graph::preset_desc;
use pyrograph_frontend::core::{GraphDoc, ParamValue};
use pyrograph_frontend::presets::{Library, Preset, matches};

use super::Editor;
use crate::paths::{input_path_params, is_anchored};

/// What "Save selection as preset" writes besides the nodes.
#[derive(Clone, Debug, Default)]
pub struct SelectionPreset {
    /// The preset's name in the library.
    pub name: String,
    /// What it makes.
    pub description: String,
    /// Search tags.
    pub tags: Vec<String>,
    /// The parameters to expose, as `(node, parameter)`; each is exposed under the parameter's
    /// name, or `node_parameter` when two ticked parameters share a name.
    pub params: Vec<(String, String)>,
    /// Replace an existing file.
    pub overwrite: bool,
}

impl Editor {
    /// Every preset on the search path (earlier folders win a name).
    pub fn preset_library(&self) -> Library {
        Library::scan(self.preset_dirs())
    }

    /// Presets whose name, description or tags contain every word of `query` (any case) and that
    /// carry every tag of `tags`, in search-path order.
    pub fn browse_presets(&self, query: &str, tags: &[String]) -> Vec<Preset> {
        filter_presets(&self.preset_library().presets, query, tags)
    }

    /// The preset document the selected nodes make: the nodes and the edges between them;
    /// an edge into the selection becomes an input, one out of it an output (with none, every
    /// output of the selection's last nodes); `spec.params` become exposed parameters.
    /// Relative file paths (footage, meshes, included presets) are rebased from the graph's folder
    /// to `dir`, where the preset will live, since an included file resolves its paths from its
    /// own folder.
    pub fn selection_preset(&self, spec: &SelectionPreset, dir: &Path) -> Result<GraphDoc, String> {
        let sel: BTreeSet<&str> = self.selection().iter().map(String::as_str).collect();
        if sel.is_empty() {
            return Err("select the nodes to save as a preset first".into());
        }
        let base = self.base_dir();
        let mut doc = GraphDoc::new();
        for (id, nd) in &self.doc().nodes.0 {
            if sel.contains(id.as_str()) {
                let mut nd = nd.clone();
                for name in input_path_params(self.registry(), &nd.type_name) {
                    if let Some(ParamValue::String(p)) = nd.params.get_mut(&name)
                        && !is_anchored(p)
                    {
                        *p = rebase(&base.join(&*p), dir);
                    }
                }
                doc.nodes.0.push((id.clone(), nd));
            }
        }
        let mut iface = InterfaceDoc::default();
        let split = |e: &str| split_endpoint(e).map(|(n, p)| (n.to_string(), p.to_string()));
        let mut crossing_out = Vec::new();
        for (from, to) in &self.doc().edges {
            let (Some((fnode, fport)), Some((tnode, tport))) = (split(from), split(to)) else { continue };
            match (sel.contains(fnode.as_str()), sel.contains(tnode.as_str())) {
                (true, true) => doc.edges.push((from.clone(), to.clone())),
                (false, true) => {
                    let name = unique(&iface, &tport, &tnode);
                    iface.inputs.insert(name, to.clone());
                }
                (true, false) => crossing_out.push((fnode, fport)),
                (false, false) => {}
            }
        }
        if crossing_out.is_empty() {
            // Nothing downstream: the selection's last nodes are what it makes.
            let feeds: BTreeSet<String> = doc.edges.iter().filter_map(|(f, _)| split(f).map(|(n, _)| n)).collect();
            for (id, _) in &doc.nodes.0 {
                if feeds.contains(id) {
                    continue;
                }
                for p in self.desc(id).map(|d| d.outputs.clone()).unwrap_or_default() {
                    crossing_out.push((id.clone(), p.name.clone()));
                }
            }
        }
        for (node, port) in crossing_out {
            let endpoint = format!("{node}.{port}");
            if !iface.outputs.values().any(|e| e == &endpoint) {
                let name = unique(&iface, &port, &node);
                iface.outputs.insert(name, endpoint);
            }
        }
        if iface.outputs.is_empty() {
            return Err("the selected nodes have no outputs to expose (writers only?)".into());
        }
        let counts = spec.params.iter().fold(BTreeMap::<&str, usize>::new(), |mut m, (_, p)| {
            *m.entry(p.as_str()).or_default() += 1;
            m
        });
        for (node, param) in &spec.params {
            if !sel.contains(node.as_str()) {
                return Err(format!("'{node}.{param}': '{node}' is not selected"));
            }
            if self.incoming(node, param).is_some() {
                return Err(format!("'{node}.{param}' is driven by a connection; only parameters can be exposed"));
            }
            let is_param = self.desc(node).and_then(|d| d.inputs.iter().find(|p| &p.name == param)).map(|p| p.ty.is_parameter());
            match is_param {
                Some(true) => {}
                Some(false) => return Err(format!("'{node}.{param}' is a data input, not a parameter")),
                None => return Err(format!("node '{node}' has no parameter '{param}'")),
            }
            let name = if counts[param.as_str()] > 1 { format!("{node}_{param}") } else { unique(&iface, param, node) };
            iface.params.insert(name, format!("{node}.{param}"));
        }
        // An input with no default cannot cook unconnected: the preset says it needs it.
        let requires: Vec<String> = iface
            .inputs
            .iter()
            .filter(|(_, ep)| {
                split(ep)
                    .and_then(|(n, p)| self.desc(&n).and_then(|d| d.inputs.iter().find(|x| x.name == p).cloned()))
                    .is_some_and(|p| p.is_required())
            })
            .map(|(name, _)| name.clone())
            .collect();
        doc.interface = Some(iface);
        doc.preset = Some(PresetDoc {
            name: spec.name.trim().to_string(),
            description: spec.description.trim().to_string(),
            tags: spec.tags.clone(),
            revision: 1,
            author: std::env::var("USER").unwrap_or_default(),
            requires,
            ..PresetDoc::default()
        });
        doc.description = Some(spec.description.trim().to_string()).filter(|d| !d.is_empty());
        Ok(doc)
    }

    /// Writes the selection as the preset `file` (see [`Editor::selection_preset`]), atomically
    /// and only over an existing file when `spec.overwrite`; returns the file.
    pub fn save_selection_as_preset(&mut self, file: &Path, spec: &SelectionPreset) -> Result<PathBuf, String> {
        if spec.name.trim().is_empty() {
            return Err("give the preset a name".into());
        }
        let file = if file.extension().is_some_and(|e| e == "ron") { file.to_path_buf() } else { file.with_extension("ron") };
        let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let doc = self.selection_preset(spec, &dir)?;
        if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        doc.save(&file, spec.overwrite).map_err(|e| match e.kind() {
            std::io::ErrorKind::AlreadyExists => format!("{} exists; tick overwrite to replace it", file.display()),
            _ => format!("writing {}: {e}", file.display()),
        })?;
        // Read back the way a graph including it would, so a preset that cannot be used is not
        // reported as saved.
        if let Err(d) = preset_desc(&file, self.registry()) {
            return Err(format!("saved {}, but it does not load as a preset: {d}", file.display()));
        }
        if let Some(dir) = file.parent().filter(|d| !self.preset_dirs().iter().any(|x| x == d)) {
            self.add_preset_dir(dir.to_path_buf());
        }
        self.set_status(format!("saved preset '{}' to {}", spec.name.trim(), file.display()), false);
        Ok(file)
    }
}

/// The presets of `all` whose name, description or tags contain every word of `query` (any
/// case) and that carry every tag of `tags`.
pub fn filter_presets(all: &[Preset], query: &str, tags: &[String]) -> Vec<Preset> {
    let words: Vec<&str> = query.split_whitespace().collect();
    all.iter().filter(|p| matches(p, tags, None) && words.iter().all(|w| matches(p, &[], Some(w)))).cloned().collect()
}

/// `want`, or `node_want` when an input, parameter or output of `iface` is already called
/// `want` or it is `path` (the include node's own file parameter).
fn unique(iface: &InterfaceDoc, want: &str, node: &str) -> String {
    let taken = |n: &str| {
        n == INCLUDE_PATH || iface.inputs.contains_key(n) || iface.params.contains_key(n) || iface.outputs.contains_key(n)
    };
    if taken(want) { format!("{node}_{want}") } else { want.to_string() }
}

/// `file` written relative to `dir` (climbing with `..` where they share a parent), else absolute.
fn rebase(file: &Path, dir: &Path) -> String {
    use std::path::Component;
    let abs = |p: &Path| {
        let p = if p.is_absolute() { p.to_path_buf() } else { std::env::current_dir().unwrap_or_default().join(p) };
        // Lexical clean-up of `.` and `..`, so the shared prefix is found without the files existing.
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                Component::ParentDir => {
                    out.pop();
                }
                Component::CurDir => {}
                other => out.push(other),
            }
        }
        out
    };
    let (f, d) = (abs(file), abs(dir));
    let (fc, dc): (Vec<_>, Vec<_>) = (f.components().collect(), d.components().collect());
    let shared = fc.iter().zip(&dc).take_while(|(a, b)| a == b).count();
    if shared <= 1 {
        return f.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in shared..dc.len() {
        rel.push("..");
    }
    for c in &fc[shared..] {
        rel.push(c);
    }
    rel.display().to_string()
}
