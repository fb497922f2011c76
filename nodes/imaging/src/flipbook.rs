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
use crate::filters::{Plane, convolve_separable, gaussian_kernel};
use crate::io::{BitDepth, ExrType, IoError, OutputFormat, output_format, write_image_file};
use crate::resize::resize;

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
        /// Motion in frame pixels mapped to 0/1 in the motion sheet; 0 = automatic (99th percentile)
        #[range(0.0, 1024.0)]
        motion_range: f32 = 0.0,
    }
}

/// A built flipbook.
#[derive(Clone, Debug, PartialEq)]
pub struct Flipbook {
    /// The colour sheet (RGBA, alpha as asked).
    pub sheet: Image,
    /// The motion-vector sheet (RGBA): R = 0.5 + dx / (2·range), G = 0.5 + dy / (2·range), B = 0, A = 1.
    pub motion: Image,
    /// The motion range used, in source-frame pixels.
    pub motion_range: f32,
    /// Cell size in sheet pixels (frame plus padding).
    pub cell: (u32, u32),
    /// Frame size inside a cell.
    pub frame: (u32, u32),
}

/// Checks that `rows × cols` cells hold exactly `frames` frames.
pub fn check_cells(frames: usize, rows: usize, cols: usize) -> Result<(), NodeError> {
    if rows == 0 || cols == 0 {
        let port = if rows == 0 { port!(FlipbookOptions, rows) } else { port!(FlipbookOptions, cols) };
        return Err(NodeError::port(port, "a flipbook needs at least one row and one column"));
    }
    let cells = rows * cols;
    match cells.cmp(&frames) {
        std::cmp::Ordering::Equal => Ok(()),
        std::cmp::Ordering::Greater => Err(NodeError::port(
            port!(FlipbookOptions, rows),
            format!(
                "{rows}x{cols} = {cells} cells but the clip has only {frames} frames; lower rows/cols or give a longer clip \
                 (every cell must hold a frame)"
            ),
        )),
        std::cmp::Ordering::Less => Err(NodeError::port(
            port!(FlipbookOptions, rows),
            format!(
                "{rows}x{cols} = {cells} cells cannot hold the clip's {frames} frames; raise rows/cols or trim the clip \
                 with imaging.time_range"
            ),
        )),
    }
}

/// Top-left pixel of cell `index`: left to right, then top to bottom, from the top-left corner.
pub fn cell_origin(index: usize, cols: usize, cell: (u32, u32)) -> (u32, u32) {
    ((index % cols) as u32 * cell.0, (index / cols) as u32 * cell.1)
}

/// The power of two nearest to `v` (ties up), at least 1.
pub fn nearest_power_of_two(v: u32) -> u32 {
    let up = v.max(1).next_power_of_two();
    let down = up / 2;
    if down >= 1 && v - down < up - v { down } else { up }
}

/// The file name of a sheet: `fire.png` → `fire_8x8.png` (rows × columns), with an optional extra suffix.
pub fn sheet_path(path: &Path, rows: usize, cols: usize, extra: &str, ext: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("flipbook");
    path.with_file_name(format!("{stem}_{rows}x{cols}{extra}.{ext}"))
}

/// Pastes `frames` (already cell-sized content) into a sheet.
fn paste(frames: &[Image], opts: &FlipbookOptions, cell: (u32, u32), sheet_size: (u32, u32)) -> Image {
    let mut sheet = Image::new(sheet_size.0, sheet_size.1, Channels::Rgba);
    let sw = sheet_size.0 as usize;
    for (i, f) in frames.iter().enumerate() {
        let (ox, oy) = cell_origin(i, opts.cols, cell);
        let (ox, oy) = ((ox + opts.padding) as usize, (oy + opts.padding) as usize);
        let fw = f.width() as usize;
        let data = sheet.data_mut();
        for (y, row) in f.data().chunks_exact(fw * 4).enumerate() {
            let start = ((oy + y) * sw + ox) * 4;
            data[start..start + fw * 4].copy_from_slice(row);
        }
    }
    sheet
}

