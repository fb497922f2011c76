//! Python plugin nodes for every front end: the folders a user names and the one beside the
//! graph, added to a registry so a graph can use the nodes they declare.

use std::path::{Path, PathBuf};

use pyrograph_plugin::discover::plugin_dirs;
use pyrograph_plugin::{PluginOptions, extend, refuse};

use crate::core::Registry;

/// What a front end's user said about plugins.
#[derive(Clone, Debug, Default)]
pub struct PluginFlags {
    /// Folders named on the command line (`--plugins DIR`).
    pub dirs: Vec<PathBuf>,
    /// Plugins turned off (`--no-plugins`): a graph that uses one is refused.
    pub off: bool,
}

/// Adds plugin nodes to `registry` from the flags' folders, `PYROGRAPH_PLUGIN_PATH` and the
/// `plugins/` folder beside `graph`. No Python runs until a graph names a type no built-in has.
pub fn attach(registry: &mut Registry, graph: Option<&Path>, flags: &PluginFlags) -> Result<(), String> {
    if flags.off {
        refuse(registry, "plugin nodes are off (--no-plugins)");
        return Ok(());
    }
    let env = std::env::var_os("PYROGRAPH_PLUGIN_PATH");
    extend(registry, &PluginOptions::new(plugin_dirs(&flags.dirs, env.as_deref(), graph)))
}
