//! The input/output node types: the loaders and writers of [`super::files`] and
//! [`super::sequence`] as declared nodes, whose cooks name the port each [`IoError`] concerns.

use std::path::Path;
use std::sync::Arc;

use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, Image, InputPath, NodeError, OutputPath, port};

use super::IoError;
use super::files::{BitDepth, ExrType, OutputFormat, output_format, read_image_file, write_image_file};
use super::sequence::{Gaps, SequenceOptions, WriteOptions, open_sequence, write_sequence};
use crate::color::AlphaMode;

// ---------------------------------------------------------------------------------------------
// imaging.load_sequence / imaging.load_image
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Loads an image sequence or a video as a clip.
    ///
    /// `path` is a folder (every .png/.jpg/.jpeg/.exr/.tif/.tiff/.dpx file, in natural name order), a pattern
    /// (`frame_####.dpx` or `frame_%04d.exr`: the existing files, by number), a single image (a one-frame clip) or a
    /// video (.mp4 .mov .avi .mkv .webm .m4v, decoded with ffmpeg). Every file's header is checked when the node
    /// cooks; frames decode on demand. Colour files give RGBA frames, gray files gray frames; 10- to 16-bit sources
    /// (TIFF, DPX, video) keep their precision. A video is turned as its rotation tag says, and one with a variable
    /// frame rate is resampled by timestamps to a constant rate, with a warning.
    #[node("imaging.load_sequence", "Input/Output", Source)]
    pub struct LoadSequence {
        /// Folder, frame pattern, image file or video file.
        path: InputPath,
        /// Frames per second; 0 = the video's rate, else 24.
        #[range(0.0, 1000.0)]
        fps: f64 = 0.0,
        /// A numbered sequence with missing numbers: error (list them) or hold (repeat the frame
        /// before each gap, so every frame keeps its number's time).
        gaps: Gaps = Gaps::Error,
        /// The layer of OpenEXR files to read (`diffuse`, `beauty.spec`…); empty = the main layer.
        layer: String = String::new(),
    }
    /// The frames.
    -> clip: ClipOf<Arc<Image>>
}

impl Cook for LoadSequence {
    fn cook(self, ctx: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        let options = SequenceOptions { fps: self.fps, gaps: self.gaps, layer: self.layer };
        let clip = open_sequence(&self.path, &options, ctx, LoadSequence::node_error);
        Ok(ClipOf::new(clip.map_err(LoadSequence::node_error)?))
    }
}

impl LoadSequence {
    /// The node error for `e`: loading fails only over the file, folder or pattern, its `path`.
    pub fn node_error(e: IoError) -> NodeError {
        match e {
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
            e => NodeError::port(port!(LoadSequence, path), e.to_string()),
        }
    }

    /// Loads `path` (folder, pattern, image or video) as the node does with its default `gaps`
    /// (a numbered sequence with missing numbers is an error), `fps` 0 meaning automatic; errors
    /// name its ports, those of a video's frames decoded later too.
    pub fn load(path: &Path, fps: f64, ctx: &CookCtx) -> Result<Clip, NodeError> {
        let options = SequenceOptions { fps, ..SequenceOptions::default() };
        open_sequence(path, &options, ctx, LoadSequence::node_error).map_err(LoadSequence::node_error)
    }
}

pyrograph_core::node! {
    /// Loads one image file (.png, .jpg, .jpeg, .tif, .tiff, .dpx or .exr).
    ///
    /// Colour files give an RGBA image, gray files a gray image; 16-bit and 10-bit files keep their precision.
    #[node("imaging.load_image", "Input/Output", Source)]
    pub struct LoadImage {
        /// The image file.
        path: InputPath,
        /// The layer of an OpenEXR file to read (`diffuse`, `beauty.spec`…); empty = the main layer.
        layer: String = String::new(),
    }
    /// The image.
    -> image: Arc<Image>
}

impl Cook for LoadImage {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(read_image_file(&self.path, &self.layer).map_err(LoadImage::node_error)?))
    }
}

impl LoadImage {
    /// The node error for `e`: loading fails only over the file, its `path`.
    pub fn node_error(e: IoError) -> NodeError {
        match e {
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
            e => NodeError::port(port!(LoadImage, path), e.to_string()),
        }
    }
}

/// Loads one image file (its main layer, for OpenEXR) as `imaging.load_image` does, for callers
/// outside a graph (which have no port to name); every error names the file.
pub fn load_image(path: &Path) -> Result<Image, IoError> {
    read_image_file(path, "")
}

