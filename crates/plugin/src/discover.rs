//! Where plugins come from: only folders the user names (`--plugins DIR`,
//! `PYROGRAPH_PLUGIN_PATH`) and the `plugins/` folder beside the graph being cooked, never a path
//! written inside a graph file, since a plugin is code that runs with the user's rights.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// A plugin file larger than this is refused unread: plugins are source code, not data.
pub const MAX_PLUGIN_BYTES: u64 = 4 << 20;

/// A folder to search, and whether it must exist (a folder named on the command line must).
#[derive(Clone, Debug, PartialEq)]
pub struct PluginDir {
    /// The folder.
    pub path: PathBuf,
    /// Where it was named: `--plugins`, `PYROGRAPH_PLUGIN_PATH` or `beside the graph`.
    pub origin: &'static str,
}

/// One plugin file as read (the bytes hashed are the bytes the worker runs).
#[derive(Clone, Debug)]
pub struct PluginFile {
    /// The file's absolute path.
    pub path: PathBuf,
    /// The SHA-256 of its bytes, in hex.
    pub sha256: String,
}

/// The folders to search, in order: `--plugins` folders, then `PYROGRAPH_PLUGIN_PATH`
/// (`:`-separated, like `PATH`), then `plugins/` in the graph's folder.
pub fn plugin_dirs(cli: &[PathBuf], env: Option<&OsStr>, graph_dir: Option<&Path>) -> Vec<PluginDir> {
    let mut dirs: Vec<PluginDir> = cli.iter().map(|p| PluginDir { path: p.clone(), origin: "--plugins" }).collect();
    if let Some(env) = env {
        let from_env = std::env::split_paths(env).filter(|p| !p.as_os_str().is_empty());
        dirs.extend(from_env.map(|path| PluginDir { path, origin: "PYROGRAPH_PLUGIN_PATH" }));
    }
    if let Some(folder) = graph_dir {
        let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
        dirs.push(PluginDir { path: folder.join("plugins"), origin: "beside the graph" });
    }
    dirs
}

/// The plugin files of `dirs`: each folder's `*.py` files (not `_*.py` helpers or hidden files),
/// sorted by name, each folder once. A folder named on the command line that is missing, a file
/// that cannot be read, or one too large is an error naming it.
pub fn scan(dirs: &[PluginDir]) -> Result<Vec<PluginFile>, String> {
    let mut seen = Vec::new();
    let mut files = Vec::new();
    for dir in dirs {
        let Ok(real) = dir.path.canonicalize() else {
            if dir.origin == "--plugins" {
                return Err(format!("plugin folder {} (from --plugins) does not exist", dir.path.display()));
            }
            continue;
        };
        if seen.contains(&real) {
            continue;
        }
        pyrograph_core::limits::may_read(&real).map_err(|e| format!("plugin folder {}: {e}", dir.path.display()))?;
        let entries = std::fs::read_dir(&real).map_err(|e| format!("plugin folder {}: {e}", dir.path.display()))?;
        let mut here: Vec<PathBuf> =
            entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| is_plugin_name(p) && p.is_file()).collect();
        here.sort();
        for path in here {
            files.push(read_plugin(&path)?);
        }
        seen.push(real);
    }
    Ok(files)
}

fn is_plugin_name(p: &Path) -> bool {
    let name = p.file_name().and_then(OsStr::to_str).unwrap_or("");
    name.ends_with(".py") && !name.starts_with('_') && !name.starts_with('.')
}

fn read_plugin(path: &Path) -> Result<PluginFile, String> {
    let size = std::fs::metadata(path).map_err(|e| format!("plugin {}: {e}", path.display()))?.len();
    if size > MAX_PLUGIN_BYTES {
        return Err(format!(
            "plugin {} is {size} bytes, over the {MAX_PLUGIN_BYTES}-byte limit for source files",
            path.display()
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("plugin {}: {e}", path.display()))?;
    let sha256 = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
    Ok(PluginFile { path: path.to_path_buf(), sha256 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_come_in_flag_env_graph_order() {
        let env = std::env::join_paths(["/a", "", "/b"]).unwrap();
        let dirs = plugin_dirs(&[PathBuf::from("/cli")], Some(&env), Some(Path::new("/g")));
        let got: Vec<(&str, &str)> = dirs.iter().map(|d| (d.path.to_str().unwrap(), d.origin)).collect();
        assert_eq!(
            got,
            [
                ("/cli", "--plugins"),
                ("/a", "PYROGRAPH_PLUGIN_PATH"),
                ("/b", "PYROGRAPH_PLUGIN_PATH"),
                ("/g/plugins", "beside the graph")
            ]
        );
        let bare = plugin_dirs(&[], None, Some(Path::new("")));
        assert_eq!(bare[0].path, Path::new("./plugins"));
    }

    #[test]
    fn scanning_takes_python_files_once_and_skips_helpers() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["b.py", "a.py", "_helpers.py", ".hidden.py", "notes.txt"] {
            std::fs::write(dir.path().join(name), "x = 1\n").unwrap();
        }
        std::fs::create_dir(dir.path().join("sub.py")).unwrap();
        let d = PluginDir { path: dir.path().to_path_buf(), origin: "PYROGRAPH_PLUGIN_PATH" };
        let files = scan(&[d.clone(), d]).unwrap();
        let names: Vec<_> = files.iter().map(|f| f.path.file_name().unwrap().to_str().unwrap()).collect();
        assert_eq!(names, ["a.py", "b.py"]);
        assert_eq!(
            files[0].sha256, "9e26bf369911c45c243c684147b23fc9e1dcfcf257d299a1c632016a6fcd33f4",
            "the hash of the bytes read"
        );
    }

    #[test]
    fn a_missing_flag_folder_is_an_error_and_a_missing_graph_folder_is_not() {
        let gone = PathBuf::from("/nonexistent/pyrograph-plugins");
        let e = scan(&[PluginDir { path: gone.clone(), origin: "--plugins" }]).unwrap_err();
        assert!(e.contains("/nonexistent/pyrograph-plugins (from --plugins) does not exist"), "{e}");
        assert!(scan(&[PluginDir { path: gone, origin: "beside the graph" }]).unwrap().is_empty());
    }

    #[test]
    fn an_oversized_plugin_is_refused_unread() {
        let dir = tempfile::tempdir().unwrap();
        let big = std::fs::File::create(dir.path().join("big.py")).unwrap();
        big.set_len(MAX_PLUGIN_BYTES + 1).unwrap();
        let e = scan(&[PluginDir { path: dir.path().to_path_buf(), origin: "--plugins" }]).unwrap_err();
        assert!(e.contains("big.py is 4194305 bytes"), "{e}");
    }
}
