//! Flipbook sheets for game engines and compositors: a clip laid out in rows × columns (top-left
//! origin, left to right then top to bottom) with straight or premultiplied alpha, a matching
//! motion-vector sheet from a pyramidal Lucas–Kanade optical flow, and a writer that puts `_RxC`
//! into the file names and describes the sheet in a JSON side-car.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use image::imageops::FilterType;
use pyrograph_core::document::write_atomic;
use pyrograph_core::{Channels, ClipOf, Cook, CookCtx, Image, NodeError, OutputPath, port};
use rayon::prelude::*;

use crate::color::AlphaMode;
use crate::filters::Plane;
use crate::io::{BitDepth, ExrType, IoError, OutputFormat, output_format, write_image_file};
use crate::media::no_images;
use crate::resize::{ResizeError, resize};

mod engine;
mod flow;
mod layout;

pub use engine::{Convention, MotionCode, SheetGeometry};
pub use flow::{MIN_CONTENT, MIN_EIGENVALUE, optical_flow};
pub use layout::{Fill, Layout, MAX_MIP_LEVELS, cell_origin, check_cells, layout, nearest_power_of_two, paste};

/// Largest number of rows or columns.
pub const MAX_CELLS_PER_SIDE: i64 = 64;

pyrograph_core::ports! {
    /// How a flipbook is laid out: the ports of both flipbook nodes after their clip.
    #[derive(Copy, PartialEq)]
    pub struct FlipbookOptions {
        /// Rows of cells
        #[range(1, MAX_CELLS_PER_SIDE)]
        rows: usize = 8,
        /// Columns of cells
        #[range(1, MAX_CELLS_PER_SIDE)]
        cols: usize = 8,
        /// Transparent pixels around each frame inside its cell
        #[range(0, 256)]
        padding: u32 = 0,
        /// Scale cells so both sheet sides are the nearest power of two
        power_of_two: bool = false,
        /// Alpha convention of the colour sheet
        alpha: AlphaMode = AlphaMode::Straight,
        /// Motion in frame pixels mapped to 0/1 in the motion sheet; 0 = automatic (99th percentile for generic, the largest vector for the engines)
        #[range(0.0, 1024.0)]
        motion_range: f32 = 0.0,
        /// Whose flipbook material reads the motion sheet: its axes, units and the number to paste (in the side-car)
        convention: Convention = Convention::Generic,
        /// Mip levels that must not mix cells: cells aligned to 2^levels pixels, at least 2^(levels-1) pixels of padding; 0 = no alignment
        #[range(0, MAX_MIP_LEVELS)]
        mip_levels: u32 = 0,
        /// Fill each cell's padding with its frame's edge (straight colour with alpha 0; motion vectors extended)
        dilate: bool = false,
    }
}

/// A built flipbook.
#[derive(Clone, Debug, PartialEq)]
pub struct Flipbook {
    /// The colour sheet (RGBA, alpha as asked).
    pub sheet: Image,
    /// The motion-vector sheet (RGBA): R and G as `code` encodes them (generic: R = 0.5 + dx / (2·range),
    /// G = 0.5 + dy / (2·range)), B = 0, A = 1.
    pub motion: Image,
    /// The motion range used, in source-frame pixels.
    pub motion_range: f32,
    /// How the motion sheet encodes a motion, and the engine's number for it.
    pub code: MotionCode,
    /// Cell size in sheet pixels (frame plus padding).
    pub cell: (u32, u32),
    /// Frame size inside a cell.
    pub frame: (u32, u32),
    /// Pixels from a cell's corner to its frame's.
    pub pad: u32,
}

/// The file name of a sheet: `fire.png` → `fire_8x8.png` (rows × columns), with an optional extra suffix.
pub fn sheet_path(path: &Path, rows: usize, cols: usize, extra: &str, ext: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("flipbook");
    path.with_file_name(format!("{stem}_{rows}x{cols}{extra}.{ext}"))
}

