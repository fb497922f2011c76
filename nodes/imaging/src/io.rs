//! Image input and output: loaders for image sequences, single images and videos (through the
//! `ffmpeg` executables), and the PNG / OpenEXR sequence writer.

use std::cmp::Ordering;
use std::io::Cursor;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};

use exr::prelude::{SpecificChannels, Vec2, WritableImage as _, f16};
use image::{DynamicImage, ImageBuffer, ImageFormat, Luma};
use pyrograph_core::document::write_atomic;
use pyrograph_core::fingerprint::{Fingerprinter, hash_metadata};
use pyrograph_core::{
    Channels, Clip, CookCtx, FnNode, FrameSource, Image, Inputs, NodeDesc, NodeError, PathRole, PortDesc, PortType, Registry,
    TimeDep, Value,
};
use rayon::prelude::*;
use std::hash::{Hash, Hasher};

use crate::color::{AlphaMode, premultiply};
use crate::convert;

/// Adds the loaders and the sequence writer.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(load_sequence_desc(), cook_load_sequence));
    registry.add(FnNode::new(load_image_desc(), cook_load_image));
    registry.add(FnNode::new(write_sequence_desc(), cook_write_sequence));
    registry.add(FnNode::new(write_image_desc(), cook_write_image));
}

/// Extensions (lower case) of the still-image files the loaders read.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr"];

/// Extensions (lower case) of the video files read through `ffmpeg`.
pub const VIDEO_EXTENSIONS: &[&str] = &["mp4", "mov", "avi", "mkv", "webm", "m4v"];

/// Frame rate of image sequences when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

// ---------------------------------------------------------------------------------------------
// Frame-number patterns
// ---------------------------------------------------------------------------------------------

/// A file name with one frame-number placeholder: `frame_####.png` or `frame_%04d.png`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {
    /// Text before the number.
    pub prefix: String,
    /// Zero-padding width (the number of `#`, or the `04` of `%04d`; 0 for `%d`).
    pub width: usize,
    /// Text after the number, extension included.
    pub suffix: String,
}

impl FramePattern {
    /// Parses a file name; `Ok(None)` when it has no placeholder, `Err` when it has several.
    pub fn parse(name: &str) -> Result<Option<FramePattern>, String> {
        let Some((start, end, width)) = find_placeholder(name) else {
            return Ok(None);
        };
        let suffix = &name[end..];
        if find_placeholder(suffix).is_some() {
            return Err(format!("'{name}' has more than one frame-number placeholder; use exactly one (#### or %04d)"));
        }
        Ok(Some(FramePattern { prefix: name[..start].to_string(), width, suffix: suffix.to_string() }))
    }

    /// The file name of frame `number`.
    pub fn file_name(&self, number: u64) -> String {
        format!("{}{:0width$}{}", self.prefix, number, self.suffix, width = self.width)
    }

    /// The frame number a file name carries, when it matches the pattern (same padding).
    pub fn number_of(&self, name: &str) -> Option<u64> {
        let digits = name.strip_prefix(&self.prefix)?.strip_suffix(&self.suffix)?;
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        // A longer number is only the same padding when it did not need padding at all.
        let padded_alike = digits.len() == self.width || (digits.len() > self.width && !digits.starts_with('0'));
        if self.width > 0 && !padded_alike {
            return None;
        }
        digits.parse().ok()
    }
}

/// `(start, end, width)` of the first `###` run or `%0Nd` in `name`.
fn find_placeholder(name: &str) -> Option<(usize, usize, usize)> {
    let hashes = name.find('#').map(|s| {
        let run = name[s..].bytes().take_while(|&b| b == b'#').count();
        (s, s + run, run)
    });
    let printf = name.match_indices('%').find_map(|(s, _)| {
        let rest = &name[s + 1..];
        let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        (rest.as_bytes().get(digits) == Some(&b'd')).then(|| (s, s + digits + 2, rest[..digits].parse().unwrap_or(0)))
    });
    match (hashes, printf) {
        (Some(h), Some(p)) => Some(if h.0 < p.0 { h } else { p }),
        (h, p) => h.or(p),
    }
}

