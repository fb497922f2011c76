//! Where frames go in a flipbook sheet: cell count, cell and frame sizes, padding, the alignment
//! that keeps mip levels from mixing cells, and pasting frames with their edges dilated.

use pyrograph_core::{Channels, Image};

use super::engine::Convention;
use super::{FlipbookError, FlipbookOptions};

/// Largest number of mip levels a sheet can be laid out for (cells aligned to 256 pixels).
pub const MAX_MIP_LEVELS: i64 = 8;

/// Checks that `rows × cols` cells hold exactly `frames` frames.
pub fn check_cells(frames: usize, rows: usize, cols: usize) -> Result<(), FlipbookError> {
    if rows == 0 || cols == 0 {
        let message = "a flipbook needs at least one row and one column".to_string();
        return Err(if rows == 0 { FlipbookError::Rows(message) } else { FlipbookError::Cols(message) });
    }
    let cells = rows * cols;
    match cells.cmp(&frames) {
        std::cmp::Ordering::Equal => Ok(()),
        std::cmp::Ordering::Greater => Err(FlipbookError::Rows(format!(
            "{rows}x{cols} = {cells} cells but the clip has only {frames} frames; lower rows/cols or give a longer clip \
                 (every cell must hold a frame)"
        ))),
        std::cmp::Ordering::Less => Err(FlipbookError::Rows(format!(
            "{rows}x{cols} = {cells} cells cannot hold the clip's {frames} frames; raise rows/cols or trim the clip \
                 with imaging.time_range"
        ))),
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

/// The geometry of a sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Cell size in sheet pixels (frame, padding, and any rounding up for mip alignment).
    pub cell: (u32, u32),
    /// Frame size inside a cell.
    pub frame: (u32, u32),
    /// Pixels from a cell's top-left corner to its frame's, on both axes.
    pub pad: u32,
    /// Sheet size.
    pub sheet: (u32, u32),
}

/// The layout of `opts` for frames of `source` size.
///
/// With `mip_levels` L > 0, every cell starts and ends on a multiple of 2^L pixels, so each texel
/// of mip levels 1..L (2×2 box averages) lies in one cell, and at least 2^(L−1) pixels of padding
/// surround each frame, so a bilinear sample anywhere on the frame at level L reads only its own
/// cell's texels. The frame stays at `pad` from the cell's top-left corner; rounding up adds room
/// on the right and at the bottom.
pub fn layout(source: (u32, u32), opts: &FlipbookOptions) -> Result<Layout, FlipbookError> {
    let levels = opts.mip_levels.min(MAX_MIP_LEVELS as u32);
    let align = 1u32 << levels;
    let pad = if levels > 0 { opts.padding.max(align / 2) } else { opts.padding };
    let (cols, rows) = (opts.cols.max(1) as u32, opts.rows.max(1) as u32);
    // In u64 and checked against the pixel budget before anything is allocated: a wide frame,
    // many cells and wide padding multiply past u32 and past any memory.
    let round = |v: u64| v.div_ceil(u64::from(align)) * u64::from(align);
    let wide = (round(u64::from(source.0) + 2 * u64::from(pad)), round(u64::from(source.1) + 2 * u64::from(pad)));
    sheet_fits((wide.0 * u64::from(cols), wide.1 * u64::from(rows)))?;
    let mut cell = (wide.0 as u32, wide.1 as u32);
    let mut frame = source;
    let mut sheet = (cell.0 * cols, cell.1 * rows);
    if opts.power_of_two {
        let target = (nearest_power_of_two(sheet.0), nearest_power_of_two(sheet.1));
        sheet_fits((u64::from(target.0), u64::from(target.1)))?;
        if opts.convention != Convention::Generic && (!target.0.is_multiple_of(cols) || !target.1.is_multiple_of(rows)) {
            // The engines' materials read cell i at i/cols of the texture: cells must tile the sheet exactly.
            return Err(FlipbookError::PowerOfTwo(format!(
                "the power-of-two sheet {}x{} does not split into {cols} columns and {rows} rows of whole pixels, \
                     and the engine's material reads cell i at i/cols of the texture, so frames would drift into their \
                     neighbours; use rows and cols that are powers of two, or leave power_of_two off",
                target.0, target.1
            )));
        }
        cell = (target.0 / cols, target.1 / rows);
        if cell.0 <= 2 * pad || cell.1 <= 2 * pad {
            return Err(FlipbookError::PowerOfTwo(
                "the power-of-two sheet leaves no room for the frames; lower padding".to_string(),
            ));
        }
        if !cell.0.is_multiple_of(align) || !cell.1.is_multiple_of(align) {
            return Err(FlipbookError::MipLevels(format!(
                "the power-of-two sheet {}x{} splits into cells of {}x{} pixels, not multiples of {align} (2^{levels}), \
                     so mip level {levels} would mix neighbouring cells; use rows and cols that are powers of two or fewer \
                     mip levels",
                target.0, target.1, cell.0, cell.1
            )));
        }
        frame = (cell.0 - 2 * pad, cell.1 - 2 * pad);
        sheet = target;
    }
    Ok(Layout { cell, frame, pad, sheet })
}

/// Refuses a sheet of `size` pixels over the pixel budget (`--max-pixels`) or too wide to address.
fn sheet_fits(size: (u64, u64)) -> Result<(), FlipbookError> {
    let budget = pyrograph_core::limits::max_pixels();
    let pixels = size.0.saturating_mul(size.1);
    if size.0 <= u64::from(u32::MAX / 2) && size.1 <= u64::from(u32::MAX / 2) && pixels <= budget {
        return Ok(());
    }
    Err(FlipbookError::Cols(format!(
        "the sheet would be {}x{} pixels, more than the pixel budget of {budget}; use fewer rows and cols, less \
             padding or fewer mip_levels, scale the frames down, or {}",
        size.0,
        size.1,
        pyrograph_core::limits::raise_hint("--max-pixels", "PYROGRAPH_MAX_PIXELS", pixels)
    )))
}

/// What fills a cell's padding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fill {
    /// Nothing: transparent (or, for the motion sheet, "no motion" set by the caller).
    Empty,
    /// The nearest edge pixel of the frame, with its alpha (`keep_alpha`) or alpha 0.
    Edge {
        /// Keep the edge pixel's alpha (motion vectors) instead of making the padding transparent.
        keep_alpha: bool,
    },
}

