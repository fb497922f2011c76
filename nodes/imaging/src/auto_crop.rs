//! `imaging.auto_crop`: the flame framed automatically, so a clip pyrograph has never seen needs
//! no hand-tuned crop rectangle.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, FrameSource, Image, Mask, NodeError, Value, port};

use crate::blobs::{RegionSelect, TRACKED_PER_FRAME, fire_boxes, mask_box, rank_over_clip};
use crate::crop::crop;

pyrograph_core::choice! {
    /// How `imaging.auto_crop` combines the per-frame boxes of the flame.
    pub enum BoxCombine {
        /// The smallest box holding the flame in every frame.
        Union = "union",
        /// Each edge at a percentile of the frames' edges: a stray flare in a few frames is left out.
        Percentile = "percentile",
    }
}

pyrograph_core::node! {
    /// Crops a clip around its flame without a hand-set rectangle (Eigenfires thesis §3.1 and §4.2: footage
    /// is cropped around the fire, centred on its fuel, to drop the static background). The box around the
    /// flame mask of each frame is combined over the clip — their union, or each edge at a percentile of the
    /// frames' edges — grown by a margin, optionally made square, its size rounded up to a multiple, and
    /// kept inside the frame. With several fires in the plate, fires frames them all (one box around the group), the largest, or one by rank (pieces about a percent of the frame apart or nearer count as one fire). Outputs the cropped clip and the box, so an artist can freeze it in
    /// imaging.crop. Frames with an empty mask are left out of the box and listed in a warning, as is a flame
    /// that touches an edge of the picture in a quarter of the frames or more (its base or tip outside it); a
    /// mask empty in every frame is an error. A fire that fills the picture (its box over the clip spans max_fill
    /// of the frame's width or height: a bonfire, a flame filmed too close) has no single axis to straighten: fills
    /// is true, with one warning in place of the edge warnings of its sides and top, and imaging.pose_normalize fed
    /// it leaves every frame unturned and unscaled.
    #[node("imaging.auto_crop", "Pre-processing", WholeClip)]
    pub struct AutoCrop {
        /// The clip to crop.
        clip: ClipOf<Arc<Image>>,
        /// The flame mask of each frame (imaging.hsv_mask), the size of the clip's frames.
        mask: ClipOf<Arc<Mask>>,
        /// Union of the boxes, or each edge at a percentile.
        combine: BoxCombine = BoxCombine::Union,
        /// Percentile mode: the share of frames (percent) whose flame edge the box reaches.
        #[range(50.0, 100.0)]
        percentile: f64 = 98.0,
        /// Margin on every side, as a fraction of the box's larger side.
        #[range(0.0, 10.0)]
        margin: f64 = 0.1,
        /// Make the box square (about its centre).
        square: bool = false,
        /// Round the box's width and height up to a multiple of this (1: exact).
        #[range(1, 1024)]
        multiple: u32 = 8,
        /// A flame whose box over the clip spans this fraction of the frame's width or height fills the picture
        #[range(0.05, 1.0)]
        max_fill: f64 = 0.9,
        /// all: one box around every fire of the mask; largest: around the largest fire; index: around the fire of that rank (0 the largest). Fires are followed from frame to frame (a fire's box overlapping its box a few frames before) and ranked by their size over the whole clip, so the choice does not swap between two fires of about one size; frames the chosen fire is missing from are left out of the box, with a warning
        fires: RegionSelect = RegionSelect::All,
        /// With fires = index: the fire to frame, 0 for the largest
        #[range(0, 100_000)]
        index: usize = 0,
    }
    pub struct AutoCropOut {
        /// The cropped clip.
        clip: ClipOf<Arc<Image>>,
        /// Left edge of the box, in pixels.
        x: u32,
        /// Top edge of the box, in pixels.
        y: u32,
        /// Width of the box.
        width: u32,
        /// Height of the box.
        height: u32,
        /// The fire fills the picture: connect to imaging.pose_normalize's fills.
        fills: bool,
    }
}

/// A box `[left, top, right, bottom)` in pixels.
type PixelBox = [u32; 4];

/// The value at `fraction` (0..1) of sorted `v` (nearest rank).
fn rank(v: &[u32], fraction: f64) -> u32 {
    let i = ((v.len() - 1) as f64 * fraction.clamp(0.0, 1.0)).round() as usize;
    v[i.min(v.len() - 1)]
}

