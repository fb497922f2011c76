//! `imaging.hsv_auto_mask`: the HSV flame mask of the Eigenfires thesis (§3.2) with its value and
//! saturation thresholds chosen per clip, so new footage needs no hand-tuned layers.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, ClipOf, Cook, CookCtx, FrameSource, Image, Mask, NodeError, PortType, Value, port};

use super::hsv::{Blend, HsvLayer, HsvRange, hsv_mask, rgb_to_hsv};
use crate::convert::unit_to_u8;

/// The threshold of Otsu's method on a 256-bin histogram: the level `t` that maximizes the
/// between-class variance of `< t` against `≥ t`; `None` for an empty histogram or one level.
///
/// Written here rather than taken from imageproc: its `otsu_level` takes an image, and this
/// histogram is of the pixels of a hue band gathered over many frames.
pub fn otsu(hist: &[u64; 256]) -> Option<u8> {
    let total: u64 = hist.iter().sum();
    let sum: f64 = hist.iter().enumerate().map(|(i, &n)| i as f64 * n as f64).sum();
    let (mut below, mut below_sum) = (0u64, 0.0f64);
    let mut best: Option<(f64, u8)> = None;
    for t in 1..256 {
        below += hist[t - 1];
        below_sum += (t - 1) as f64 * hist[t - 1] as f64;
        let above = total - below;
        if below == 0 || above == 0 {
            continue;
        }
        let (m0, m1) = (below_sum / below as f64, (sum - below_sum) / above as f64);
        let between = below as f64 * above as f64 * (m0 - m1).powi(2);
        if best.is_none_or(|(b, _)| between > b) {
            best = Some((between, t as u8));
        }
    }
    best.map(|(_, t)| t)
}

/// Value and saturation thresholds for the flame pixels of `frames` (RGBA): Otsu's threshold on
/// the value of the pixels whose hue lies in `hues` (wrapping when min > max), then Otsu's on the
/// saturation of those at or above it, never below `s_floor`. `None` when no pixel has a hue in
/// the band.
pub fn auto_thresholds<'a>(frames: impl Iterator<Item = &'a Image>, hues: (f32, f32), s_floor: f32) -> Option<(f32, f32)> {
    auto_levels(frames, hues, s_floor).map(|(v, s, _)| (v, s))
}

/// [`auto_thresholds`] with the value histogram of the band's pixels (for [`core_level`]).
pub fn auto_levels<'a>(
    frames: impl Iterator<Item = &'a Image>,
    hues: (f32, f32),
    s_floor: f32,
) -> Option<(f32, f32, Box<[u64; 256]>)> {
    let mut levels = BandHistograms::new(hues);
    frames.for_each(|img| levels.add(img));
    levels.thresholds(s_floor)
}

/// What the thresholds are chosen from, gathered one frame at a time so a clip of any length is
/// read without holding its frames: the value histogram of the band's pixels with a saturation
/// histogram per value level (so the second Otsu pass needs no second read), and for gray frames
/// the value histogram of every pixel.
#[derive(Clone)]
pub struct BandHistograms {
    band: HsvRange,
    v_hist: [u64; 256],
    s_by_v: Vec<[u64; 256]>,
    gray_hist: [u64; 256],
    /// Frames added: RGBA and gray.
    rgba: usize,
    gray: usize,
}

impl BandHistograms {
    /// Empty histograms for the flame's hue band `hues` (wrapping when min > max).
    pub fn new(hues: (f32, f32)) -> BandHistograms {
        BandHistograms {
            band: HsvRange { h_min: hues.0, h_max: hues.1, s_min: 0.0, s_max: 255.0, v_min: 0.0, v_max: 255.0 },
            v_hist: [0; 256],
            s_by_v: vec![[0; 256]; 256],
            gray_hist: [0; 256],
            rgba: 0,
            gray: 0,
        }
    }

    /// Counts one frame's pixels.
    pub fn add(&mut self, img: &Image) {
        if img.channels() == Channels::Gray {
            self.gray += 1;
            for &v in img.data() {
                self.gray_hist[usize::from(unit_to_u8(v))] += 1;
            }
            return;
        }
        self.rgba += 1;
        for px in img.data().chunks_exact(4) {
            let hsv = rgb_to_hsv(px[0], px[1], px[2]);
            if hsv[1] > 0.0 && self.band.contains(hsv) {
                self.v_hist[hsv[2] as usize] += 1;
                self.s_by_v[hsv[2] as usize][hsv[1] as usize] += 1;
            }
        }
    }