/// Why a flipbook cannot be built, by the setting or input it concerns (the flipbook nodes name
/// the matching port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FlipbookError {
    /// The rows do not fit the clip.
    #[error("{0}")]
    Rows(String),
    /// The columns do not fit the clip, or the sheet is too large.
    #[error("{0}")]
    Cols(String),
    /// The power-of-two sheet cannot be laid out.
    #[error("{0}")]
    PowerOfTwo(String),
    /// The cells cannot be aligned for the mip levels.
    #[error("{0}")]
    MipLevels(String),
    /// The motion range is not a non-negative number.
    #[error("{0}")]
    MotionRange(String),
    /// The clip's frames differ in size.
    #[error("{0}")]
    Clip(String),
    /// The motion vectors do not fit the clip.
    #[error("{0}")]
    MotionVectors(String),
    /// A frame could not be scaled to the cell.
    #[error(transparent)]
    Resize(#[from] ResizeError),
    /// Anything no setting is to blame for.
    #[error("{0}")]
    Message(String),
}

/// A flipbook error on the port of the flipbook nodes it concerns.
impl From<FlipbookError> for NodeError {
    fn from(e: FlipbookError) -> NodeError {
        match e {
            FlipbookError::Rows(m) => NodeError::port(port!(FlipbookOptions, rows), m),
            FlipbookError::Cols(m) => NodeError::port(port!(FlipbookOptions, cols), m),
            FlipbookError::PowerOfTwo(m) => NodeError::port(port!(FlipbookOptions, power_of_two), m),
            FlipbookError::MipLevels(m) => NodeError::port(port!(FlipbookOptions, mip_levels), m),
            FlipbookError::MotionRange(m) => NodeError::port(port!(FlipbookOptions, motion_range), m),
            FlipbookError::Clip(m) => NodeError::port(port!(FlipbookInputs, clip), m),
            FlipbookError::MotionVectors(m) => NodeError::port(port!(FlipbookInputs, motion_vectors), m),
            FlipbookError::Resize(e) => e.into(),
            FlipbookError::Message(m) => NodeError::msg(m),
        }
    }
}

/// Builds the colour and motion sheets of `frames` (all the same size; their count must equal rows × cols).
pub fn build_flipbook(frames: &[Arc<Image>], opts: &FlipbookOptions) -> Result<Flipbook, FlipbookError> {
    build_flipbook_with(frames, None, opts)
}

/// [`build_flipbook`] with the motion given per frame (`vectors`: R, G the motion in frame pixels,
/// x right, y down, one image per frame the frames' size) instead of measured by optical flow.
pub fn build_flipbook_with(
    frames: &[Arc<Image>],
    vectors: Option<&[Arc<Image>]>,
    opts: &FlipbookOptions,
) -> Result<Flipbook, FlipbookError> {
    check_cells(frames.len(), opts.rows, opts.cols)?;
    let (w, h) = frames[0].size();
    if let Some((i, f)) = frames.iter().enumerate().find(|(_, f)| f.size() != (w, h)) {
        return Err(FlipbookError::Clip(format!(
            "frame {i} is {}x{} but frame 0 is {w}x{h}; flipbook frames must share one size",
            f.width(),
            f.height()
        )));
    }
    if !opts.motion_range.is_finite() || opts.motion_range < 0.0 {
        return Err(FlipbookError::MotionRange("must be a non-negative number (0 = automatic)".into()));
    }
    let geometry = layout((w, h), opts)?;
    let frame = geometry.frame;
    let colour: Vec<Image> = frames
        .par_iter()
        .map(|f| {
            let f = if f.size() == frame { (**f).clone() } else { resize(f, frame.0, frame.1, FilterType::CatmullRom)? };
            Ok(opts.alpha.apply(&f.to_rgba()))
        })
        .collect::<Result<_, FlipbookError>>()?;
    let flows = match vectors {
        Some(v) => given_motion(v, frames.len(), (w, h))?,
        None => motion_of(frames, opts.convention.central_vectors()),
    };
    let range = match opts.motion_range {
        r if r > 0.0 => r,
        _ if opts.convention.wants_largest_range() => largest_motion(&flows),
        _ => auto_range(&flows),
    };
    let sizes = SheetGeometry { source: (w, h), frame, cell: geometry.cell, sheet: geometry.sheet };
    let code = opts.convention.motion_code(range, &sizes);
    let motion_frames: Vec<Image> = flows
        .par_iter()
        .map(|(u, v)| {
            let data = u
                .data
                .iter()
                .zip(&v.data)
                .flat_map(|(&dx, &dy)| {
                    let (r, g) = code.encode(dx, dy);
                    [r, g, 0.0, 1.0]
                })
                .collect();
            let img = Image::from_vec(w, h, Channels::Rgba, data)
                .ok_or_else(|| FlipbookError::Message("motion size mismatch".into()))?;
            if img.size() == frame { Ok(img) } else { Ok(resize(&img, frame.0, frame.1, FilterType::Triangle)?) }
        })
        .collect::<Result<_, FlipbookError>>()?;
    // Straight colour can carry its edge into transparent padding; premultiplied colour there would glow.
    let colour_fill =
        if opts.dilate && opts.alpha == AlphaMode::Straight { Fill::Edge { keep_alpha: false } } else { Fill::Empty };
    let sheet = paste(&colour, opts.cols, &geometry, colour_fill);
    let motion_fill = if opts.dilate { Fill::Edge { keep_alpha: true } } else { Fill::Empty };
    let mut motion = paste(&motion_frames, opts.cols, &geometry, motion_fill);
    // Cells' padding (unless dilated) and unused sheet area mean "no motion".
    for px in motion.data_mut().chunks_exact_mut(4) {
        if px[3] == 0.0 {
            px.copy_from_slice(&[0.5, 0.5, 0.0, 1.0]);
        }
    }
    Ok(Flipbook { sheet, motion, motion_range: range, code, cell: geometry.cell, frame, pad: geometry.pad })
}

