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

/// The folder the two files are written to: the user's cache folder (`XDG_CACHE_HOME`, else
/// `~/.cache`), else the temporary folder.
pub fn default_dir() -> PathBuf {
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").filter(|p| !p.is_empty()).map(|h| Path::new(&h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    let tag: String = digest()[..6].iter().map(|b| format!("{b:02x}")).collect();
    cache.join("pyrograph").join(format!("python-host-{tag}"))
}

/// Writes the files into `dir` unless they are already there with the same text (each replaced
/// atomically, so a worker starting at the same moment never reads half a file).
pub fn install(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for (name, text) in FILES {
        let path = dir.join(name);
        if std::fs::read(&path).is_ok_and(|old| old == text.as_bytes()) {
            continue;
        }
        let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
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
