//! Collapsing a selection into a subgraph (Houdini's "collapse into subnet", Nuke's Ctrl+G):
//! the selected nodes move into a new include whose graph is kept in the document, every wire
//! that crossed the selection's edge now runs through a port of the include, and the cooked
//! results are those of before. One undo step takes it back.

use std::collections::{BTreeMap, HashSet};

use pyrograph_frontend::core::builtin::INCLUDE_TYPE;
use pyrograph_frontend::core::document::{InterfaceDoc, split_endpoint};
use pyrograph_frontend::core::{GraphDoc, NodeDoc, TimeDep};

use super::Editor;

impl Editor {
    /// Moves nodes `ids` into a new local subgraph (see the module); returns the include's id.
    pub fn collapse(&mut self, ids: &[String]) -> Result<String, String> {
        let chosen: HashSet<&str> = ids.iter().map(String::as_str).filter(|id| self.node_doc(id).is_some()).collect();
        if chosen.is_empty() {
            return Err("select the nodes to collapse into a subgraph first".into());
        }
        let id = self.unique_id("subgraph");
        let outputs = |n: &str| -> Vec<String> {
            let writer = self.desc(n).is_some_and(|d| d.time == TimeDep::Sink);
            match writer {
                true => Vec::new(),
                false => self.desc(n).map(|d| d.outputs.iter().map(|p| p.name.clone()).collect()).unwrap_or_default(),
            }
        };
        let doc = collapsed(self.doc(), &chosen, &id, outputs)?;
        self.edit(None, |d| *d = doc);
        self.seal();
        self.set_selection(vec![id.clone()]);
        self.set_status(format!("collapsed {} node(s) into {id}: double-click it to step inside", chosen.len()), false);
        Ok(id)
    }
}

/// A port name for `node.port` not yet in `taken`: `node_port`, then `node_port2`, ….
fn port_name(endpoint: &str, taken: &BTreeMap<String, String>) -> String {
    let base = endpoint.replace('.', "_");
    if !taken.contains_key(&base) {
        return base;
    }
    (2..).map(|i| format!("{base}{i}")).find(|c| !taken.contains_key(c)).unwrap_or(base)
}

