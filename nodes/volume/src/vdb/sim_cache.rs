//! A simulation's frames cached as VDB files between the two steps of a farm job: `pyrograph
//! simulate` steps every `volume.simulate` node once and writes each frame here, and a render
//! with `--sim-cache` reads the frames back instead of stepping, so each chunk of a farm render
//! needs no simulation of its own (Houdini's File Cache "load from disk", done by the CLI).
//!
//! The files are exact (32-bit float grids, uncompressed) and hold every field and statistic of
//! the volume, so a render from the cache is byte-identical to one that simulates.

use std::path::{Path, PathBuf};

use pyrograph_core::document::write_atomic;
use pyrograph_core::{CookCtx, FrameSource, NodeError, Value};

use super::nodes::load_vdb_file;
use super::write::{Compression, WriteOptions, write_volume};
use crate::grid::Volume;

/// The cache folder's name for a node id: an include's path separator and anything a file name
/// should not hold become `_` (`fire/sim` → `fire_sim`).
pub fn cache_name(node_id: &str) -> String {
    node_id.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// The file of frame `frame` (0-based) of simulation `node_id` in the cache folder `dir`.
pub fn cache_file(dir: &Path, node_id: &str, frame: usize) -> PathBuf {
    let name = cache_name(node_id);
    dir.join(&name).join(format!("{name}.{frame:04}.vdb"))
}

/// Writes frame `frame` of simulation `node_id` into the cache (atomically, replacing an older
/// file: the cache folder is pyrograph's own).
pub fn write_cache_frame(dir: &Path, node_id: &str, frame: usize, volume: &Volume) -> Result<PathBuf, String> {
    let path = cache_file(dir, node_id, frame);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    }
    let options = WriteOptions { fields: Vec::new(), half: false, compression: Compression::None };
    let bytes = write_volume(volume, &options).map_err(|e| format!("{}: {e}", path.display()))?;
    write_atomic(&path, &bytes, true).map_err(|e| format!("writing {}: {e}", path.display()))?;
    Ok(path)
}

/// A simulation's frames read from its cache folder, file `i` for frame `i`.
pub(crate) struct CachedFrames {
    /// The cache folder.
    pub dir: PathBuf,
    /// The simulation node's id.
    pub node: String,
    /// Frames in the clip.
    pub frames: usize,
}

impl FrameSource for CachedFrames {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, _: &CookCtx) -> Result<Value, NodeError> {
        let path = cache_file(&self.dir, &self.node, index);
        if !path.is_file() {
            return Err(NodeError::msg(format!(
                "frame {index} of the simulation is not in the cache: {} does not exist. Cache it first with \
                 `pyrograph simulate GRAPH --sim-cache {}` (a farm job's Simulate step), with the same --set and --frames",
                path.display(),
                self.dir.display()
            )));
        }
        let (v, _) = load_vdb_file(&path).map_err(NodeError::msg)?;
        Ok(Value::custom(std::sync::Arc::new(v)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_keep_letters_digits_dashes_and_underscores() {
        assert_eq!(cache_name("fire/sim"), "fire_sim");
        assert_eq!(cache_name("smoke-2"), "smoke-2");
        assert_eq!(cache_file(Path::new("/c"), "a/b", 7), Path::new("/c/a_b/a_b.0007.vdb"));
    }
}
