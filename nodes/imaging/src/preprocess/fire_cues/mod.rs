//! `imaging.fire_cues`: a colour mask keeps what looks like fire; this node keeps what also
//! behaves like fire. Stock fire is shot on black, but in a scene plate a lamp, a sunlit patch or a
//! glowing wall has the flame's colours and its brightness. Fire flickers (its brightness changes
//! from frame to frame at 2–15 Hz where a lit wall holds still) and is brighter than what is
//! around it; each blob of the mask is judged by both cues and dropped when it lacks either.
//!
//! Sources: the temporal cue follows Töreyin, Dedeoğlu, Güdükbay & Çetin, "Computer vision based
//! method for real-time fire and flame detection" (Pattern Recognition Letters 27, 2006), whose
//! flicker test is the energy of the first temporal wavelet band (a frame difference) of each
//! fire-coloured pixel, and Phillips, Shah & da Vitoria Lobo, "Flame recognition in video"
//! (Pattern Recognition Letters 23, 2002), who judge colour candidates by their temporal variation
//! over a window of frames. The brightness cue is Chen, Wu & Chiou's "brighter than its
//! surroundings" rule ("An early fire-detection method based on image processing", ICIP 2004).

use std::collections::VecDeque;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, FrameSource, Image, Mask, NodeError, PortType, Value, port};

use crate::blobs::label_fires;
use crate::filters::Plane;

/// Longest side of the plane the flicker is measured on: larger frames are box-averaged down by
/// halves, so a 4K frame costs about what a 1080p one does and camera noise averages out.
pub const WORK_SIDE: usize = 960;

pyrograph_core::node! {
    /// Keeps the blobs of a fire mask that behave like fire, not only look like it, so lamps, windows, sunlit patches and lit walls of fire-like colour in a scene plate drop out (extends Eigenfires thesis §3.2, whose flames are filmed on black; flicker after Töreyin et al. 2006 and Phillips et al. 2002, relative brightness after Chen et al. 2004).
    ///
    /// Flicker: each pixel's mean absolute brightness change between consecutive frames over the window frames before it (the first temporal wavelet band of Töreyin et al.), each change taken as the smallest over a shift of up to reach pixels, so a camera moving a pixel or two or leftover shake after imaging.stabilize does not count as flicker. Measured on the frame box-averaged down to at most 960 pixels a side; pixels with alpha 0 (no picture: the border imaging.stabilize brings in from outside the frame, a cut-out's clear background) are not measured, so a border moving from frame to frame is not flicker (a gray clip has no alpha: its border is black and is measured). A blob of the mask (pieces about a percent of the frame's size apart or nearer count as one) is kept when its mean flicker reaches min_flicker of its mean brightness (so a darker exposure is judged alike) and its mean brightness is min_contrast times that of the unmasked pixels around it (its box grown by half its size each way). The flicker output shows each pixel's flicker as a share of its brightness, 0.5 at min_flicker. A clip of one or two frames has no flicker to judge and passes unchanged, with a warning.
    #[node("imaging.fire_cues", "Pre-processing", WholeClip)]
    pub struct FireCues {
        /// The frames the mask was made from (stabilize a handheld clip first).
        clip: ClipOf<Arc<Image>>,
        /// The fire mask of each frame (imaging.hsv_auto_mask), the size of the clip's frames.
        mask: ClipOf<Arc<Mask>>,
        /// Frames before a frame over which its flicker is measured (after it, for the clip's first frames).
        #[range(1, 60)]
        window: usize = 8,
        /// A blob whose mean brightness change per frame is less than this share of its mean brightness is still, not fire.
        #[range(0.0, 1.0)]
        min_flicker: f64 = 0.003,
        /// A blob must be this many times as bright as the unmasked pixels around it.
        #[range(0.0, 100.0)]
        min_contrast: f64 = 1.05,
        /// Pixels of shift (on the measuring plane) a change may be explained by before it counts as flicker.
        #[range(0, 8)]
        reach: usize = 1,
    }
    pub struct FireCuesOut {
        /// The mask with the blobs that are not fire removed.
        mask: ClipOf<Arc<Mask>>,
        /// Each pixel's flicker as a share of its brightness, as a gray image: 0.5 at min_flicker.
        flicker: ClipOf<Arc<Image>>,
    }
}

/// A frame's luminance on the measuring plane, the halvings that made it, and the frame's size.
type Measured = (Arc<Plane>, u32, (u32, u32));

/// The planes of the frames read last by one thread walking a run of frames, newest at the back.
type Ring = VecDeque<(usize, Measured)>;