/// Compares file names so that `frame_2` sorts before `frame_10`.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    natural_chunks(a).cmp(&natural_chunks(b)).then_with(|| a.cmp(b))
}

#[derive(PartialEq, Eq, PartialOrd, Ord)]
enum Chunk<'a> {
    Number(u128),
    Text(&'a str),
}

fn natural_chunks(s: &str) -> Vec<Chunk<'_>> {
    let mut chunks = Vec::new();
    let mut rest = s;
    while let Some(first) = rest.chars().next() {
        let is_digit = first.is_ascii_digit();
        let len = rest.find(|c: char| c.is_ascii_digit() != is_digit).unwrap_or(rest.len());
        let (head, tail) = rest.split_at(len);
        chunks.push(match head.parse() {
            Ok(n) if is_digit => Chunk::Number(n),
            _ => Chunk::Text(head),
        });
        rest = tail;
    }
    chunks
}

// ---------------------------------------------------------------------------------------------
// Finding the input files
// ---------------------------------------------------------------------------------------------

/// What a loader's `path` names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum InputFiles {
    /// Still images, in frame order.
    Images(Vec<PathBuf>),
    /// One video file.
    Video(PathBuf),
}

fn has_extension(path: &Path, list: &[&str]) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| list.contains(&e.to_ascii_lowercase().as_str()))
}

fn no_such(path: &Path) -> NodeError {
    NodeError::port("path", format!("{}: no such file or directory", path.display()))
}