    /// The counts of both, as if every frame of each had been added to one.
    pub fn merge(mut self, other: &BandHistograms) -> BandHistograms {
        let add = |a: &mut [u64; 256], b: &[u64; 256]| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        add(&mut self.v_hist, &other.v_hist);
        add(&mut self.gray_hist, &other.gray_hist);
        self.s_by_v.iter_mut().zip(&other.s_by_v).for_each(|(a, b)| add(a, b));
        self.rgba += other.rgba;
        self.gray += other.gray;
        self
    }

    /// Value and saturation thresholds of the RGBA frames (see [`auto_thresholds`]), with the
    /// value histogram; `None` when no pixel has a hue in the band.
    pub fn thresholds(&self, s_floor: f32) -> Option<(f32, f32, Box<[u64; 256]>)> {
        // One level only (a flat synthetic flame): every band pixel is flame.
        let v_min = otsu(&self.v_hist).or_else(|| self.v_hist.iter().position(|&c| c > 0).map(|v| v as u8))?;
        let mut s_hist = [0u64; 256];
        for row in &self.s_by_v[v_min as usize..] {
            for (a, b) in s_hist.iter_mut().zip(row) {
                *a += b;
            }
        }
        let s_min = otsu(&s_hist).map_or(s_floor, |s| f32::from(s).max(s_floor));
        Some((f32::from(v_min), s_min, Box::new(self.v_hist)))
    }
}

/// The value from which a pixel counts as the white-hot core: `fraction` of the brightest value
/// of the band's flame pixels (their 99.5th percentile, so a few hot pixels do not set it), never
/// below `v_min`. Relative to the clip's own brightest flame, so a darker exposure lowers it too.
pub fn core_level(v_hist: &[u64; 256], v_min: f32, fraction: f32) -> f32 {
    let from = v_min.clamp(0.0, 255.0) as usize;
    let total: u64 = v_hist[from..].iter().sum();
    let mut seen = 0u64;
    let top = (from..256)
        .rev()
        .find(|&v| {
            seen += v_hist[v];
            seen as f64 >= 0.005 * total as f64
        })
        .unwrap_or(255);
    (fraction * top as f32).max(v_min)
}

/// `band` with the components of `core` that touch it (8-connected, one pixel apart): the
/// white-hot core joins the flame it sits in, glare elsewhere stays out.
///
/// By hand because imageproc's labelling would need a second pass to find the touching labels;
/// one flood fill from the band does both.
pub fn join_core(band: &Mask, core: &Mask) -> Mask {
    let (w, h) = (band.width() as usize, band.height() as usize);
    let (b, c) = (band.data(), core.data());
    let mut out = b.to_vec();
    let mut stack: Vec<usize> = (0..w * h).filter(|&i| b[i] > 0).collect();
    while let Some(i) = stack.pop() {
        let (x, y) = (i % w, i / w);
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if c[j] > 0 && out[j] == 0 {
                    out[j] = 255;
                    stack.push(j);
                }
            }
        }
    }
    Mask::from_vec(band.width(), band.height(), out).unwrap_or_else(|| band.clone())
}

