//! The Python side, compiled into the binary: the worker loop (`pyrograph_host.py`) and the
//! module plugins import (`pyrograph_plugin.py`). They are written once into a folder named by
//! their hash, so a worker needs only `python3` and numpy, never the compiled Python module.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// The worker loop's file name.
pub const HOST_FILE: &str = "pyrograph_host.py";
/// The declaration module's file name.
pub const API_FILE: &str = "pyrograph_plugin.py";

/// Every file of `host/`, the worker's own modules beside the two above.
const FILES: [(&str, &str); 4] = [
    (HOST_FILE, include_str!("../host/pyrograph_host.py")),
    (API_FILE, include_str!("../host/pyrograph_plugin.py")),
    ("pyrograph_host_io.py", include_str!("../host/pyrograph_host_io.py")),
    ("pyrograph_host_clip.py", include_str!("../host/pyrograph_host_clip.py")),
];

/// A hash of both files: part of every plugin node's fingerprint, since they convert its values.
pub fn digest() -> [u8; 32] {
    let mut h = Sha256::new();
    for (name, text) in FILES {
        h.update(name.as_bytes());
        h.update((text.len() as u64).to_le_bytes());
        h.update(text.as_bytes());
    }
    h.finalize().into()
}

/// The folder the files are written to: in the user's cache folder (`XDG_CACHE_HOME`, else
/// `~/.cache`), else in a folder of the temporary folder named after the user, which [`install`]
/// makes private (the folder comes first on the workers' `PYTHONPATH`: nobody else may write in it).
pub fn default_dir() -> PathBuf {
    let tag: String = digest()[..6].iter().map(|b| format!("{b:02x}")).collect();
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").filter(|p| !p.is_empty()).map(|h| Path::new(&h).join(".cache")));
    match cache {
        Some(cache) => cache.join("pyrograph").join(format!("python-host-{tag}")),
        // SAFETY: getuid has no preconditions and cannot fail.
        None => std::env::temp_dir().join(format!("pyrograph-{}", unsafe { libc::getuid() })).join(format!("python-host-{tag}")),
    }
}

/// Refuses a folder another user owns or may write in; `sticky_ok` lets a shared folder with the
/// sticky bit (`/tmp`) pass, where nobody can move or remove what another user made.
fn check_private(dir: &Path, sticky_ok: bool) -> std::io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::symlink_metadata(dir)?;
    // SAFETY: getuid has no preconditions and cannot fail.
    let me = unsafe { libc::getuid() };
    let sticky = sticky_ok && meta.mode() & 0o1000 != 0;
    if !meta.is_dir() || !sticky && (meta.uid() != me || meta.mode() & 0o022 != 0) {
        return Err(std::io::Error::other(format!(
            "{} is not a folder only you can write in; remove it, or set XDG_CACHE_HOME to a folder of your own",
            dir.display()
        )));
    }
    Ok(())
}

/// Writes the files into `dir` unless they are already there with the same text (each replaced
/// atomically, so a worker starting at the same moment never reads half a file).
pub fn install(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::DirBuilderExt;
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    std::fs::DirBuilder::new().recursive(true).mode(0o700).create(dir)?;
    check_private(dir, false)?;
    if let Some(parent) = dir.parent() {
        check_private(parent, true)?;
    }
    for (name, text) in FILES {
        let path = dir.join(name);
        if std::fs::read(&path).is_ok_and(|old| old == text.as_bytes()) {
            continue;
        }
        // A name of its own for each writer, so two threads installing at once do not collide.
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, &path)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn installing_writes_both_files_once_and_mends_a_changed_one() {
        let dir = tempfile::tempdir().unwrap();
        install(dir.path()).unwrap();
        for (name, text) in FILES {
            assert_eq!(std::fs::read_to_string(dir.path().join(name)).unwrap(), text);
        }
        std::fs::write(dir.path().join(HOST_FILE), "tampered").unwrap();
        install(dir.path()).unwrap();
        assert_eq!(std::fs::read_to_string(dir.path().join(HOST_FILE)).unwrap(), FILES[0].1);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), FILES.len(), "no temporary file left");
    }

    #[test]
    fn a_folder_others_may_write_in_is_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let host = dir.path().join("host");
        std::fs::create_dir(&host).unwrap();
        std::fs::set_permissions(&host, std::fs::Permissions::from_mode(0o777)).unwrap();
        let e = install(&host).unwrap_err().to_string();
        assert!(e.contains("is not a folder only you can write in"), "{e}");
        std::fs::set_permissions(&host, std::fs::Permissions::from_mode(0o700)).unwrap();
        install(&host).unwrap();
    }

    #[test]
    fn every_python_file_of_the_host_folder_is_compiled_in() {
        let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("host");
        let mut on_disk: Vec<String> =
            std::fs::read_dir(folder).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        on_disk.retain(|n| n.ends_with(".py"));
        on_disk.sort();
        let mut embedded: Vec<String> = FILES.iter().map(|(n, _)| n.to_string()).collect();
        embedded.sort();
        assert_eq!(embedded, on_disk, "a module the worker imports would be missing from the folder it runs in");
    }
}