/// Resolves a loader path: a directory, a `####` / `%04d` pattern, a video or a single image.
pub fn find_input_files(path: &Path) -> Result<InputFiles, NodeError> {
    if path.is_dir() {
        return list_directory(path).map(InputFiles::Images);
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    if let Some(pattern) = FramePattern::parse(name).map_err(|e| NodeError::port("path", e))? {
        return list_pattern(path, &pattern).map(InputFiles::Images);
    }
    if !path.is_file() {
        return Err(no_such(path));
    }
    if has_extension(path, VIDEO_EXTENSIONS) {
        Ok(InputFiles::Video(path.to_path_buf()))
    } else {
        Ok(InputFiles::Images(vec![path.to_path_buf()]))
    }
}

/// The image files of a directory, in natural name order.
pub fn list_directory(dir: &Path) -> Result<Vec<PathBuf>, NodeError> {
    let entries = std::fs::read_dir(dir).map_err(|e| NodeError::port("path", format!("{}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> =
        entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_file() && has_extension(p, IMAGE_EXTENSIONS)).collect();
    files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    if files.is_empty() {
        return Err(NodeError::port(
            "path",
            format!("{} holds no image files (looked for {})", dir.display(), IMAGE_EXTENSIONS.join(", ")),
        ));
    }
    Ok(files)
}

/// The existing files matching `pattern` in the folder of `path`, by frame number.
pub fn list_pattern(path: &Path, pattern: &FramePattern) -> Result<Vec<PathBuf>, NodeError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(no_such(dir));
    }
    let entries = std::fs::read_dir(dir).map_err(|e| NodeError::port("path", format!("{}: {e}", dir.display())))?;
    let mut numbered: Vec<(u64, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter_map(|p| {
            let n = pattern.number_of(p.file_name()?.to_str()?)?;
            Some((n, p))
        })
        .collect();
    numbered.sort();
    if numbered.is_empty() {
        return Err(NodeError::port("path", format!("no files match {}", path.display())));
    }
    Ok(numbered.into_iter().map(|(_, p)| p).collect())
}

/// Hash of file names, sizes and modification times: changes whenever a file is replaced.
pub fn fingerprint_files(files: &[PathBuf]) -> Result<u64, NodeError> {
    let mut h = Fingerprinter::new();
    for f in files {
        let meta = std::fs::metadata(f).map_err(|e| NodeError::port("path", format!("{}: {e}", f.display())))?;
        f.hash(&mut h);
        hash_metadata(&mut h, &meta);
    }
    Ok(h.finish())
}

// ---------------------------------------------------------------------------------------------
// Reading still images
// ---------------------------------------------------------------------------------------------

fn is_exr(path: &Path) -> bool {
    has_extension(path, &["exr"])
}

/// Width and height from the file's header, without decoding the pixels.
pub fn image_dimensions(path: &Path) -> Result<(u32, u32), NodeError> {
    let named = |e: &dyn std::fmt::Display| NodeError::msg(format!("{}: {e}", path.display()));
    if is_exr(path) {
        // The exr crate, not `image`, so gray (`Y`) files written by the writer read back too.
        let meta = exr::prelude::MetaData::read_from_file(path, false).map_err(|e| named(&e))?;
        let header = meta.headers.first().ok_or_else(|| named(&"no image layer"))?;
        let size = header.layer_size;
        return Ok((to_u32(size.0, path)?, to_u32(size.1, path)?));
    }
    image::ImageReader::open(path)
        .map_err(|e| named(&e))?
        .with_guessed_format()
        .map_err(|e| named(&e))?
        .into_dimensions()
        .map_err(|e| named(&e))
}

fn to_u32(v: usize, path: &Path) -> Result<u32, NodeError> {
    u32::try_from(v).map_err(|_| NodeError::msg(format!("{}: image too large ({v} pixels wide or high)", path.display())))
}

/// Decodes one image file: colour files become RGBA, gray files gray.
pub fn decode_image(path: &Path) -> Result<Image, NodeError> {
    if is_exr(path) {
        return decode_exr(path);
    }
    let named = |e: &dyn std::fmt::Display| NodeError::msg(format!("{}: {e}", path.display()));
    let img = image::ImageReader::open(path)
        .map_err(|e| named(&e))?
        .with_guessed_format()
        .map_err(|e| named(&e))?
        .decode()
        .map_err(|e| named(&e))?;
    Ok(convert::from_dynamic(img))
}

/// Decodes the first layer of an OpenEXR file: `Y` only → gray, else R, G, B (and A, default 1).
pub fn decode_exr(path: &Path) -> Result<Image, NodeError> {
    let named = |e: &dyn std::fmt::Display| NodeError::msg(format!("{}: {e}", path.display()));
    let file = exr::prelude::read_first_flat_layer_from_file(path).map_err(|e| named(&e))?;
    let layer = &file.layer_data;
    let (w, h) = (to_u32(layer.size.0, path)?, to_u32(layer.size.1, path)?);
    let pixels = w as usize * h as usize;
    // Subsampled channels (chroma) hold fewer samples than pixels; they are treated as absent.
    let channel = |name: &str| -> Option<Vec<f32>> {
        let c = layer.channel_data.list.iter().find(|c| c.name.eq(name))?;
        let samples: Vec<f32> = c.sample_data.values_as_f32().collect();
        (samples.len() == pixels).then_some(samples)
    };
    let image = match (channel("R"), channel("G"), channel("B"), channel("Y")) {
        (Some(r), Some(g), Some(b), _) => {
            let a = channel("A").unwrap_or_else(|| vec![1.0; pixels]);
            let data = (0..pixels).flat_map(|i| [r[i], g[i], b[i], a[i]]).collect();
            Image::from_vec(w, h, Channels::Rgba, data)
        }
        (_, _, _, Some(y)) => Image::from_vec(w, h, Channels::Gray, y),
        _ => return Err(named(&"has neither R, G, B nor Y channels")),
    };
    image.ok_or_else(|| named(&"channel sizes do not match the image size"))
}

/// Reads every file's header (in parallel) and checks that all frames share one size.
pub fn check_same_size(files: &[PathBuf]) -> Result<(u32, u32), NodeError> {
    let sizes: Vec<Result<(u32, u32), NodeError>> = files.par_iter().map(|f| image_dimensions(f)).collect();
    let mut first: Option<((u32, u32), &PathBuf)> = None;
    for (size, file) in sizes.into_iter().zip(files) {
        let size = size.map_err(|e| NodeError::port("path", e.to_string()))?;
        match first {
            None => first = Some((size, file)),
            Some((want, first_file)) if want != size => {
                return Err(NodeError::port(
                    "path",
                    format!(
                        "{} is {}x{} but {} is {}x{}; all frames of a sequence must have the same size",
                        file.display(),
                        size.0,
                        size.1,
                        first_file.display(),
                        want.0,
                        want.1
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    first.map(|(s, _)| s).ok_or_else(|| NodeError::port("path", "no image files"))
}

/// Frames decoded lazily from a list of image files.
struct FileFrames {
    files: Vec<PathBuf>,
    size: (u32, u32),
}

impl FrameSource for FileFrames {
    fn len(&self) -> usize {
        self.files.len()
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        let file = self.files.get(index).ok_or_else(|| NodeError::msg(format!("no frame {index}")))?;
        let img = decode_image(file)?;
        // The file may have been replaced since the headers were checked.
        if img.size() != self.size {
            return Err(NodeError::msg(format!(
                "{} is {}x{} but the sequence is {}x{}",
                file.display(),
                img.width(),
                img.height(),
                self.size.0,
                self.size.1
            )));
        }
        Ok(Value::Image(Arc::new(img)))
    }
}

/// A lazy clip of image files after checking every header; frames decode on access.
pub fn image_sequence_clip(files: Vec<PathBuf>, fps: f64) -> Result<Clip, NodeError> {
    let size = check_same_size(&files)?;
    let fingerprint = fingerprint_files(&files)?;
    Ok(Clip::new(PortType::Image, fps, fingerprint, Arc::new(FileFrames { files, size })))
}

// ---------------------------------------------------------------------------------------------
// imaging.load_sequence / imaging.load_image
// ---------------------------------------------------------------------------------------------

fn load_sequence_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.load_sequence",
        "Input/Output",
        TimeDep::Source,
        "Loads an image sequence or a video as a clip.\n\n`path` is a folder (every .png/.jpg/.jpeg/.exr file, in \
         natural name order), a pattern (`frame_####.png` or `frame_%04d.png`: the existing files, by number), a \
         single image (a one-frame clip) or a video (.mp4 .mov .avi .mkv .webm .m4v, decoded with ffmpeg). Every \
         file's header is checked when the node cooks; frames decode on demand. Colour files give RGBA frames, \
         gray files gray frames.",
    )
    .input(PortDesc::path("path", PathRole::Input, None, "Folder, frame pattern, image file or video file."))
    .input(PortDesc::float("fps", 0.0, (0.0, 1000.0), "Frames per second; 0 = the video's rate, else 24."))
    .output("clip", PortType::clip_of(PortType::Image), "The frames.")
}

/// Loads `path` (folder, pattern, image or video) as a clip; `fps` 0 means automatic.
pub fn load_sequence(path: &Path, fps: f64, ctx: &CookCtx) -> Result<Clip, NodeError> {
    match find_input_files(path)? {
        InputFiles::Video(video) => crate::video::video_clip(&video, fps, ctx),
        InputFiles::Images(files) => image_sequence_clip(files, if fps > 0.0 { fps } else { DEFAULT_FPS }),
    }
}

fn cook_load_sequence(i: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let clip = load_sequence(i.path("path")?, i.float("fps")?, ctx)?;
    Ok(vec![Value::Clip(clip)])
}

fn load_image_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.load_image",
        "Input/Output",
        TimeDep::Source,
        "Loads one image file (.png, .jpg, .jpeg or .exr).\n\nColour files give an RGBA image, gray files a gray image.",
    )
    .input(PortDesc::path("path", PathRole::Input, None, "The image file."))
    .output("image", PortType::Image, "The image.")
}

/// Loads one image file; errors name the file.
pub fn load_image(path: &Path) -> Result<Image, NodeError> {
    if path.is_dir() {
        return Err(NodeError::port(
            "path",
            format!("{} is a folder; give one image file, or use imaging.load_sequence", path.display()),
        ));
    }
    if !path.is_file() {
        return Err(no_such(path));
    }
    image_dimensions(path).map_err(|e| NodeError::port("path", e.to_string()))?;
    decode_image(path).map_err(|e| NodeError::port("path", e.to_string()))
}

fn cook_load_image(i: &Inputs<'_>, _ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Image(Arc::new(load_image(i.path("path")?)?))])
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
pub fn encode_image(img: &Image, format: OutputFormat) -> Result<Vec<u8>, NodeError> {
    match format {
        OutputFormat::Png { sixteen_bit } => encode_png(img, sixteen_bit),
        OutputFormat::Exr { half } => encode_exr(img, half),
    }
}

// `write_to` encodes with image's default PNG settings, the png crate's `Compression::Fast` with
// adaptive filters: a writer's cost stays near the decoder's (benches/stream/run.sh, BENCHMARKS.md).
fn encode_png(img: &Image, sixteen_bit: bool) -> Result<Vec<u8>, NodeError> {
    let (w, h) = img.size();
    let dynamic = match (img.channels(), sixteen_bit) {
        (Channels::Gray, false) => DynamicImage::ImageLuma8(convert::to_gray8(img)),
        (Channels::Gray, true) => {
            let data = img.data().iter().map(|&v| unit_to_u16(v)).collect();
            let buf: ImageBuffer<Luma<u16>, Vec<u16>> =
                ImageBuffer::from_raw(w, h, data).ok_or_else(|| NodeError::msg("image data does not match its size"))?;
            DynamicImage::ImageLuma16(buf)
        }
        (Channels::Rgba, false) => DynamicImage::ImageRgba8(convert::to_rgba8(img)),
        (Channels::Rgba, true) => DynamicImage::ImageRgba16(convert::to_rgba16(img)),
    };
    let mut bytes = Vec::new();
    dynamic.write_to(&mut Cursor::new(&mut bytes), ImageFormat::Png).map_err(|e| NodeError::msg(format!("encoding PNG: {e}")))?;
    Ok(bytes)
}

/// 0..1 float to a 16-bit sample, clamped and rounded (as `convert::to_rgba16`).
fn unit_to_u16(v: f32) -> u16 {
    (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
}

fn encode_exr(img: &Image, half: bool) -> Result<Vec<u8>, NodeError> {
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
            exr::image::Image::from_channels((w, h), pixels).write().to_buffered(cursor)
        }
        (Channels::Gray, false) => {
            let pixels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|p: Vec2<usize>| (sample(p.0, p.1, 0),));
            exr::image::Image::from_channels((w, h), pixels).write().to_buffered(cursor)
        }
        (Channels::Rgba, true) => {
            let px = |p: Vec2<usize>| {
                let s = |c| f16::from_f32(sample(p.0, p.1, c));
                (s(0), s(1), s(2), s(3))
            };
            exr::image::Image::from_channels((w, h), SpecificChannels::rgba(px)).write().to_buffered(cursor)
        }
        (Channels::Rgba, false) => {
            let px = |p: Vec2<usize>| (sample(p.0, p.1, 0), sample(p.0, p.1, 1), sample(p.0, p.1, 2), sample(p.0, p.1, 3));
            exr::image::Image::from_channels((w, h), SpecificChannels::rgba(px)).write().to_buffered(cursor)
        }
    };
    result.map_err(|e| NodeError::msg(format!("encoding EXR: {e}")))?;
    Ok(bytes)
}

// ---------------------------------------------------------------------------------------------
// imaging.write_sequence
// ---------------------------------------------------------------------------------------------

fn write_sequence_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.write_sequence",
        "Input/Output",
        TimeDep::Sink,
        "Writes a clip as a numbered PNG or OpenEXR sequence.\n\nThe pattern's `####` (or `%04d`) is the zero-padded \
         frame number and its extension picks the format. Writes the render's frame range (`--frames`) or every \
         frame, in parallel, each file atomically; refuses to replace existing files unless `overwrite` is on. \
         `alpha` writes RGBA frames with straight or premultiplied alpha; the `alpha` output states which.",
    )
    .input(PortDesc::new("clip", PortType::clip_of(PortType::Image), "The frames to write."))
    .input(PortDesc::path(
        "pattern",
        PathRole::Output,
        Some("frame_####.png"),
        "Output files: `####` or `%04d` is the frame number; .png or .exr.",
    ))
    .input(PortDesc::choice("bit_depth", &["8", "16"], "8", "Bits per channel of PNG files."))
    .input(PortDesc::choice("exr_type", &["half", "float"], "half", "Sample type of EXR files."))
    .input(PortDesc::int("start", 0, (0, 999_999_999), "File number of the clip's frame 0 (frame i is written as start + i)."))
    .input(PortDesc::bool("overwrite", false, "Replace files that already exist."))
    .input(PortDesc::choice(
        "alpha",
        &["straight", "premultiplied"],
        "straight",
        "Alpha convention of RGBA files: straight (PNG's own) or premultiplied (colour × alpha, usual for EXR).",
    ))
    .output("frames", PortType::Int, "How many files were written.")
    .output("first", PortType::Path, "The first file written.")
    .output("alpha", PortType::String, "The alpha convention of the files written (straight or premultiplied).")
}

/// What and where [`write_sequence`] writes.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteOptions {
    /// Output path whose file name holds the frame-number placeholder.
    pub pattern: PathBuf,
    /// PNG or EXR flavour.
    pub format: OutputFormat,
    /// File number of the clip's frame 0.
    pub start: u64,
    /// Replace existing files.
    pub overwrite: bool,
    /// Inclusive range of clip frames to write; every frame when `None`.
    pub frames: Option<(usize, usize)>,
    /// Alpha convention of the files (frames are straight in memory; gray frames have no alpha).
    pub alpha: AlphaMode,
}

