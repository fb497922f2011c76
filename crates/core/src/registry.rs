//! The table of node types, filled by each node family's explicit `register` function.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::node::{Node, NodeDesc};
use crate::typos::within_edits;

/// Node types by stable type name.
#[derive(Clone, Default)]
pub struct Registry {
    nodes: BTreeMap<String, Arc<dyn Node>>,
    /// Types the graph loader builds itself (`graph.include`): listed, never cooked.
    loader: BTreeMap<String, NodeDesc>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Self {
        Registry::default()
    }

    /// A registry with the core's own nodes (`graph.include`, `value.*`, `math.*`).
    pub fn with_builtins() -> Self {
        let mut r = Registry::new();
        for node in crate::builtin::nodes() {
            r.add(node);
        }
        let include = crate::builtin::include_desc();
        r.loader.insert(include.type_name.clone(), include);
        r
    }

    /// Adds a node type.
    ///
    /// # Panics
    /// When the type name is already taken: two node families claiming one name is a programming
    /// error caught by the first test that builds the registry, never a user-input condition.
    pub fn add(&mut self, node: Arc<dyn Node>) {
        let name = node.desc().type_name.clone();
        let taken = self.loader.contains_key(&name);
        let previous = self.nodes.insert(name.clone(), node);
        assert!(previous.is_none() && !taken, "node type '{name}' registered twice");
    }

    /// Adds a node declared with [`crate::node!`]: `registry.declare::<levels::Levels>()`.
    pub fn declare<T: crate::declare::Cook>(&mut self) {
        self.add(T::node());
    }

    /// The node type named `type_name`.
    pub fn get(&self, type_name: &str) -> Option<&Arc<dyn Node>> {
        self.nodes.get(type_name)
    }

    /// The description of type `type_name`, cookable or built by the loader.
    pub fn desc(&self, type_name: &str) -> Option<&NodeDesc> {
        self.nodes.get(type_name).map(|n| n.desc()).or_else(|| self.loader.get(type_name))
    }

    /// All descriptions, sorted by type name.
    pub fn descs(&self) -> impl Iterator<Item = &NodeDesc> {
        let mut all: Vec<&NodeDesc> = self.nodes.values().map(|n| n.desc()).chain(self.loader.values()).collect();
        all.sort_by(|a, b| a.type_name.cmp(&b.type_name));
        all.into_iter()
    }

    /// Type names close to `name` (same suffix or a small edit distance), for "did you mean" hints.
    pub fn suggest(&self, name: &str) -> Option<&str> {
        let tail = name.rsplit('.').next().unwrap_or(name);
        self.nodes
            .keys()
            .chain(self.loader.keys())
            .filter_map(|k| {
                let whole = within_edits(k, name, 2);
                let short = within_edits(k.rsplit('.').next().unwrap_or(k), tail, 2);
                Some((whole.into_iter().chain(short).min()?, k))
            })
            .min()
            .map(|(_, k)| k.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::typos::edit_distance;

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("to_gray", "to_grey"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("same", "same"), 0);
    }

    #[test]
    fn suggests_a_close_type_name() {
        let r = Registry::with_builtins();
        assert_eq!(r.suggest("math.ad"), Some("math.add"));
        assert_eq!(r.suggest("zzzzzzzz"), None);
        // Lengths too far apart are not compared (a hostile name of millions of characters).
        assert_eq!(within_edits("math.add", "math.addxx", 2), Some(2));
        assert_eq!(within_edits("math.add", "math.addxxx", 2), None);
        assert_eq!(r.suggest(&"m".repeat(1_000_000)), None);
    }
}
