//! What a pyrograph process may read and how big a graph or an image it builds: the limits a
//! studio service sets before it cooks graphs its users submit.
//!
//! They are process-wide (one setting for every graph, include, reader and thread), because a
//! reader deep in a node (an image sequence's frames, an Eigenfires database's packs, a mesh)
//! must obey them as much as the loader does. The command line sets them with `--read-root`,
//! `--max-nodes` and `--max-pixels`; Python with `pyrograph.set_limits`; the budgets also read
//! the environment variables `PYROGRAPH_MAX_NODES` and `PYROGRAPH_MAX_PIXELS`.

use std::path::{Path, PathBuf};
use std::sync::RwLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// Nodes a flattened graph may have by default: far more than any real graph (the shipped ones
/// have at most a few hundred).
pub const DEFAULT_MAX_NODES: u64 = 1_000_000;

/// Pixels an image may declare by default: 16384 × 16384.
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 28;

/// Active voxels a volume may hold by default (a simulation, a VDB read): 64 Mi, about 4 GiB of
/// simulation state.
pub const DEFAULT_MAX_VOXELS: u64 = 1 << 26;

/// 0 means "not set here: the environment variable, else the default".
static MAX_NODES: AtomicU64 = AtomicU64::new(0);
static MAX_PIXELS: AtomicU64 = AtomicU64::new(0);
static MAX_VOXELS: AtomicU64 = AtomicU64::new(0);
/// Canonical folders reads are confined to; empty means reads are not confined.
static READ_ROOTS: RwLock<Vec<PathBuf>> = RwLock::new(Vec::new());

fn from_env(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.trim().replace('_', "").parse().ok())
}

/// Nodes a flattened graph may have: `--max-nodes`, else `PYROGRAPH_MAX_NODES`, else
/// [`DEFAULT_MAX_NODES`].
pub fn max_nodes() -> u64 {
    match MAX_NODES.load(Ordering::Relaxed) {
        0 => from_env("PYROGRAPH_MAX_NODES").unwrap_or(DEFAULT_MAX_NODES),
        n => n,
    }
}

/// Pixels an image or video frame may declare and still be decoded: `--max-pixels`, else
/// `PYROGRAPH_MAX_PIXELS`, else [`DEFAULT_MAX_PIXELS`].
pub fn max_pixels() -> u64 {
    match MAX_PIXELS.load(Ordering::Relaxed) {
        0 => from_env("PYROGRAPH_MAX_PIXELS").unwrap_or(DEFAULT_MAX_PIXELS),
        n => n,
    }
}

/// Active voxels a volume may hold (a simulation's active region, a VDB file's grids):
/// `--max-voxels`, else `PYROGRAPH_MAX_VOXELS`, else [`DEFAULT_MAX_VOXELS`].
pub fn max_voxels() -> u64 {
    match MAX_VOXELS.load(Ordering::Relaxed) {
        0 => from_env("PYROGRAPH_MAX_VOXELS").unwrap_or(DEFAULT_MAX_VOXELS),
        n => n,
    }
}

/// Sets the voxel budget for this process (`None`: back to the environment or the default).
pub fn set_max_voxels(n: Option<u64>) {
    MAX_VOXELS.store(n.unwrap_or(0).max(u64::from(n.is_some())), Ordering::Relaxed);
}

/// Sets the node limit for this process (`None`: back to the environment or the default).
pub fn set_max_nodes(n: Option<u64>) {
    MAX_NODES.store(n.unwrap_or(0).max(u64::from(n.is_some())), Ordering::Relaxed);
}

/// Sets the pixel budget for this process (`None`: back to the environment or the default).
pub fn set_max_pixels(n: Option<u64>) {
    MAX_PIXELS.store(n.unwrap_or(0).max(u64::from(n.is_some())), Ordering::Relaxed);
}

/// How to raise a limit, for its error message: the flag, and the environment variable.
pub fn raise_hint(flag: &str, variable: &str, value: u64) -> String {
    format!("raise the limit with {flag} {value} (or the environment variable {variable}={value})")
}

