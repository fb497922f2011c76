//! Content fingerprints that key the evaluator's cache.

use std::collections::hash_map::DefaultHasher;
use std::fs::Metadata;
use std::hash::{Hash, Hasher};
use std::path::Path;
use std::time::UNIX_EPOCH;

/// A deterministic 64-bit hasher (SipHash with fixed keys), stable within one build of pyrograph.
#[derive(Clone, Debug, Default)]
pub struct Fingerprinter(DefaultHasher);

impl Fingerprinter {
    /// A fresh hasher.
    pub fn new() -> Self {
        Fingerprinter(DefaultHasher::new())
    }
}

impl Hasher for Fingerprinter {
    fn finish(&self) -> u64 {
        self.0.finish()
    }
    fn write(&mut self, bytes: &[u8]) {
        self.0.write(bytes)
    }
}

/// Hashes float samples by their bit patterns, as one byte slice (much faster than per-float calls).
pub fn hash_f32s(h: &mut Fingerprinter, data: &[f32]) {
    h.write(bytemuck::cast_slice(data));
}

/// Hashes what changes when a file is replaced or rewritten: its size and modification time.
pub fn hash_metadata(h: &mut Fingerprinter, meta: &Metadata) {
    meta.len().hash(h);
    let mtime = meta.modified().ok().and_then(|t| t.duration_since(UNIX_EPOCH).ok()).map(|d| d.as_nanos());
    mtime.hash(h);
}

/// Hashes how `path` looks on disk now, so that a node reading it re-cooks when it changes
/// (the path alone would keep serving the old content from the cache). A file gives its size and
/// modification time; a folder (a frame sequence, a database) the names, sizes and times of its
/// entries; a path that names nothing (a frame pattern such as `frames/f_####.png`) its folder.
pub fn hash_path_on_disk(h: &mut Fingerprinter, path: &Path) {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => hash_folder(h, path),
        Ok(meta) => hash_metadata(h, &meta),
        Err(_) => match path.parent() {
            Some(dir) if dir.is_dir() => hash_folder(h, dir),
            _ => "missing".hash(h),
        },
    }
}

/// The folder's entries, not recursive, in name order (`read_dir`'s order is unspecified).
fn hash_folder(h: &mut Fingerprinter, dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return "unreadable".hash(h) };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).map(|e| (e.file_name(), e.metadata().ok())).collect();
    entries.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, meta) in &entries {
        name.hash(h);
        if let Some(meta) = meta {
            hash_metadata(h, meta);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamp(path: &Path) -> u64 {
        let mut h = Fingerprinter::new();
        hash_path_on_disk(&mut h, path);
        h.finish()
    }

    #[test]
    fn a_rewritten_file_a_new_frame_and_a_pattern_change_the_stamp() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f_0001.png");
        std::fs::write(&file, b"one").unwrap();
        let (file_stamp, dir_stamp) = (stamp(&file), stamp(dir.path()));
        let pattern = dir.path().join("f_####.png");
        let pattern_stamp = stamp(&pattern);
        assert_eq!(stamp(&file), file_stamp, "an untouched file keeps its stamp");
        assert_eq!(stamp(dir.path()), dir_stamp);

        std::fs::write(&file, b"three").unwrap();
        assert_ne!(stamp(&file), file_stamp, "a rewritten file");
        assert_ne!(stamp(dir.path()), dir_stamp, "a rewritten file in a folder");
        let (dir_stamp, pattern_stamp2) = (stamp(dir.path()), stamp(&pattern));
        assert_ne!(pattern_stamp2, pattern_stamp, "a rewritten frame of a pattern");

        std::fs::write(dir.path().join("f_0002.png"), b"two").unwrap();
        assert_ne!(stamp(dir.path()), dir_stamp, "a new frame in a folder");
        assert_ne!(stamp(&pattern), pattern_stamp2, "a new frame of a pattern");
        assert_eq!(stamp(&dir.path().join("no/such/file")), stamp(&dir.path().join("nor/this")));
    }
}