/// The parsed pattern of a writer path, with the folder it writes into.
pub fn output_pattern(pattern: &Path) -> Result<(PathBuf, FramePattern), NodeError> {
    let name = pattern.file_name().and_then(|n| n.to_str()).ok_or_else(|| {
        NodeError::port("pattern", format!("'{}' does not end in a file name like frame_####.png", pattern.display()))
    })?;
    let parsed = FramePattern::parse(name).map_err(|e| NodeError::port("pattern", e))?.ok_or_else(|| {
        NodeError::port("pattern", format!("'{name}' has no frame-number placeholder; add #### or %04d (frame_####.png)"))
    })?;
    let dir = pattern.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok((dir, parsed))
}

/// The format named by the pattern's extension, with the PNG / EXR options.
pub fn output_format(pattern: &Path, bit_depth: &str, exr_type: &str) -> Result<OutputFormat, NodeError> {
    let ext = pattern.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    match ext.as_str() {
        "png" => match bit_depth {
            "8" | "16" => Ok(OutputFormat::Png { sixteen_bit: bit_depth == "16" }),
            other => Err(NodeError::port("bit_depth", format!("'{other}' is not 8 or 16"))),
        },
        "exr" => match exr_type {
            "half" | "float" => Ok(OutputFormat::Exr { half: exr_type == "half" }),
            other => Err(NodeError::port("exr_type", format!("'{other}' is not half or float"))),
        },
        _ => Err(NodeError::port("pattern", format!("'{}' must end in .png or .exr", pattern.display()))),
    }
}

