//! Python plugin nodes on the command line: the flags every command takes, the folders they
//! name, and the node listing that shows where each plugin node comes from.

use std::path::{Path, PathBuf};

use pyrograph::outln;
use pyrograph_frontend::core::Registry;
use pyrograph_frontend::plugins::PluginFlags;
use pyrograph_frontend::text::printable_json;

use crate::{Command, Failure};

/// Where Python plugin nodes come from (every command takes these).
#[derive(clap::Args)]
pub struct PluginArgs {
    /// Load Python plugin nodes from this folder too (repeat for several). The folders of
    /// PYROGRAPH_PLUGIN_PATH and the `plugins/` folder beside the graph are always searched;
    /// Python (PYROGRAPH_PYTHON, else python3) starts only for a graph that uses a plugin node.
    #[arg(long = "plugins", value_name = "DIR", global = true)]
    dirs: Vec<PathBuf>,
    /// Load no Python plugins: a graph that uses a plugin node is refused.
    #[arg(long, global = true, conflicts_with = "dirs")]
    no_plugins: bool,
}

impl PluginArgs {
    /// The flags a farm task needs to find the same plugins: every folder given here or on
    /// `PYROGRAPH_PLUGIN_PATH`, absolute, as `--plugins DIR` (the graph's own `plugins/` folder
    /// goes with the graph), or `--no-plugins`.
    pub fn args(&self) -> Result<Vec<String>, Failure> {
        if self.no_plugins {
            return Ok(vec!["--no-plugins".into()]);
        }
        let flags = PluginFlags { dirs: self.dirs.clone(), off: false, python: None };
        let mut args = Vec::new();
        // A folder of PYROGRAPH_PLUGIN_PATH that is not there is skipped here as in a local render
        // (as a `--plugins` folder it would fail every task).
        for dir in flags.dirs_for(None).into_iter().filter(|d| d.origin == "--plugins" || d.path.is_dir()) {
            let abs = std::path::absolute(&dir.path).map_err(|e| Failure(format!("error: {}: {e}", dir.path.display())))?;
            args.extend(["--plugins".to_string(), abs.to_string_lossy().into_owned()]);
        }
        Ok(args)
    }

    /// Adds the plugin folders for `command` (the one beside its graph, if it has one).
    pub fn attach(&self, registry: &mut Registry, command: Option<&Command>) -> Result<(), Failure> {
        let flags = PluginFlags { dirs: self.dirs.clone(), off: self.no_plugins, python: None };
        let graph_dir = command.and_then(graph_of).map(|g| g.parent().unwrap_or(Path::new("")));
        pyrograph_frontend::plugins::attach(registry, graph_dir, &flags).map_err(|e| Failure(format!("error: {e}")))
    }
}

/// The graph a command cooks or reads, whose `plugins/` folder is searched.
fn graph_of(command: &Command) -> Option<&Path> {
    match command {
        Command::Render { graph, .. } | Command::Check { graph, .. } | Command::Info { graph, .. } => Some(graph),
        Command::Job { graph, .. } | Command::Presets { graph, .. } => graph.as_deref(),
        // A preset named by its file: the plugins beside that file.
        Command::Preset { graph, name, .. } => graph.as_deref().or_else(|| Some(Path::new(name)).filter(|p| p.is_file())),
        Command::Simulate(args) => Some(args.graph()),
        _ => None,
    }
}

/// Lists every node type (plugin nodes with the file and line that declare them); a plugin that
/// could not be loaded is reported and fails the command.
pub fn nodes(registry: &Registry, markdown: bool, json_out: bool) -> Result<(), Failure> {
    if markdown {
        print!("{}", pyrograph_frontend::reference::markdown(registry));
    } else if json_out {
        println!("{}", printable_json(pyrograph_frontend::reference::json(registry)));
    } else {
        let places = registry.extension().map(|f| &f.places);
        for d in registry.descs() {
            let place = places.and_then(|p| p.get(&d.type_name)).map(|p| format!("  ({p})")).unwrap_or_default();
            outln!("{:<32} {:<16} {}{place}", d.type_name, d.category, d.summary());
        }
    }
    match registry.extension().map(|f| f.problems.as_slice()).unwrap_or_default() {
        [] => Ok(()),
        problems => Err(Failure(problems.iter().map(|p| format!("error: {p}")).collect::<Vec<_>>().join("\n"))),
    }
}
