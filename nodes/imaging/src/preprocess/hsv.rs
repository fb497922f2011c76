//! `imaging.hsv_mask`: the multi-layer HSV colour mask of the Eigenfires thesis (§3.2, eq. 3–4, Fig. 17).

use pyrograph_core::declare::Field;
use pyrograph_core::{Channels, Cook, CookCtx, Image, Inputs, Mask, NodeError, PortDesc, port};
use rayon::prelude::*;
use std::sync::Arc;

use crate::convert::unit_to_u8;

pyrograph_core::choice! {
    /// How one layer's mask combines with the masks of the layers above it (thesis Fig. 17).
    pub enum Blend {
        /// Union: inside if inside either.
        Add = "add",
        /// Removes this layer's pixels from the running mask.
        Subtract = "subtract",
        /// Symmetric difference (exclusive or).
        Difference = "difference",
        /// Intersection: inside only if inside both.
        Intersect = "intersect",
    }
}

impl Blend {
    /// Combines the running mask bit `acc` with this layer's bit `layer`.
    #[inline]
    pub fn apply(self, acc: bool, layer: bool) -> bool {
        match self {
            Blend::Add => acc | layer,
            Blend::Subtract => acc & !layer,
            Blend::Difference => acc ^ layer,
            Blend::Intersect => acc & layer,
        }
    }
}

/// One HSV range of eq. 4: hue in degrees 0–360, saturation and value on 0–255, all inclusive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HsvRange {
    /// Lowest hue; a `h_min` above `h_max` wraps past red (340..20 keeps magenta to orange).
    pub h_min: f32,
    /// Highest hue.
    pub h_max: f32,
    /// Lowest saturation.
    pub s_min: f32,
    /// Highest saturation.
    pub s_max: f32,
    /// Lowest value.
    pub v_min: f32,
    /// Highest value.
    pub v_max: f32,
}

impl HsvRange {
    /// Whether a pixel's `(h, s, v)` lies in the range (eq. 4).
    #[inline]
    pub fn contains(&self, [h, s, v]: [f32; 3]) -> bool {
        let hue_ok =
            if self.h_min <= self.h_max { h >= self.h_min && h <= self.h_max } else { h >= self.h_min || h <= self.h_max };
        hue_ok && s >= self.s_min && s <= self.s_max && v >= self.v_min && v <= self.v_max
    }
}

/// One enabled layer: a range and how it blends into the running mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HsvLayer {
    /// The colour range.
    pub range: HsvRange,
    /// How it combines with the layers before it.
    pub blend: Blend,
}

/// Eq. 3 on an 8-bit-quantized RGB pixel: hue in degrees `[0, 360)`, saturation and value on 0–255.
///
/// The inputs are quantized to bytes first and saturation is rounded, as OpenCV's 8-bit
/// `cvtColor(RGB2HSV)` does, so the default ranges select the same pixels as the OpenCV peer.
/// Eq. 3 as printed divides the hue by `S`; the standard formula (and OpenCV) divides by
/// `V − min(R, G, B)`, which is what is used here.
#[inline]
pub fn rgb_to_hsv(r: f32, g: f32, b: f32) -> [f32; 3] {
    let (r, g, b) = (f32::from(unit_to_u8(r)), f32::from(unit_to_u8(g)), f32::from(unit_to_u8(b)));
    let v = r.max(g).max(b);
    let delta = v - r.min(g).min(b);
    if delta <= 0.0 {
        return [0.0, 0.0, v];
    }
    let s = (255.0 * delta / v).round();
    let h = if v == r {
        60.0 * (g - b) / delta
    } else if v == g {
        120.0 + 60.0 * (b - r) / delta
    } else {
        240.0 + 60.0 * (r - g) / delta
    };
    [if h < 0.0 { h + 360.0 } else { h }, s, v]
}

/// Pixels per block of the fused pass: each stage runs over a whole block so it vectorizes.
const BLOCK: usize = 64;