pyrograph_core::node! {
    /// The HSV flame mask of the Eigenfires thesis (§3.2, eq. 3–4) with thresholds chosen per clip: Otsu's
    /// method on the value of the pixels whose hue lies in the flame's band (sampled every `stride` frames)
    /// splits flame from background, then Otsu's on their saturation drops pale glare, never below `s_min_floor`;
    /// lit wax and glass, which glow pink-orange, stay out by hue. Every frame is masked with one layer of that
    /// band and, when `blue_base` is on, one of the blue base (200–260°), both at the chosen thresholds.
    /// The chosen thresholds are outputs, so an artist can freeze them in imaging.hsv_mask. A gray clip (no hue) is
    /// split by Otsu's method on the value alone.
    #[node("imaging.hsv_auto_mask", "Pre-processing", WholeClip)]
    pub struct HsvAutoMask {
        /// Frames to segment (RGBA; gray frames are split by value alone).
        clip: ClipOf<Arc<Image>>,
        // Candle and wood flames are 20–60° where they are bright; lit wax and glass glow
        // pink-orange below 20° (a tea-light's holder fills a frame with it).
        /// Lowest hue of the flame band, in degrees (above hue_max wraps past red).
        #[range(0.0, 360.0)]
        hue_min: f32 = 20.0,
        /// Highest hue of the flame band, in degrees.
        #[range(0.0, 360.0)]
        hue_max: f32 = 70.0,
        /// Also keep the flame's blue base (hues 200–260) at the chosen thresholds.
        blue_base: bool = true,
        /// Lowest saturation threshold the method may choose (0–255).
        #[range(0.0, 255.0)]
        s_min_floor: f32 = 40.0,
        /// Frames sampled for the thresholds: every stride-th.
        #[range(1, 100_000)]
        stride: usize = 5,
        /// Also keep the white-hot core where it touches the flame: pixels at least core_level of the flame's brightest value, white (saturation up to core_s_max) or in the flame's hue band at any saturation (a candle's core is nearly white, so the saturation threshold drops it).
        core: bool = true,
        /// The core's value threshold as a fraction of the flame's brightest value (its 99.5th percentile).
        #[range(0.5, 1.0)]
        core_level: f32 = 0.85,
        // A tea-light's lit wax and glass glow as brightly as its flame, tinted pink-orange
        // (saturation 70–100 at hue 0–20°), while a flame's hottest parts are white or yellow.
        /// A core pixel outside the flame's hue band must be nearly white: saturation at most this (0–255).
        #[range(0.0, 255.0)]
        core_s_max: f32 = 40.0,
    }
    pub struct HsvAutoMaskOut {
        /// 255 where the flame is, per frame.
        mask: ClipOf<Arc<Mask>>,
        /// The value threshold chosen (0–255): imaging.hsv_mask's v_min.
        value_threshold: f32,
        /// The saturation threshold chosen (0–255): imaging.hsv_mask's s_min.
        saturation_threshold: f32,
        /// The core's value threshold chosen (0–255; 255 with core off).
        core_threshold: f32,
    }
}

/// Masks every frame of a clip with fixed layers.
struct MaskSource {
    clip: Clip,
    layers: Vec<HsvLayer>,
    /// The core's layers (none with core off), joined where they touch the band.
    core: Vec<HsvLayer>,
    /// For a gray clip: the value (0–255) from which a pixel is flame, instead of the layers.
    gray: Option<f32>,
}

impl FrameSource for MaskSource {
    fn len(&self) -> usize {
        self.clip.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let Value::Image(img) = self.clip.get(index, ctx)? else {
            return Err(NodeError::port(port!(HsvAutoMask, clip), format!("frame {index} is not an image")));
        };
        if let Some(t) = self.gray {
            if img.channels() != Channels::Gray {
                return Err(NodeError::port(
                    port!(HsvAutoMask, clip),
                    format!("frame {index} is RGBA but the clip's sampled frames are gray; every frame must be the same kind"),
                ));
            }
            let data = img.data().iter().map(|&v| if f32::from(unit_to_u8(v)) >= t { 255 } else { 0 }).collect();
            let mask = Mask::from_vec(img.width(), img.height(), data)
                .ok_or_else(|| NodeError::port(port!(HsvAutoMask, clip), format!("frame {index}: mask size")))?;
            return Ok(Value::Mask(Arc::new(mask)));
        }
        let band = hsv_mask(&img, &self.layers)?;
        let mask = if self.core.is_empty() { band } else { join_core(&band, &hsv_mask(&img, &self.core)?) };
        Ok(Value::Mask(Arc::new(mask)))
    }
}

