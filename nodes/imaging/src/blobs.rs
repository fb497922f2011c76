//! The separate fires of a mask: their labels, boxes and ranks, shared by the nodes that find,
//! judge and frame them (`imaging.fire_cues`, `imaging.fire_regions`, `imaging.auto_crop`). Below
//! both the crop and the pre-processing modules, which each use it.

use image::{GrayImage, Luma};
use imageproc::region_labelling::{Connectivity, connected_components};
use pyrograph_core::Mask;

pyrograph_core::choice! {
    /// Which fires `imaging.fire_regions` keeps, or `imaging.auto_crop` frames.
    pub enum RegionSelect {
        /// Every fire at least min_share of the largest one's area (and min_area pixels).
        All = "all",
        /// The largest fire only.
        Largest = "largest",
        /// The fire at position index among the kept ones, largest first.
        Index = "index",
    }
}

/// The box around the set pixels of `mask`, `None` when it has none.
pub fn mask_box(mask: &Mask) -> Option<[u32; 4]> {
    let w = mask.width() as usize;
    let (mut left, mut top, mut right, mut bottom) = (u32::MAX, u32::MAX, 0, 0);
    for (i, _) in mask.data().iter().enumerate().filter(|(_, v)| **v != 0) {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        (left, top, right, bottom) = (left.min(x), top.min(y), right.max(x + 1), bottom.max(y + 1));
    }
    (left != u32::MAX).then_some([left, top, right, bottom])
}

/// Each set pixel's fire (1, 2, …; 0 where the mask is clear) and how many there are. Pieces of
/// one fire a few pixels apart (a tip, the blue base, a tongue cut by a threshold) are one: the
/// mask is labelled (8-connected) grown by half a percent of the frame's larger side, at least 2
/// pixels. `None` for a mask whose data does not match its size.
pub fn label_fires(mask: &Mask) -> Option<(Vec<u32>, usize)> {
    let (w, h) = (mask.width(), mask.height());
    if mask.data().len() != (w as usize) * (h as usize) {
        return None;
    }
    let mut labels = vec![0u32; mask.data().len()];
    // Labelled inside the box around the set pixels (with room to grow): a small fire in a large
    // frame costs its own size.
    let Some([x0, y0, x1, y1]) = mask_box(mask) else { return Some((labels, 0)) };
    let join = (w.max(h) / 200).clamp(2, 255);
    let (bx, by) = (x0.saturating_sub(join), y0.saturating_sub(join));
    let (bw, bh) = ((x1 + join).min(w) - bx, (y1 + join).min(h) - by);
    let inside = GrayImage::from_fn(bw, bh, |x, y| Luma([mask.data()[((by + y) * w + bx + x) as usize]]));
    let grown = imageproc::morphology::dilate(&inside, imageproc::distance_transform::Norm::LInf, join as u8);
    let local = connected_components(&grown, Connectivity::Eight, Luma([0u8]));
    let mut count = 0;
    for (x, y, l) in local.enumerate_pixels() {
        let i = ((by + y) * w + bx + x) as usize;
        if mask.data()[i] != 0 {
            labels[i] = l[0];
            count = count.max(l[0] as usize);
        }
    }
    Some((labels, count))
}

/// The box around the fire of rank `index` (0 the largest by pixels) of `mask`, `None` when it
/// has fewer fires (see [`label_fires`]).
pub fn fire_box(mask: &Mask, index: usize) -> Option<[u32; 4]> {
    let (labels, count) = label_fires(mask)?;
    let w = mask.width() as usize;
    let mut fires = vec![(0usize, [u32::MAX, u32::MAX, 0, 0]); count + 1];
    for (i, l) in labels.iter().enumerate().filter(|(_, l)| **l != 0) {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let (n, b) = &mut fires[*l as usize];
        *n += 1;
        *b = [b[0].min(x), b[1].min(y), b[2].max(x + 1), b[3].max(y + 1)];
    }
    fires.retain(|(n, _)| *n > 0);
    // Largest first; equal sizes by position, so a rank means the same fire from run to run.
    fires.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    fires.get(index).map(|(_, b)| *b)
}