/// `floor(y)` for `0 ≤ y < 2²²` in plain f32 arithmetic, so it vectorizes on baseline x86-64
/// (where `f32::floor` is a libm call and Rust's saturating `as i32` stays scalar): adding and
/// subtracting 2²³ rounds to the nearest integer, then one is taken off if that rounded up.
#[inline(always)]
fn floor_small(y: f32) -> f32 {
    const MAGIC: f32 = 8_388_608.0; // 2^23
    let nearest = (y + MAGIC) - MAGIC;
    if nearest > y { nearest - 1.0 } else { nearest }
}

/// `x` if above 0, else 0 (also for NaN): one `maxps`, where `f32::max` needs NaN fix-ups.
#[inline(always)]
fn positive(x: f32) -> f32 {
    if x > 0.0 { x } else { 0.0 }
}

/// The larger of two non-NaN values, as one `maxps`.
#[inline(always)]
fn larger(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// [`unit_to_u8`] as an f32, in a form that vectorizes: the clamp is two selects (NaN gives 0,
/// as `as u8` does there) and the truncation is [`floor_small`].
#[inline(always)]
fn quantize(x: f32) -> f32 {
    let x = positive(x);
    let x = if x < 1.0 { x } else { 1.0 };
    floor_small(x * 255.0 + 0.5)
}

/// The quantized channels of a block of pixels and their value `max(R, G, B)`.
struct Block {
    r: [f32; BLOCK],
    g: [f32; BLOCK],
    b: [f32; BLOCK],
    v: [f32; BLOCK],
}

impl Block {
    /// An all-black block (allocated once per row; the loads overwrite it).
    fn new() -> Block {
        Block { r: [0.0; BLOCK], g: [0.0; BLOCK], b: [0.0; BLOCK], v: [0.0; BLOCK] }
    }

    /// The quantized value `max(R, G, B)` of up to [`BLOCK`] RGBA pixels of `src`; lanes past its
    /// end keep stale pixels, whose results are never written out. Quantizing is monotone, so
    /// the value is the quantized maximum of the raw channels (made non-NaN first, as quantizing
    /// maps NaN and negatives to 0 alike): one quantization per pixel instead of three.
    #[inline(always)]
    fn load_value(&mut self, src: &[f32]) {
        for (v, px) in self.v.iter_mut().zip(src.chunks_exact(4)) {
            *v = quantize(larger(larger(positive(px[0]), positive(px[1])), positive(px[2])));
        }
    }

    /// The quantized channels of the same pixels as [`Block::load_value`].
    #[inline(always)]
    fn load_channels(&mut self, src: &[f32]) {
        for (i, px) in src.chunks_exact(4).take(BLOCK).enumerate() {
            self.r[i] = quantize(px[0]);
            self.g[i] = quantize(px[1]);
            self.b[i] = quantize(px[2]);
        }
    }

    /// Whether some lane's value lies in some layer's value range. A pixel outside every layer's
    /// value range is selected by none, and blending only unselected layers into the empty start
    /// mask leaves it outside, so such a block (dark background) needs no hue or saturation.
    /// Lanes are OR-ed without early exit so the test vectorizes.
    #[inline(always)]
    fn any_in_value_range(&self, layers: &[HsvLayer]) -> bool {
        let mut alive = [false; BLOCK];
        for l in layers {
            for (a, &v) in alive.iter_mut().zip(&self.v) {
                *a |= (v >= l.range.v_min) & (v <= l.range.v_max);
            }
        }
        alive.iter().fold(false, |any, &a| any | a)
    }

    /// Hue and saturation, computed branch-free with exactly the f32 operations of
    /// [`rgb_to_hsv`] (so bit-identical up to the sign of a zero hue, which no comparison sees).
    /// `round` (a libm call on baseline x86-64, and not vectorizable there) is `floor` plus one
    /// when the exact fraction `x − floor(x)` is at least ½, which equals `round` for `0 ≤ x ≤ 255`.
    #[inline(always)]
    fn hue_saturation(&self, h: &mut [f32; BLOCK], s: &mut [f32; BLOCK]) {
        for i in 0..BLOCK {
            let (r, g, b, max) = (self.r[i], self.g[i], self.b[i], self.v[i]);
            let min = if r < g { r } else { g };
            let delta = max - if min < b { min } else { b };
            let sat = 255.0 * delta / max;
            let floor = floor_small(sat);
            let sat = floor + if sat - floor >= 0.5 { 1.0 } else { 0.0 };
            let (num, offset) = if max == r {
                (g - b, 0.0)
            } else if max == g {
                (b - r, 120.0)
            } else {
                (r - g, 240.0)
            };
            let q = 60.0 * num / delta;
            let hue = if max == r { q } else { offset + q };
            let hue = if hue < 0.0 { hue + 360.0 } else { hue };
            let chromatic = delta > 0.0;
            h[i] = if chromatic { hue } else { 0.0 };
            s[i] = if chromatic { sat } else { 0.0 };
        }
    }
}

/// Blends one layer into the block's running mask, one loop per blend mode and hue form so each vectorizes.
#[inline(always)]
fn blend_block(acc: &mut [bool; BLOCK], layer: &HsvLayer, h: &[f32; BLOCK], s: &[f32; BLOCK], v: &[f32; BLOCK]) {
    let r = &layer.range;
    let sv = |i: usize| (s[i] >= r.s_min) & (s[i] <= r.s_max) & (v[i] >= r.v_min) & (v[i] <= r.v_max);
    macro_rules! fold {
        ($hue_ok:expr) => {
            match layer.blend {
                Blend::Add => (0..BLOCK).for_each(|i| acc[i] |= $hue_ok(h[i]) & sv(i)),
                Blend::Subtract => (0..BLOCK).for_each(|i| acc[i] &= !($hue_ok(h[i]) & sv(i))),
                Blend::Difference => (0..BLOCK).for_each(|i| acc[i] ^= $hue_ok(h[i]) & sv(i)),
                Blend::Intersect => (0..BLOCK).for_each(|i| acc[i] &= $hue_ok(h[i]) & sv(i)),
            }
        };
    }
    if r.h_min <= r.h_max {
        fold!(|h: f32| (h >= r.h_min) & (h <= r.h_max))
    } else {
        fold!(|h: f32| (h >= r.h_min) | (h <= r.h_max))
    }
}

/// Rows per rayon task in [`hsv_mask`].
const ROWS_PER_TASK: usize = 8;

/// The mask of eq. 4 repeated over `layers` and blended in order, starting from an empty mask.
///
/// Errors if `image` is not RGBA (the hue of a gray image is undefined), naming port `image`.
///
/// Per pixel this is `layers` folded over [`HsvRange::contains`] of [`rgb_to_hsv`], fused into
/// one pass over blocks of pixels that never builds an HSV image and has no data-dependent
/// branches (noisy flame edges made the per-pixel branches mispredict). Tests check it against
/// that definition on a grid of colours, random colours and random layers.
pub fn hsv_mask(image: &Image, layers: &[HsvLayer]) -> Result<Mask, HsvError> {
    if image.channels() != Channels::Rgba {
        return Err(HsvError::Image("needs an RGBA image: hue is undefined for a gray image".into()));
    }
    let (w, h) = image.size();
    let mut out = vec![0u8; w as usize * h as usize];
    // Rows are independent: a few rows per rayon task.
    out.par_chunks_mut(w.max(1) as usize)
        .zip(image.data().par_chunks(w.max(1) as usize * 4))
        .with_min_len(ROWS_PER_TASK)
        .for_each(|(row, src)| {
            let (mut hb, mut sb, mut blk) = ([0f32; BLOCK], [0f32; BLOCK], Block::new());
            for (dst, px) in row.chunks_mut(BLOCK).zip(src.chunks(BLOCK * 4)) {
                blk.load_value(px);
                if !blk.any_in_value_range(layers) {
                    dst.fill(0);
                    continue;
                }
                blk.load_channels(px);
                blk.hue_saturation(&mut hb, &mut sb);
                let mut acc = [false; BLOCK];
                for layer in layers {
                    blend_block(&mut acc, layer, &hb, &sb, &blk.v);
                }
                for (d, &a) in dst.iter_mut().zip(&acc) {
                    *d = if a { 255 } else { 0 };
                }
            }
        });
    Mask::from_vec(w, h, out).ok_or_else(|| HsvError::Message("internal: mask size mismatch".into()))
}

/// Why an image cannot be masked (`HsvMask`'s cook names the port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HsvError {
    /// The image has no hue (it is gray).
    #[error("{0}")]
    Image(String),
    /// Anything the image is not to blame for.
    #[error("{0}")]
    Message(String),
}