/// What both outputs read; also the clip of flicker images.
#[derive(Clone)]
struct Cues {
    clip: Clip,
    mask: Clip,
    window: usize,
    min_flicker: f64,
    min_contrast: f64,
    reach: usize,
}

impl Cues {
    /// Frame `index`'s luminance on the measuring plane, from `ring` when it is there (and kept
    /// there, at most a window's worth).
    fn plane(&self, index: usize, ring: &mut Ring, ctx: &CookCtx) -> Result<Measured, NodeError> {
        if let Some((_, m)) = ring.iter().find(|(i, _)| *i == index) {
            return Ok(m.clone());
        }
        let Value::Image(img) = self.clip.get(index, ctx)? else {
            return Err(NodeError::port(port!(FireCues, clip), format!("frame {index} is not an image")));
        };
        let (p, halvings) = work_plane(&img);
        let measured = (Arc::new(p), halvings, img.size());
        if ring.len() > self.window + 1 {
            ring.pop_front();
        }
        ring.push_back((index, measured.clone()));
        Ok(measured)
    }

    /// Frame `index`'s flicker plane (inside the full-size box `region` only, when given) and its
    /// luminance, with the halvings and the frame's size.
    fn flicker(
        &self,
        index: usize,
        region: Option<[u32; 4]>,
        ring: &mut Ring,
        ctx: &CookCtx,
    ) -> Result<(Plane, Measured), NodeError> {
        let (lo, hi) = window_of(index, self.window, self.clip.len());
        let mut planes = Vec::with_capacity(hi - lo + 1);
        for t in lo..=hi {
            ctx.check_cancel()?;
            planes.push(self.plane(t, ring, ctx)?);
        }
        let (here, halvings, size) = planes[index - lo].clone();
        if let Some((t, (_, _, s))) = planes.iter().enumerate().map(|(k, p)| (lo + k, p)).find(|(_, p)| p.2 != size) {
            return Err(NodeError::port(
                port!(FireCues, clip),
                format!(
                    "frame {t} is {}x{} but frame {index} is {}x{}: every frame must be the same size",
                    s.0, s.1, size.0, size.1
                ),
            ));
        }
        let refs: Vec<&Plane> = planes.iter().map(|(p, _, _)| p.as_ref()).collect();
        let on_plane = region.map(|[x0, y0, x1, y1]| {
            let s = halvings;
            let edge = |v: u32, most: usize| ((v >> s) as usize).min(most);
            [
                edge(x0, here.width),
                edge(y0, here.height),
                (edge(x1, here.width) + 1).min(here.width),
                (edge(y1, here.height) + 1).min(here.height),
            ]
        });
        Ok((flicker_plane(&refs, self.reach, on_plane), (here, halvings, size)))
    }

    /// Frame `index`'s mask.
    fn mask(&self, index: usize, ctx: &CookCtx) -> Result<Arc<Mask>, NodeError> {
        match self.mask.get(index, ctx)? {
            Value::Mask(m) => Ok(m),
            _ => Err(NodeError::port(port!(FireCues, mask), format!("frame {index} is not a mask"))),
        }
    }

    /// Which fires of frame `index`'s mask (by [`label_fires`]' labels, 0 unused) are kept.
    fn judge(&self, index: usize, ring: &mut Ring, ctx: &CookCtx) -> Result<Vec<bool>, NodeError> {
        let mask = self.mask(index, ctx)?;
        // A frame with nothing masked has nothing to judge, and no frame before it is read.
        let Some(set) = crate::blobs::mask_box(&mask) else { return Ok(Vec::new()) };
        let (flicker, (luma, halvings, size)) = self.flicker(index, Some(set), ring, ctx)?;
        if size != (mask.width(), mask.height()) {
            return Err(NodeError::port(
                port!(FireCues, mask),
                format!(
                    "frame {index}'s mask is {}x{} but its frame is {}x{}: the mask and the clip must be the same size",
                    mask.width(),
                    mask.height(),
                    size.0,
                    size.1
                ),
            ));
        }
        Ok(judge_fires(&mask, &flicker, &luma, halvings, self.min_flicker, self.min_contrast))
    }
}

/// The cue-judged masks: each frame's mask with the fires judged in the cook kept.
struct MaskSource {
    cues: Cues,
    /// Per frame, which fires are kept; `None` for a clip too short to judge.
    verdicts: Option<Arc<Vec<Vec<bool>>>>,
}

