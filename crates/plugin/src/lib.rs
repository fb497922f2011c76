//! Node types written in Python. A plugin is a `.py` file in a plugin folder whose functions are
//! declared with `@node` (`host/pyrograph_plugin.py`); pyrograph asks a Python worker process what
//! the files declare only when a graph names a type no built-in node has, and cooks each plugin
//! node in a pool of workers, one per cook thread. Nothing here links Python: a machine without
//! it cooks every graph of built-in nodes as before.
#![deny(missing_docs)]

pub mod arena;
pub mod convert;
pub mod decl;
pub mod discover;
pub mod host;
pub mod node;
pub mod pool;
pub mod protocol;
pub mod worker;

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use pyrograph_core::registry::{Extension, Found};
use pyrograph_core::{Node, Registry};

use crate::discover::{PluginDir, PluginFile};
use crate::node::PyNode;
use crate::pool::Pool;
use crate::protocol::Reply;
use crate::worker::{Launch, WorkerError};

/// How long a worker may take to load one plugin file and say what it declares (a plugin whose
/// top level hangs is given up on, and named).
pub const DESCRIBE_TIMEOUT: Duration = Duration::from_secs(30);

/// How plugins are found and run.
#[derive(Clone, Debug)]
pub struct PluginOptions {
    /// The folders to search, in order ([`discover::plugin_dirs`]).
    pub dirs: Vec<PluginDir>,
    /// The Python interpreter (`PYROGRAPH_PYTHON`, else `python3`).
    pub python: OsString,
    /// The most workers at once: the cook's threads (rayon's pool, `RAYON_NUM_THREADS`).
    pub workers: usize,
    /// Where the host script is written.
    pub host_dir: PathBuf,
    /// How long a worker may take to load one plugin file ([`DESCRIBE_TIMEOUT`]).
    pub describe_timeout: Duration,
}

impl PluginOptions {
    /// Options for these folders, with the interpreter from `PYROGRAPH_PYTHON` and a worker per cook thread.
    pub fn new(dirs: Vec<PluginDir>) -> PluginOptions {
        PluginOptions {
            dirs,
            python: std::env::var_os("PYROGRAPH_PYTHON").filter(|p| !p.is_empty()).unwrap_or_else(|| "python3".into()),
            workers: rayon::current_num_threads(),
            host_dir: host::default_dir(),
            describe_timeout: DESCRIBE_TIMEOUT,
        }
    }
}

/// Adds the plugin nodes of `options.dirs` to `registry`, looked up only when a graph names a
/// type no built-in has. The folders are scanned now (no Python runs); an unreadable folder or
/// file is an error naming it.
pub fn extend(registry: &mut Registry, options: &PluginOptions) -> Result<(), String> {
    extend_scanned(registry, discover::scan(&options.dirs)?, options);
    Ok(())
}

/// [`extend`] with files already scanned (a front end that compares them with the last scan to
/// see whether a plugin changed).
pub fn extend_scanned(registry: &mut Registry, files: Vec<PluginFile>, options: &PluginOptions) {
    let builtin: Vec<String> = registry.descs().map(|d| d.type_name.clone()).collect();
    registry.extend_with(Arc::new(Plugins {
        files,
        builtin,
        options: options.clone(),
        found: OnceLock::new(),
        stale: AtomicBool::new(false),
    }));
}

/// Turns plugins off: a graph that names a type no built-in has is refused, saying plugins are
/// off (`--no-plugins`).
pub fn refuse(registry: &mut Registry, why: &str) {
    registry.extend_with(Arc::new(Refused(Found { problems: vec![why.to_string()], ..Found::default() })));
}

struct Refused(Found);

impl Extension for Refused {
    fn found(&self) -> &Found {
        &self.0
    }
}

/// The plugin files of a registry, described on first use.
struct Plugins {
    files: Vec<PluginFile>,
    builtin: Vec<String>,
    options: PluginOptions,
    found: OnceLock<Found>,
    /// Some file could not be asked (Python missing, a worker hung or died): asking again, after
    /// the user mended it, may succeed though no plugin file changed.
    stale: AtomicBool,
}