/// A mask error on the port of `imaging.hsv_mask` it concerns.
impl From<HsvError> for NodeError {
    fn from(e: HsvError) -> NodeError {
        match e {
            HsvError::Image(m) => NodeError::port(port!(HsvMask, image), m),
            HsvError::Message(m) => NodeError::msg(m),
        }
    }
}

/// The ports of one layer, `{prefix}_enabled`, `{prefix}_h_min` … `{prefix}_v_max`, `{prefix}_blend`:
/// declared once by its [`Field`] impl and used three times by [`HsvMask`], whose field name is the
/// prefix, whose `= default` the layer's defaults and whose doc the start of every port's doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HsvLayerPorts {
    /// Whether this layer contributes.
    pub enabled: bool,
    /// The colour range.
    pub range: HsvRange,
    /// How it combines with the layers above.
    pub blend: Blend,
}

impl HsvLayerPorts {
    /// The layer if it is enabled. A saturation or value minimum above its maximum is an error
    /// naming the `{prefix}_…_min` port: only hue ranges wrap.
    pub fn layer(&self, prefix: &str) -> Result<Option<HsvLayer>, NodeError> {
        if !self.enabled {
            return Ok(None);
        }
        let r = self.range;
        for (what, lo, hi) in [("s", r.s_min, r.s_max), ("v", r.v_min, r.v_max)] {
            if lo > hi {
                return Err(NodeError::port(
                    format!("{prefix}_{what}_min"),
                    format!("{lo} is above {prefix}_{what}_max {hi}; only hue ranges wrap"),
                ));
            }
        }
        Ok(Some(HsvLayer { range: r, blend: self.blend }))
    }
}