impl Cook for HsvAutoMask {
    fn cook(self, ctx: &CookCtx) -> Result<HsvAutoMaskOut, NodeError> {
        use rayon::prelude::*;
        let clip: &Clip = &self.clip;
        let picks: Vec<usize> = (0..clip.len()).step_by(self.stride.max(1)).collect();
        // Each sampled frame is counted and dropped: memory does not grow with the clip (a 1080p
        // clip of 1,000 frames held its 200 samples, 6.6 GB). Threads take turns decoding.
        let levels = picks
            .par_iter()
            .try_fold(
                || BandHistograms::new((self.hue_min, self.hue_max)),
                |mut acc, &i| {
                    ctx.check_cancel()?;
                    let Value::Image(img) = clip.get(i, ctx)? else {
                        return Err(NodeError::port(port!(HsvAutoMask, clip), format!("frame {i} is not an image")));
                    };
                    acc.add(&img);
                    Ok(acc)
                },
            )
            .try_reduce(|| BandHistograms::new((self.hue_min, self.hue_max)), |a, b| Ok(a.merge(&b)))?;
        if levels.gray > 0 && levels.rgba > 0 {
            return Err(NodeError::port(
                port!(HsvAutoMask, clip),
                "the clip mixes gray and RGBA frames; every frame must be the same kind",
            ));
        }
        if levels.gray > 0 {
            return HsvAutoMask::gray_masks(clip, &levels.gray_hist);
        }
        let sampled = picks.len();
        let (v_min, s_min, v_hist) = levels.thresholds(self.s_min_floor).ok_or_else(|| {
            NodeError::port(
                port!(HsvAutoMask, hue_min),
                format!(
                    "no pixel of the {sampled} sampled frames has a hue in {}–{}°: widen the band",
                    self.hue_min, self.hue_max
                ),
            )
        })?;
        let layer = |h_min, h_max| HsvLayer {
            range: HsvRange { h_min, h_max, s_min, s_max: 255.0, v_min, v_max: 255.0 },
            blend: Blend::Add,
        };
        let mut layers = vec![layer(self.hue_min, self.hue_max)];
        if self.blue_base {
            layers.push(layer(200.0, 260.0));
        }
        let core_v = if self.core { core_level(&v_hist, v_min, self.core_level) } else { 255.0 };
        let core_layer = |h_min, h_max, s_max| HsvLayer {
            range: HsvRange { h_min, h_max, s_min: 0.0, s_max, v_min: core_v, v_max: 255.0 },
            blend: Blend::Add,
        };
        let core = if self.core {
            vec![core_layer(0.0, 360.0, self.core_s_max), core_layer(self.hue_min, self.hue_max, 255.0)]
        } else {
            Vec::new()
        };
        let mut h = Fingerprinter::new();
        ("imaging.hsv_auto_mask", clip.fingerprint(), format!("{layers:?} {core:?}")).hash(&mut h);
        let source = MaskSource { clip: clip.clone(), layers, core, gray: None };
        let masks = Clip::new(PortType::Mask, clip.fps(), h.finish(), Arc::new(source));
        Ok(HsvAutoMaskOut {
            mask: ClipOf::new(masks),
            value_threshold: v_min,
            saturation_threshold: s_min,
            core_threshold: core_v,
        })
    }
}