/// Confines every read of this process to `roots` (folders; symbolic links resolved). An empty
/// list lifts the confinement. A root that is not an existing folder is an error naming it.
pub fn set_read_roots(roots: &[PathBuf]) -> Result<(), String> {
    let mut canon = Vec::with_capacity(roots.len());
    for r in roots {
        match r.canonicalize() {
            Ok(c) if c.is_dir() => canon.push(c),
            Ok(_) => return Err(format!("{}: not a folder", r.display())),
            Err(e) => return Err(format!("{}: {e}", r.display())),
        }
    }
    *READ_ROOTS.write().unwrap_or_else(|e| e.into_inner()) = canon;
    Ok(())
}

/// The folders reads are confined to (canonical), empty when they are not confined.
pub fn read_roots() -> Vec<PathBuf> {
    READ_ROOTS.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Whether `path` may be read: always when reads are not confined, else when the file (or,
/// for a file not there yet or a pattern, its nearest existing folder) is inside a read root
/// once symbolic links are resolved. The error names the path and the roots, never anything
/// read from the file.
pub fn may_read(path: &Path) -> Result<(), String> {
    let roots = READ_ROOTS.read().unwrap_or_else(|e| e.into_inner());
    if roots.is_empty() {
        return Ok(());
    }
    let real = resolved(path);
    if roots.iter().any(|r| real.starts_with(r)) {
        return Ok(());
    }
    let list: Vec<String> = roots.iter().map(|r| r.display().to_string()).collect();
    Err(format!(
        "{} is outside the folders pyrograph may read ({}); move it into one, or add its folder with --read-root",
        path.display(),
        list.join(", ")
    ))
}

/// Whether `path` stays inside folder `root`, judged by names (`out/a/../b.png` is inside
/// `out`; `out/../b.png` and `/tmp/b.png` are not, unless `root` is `/tmp`) and by where the file
/// system takes them: a symbolic link inside `root` to a folder elsewhere (`out/link/b.png`)
/// leads outside. A relative `root` is taken from the current folder, as the writer will take it.
pub fn inside(path: &Path, root: &Path) -> bool {
    let abs = |p: &Path| if p.is_absolute() { lexical(p) } else { lexical(&std::env::current_dir().unwrap_or_default().join(p)) };
    let (path, root) = (abs(path), abs(root));
    // The file itself is replaced by a rename, which follows no link: only its folder counts.
    let landing = match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => resolved(parent).join(name),
        _ => resolved(&path),
    };
    path.starts_with(&root) && landing.starts_with(resolved(&root))
}

/// `path` made absolute and lexically clean, its longest existing ancestor resolved through
/// symbolic links (the rest, which does not exist, appended as names).
pub(crate) fn resolved(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() { lexical(path) } else { lexical(&std::env::current_dir().unwrap_or_default().join(path)) };
    let mut existing = abs.as_path();
    let mut missing = Vec::new();
    loop {
        if let Ok(real) = existing.canonicalize() {
            return missing.iter().rev().fold(real, |p, name| p.join(name));
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                missing.push(name.to_os_string());
                existing = parent;
            }
            _ => return abs,
        }
    }
}

/// `path` with `.` and `..` resolved by their names (no file-system access: the file may not
/// exist yet); a `..` above the start is kept.
pub(crate) fn lexical(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out: Vec<Component> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.last() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(c),
            },
            other => out.push(other),
        }
    }
    out.iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_file_resolves_through_its_existing_folder() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().canonicalize().unwrap();
        assert_eq!(resolved(&dir.path().join("a/../b/c.png")), real.join("b/c.png"));
        #[cfg(unix)]
        {
            let elsewhere = tempfile::tempdir().unwrap();
            std::os::unix::fs::symlink(elsewhere.path(), dir.path().join("link")).unwrap();
            let through = resolved(&dir.path().join("link/x.png"));
            assert_eq!(through, elsewhere.path().canonicalize().unwrap().join("x.png"));
        }
    }

    #[test]
    fn lexical_keeps_a_climb_above_the_start() {
        assert_eq!(lexical(Path::new("a/./b/../../../c")), PathBuf::from("../c"));
        assert_eq!(lexical(Path::new("/../x")), PathBuf::from("/x"));
    }
}