/// The field of an [`HsvRange`] that a port sets.
type RangeField = fn(&mut HsvRange) -> &mut f32;

/// The range ports of a layer in port order: name suffix, upper bound (the lower is 0), doc and
/// the range's field.
const RANGE_PORTS: [(&str, f64, &str, RangeField); 6] = [
    ("h_min", 360.0, "lowest hue in degrees; above h_max wraps past red", |r| &mut r.h_min),
    ("h_max", 360.0, "highest hue in degrees", |r| &mut r.h_max),
    ("s_min", 255.0, "lowest saturation (0–255)", |r| &mut r.s_min),
    ("s_max", 255.0, "highest saturation (0–255)", |r| &mut r.s_max),
    ("v_min", 255.0, "lowest value (0–255)", |r| &mut r.v_min),
    ("v_max", 255.0, "highest value (0–255)", |r| &mut r.v_max),
];

impl Field for HsvLayerPorts {
    fn describe(name: &str, doc: &str, default: Option<Self>, _: Option<(f64, f64)>, out: &mut Vec<PortDesc>) {
        let port = |suffix: &str| format!("{name}_{suffix}");
        let doc = |text: &str| format!("{doc}: {text}");
        <bool as Field>::describe(
            &port("enabled"),
            &doc("whether this layer contributes"),
            default.map(|d| d.enabled),
            None,
            out,
        );
        for (suffix, hi, text, field) in RANGE_PORTS {
            let value = default.map(|mut d| *field(&mut d.range));
            <f32 as Field>::describe(&port(suffix), &doc(text), value, Some((0.0, hi)), out);
        }
        let blend_doc = doc("how it combines with the layers above: add = union");
        <Blend as Field>::describe(&port("blend"), &blend_doc, default.map(|d| d.blend), None, out);
    }