impl HsvAutoMask {
    /// The masks of a gray clip (no hue to select by: a pre-processed or monochrome plate): Otsu's
    /// threshold on `hist`, the value of every sampled pixel.
    fn gray_masks(clip: &Clip, hist: &[u64; 256]) -> Result<HsvAutoMaskOut, NodeError> {
        let t = f32::from(otsu(hist).ok_or_else(|| {
            NodeError::port(
                port!(HsvAutoMask, clip),
                "every sampled gray frame has one value: no flame to tell from the background",
            )
        })?);
        let mut h = Fingerprinter::new();
        ("imaging.hsv_auto_mask gray", clip.fingerprint(), t.to_bits()).hash(&mut h);
        let source = MaskSource { clip: clip.clone(), layers: Vec::new(), core: Vec::new(), gray: Some(t) };
        let masks = Clip::new(PortType::Mask, clip.fps(), h.finish(), Arc::new(source));
        Ok(HsvAutoMaskOut { mask: ClipOf::new(masks), value_threshold: t, saturation_threshold: 0.0, core_threshold: 255.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn otsu_splits_two_clusters_between_them() {
        let mut hist = [0u64; 256];
        hist[20] = 1000;
        hist[21] = 500;
        hist[200] = 300;
        hist[210] = 200;
        let t = otsu(&hist).unwrap();
        assert!((22..=200).contains(&t), "{t}");
        assert_eq!(otsu(&[0; 256]), None);
        let mut one = [0u64; 256];
        one[7] = 9;
        assert_eq!(otsu(&one), None);
    }

    /// A 60×40 frame of `paint`'s colours (times `brightness`) over dim reddish noise (background
    /// lit by the flame) where it paints nothing.
    fn painted(brightness: f32, paint: impl Fn(u32, u32) -> Option<[f32; 3]>) -> Image {
        let (w, h) = (60u32, 40u32);
        let mut data = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h {
            for x in 0..w {
                let rgb = paint(x, y).unwrap_or_else(|| {
                    let n = ((x * 7 + y * 13) % 10) as f32 / 100.0;
                    [0.06 + n, 0.03 + n / 2.0, 0.02]
                });
                data.extend(rgb.map(|c| c * brightness));
                data.push(1.0);
            }
        }
        Image::from_vec(w, h, Channels::Rgba, data).unwrap()
    }

    /// A bright saturated orange flame and a bright pale pink glare (glowing wax).
    fn frame(brightness: f32) -> Image {
        painted(brightness, |x, y| {
            if (20..35).contains(&x) && (5..30).contains(&y) {
                Some([1.0, 0.55, 0.1])
            } else if (45..55).contains(&x) && (10..20).contains(&y) {
                Some([1.0, 0.85, 0.85])
            } else {
                None
            }
        })
    }

    #[test]
    fn thresholds_keep_the_flame_and_drop_the_background_and_the_pale_glare_at_any_exposure() {
        for brightness in [1.0, 0.25] {
            let img = frame(brightness);
            let (v, s) = auto_thresholds(std::iter::once(&img), (340.0, 70.0), 40.0).unwrap();
            let layer = HsvLayer {
                range: HsvRange { h_min: 340.0, h_max: 70.0, s_min: s, s_max: 255.0, v_min: v, v_max: 255.0 },
                blend: Blend::Add,
            };
            let mask = hsv_mask(&img, &[layer]).unwrap();
            let inside = |x: u32, y: u32| mask.get(x, y);
            assert!(inside(25, 15) && inside(34, 29), "{brightness}: the flame is kept (v {v}, s {s})");
            assert!(!inside(2, 2) && !inside(58, 38), "{brightness}: the background is dropped (v {v}, s {s})");
            assert!(!inside(50, 15), "{brightness}: the pale glare is dropped (v {v}, s {s})");
        }
        // A flat flame on a background outside the band: one level, all of it flame.
        let flat = Image::from_vec(2, 1, Channels::Rgba, vec![1.0, 0.55, 0.1, 1.0, 0.02, 0.01, 0.01, 1.0]).unwrap();
        let (v, _) = auto_thresholds(std::iter::once(&flat), (20.0, 70.0), 40.0).unwrap();
        assert_eq!(v, 255.0);
        let black = Image::new(8, 8, Channels::Rgba);
        assert!(auto_levels(std::iter::once(&black), (340.0, 70.0), 40.0).is_none());
        assert_eq!(auto_thresholds(std::iter::once(&black), (340.0, 70.0), 40.0), None);
    }

    #[test]
    fn the_core_joins_where_it_touches_the_flame_and_glare_stays_out() {
        let m = |w: u32, h: u32, on: &dyn Fn(u32, u32) -> bool| {
            Mask::from_vec(
                w,
                h,
                (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| if on(x, y) { 255 } else { 0 }).collect(),
            )
            .unwrap()
        };
        // The band: a ring of orange around a hole (the white core); a second white blob far off.
        let band = m(20, 10, &|x, y| (2..9).contains(&x) && (2..8).contains(&y) && !((4..7).contains(&x) && (4..6).contains(&y)));
        let core =
            m(20, 10, &|x, y| ((4..7).contains(&x) && (4..6).contains(&y)) || ((14..18).contains(&x) && (3..6).contains(&y)));
        let joined = join_core(&band, &core);
        assert!(joined.get(5, 4), "the core inside the flame joins it");
        assert!(!joined.get(15, 4), "the glare apart from it does not");
        assert!(joined.get(2, 2), "the band itself stays");
    }

    /// A yellow flame with a white core, and lit wax beside it as bright as the flame but tinted
    /// pink-orange (hue 14°, saturation 0.35), touching it: a tea-light in its holder.
    #[test]
    fn lit_wax_touching_the_flame_stays_out_of_the_mask() {
        let img = painted(1.0, |x, y| {
            if (25..30).contains(&x) && (15..25).contains(&y) {
                Some([1.0, 1.0, 1.0])
            } else if (20..35).contains(&x) && (5..30).contains(&y) {
                Some([1.0, 0.75, 0.2])
            } else if (35..55).contains(&x) && (20..38).contains(&y) {
                Some([0.97, 0.71, 0.63])
            } else {
                None
            }
        });
        let clip = Clip::from_frames(PortType::Image, 24.0, vec![Value::Image(Arc::new(img))]);
        let node = HsvAutoMask {
            clip: ClipOf::new(clip),
            hue_min: 20.0,
            hue_max: 70.0,
            blue_base: true,
            s_min_floor: 40.0,
            stride: 1,
            core: true,
            core_level: 0.85,
            core_s_max: 40.0,
        };
        let ctx = CookCtx::new();
        let out = node.cook(&ctx).unwrap();
        let Value::Mask(mask) = out.mask.get(0, &ctx).unwrap() else { panic!("a mask") };
        assert!(mask.get(22, 8) && mask.get(27, 20), "the flame and its white core are kept");
        assert!(!mask.get(45, 30) && !mask.get(36, 25), "the lit wax is left out");
    }

    #[test]
    fn a_gray_clip_is_split_by_value() {
        let mut data = vec![0.05_f32; 40 * 30];
        for y in 8..25 {
            for x in 15..25 {
                data[y * 40 + x] = 0.9;
            }
        }
        let img = Image::from_vec(40, 30, Channels::Gray, data).unwrap();
        let clip = Clip::from_frames(PortType::Image, 24.0, vec![Value::Image(Arc::new(img))]);
        let ctx = CookCtx::new();
        let hist_of = |c: &Clip| {
            let mut levels = BandHistograms::new((20.0, 70.0));
            levels.add(&c.image(0, &ctx).unwrap());
            levels.gray_hist
        };
        let out = HsvAutoMask::gray_masks(&clip, &hist_of(&clip)).unwrap();
        let Value::Mask(mask) = out.mask.get(0, &ctx).unwrap() else { panic!("a mask") };
        assert!(mask.get(20, 15) && !mask.get(2, 2), "flame in, background out (threshold {})", out.value_threshold);
        let flat = Image::from_vec(4, 4, Channels::Gray, vec![0.5; 16]).unwrap();
        let flat_clip = Clip::from_frames(PortType::Image, 24.0, vec![Value::Image(Arc::new(flat))]);
        assert!(HsvAutoMask::gray_masks(&flat_clip, &hist_of(&flat_clip)).is_err());
    }

    #[test]
    fn histograms_gathered_in_parts_choose_what_one_pass_chooses() {
        let frames: Vec<Image> = (0..6)
            .map(|k| {
                painted(0.5 + 0.1 * k as f32, |x, y| {
                    ((20..40).contains(&x) && (5..35).contains(&y)).then_some([1.0, 0.6 + 0.01 * y as f32, 0.1])
                })
            })
            .collect();
        let whole = auto_levels(frames.iter(), (20.0, 70.0), 40.0).unwrap();
        let mut a = BandHistograms::new((20.0, 70.0));
        let mut b = BandHistograms::new((20.0, 70.0));
        frames[..2].iter().for_each(|f| a.add(f));
        frames[2..].iter().for_each(|f| b.add(f));
        assert_eq!(a.merge(&b).thresholds(40.0).unwrap(), whole);
    }

    #[test]
    fn the_core_level_follows_the_exposure() {
        // Flame values spread up to 250 (bright) or 125 (two stops darker in 8-bit).
        let hist = |top: usize| {
            let mut h = [0u64; 256];
            h[40..=top].fill(10);
            h
        };
        let bright = core_level(&hist(250), 60.0, 0.85);
        let dark = core_level(&hist(125), 30.0, 0.85);
        assert!((bright - 211.0).abs() < 2.0, "{bright}");
        assert!((dark - 105.0).abs() < 2.0, "{dark}");
        assert_eq!(core_level(&hist(70), 65.0, 0.85), 65.0, "never below the band's threshold");
    }
}
