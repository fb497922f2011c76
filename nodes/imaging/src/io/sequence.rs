//! Sequences of image files: frame-number patterns (`frame_####.png`, `frame_%04d.png`), finding
//! a loader's files, the lazy clip that decodes them on demand, and the parallel sequence writer.

use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};

use pyrograph_core::document::write_atomic;
use pyrograph_core::{Clip, CookCtx, FrameSet, FrameSource, NodeError, PortType, Value};
use rayon::prelude::*;

use super::files::{OutputFormat, decode_image, encode_image, image_dimensions};
use super::{DEFAULT_FPS, IMAGE_EXTENSIONS, IoError, ReportError, VIDEO_EXTENSIONS, fingerprint_files, has_extension, no_such};
use crate::color::{AlphaMode, premultiply};

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

pyrograph_core::choice! {
    /// What a numbered image sequence with missing numbers gives.
    pub enum Gaps {
        /// Refuse it, listing the missing numbers: a dropped frame would otherwise shift every
        /// later frame's time.
        Error = "error",
        /// Repeat the frame before each gap, so every frame keeps its number's time.
        Hold = "hold",
    }
}

/// Resolves a loader path: a directory, a `####` / `%04d` pattern, a video or a single image. A
/// numbered sequence (a pattern, or a folder whose images differ only in their number) with
/// missing numbers between its first and last is refused or held, as `gaps` says.
pub fn find_input_files(path: &Path, gaps: Gaps) -> Result<InputFiles, IoError> {
    pyrograph_core::limits::may_read(path).map_err(IoError::Path)?;
    if path.is_dir() {
        let files = list_directory(path)?;
        return match numbered_files(&files) {
            Some(numbered) => fill_gaps(numbered, gaps, path).map(InputFiles::Images),
            None => Ok(InputFiles::Images(files)),
        };
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    if let Some(pattern) = FramePattern::parse(name).map_err(IoError::Path)? {
        return fill_gaps(list_pattern_numbered(path, &pattern)?, gaps, path).map(InputFiles::Images);
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

/// The image files of a directory, in natural name order: those of its most common image type,
/// so a reference still or a thumbnail beside the frames (a TIFF beside DPX scans, a JPEG beside
/// PNGs) is not read as a frame.
pub fn list_directory(dir: &Path) -> Result<Vec<PathBuf>, IoError> {
    let entries = std::fs::read_dir(dir).map_err(|e| IoError::Path(format!("{}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> =
        entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_file() && has_extension(p, IMAGE_EXTENSIONS)).collect();
    // One type, two spellings: .jpg and .jpeg, .tif and .tiff.
    let kind = |p: &PathBuf| match p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("jpeg") => "jpg".to_string(),
        Some("tiff") => "tif".to_string(),
        other => other.unwrap_or_default().to_string(),
    };
    let mut counts: Vec<(String, usize)> = Vec::new();
    for f in &files {
        match counts.iter_mut().find(|(k, _)| *k == kind(f)) {
            Some((_, n)) => *n += 1,
            None => counts.push((kind(f), 1)),
        }
    }
    // The most files; a tie goes to the type listed first in IMAGE_EXTENSIONS.
    let rank = |k: &str| IMAGE_EXTENSIONS.iter().position(|e| *e == k).unwrap_or(usize::MAX);
    if let Some((main, _)) = counts.iter().min_by_key(|(k, n)| (std::cmp::Reverse(*n), rank(k))) {
        let main = main.clone();
        files.retain(|f| kind(f) == main);
    }
    files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    if files.is_empty() {
        return Err(IoError::Path(format!(
            "{} holds no image files (looked for {})",
            dir.display(),
            IMAGE_EXTENSIONS.join(", ")
        )));
    }
    Ok(files)
}

/// The existing files matching `pattern` in the folder of `path`, by frame number.
pub fn list_pattern(path: &Path, pattern: &FramePattern) -> Result<Vec<PathBuf>, IoError> {
    Ok(list_pattern_numbered(path, pattern)?.into_iter().map(|(_, p)| p).collect())
}

/// [`list_pattern`] with each file's frame number.
/// The existing files matching `pattern` in the folder of `path`, with their frame numbers, in order.
pub fn list_pattern_numbered(path: &Path, pattern: &FramePattern) -> Result<Vec<(u64, PathBuf)>, IoError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(no_such(dir));
    }
    let entries = std::fs::read_dir(dir).map_err(|e| IoError::Path(format!("{}: {e}", dir.display())))?;
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
        return Err(IoError::Path(format!("no files match {}", path.display())));
    }
    Ok(numbered)
}

/// The frame numbers of a folder's images when they form one numbered sequence: every name is
/// the same text around its last run of digits (`frame_0007.png`). `None` for other folders.
fn numbered_files(files: &[PathBuf]) -> Option<Vec<(u64, PathBuf)>> {
    let mut frame: Option<(String, String)> = None;
    let mut out = Vec::with_capacity(files.len());
    for f in files {
        let name = f.file_name()?.to_str()?;
        let end = name.rfind(|c: char| c.is_ascii_digit())? + 1;
        let start = name[..end].rfind(|c: char| !c.is_ascii_digit()).map_or(0, |i| i + 1);
        let around = (name[..start].to_string(), name[end..].to_string());
        if frame.get_or_insert_with(|| around.clone()) != &around {
            return None;
        }
        out.push((name[start..end].parse().ok()?, f.clone()));
    }
    out.sort();
    Some(out)
}

/// The files of a numbered sequence in frame order, from its first number to its last: refused
/// when numbers are missing (`Gaps::Error`, naming them), or each gap filled with the frame before
/// it (`Gaps::Hold`).
pub fn fill_gaps(numbered: Vec<(u64, PathBuf)>, gaps: Gaps, path: &Path) -> Result<Vec<PathBuf>, IoError> {
    let missing = missing_ranges(&numbered.iter().map(|(n, _)| *n).collect::<Vec<_>>());
    if missing.is_empty() {
        return Ok(numbered.into_iter().map(|(_, p)| p).collect());
    }
    if gaps == Gaps::Error {
        let count: u64 = missing.iter().map(|(a, b)| b - a + 1).sum();
        let list: Vec<String> = missing.iter().map(|&(a, b)| if a == b { a.to_string() } else { format!("{a}-{b}") }).collect();
        let (first, last) = (numbered[0].0, numbered[numbered.len() - 1].0);
        let (what, them) = if count == 1 {
            (format!("frame {} is", list[0]), "it")
        } else {
            (format!("frames {} are", list.join(", ")), "them")
        };
        return Err(IoError::Path(format!(
            "{}: {what} missing ({count} of the numbers {first}-{last}); render or copy {them}, or set gaps \
             to hold to repeat the frame before each gap",
            path.display()
        )));
    }
    let mut out = Vec::new();
    let mut next = numbered[0].0;
    for (n, file) in numbered {
        // Numbers below `next` cannot happen (sorted, distinct); `n > next` is a gap to hold over.
        while next < n {
            out.push(out.last().cloned().unwrap_or_else(|| file.clone()));
            next += 1;
        }
        out.push(file);
        next = n + 1;
    }
    Ok(out)
}

/// The missing numbers between the first and last of sorted, distinct `numbers`, as inclusive ranges.
fn missing_ranges(numbers: &[u64]) -> Vec<(u64, u64)> {
    numbers.windows(2).filter(|w| w[1] > w[0] + 1).map(|w| (w[0] + 1, w[1] - 1)).collect()
}

/// Reads every file's header (in parallel; `layer` of OpenEXR files) and checks that all frames
/// share one size.
pub fn check_same_size(files: &[PathBuf], layer: &str) -> Result<(u32, u32), IoError> {
    let sizes: Vec<Result<(u32, u32), IoError>> = files.par_iter().map(|f| image_dimensions(f, layer)).collect();
    let mut first: Option<((u32, u32), &PathBuf)> = None;
    for (size, file) in sizes.into_iter().zip(files) {
        let size = size.map_err(|e| IoError::Path(e.to_string()))?;
        match first {
            None => first = Some((size, file)),
            Some((want, first_file)) if want != size => {
                return Err(IoError::Path(format!(
                    "{} is {}x{} but {} is {}x{}; all frames of a sequence must have the same size",
                    file.display(),
                    size.0,
                    size.1,
                    first_file.display(),
                    want.0,
                    want.1
                )));
            }
            Some(_) => {}
        }
    }
    first.map(|(s, _)| s).ok_or_else(|| IoError::Path("no image files".to_string()))
}

/// Frames decoded lazily from a list of image files.
struct FileFrames {
    files: Vec<PathBuf>,
    size: (u32, u32),
    /// The OpenEXR layer to read ("" = the main one).
    layer: String,
}

impl FrameSource for FileFrames {
    fn len(&self) -> usize {
        self.files.len()
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        let file = self.files.get(index).ok_or_else(|| NodeError::msg(format!("no frame {index}")))?;
        let img = decode_image(file, &self.layer)?;
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

/// A lazy clip of image files (`layer` of OpenEXR files, "" the main one) after checking every
/// header; frames decode on access.
pub fn image_sequence_clip(files: Vec<PathBuf>, fps: f64, layer: &str) -> Result<Clip, IoError> {
    let size = check_same_size(&files, layer)?;
    let mut fingerprint = fingerprint_files(&files)?;
    if !layer.is_empty() {
        let mut h = pyrograph_core::fingerprint::Fingerprinter::new();
        std::hash::Hash::hash(&(fingerprint, layer), &mut h);
        fingerprint = std::hash::Hasher::finish(&h);
    }
    let layer = layer.to_string();
    Ok(Clip::new(PortType::Image, fps, fingerprint, Arc::new(FileFrames { files, size, layer })))
}

/// How [`open_sequence`] reads what it finds.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceOptions {
    /// Frames per second; 0 = automatic (the video's rate, else [`DEFAULT_FPS`]).
    pub fps: f64,
    /// What to do about missing numbers in a numbered sequence.
    pub gaps: Gaps,
    /// The layer of OpenEXR files to read; "" = the main (unnamed) layer.
    pub layer: String,
}

impl Default for SequenceOptions {
    fn default() -> Self {
        SequenceOptions { fps: 0.0, gaps: Gaps::Error, layer: String::new() }
    }
}

/// Opens `path` (folder, pattern, image or video) as a clip. A video's frames decode after this
/// returns: their errors reach the user through `report`.
pub fn open_sequence(path: &Path, options: &SequenceOptions, ctx: &CookCtx, report: ReportError) -> Result<Clip, IoError> {
    match find_input_files(path, options.gaps)? {
        InputFiles::Video(_) if !options.layer.is_empty() => Err(IoError::Path(format!(
            "{}: layer '{}' was asked for, but a video has no layers (only OpenEXR files do)",
            path.display(),
            options.layer
        ))),
        InputFiles::Video(video) => crate::video::video_clip(&video, options.fps, ctx, report),
        InputFiles::Images(files) => {
            image_sequence_clip(files, if options.fps > 0.0 { options.fps } else { DEFAULT_FPS }, &options.layer)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Writing sequences
// ---------------------------------------------------------------------------------------------

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
    /// Clip frames to write; every frame when `None`.
    pub frames: Option<FrameSet>,
    /// Leave frames whose files exist alone instead of refusing or replacing them.
    pub skip_existing: bool,
    /// Alpha convention of the files (frames are straight in memory; gray frames have no alpha).
    pub alpha: AlphaMode,
}

/// The parsed pattern of a writer path, with the folder it writes into.
pub fn output_pattern(pattern: &Path) -> Result<(PathBuf, FramePattern), IoError> {
    let name = pattern
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| IoError::Path(format!("'{}' does not end in a file name like frame_####.png", pattern.display())))?;
    let parsed = FramePattern::parse(name)
        .map_err(IoError::Path)?
        .ok_or_else(|| IoError::Path(format!("'{name}' has no frame-number placeholder; add #### or %04d (frame_####.png)")))?;
    let dir = pattern.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok((dir, parsed))
}

/// The clip frames to write, ascending: the requested set (checked against the clip) or all.
pub fn frames_to_write(len: usize, frames: Option<&FrameSet>) -> Result<Vec<usize>, IoError> {
    if len == 0 {
        return Err(IoError::EmptyClip);
    }
    match frames {
        None => Ok((0..len).collect()),
        Some(set) if set.last() < len => Ok(set.frames()),
        Some(set) => Err(IoError::Message(format!("frames {set} reach past the clip's frames 0-{}", len - 1))),
    }
}

/// Writes the frames of `clip` as files; returns the paths written, in frame order.
///
/// Nothing is written when any target exists and `overwrite` is off.
pub fn write_sequence(clip: &Clip, options: &WriteOptions, ctx: &CookCtx) -> Result<Vec<PathBuf>, IoError> {
    write_frames(clip.len(), options, ctx, |i| {
        let img = clip.image(i, ctx)?;
        match options.alpha {
            AlphaMode::Straight => encode_image(&img, options.format),
            AlphaMode::Premultiplied => encode_image(&premultiply(&img), options.format),
        }
    })
}

/// Writes `len` frames as files named by `options.pattern` (its format and alpha are the caller's
/// to apply in `encode`, which makes frame `i`'s bytes): the render's frame range or every frame,
/// in parallel, each file atomically; returns the paths written, in frame order. Nothing is
/// written when any target exists and `overwrite` is off.
pub fn write_frames(
    len: usize,
    options: &WriteOptions,
    ctx: &CookCtx,
    encode: impl Fn(usize) -> Result<Vec<u8>, IoError> + Sync,
) -> Result<Vec<PathBuf>, IoError> {
    let (dir, pattern) = output_pattern(&options.pattern)?;
    let frames = frames_to_write(len, options.frames.as_ref())?;
    let mut targets: Vec<(usize, PathBuf)> =
        frames.into_iter().map(|i| (i, dir.join(pattern.file_name(options.start + i as u64)))).collect();
    if options.skip_existing {
        // Existing files are whole (every write is atomic) and belong to this render's output.
        targets.retain(|(_, p)| {
            let exists = p.exists();
            if exists {
                ctx.record_written(p);
            }
            !exists
        });
    } else if !options.overwrite {
        refuse_existing(&targets)?;
    }
    if !dir.as_os_str().is_empty() {
        std::fs::create_dir_all(&dir).map_err(|e| IoError::Path(format!("cannot create {}: {e}", dir.display())))?;
    }
    let done = AtomicUsize::new(0);
    // Frames go in windows of two per thread, in order: at most that many are in flight, and a
    // simulation upstream is asked for its frames in order (it steps through them once, the other
    // threads waiting for the frames it passes) while the frames it gave are encoded beside it.
    let window = 2 * rayon::current_num_threads().max(1);
    for chunk in targets.chunks(window) {
        chunk.par_iter().try_for_each(|(i, path)| {
            ctx.check_cancel()?;
            // The frame is named once, when the error becomes the node's (see `From<IoError>`).
            let bytes = encode(*i).map_err(|e| IoError::Frame { frame: *i, source: Box::new(e) })?;
            write_atomic(path, &bytes, options.overwrite)
                .map_err(|e| IoError::Message(format!("writing {}: {e}", path.display())))?;
            ctx.record_written(path);
            ctx.frame_progress(done.fetch_add(1, AtomicOrdering::Relaxed) + 1, targets.len());
            Ok::<(), IoError>(())
        })?;
    }
    Ok(targets.into_iter().map(|(_, p)| p).collect())
}

fn refuse_existing(targets: &[(usize, PathBuf)]) -> Result<(), IoError> {
    let existing: Vec<&PathBuf> = targets.iter().map(|(_, p)| p).filter(|p| p.exists()).collect();
    match existing.first() {
        None => Ok(()),
        Some(first) => Err(IoError::Exists(format!(
            "{} already exists ({} of the {} target files do); nothing was written. Set overwrite to true or \
             render with --overwrite to replace them",
            first.display(),
            existing.len(),
            targets.len()
        ))),
    }
}