/// The clip frames to write: the requested inclusive range (checked) or all of them.
pub fn frames_to_write(len: usize, frames: Option<(usize, usize)>) -> Result<Range<usize>, NodeError> {
    if len == 0 {
        return Err(NodeError::port("clip", "the clip has no frames"));
    }
    match frames {
        None => Ok(0..len),
        Some((a, b)) if a <= b && b < len => Ok(a..b + 1),
        Some((a, b)) => Err(NodeError::msg(format!("frame range {a}-{b} is outside the clip's frames 0-{}", len - 1))),
    }
}

/// Writes the frames of `clip` as files; returns the paths written, in frame order.
///
/// Nothing is written when any target exists and `overwrite` is off.
pub fn write_sequence(clip: &Clip, options: &WriteOptions, ctx: &CookCtx) -> Result<Vec<PathBuf>, NodeError> {
    let (dir, pattern) = output_pattern(&options.pattern)?;
    let range = frames_to_write(clip.len(), options.frames)?;
    let targets: Vec<(usize, PathBuf)> = range.map(|i| (i, dir.join(pattern.file_name(options.start + i as u64)))).collect();
    if !options.overwrite {
        refuse_existing(&targets)?;
    }
    if !dir.as_os_str().is_empty() {
        std::fs::create_dir_all(&dir).map_err(|e| NodeError::port("pattern", format!("cannot create {}: {e}", dir.display())))?;
    }
    let done = AtomicUsize::new(0);
    targets.par_iter().try_for_each(|(i, path)| {
        ctx.check_cancel()?;
        let img = clip.image(*i, ctx).map_err(|e| NodeError::Frame { frame: *i, source: Box::new(e) })?;
        let bytes = match options.alpha {
            AlphaMode::Straight => encode_image(&img, options.format)?,
            AlphaMode::Premultiplied => encode_image(&premultiply(&img), options.format)?,
        };
        write_atomic(path, &bytes, options.overwrite).map_err(|e| NodeError::msg(format!("writing {}: {e}", path.display())))?;
        ctx.frame_progress(done.fetch_add(1, AtomicOrdering::Relaxed) + 1, targets.len());
        Ok::<(), NodeError>(())
    })?;
    Ok(targets.into_iter().map(|(_, p)| p).collect())
}