impl FrameSource for MaskSource {
    fn len(&self) -> usize {
        self.cues.mask.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let mask = self.cues.mask(index, ctx)?;
        let Some(keep) = self.verdicts.as_ref().and_then(|v| v.get(index)) else {
            // A copy: the frame cache keeps a frame held outside it, so the input's own mask
            // cached by both clips would pin itself.
            return Ok(Value::Mask(Arc::new((*mask).clone())));
        };
        Ok(Value::Mask(Arc::new(keep_fires(&mask, keep))))
    }
}

/// The flicker measure as images: the cues themselves are that clip (and their helpers are
/// its per-frame cook).
impl FrameSource for Cues {
    fn len(&self) -> usize {
        self.clip.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let mut ring = Ring::new();
        if self.clip.len() < 3 {
            let (p, halvings, size) = self.plane(index, &mut ring, ctx)?;
            return Ok(Value::Image(Arc::new(upsample(&Plane::new(p.width, p.height), halvings, size, 1.0))));
        }
        let (mut flicker, (luma, halvings, size)) = self.flicker(index, None, &mut ring, ctx)?;
        // As a share of the pixel's brightness, as blobs are judged; dark pixels are not divided
        // by their noise.
        flicker.data.iter_mut().zip(&luma.data).for_each(|(f, l)| *f /= l.max(0.1));
        let gain = 0.5 / self.min_flicker.max(1e-6) as f32;
        Ok(Value::Image(Arc::new(upsample(&flicker, halvings, size, gain))))
    }
}

impl Cook for FireCues {
    fn cook(self, ctx: &CookCtx) -> Result<FireCuesOut, NodeError> {
        use rayon::prelude::*;
        let (clip, mask): (&Clip, &Clip) = (&self.clip, &self.mask);
        if clip.len() != mask.len() {
            return Err(NodeError::port(
                port!(FireCues, mask),
                format!(
                    "the mask has {} frames but the clip has {}: connect the mask made from this clip",
                    mask.len(),
                    clip.len()
                ),
            ));
        }
        let cues = Cues {
            clip: clip.clone(),
            mask: mask.clone(),
            window: self.window.max(1),
            min_flicker: self.min_flicker,
            min_contrast: self.min_contrast,
            reach: self.reach,
        };
        // Judged here, in one pass: each thread walks long runs of frames in order, keeping the
        // planes of the window behind it, so every frame is read once and forward (a video
        // decodes forward; frames looked back on by several threads at once sent reads behind
        // the decoder, a new one from the last keyframe each time). Only the verdicts are kept,
        // a few bytes a frame.
        let verdicts = if clip.len() < 3 {
            ctx.warn(format!("a clip of {} frame(s) has no flicker to judge: the mask passes unchanged", clip.len()));
            None
        } else {
            let n = clip.len();
            let v = (0..n)
                .into_par_iter()
                .with_min_len(crate::media::long_runs(n))
                .map_init(Ring::new, |ring, i| cues.judge(i, ring, ctx))
                .collect::<Result<Vec<Vec<bool>>, NodeError>>()?;
            Some(Arc::new(v))
        };
        let key = |what: u8| {
            let mut h = Fingerprinter::new();
            let params = (self.window, self.min_flicker.to_bits(), self.min_contrast.to_bits(), self.reach);
            ("imaging.fire_cues", what, clip.fingerprint(), mask.fingerprint(), params).hash(&mut h);
            h.finish()
        };
        let masks = Clip::new(PortType::Mask, mask.fps(), key(0), Arc::new(MaskSource { cues: cues.clone(), verdicts }));
        let image = clip.element().clone();
        let flicker = Clip::new(image, clip.fps(), key(1), Arc::new(cues));
        Ok(FireCuesOut { mask: ClipOf::new(masks), flicker: ClipOf::new(flicker) })
    }
}

/// The frames `[lo, hi]` whose changes measure frame `index`'s flicker in a clip of `n`: the
/// `window` frames before it and itself, or the first `window + 1` frames of the clip for the
/// frames before them.
pub fn window_of(index: usize, window: usize, n: usize) -> (usize, usize) {
    let lo = index.saturating_sub(window);
    (lo, (lo + window).max(index).min(n.saturating_sub(1)))
}