/// Pastes `frames` (each `layout.frame` in size) into a sheet, cell `i` at `cell_origin(i)`.
pub fn paste(frames: &[Image], cols: usize, layout: &Layout, fill: Fill) -> Image {
    let mut sheet = Image::new(layout.sheet.0, layout.sheet.1, Channels::Rgba);
    let sw = layout.sheet.0 as usize;
    let pad = layout.pad as usize;
    for (i, f) in frames.iter().enumerate() {
        let (cx, cy) = cell_origin(i, cols, layout.cell);
        let (cx, cy) = (cx as usize, cy as usize);
        let (fw, fh) = (f.width() as usize, f.height() as usize);
        if fw == 0 || fh == 0 {
            continue;
        }
        let data = sheet.data_mut();
        match fill {
            Fill::Empty => {
                for (y, row) in f.data().chunks_exact(fw * 4).enumerate() {
                    let start = ((cy + pad + y) * sw + cx + pad) * 4;
                    data[start..start + fw * 4].copy_from_slice(row);
                }
            }
            Fill::Edge { keep_alpha } => {
                let (cw, ch) = (layout.cell.0 as usize, layout.cell.1 as usize);
                for y in 0..ch {
                    let sy = y.saturating_sub(pad).min(fh - 1);
                    for x in 0..cw {
                        let sx = x.saturating_sub(pad).min(fw - 1);
                        let src = &f.data()[(sy * fw + sx) * 4..][..4];
                        let inside = (pad..pad + fw).contains(&x) && (pad..pad + fh).contains(&y);
                        let dst = &mut data[((cy + y) * sw + cx + x) * 4..][..4];
                        dst.copy_from_slice(src);
                        if !inside && !keep_alpha {
                            dst[3] = 0.0;
                        }
                    }
                }
            }
        }
    }
    sheet
}