fn refuse_existing(targets: &[(usize, PathBuf)]) -> Result<(), NodeError> {
    let existing: Vec<&PathBuf> = targets.iter().map(|(_, p)| p).filter(|p| p.exists()).collect();
    match existing.first() {
        None => Ok(()),
        Some(first) => Err(NodeError::port(
            "overwrite",
            format!(
                "{} already exists ({} of the {} target files do); nothing was written. Set overwrite to true or \
                 render with --overwrite to replace them",
                first.display(),
                existing.len(),
                targets.len()
            ),
        )),
    }
}

fn cook_write_sequence(i: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let pattern = i.path("pattern")?.to_path_buf();
    let options = WriteOptions {
        format: output_format(&pattern, i.choice("bit_depth")?, i.choice("exr_type")?)?,
        start: i.usize("start")? as u64,
        overwrite: i.bool("overwrite")? || ctx.settings().overwrite,
        frames: ctx.settings().frames,
        alpha: AlphaMode::parse(i.choice("alpha")?, "alpha")?,
        pattern,
    };
    let written = write_sequence(i.clip("clip")?, &options, ctx)?;
    let first = written.first().cloned().unwrap_or_default();
    Ok(vec![Value::Int(written.len() as i64), Value::Path(first), Value::String(options.alpha.name().to_string())])
}

