//! Image input and output: loaders for image sequences, single images and videos (through the
//! `ffmpeg` executables), and the PNG / OpenEXR sequence writer.
//!
//! Split by topic: [`files`] decodes and encodes one image file and writes it atomically,
//! [`sequence`] finds a sequence's files by folder or frame-number pattern, serves them as a lazy
//! clip and writes clips as numbered files, and [`nodes`] declares the node types on top of both.
//! The functions of `files` and `sequence` report an [`IoError`] that says what a problem concerns;
//! the nodes name the port. [`load_image`], [`load_sequence`] and [`write_image`] are the nodes'
//! cooks as plain functions, for callers outside a graph.

pub mod dpx;
pub mod exr_layers;
pub mod files;
pub mod nodes;
pub mod sequence;
pub mod write_layers;

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use pyrograph_core::NodeError;
use pyrograph_core::fingerprint::{Fingerprinter, hash_metadata};

pub use files::*;
pub use nodes::*;
pub use sequence::*;

/// Extensions (lower case) of the still-image files the loaders read.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr", "tif", "tiff", "dpx"];

/// Extensions (lower case) of the video files read through `ffmpeg`.
pub const VIDEO_EXTENSIONS: &[&str] = &["mp4", "mov", "avi", "mkv", "webm", "m4v"];

/// Frame rate of image sequences when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

/// Why reading or writing image files failed, by what the problem concerns; the node that read or
/// wrote turns it into a [`NodeError`] on the matching port.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IoError {
    /// The file, folder or pattern read or written.
    #[error("{0}")]
    Path(String),
    /// A file to write exists and replacing it was not asked for.
    #[error("{0}")]
    Exists(String),
    /// The clip to write has no frames.
    #[error("the clip has no frames")]
    EmptyClip,
    /// Anything else (decoding, encoding, a frame that failed, a cancelled cook): already a node
    /// error, passed on as it is.
    #[error(transparent)]
    Other(#[from] NodeError),
}

/// How a node turns an [`IoError`] into its own error, naming its ports. A video clip keeps its
/// loader's, for the errors of frames it decodes after the cook.
pub type ReportError = fn(IoError) -> NodeError;

fn has_extension(path: &Path, list: &[&str]) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| list.contains(&e.to_ascii_lowercase().as_str()))
}

/// The error for a path that does not exist.
fn no_such(path: &Path) -> IoError {
    IoError::Path(format!("{}: no such file or directory", path.display()))
}

/// Hash of file names, sizes and modification times: changes whenever a file is replaced.
pub fn fingerprint_files(files: &[PathBuf]) -> Result<u64, IoError> {
    let mut h = Fingerprinter::new();
    for f in files {
        let meta = std::fs::metadata(f).map_err(|e| IoError::Path(format!("{}: {e}", f.display())))?;
        f.hash(&mut h);
        hash_metadata(&mut h, &meta);
    }
    Ok(h.finish())
}

#[cfg(test)]
mod tests;
