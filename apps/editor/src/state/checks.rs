//! What a document change means for validation: whether it changes what cooks, and which nodes
//! a problem is about.

use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::{Diagnostic, GraphDoc, Location};

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
