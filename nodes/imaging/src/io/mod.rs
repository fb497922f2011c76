//! Image input and output: loaders for image sequences, single images and videos (through the
//! `ffmpeg` executables), and the PNG / OpenEXR sequence writer.
//!
//! Split by topic: [`files`] decodes and encodes one image file and writes it atomically,
//! [`sequence`] finds a sequence's files by folder or frame-number pattern, serves them as a lazy
//! clip and writes clips as numbered files, and [`nodes`] declares the node types on top of both.
//! The functions of `files` and `sequence` report an [`IoError`] that says what a problem concerns;
//! the nodes name the port. [`load_image`] and [`write_image`] are the nodes' work as plain
//! functions for callers outside a graph; [`LoadSequence::load`] loads a sequence as the node does
//! (its video frames decode later, so their errors need the node's ports).

pub mod dpx;
pub mod exr_layers;
pub mod files;
pub mod nodes;
pub mod sequence;
pub mod write_layers;

use std::path::Path;

pub use crate::media::{DEFAULT_FPS, IoError, ReportError, fingerprint_files, over_budget, pixel_budget};
pub use files::*;
pub use nodes::*;
pub use sequence::*;

/// Extensions (lower case) of the still-image files the loaders read.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr", "tif", "tiff", "dpx"];

/// Extensions (lower case) of the video files read through `ffmpeg`.
pub const VIDEO_EXTENSIONS: &[&str] = &["mp4", "mov", "avi", "mkv", "webm", "m4v"];

fn has_extension(path: &Path, list: &[&str]) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| list.contains(&e.to_ascii_lowercase().as_str()))
}

/// The error for a path that does not exist.
fn no_such(path: &Path) -> IoError {
    IoError::Path(format!("{}: no such file or directory", path.display()))
}

#[cfg(test)]
mod tests;