/// The largest flow component's magnitude (what a 16-bit sheet can hold without clamping a single
/// vector), 1 pixel when nothing moves.
pub fn largest_motion(flows: &[(Plane, Plane)]) -> f32 {
    let largest = flows
        .iter()
        .flat_map(|(u, v)| u.data.iter().chain(&v.data))
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .fold(0.0f32, f32::max);
    if largest > 1e-3 { largest } else { 1.0 }
}

/// The automatic motion range: the 99th percentile of the non-zero flow components' magnitudes
/// (robust to a few wild vectors), 1 pixel when nothing moves.
pub fn auto_range(flows: &[(Plane, Plane)]) -> f32 {
    let mut mags: Vec<f32> = flows
        .iter()
        .flat_map(|(u, v)| u.data.iter().chain(&v.data))
        .map(|x| x.abs())
        .filter(|x| *x > 1e-3 && x.is_finite())
        .collect();
    if mags.is_empty() {
        return 1.0;
    }
    let k = ((mags.len() - 1) as f32 * 0.99) as usize;
    let (_, p99, _) = mags.select_nth_unstable_by(k, f32::total_cmp);
    p99.max(1e-2)
}

fn neg(mut p: Plane) -> Plane {
    p.data.iter_mut().for_each(|v| *v = -*v);
    p
}

/// The motion of each frame, in its own pixels: to the next frame (the last frame: minus the motion
/// back to the previous one), or with `central` the mean of that and of minus the motion back to
/// the previous frame (a central difference: the velocity at the frame, which materials that move
/// frame t+1 by its own vector need as much as frame t's).
fn motion_of(frames: &[Arc<Image>], central: bool) -> Vec<(Plane, Plane)> {
    let n = frames.len();
    (0..n)
        .into_par_iter()
        .map(|i| {
            let (w, h) = (frames[i].width() as usize, frames[i].height() as usize);
            let forward = (i + 1 < n).then(|| optical_flow(&frames[i], &frames[i + 1]));
            let back = (i > 0 && (central || forward.is_none())).then(|| {
                let (u, v) = optical_flow(&frames[i], &frames[i - 1]);
                (neg(u), neg(v))
            });
            match (forward, back) {
                (Some((fu, fv)), Some((bu, bv))) => (mean(fu, &bu), mean(fv, &bv)),
                (Some(f), None) | (None, Some(f)) => f,
                (None, None) => (Plane::new(w, h), Plane::new(w, h)),
            }
        })
        .collect()
}

