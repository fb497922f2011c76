//! Image input and output: loaders for image sequences, single images and videos (through the
//! `ffmpeg` executables), and the PNG / OpenEXR sequence writer.
//!
//! Split by topic: [`files`] decodes and encodes one image file and writes it atomically,
//! [`sequence`] finds a sequence's files by folder or frame-number pattern, serves them as a lazy
//! clip and writes clips as numbered files, and [`nodes`] declares the node types on top of both.

pub mod files;
pub mod nodes;
pub mod sequence;

use std::path::Path;

use pyrograph_core::NodeError;

pub use files::*;
pub use nodes::*;
pub use sequence::*;

/// Extensions (lower case) of the still-image files the loaders read.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr"];

/// Extensions (lower case) of the video files read through `ffmpeg`.
pub const VIDEO_EXTENSIONS: &[&str] = &["mp4", "mov", "avi", "mkv", "webm", "m4v"];

/// Frame rate of image sequences when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

fn has_extension(path: &Path, list: &[&str]) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| list.contains(&e.to_ascii_lowercase().as_str()))
}

/// The error for a path that does not exist, on the loader port `port`.
fn no_such(port: &str, path: &Path) -> NodeError {
    NodeError::port(port, format!("{}: no such file or directory", path.display()))
}

#[cfg(test)]
mod tests;
