//! What a document change means for validation: whether it changes what cooks, and which nodes
//! a problem is about.

use std::collections::BTreeMap;
use std::sync::Arc;

use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::{Diagnostic, GraphDoc, Location};

use super::{Editor, Validation, opening};

/// Whether two documents differ only in node positions (which do not affect cooking; a bypass does).
pub fn same_structure(a: &GraphDoc, b: &GraphDoc) -> bool {
    a.edges == b.edges
        && a.interface == b.interface
        && a.nodes.0.len() == b.nodes.0.len()
        && a.nodes.0.iter().zip(&b.nodes.0).all(|((ia, na), (ib, nb))| {
            ia == ib && na.type_name == nb.type_name && na.params == nb.params && na.bypass == nb.bypass
        })
}

/// The node ids a diagnostic is about.
pub fn diagnostic_nodes(d: &Diagnostic) -> Vec<String> {
    match &d.location {
        Location::Node(n) => vec![n.clone()],
        Location::Port { node, .. } => vec![node.clone()],
        Location::Edge { text, .. } => {
            text.split(" -> ").filter_map(|e| split_endpoint(e.trim()).map(|(n, _)| n.to_string())).collect()
        }
        Location::File | Location::Text { .. } | Location::Group { .. } => Vec::new(),
    }
}

impl Editor {
    /// Rebuilds the graph from the document and maps every problem to its node.
    pub fn revalidate(&mut self) {
        let mut checked = opening::check(&self.doc, &self.registry, &self.base_dir());
        if !self.scope.is_empty() {
            // Inside an include: this level's problems and pins from the level on its own, the
            // graph to cook (and problems only the whole shows) from the whole document.
            let root = opening::check(self.root_doc(), &self.registry, &self.base_dir());
            checked.graph = match (root.graph, checked.graph) {
                (Ok(g), Ok(_)) => Ok(g),
                (Ok(_), Err(d)) => Err(d),
                (Err(d), Ok(_)) => Err(d),
                (Err(mut top), Err(level)) => {
                    top.0.splice(0..0, level.0);
                    Err(top)
                }
            };
        }
        self.apply_validation(checked);
    }

    /// Adopts a validation of the current document (made here or by the loader thread).
    pub(super) fn apply_validation(&mut self, checked: opening::Checked) {
        let (graph, diagnostics) = match checked.graph {
            Ok(g) => (Some(Arc::new(g)), Vec::new()),
            Err(d) => (None, d.0),
        };
        let mut by_node: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for d in &diagnostics {
            for node in diagnostic_nodes(d) {
                let text = match &d.location {
                    Location::Port { port, .. } => format!("{port}: {}", d.message),
                    _ => d.message.clone(),
                };
                by_node.entry(node).or_default().push(text);
            }
        }
        self.descs = checked.descs;
        self.validation = Validation { graph, diagnostics, by_node };
        self.reindex();
        let (index, doc, revision) = (&self.index, &self.doc, self.revision);
        // Cook results are named by the top-level graph's ids.
        let top = self.scope.first().map(|l| &l.parent);
        let known = |k: &str| {
            let first = k.split('/').next().unwrap_or(k);
            match top {
                Some(top) => top.node(first).is_some(),
                None => index.node(doc, revision, first).is_some(),
            }
        };
        self.cook_errors.retain(|k, _| known(k));
        self.cook_warnings.retain(|k, _| known(k));
    }
}