/// The motion of each frame read from `vectors` (R and G, in pixels per frame), checked against
/// the clip: one per frame, each the frames' size, every vector finite.
fn given_motion(vectors: &[Arc<Image>], frames: usize, (w, h): (u32, u32)) -> Result<Vec<(Plane, Plane)>, FlipbookError> {
    if vectors.len() != frames {
        return Err(FlipbookError::MotionVectors(format!(
            "has {} frames but the clip has {frames}; give one per frame",
            vectors.len()
        )));
    }
    vectors
        .iter()
        .enumerate()
        .map(|(k, img)| {
            if img.size() != (w, h) {
                let (vw, vh) = img.size();
                return Err(FlipbookError::MotionVectors(format!("frame {k} is {vw}x{vh} but the clip's frames are {w}x{h}")));
            }
            if img.channels() != Channels::Rgba {
                return Err(FlipbookError::MotionVectors(format!(
                    "frame {k} is gray; motion vectors need R (x) and G (y), as volume.render's motion pass gives them"
                )));
            }
            let (mut u, mut v) = (Plane::new(w as usize, h as usize), Plane::new(w as usize, h as usize));
            for ((px, x), y) in img.data().chunks_exact(4).zip(&mut u.data).zip(&mut v.data) {
                if !(px[0].is_finite() && px[1].is_finite()) {
                    return Err(FlipbookError::MotionVectors(format!(
                        "frame {k} holds a non-finite vector ({}, {})",
                        px[0], px[1]
                    )));
                }
                (*x, *y) = (px[0], px[1]);
            }
            Ok((u, v))
        })
        .collect()
}

fn mean(mut a: Plane, b: &Plane) -> Plane {
    a.data.iter_mut().zip(&b.data).for_each(|(x, y)| *x = 0.5 * (*x + y));
    a
}

// ---------------------------------------------------------------------------------------------
// Nodes
// ---------------------------------------------------------------------------------------------

pyrograph_core::ports! {
    /// The clip and layout of both flipbook nodes.
    pub struct FlipbookInputs {
        /// Frames; exactly rows × cols of them
        clip: ClipOf<Arc<Image>>,
        /// Motion vectors, one image per frame (volume.render's motion pass: R, G the motion in frame pixels
        /// per frame, x right, y down), used instead of measuring the clip's optical flow; default none (measured)
        motion_vectors: ClipOf<Arc<Image>> = no_images(),
        /// The layout.
        layout: FlipbookOptions,
    }
}

impl FlipbookInputs {
    /// Checks the cell count, then pulls every frame of the clip (in parallel).
    fn frames(&self, ctx: &CookCtx) -> Result<Vec<Arc<Image>>, NodeError> {
        check_cells(self.clip.len(), self.layout.rows, self.layout.cols)?;
        (0..self.clip.len()).into_par_iter().map(|k| self.clip.image(k, ctx)).collect()
    }

    /// The flipbook of the clip, with the given motion vectors if connected.
    fn build(&self, ctx: &CookCtx) -> Result<Flipbook, NodeError> {
        let frames = self.frames(ctx)?;
        if self.motion_vectors.is_empty() {
            return Ok(build_flipbook(&frames, &self.layout)?);
        }
        let vectors: Vec<Arc<Image>> = (0..self.motion_vectors.len())
            .into_par_iter()
            .map(|k| self.motion_vectors.image(k, ctx))
            .collect::<Result<_, _>>()?;
        Ok(build_flipbook_with(&frames, Some(&vectors), &self.layout)?)
    }
}

pyrograph_core::node! {
    /// Lays a clip out as a flipbook sheet with a matching motion-vector sheet (post-processing output of the Eigenfires thesis ch. 6 for game engines).
    ///
    /// Cells run left to right, then top to bottom, from the top-left corner; rows × cols must equal the number
    /// of frames. The motion sheet holds a Lucas–Kanade optical flow from each frame to the next (or the
    /// motion_vectors given, such as volume.render's motion pass from the simulation's velocity), encoded for
    /// `convention`: generic R = 0.5 + dx / (2·range), G = 0.5 + dy / (2·range) (x right, y down, frame pixels;
    /// 0.5 = no motion); unity, unreal and houdini-labs in the units, axes and sign their flipbook materials
    /// decode, with `motion_scale` the number to paste. `mip_levels` aligns cells so mip-maps down to that level
    /// do not mix frames; `dilate` fills padding with the frame's edge. Write both with imaging.write_flipbook.
    #[node("imaging.flipbook", "Color & Post", WholeClip)]
    pub struct FlipbookNode {
        /// The clip and layout.
        inputs: FlipbookInputs,
    }
    pub struct FlipbookNodeOut {
        /// Colour sheet (RGBA)
        sheet: Arc<Image>,
        /// Motion-vector sheet (RGBA)
        motion: Arc<Image>,
        /// Motion range used, in frame pixels
        motion_range: f64,
        /// The engine's motion setting for this sheet (Motion Vector Scale, strength, Distortion; generic: the range)
        motion_scale: f64,
    }
}