    fn read(inputs: &Inputs<'_>, name: &str) -> Result<Self, NodeError> {
        let mut range = HsvRange { h_min: 0.0, h_max: 0.0, s_min: 0.0, s_max: 0.0, v_min: 0.0, v_max: 0.0 };
        for (suffix, _, _, field) in RANGE_PORTS {
            *field(&mut range) = <f32 as Field>::read(inputs, &format!("{name}_{suffix}"))?;
        }
        Ok(HsvLayerPorts {
            enabled: <bool as Field>::read(inputs, &format!("{name}_enabled"))?,
            range,
            blend: <Blend as Field>::read(inputs, &format!("{name}_blend"))?,
        })
    }
}

// Default layers, converted from the OpenCV peer's half-hue ranges (×2):
// blue (100,80,60)–(130,255,255), red (0,100,80)–(15,255,255), yellow (15,80,100)–(35,255,255).

/// Layer 1's defaults: the OpenCV peer's blue range, on.
pub const BLUE_DEFAULTS: HsvLayerPorts = HsvLayerPorts {
    enabled: true,
    range: HsvRange { h_min: 200.0, h_max: 260.0, s_min: 80.0, s_max: 255.0, v_min: 60.0, v_max: 255.0 },
    blend: Blend::Add,
};
/// Layer 2's defaults: the OpenCV peer's red range, off.
pub const RED_DEFAULTS: HsvLayerPorts = HsvLayerPorts {
    enabled: false,
    range: HsvRange { h_min: 0.0, h_max: 30.0, s_min: 100.0, s_max: 255.0, v_min: 80.0, v_max: 255.0 },
    blend: Blend::Add,
};
/// Layer 3's defaults: the OpenCV peer's yellow range, off.
pub const YELLOW_DEFAULTS: HsvLayerPorts = HsvLayerPorts {
    enabled: false,
    range: HsvRange { h_min: 30.0, h_max: 70.0, s_min: 80.0, s_max: 255.0, v_min: 100.0, v_max: 255.0 },
    blend: Blend::Add,
};

pyrograph_core::node! {
    /// Binary mask of up to three HSV colour ranges blended in order (Eigenfires thesis §3.2, eq. 3–4, Fig. 17).
    ///
    /// Each enabled layer selects pixels whose hue (0–360°), saturation and value (0–255) lie in its inclusive
    /// ranges and combines them into the running mask (starting empty) by add (union), subtract, difference or
    /// intersect. A hue range with min > max wraps past red. Defaults are the OpenCV peer's blue, red and yellow
    /// flame ranges (half-hues ×2); the image must be RGBA.
    #[node("imaging.hsv_mask", "Pre-processing", PerFrame)]
    pub struct HsvMask {
        /// RGBA frame to segment
        image: Arc<Image>,
        /// Layer 1 (blue by default)
        layer1: HsvLayerPorts = BLUE_DEFAULTS,
        /// Layer 2 (red by default)
        layer2: HsvLayerPorts = RED_DEFAULTS,
        /// Layer 3 (yellow by default)
        layer3: HsvLayerPorts = YELLOW_DEFAULTS,
    }
    /// 255 where the blended layers select the pixel
    -> mask: Arc<Mask>
}

impl HsvMask {
    /// The enabled layers, in order.
    pub fn layers(&self) -> Result<Vec<HsvLayer>, NodeError> {
        let layers = [
            (&self.layer1, port!(HsvMask, layer1)),
            (&self.layer2, port!(HsvMask, layer2)),
            (&self.layer3, port!(HsvMask, layer3)),
        ];
        layers.into_iter().filter_map(|(ports, prefix)| ports.layer(prefix).transpose()).collect()
    }
}