impl Extension for Plugins {
    fn found(&self) -> &Found {
        self.found.get_or_init(|| self.describe())
    }

    fn is_stale(&self) -> bool {
        self.stale.load(Ordering::Relaxed)
    }
}

impl Plugins {
    /// Asks a worker what every file declares and builds the node types, keeping one line per
    /// problem: a file that failed to load, a bad declaration, a name taken by a built-in or
    /// declared twice (both places named; neither is used).
    fn describe(&self) -> Found {
        let mut found = Found::default();
        if self.files.is_empty() {
            return found;
        }
        let pool = Arc::new(Pool::new(
            Launch { python: self.options.python.clone(), host_dir: self.options.host_dir.clone() },
            self.options.workers,
        ));
        if let Err(e) = host::install(&self.options.host_dir) {
            self.stale.store(true, Ordering::Relaxed);
            let dir = self.options.host_dir.display();
            found.problems.push(format!("the Python plugins could not be read: could not write the host files to {dir}: {e}"));
            return found;
        }
        let mut places: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for file in &self.files {
            let file = Arc::new(file.clone());
            // One file a request: a file that hangs or kills its worker is named, and the others
            // are read by the next worker.
            let reply = match self.ask(&pool, &file) {
                Ok(reply) => reply,
                Err(why) => {
                    self.stale.store(true, Ordering::Relaxed);
                    found.problems.push(format!("plugin {} could not be loaded: {why}", file.path.display()));
                    continue;
                }
            };
            if let Some(e) = reply.error {
                found.problems.push(format!("plugin {} could not be loaded: {}", file.path.display(), e.render()));
                continue;
            }
            for decl in reply.nodes {
                let place = format!("{}:{}", file.path.display(), decl.line);
                let desc = match decl.to_desc() {
                    Ok(d) => d,
                    Err(e) => {
                        found.problems.push(format!("{place}: {}: {e}", decl.type_name));
                        continue;
                    }
                };
                if self.builtin.contains(&desc.type_name) {
                    found.problems.push(format!(
                        "{place}: '{}' is a built-in node type; give the plugin node another name",
                        desc.type_name
                    ));
                    continue;
                }
                found.places.insert(desc.type_name.clone(), place.clone());
                places.entry(desc.type_name.clone()).or_default().push(place);
                let channels = decl.inputs.iter().map(|p| p.channels.clone().filter(|c| c != "any")).collect();
                let salt = salt(&file, &desc.type_name);
                let node = PyNode { desc, file: file.clone(), channels, pool: pool.clone(), salt };
                found.nodes.insert(node.desc.type_name.clone(), Arc::new(node) as Arc<dyn Node>);
            }
        }
        for (name, at) in places.into_iter().filter(|(_, at)| at.len() > 1) {
            found.nodes.remove(&name);
            found.places.remove(&name);
            found.problems.push(format!("plugin node type '{name}' is declared twice: at {}", at.join(" and at ")));
        }
        found
    }

    /// What one file declares, asked of a worker that gets `describe_timeout` to load it.
    fn ask(&self, pool: &Pool, file: &PluginFile) -> Result<protocol::DescribedFile, String> {
        let request = serde_json::json!({"op": "describe", "files": [{"path": file.path, "sha256": file.sha256}]});
        let reply =
            pool.with_worker(None, false, |w| w.request_within(&request, None, self.options.describe_timeout)).map_err(|e| {
                match e {
                    WorkerError::Cancelled => "cancelled".to_string(),
                    WorkerError::Broken(why) => why,
                }
            })?;
        match reply {
            Reply::Described { mut files } if files.len() == 1 => Ok(files.remove(0)),
            other => Err(format!("the Python worker answered with '{}' instead of what the file declares", other.op())),
        }
    }
}

/// The fingerprint salt of a plugin node: its file's hash, the host's, and its type name.
fn salt(file: &PluginFile, type_name: &str) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (file.sha256.as_str(), host::digest(), type_name).hash(&mut h);
    h.finish()
}