impl Cook for FlipbookNode {
    fn cook(self, ctx: &CookCtx) -> Result<FlipbookNodeOut, NodeError> {
        let fb = self.inputs.build(ctx)?;
        Ok(FlipbookNodeOut {
            sheet: Arc::new(fb.sheet),
            motion: Arc::new(fb.motion),
            motion_range: f64::from(fb.motion_range),
            motion_scale: f64::from(fb.code.scale),
        })
    }
}

pyrograph_core::node! {
    /// Writes a flipbook sheet, its motion-vector sheet and a JSON side-car (layout of imaging.flipbook).
    ///
    /// `fire.png` with 8 rows and 8 columns writes fire_8x8.png, fire_8x8_mv.png and fire_8x8.json (rows, cols,
    /// frames, fps, cell and frame size, alpha mode, motion range and encoding; for an engine convention also the
    /// engine's setting and the value to paste). The extension picks PNG (8-bit colour; motion 8-bit for generic,
    /// 16-bit for the engines unless `motion_bits` says) or EXR (half).
    #[node("imaging.write_flipbook", "Color & Post", Sink)]
    pub struct WriteFlipbook {
        /// The clip and layout.
        inputs: FlipbookInputs,
        /// Base file; _RxC is added to its name
        path: OutputPath = "flipbook.png".into(),
        /// Also write the motion-vector sheet
        motion: bool = true,
        /// Bits per channel of a PNG motion sheet; auto = 8 for generic, 16 for the engine conventions
        motion_bits: MotionBits = MotionBits::Auto,
        /// Replace files that already exist
        overwrite: bool = false,
    }
    pub struct WriteFlipbookOut {
        /// The colour sheet written
        path: OutputPath,
        /// Frames in the sheet
        frames: usize,
    }
}

/// What a side-car says besides the flipbook and its options.
#[derive(Clone, Copy, Debug)]
pub struct Sidecar<'a> {
    /// Frames in the sheet.
    pub frames: usize,
    /// Their rate.
    pub fps: f64,
    /// The colour sheet's file name.
    pub sheet: &'a str,
    /// The motion sheet's file name, if written.
    pub motion: Option<&'a str>,
    /// Bits per channel of the motion sheet.
    pub motion_bits: u32,
}

/// The JSON side-car describing a written flipbook.
pub fn sidecar_json(fb: &Flipbook, opts: &FlipbookOptions, sheet: &Sidecar) -> String {
    let quote = |s: &str| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""));
    let Sidecar { frames, fps, sheet, motion, motion_bits } = *sheet;
    let mut extras = String::new();
    if opts.mip_levels > 0 || opts.dilate {
        extras += &format!("  \"mip_levels\": {},\n  \"dilate\": {},\n", opts.mip_levels, opts.dilate);
    }
    extras += &opts.convention.sidecar(&fb.code, opts.rows, opts.cols, motion_bits);
    let encoding = if opts.convention == Convention::Generic {
        "R = 0.5 + dx / (2 * range), G = 0.5 + dy / (2 * range); x right, y down, in source-frame pixels, from each frame to the next"
            .to_string()
    } else {
        format!(
            "R = 0.5 + dx / {}, G = 0.5 + dy / {}; dx, dy in source-frame pixels (x right, y down), from each frame to the next",
            fb.code.div.0, fb.code.div.1
        )
    };
    // One literal per line of the file (the same bytes as before, checked by their SHA-256 in
    // tests/flipbook_engines.rs).
    format!(
        concat!(
            "{{\n",
            "  \"sheet\": {},\n  \"motion_sheet\": {},\n  \"rows\": {},\n  \"cols\": {},\n  \"frames\": {},\n  \"fps\": {},\n",
            "  \"order\": \"left-to-right, top-to-bottom, top-left origin\",\n  \"sheet_width\": {},\n  \"sheet_height\": {},\n",
            "  \"cell_width\": {},\n  \"cell_height\": {},\n  \"frame_width\": {},\n  \"frame_height\": {},\n  \"padding\": {},\n",
            "  \"alpha\": {},\n  \"motion_range_px\": {},\n{}  \"motion_encoding\": {}\n",
            "}}\n",
        ),
        quote(sheet),
        motion.map_or("null".to_string(), quote),
        opts.rows,
        opts.cols,
        frames,
        fps,
        fb.sheet.width(),
        fb.sheet.height(),
        fb.cell.0,
        fb.cell.1,
        fb.frame.0,
        fb.frame.1,
        fb.pad,
        quote(opts.alpha.name()),
        fb.motion_range,
        extras,
        quote(&encoding),
    )
}

