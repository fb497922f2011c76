//! Contact sheets: frames of a clip laid out in a grid, for reviews, READMEs and previews.

use std::sync::Arc;

use pyrograph_core::{Channels, ClipOf, Cook, CookCtx, Image, NodeError, port};

/// Puts `b` below (or right of) `a`, `gap` pixels apart, on `background`; narrower (shorter)
/// images are left-aligned (top-aligned). Gray inputs are promoted to RGBA.
pub fn stack(a: &Image, b: &Image, vertical: bool, gap: u32, background: [f32; 4]) -> Image {
    let (a, b) = (a.to_rgba(), b.to_rgba());
    let (w, h) = if vertical {
        (a.width().max(b.width()), a.height() + gap + b.height())
    } else {
        (a.width() + gap + b.width(), a.height().max(b.height()))
    };
    let mut data: Vec<f32> = std::iter::repeat_n(background, w as usize * h as usize).flatten().collect();
    let offset_b = if vertical { (0, a.height() + gap) } else { (a.width() + gap, 0) };
    for (img, (x0, y0)) in [(&a, (0, 0)), (&b, offset_b)] {
        for (y, row) in img.data().chunks_exact(img.width() as usize * 4).enumerate() {
            let start = (((y0 + y as u32) * w + x0) * 4) as usize;
            data[start..start + row.len()].copy_from_slice(row);
        }
    }
    Image::from_vec(w, h, Channels::Rgba, data).unwrap_or_else(|| Image::new(w, h, Channels::Rgba))
}

pyrograph_core::choice! {
    /// Where `imaging.stack` puts its second image.
    pub enum StackDirection {
        /// b below a.
        Vertical = "vertical",
        /// b right of a.
        Horizontal = "horizontal",
    }
}

pyrograph_core::node! {
    /// Stacks two images, b below a (or right of it), for multi-row sheets and side-by-side comparisons.
    #[node("imaging.stack", "Imaging", PerFrame)]
    pub struct Stack {
        /// First (top or left) image.
        a: Arc<Image>,
        /// Second (bottom or right) image.
        b: Arc<Image>,
        /// vertical puts b below a, horizontal to its right.
        direction: StackDirection = StackDirection::Vertical,
        /// Pixels between the two.
        #[range(0, 4096)]
        gap: u32 = 4,
        /// Colour of the gap and of padding.
        background: [f32; 4] = [0.08, 0.08, 0.08, 1.0],
    }
    /// The stacked image (RGBA).
    -> image: Arc<Image>
}

impl Cook for Stack {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let vertical = self.direction == StackDirection::Vertical;
        Ok(Arc::new(stack(&self.a, &self.b, vertical, self.gap, self.background)))
    }
}

/// Indices of `count` frames spread evenly over `len` frames, first and last included.
pub fn pick_frames(len: usize, count: usize) -> Vec<usize> {
    match (len, count) {
        (0, _) | (_, 0) => Vec::new(),
        (_, 1) => vec![0],
        _ => {
            let count = count.min(len);
            (0..count).map(|i| (i * (len - 1) + (count - 1) / 2) / (count - 1)).collect()
        }
    }
}

/// Lays `frames` (all the same size) out left→right, top→bottom on a `background`, `gap` pixels apart.
pub fn contact_sheet(frames: &[&Image], columns: usize, gap: u32, background: [f32; 4]) -> Result<Image, String> {
    let first = frames.first().ok_or("no frames to lay out")?;
    let (w, h) = first.size();
    if let Some(odd) = frames.iter().find(|f| f.size() != (w, h)) {
        return Err(format!("frames differ in size: {}x{} and {}x{}", w, h, odd.width(), odd.height()));
    }
    let columns = columns.clamp(1, frames.len());
    let rows = frames.len().div_ceil(columns);
    let sheet_w = columns as u32 * w + (columns as u32 + 1) * gap;
    let sheet_h = rows as u32 * h + (rows as u32 + 1) * gap;
    let mut data: Vec<f32> = std::iter::repeat_n(background, sheet_w as usize * sheet_h as usize).flatten().collect();
    for (k, frame) in frames.iter().enumerate() {
        let rgba = frame.to_rgba();
        let x0 = gap + (k % columns) as u32 * (w + gap);
        let y0 = gap + (k / columns) as u32 * (h + gap);
        for (y, row) in rgba.data().chunks_exact(w as usize * 4).enumerate() {
            let start = (((y0 + y as u32) * sheet_w + x0) * 4) as usize;
            data[start..start + row.len()].copy_from_slice(row);
        }
    }
    Image::from_vec(sheet_w, sheet_h, Channels::Rgba, data).ok_or_else(|| "sheet size overflow".to_string())
}

/// `frame` scaled down (triangle filter) so its longer side is at most `cell` pixels; as it is
/// when it already fits, when `cell` is 0, or when it is empty.
pub fn fit_cell(frame: Arc<Image>, cell: u32) -> Arc<Image> {
    let (w, h) = frame.size();
    if cell == 0 || w.max(h) <= cell || w == 0 || h == 0 {
        return frame;
    }
    let (tw, th) = if w >= h { (cell, 0) } else { (0, cell) };
    crate::resize::resize(&frame, tw, th, image::imageops::FilterType::Triangle).map_or(frame, Arc::new)
}