/// `img`'s luminance halved until its longer side is at most [`WORK_SIDE`], and how many halvings.
/// Pixels with no picture (alpha 0: past the frame's edge after `imaging.stabilize` turned and
/// moved it) are NaN, and so is every measuring pixel they touch: a border that moves from frame
/// to frame is not flicker.
pub fn work_plane(img: &Image) -> (Plane, u32) {
    let mut p = Plane::luminance(img);
    if img.channels() == pyrograph_core::Channels::Rgba {
        for (v, px) in p.data.iter_mut().zip(img.data().chunks_exact(4)) {
            if px[3] <= 0.0 {
                *v = f32::NAN;
            }
        }
    }
    let mut halvings = 0;
    while p.width.max(p.height) > WORK_SIDE {
        p = p.half();
        halvings += 1;
    }
    (p, halvings)
}

/// Mean absolute change between consecutive `planes` (same size, at least two), each change the
/// smallest over shifts of the earlier plane by up to `reach` pixels: a still scene moved a pixel
/// by the camera changes nothing, a flame's flicker does. Only inside `region` (`[x0, y0, x1, y1)`
/// on the plane) when given, zero outside: a mask's blobs need no more. A pair with no picture at
/// a pixel (NaN, see [`work_plane`]) adds no change there.
pub fn flicker_plane(planes: &[&Plane], reach: usize, region: Option<[usize; 4]>) -> Plane {
    use rayon::prelude::*;
    let (w, h) = (planes[0].width, planes[0].height);
    let mut out = Plane::new(w, h);
    if planes.len() < 2 {
        return out;
    }
    let [x0, y0, x1, y1] = region.unwrap_or([0, 0, w, h]);
    let r = reach as i64;
    out.data.par_chunks_mut(w.max(1)).enumerate().filter(|(y, _)| (y0..y1).contains(y)).for_each(|(y, row)| {
        // Pairs measured at each pixel: a pixel under the border in some frames is the mean of
        // the others, not understated by them.
        let mut pairs = vec![0u16; row.len()];
        for pair in planes.windows(2) {
            let (before, now) = (&pair[0], &pair[1]);
            for ((x, o), n) in row.iter_mut().enumerate().zip(pairs.iter_mut()).take(x1).skip(x0) {
                let v = now.data[y * w + x];
                if v.is_nan() {
                    continue;
                }
                // `min` passes over NaN: a neighbour with no picture explains nothing.
                let mut best = f32::MAX;
                for dy in -r..=r {
                    let yy = (y as i64 + dy).clamp(0, h as i64 - 1) as usize;
                    for dx in -r..=r {
                        let xx = (x as i64 + dx).clamp(0, w as i64 - 1) as usize;
                        best = best.min((v - before.data[yy * w + xx]).abs());
                    }
                }
                if best < f32::MAX {
                    *o += best;
                    *n += 1;
                }
            }
        }
        row.iter_mut().zip(&pairs).for_each(|(o, n)| *o /= f32::from((*n).max(1)));
    });
    out
}

/// One blob of the mask, summed.
#[derive(Clone, Copy, Default)]
struct Blob {
    pixels: f64,
    flicker: f64,
    brightness: f64,
    bounds: [usize; 4],
}

/// Which fires of `mask` (by [`label_fires`]' labels; index 0 unused) behave like fire: their
/// mean `flicker` reaches `min_flicker` of their mean brightness and that brightness is
/// `min_contrast` times that of the unmasked pixels around them. `flicker` and `luma` are on the
/// measuring plane, `halvings` times smaller than the mask.
pub fn judge_fires(mask: &Mask, flicker: &Plane, luma: &Plane, halvings: u32, min_flicker: f64, min_contrast: f64) -> Vec<bool> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let Some((labels, count)) = label_fires(mask) else { return Vec::new() };
    let on_plane = |x: usize, y: usize| ((y >> halvings).min(luma.height - 1)) * luma.width + (x >> halvings).min(luma.width - 1);
    let mut blobs = vec![Blob { bounds: [usize::MAX, usize::MAX, 0, 0], ..Blob::default() }; count + 1];
    for (i, l) in labels.iter().enumerate() {
        if *l == 0 {
            continue;
        }
        let (x, y) = (i % w, i / w);
        let b = &mut blobs[*l as usize];
        let k = on_plane(x, y);
        // A pixel with no picture tells nothing of the blob (see `work_plane`).
        if luma.data[k].is_nan() {
            continue;
        }
        b.pixels += 1.0;
        b.flicker += f64::from(flicker.data[k]);
        b.brightness += f64::from(luma.data[k]);
        b.bounds = [b.bounds[0].min(x), b.bounds[1].min(y), b.bounds[2].max(x + 1), b.bounds[3].max(y + 1)];
    }
    let around = Surroundings::new(mask, luma, halvings);
    blobs
        .iter()
        .map(|b| {
            if b.pixels == 0.0 {
                return false;
            }
            let [x0, y0, x1, y1] = b.bounds;
            let (gx, gy) = ((x1 - x0).div_ceil(2), (y1 - y0).div_ceil(2));
            let grown = [x0.saturating_sub(gx), y0.saturating_sub(gy), (x1 + gx).min(w), (y1 + gy).min(h)];
            // A little light in both keeps a blob on black from dividing by nothing.
            let contrast = (b.brightness / b.pixels + 0.02) / (around.mean(grown).unwrap_or(0.0) + 0.02);
            // Relative to the blob's brightness, so an exposure darker by stops flickers as much.
            b.flicker / b.brightness.max(1e-9) >= min_flicker && contrast >= min_contrast
        })
        .collect()
}

