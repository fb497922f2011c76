//! The input/output node types: the loaders and writers of [`super::files`] and
//! [`super::sequence`] as declared nodes.

use std::sync::Arc;

use pyrograph_core::{ClipOf, Cook, CookCtx, Image, InputPath, NodeError, OutputPath, Registry};

use super::files::{load_image, output_format, write_image};
use super::sequence::{WriteOptions, load_sequence, write_sequence};
use crate::color::AlphaMode;

/// Adds the loaders and the sequence writer.
pub fn register(registry: &mut Registry) {
    registry.add(LoadSequence::node());
    registry.add(LoadImage::node());
    registry.add(WriteSequence::node());
    registry.add(WriteImage::node());
}

pyrograph_core::choice! {
    /// Bits per channel of PNG files.
    pub enum BitDepth {
        /// 8-bit samples.
        Eight = "8",
        /// 16-bit samples.
        Sixteen = "16",
    }
}

pyrograph_core::choice! {
    /// Sample type of EXR files.
    pub enum ExrType {
        /// 16-bit half floats.
        Half = "half",
        /// 32-bit floats.
        Float = "float",
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.load_sequence / imaging.load_image
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Loads an image sequence or a video as a clip.
    ///
    /// `path` is a folder (every .png/.jpg/.jpeg/.exr file, in natural name order), a pattern (`frame_####.png` or
    /// `frame_%04d.png`: the existing files, by number), a single image (a one-frame clip) or a video (.mp4 .mov .avi
    /// .mkv .webm .m4v, decoded with ffmpeg). Every file's header is checked when the node cooks; frames decode on
    /// demand. Colour files give RGBA frames, gray files gray frames.
    #[node("imaging.load_sequence", "Input/Output", Source)]
    pub struct LoadSequence {
        /// Folder, frame pattern, image file or video file.
        path: InputPath,
        /// Frames per second; 0 = the video's rate, else 24.
        #[range(0.0, 1000.0)]
        fps: f64 = 0.0,
    }
    pub struct LoadSequenceOut {
        /// The frames.
        clip: ClipOf<Arc<Image>>,
    }
}

impl Cook for LoadSequence {
    fn cook(self, ctx: &CookCtx) -> Result<LoadSequenceOut, NodeError> {
        Ok(LoadSequenceOut { clip: ClipOf::new(load_sequence(&self.path, self.fps, ctx)?) })
    }
}

pyrograph_core::node! {
    /// Loads one image file (.png, .jpg, .jpeg or .exr).
    ///
    /// Colour files give an RGBA image, gray files a gray image.
    #[node("imaging.load_image", "Input/Output", Source)]
    pub struct LoadImage {
        /// The image file.
        path: InputPath,
    }
    pub struct LoadImageOut {
        /// The image.
        image: Arc<Image>,
    }
}

impl Cook for LoadImage {
    fn cook(self, _: &CookCtx) -> Result<LoadImageOut, NodeError> {
        Ok(LoadImageOut { image: Arc::new(load_image(&self.path)?) })
    }
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
            format: output_format(&self.pattern, self.bit_depth, self.exr_type)?,
            start: self.start,
            overwrite: self.overwrite || ctx.settings().overwrite,
            frames: ctx.settings().frames.clone(),
            skip_existing: ctx.settings().skip_existing,
            alpha: self.alpha,
            pattern: self.pattern.0,
        };
        let written = write_sequence(&self.clip, &options, ctx)?;
        Ok(WriteSequenceOut {
            frames: written.len(),
            first: OutputPath(written.first().cloned().unwrap_or_default()),
            alpha: options.alpha.name().to_string(),
        })
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
    pub struct WriteImageOut {
        /// The file written.
        path: OutputPath,
    }
}

impl Cook for WriteImage {
    fn cook(self, ctx: &CookCtx) -> Result<WriteImageOut, NodeError> {
        // The format error names the sequence writer's `pattern`; here the file is `path`.
        let format = output_format(&self.path, self.bit_depth, self.exr_type).map_err(|e| match e {
            NodeError::Port { message, .. } => NodeError::port(pyrograph_core::port!(WriteImage, path), message),
            e => e,
        })?;
        write_image(&self.image, &self.path, format, self.overwrite || ctx.settings().overwrite)?;
        ctx.record_written(&self.path);
        Ok(WriteImageOut { path: self.path })
    }
}