pyrograph_core::choice! {
    /// Bits per channel of a PNG motion sheet.
    pub enum MotionBits {
        /// 8 bits for the generic convention, 16 for the engines (their materials want uncompressed vectors).
        Auto = "auto",
        /// 8-bit samples.
        Eight = "8",
        /// 16-bit samples.
        Sixteen = "16",
    }
}

impl MotionBits {
    /// The bits this choice gives for `convention`.
    pub fn bits(self, convention: Convention) -> u32 {
        match self {
            MotionBits::Eight => 8,
            MotionBits::Sixteen => 16,
            MotionBits::Auto if convention == Convention::Generic => 8,
            MotionBits::Auto => 16,
        }
    }
}

impl Cook for WriteFlipbook {
    fn cook(self, ctx: &CookCtx) -> Result<WriteFlipbookOut, NodeError> {
        let (opts, clip, base) = (&self.inputs.layout, &self.inputs.clip, &*self.path);
        check_cells(clip.len(), opts.rows, opts.cols)?;
        let ext = base.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        let path_port = port!(WriteFlipbook, path);
        // A problem with a file written is one with this node's `path` (or `overwrite`).
        let file_error = |e: IoError| match e {
            IoError::Exists(message) => NodeError::port(port!(WriteFlipbook, overwrite), message),
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
            e => NodeError::port(path_port, e.to_string()),
        };
        let format: OutputFormat = output_format(base, BitDepth::Eight, ExrType::Half).map_err(file_error)?;
        let motion_bits = self.motion_bits.bits(opts.convention);
        let motion_depth = if motion_bits == 16 { BitDepth::Sixteen } else { BitDepth::Eight };
        let motion_format = output_format(base, motion_depth, ExrType::Half).map_err(file_error)?;
        let overwrite = self.overwrite || ctx.settings().overwrite;
        let fb = self.inputs.build(ctx)?;
        let sheet_file = sheet_path(base, opts.rows, opts.cols, "", &ext);
        let motion_path = self.motion.then(|| sheet_path(base, opts.rows, opts.cols, "_mv", &ext));
        let json_path = sheet_path(base, opts.rows, opts.cols, "", "json");
        for p in [Some(&sheet_file), motion_path.as_ref(), Some(&json_path)].into_iter().flatten() {
            if !overwrite && p.exists() {
                return Err(NodeError::port(
                    port!(WriteFlipbook, overwrite),
                    format!(
                        "{} already exists; nothing was written. Set overwrite to true or render with --overwrite",
                        p.display()
                    ),
                ));
            }
        }
        write_image_file(&fb.sheet, &sheet_file, format, overwrite).map_err(file_error)?;
        if let Some(mp) = &motion_path {
            write_image_file(&fb.motion, mp, motion_format, overwrite).map_err(file_error)?;
        }
        let name = |p: &Path| p.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_string();
        let (sheet_name, motion_name) = (name(&sheet_file), motion_path.as_deref().map(name));
        let bits = if ext == "exr" { 16 } else { motion_bits };
        let about = Sidecar {
            frames: clip.len(),
            fps: clip.fps(),
            sheet: &sheet_name,
            motion: motion_name.as_deref(),
            motion_bits: bits,
        };
        let json = sidecar_json(&fb, opts, &about);
        write_atomic(&json_path, json.as_bytes(), overwrite)
            .map_err(|e| NodeError::port(path_port, format!("writing {}: {e}", json_path.display())))?;
        for p in [Some(&sheet_file), motion_path.as_ref(), Some(&json_path)].into_iter().flatten() {
            ctx.record_written(p);
        }
        Ok(WriteFlipbookOut { path: OutputPath(sheet_file), frames: clip.len() })
    }
}

#[cfg(test)]
mod tests;