fn write_image_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.write_image",
        "Input/Output",
        TimeDep::Sink,
        "Writes one image (a still, a contact sheet) as a PNG or OpenEXR file.",
    )
    .input(PortDesc::new("image", PortType::Image, "The image to write."))
    .input(PortDesc::path(
        "path",
        PathRole::Output,
        Some("image.png"),
        "Output file; the extension (.png or .exr) picks the format.",
    ))
    .input(PortDesc::choice("bit_depth", &["8", "16"], "8", "Bits per channel of PNG files."))
    .input(PortDesc::choice("exr_type", &["half", "float"], "half", "Sample type of EXR files."))
    .input(PortDesc::bool("overwrite", false, "Replace the file if it already exists."))
    .output("path", PortType::Path, "The file written.")
}

/// Writes one image atomically; an existing file is an error unless `overwrite`.
pub fn write_image(img: &Image, path: &Path, format: OutputFormat, overwrite: bool) -> Result<(), NodeError> {
    if !overwrite && path.exists() {
        return Err(NodeError::port(
            "overwrite",
            format!("{} already exists; nothing was written. Set overwrite to true or render with --overwrite", path.display()),
        ));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| NodeError::port("path", format!("cannot create {}: {e}", dir.display())))?;
    }
    let bytes = encode_image(img, format)?;
    write_atomic(path, &bytes, overwrite).map_err(|e| NodeError::port("path", format!("writing {}: {e}", path.display())))
}

fn cook_write_image(i: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let path = i.path("path")?.to_path_buf();
    let format = output_format(&path, i.choice("bit_depth")?, i.choice("exr_type")?)
        .map_err(|e| if let NodeError::Port { message, .. } = e { NodeError::port("path", message) } else { e })?;
    write_image(i.image("image")?, &path, format, i.bool("overwrite")? || ctx.settings().overwrite)?;
    Ok(vec![Value::Path(path)])
}

#[cfg(test)]
#[path = "io_tests.rs"]
mod tests;
