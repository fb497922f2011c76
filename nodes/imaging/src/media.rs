//! What reading media needs whatever the container: the errors a reader reports, the default
//! frame rate, the fingerprint of the files read and the pixel budget. Image files and sequences
//! (`io`) and videos (`video`) both build on it; `io` hands a video path to `video`, so these live
//! below both rather than in `io` (which made the two modules import each other).

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use pyrograph_core::NodeError;
use pyrograph_core::fingerprint::{Fingerprinter, hash_metadata};

/// Frame rate of image sequences when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

/// An empty image clip: the default of optional clip inputs (imaging.write_exr_layers' extra
/// layers, the flipbooks' motion vectors).
pub fn no_images() -> pyrograph_core::ClipOf<std::sync::Arc<pyrograph_core::Image>> {
    pyrograph_core::ClipOf::new(pyrograph_core::Clip::from_frames(pyrograph_core::PortType::Image, 0.0, Vec::new()))
}

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
    /// Decoding or encoding a file failed, or anything else no port is for; the message names the
    /// file where there is one.
    #[error("{0}")]
    Message(String),
    /// Writing frame `frame` of a clip failed.
    #[error("frame {frame}: {source}")]
    Frame {
        /// Frame index within the clip.
        frame: usize,
        /// Why it failed.
        source: Box<IoError>,
    },
    /// A node error met on the way (a clip's frame that failed upstream, a cancelled cook),
    /// passed on as it is.
    #[error(transparent)]
    Other(#[from] NodeError),
}

/// The error of an [`IoError`] that names no port: its message, a failed frame as the node error
/// of that frame (once, however often it was wrapped), and a node error as it was.
impl From<IoError> for NodeError {
    fn from(e: IoError) -> NodeError {
        match e {
            IoError::Other(e) => e,
            IoError::Frame { frame, source } => match NodeError::from(*source) {
                e @ NodeError::Frame { .. } => e,
                e => NodeError::Frame { frame, source: Box::new(e) },
            },
            e => NodeError::msg(e.to_string()),
        }
    }
}

/// How a node turns an [`IoError`] into its own error, naming its ports. A video clip keeps its
/// loader's, for the errors of frames it decodes after the cook.
pub type ReportError = fn(IoError) -> NodeError;

/// Pixels an image file may declare and still be decoded: 16384 × 16384 unless `--max-pixels`
/// or the environment variable `PYROGRAPH_MAX_PIXELS` says otherwise (see
/// [`pyrograph_core::limits`]). A header is checked against it before any pixel is allocated, so
/// a small file declaring an enormous image (a decompression bomb) is an error naming the file
/// and its size, not an exhausted machine.
pub fn pixel_budget() -> u64 {
    pyrograph_core::limits::max_pixels()
}

/// The error for a file (an image, or a video's frames) declaring `w` × `h` pixels, when that is
/// more than [`pixel_budget`].
pub fn over_budget(path: &Path, w: u32, h: u32) -> Option<String> {
    let (pixels, budget) = (u64::from(w) * u64::from(h), pixel_budget());
    if pixels <= budget {
        return None;
    }
    // Megapixels, except for a budget set below one (a test's, or a tight service's).
    let amount = |px: u64| if px >= 1_000_000 { format!("{:.1} megapixels", px as f64 / 1e6) } else { format!("{px} pixels") };
    Some(format!(
        "{}: the file declares {w} × {h} pixels ({}), more than the {} pyrograph decodes; if it is a real \
         image, {}",
        path.display(),
        amount(pixels),
        amount(budget),
        pyrograph_core::limits::raise_hint("--max-pixels", "PYROGRAPH_MAX_PIXELS", pixels)
    ))
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

/// The shortest run of frames a thread takes when a clip of `n` frames is read in parallel: two
/// runs per thread. A video decodes forward: threads taking turns on neighbouring frames send
/// reads behind the decoder, which starts again from the last keyframe.
pub fn long_runs(n: usize) -> usize {
    n.div_ceil(2 * rayon::current_num_threads()).max(1)
}
