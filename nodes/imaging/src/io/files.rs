//! One image file: reading its header and pixels (PNG, JPEG, TIFF, DPX, OpenEXR), encoding an image as PNG
//! or OpenEXR bytes, and writing a file atomically.

use std::io::Cursor;
use std::path::Path;

use exr::prelude::{SpecificChannels, Vec2, WritableImage as _, f16};
use image::{DynamicImage, ImageBuffer, ImageFormat, Luma};
use pyrograph_core::document::write_atomic;
use pyrograph_core::{Channels, Image};

use super::{IoError, has_extension, no_such};
use crate::convert;
use crate::media::over_budget;

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
// Reading still images
// ---------------------------------------------------------------------------------------------

fn is_exr(path: &Path) -> bool {
    has_extension(path, &["exr"])
}

/// Refuses a header that declares more pixels than [`pixel_budget`](crate::media::pixel_budget).
fn check_budget(path: &Path, (w, h): (u32, u32)) -> Result<(u32, u32), IoError> {
    match over_budget(path, w, h) {
        Some(m) => Err(IoError::Message(m)),
        None => Ok((w, h)),
    }
}

/// Width and height from the file's header (of `layer`, for OpenEXR; "" is the main layer),
/// without decoding the pixels; a size over the [`pixel_budget`](crate::media::pixel_budget) is an error.
pub fn image_dimensions(path: &Path, layer: &str) -> Result<(u32, u32), IoError> {
    header_dimensions(path, layer).and_then(|size| check_budget(path, size))
}

fn header_dimensions(path: &Path, layer: &str) -> Result<(u32, u32), IoError> {
    // Every decode passes here first: a file outside the read roots is not opened.
    pyrograph_core::limits::may_read(path).map_err(IoError::Message)?;
    let named = |e: &dyn std::fmt::Display| IoError::Message(format!("{}: {e}", path.display()));
    if is_exr(path) {
        // The exr crate, not `image`, so gray (`Y`) files and layers other than the first read too.
        // Reading a layer decodes every part of the file: each is held to the budget.
        for (w, h) in super::exr_layers::exr_part_sizes(path)? {
            check_budget(path, (w, h))?;
        }
        return super::exr_layers::exr_dimensions(path, layer);
    }
    if !layer.is_empty() {
        return Err(named(&format!("layer '{layer}' was asked for, but only OpenEXR files have layers")));
    }
    if has_extension(path, &["dpx"]) {
        return super::dpx::dpx_dimensions(path);
    }
    image::ImageReader::open(path)
        .map_err(|e| named(&e))?
        .with_guessed_format()
        .map_err(|e| named(&e))?
        .into_dimensions()
        .map_err(|e| named(&e))
}

/// Decodes one image file (`layer` of an OpenEXR file; "" is its main layer): colour files become
/// RGBA, gray files gray. Its header is checked against the [`pixel_budget`](crate::media::pixel_budget) first (decoders
/// allocate what a header declares).
pub fn decode_image(path: &Path, layer: &str) -> Result<Image, IoError> {
    let (w, h) = image_dimensions(path, layer)?;
    if is_exr(path) {
        return super::exr_layers::decode_exr_layer(path, layer);
    }
    if has_extension(path, &["dpx"]) {
        return super::dpx::decode_dpx(path, (w, h));
    }
    let named = |e: &dyn std::fmt::Display| IoError::Message(format!("{}: {e}", path.display()));
    let mut reader = image::ImageReader::open(path).map_err(|e| named(&e))?.with_guessed_format().map_err(|e| named(&e))?;
    // The image crate's own allocation limit (512 MiB by default) would refuse a plate within
    // the budget (16-bit RGBA at 8192 × 8192 is 512 MiB): allow what the budget allows.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some((u64::from(w) * u64::from(h) * 8).max(512 << 20));
    reader.limits(limits);
    let img = reader.decode().map_err(|e| named(&e))?;
    Ok(convert::from_dynamic(img))
}

/// Loads one image file after checking its header; every error names the file and is an
/// [`IoError::Path`].
pub fn read_image_file(path: &Path, layer: &str) -> Result<Image, IoError> {
    pyrograph_core::limits::may_read(path).map_err(IoError::Path)?;
    if path.is_dir() {
        return Err(IoError::Path(format!("{} is a folder; give one image file, or use imaging.load_sequence", path.display())));
    }
    if !path.is_file() {
        return Err(no_such(path));
    }
    decode_image(path, layer).map_err(|e| IoError::Path(e.to_string()))
}

// ---------------------------------------------------------------------------------------------
// Encoding
// ---------------------------------------------------------------------------------------------

/// A file format the writer produces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// PNG, 8 or 16 bits per channel (values clamped to 0..1).
    Png {
        /// Whether to write 16-bit samples.
        sixteen_bit: bool,
    },
    /// OpenEXR, half or full float (HDR values kept).
    Exr {
        /// Whether to write 16-bit half floats instead of 32-bit floats.
        half: bool,
    },
}

