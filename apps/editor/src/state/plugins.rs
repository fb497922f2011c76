//! Python plugin nodes in the editor: the session's node types are the built-ins plus the
//! plugins of `PYROGRAPH_PLUGIN_PATH` and of the open document's `plugins/` folder, found again
//! when a document opens and when the user reloads them after editing a plugin file.

use std::path::Path;
use std::sync::Arc;

use pyrograph_frontend::plugins::{PluginFlags, PluginRegistries};

use super::Editor;

impl Editor {
    /// A session with every node type pyrograph ships and the Python plugin nodes `flags` and
    /// the open document's folder give.
    pub fn with_plugins(flags: PluginFlags) -> Self {
        let plugins = Arc::new(PluginRegistries::new(pyrograph_frontend::registry(), flags));
        let mut ed = Editor::new(plugins.for_graph(None));
        ed.plugins = Some(plugins);
        ed
    }

    /// Takes the plugins for a document in `graph_dir` (before it is opened or after it moved).
    pub(super) fn plugins_for(&mut self, graph_dir: Option<&Path>) {
        if let Some(p) = &self.plugins {
            self.registry = p.for_graph(graph_dir);
        }
    }

    /// Reads the plugin folders again: the nodes of an edited plugin file get new fingerprints, so
    /// they and what they feed cook again and nothing else does; new plugin files join the
    /// palette. Says in the status line what it found.
    pub fn reload_plugins(&mut self) {
        let dir = self.base_dir();
        self.plugins_for(Some(&dir));
        self.revalidate();
        self.revision += 1;
        if self.auto_cook {
            self.request_preview();
        }
        let (nodes, problems) = match self.registry.extension() {
            Some(found) => (found.nodes.len(), found.problems.clone()),
            None => (0, Vec::new()),
        };
        match problems.first() {
            None => self.set_status(format!("plugins reloaded: {nodes} plugin node types"), false),
            Some(first) => self.set_status(format!("plugins reloaded with problems: {first}"), true),
        }
    }
}