/// Combines per-frame boxes (at least one) into one (see `imaging.auto_crop`).
pub fn combine_boxes(boxes: &[PixelBox], combine: BoxCombine, percentile: f64) -> PixelBox {
    let edge = |k: usize| {
        let mut v: Vec<u32> = boxes.iter().map(|b| b[k]).collect();
        v.sort_unstable();
        v
    };
    let p = percentile / 100.0;
    match combine {
        BoxCombine::Union => {
            let [l, t, r, b] = [0, 1, 2, 3].map(edge);
            [l[0], t[0], r[r.len() - 1], b[b.len() - 1]]
        }
        // Left and top edges low, right and bottom edges high: the box reaches the flame's edge
        // in `percentile` % of the frames on every side.
        BoxCombine::Percentile => [rank(&edge(0), 1.0 - p), rank(&edge(1), 1.0 - p), rank(&edge(2), p), rank(&edge(3), p)],
    }
}

/// Grows `b` by `margin` × its larger side, optionally squares it, rounds its size up to a
/// multiple of `multiple`, and fits it inside a `width × height` frame (shifted in, and shrunk to
/// the frame — to a multiple where the frame allows — when larger). Returns `(x, y, w, h)`.
pub fn frame_box(b: PixelBox, margin: f64, square: bool, multiple: u32, width: u32, height: u32) -> (u32, u32, u32, u32) {
    let (cx, cy) = (f64::from(b[0] + b[2]) / 2.0, f64::from(b[1] + b[3]) / 2.0);
    let (mut w, mut h) = (f64::from(b[2] - b[0]), f64::from(b[3] - b[1]));
    let grow = margin * w.max(h);
    (w, h) = (w + 2.0 * grow, h + 2.0 * grow);
    if square {
        (w, h) = (w.max(h), w.max(h));
    }
    let m = f64::from(multiple.max(1));
    let fit = |size: f64, frame: u32| {
        let rounded = (size / m).ceil() * m;
        if rounded <= f64::from(frame) {
            rounded as u32
        } else {
            // The frame is smaller: the largest multiple inside it, or the whole frame.
            let inside = (f64::from(frame) / m).floor() * m;
            if inside >= 1.0 { inside as u32 } else { frame }
        }
    };
    let (w, h) = (fit(w, width), fit(h, height));
    let place =
        |centre: f64, size: u32, frame: u32| (centre - f64::from(size) / 2.0).round().clamp(0.0, f64::from(frame - size)) as u32;
    (place(cx, w, width), place(cy, h, height), w, h)
}

/// What a flame cut by the edge below it means, and what to do (also `flame_model.fit`'s words).
pub const BASE_OUTSIDE: &str = "its base is outside the picture; crop lower or use a clip where the base is visible";

/// Whether `touching` of `frames` flame frames touching an edge is a framing problem: a flame
/// grazing an edge now and then is a flare, a quarter of the frames or more is the framing.
/// Counted in whole frames, so exactly a quarter counts.
pub fn is_framing_problem(touching: usize, frames: usize) -> bool {
    touching > 0 && 4 * touching >= frames
}

/// The warning for a flame touching `edge` in `touching` of `frames` frames, and what it means.
pub fn edge_warning(edge: &str, touching: usize, frames: usize, what: &str) -> String {
    format!("the flame touches the {edge} edge in {:.0} % of frames: {what}", 100.0 * touching as f64 / frames.max(1) as f64)
}

/// What the masks say about the footage that the user should know: frames without a flame, and
/// a flame cut by an edge of the picture (its base below the frame, its tip above it).
pub fn framing_warnings(boxes: &[PixelBox], empty: &[usize], frames: usize, (width, height): (u32, u32)) -> Vec<String> {
    let mut out = Vec::new();
    if !empty.is_empty() {
        out.push(format!(
            "the mask is empty in {} of {frames} frames ({}): those frames have no flame in the box",
            empty.len(),
            pyrograph_core::frames::list_for_message(empty)
        ));
    }
    let touching = |f: &dyn Fn(&PixelBox) -> bool| boxes.iter().filter(|b| f(b)).count();
    let edges: [(&str, usize, &str); 4] = [
        ("bottom", touching(&|b| b[3] >= height), BASE_OUTSIDE),
        ("top", touching(&|b| b[1] == 0), "its tip is outside the picture; the flame's height is cut"),
        ("left", touching(&|b| b[0] == 0), "the flame is cut at the side"),
        ("right", touching(&|b| b[2] >= width), "the flame is cut at the side"),
    ];
    for (edge, k, what) in edges {
        if is_framing_problem(k, boxes.len()) {
            out.push(edge_warning(edge, k, boxes.len(), what));
        }
    }
    out
}