/// Builds the colour and motion sheets of `frames` (all the same size; their count must equal rows × cols).
pub fn build_flipbook(frames: &[Arc<Image>], opts: &FlipbookOptions) -> Result<Flipbook, NodeError> {
    check_cells(frames.len(), opts.rows, opts.cols)?;
    let (w, h) = frames[0].size();
    if let Some((i, f)) = frames.iter().enumerate().find(|(_, f)| f.size() != (w, h)) {
        return Err(NodeError::port(
            port!(FlipbookInputs, clip),
            format!("frame {i} is {}x{} but frame 0 is {w}x{h}; flipbook frames must share one size", f.width(), f.height()),
        ));
    }
    if !opts.motion_range.is_finite() || opts.motion_range < 0.0 {
        return Err(NodeError::port(port!(FlipbookOptions, motion_range), "must be a non-negative number (0 = automatic)"));
    }
    let p = opts.padding;
    let mut cell = (w + 2 * p, h + 2 * p);
    let mut sheet_size = (cell.0 * opts.cols as u32, cell.1 * opts.rows as u32);
    if opts.power_of_two {
        let target = (nearest_power_of_two(sheet_size.0), nearest_power_of_two(sheet_size.1));
        cell = (target.0 / opts.cols as u32, target.1 / opts.rows as u32);
        if cell.0 <= 2 * p || cell.1 <= 2 * p {
            return Err(NodeError::port(
                port!(FlipbookOptions, power_of_two),
                "the power-of-two sheet leaves no room for the frames; lower padding",
            ));
        }
        sheet_size = target;
    }
    let frame = (cell.0 - 2 * p, cell.1 - 2 * p);
    let colour: Vec<Image> = frames
        .par_iter()
        .map(|f| {
            let f = if f.size() == frame { (**f).clone() } else { resize(f, frame.0, frame.1, FilterType::CatmullRom)? };
            Ok(opts.alpha.apply(&f.to_rgba()))
        })
        .collect::<Result<_, NodeError>>()?;
    // Motion from each frame to the next (the last frame: minus the motion back to the previous one).
    let flows: Vec<(Plane, Plane)> = (0..frames.len())
        .into_par_iter()
        .map(|i| {
            let n = frames.len();
            if n < 2 {
                let z = Plane::new(w as usize, h as usize);
                return (z.clone(), z);
            }
            if i + 1 < n {
                optical_flow(&frames[i], &frames[i + 1])
            } else {
                let (u, v) = optical_flow(&frames[i], &frames[i - 1]);
                (neg(u), neg(v))
            }
        })
        .collect();
    let range = if opts.motion_range > 0.0 { opts.motion_range } else { auto_range(&flows) };
    let motion_frames: Vec<Image> = flows
        .par_iter()
        .map(|(u, v)| {
            let enc = |d: f32| (0.5 + d / (2.0 * range)).clamp(0.0, 1.0);
            let data = u.data.iter().zip(&v.data).flat_map(|(&dx, &dy)| [enc(dx), enc(dy), 0.0, 1.0]).collect();
            let img = Image::from_vec(w, h, Channels::Rgba, data).ok_or_else(|| NodeError::msg("motion size mismatch"))?;
            if img.size() == frame { Ok(img) } else { resize(&img, frame.0, frame.1, FilterType::Triangle) }
        })
        .collect::<Result<_, NodeError>>()?;
    let sheet = paste(&colour, opts, cell, sheet_size);
    let mut motion = paste(&motion_frames, opts, cell, sheet_size);
    // Cells' padding and unused sheet area mean "no motion".
    for px in motion.data_mut().chunks_exact_mut(4) {
        if px[3] == 0.0 {
            px.copy_from_slice(&[0.5, 0.5, 0.0, 1.0]);
        }
    }
    Ok(Flipbook { sheet, motion, motion_range: range, cell, frame })
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

// ---------------------------------------------------------------------------------------------
// Optical flow
// ---------------------------------------------------------------------------------------------

/// Smallest eigenvalue of the windowed structure tensor (luminance 0..1, per pixel²) for which
/// Lucas–Kanade trusts a window; below it (dark noise, flat areas) the flow is left at zero.
pub const MIN_EIGENVALUE: f32 = 1e-4;

/// Luminance (locally averaged over the window) below which a pixel counts as empty background
/// and gets zero motion.
pub const MIN_CONTENT: f32 = 0.02;

/// Luminance × alpha of an image as a plane.
fn luminance(img: &Image) -> Plane {
    let data = match img.channels() {
        Channels::Gray => img.data().to_vec(),
        Channels::Rgba => img.data().chunks_exact(4).map(|p| (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) * p[3]).collect(),
    };
    Plane { width: img.width() as usize, height: img.height() as usize, data }
}

fn sample(p: &Plane, x: f32, y: f32) -> f32 {
    let x = x.clamp(0.0, (p.width - 1) as f32);
    let y = y.clamp(0.0, (p.height - 1) as f32);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(p.width - 1), (y0 + 1).min(p.height - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let at = |x: usize, y: usize| p.data[y * p.width + x];
    let top = at(x0, y0) + fx * (at(x1, y0) - at(x0, y0));
    let bottom = at(x0, y1) + fx * (at(x1, y1) - at(x0, y1));
    top + fy * (bottom - top)
}

/// Dense optical flow from `a` to `b` in pixels (x right, y down): a pyramidal Lucas–Kanade with a
/// Gaussian window (σ 2), five levels at most and five iterations per level. A pixel at `p` in `a`
/// is at `p + (u, v)` in `b`. Textureless regions (a black background) get zero motion; images of
/// different sizes (or empty ones) give zero flow.
pub fn optical_flow(a: &Image, b: &Image) -> (Plane, Plane) {
    if a.size() != b.size() || a.width() == 0 || a.height() == 0 {
        let (w, h) = (a.width() as usize, a.height() as usize);
        return (Plane::new(w, h), Plane::new(w, h));
    }
    let (mut pa, mut pb) = (vec![luminance(a)], vec![luminance(b)]);
    while pa.len() < 5 && pa[pa.len() - 1].width.min(pa[pa.len() - 1].height) >= 32 {
        let (na, nb) = (pa[pa.len() - 1].half(), pb[pb.len() - 1].half());
        pa.push(na);
        pb.push(nb);
    }
    let window = gaussian_kernel(2.0);
    let mut flow: Option<(Plane, Plane)> = None;
    for level in (0..pa.len()).rev() {
        let (i1, i2) = (&pa[level], &pb[level]);
        let (w, h) = (i1.width, i1.height);
        // Initial flow: the coarser level's, doubled.
        let (mut u, mut v) = match flow.take() {
            None => (Plane::new(w, h), Plane::new(w, h)),
            Some((cu, cv)) => {
                let up = |c: &Plane| Plane {
                    width: w,
                    height: h,
                    data: (0..w * h)
                        .map(|k| 2.0 * sample(c, ((k % w) as f32 - 0.5) / 2.0, ((k / w) as f32 - 0.5) / 2.0))
                        .collect(),
                };
                (up(&cu), up(&cv))
            }
        };
        let at = |p: &Plane, x: usize, y: usize| p.data[y * p.width + x];
        let grad = |x: usize, y: usize| {
            let gx = 0.5 * (at(i1, (x + 1).min(w - 1), y) - at(i1, x.saturating_sub(1), y));
            let gy = 0.5 * (at(i1, x, (y + 1).min(h - 1)) - at(i1, x, y.saturating_sub(1)));
            (gx, gy)
        };
        let (gx, gy): (Vec<f32>, Vec<f32>) = (0..w * h).map(|k| grad(k % w, k / w)).unzip();
        let prod = |f: &dyn Fn(usize) -> f32| {
            convolve_separable(&Plane { width: w, height: h, data: (0..w * h).map(f).collect() }, &window)
        };
        let sxx = prod(&|k| gx[k] * gx[k]);
        let sxy = prod(&|k| gx[k] * gy[k]);
        let syy = prod(&|k| gy[k] * gy[k]);
        for _ in 0..5 {
            let it: Vec<f32> =
                (0..w * h).map(|k| sample(i2, (k % w) as f32 + u.data[k], (k / w) as f32 + v.data[k]) - i1.data[k]).collect();
            let bx = prod(&|k| gx[k] * it[k]);
            let by = prod(&|k| gy[k] * it[k]);
            for k in 0..w * h {
                let (a, b, c) = (sxx.data[k], sxy.data[k], syy.data[k]);
                let det = a * c - b * b;
                let trace = a + c;
                // Skip ill-conditioned windows: flat or noisy-dark regions (small eigenvalue) and pure edges.
                let lambda_min = 0.5 * (trace - (trace * trace - 4.0 * det).max(0.0).sqrt());
                if lambda_min < MIN_EIGENVALUE || det < 1e-3 * trace * trace {
                    continue;
                }
                let du = -(c * bx.data[k] - b * by.data[k]) / det;
                let dv = -(a * by.data[k] - b * bx.data[k]) / det;
                u.data[k] += du.clamp(-2.0, 2.0);
                v.data[k] += dv.clamp(-2.0, 2.0);
            }
        }
        flow = Some((u, v));
    }
    let (w, h) = (a.width() as usize, a.height() as usize);
    let (mut u, mut v) = flow.unwrap_or_else(|| (Plane::new(w, h), Plane::new(w, h)));
    // Coarse levels spread motion into the empty background around a flame; nothing moves where
    // neither frame has content nearby.
    let content = Plane { width: w, height: h, data: pa[0].data.iter().zip(&pb[0].data).map(|(x, y)| x.max(*y)).collect() };
    let near = convolve_separable(&content, &window);
    for (k, &c) in near.data.iter().enumerate() {
        if c < MIN_CONTENT {
            u.data[k] = 0.0;
            v.data[k] = 0.0;
        }
    }
    (u, v)
}

// ---------------------------------------------------------------------------------------------
// Nodes
// ---------------------------------------------------------------------------------------------

pyrograph_core::ports! {
    /// The clip and layout of both flipbook nodes.
    pub struct FlipbookInputs {
        /// Frames; exactly rows × cols of them
        clip: ClipOf<Arc<Image>>,
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
}

pyrograph_core::node! {
    /// Lays a clip out as a flipbook sheet with a matching motion-vector sheet (post-processing output of the Eigenfires thesis ch. 6 for game engines).
    ///
    /// Cells run left to right, then top to bottom, from the top-left corner; rows × cols must equal the number
    /// of frames. The motion sheet holds a Lucas–Kanade optical flow from each frame to the next: R = 0.5 +
    /// dx / (2·range), G = 0.5 + dy / (2·range) (x right, y down, frame pixels; 0.5 = no motion). Write both with
    /// imaging.write_flipbook.
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
    }
}

impl Cook for FlipbookNode {
    fn cook(self, ctx: &CookCtx) -> Result<FlipbookNodeOut, NodeError> {
        let fb = build_flipbook(&self.inputs.frames(ctx)?, &self.inputs.layout)?;
        Ok(FlipbookNodeOut { sheet: Arc::new(fb.sheet), motion: Arc::new(fb.motion), motion_range: f64::from(fb.motion_range) })
    }
}

pyrograph_core::node! {
    /// Writes a flipbook sheet, its motion-vector sheet and a JSON side-car (layout of imaging.flipbook).
    ///
    /// `fire.png` with 8 rows and 8 columns writes fire_8x8.png, fire_8x8_mv.png and fire_8x8.json (rows, cols,
    /// frames, fps, cell and frame size, alpha mode, motion range and encoding). The extension picks PNG (8-bit)
    /// or EXR (half).
    #[node("imaging.write_flipbook", "Color & Post", Sink)]
    pub struct WriteFlipbook {
        /// The clip and layout.
        inputs: FlipbookInputs,
        /// Base file; _RxC is added to its name
        path: OutputPath = "flipbook.png".into(),
        /// Also write the motion-vector sheet
        motion: bool = true,
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

/// The JSON side-car describing a written flipbook.
pub fn sidecar_json(fb: &Flipbook, opts: &FlipbookOptions, frames: usize, fps: f64, sheet: &str, motion: Option<&str>) -> String {
    let quote = |s: &str| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""));
    format!(
        "{{\n  \"sheet\": {},\n  \"motion_sheet\": {},\n  \"rows\": {},\n  \"cols\": {},\n  \"frames\": {},\n  \"fps\": {},\n  \
         \"order\": \"left-to-right, top-to-bottom, top-left origin\",\n  \"sheet_width\": {},\n  \"sheet_height\": {},\n  \
         \"cell_width\": {},\n  \"cell_height\": {},\n  \"frame_width\": {},\n  \"frame_height\": {},\n  \"padding\": {},\n  \
         \"alpha\": {},\n  \"motion_range_px\": {},\n  \"motion_encoding\": \"R = 0.5 + dx / (2 * range), G = 0.5 + dy / (2 * range); \
         x right, y down, in source-frame pixels, from each frame to the next\"\n}}\n",
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
        opts.padding,
        quote(opts.alpha.name()),
        fb.motion_range,
    )
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
            IoError::Other(e) => e,
            e => NodeError::port(path_port, e.to_string()),
        };
        let format: OutputFormat = output_format(base, BitDepth::Eight, ExrType::Half).map_err(file_error)?;
        let overwrite = self.overwrite || ctx.settings().overwrite;
        let fb = build_flipbook(&self.inputs.frames(ctx)?, opts)?;
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
            write_image_file(&fb.motion, mp, format, overwrite).map_err(file_error)?;
        }
        let name = |p: &Path| p.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_string();
        let json =
            sidecar_json(&fb, opts, clip.len(), clip.fps(), &name(&sheet_file), motion_path.as_deref().map(name).as_deref());
        write_atomic(&json_path, json.as_bytes(), overwrite)
            .map_err(|e| NodeError::port(path_port, format!("writing {}: {e}", json_path.display())))?;
        for p in [Some(&sheet_file), motion_path.as_ref(), Some(&json_path)].into_iter().flatten() {
            ctx.record_written(p);
        }
        Ok(WriteFlipbookOut { path: OutputPath(sheet_file), frames: clip.len() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::{Inputs, PortType, Value};

    fn numbered(n: usize, w: u32, h: u32) -> Vec<Arc<Image>> {
        (0..n)
            .map(|k| {
                let v = k as f32 / n as f32;
                Arc::new(Image::from_vec(w, h, Channels::Rgba, (0..w * h).flat_map(|_| [v, 0.0, 0.0, 0.5]).collect()).unwrap())
            })
            .collect()
    }

    #[test]
    fn cells_run_left_to_right_then_top_to_bottom() {
        assert_eq!(cell_origin(0, 3, (10, 20)), (0, 0));
        assert_eq!(cell_origin(2, 3, (10, 20)), (20, 0));
        assert_eq!(cell_origin(3, 3, (10, 20)), (0, 20));
        let frames = numbered(6, 4, 2);
        let opts = FlipbookOptions { rows: 2, cols: 3, padding: 1, ..Default::default() };
        let fb = build_flipbook(&frames, &opts).unwrap();
        assert_eq!(fb.sheet.size(), (18, 8));
        assert_eq!(fb.cell, (6, 4));
        for k in 0..6 {
            let (ox, oy) = cell_origin(k, 3, fb.cell);
            // Padding is transparent, the frame starts one pixel in.
            assert_eq!(fb.sheet.pixel(ox, oy)[3], 0.0);
            let p = fb.sheet.pixel(ox + 1, oy + 1);
            assert!((p[0] - k as f32 / 6.0).abs() < 1e-6 && p[3] == 0.5, "cell {k}: {p:?}");
        }
        // Constant frames do not move: every motion pixel is 0.5.
        assert!(fb.motion.data().chunks(4).all(|p| p[0] == 0.5 && p[1] == 0.5));
    }

    #[test]
    fn premultiplied_sheets_multiply_colour_by_alpha() {
        let frames = numbered(4, 2, 2);
        let opts = FlipbookOptions { rows: 2, cols: 2, alpha: AlphaMode::Premultiplied, ..Default::default() };
        let fb = build_flipbook(&frames, &opts).unwrap();
        // Cell 3 (bottom right) holds red 0.75 with alpha 0.5.
        let p = fb.sheet.pixel(2, 2);
        assert!((p[0] - 0.75 * 0.5).abs() < 1e-6 && p[3] == 0.5, "{p:?}");
    }

    #[test]
    fn cell_count_must_match_the_frames() {
        let frames = numbered(6, 2, 2);
        let more = build_flipbook(&frames, &FlipbookOptions { rows: 3, cols: 3, ..Default::default() }).unwrap_err().to_string();
        assert!(more.contains("9 cells but the clip has only 6 frames"), "{more}");
        let fewer = build_flipbook(&frames, &FlipbookOptions { rows: 1, cols: 4, ..Default::default() }).unwrap_err().to_string();
        assert!(fewer.contains("cannot hold the clip's 6 frames"), "{fewer}");
        assert!(check_cells(6, 0, 6).is_err());
    }

    #[test]
    fn power_of_two_and_file_names() {
        assert_eq!(nearest_power_of_two(2400), 2048);
        assert_eq!(nearest_power_of_two(3100), 4096);
        assert_eq!(nearest_power_of_two(1), 1);
        let frames = numbered(4, 30, 30);
        let fb =
            build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, power_of_two: true, ..Default::default() }).unwrap();
        assert_eq!(fb.sheet.size(), (64, 64));
        assert_eq!(fb.frame, (32, 32));
        assert_eq!(sheet_path(Path::new("out/fire.png"), 8, 8, "", "png"), PathBuf::from("out/fire_8x8.png"));
        assert_eq!(sheet_path(Path::new("fire.png"), 4, 6, "_mv", "png"), PathBuf::from("fire_4x6_mv.png"));
        let json = sidecar_json(&fb, &FlipbookOptions { rows: 2, cols: 2, ..Default::default() }, 4, 24.0, "f_2x2.png", None);
        for key in
            ["\"rows\": 2", "\"cols\": 2", "\"frames\": 4", "\"fps\": 24", "\"alpha\": \"straight\"", "\"motion_range_px\""]
        {
            assert!(json.contains(key), "{key} missing in {json}");
        }
    }

    /// A smooth texture translated by (dx, dy).
    fn texture(w: u32, h: u32, dx: f32, dy: f32) -> Image {
        Image::gray_from_fn(w, h, |x, y| {
            let (x, y) = (x as f32 - dx, y as f32 - dy);
            0.5 + 0.2 * (x * 0.21).sin() * (y * 0.17).cos()
                + 0.15 * (x * 0.07 + y * 0.11).sin()
                + 0.1 * (y * 0.29 - x * 0.05).cos()
        })
    }

    fn median(mut v: Vec<f32>) -> f32 {
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    }

    #[test]
    fn flow_of_a_translated_pattern_points_the_right_way() {
        for (dx, dy) in [(3.0f32, -2.0f32), (-1.5, 4.0), (0.0, 0.0)] {
            let (a, b) = (texture(96, 80, 0.0, 0.0), texture(96, 80, dx, dy));
            let (u, v) = optical_flow(&a, &b);
            let inner = |p: &Plane| -> Vec<f32> {
                (0..p.data.len())
                    .filter(|k| (12..84).contains(&(k % 96)) && (12..68).contains(&(k / 96)))
                    .map(|k| p.data[k])
                    .collect()
            };
            let (mu, mv) = (median(inner(&u)), median(inner(&v)));
            assert!((mu - dx).abs() < 0.2 && (mv - dy).abs() < 0.2, "shift ({dx}, {dy}): median flow ({mu}, {mv})");
        }
    }

    #[test]
    fn an_empty_background_does_not_move() {
        let blob =
            |cx: f32| Image::gray_from_fn(64, 64, |x, y| (-((x as f32 - cx).powi(2) + (y as f32 - 32.0).powi(2)) / 18.0).exp());
        let (u, v) = optical_flow(&blob(30.0), &blob(32.0));
        // Far from the blob: exactly zero; at the blob's flank: about +2 px in x.
        assert_eq!((u.data[5 * 64 + 5], v.data[5 * 64 + 5]), (0.0, 0.0));
        assert!((u.data[32 * 64 + 27] - 2.0).abs() < 0.5, "{}", u.data[32 * 64 + 27]);
    }

    #[test]
    fn motion_sheet_encodes_around_one_half() {
        let frames: Vec<Arc<Image>> = (0..4).map(|k| Arc::new(texture(64, 64, 2.0 * k as f32, 0.0))).collect();
        let fb = build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, motion_range: 4.0, ..Default::default() }).unwrap();
        // 2 px right with range 4: R ≈ 0.5 + 2/8 = 0.75, G ≈ 0.5, in the middle of every cell (also the last).
        for k in 0..4 {
            let (ox, oy) = cell_origin(k, 2, fb.cell);
            let p = fb.motion.pixel(ox + 32, oy + 32);
            assert!((p[0] - 0.75).abs() < 0.03 && (p[1] - 0.5).abs() < 0.03, "cell {k}: {p:?}");
        }
        assert_eq!(fb.motion_range, 4.0);
    }

    #[test]
    fn mismatched_frame_sizes_are_errors() {
        let mut frames = numbered(2, 4, 4);
        frames.push(Arc::new(Image::new(3, 3, Channels::Rgba)));
        frames.push(Arc::new(Image::new(4, 4, Channels::Rgba)));
        let e = build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, ..Default::default() }).unwrap_err().to_string();
        assert!(e.contains("frame 2 is 3x3"), "{e}");
    }

    #[test]
    fn writer_puts_rxc_into_the_names_and_writes_a_sidecar() {
        let dir = tempfile::tempdir().unwrap();
        let reg = {
            let mut r = pyrograph_core::Registry::new();
            crate::register(&mut r);
            r
        };
        let node = reg.get("imaging.write_flipbook").unwrap();
        let desc = node.desc();
        let frames: Vec<Value> = numbered(4, 4, 4).into_iter().map(Value::Image).collect();
        let clip = pyrograph_core::Clip::from_frames(PortType::Image, 12.0, frames);
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or(Value::Int(0))).collect();
        let set = |values: &mut Vec<Value>, name: &str, v: Value| values[desc.input_index(name).unwrap()] = v;
        set(&mut values, "clip", Value::Clip(clip));
        set(&mut values, "rows", Value::Int(2));
        set(&mut values, "cols", Value::Int(2));
        set(&mut values, "path", Value::Path(dir.path().join("fire.png")));
        let out = node.cook(&Inputs::new(desc, &values), &CookCtx::new()).unwrap();
        assert!(matches!(&out[0], Value::Path(p) if p.ends_with("fire_2x2.png")));
        assert!(dir.path().join("fire_2x2_mv.png").exists());
        let json = std::fs::read_to_string(dir.path().join("fire_2x2.json")).unwrap();
        assert!(json.contains("\"fps\": 12") && json.contains("\"frames\": 4"), "{json}");
        // A second write refuses to overwrite.
        assert!(node.cook(&Inputs::new(desc, &values), &CookCtx::new()).unwrap_err().to_string().contains("already exists"));
    }
}