/// Encodes an image into the bytes of a file: gray images stay one-channel (PNG L8/L16, EXR `Y`).
pub fn encode_image(img: &Image, format: OutputFormat) -> Result<Vec<u8>, IoError> {
    match format {
        OutputFormat::Png { sixteen_bit } => encode_png(img, sixteen_bit),
        OutputFormat::Exr { half } => encode_exr(img, half),
    }
}

// `write_to` encodes with image's default PNG settings, the png crate's `Compression::Fast` with
// adaptive filters: a writer's cost stays near the decoder's (benches/stream/run.sh, BENCHMARKS.md).
fn encode_png(img: &Image, sixteen_bit: bool) -> Result<Vec<u8>, IoError> {
    let (w, h) = img.size();
    let dynamic = match (img.channels(), sixteen_bit) {
        (Channels::Gray, false) => DynamicImage::ImageLuma8(convert::to_gray8(img)),
        (Channels::Gray, true) => {
            let data = img.data().iter().map(|&v| unit_to_u16(v)).collect();
            let buf: ImageBuffer<Luma<u16>, Vec<u16>> =
                ImageBuffer::from_raw(w, h, data).ok_or_else(|| IoError::Message("image data does not match its size".into()))?;
            DynamicImage::ImageLuma16(buf)
        }
        (Channels::Rgba, false) => DynamicImage::ImageRgba8(convert::to_rgba8(img)),
        (Channels::Rgba, true) => DynamicImage::ImageRgba16(convert::to_rgba16(img)),
    };
    let mut bytes = Vec::new();
    dynamic
        .write_to(&mut Cursor::new(&mut bytes), ImageFormat::Png)
        .map_err(|e| IoError::Message(format!("encoding PNG: {e}")))?;
    Ok(bytes)
}

/// 0..1 float to a 16-bit sample, clamped and rounded (as `convert::to_rgba16`).
fn unit_to_u16(v: f32) -> u16 {
    (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

/// Chunks are compressed one after another (`non_parallel`): in parallel, the exr crate writes them
/// in the order they finish, so one frame rendered twice gave two different files with the same
/// pixels, and a farm could not check outputs by their hash. Writers already encode several frames
/// at once, which keeps the cores busy.
fn encode_exr(img: &Image, half: bool) -> Result<Vec<u8>, IoError> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let n = img.channels().count();
    let data = img.data();
    let sample = move |x: usize, y: usize, c: usize| data.get((y * w + x) * n + c).copied().unwrap_or(0.0);
    let mut bytes = Vec::new();
    let cursor = Cursor::new(&mut bytes);
    let result = match (img.channels(), half) {
        (Channels::Gray, true) => {
            let pixels =
                SpecificChannels::build().with_channel("Y").with_pixel_fn(|p: Vec2<usize>| (f16::from_f32(sample(p.0, p.1, 0)),));
            exr::image::Image::from_channels((w, h), pixels).write().non_parallel().to_buffered(cursor)
        }
        (Channels::Gray, false) => {
            let pixels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|p: Vec2<usize>| (sample(p.0, p.1, 0),));
            exr::image::Image::from_channels((w, h), pixels).write().non_parallel().to_buffered(cursor)
        }
        (Channels::Rgba, true) => {
            let px = |p: Vec2<usize>| {
                let s = |c| f16::from_f32(sample(p.0, p.1, c));
                (s(0), s(1), s(2), s(3))
            };
            exr::image::Image::from_channels((w, h), SpecificChannels::rgba(px)).write().non_parallel().to_buffered(cursor)
        }
        (Channels::Rgba, false) => {
            let px = |p: Vec2<usize>| (sample(p.0, p.1, 0), sample(p.0, p.1, 1), sample(p.0, p.1, 2), sample(p.0, p.1, 3));
            exr::image::Image::from_channels((w, h), SpecificChannels::rgba(px)).write().non_parallel().to_buffered(cursor)
        }
    };
    result.map_err(|e| IoError::Message(format!("encoding EXR: {e}")))?;
    Ok(bytes)
}

/// The format named by the pattern's extension, with the PNG / EXR options; an unknown extension
/// is an [`IoError::Path`].
pub fn output_format(pattern: &Path, bit_depth: BitDepth, exr_type: ExrType) -> Result<OutputFormat, IoError> {
    let ext = pattern.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    match ext.as_str() {
        "png" => Ok(OutputFormat::Png { sixteen_bit: bit_depth == BitDepth::Sixteen }),
        "exr" => Ok(OutputFormat::Exr { half: exr_type == ExrType::Half }),
        _ => Err(IoError::Path(format!("'{}' must end in .png or .exr", pattern.display()))),
    }
}

/// Writes one image atomically; an existing file is an [`IoError::Exists`] unless `overwrite`.
pub fn write_image_file(img: &Image, path: &Path, format: OutputFormat, overwrite: bool) -> Result<(), IoError> {
    if !overwrite && path.exists() {
        return Err(IoError::Exists(format!(
            "{} already exists; nothing was written. Set overwrite to true or render with --overwrite",
            path.display()
        )));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| IoError::Path(format!("cannot create {}: {e}", dir.display())))?;
    }
    let bytes = encode_image(img, format)?;
    write_atomic(path, &bytes, overwrite).map_err(|e| IoError::Path(format!("writing {}: {e}", path.display())))
}