/// Whether a fire whose box spans `span` (width, height) fills a `frame` (width, height): it
/// reaches `max_fill` of either side. `imaging.auto_crop`'s rule over a clip, which
/// `imaging.pose_normalize` follows through its `fills`.
pub fn fills_picture(span: (f64, f64), frame: (f64, f64), max_fill: f64) -> bool {
    span.0 >= max_fill * frame.0 || span.1 >= max_fill * frame.1
}

/// What a fire filling the picture means and what is done about it: `span` is how much of the
/// frame the fire's box over the clip spans (auto crop), `None` for one frame's outline (pose).
pub fn fill_warning(span: Option<f64>, max_fill: f64) -> String {
    let what = match span {
        Some(share) => format!("its box over the clip spans {:.0} % of the frame's width or height", 100.0 * share),
        None => format!("in frames like this the outline spans {:.0} % of the frame's width or more", 100.0 * max_fill),
    };
    format!(
        "the fire fills the picture ({what}): it has no single axis, so it is neither turned nor scaled; crop to one \
         flame with room around it to straighten it"
    )
}

/// How much of a `width` × `height` frame the box `b` spans: the larger of its width's and its
/// height's share.
pub fn box_span(b: PixelBox, (width, height): (u32, u32)) -> f64 {
    (f64::from(b[2] - b[0]) / f64::from(width.max(1))).max(f64::from(b[3] - b[1]) / f64::from(height.max(1)))
}

/// Frames of a clip, cropped to one box.
struct CropSource {
    clip: Clip,
    rect: (u32, u32, u32, u32),
}

impl FrameSource for CropSource {
    fn len(&self) -> usize {
        self.clip.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let Value::Image(img) = self.clip.get(index, ctx)? else {
            return Err(NodeError::port(port!(AutoCrop, clip), format!("frame {index} is not an image")));
        };
        let (x, y, w, h) = self.rect;
        if x + w > img.width() || y + h > img.height() {
            return Err(NodeError::port(
                port!(AutoCrop, clip),
                format!(
                    "frame {index} is {}x{}, smaller than the {w}x{h} box at ({x}, {y}) found in the masks: the mask and the clip must be the same size",
                    img.width(),
                    img.height()
                ),
            ));
        }
        Ok(Value::Image(Arc::new(crop(&img, x, y, w, h)?)))
    }
}

