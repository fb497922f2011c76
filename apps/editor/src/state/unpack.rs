//! Unpacking an included graph (Houdini's "unpack" of a subnet, Nuke's "expand group"): the
//! include node is replaced by the nodes of its file, renamed `<include>_<node>`, placed where
//! the include was, with its exposed parameters written onto the inner ports they set, the wires
//! into and out of its ports moved to the inner ports they stood for, and the inner graph's
//! relative file paths rebased onto this graph's folder. The cooked frames are those of the
//! include; one undo step takes it back.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use pyrograph_frontend::core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::graph::expand_vars;
use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue};

use super::Editor;
use crate::layout::relative_path;
use crate::paths::{input_path_params, is_anchored};

impl Editor {
    /// Replaces include `id` by the nodes of its graph (see the module); returns their new ids.
    pub fn unpack(&mut self, id: &str) -> Result<Vec<String>, String> {
        let include = self.node_doc(id).cloned().ok_or_else(|| format!("no node '{id}' to unpack"))?;
        if include.type_name != INCLUDE_TYPE {
            return Err(format!("'{id}' is a {}, not an included graph: there is nothing to unpack", include.type_name));
        }
        // A local copy is unpacked as it is (its paths already resolve from here).
        let (inner, inner_dir) = match self.doc().subgraphs.get(id) {
            Some(local) => (local.clone(), None),
            None => {
                let file = self.include_file(id, &include)?;
                let inner = GraphDoc::load(&file).map_err(|d| format!("cannot unpack '{id}': {d}"))?;
                (inner, Some(file.parent().unwrap_or(Path::new(".")).to_path_buf()))
            }
        };
        let (doc, ids) = unpacked(self, id, &include, &inner, inner_dir.as_deref())?;
        self.edit(None, |d| *d = doc);
        self.seal();
        self.set_selection(ids.clone());
        self.set_status(format!("unpacked {id} into {} nodes", ids.len()), false);
        Ok(ids)
    }

    /// The graph file include `id` reads, resolved as the graph resolves it.
    fn include_file(&self, id: &str, include: &NodeDoc) -> Result<PathBuf, String> {
        let Some(ParamValue::String(path)) = include.params.get(INCLUDE_PATH) else {
            return Err(format!("'{id}' names no graph file to unpack"));
        };
        let path = expand_vars(path).map_err(|e| format!("cannot unpack '{id}': {e}"))?;
        Ok(self.base_dir().join(path))
    }
}

/// The document with include `id` unpacked, and the new nodes' ids.
fn unpacked(
    ed: &Editor,
    id: &str,
    include: &NodeDoc,
    inner: &GraphDoc,
    inner_dir: Option<&Path>,
) -> Result<(GraphDoc, Vec<String>), String> {
    let doc = ed.doc();
    let face = inner.interface.clone().unwrap_or_default();
    let mut taken: HashSet<String> = doc.nodes.0.iter().map(|(n, _)| n.clone()).filter(|n| n != id).collect();
    let mut rename = HashMap::new();
    for (n, _) in &inner.nodes.0 {
        let base = format!("{id}_{n}");
        let new = if taken.contains(&base) {
            (2..).map(|i| format!("{base}{i}")).find(|c| !taken.contains(c)).unwrap_or(base)
        } else {
            base
        };
        taken.insert(new.clone());
        rename.insert(n.as_str(), new);
    }
    let renamed = |endpoint: &str| -> Option<String> {
        let (n, port) = split_endpoint(endpoint)?;
        Some(format!("{}.{port}", rename.get(n)?))
    };
    // Inner positions keep their layout, with their top-left corner where the include was.
    let at = include.pos.unwrap_or((0.0, 0.0));
    let corner =
        inner.nodes.0.iter().filter_map(|(_, n)| n.pos).fold((f32::INFINITY, f32::INFINITY), |c, p| (c.0.min(p.0), c.1.min(p.1)));
    let base = ed.base_dir();
    let mut nodes: Vec<(String, NodeDoc)> = Vec::with_capacity(inner.nodes.0.len());
    for (n, nd) in &inner.nodes.0 {
        let mut nd = nd.clone();
        nd.pos = nd.pos.map(|p| ((p.0 - corner.0 + at.0).round(), (p.1 - corner.1 + at.1).round()));
        for name in input_path_params(ed.registry(), &nd.type_name) {
            if let Some(ParamValue::String(p)) = nd.params.get_mut(&name)
                && !is_anchored(p)
                && let Some(dir) = inner_dir
            {
                *p = relative_path(&dir.join(&*p), &base);
            }
        }
        nodes.push((rename[n.as_str()].clone(), nd));
    }
    // The include's parameters set the inner ports its interface names.
    for (name, value) in include.params.iter().filter(|(k, _)| k.as_str() != INCLUDE_PATH) {
        let target = face.params.get(name).or_else(|| face.inputs.get(name));
        let Some((n, port)) = target.and_then(|t| split_endpoint(t)) else {
            return Err(format!("cannot unpack '{id}': its parameter '{name}' is not one its graph exposes"));
        };
        let new = rename.get(n).ok_or_else(|| format!("cannot unpack '{id}': its graph exposes '{name}' on a missing node"))?;
        if let Some((_, nd)) = nodes.iter_mut().find(|(k, _)| k == new) {
            nd.params.insert(port.to_string(), value.clone());
        }
    }
    let mut edges: Vec<(String, String)> = inner.edges.iter().filter_map(|(a, b)| Some((renamed(a)?, renamed(b)?))).collect();
    for (a, b) in &doc.edges {
        let port_of = |e: &str| split_endpoint(e).filter(|(n, _)| *n == id).map(|(_, p)| p.to_string());
        let a = match port_of(a) {
            Some(p) => face.outputs.get(&p).and_then(|s| renamed(s)).ok_or_else(|| format!("'{id}' has no output '{p}'"))?,
            None => a.clone(),
        };
        let b = match port_of(b) {
            Some(p) => face.inputs.get(&p).and_then(|s| renamed(s)).ok_or_else(|| format!("'{id}' has no input '{p}'"))?,
            None => b.clone(),
        };
        edges.push((a, b));
    }
    let mut out = doc.clone();
    out.subgraphs.remove(id);
    // The inner graph's own local subgraphs come along under their nodes' new ids.
    for (n, local) in &inner.subgraphs {
        let Some(new) = rename.get(n.as_str()) else { continue };
        let mut local = local.clone();
        if let Some(dir) = inner_dir {
            crate::paths::rebase_paths(&mut local, ed.registry(), dir, &base);
        }
        out.subgraphs.insert(new.clone(), local);
    }
    let at_index = out.nodes.0.iter().position(|(n, _)| n == id).unwrap_or(out.nodes.0.len());
    out.nodes.0.remove(at_index);
    let ids: Vec<String> = nodes.iter().map(|(n, _)| n.clone()).collect();
    out.nodes.0.splice(at_index..at_index, nodes);
    out.edges = edges;
    for g in &mut out.groups {
        if let Some(i) = g.nodes.iter().position(|n| n == id) {
            g.nodes.splice(i..=i, ids.iter().cloned());
        }
    }
    Ok((out, ids))
}
