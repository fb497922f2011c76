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
    /// Types found at run time (Python plugins), asked only for a name no built-in has.
    extension: Option<Arc<dyn Extension>>,
}

/// Node types found at run time (Python plugins in a folder). They are looked up only when a
/// graph names a type no built-in has, so a graph of built-in nodes never pays for finding them
/// (never starts an interpreter).
pub trait Extension: Send + Sync {
    /// The types found (found on the first call, then kept), and why some could not be read: one
    /// line per broken file or clash, each naming its file.
    fn found(&self) -> &Found;

    /// Whether asking again could find more though no plugin file changed (the interpreter was
    /// missing, a worker hung): front ends that keep registries make a new one then.
    fn is_stale(&self) -> bool {
        false
    }
}

/// What an [`Extension`] found.
#[derive(Default)]
pub struct Found {
    /// The node types, by type name.
    pub nodes: BTreeMap<String, Arc<dyn Node>>,
    /// Why files or names could not be used, one line each, naming the file.
    pub problems: Vec<String>,
    /// Where each type is declared (`file:line`), for listings.
    pub places: BTreeMap<String, String>,
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

    /// Whether `type_name` is a built-in type (compiled in or built by the loader): what a
    /// run-time type may not claim.
    pub fn is_builtin(&self, type_name: &str) -> bool {
        self.nodes.contains_key(type_name) || self.loader.contains_key(type_name)
    }

    /// Adds run-time types (Python plugins), looked up after the built-in ones.
    pub fn extend_with(&mut self, extension: Arc<dyn Extension>) {
        self.extension = Some(extension);
    }

    /// What the run-time types' finder reported, finding them if no one asked before; `None`
    /// without an extension.
    pub fn extension(&self) -> Option<&Found> {
        self.extension.as_deref().map(|e| e.found())
    }

    /// Whether the run-time types should be found again ([`Extension::is_stale`]); never finds them.
    pub fn extension_is_stale(&self) -> bool {
        self.extension.as_ref().is_some_and(|e| e.is_stale())
    }

    /// The node type named `type_name`.
    pub fn get(&self, type_name: &str) -> Option<&Arc<dyn Node>> {
        self.nodes.get(type_name).or_else(|| self.extension()?.nodes.get(type_name))
    }

    /// The description of type `type_name`, cookable or built by the loader.
    pub fn desc(&self, type_name: &str) -> Option<&NodeDesc> {
        let builtin = self.nodes.get(type_name).map(|n| n.desc()).or_else(|| self.loader.get(type_name));
        builtin.or_else(|| Some(self.extension()?.nodes.get(type_name)?.desc()))
    }

    /// All descriptions, sorted by type name (run-time types included, which finds them).
    pub fn descs(&self) -> impl Iterator<Item = &NodeDesc> {
        let found = self.extension().map(|f| f.nodes.values()).into_iter().flatten();
        let mut all: Vec<&NodeDesc> = self.nodes.values().chain(found).map(|n| n.desc()).chain(self.loader.values()).collect();
        all.sort_by(|a, b| a.type_name.cmp(&b.type_name));
        all.into_iter()
    }

    /// Type names close to `name` (same suffix or a small edit distance), for "did you mean" hints.
    pub fn suggest(&self, name: &str) -> Option<&str> {
        let tail = name.rsplit('.').next().unwrap_or(name);
        let found = self.extension().map(|f| f.nodes.keys()).into_iter().flatten();
        self.nodes
            .keys()
            .chain(self.loader.keys())
            .chain(found)
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

    /// An extension that counts how often it is asked; it declares `studio.add` (math.add's node
    /// under a second name: any node will do).
    struct Counting {
        asked: std::sync::atomic::AtomicUsize,
        found: Found,
    }

    impl Extension for Counting {
        fn found(&self) -> &Found {
            self.asked.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            &self.found
        }
    }

    #[test]
    fn run_time_types_are_asked_for_only_when_no_built_in_has_the_name() {
        let mut r = Registry::with_builtins();
        let node = r.get("math.add").unwrap().clone();
        let mut found = Found::default();
        found.nodes.insert("studio.add".into(), node);
        found.problems.push("plugin x.py could not be loaded".into());
        let ext = Arc::new(Counting { asked: 0.into(), found });
        r.extend_with(ext.clone());
        let asked = || ext.asked.load(std::sync::atomic::Ordering::SeqCst);
        assert!(r.get("math.add").is_some() && r.desc("graph.include").is_some());
        assert_eq!(asked(), 0, "a built-in name never asks the extension");
        assert!(r.get("studio.add").is_some());
        assert!(r.get("studio.nothing").is_none());
        assert!(r.descs().any(|d| d.type_name == "math.add"), "listings include the run-time types' descriptions");
        assert!(r.is_builtin("math.add") && !r.is_builtin("studio.add"));
        assert_eq!(r.extension().unwrap().problems, ["plugin x.py could not be loaded"]);
        assert!(asked() >= 3);
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