// ---------------------------------------------------------------------------------------------
// imaging.write_sequence / imaging.write_image
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Writes a clip as a numbered PNG or OpenEXR sequence.
    ///
    /// The pattern's `####` (or `%04d`) is the zero-padded frame number and its extension picks the format. Writes
    /// the render's frame range (`--frames`) or every frame, in parallel, each file atomically; refuses to replace
    /// existing files unless `overwrite` is on. `alpha` writes RGBA frames with straight or premultiplied alpha; the
    /// `alpha` output states which.
    #[node("imaging.write_sequence", "Input/Output", Sink)]
    pub struct WriteSequence {
        /// The frames to write.
        clip: ClipOf<Arc<Image>>,
        /// Output files: `####` or `%04d` is the frame number; .png or .exr.
        pattern: OutputPath = "frame_####.png".into(),
        /// Bits per channel of PNG files.
        bit_depth: BitDepth = BitDepth::Eight,
        /// Sample type of EXR files.
        exr_type: ExrType = ExrType::Half,
        /// File number of the clip's frame 0 (frame i is written as start + i).
        #[range(0, 999_999_999)]
        start: u64 = 0,
        /// Replace files that already exist.
        overwrite: bool = false,
        /// Alpha convention of RGBA files: straight (PNG's own) or premultiplied (colour × alpha, usual for EXR).
        alpha: AlphaMode = AlphaMode::Straight,
    }
    pub struct WriteSequenceOut {
        /// How many files were written.
        frames: usize,
        /// The first file written.
        first: OutputPath,
        /// The alpha convention of the files written (straight or premultiplied).
        alpha: String,
    }
}

impl Cook for WriteSequence {
    fn cook(self, ctx: &CookCtx) -> Result<WriteSequenceOut, NodeError> {
        let options = WriteOptions {
            format: output_format(&self.pattern, self.bit_depth, self.exr_type).map_err(WriteSequence::node_error)?,
            start: self.start,
            overwrite: self.overwrite || ctx.settings().overwrite,
            frames: ctx.settings().frames.clone(),
            skip_existing: ctx.settings().skip_existing,
            alpha: self.alpha,
            pattern: self.pattern.0,
        };
        let written = write_sequence(&self.clip, &options, ctx).map_err(WriteSequence::node_error)?;
        Ok(WriteSequenceOut {
            frames: written.len(),
            first: OutputPath(written.first().cloned().unwrap_or_default()),
            alpha: options.alpha.name().to_string(),
        })
    }
}

impl WriteSequence {
    /// The node error for `e`: a problem with the files is one with the `pattern`, an existing
    /// file one for `overwrite`, an empty clip one with the `clip`.
    pub fn node_error(e: IoError) -> NodeError {
        match e {
            IoError::Path(message) => NodeError::port(port!(WriteSequence, pattern), message),
            IoError::Exists(message) => NodeError::port(port!(WriteSequence, overwrite), message),
            e @ IoError::EmptyClip => NodeError::port(port!(WriteSequence, clip), e.to_string()),
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
        }
    }
}

pyrograph_core::node! {
    /// Writes one image (a still, a contact sheet) as a PNG or OpenEXR file.
    #[node("imaging.write_image", "Input/Output", Sink)]
    pub struct WriteImage {
        /// The image to write.
        image: Arc<Image>,
        /// Output file; the extension (.png or .exr) picks the format.
        path: OutputPath = "image.png".into(),
        /// Bits per channel of PNG files.
        bit_depth: BitDepth = BitDepth::Eight,
        /// Sample type of EXR files.
        exr_type: ExrType = ExrType::Half,
        /// Replace the file if it already exists.
        overwrite: bool = false,
    }
    /// The file written.
    -> path: OutputPath
}

impl Cook for WriteImage {
    fn cook(self, ctx: &CookCtx) -> Result<OutputPath, NodeError> {
        let format = output_format(&self.path, self.bit_depth, self.exr_type).map_err(WriteImage::node_error)?;
        write_image_file(&self.image, &self.path, format, self.overwrite || ctx.settings().overwrite)
            .map_err(WriteImage::node_error)?;
        ctx.record_written(&self.path);
        Ok(self.path)
    }
}

impl WriteImage {
    /// The node error for `e`: an existing file is one for `overwrite`, any other problem with the
    /// file one with its `path`.
    pub fn node_error(e: IoError) -> NodeError {
        match e {
            IoError::Exists(message) => NodeError::port(port!(WriteImage, overwrite), message),
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
            e => NodeError::port(port!(WriteImage, path), e.to_string()),
        }
    }
}

/// Writes one image atomically as `imaging.write_image` does (an existing file is an
/// [`IoError::Exists`] unless `overwrite`), for callers outside a graph.
pub fn write_image(img: &Image, path: &Path, format: OutputFormat, overwrite: bool) -> Result<(), IoError> {
    write_image_file(img, path, format, overwrite)
}