impl Cook for AutoCrop {
    fn cook(self, ctx: &CookCtx) -> Result<AutoCropOut, NodeError> {
        let masks: &Clip = &self.mask;
        // Every frame's mask cooks the chain above it (a decode and a mask at full size): in
        // parallel, in frame order; only the boxes are kept. Each thread walks long runs of
        // frames: a video is decoded forward, and threads taking turns on neighbouring frames
        // send reads behind the decoder (a new one from the last keyframe), most of all when
        // the masks look back over frames (imaging.fire_cues).
        use rayon::prelude::*;
        let found = (0..masks.len())
            .into_par_iter()
            .with_min_len(crate::media::long_runs(masks.len()))
            .map(|i| {
                ctx.check_cancel()?;
                let Value::Mask(mask) = masks.get(i, ctx)? else {
                    return Err(NodeError::port(port!(AutoCrop, mask), format!("frame {i} is not a mask")));
                };
                let all = mask_box(&mask);
                // A few boxes a frame (the largest fires), ranked over the clip below.
                let fires = match self.fires {
                    RegionSelect::All => Vec::new(),
                    _ => fire_boxes(&mask).into_iter().take(TRACKED_PER_FRAME).collect(),
                };
                Ok(((mask.width(), mask.height()), all, fires))
            })
            .collect::<Result<Vec<_>, NodeError>>()?;
        let size = found.first().map(|(s, _, _)| *s);
        let chosen: Vec<Option<PixelBox>> = match self.fires {
            RegionSelect::All => found.iter().map(|(_, all, _)| *all).collect(),
            RegionSelect::Largest | RegionSelect::Index => {
                let rank = if self.fires == RegionSelect::Largest { 0 } else { self.index };
                let fires: Vec<_> = found.iter().map(|(_, _, f)| f.clone()).collect();
                rank_over_clip(&fires, rank)
            }
        };
        let (mut boxes, mut empty, mut fewer) = (Vec::new(), Vec::new(), Vec::new());
        for (i, (b, (_, all, _))) in chosen.into_iter().zip(&found).enumerate() {
            match (b, all.is_some()) {
                (Some(b), _) => boxes.push(b),
                (None, true) => fewer.push(i),
                (None, false) => empty.push(i),
            }
        }
        if !fewer.is_empty() {
            let which =
                if self.fires == RegionSelect::Largest { "the largest".to_string() } else { format!("index {}", self.index) };
            ctx.warn(format!(
                "the fire chosen ({}, ranked by its size over the clip) is not in {} of {} frames ({}): they are left out of the box",
                which,
                fewer.len(),
                masks.len(),
                pyrograph_core::frames::list_for_message(&fewer)
            ));
        }
        let Some((width, height)) = size else {
            return Err(NodeError::port(port!(AutoCrop, mask), "the mask clip has no frames"));
        };
        if boxes.is_empty() {
            return Err(NodeError::port(
                port!(AutoCrop, mask),
                if fewer.is_empty() {
                    format!(
                        "the mask is empty in all {} frames: no flame to frame (check the HSV mask's thresholds)",
                        masks.len()
                    )
                } else {
                    format!(
                        "fires = index {}: the clip holds fewer fires than that, followed from frame to frame (lower index, or fires = all)",
                        self.index
                    )
                },
            ));
        }
        let b = combine_boxes(&boxes, self.combine, self.percentile);
        let rect = frame_box(b, self.margin, self.square, self.multiple, width, height);
        let span = box_span(b, (width, height));
        let fills = span >= self.max_fill;
        for warning in framing_warnings(&boxes, &empty, masks.len(), (width, height)) {
            // A fire filling the picture reaches its sides and top: one warning says so, below. A
            // base outside the picture is another matter (a learned flame needs it) and stays.
            if !fills || warning.contains(BASE_OUTSIDE) || !warning.starts_with("the flame touches") {
                ctx.warn(warning);
            }
        }
        if fills {
            ctx.warn(fill_warning(Some(span), self.max_fill));
        }
        let clip: &Clip = &self.clip;
        let mut h = Fingerprinter::new();
        ("imaging.auto_crop", clip.fingerprint(), rect).hash(&mut h);
        let cropped =
            Clip::new(clip.element().clone(), clip.fps(), h.finish(), Arc::new(CropSource { clip: clip.clone(), rect }));
        Ok(AutoCropOut { clip: ClipOf::new(cropped), x: rect.0, y: rect.1, width: rect.2, height: rect.3, fills })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask_with(w: u32, h: u32, rect: PixelBox) -> Mask {
        let data = (0..w * h)
            .map(|i| u8::from((rect[0]..rect[2]).contains(&(i % w)) && (rect[1]..rect[3]).contains(&(i / w))))
            .collect();
        Mask::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn a_flame_cut_by_the_bottom_edge_and_empty_frames_are_reported() {
        let cut: Vec<PixelBox> = (0..10).map(|i| [10, 20, 30, if i < 9 { 60 } else { 50 }]).collect();
        let w = framing_warnings(&cut, &[3, 17], 12, (80, 60));
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("empty in 2 of 12 frames (3, 17)"), "{}", w[0]);
        assert!(w[1].contains("bottom edge in 90 % of frames") && w[1].contains("base is outside"), "{}", w[1]);
        let whole: Vec<PixelBox> = vec![[10, 5, 30, 50]; 10];
        assert!(framing_warnings(&whole, &[], 10, (80, 60)).is_empty());
    }

    #[test]
    fn a_fire_fills_the_picture_when_its_box_spans_most_of_the_frame_either_way() {
        assert_eq!(box_span([30, 10, 60, 70], (100, 80)), 0.75);
        assert!(!fills_picture((30.0, 60.0), (100.0, 80.0), 0.9));
        assert_eq!(box_span([2, 10, 98, 40], (100, 80)), 0.96, "wide");
        assert_eq!(box_span([40, 0, 50, 76], (100, 80)), 0.95, "tall");
        assert!(fills_picture((10.0, 76.0), (100.0, 80.0), 0.9) && fills_picture((96.0, 30.0), (100.0, 80.0), 0.9));
        let w = fill_warning(Some(0.96), 0.9);
        assert!(w.contains("fills the picture (its box over the clip spans 96 % of the frame's width or height)"), "{w}");
        assert!(fill_warning(None, 0.9).contains("in frames like this the outline spans 90 % of the frame's width or more"));
    }

    /// Cooks the node with `margin` 0.1 over masks whose flame is the box of each frame in `boxes`,
    /// in 100 × 80 frames; returns whether it fills and the warnings.
    fn cook_boxes(boxes: &[PixelBox]) -> (AutoCropOut, Vec<String>) {
        let frames: Vec<Vec<PixelBox>> = boxes.iter().map(|b| vec![*b]).collect();
        cook_fires(&frames, RegionSelect::All, 0).unwrap()
    }

    /// [`cook_boxes`] with several fires a frame (each a box), framing `fires` (`index`).
    fn cook_fires(frames: &[Vec<PixelBox>], fires: RegionSelect, index: usize) -> Result<(AutoCropOut, Vec<String>), String> {
        use pyrograph_core::{PortType, Value};
        let masks = frames
            .iter()
            .map(|boxes| {
                let mut m = Mask::new(100, 80);
                for b in boxes {
                    let one = mask_with(100, 80, *b);
                    m = Mask::from_vec(100, 80, m.data().iter().zip(one.data()).map(|(a, b)| a | b).collect()).unwrap();
                }
                Value::Mask(Arc::new(m))
            })
            .collect();
        let images = frames.iter().map(|_| Value::Image(Arc::new(Image::new(100, 80, pyrograph_core::Channels::Gray)))).collect();
        let node = AutoCrop {
            clip: ClipOf::new(Clip::from_frames(PortType::Image, 24.0, images)),
            mask: ClipOf::new(Clip::from_frames(PortType::Mask, 24.0, masks)),
            combine: BoxCombine::Union,
            percentile: 98.0,
            margin: 0.1,
            square: false,
            multiple: 8,
            max_fill: 0.9,
            fires,
            index,
        };
        let ctx = CookCtx::new();
        let out = node.cook(&ctx).map_err(|e| e.to_string())?;
        Ok((out, ctx.warnings().into_iter().map(|w| w.message).collect()))
    }

    #[test]
    fn a_fire_chosen_by_rank_is_followed_over_the_clip_and_its_absence_is_reported() {
        // Two fires of about one size that swap the lead every frame (the left one larger in
        // even frames); the right one is missing in frames 4 and 5, so over the clip the left is
        // the largest (6,240 pixels against 4,800).
        let frames: Vec<Vec<PixelBox>> = (0..8)
            .map(|t| {
                let left = if t % 2 == 0 { [10, 20, 30, 60] } else { [10, 22, 30, 60] };
                let right = if t % 2 == 0 { [60, 22, 80, 60] } else { [60, 18, 80, 60] };
                if (4..6).contains(&t) { vec![left] } else { vec![left, right] }
            })
            .collect();
        let (out, warnings) = cook_fires(&frames, RegionSelect::Largest, 0).unwrap();
        assert!(out.x + out.width < 60, "the left fire alone, in every frame: x {} width {}", out.x, out.width);
        assert!(warnings.is_empty(), "{warnings:?}");
        let (out, warnings) = cook_fires(&frames, RegionSelect::Index, 1).unwrap();
        assert!(out.x > 30, "the right fire alone: x {}", out.x);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].contains("(index 1, ranked by its size over the clip) is not in 2 of 8 frames (4, 5)"),
            "{}",
            warnings[0]
        );
        let err = cook_fires(&frames, RegionSelect::Index, 2).err().unwrap();
        assert!(err.contains("fires = index 2: the clip holds fewer fires than that"), "{err}");
    }

    #[test]
    fn a_clip_that_fills_the_picture_says_so_once_and_keeps_its_base_warning() {
        // A flame swaying across the frame: wall to wall over the clip, cut at both sides.
        let sway: Vec<PixelBox> = (0..8).map(|i| if i % 2 == 0 { [0, 20, 60, 70] } else { [40, 20, 100, 70] }).collect();
        let (out, warnings) = cook_boxes(&sway);
        assert!(out.fills);
        assert_eq!(warnings.len(), 1, "the side edges are part of filling the picture: {warnings:?}");
        assert!(warnings[0].contains("spans 100 % of the frame's width or height"), "{}", warnings[0]);
        // Its base below the frame as well: that is said apart (a learned flame needs its base).
        let cut: Vec<PixelBox> = sway.iter().map(|b| [b[0], b[1], b[2], 80]).collect();
        let (_, warnings) = cook_boxes(&cut);
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(warnings.iter().any(|w| w.contains(BASE_OUTSIDE)));
        // One flame with room around it: no fill, no warning.
        let (out, warnings) = cook_boxes(&[[40, 20, 60, 60]; 8]);
        assert!(!out.fills && warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn one_fire_of_several_is_framed_by_rank_and_pieces_of_one_fire_count_as_one() {
        let mut data = vec![0u8; 200 * 100];
        let mut fill = |r: PixelBox| {
            for y in r[1]..r[3] {
                for x in r[0]..r[2] {
                    data[(y * 200 + x) as usize] = 255;
                }
            }
        };
        fill([10, 10, 30, 60]); // 1,000 px
        fill([100, 20, 110, 40]); // 200 px, and its tip 2 px above it: one fire
        fill([100, 15, 110, 18]);
        fill([150, 70, 160, 80]); // 100 px
        let mask = Mask::from_vec(200, 100, data).unwrap();
        let fire_box = |rank: usize| fire_boxes(&mask).get(rank).map(|(_, b)| *b);
        assert_eq!(fire_box(0), Some([10, 10, 30, 60]));
        assert_eq!(fire_box(1), Some([100, 15, 110, 40]));
        assert_eq!(fire_box(2), Some([150, 70, 160, 80]));
        assert_eq!(fire_box(3), None);
        assert_eq!(mask_box(&mask), Some([10, 10, 160, 80]));
    }

    #[test]
    fn the_box_of_a_mask_is_its_set_pixels() {
        assert_eq!(mask_box(&mask_with(40, 30, [5, 7, 12, 20])), Some([5, 7, 12, 20]));
        assert_eq!(mask_box(&Mask::new(8, 8)), None);
    }

    #[test]
    fn union_holds_every_box_and_a_percentile_leaves_out_a_stray_flare() {
        let mut boxes = vec![[10, 10, 20, 40]; 99];
        boxes.push([0, 0, 60, 45]);
        assert_eq!(combine_boxes(&boxes, BoxCombine::Union, 98.0), [0, 0, 60, 45]);
        assert_eq!(combine_boxes(&boxes, BoxCombine::Percentile, 98.0), [10, 10, 20, 40]);
    }

    #[test]
    fn the_frame_box_has_its_margin_multiple_and_stays_inside_the_frame() {
        // 10 × 30 box, margin 0.1 × 30 = 3 a side: 16 × 36, up to multiples of 8: 16 × 40.
        let (x, y, w, h) = frame_box([20, 10, 30, 40], 0.1, false, 8, 100, 100);
        assert_eq!((w, h), (16, 40));
        assert_eq!((x, y), (17, 5), "centred on (25, 25)");
        // Square, at the frame's corner: shifted inside.
        let (x, y, w, h) = frame_box([0, 0, 10, 30], 0.0, true, 8, 100, 100);
        assert_eq!((x, y, w, h), (0, 0, 32, 32));
        // Larger than the frame: the largest multiple inside it.
        let (x, y, w, h) = frame_box([0, 0, 90, 60], 0.5, false, 8, 100, 70);
        assert_eq!((x, y, w, h), (0, 0, 96, 64));
        for (b, m) in [([3, 4, 9, 11], 1), ([50, 60, 99, 99], 8), ([0, 0, 1, 1], 16)] {
            let (x, y, w, h) = frame_box(b, 0.2, true, m, 100, 100);
            assert!(x + w <= 100 && y + h <= 100 && w > 0 && h > 0, "{b:?}: {x} {y} {w} {h}");
            assert!(x <= b[0] && y <= b[1] && x + w >= b[2] && y + h >= b[3], "{b:?} inside ({x}, {y}, {w}, {h})");
        }
    }
}
