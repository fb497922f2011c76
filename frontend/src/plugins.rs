//! Python plugin nodes for every front end: the folders a user names and the one beside the
//! graph, added to a registry so a graph can use the nodes they declare.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use pyrograph_plugin::discover::{PluginDir, PluginFile, plugin_dirs, scan};
use pyrograph_plugin::{PluginOptions, extend_scanned, refuse};

use crate::core::Registry;

/// What a front end's user said about plugins.
#[derive(Clone, Debug, Default)]
pub struct PluginFlags {
    /// Folders named on the command line (`--plugins DIR`).
    pub dirs: Vec<PathBuf>,
    /// Plugins turned off (`--no-plugins`): a graph that uses one is refused.
    pub off: bool,
    /// The Python to run them with, instead of `PYROGRAPH_PYTHON` or `python3`.
    pub python: Option<std::ffi::OsString>,
}

impl PluginFlags {
    /// The folders to search for a graph in `graph_dir`: the flags', `PYROGRAPH_PLUGIN_PATH`'s
    /// and the graph folder's `plugins/`.
    pub fn dirs_for(&self, graph_dir: Option<&Path>) -> Vec<PluginDir> {
        plugin_dirs(&self.dirs, std::env::var_os("PYROGRAPH_PLUGIN_PATH").as_deref(), graph_dir)
    }

    /// How plugins for a graph in `graph_dir` are found and run.
    pub fn options_for(&self, graph_dir: Option<&Path>) -> PluginOptions {
        let mut options = PluginOptions::new(self.dirs_for(graph_dir));
        if let Some(p) = &self.python {
            options.python = p.clone();
        }
        options
    }
}

/// Whether `PYROGRAPH_NO_PLUGINS` turns plugins off (set, not empty, not `0`): for services and for
/// the Python module, which has no command line.
pub fn off_by_environment() -> bool {
    std::env::var_os("PYROGRAPH_NO_PLUGINS").is_some_and(|v| !v.is_empty() && v != "0")
}

/// Adds plugin nodes to `registry` from the flags' folders, `PYROGRAPH_PLUGIN_PATH` and the
/// `plugins/` folder in `graph_dir`. No Python runs until a graph names a type no built-in has.
pub fn attach(registry: &mut Registry, graph_dir: Option<&Path>, flags: &PluginFlags) -> Result<(), String> {
    if flags.off || off_by_environment() {
        refuse(registry, "plugin nodes are off (--no-plugins or PYROGRAPH_NO_PLUGINS)");
        return Ok(());
    }
    let options = flags.options_for(graph_dir);
    extend_scanned(registry, scan(&options.dirs)?, &options);
    Ok(())
}

/// Registries with the plugins for each graph folder, for front ends that build graphs again and
/// again (the editor, the Python module): the folders are scanned at every request, and the
/// registry (with its Python workers) is kept while no plugin file changed. An edited, added or
/// removed plugin gives a new registry, whose changed nodes have new fingerprints: what they feed
/// cooks again, nothing else does. One registry is kept per set of folders, for the last few sets.
pub struct PluginRegistries {
    base: Registry,
    flags: PluginFlags,
    kept: Mutex<Vec<Kept>>,
}

/// How many sets of folders keep their registry (and idle workers) at once.
const KEPT: usize = 16;

struct Kept {
    dirs: Vec<PluginDir>,
    files: Vec<(PathBuf, String)>,
    registry: Arc<Registry>,
}

impl PluginRegistries {
    /// Plugins added to `base` as `flags` say.
    pub fn new(base: Registry, flags: PluginFlags) -> PluginRegistries {
        PluginRegistries { base, flags, kept: Mutex::new(Vec::new()) }
    }

    /// The registry for a graph in `graph_dir`. An unreadable plugin folder or file does not stop
    /// a graph of built-in nodes: a graph that uses a plugin node is refused with the reason.
    pub fn for_graph(&self, graph_dir: Option<&Path>) -> Arc<Registry> {
        let refused = |why: &str| {
            let mut r = self.base.clone();
            refuse(&mut r, why);
            Arc::new(r)
        };
        if self.flags.off || off_by_environment() {
            return refused("plugin nodes are off (--no-plugins or PYROGRAPH_NO_PLUGINS)");
        }
        let options = self.flags.options_for(graph_dir);
        let files = match scan(&options.dirs) {
            Ok(files) => files,
            Err(e) => return refused(&e),
        };
        let key: Vec<(PathBuf, String)> = files.iter().map(|f: &PluginFile| (f.path.clone(), f.sha256.clone())).collect();
        let Ok(mut kept) = self.kept.lock() else { return refused("the plugin registries failed earlier") };
        if let Some(k) = kept.iter().find(|k| k.dirs == options.dirs && k.files == key && !k.registry.extension_is_stale()) {
            return k.registry.clone();
        }
        let mut registry = self.base.clone();
        extend_scanned(&mut registry, files, &options);
        let registry = Arc::new(registry);
        kept.retain(|k| k.dirs != options.dirs);
        if kept.len() >= KEPT {
            kept.remove(0);
        }
        kept.push(Kept { dirs: options.dirs, files: key, registry: registry.clone() });
        registry
    }
}
