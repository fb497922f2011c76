//! The separate fires of a mask: their labels, boxes and ranks, shared by the nodes that find,
//! judge and frame them (`imaging.fire_cues`, `imaging.fire_regions`, `imaging.auto_crop`). Below
//! both the crop and the pre-processing modules, which each use it.

use image::{GrayImage, Luma};
use imageproc::region_labelling::{Connectivity, connected_components};
use pyrograph_core::Mask;

pyrograph_core::choice! {
    /// Which fires `imaging.fire_regions` keeps, or `imaging.auto_crop` frames.
    pub enum RegionSelect {
        /// Every fire (imaging.fire_regions: every one at least min_share of the largest one's area and min_area pixels).
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
/// pixels, so pieces about a percent apart or nearer join. `None` for a mask whose data does not match its size.
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

/// The fires of `mask` (see [`label_fires`]) as (pixels, box), largest first; equal sizes by
/// position, so a rank means the same fire from run to run.
pub fn fire_boxes(mask: &Mask) -> Vec<(usize, [u32; 4])> {
    let Some((labels, count)) = label_fires(mask) else { return Vec::new() };
    let w = mask.width() as usize;
    let mut fires = vec![(0usize, [u32::MAX, u32::MAX, 0, 0]); count + 1];
    for (i, l) in labels.iter().enumerate().filter(|(_, l)| **l != 0) {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let (n, b) = &mut fires[*l as usize];
        *n += 1;
        *b = [b[0].min(x), b[1].min(y), b[2].max(x + 1), b[3].max(y + 1)];
    }
    fires.retain(|(n, _)| *n > 0);
    fires.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    fires
}

/// Fires a frame's ranking over a clip follows, at most: specks past these add nothing to a rank.
pub const TRACKED_PER_FRAME: usize = 16;

/// Frames a fire may vanish for (a flicker below the threshold) and still be the same fire.
const TRACK_GAP: usize = 4;

/// The fire of rank `rank` over a whole clip (0 the largest), frame by frame: each frame's fires
/// (from [`fire_boxes`], in frame order) are followed from frame to frame (a fire whose box meets
/// a fire's box of the frame before, or of up to [`TRACK_GAP`] frames before, is that fire), the
/// followed fires ranked by their pixels summed over the clip, and per frame the box around the
/// chosen one's pieces given (`None` where it is not in that frame). Ranked once for the clip, so
/// two fires of about one size do not swap from frame to frame as per-frame ranks would.
pub fn rank_over_clip(frames: &[Vec<(usize, [u32; 4])>], rank: usize) -> Vec<Option<[u32; 4]>> {
    let meets = |a: [u32; 4], b: [u32; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
    // Per track: pixels over the clip, its box last seen and when.
    let mut tracks: Vec<(usize, [u32; 4], usize)> = Vec::new();
    let mut member: Vec<Vec<usize>> = Vec::with_capacity(frames.len());
    for (t, fires) in frames.iter().enumerate() {
        let mut here = Vec::with_capacity(fires.len());
        let mut seen: Vec<(usize, [u32; 4])> = Vec::new();
        for &(n, b) in fires.iter().take(TRACKED_PER_FRAME) {
            // The live track whose last box meets this one, the most recently seen first.
            let found = tracks
                .iter()
                .enumerate()
                .filter(|(_, (_, last, when))| *when < t && t - when <= TRACK_GAP && meets(*last, b))
                .max_by_key(|(k, (_, _, when))| (*when, usize::MAX - k))
                .map(|(k, _)| k);
            let k = found.unwrap_or_else(|| {
                tracks.push((0, b, t));
                tracks.len() - 1
            });
            tracks[k].0 += n;
            seen.push((k, b));
            here.push(k);
        }
        // Boxes are updated after the frame, so two pieces of this frame both find last frame's box.
        for (k, b) in seen {
            let (_, last, when) = &mut tracks[k];
            *last = if *when == t { union(*last, b) } else { b };
            *when = t;
        }
        member.push(here);
    }
    let mut order: Vec<usize> = (0..tracks.len()).collect();
    order.sort_by(|a, b| tracks[*b].0.cmp(&tracks[*a].0).then(a.cmp(b)));
    let Some(&chosen) = order.get(rank) else { return vec![None; frames.len()] };
    frames
        .iter()
        .zip(&member)
        .map(|(fires, ks)| fires.iter().zip(ks).filter(|(_, k)| **k == chosen).map(|((_, b), _)| *b).reduce(union))
        .collect()
}

fn union(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    [a[0].min(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].max(b[3])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_fires_of_about_one_size_keep_their_rank_over_the_clip() {
        // Left fire 100 px in even frames and 90 in odd ones; right fire 91 and 101, drifting
        // right; a speck in frame 2 only. Per frame, the largest would swap sides every frame.
        let frames: Vec<Vec<(usize, [u32; 4])>> = (0..6u32)
            .map(|t| {
                let (l, r) = if t % 2 == 0 { (100, 91) } else { (90, 101) };
                let mut f = vec![(l, [10, 10, 20, 20]), (r, [50 + t, 10, 60 + t, 20])];
                if t == 2 {
                    f.push((5, [80, 80, 82, 82]));
                }
                f.sort_by_key(|(n, _)| std::cmp::Reverse(*n));
                f
            })
            .collect();
        // Over the clip: right 576 px, left 570.
        let first = rank_over_clip(&frames, 0);
        assert!(first.iter().enumerate().all(|(t, b)| *b == Some([50 + t as u32, 10, 60 + t as u32, 20])), "{first:?}");
        let second = rank_over_clip(&frames, 1);
        assert!(second.iter().all(|b| *b == Some([10, 10, 20, 20])), "{second:?}");
        let speck = rank_over_clip(&frames, 2);
        assert_eq!(speck.iter().filter(|b| b.is_some()).count(), 1, "{speck:?}");
        assert!(rank_over_clip(&frames, 3).iter().all(Option::is_none));
    }

    #[test]
    fn a_fire_that_splits_and_a_fire_that_vanishes_for_a_frame_stay_one_fire() {
        let frames = vec![
            vec![(200, [10, 10, 30, 40])],
            vec![(120, [10, 10, 30, 25]), (80, [12, 26, 28, 40])],
            vec![],
            vec![(200, [11, 10, 31, 40])],
        ];
        let boxes = rank_over_clip(&frames, 0);
        assert_eq!(boxes, vec![Some([10, 10, 30, 40]), Some([10, 10, 30, 40]), None, Some([11, 10, 31, 40])]);
        assert!(rank_over_clip(&frames, 1).iter().all(Option::is_none), "one fire only");
    }
}