pyrograph_core::node! {
    /// Lays frames of a clip out in a grid (left→right, top→bottom), picked evenly from first to last.
    #[node("imaging.contact_sheet", "Imaging", WholeClip)]
    pub struct ContactSheet {
        /// The clip to sample.
        clip: ClipOf<Arc<Image>>,
        /// How many frames to show (fewer if the clip is shorter).
        #[range(1, 1024)]
        count: usize = 8,
        /// Frames per row.
        #[range(1, 1024)]
        columns: usize = 8,
        /// Pixels between and around frames.
        #[range(0, 256)]
        gap: u32 = 4,
        /// Colour of the gaps.
        background: [f32; 4] = [0.08, 0.08, 0.08, 1.0],
        /// Longest side of a cell in pixels: larger frames are scaled down to fit, keeping their
        /// aspect, so a sheet of 4K frames stays a reviewable (and memory-bounded) size. 0 shows
        /// frames at their own size.
        #[range(0, 16384)]
        cell_size: u32 = 0,
    }
    /// The sheet (RGBA).
    -> image: Arc<Image>
}

impl Cook for ContactSheet {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let clip = &self.clip;
        if clip.is_empty() {
            return Err(NodeError::port(port!(ContactSheet, clip), "the clip has no frames"));
        }
        let picks = pick_frames(clip.len(), self.count);
        // One frame at a time, each shrunk before the next is read: the full-size frames are
        // never all held at once.
        let frames = picks
            .iter()
            .map(|&f| clip.image(f, ctx).map(|frame| fit_cell(frame, self.cell_size)))
            .collect::<Result<Vec<_>, _>>()?;
        let refs: Vec<&Image> = frames.iter().map(|f| f.as_ref()).collect();
        let sheet = contact_sheet(&refs, self.columns, self.gap, self.background)
            .map_err(|m| NodeError::port(port!(ContactSheet, clip), m))?;
        Ok(Arc::new(sheet))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_spread_evenly_including_both_ends() {
        assert_eq!(pick_frames(10, 4), vec![0, 3, 6, 9]);
        assert_eq!(pick_frames(3, 8), vec![0, 1, 2]);
        assert_eq!(pick_frames(5, 1), vec![0]);
        assert!(pick_frames(0, 3).is_empty());
    }

    #[test]
    fn frames_land_in_reading_order_with_gaps() {
        let a = Image::gray_from_fn(1, 1, |_, _| 0.25);
        let b = Image::gray_from_fn(1, 1, |_, _| 0.5);
        let c = Image::gray_from_fn(1, 1, |_, _| 0.75);
        let sheet = contact_sheet(&[&a, &b, &c], 2, 1, [0.0, 0.0, 0.0, 1.0]).unwrap();
        assert_eq!(sheet.size(), (5, 5));
        assert_eq!(sheet.pixel(1, 1)[0], 0.25);
        assert_eq!(sheet.pixel(3, 1)[0], 0.5);
        assert_eq!(sheet.pixel(1, 3)[0], 0.75);
        assert_eq!(sheet.pixel(3, 3), &[0.0, 0.0, 0.0, 1.0], "empty cell keeps the background");
        assert_eq!(sheet.pixel(0, 0), &[0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn stack_places_b_below_or_right_of_a_and_pads() {
        let a = Image::gray_from_fn(2, 1, |_, _| 0.25);
        let b = Image::gray_from_fn(1, 2, |_, _| 0.75);
        let v = stack(&a, &b, true, 1, [0.0; 4]);
        assert_eq!(v.size(), (2, 4));
        assert_eq!(v.pixel(1, 0)[0], 0.25);
        assert_eq!(v.pixel(0, 1), &[0.0; 4], "gap row");
        assert_eq!(v.pixel(0, 3)[0], 0.75);
        assert_eq!(v.pixel(1, 3), &[0.0; 4], "padding right of the narrower b");
        let h = stack(&a, &b, false, 0, [0.0; 4]);
        assert_eq!(h.size(), (3, 2));
        assert_eq!(h.pixel(2, 1)[0], 0.75);
    }

    #[test]
    fn large_frames_shrink_to_the_cell_keeping_their_aspect() {
        let big = Arc::new(Image::gray_from_fn(400, 100, |x, _| if x < 200 { 0.0 } else { 1.0 }));
        let small = fit_cell(big.clone(), 80);
        assert_eq!(small.size(), (80, 20));
        assert!(small.pixel(10, 10)[0] < 0.01 && small.pixel(70, 10)[0] > 0.99, "content kept in place");
        assert!(Arc::ptr_eq(&fit_cell(big.clone(), 0), &big), "0 keeps the frame");
        assert!(Arc::ptr_eq(&fit_cell(big.clone(), 400), &big), "a frame that fits is kept");
        let tall = fit_cell(Arc::new(Image::gray_from_fn(30, 90, |_, _| 0.5)), 45);
        assert_eq!(tall.size(), (15, 45));
    }

    #[test]
    fn mismatched_sizes_are_an_error() {
        let a = Image::gray_from_fn(1, 1, |_, _| 0.0);
        let b = Image::gray_from_fn(2, 1, |_, _| 0.0);
        assert!(contact_sheet(&[&a, &b], 2, 0, [0.0; 4]).unwrap_err().contains("differ in size"));
    }
}
