//! Synthetic colouring (Eigenfires thesis §6.1.2): lightness from the gray flame, hue and
//! saturation from a colour, a colour ramp or a texture (HLS transfer).

use std::sync::Arc;

use pyrograph_core::declare::Port;
use pyrograph_core::value::RampKeys;
use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError, PortType, Value};

use super::{ColoringError, check_size, rgb};

/// RGB (0..1) to HLS: hue in degrees 0..360, lightness and saturation in 0..1 (the usual
/// double-hexcone model, as Python's `colorsys` and OpenCV's `COLOR_RGB2HLS`).
pub fn rgb_to_hls([r, g, b]: [f32; 3]) -> [f32; 3] {
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let l = (max + min) / 2.0;
    let d = max - min;
    if d <= f32::EPSILON {
        return [0.0, l, 0.0];
    }
    let s = if l <= 0.5 { d / (max + min) } else { d / (2.0 - max - min) };
    let h = if max == r {
        60.0 * ((g - b) / d)
    } else if max == g {
        60.0 * ((b - r) / d + 2.0)
    } else {
        60.0 * ((r - g) / d + 4.0)
    };
    [h.rem_euclid(360.0), l, s]
}

/// HLS (hue in degrees, lightness and saturation 0..1) to RGB; the inverse of [`rgb_to_hls`].
pub fn hls_to_rgb([h, l, s]: [f32; 3]) -> [f32; 3] {
    if s <= 0.0 {
        return [l; 3];
    }
    let m2 = if l <= 0.5 { l * (1.0 + s) } else { l + s - l * s };
    let m1 = 2.0 * l - m2;
    let channel = |hue: f32| {
        let hue = hue.rem_euclid(360.0);
        if hue < 60.0 {
            m1 + (m2 - m1) * hue / 60.0
        } else if hue < 180.0 {
            m2
        } else if hue < 240.0 {
            m1 + (m2 - m1) * (240.0 - hue) / 60.0
        } else {
            m1
        }
    };
    [channel(h + 120.0), channel(h), channel(h - 120.0)]
}

/// The colour with the lightness `l` and the hue and saturation of `blend` (the HLS transfer of §6.1.2).
pub fn hls_transfer(l: f32, blend: [f32; 3]) -> [f32; 3] {
    let [h, _, s] = rgb_to_hls(blend);
    hls_to_rgb([h, l.clamp(0.0, 1.0), s])
}

/// A colour ramp: stops `(position, rgb)` sorted by position in 0..1.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorRamp {
    stops: Vec<(f32, [f32; 3])>,
}

/// A ColorRamp port of `(position, (r, g, b))` keys: `[(0, (0, 0, 0)), (1, (1, 0.95, 0.75))]`.
impl Port for ColorRamp {
    fn port_type() -> PortType {
        PortType::Ramp(3)
    }
    fn into_value(self) -> Value {
        // The shortest decimal of each f32, so defaults print as declared.
        let short = |x: f32| x.to_string().parse::<f64>().unwrap_or(f64::from(x));
        let keys = self.stops.iter().map(|(p, c)| (short(*p), [short(c[0]), short(c[1]), short(c[2]), 0.0])).collect();
        match RampKeys::new(3, keys) {
            Ok(k) => Value::Ramp(Arc::new(k)),
            // `ColorRamp::new` keeps stops finite and sorted, which is all `RampKeys::new` checks.
            Err(m) => Value::String(m),
        }
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        match v {
            Value::Ramp(keys) => ColorRamp::from_keys(keys),
            other => Err(format!("needs a colour ramp, got {}", other.type_name())),
        }
    }
}

/// The default flame ramp: black, deep red, orange, yellow-white.
pub const DEFAULT_RAMP: &str = "0:0,0,0; 0.3:0.6,0.05,0; 0.65:1,0.5,0.05; 1:1,0.95,0.75";

impl ColorRamp {
    /// A ramp from stops (sorted here); at least one stop is needed.
    pub fn new(mut stops: Vec<(f32, [f32; 3])>) -> Result<Self, String> {
        if stops.is_empty() {
            return Err("a colour ramp needs at least one stop".into());
        }
        if stops.iter().any(|(p, c)| !p.is_finite() || c.iter().any(|v| !v.is_finite())) {
            return Err("colour ramp stops must be finite numbers".into());
        }
        stops.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(ColorRamp { stops })
    }

    /// Parses the text form older files hold, `"pos:r,g,b; pos:r,g,b; …"` (components in 0..1),
    /// e.g. [`DEFAULT_RAMP`].
    pub fn parse(text: &str) -> Result<Self, String> {
        ColorRamp::from_keys(&RampKeys::parse_legacy(text, 3)?)
    }

    /// A built-in ramp (a port default).
    ///
    /// # Panics
    /// When `text` does not parse: a declaration error, caught by every test that builds a default.
    pub fn preset(text: &str) -> Self {
        ColorRamp::parse(text).unwrap_or_else(|e| panic!("built-in ramp '{text}': {e}"))
    }

    fn from_keys(keys: &RampKeys) -> Result<Self, String> {
        if keys.width() != 3 {
            return Err(format!("needs (r, g, b) keys, got {} values a key", keys.width()));
        }
        // Ports hold f64; colouring computes in f32, so rounding here is the intent.
        ColorRamp::new(keys.keys().iter().map(|(p, v)| (*p as f32, [v[0] as f32, v[1] as f32, v[2] as f32])).collect())
    }