impl Cook for HsvMask {
    fn cook(self, _: &CookCtx) -> Result<Arc<Mask>, NodeError> {
        let layers = self.layers()?;
        Ok(Arc::new(hsv_mask(&self.image, &layers)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use pyrograph_core::Value;

    fn rgba(pixels: &[[f32; 3]]) -> Image {
        let data = pixels.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
        Image::from_vec(pixels.len() as u32, 1, Channels::Rgba, data).unwrap()
    }

    fn range(h_min: f32, h_max: f32) -> HsvRange {
        HsvRange { h_min, h_max, s_min: 50.0, s_max: 255.0, v_min: 50.0, v_max: 255.0 }
    }

    const RED: [f32; 3] = [1.0, 0.0, 0.0];
    const YELLOW: [f32; 3] = [1.0, 1.0, 0.0];
    const BLUE: [f32; 3] = [0.0, 0.0, 1.0];
    const MAGENTA: [f32; 3] = [1.0, 0.0, 1.0];
    const BLACK: [f32; 3] = [0.0, 0.0, 0.0];

    fn bits(m: &Mask) -> Vec<u8> {
        m.data().iter().map(|&v| u8::from(v != 0)).collect()
    }

    #[test]
    fn hsv_of_primaries() {
        assert_eq!(rgb_to_hsv(1.0, 0.0, 0.0), [0.0, 255.0, 255.0]);
        assert_eq!(rgb_to_hsv(0.0, 1.0, 0.0), [120.0, 255.0, 255.0]);
        assert_eq!(rgb_to_hsv(0.0, 0.0, 1.0), [240.0, 255.0, 255.0]);
        assert_eq!(rgb_to_hsv(1.0, 0.0, 1.0), [300.0, 255.0, 255.0]);
        assert_eq!(rgb_to_hsv(0.5, 0.5, 0.5), [0.0, 0.0, 128.0]);
    }

    #[test]
    fn each_blend_mode_gives_its_known_mask() {
        // Pixels: red, yellow, blue, black. Layer A = hue 0..70 (red+yellow), layer B = hue 50..250 (yellow+blue).
        let img = rgba(&[RED, YELLOW, BLUE, BLACK]);
        let a = HsvLayer { range: range(0.0, 70.0), blend: Blend::Add };
        let cases = [
            (Blend::Add, [1, 1, 1, 0]),
            (Blend::Subtract, [1, 0, 0, 0]),
            (Blend::Difference, [1, 0, 1, 0]),
            (Blend::Intersect, [0, 1, 0, 0]),
        ];
        for (blend, want) in cases {
            let b = HsvLayer { range: range(50.0, 250.0), blend };
            assert_eq!(bits(&hsv_mask(&img, &[a, b]).unwrap()), want, "{blend:?}");
        }
    }

    #[test]
    fn first_layer_starts_from_empty() {
        let img = rgba(&[RED, BLUE]);
        let only = HsvLayer { range: range(0.0, 10.0), blend: Blend::Intersect };
        assert_eq!(bits(&hsv_mask(&img, &[only]).unwrap()), [0, 0]);
        assert_eq!(bits(&hsv_mask(&img, &[]).unwrap()), [0, 0]);
    }

    #[test]
    fn hue_range_wraps_past_red() {
        let img = rgba(&[RED, MAGENTA, YELLOW, BLUE, [1.0, 0.0, 0.2]]);
        let wrap = HsvLayer { range: range(290.0, 20.0), blend: Blend::Add };
        assert_eq!(bits(&hsv_mask(&img, &[wrap]).unwrap()), [1, 1, 0, 0, 1]);
    }

    #[test]
    fn default_layers_match_the_opencv_peer_ranges() {
        // Deep blue (h 240), orange-red (h 20), yellow-orange (h 50), dim grey: the peer keeps the first three.
        let img = rgba(&[[0.1, 0.2, 0.9], [1.0, 0.33, 0.0], [1.0, 0.83, 0.0], [0.2, 0.2, 0.2]]);
        let layers: Vec<HsvLayer> = [BLUE_DEFAULTS, RED_DEFAULTS, YELLOW_DEFAULTS]
            .iter()
            .map(|d| HsvLayer { range: d.range, blend: Blend::Add })
            .collect();
        assert_eq!(bits(&hsv_mask(&img, &layers).unwrap()), [1, 1, 1, 0]);
    }

    /// The definition the fused pass must equal: fold the layers over `contains(rgb_to_hsv(..))`.
    fn reference_mask(image: &Image, layers: &[HsvLayer]) -> Vec<u8> {
        image
            .data()
            .chunks_exact(4)
            .map(|px| {
                let hsv = rgb_to_hsv(px[0], px[1], px[2]);
                let inside = layers.iter().fold(false, |acc, l| l.blend.apply(acc, l.range.contains(hsv)));
                if inside { 255 } else { 0 }
            })
            .collect()
    }

    #[test]
    fn block_hsv_equals_rgb_to_hsv_on_every_max_min_pair_and_hue_order() {
        // Every (max, min) byte pair with the middle channel at min, max and between, in all six
        // channel orders: covers every saturation the rounding can produce and every hue branch.
        let mut pixels = Vec::new();
        for hi in 0..=255u8 {
            for lo in 0..=hi {
                for mid in [lo, hi, lo + (hi - lo) / 3] {
                    let (a, b, c) = (f32::from(hi) / 255.0, f32::from(mid) / 255.0, f32::from(lo) / 255.0);
                    pixels.extend([[a, b, c], [a, c, b], [b, a, c], [c, a, b], [b, c, a], [c, b, a]]);
                }
            }
        }
        let data: Vec<f32> = pixels.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let (mut h, mut s) = ([0f32; BLOCK], [0f32; BLOCK]);
        for (chunk, px) in data.chunks(BLOCK * 4).zip(pixels.chunks(BLOCK)) {
            let mut blk = Block::new();
            blk.load_value(chunk);
            blk.load_channels(chunk);
            assert!((0..chunk.len() / 4).all(|i| blk.v[i] == blk.r[i].max(blk.g[i]).max(blk.b[i])));
            blk.hue_saturation(&mut h, &mut s);
            let v = blk.v;
            for (i, p) in px.iter().enumerate() {
                let want = rgb_to_hsv(p[0], p[1], p[2]);
                // `==` treats the two zeros as equal, as every range comparison does.
                assert!([h[i], s[i], v[i]] == want, "{p:?}: {:?} vs {want:?}", [h[i], s[i], v[i]]);
            }
        }
    }

    #[test]
    fn floor_small_is_floor() {
        let edges = (0..=1024).flat_map(|i| {
            let y = i as f32 / 4.0;
            [y, y.next_down(), y.next_up()]
        });
        for y in edges.chain([0.0, 255.5, 255.49998, 4_194_303.5]).filter(|y| *y >= 0.0) {
            assert_eq!(floor_small(y), y.floor(), "{y}");
        }
    }

    #[test]
    fn quantize_is_unit_to_u8() {
        for x in (-300..1300).map(|i| i as f32 / 1000.0).chain([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.5 / 255.0]) {
            assert_eq!(quantize(x), f32::from(unit_to_u8(x)), "{x}");
        }
    }

    #[test]
    fn fused_mask_equals_the_definition_on_every_hue_step() {
        // Every (max, mid, min) ordering over a coarse byte grid plus out-of-range and NaN inputs.
        let steps: Vec<f32> = (0..=255).step_by(5).map(|v| v as f32 / 255.0).chain([-0.5, 1.5, f32::NAN]).collect();
        let mut pixels = Vec::new();
        for &r in &steps {
            for &g in &steps {
                for &b in steps.iter().step_by(3) {
                    pixels.push([r, g, b]);
                }
            }
        }
        let img = rgba(&pixels);
        let layers: Vec<HsvLayer> = [BLUE_DEFAULTS, RED_DEFAULTS, YELLOW_DEFAULTS]
            .iter()
            .map(|d| HsvLayer { range: d.range, blend: Blend::Add })
            .collect();
        let odd = [
            HsvLayer { range: range(290.0, 20.0), blend: Blend::Add },
            HsvLayer {
                range: HsvRange { h_min: 0.0, h_max: 0.0, s_min: 0.0, s_max: 0.0, v_min: 0.0, v_max: 255.0 },
                blend: Blend::Difference,
            },
            HsvLayer { range: range(100.0, 200.0), blend: Blend::Subtract },
            HsvLayer { range: range(0.0, 360.0), blend: Blend::Intersect },
        ];
        for ls in [&layers[..], &odd[..], &odd[1..], &[]] {
            assert_eq!(hsv_mask(&img, ls).unwrap().data(), reference_mask(&img, ls));
        }
    }

    #[test]
    fn gray_image_is_an_error_naming_the_image_port() {
        let gray = Image::new(2, 2, Channels::Gray);
        let err = NodeError::from(hsv_mask(&gray, &[]).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "image"), "{err}");
    }

    /// Cooks imaging.hsv_mask on one red pixel with `overrides`.
    fn cook_red(overrides: &[(&str, Value)]) -> Result<Vec<Value>, NodeError> {
        let mut set = vec![("image", Value::Image(Arc::new(rgba(&[RED]))))];
        set.extend(overrides.iter().cloned());
        pyrograph_core::testing::cook::<HsvMask>(&set)
    }

    #[test]
    fn saturation_min_above_max_names_the_port() {
        let err = cook_red(&[
            ("layer2_enabled", Value::Bool(true)),
            ("layer2_s_min", Value::Float(200.0)),
            ("layer2_s_max", Value::Float(100.0)),
        ])
        .unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "layer2_s_min"), "{err}");
    }