/// `mask` with only the fires `keep` marks (by [`label_fires`]' labels).
pub fn keep_fires(mask: &Mask, keep: &[bool]) -> Mask {
    let Some((labels, _)) = label_fires(mask) else { return mask.clone() };
    let data = labels.iter().map(|l| if keep.get(*l as usize).copied().unwrap_or(false) { 255 } else { 0 }).collect();
    Mask::from_vec(mask.width(), mask.height(), data).unwrap_or_else(|| mask.clone())
}

/// Summed-area tables of the unmasked pixels' brightness and count on the measuring plane, so the
/// surroundings of each blob cost four lookups however many blobs a frame has.
struct Surroundings {
    width: usize,
    halvings: u32,
    sum: Vec<f64>,
    count: Vec<f64>,
}

impl Surroundings {
    fn new(mask: &Mask, luma: &Plane, halvings: u32) -> Surroundings {
        let (w, h) = (luma.width, luma.height);
        // Share of each measuring pixel the mask leaves free: all of it, less each set pixel
        // (only the box around them is read).
        let mut free = vec![1.0f64; w * h];
        let per = f64::from(1u32 << (2 * halvings));
        if let Some([x0, y0, x1, y1]) = crate::blobs::mask_box(mask) {
            let mw = mask.width() as usize;
            for y in y0 as usize..y1 as usize {
                for x in x0 as usize..x1 as usize {
                    if mask.data()[y * mw + x] != 0 {
                        let k = ((y >> halvings).min(h - 1)) * w + (x >> halvings).min(w - 1);
                        free[k] = (free[k] - 1.0 / per).max(0.0);
                    }
                }
            }
        }
        let (mut sum, mut count) = (vec![0.0; (w + 1) * (h + 1)], vec![0.0; (w + 1) * (h + 1)]);
        for y in 0..h {
            let (mut row_sum, mut row_count) = (0.0, 0.0);
            for x in 0..w {
                // No picture counts as black, as the dark around a flame on black does.
                let v = luma.data[y * w + x];
                row_sum += free[y * w + x] * f64::from(if v.is_nan() { 0.0 } else { v });
                row_count += free[y * w + x];
                let k = (y + 1) * (w + 1) + x + 1;
                sum[k] = sum[k - (w + 1)] + row_sum;
                count[k] = count[k - (w + 1)] + row_count;
            }
        }
        Surroundings { width: w + 1, halvings, sum, count }
    }

    /// Mean brightness of the unmasked pixels in the full-size box `[x0, y0, x1, y1)`; `None` when
    /// it has none.
    fn mean(&self, b: [usize; 4]) -> Option<f64> {
        let s = self.halvings;
        let (x0, y0) = (b[0] >> s, b[1] >> s);
        let (x1, y1) =
            ((b[2].div_ceil(1 << s)).min(self.width - 1), (b[3].div_ceil(1 << s)).min(self.sum.len() / self.width - 1));
        let area =
            |t: &[f64]| t[y1 * self.width + x1] - t[y0 * self.width + x1] - t[y1 * self.width + x0] + t[y0 * self.width + x0];
        let n = area(&self.count);
        (n > 0.5).then(|| area(&self.sum) / n)
    }
}

/// `p` scaled by `gain`, clamped to 0..1 and enlarged back to `size` (nearest), as a gray image.
fn upsample(p: &Plane, halvings: u32, size: (u32, u32), gain: f32) -> Image {
    Image::gray_from_fn(size.0, size.1, |x, y| {
        let (px, py) = (((x >> halvings) as usize).min(p.width - 1), ((y >> halvings) as usize).min(p.height - 1));
        (p.data[py * p.width + px] * gain).clamp(0.0, 1.0)
    })
}

#[cfg(test)]
mod tests;