    /// The colour at `t` (clamped to the end stops), linearly interpolated: the intensity → colour
    /// transfer function used for synthetic colouring and for the learned flame model's renderer.
    pub fn color_at(&self, t: f32) -> [f32; 3] {
        let first = self.stops[0];
        let last = self.stops[self.stops.len() - 1];
        if t.is_nan() || t <= first.0 {
            return first.1;
        }
        if t >= last.0 {
            return last.1;
        }
        let k = self.stops.partition_point(|s| s.0 <= t).max(1);
        let (a, b) = (self.stops[k - 1], self.stops[k]);
        let f = if b.0 > a.0 { (t - a.0) / (b.0 - a.0) } else { 1.0 };
        std::array::from_fn(|c| a.1[c] + f * (b.1[c] - a.1[c]))
    }
}

/// Where the hue and saturation of synthetic colouring come from.
#[derive(Clone, Debug)]
pub enum Blend<'a> {
    /// One colour for every pixel (e.g. orange).
    Solid([f32; 3]),
    /// A ramp indexed by the source intensity; hue and saturation are transferred.
    Ramp(&'a ColorRamp),
    /// A ramp indexed by the source intensity, whose colour is used directly (no HLS transfer).
    RampDirect(&'a ColorRamp),
    /// A texture of the source's size.
    Texture(&'a Image),
}

/// Synthetic colouring (§6.1.2): each pixel gets the lightness of `source` and the hue and
/// saturation of the blend colour (HLS transfer). Alpha is the source's (1 for gray).
pub fn synthetic_coloring(source: &Image, blend: &Blend<'_>) -> Result<Image, ColoringError> {
    if let Blend::Texture(t) = blend {
        check_size(source, t).map_err(ColoringError::Texture)?;
    }
    let (w, h) = source.size();
    let n = w as usize * h as usize;
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let (l, alpha) = match source.channels() {
            Channels::Gray => (source.data()[i], 1.0),
            Channels::Rgba => (rgb_to_hls(rgb(source, i))[1], source.data()[4 * i + 3]),
        };
        let px = match blend {
            Blend::Solid(c) => hls_transfer(l, *c),
            Blend::Ramp(r) => hls_transfer(l, r.color_at(l)),
            Blend::RampDirect(r) => r.color_at(l),
            Blend::Texture(t) => hls_transfer(l, rgb(t, i)),
        };
        out.extend_from_slice(&[px[0], px[1], px[2], alpha]);
    }
    Image::from_vec(w, h, Channels::Rgba, out).ok_or_else(|| ColoringError::Message("image data does not match its size".into()))
}

pyrograph_core::choice! {
    /// Where synthetic colouring takes the hue and saturation from (the `mode` of `imaging.synthetic_coloring`).
    pub enum SyntheticMode {
        /// One colour, [`Blend::Solid`].
        Solid = "solid",
        /// A ramp by HLS transfer, [`Blend::Ramp`].
        Ramp = "ramp",
        /// A ramp's colour itself, [`Blend::RampDirect`].
        RampDirect = "ramp_direct",
    }
}

pyrograph_core::node! {
    /// Colours a gray flame by HLS transfer (Eigenfires thesis §6.1.2): lightness from the source, hue and saturation from a blend colour.
    ///
    /// mode solid uses one colour; ramp indexes a colour ramp by the source intensity and transfers its hue and
    /// saturation; ramp_direct uses the ramp colour itself (the intensity → colour transfer function of the
    /// flame-model renderer). Ramp text: `pos:r,g,b; …` with components in 0..1. For a texture use
    /// imaging.synthetic_coloring_texture.
    #[node("imaging.synthetic_coloring", "Color & Post", PerFrame)]
    pub struct SyntheticColoring {
        /// Gray flame (RGBA uses its HLS lightness)
        source: Arc<Image>,
        /// Where the hue and saturation come from
        mode: SyntheticMode = SyntheticMode::Solid,
        /// Blend colour of mode solid (orange)
        color: [f32; 4] = [1.0, 0.5, 0.1, 1.0],
        /// Colour ramp of modes ramp and ramp_direct: `[(position, (r, g, b)), …]`.
        ramp: ColorRamp = ColorRamp::preset(DEFAULT_RAMP),
    }
    /// Coloured flame (RGBA)
    -> image: Arc<Image>
}

impl Cook for SyntheticColoring {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let img = match self.mode {
            SyntheticMode::Solid => {
                let c = self.color;
                synthetic_coloring(&self.source, &Blend::Solid([c[0], c[1], c[2]]))?
            }
            SyntheticMode::Ramp | SyntheticMode::RampDirect => {
                let ramp = &self.ramp;
                let blend = if self.mode == SyntheticMode::Ramp { Blend::Ramp(ramp) } else { Blend::RampDirect(ramp) };
                synthetic_coloring(&self.source, &blend)?
            }
        };
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Colours a gray flame with the hue and saturation of a texture of the same size (Eigenfires thesis §6.1.2, HLS transfer).
    #[node("imaging.synthetic_coloring_texture", "Color & Post", PerFrame)]
    pub struct SyntheticColoringTexture {
        /// Gray flame (RGBA uses its HLS lightness)
        source: Arc<Image>,
        /// Blend texture, same size as the source
        texture: Arc<Image>,
    }
    /// Coloured flame (RGBA)
    -> image: Arc<Image>
}

impl Cook for SyntheticColoringTexture {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let img = synthetic_coloring(&self.source, &Blend::Texture(&self.texture))?;
        Ok(Arc::new(img))
    }
}