/// `doc` with nodes `chosen` moved into a local subgraph of a new include `id`. The outputs of
/// a chosen node that feeds nothing (`outputs` names them; none for a writer) are exposed too,
/// as a subnet's display node is: the end of a chain stays something to look at and wire on.
fn collapsed(
    doc: &GraphDoc,
    chosen: &HashSet<&str>,
    id: &str,
    outputs: impl Fn(&str) -> Vec<String>,
) -> Result<GraphDoc, String> {
    let inside = |e: &str| split_endpoint(e).is_some_and(|(n, _)| chosen.contains(n));
    let mut inner = GraphDoc::new();
    let mut face = InterfaceDoc::default();
    let mut edges = Vec::with_capacity(doc.edges.len());
    for (a, b) in &doc.edges {
        match (inside(a), inside(b)) {
            (true, true) => inner.edges.push((a.clone(), b.clone())),
            (false, false) => edges.push((a.clone(), b.clone())),
            // A wire in: an input of the include feeds the inner port (one input per port, as
            // an input takes one wire).
            (false, true) => {
                let name = port_name(b, &face.inputs);
                face.inputs.insert(name.clone(), b.clone());
                edges.push((a.clone(), format!("{id}.{name}")));
            }
            // A wire out: one output per inner port, shared by every wire it fed.
            (true, false) => {
                let name = match face.outputs.iter().find(|(_, inner)| *inner == a) {
                    Some((name, _)) => name.clone(),
                    None => {
                        let name = port_name(a, &face.outputs);
                        face.outputs.insert(name.clone(), a.clone());
                        name
                    }
                };
                edges.push((format!("{id}.{name}"), b.clone()));
            }
        }
    }
    let feeds: HashSet<&str> = doc.edges.iter().filter_map(|(a, _)| split_endpoint(a).map(|(n, _)| n)).collect();
    for (n, _) in doc.nodes.0.iter().filter(|(n, _)| chosen.contains(n.as_str()) && !feeds.contains(n.as_str())) {
        for port in outputs(n) {
            let endpoint = format!("{n}.{port}");
            let name = port_name(&endpoint, &face.outputs);
            face.outputs.insert(name, endpoint);
        }
    }
    let mut out = doc.clone();
    let first = out.nodes.0.iter().position(|(n, _)| chosen.contains(n.as_str())).unwrap_or(out.nodes.0.len());
    let mut corner = (f32::INFINITY, f32::INFINITY);
    for (n, nd) in &doc.nodes.0 {
        if chosen.contains(n.as_str()) {
            if let Some(p) = nd.pos {
                corner = (corner.0.min(p.0), corner.1.min(p.1));
            }
            inner.nodes.0.push((n.clone(), nd.clone()));
            if let Some(local) = out.subgraphs.remove(n) {
                inner.subgraphs.insert(n.clone(), local);
            }
        }
    }
    out.nodes.0.retain(|(n, _)| !chosen.contains(n.as_str()));
    let mut include = NodeDoc::new(INCLUDE_TYPE);
    include.pos = corner.0.is_finite().then_some(corner);
    out.nodes.0.insert(first.min(out.nodes.0.len()), (id.to_string(), include));
    out.edges = edges;
    // Groups wholly inside go inside; the others lose the moved nodes.
    for g in &doc.groups {
        if !g.nodes.is_empty() && g.nodes.iter().all(|n| chosen.contains(n.as_str())) {
            inner.groups.push(g.clone());
        }
    }
    out.groups.retain(|g| !inner.groups.contains(g));
    for g in &mut out.groups {
        g.nodes.retain(|n| !chosen.contains(n.as_str()));
    }
    inner.description = Some(format!("Collapsed from {} node(s).", inner.nodes.0.len()));
    inner.interface = Some(face);
    out.subgraphs.insert(id.to_string(), inner);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue};

    use crate::Editor;
    use crate::state::scope::tests::cooked;

    /// t (frame) → add (+100) → mul (×2) → out (+1); `add` also feeds `side` (−1).
    fn chain() -> GraphDoc {
        let mut doc = GraphDoc::new();
        doc.add_node("t", NodeDoc::new("time.frame").param("frames", ParamValue::Int(5)));
        doc.add_node("add", NodeDoc::new("math.add").param("b", ParamValue::Float(100.0)));
        doc.add_node("mul", NodeDoc::new("math.multiply").param("b", ParamValue::Float(2.0)));
        doc.add_node("out", NodeDoc::new("math.add").param("b", ParamValue::Float(1.0)));
        doc.add_node("side", NodeDoc::new("math.add").param("b", ParamValue::Float(-1.0)));
        doc.connect("t.frame", "add.a")
            .connect("add.value", "mul.a")
            .connect("mul.value", "out.a")
            .connect("add.value", "side.a");
        doc
    }

    fn all(ed: &mut Editor) -> Vec<String> {
        let mut v: Vec<String> = (0..3).map(|f| cooked(ed, "out", f)).collect();
        v.push(cooked(ed, "side", 4));
        v
    }

    #[test]
    fn collapsing_keeps_what_cooks_and_one_undo_restores_the_document() {
        let mut ed = Editor::with_default_registry();
        ed.edit(None, |d| *d = chain());
        ed.seal();
        let before = all(&mut ed);
        assert_eq!(before, ["201", "203", "205", "103"]);
        let original = ed.doc().to_ron();

        let sub = ed.collapse(&["add".into(), "mul".into()]).unwrap();
        assert_eq!(sub, "subgraph");
        let doc = ed.doc();
        assert!(doc.node("add").is_none() && doc.node("subgraph").is_some());
        let face = doc.subgraphs["subgraph"].interface.clone().unwrap();
        assert_eq!(face.inputs.into_iter().collect::<Vec<_>>(), [("add_a".to_string(), "add.a".to_string())]);
        assert_eq!(face.outputs.len(), 2, "add.value (to side) and mul.value (to out): {:?}", face.outputs);
        assert!(ed.validation().graph.is_some(), "{:?}", ed.validation().diagnostics);
        let after = all(&mut ed);
        assert_eq!(after, before);
        assert!(ed.doc().to_ron().contains("version: 6"));

        assert!(ed.undo());
        assert_eq!(ed.doc().to_ron(), original);
    }
}