    #[test]
    fn node_with_all_layers_keeps_red() {
        let out = cook_red(&[("layer2_enabled", Value::Bool(true)), ("layer3_enabled", Value::Bool(true))]).unwrap();
        let Value::Mask(m) = &out[0] else { panic!("not a mask") };
        assert_eq!(bits(m), [1]);
    }

    proptest! {
        /// Random colours (including out-of-range values) and random layers, thresholds put on
        /// and between byte levels: the fused pass equals the definition.
        #[test]
        fn fused_mask_equals_the_definition(
            pixels in proptest::collection::vec(proptest::array::uniform3(-0.1f32..1.1), 1..200),
            ranges in proptest::collection::vec((0.0f32..360.0, 0.0f32..360.0, 0.0f32..255.0, 0.0f32..255.0, 0.0f32..255.0, 0.0f32..255.0, 0usize..4), 0..4),
        ) {
            let layers: Vec<HsvLayer> = ranges
                .into_iter()
                .map(|(h_min, h_max, s0, s1, v0, v1, blend)| HsvLayer {
                    range: HsvRange { h_min, h_max, s_min: s0.min(s1).round(), s_max: s0.max(s1), v_min: v0.min(v1), v_max: v0.max(v1).round() },
                    blend: [Blend::Add, Blend::Subtract, Blend::Difference, Blend::Intersect][blend],
                })
                .collect();
            let img = rgba(&pixels);
            let fused = hsv_mask(&img, &layers).unwrap();
            prop_assert_eq!(fused.data(), &reference_mask(&img, &layers)[..]);
        }

        /// Mostly dark rows with a few bright pixels, value ranges around them: blocks skipped as
        /// dark and blocks computed in full both equal the definition.
        #[test]
        fn dark_blocks_equal_the_definition(
            w in 1u32..200,
            bright in proptest::collection::vec((0usize..200, proptest::array::uniform3(0.0f32..1.0)), 0..4),
            ranges in proptest::collection::vec((0.0f32..360.0, 0.0f32..360.0, 0.0f32..255.0, 0.0f32..255.0, 0.0f32..120.0, 0usize..4), 1..4),
        ) {
            let mut pixels: Vec<[f32; 3]> = (0..w).map(|i| [0.02 * (i % 7) as f32, 0.03, 0.01 * (i % 5) as f32]).collect();
            for (i, p) in bright {
                if let Some(px) = pixels.get_mut(i) {
                    *px = p;
                }
            }
            let layers: Vec<HsvLayer> = ranges
                .into_iter()
                .map(|(h_min, h_max, s0, s1, v_min, blend)| HsvLayer {
                    range: HsvRange { h_min, h_max, s_min: s0.min(s1), s_max: s0.max(s1), v_min: v_min.round(), v_max: 255.0 },
                    blend: [Blend::Add, Blend::Subtract, Blend::Difference, Blend::Intersect][blend],
                })
                .collect();
            let img = rgba(&pixels);
            let fused = hsv_mask(&img, &layers).unwrap();
            prop_assert_eq!(fused.data(), &reference_mask(&img, &layers)[..]);
        }
    }
}
