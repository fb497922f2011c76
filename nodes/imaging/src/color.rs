//! Colouring of gray flames (Eigenfires thesis §6.1): original colouring from the source video
//! (Algorithm 2, with the smoke and bloom layers of §6.2–6.3 and the custom masks of §6.4),
//! synthetic colouring by HLS transfer (§6.1.2), colour ramps, and alpha premultiplication.
//!
//! Images are f32 in 0..1, so the thesis's 8-bit threshold (0–255) is divided by 255 and its
//! saturation `min(v, 0xff)` becomes `min(v, 1)`.
//!
//! Optional layers: image ports cannot have default values, so Algorithm 2 is offered as three
//! nodes over one function, [`original_coloring`]: `imaging.original_coloring` (empty destination,
//! smoke disabled), `imaging.original_coloring_layered` (destination = a bloom image and a smoke
//! image, both required; feed a black `imaging.constant_color` to switch one off — with a zero
//! layer Algorithm 2 gives exactly the result of the disabled branch) and
//! `imaging.original_coloring_masked` (the layered node plus a §6.4 custom mask).

use std::sync::Arc;

use pyrograph_core::{
    Channels, CookCtx, FnNode, Image, Inputs, Mask, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep, Value,
};

/// Palette category of the colour and post-processing nodes.
pub const CATEGORY: &str = "Color & Post";

/// Adds this module's node types.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(original_desc(), cook_original));
    registry.add(FnNode::new(original_layered_desc(), cook_original_layered));
    registry.add(FnNode::new(original_masked_desc(), cook_original_masked));
    registry.add(FnNode::new(synthetic_desc(), cook_synthetic));
    registry.add(FnNode::new(synthetic_texture_desc(), cook_synthetic_texture));
    registry.add(FnNode::new(premultiply_desc(), cook_premultiply));
    registry.add(FnNode::new(set_alpha_desc(), cook_set_alpha));
}

fn size_text(img: &Image) -> String {
    format!("{}x{}", img.width(), img.height())
}

/// Checks that `other` (on port `port`) has the size of `source`.
pub fn check_size(source: &Image, other: &Image, port: &str) -> Result<(), NodeError> {
    if source.size() != other.size() {
        return Err(NodeError::port(
            port,
            format!("'{port}' is {} but the source is {}; both must have the same size", size_text(other), size_text(source)),
        ));
    }
    Ok(())
}

/// Intensity of pixel `i` of an image: the gray value, or the Rec. 601 luma of RGBA.
fn intensity(img: &Image, i: usize) -> f32 {
    let d = img.data();
    match img.channels() {
        Channels::Gray => d[i],
        Channels::Rgba => 0.299 * d[4 * i] + 0.587 * d[4 * i + 1] + 0.114 * d[4 * i + 2],
    }
}

/// RGB of pixel `i` (gray is replicated).
fn rgb(img: &Image, i: usize) -> [f32; 3] {
    let d = img.data();
    match img.channels() {
        Channels::Gray => [d[i]; 3],
        Channels::Rgba => [d[4 * i], d[4 * i + 1], d[4 * i + 2]],
    }
}

// ---------------------------------------------------------------------------------------------
// Original coloring (§6.1.1, Algorithm 2)
// ---------------------------------------------------------------------------------------------

/// The optional inputs of Algorithm 2.
#[derive(Clone, Copy, Debug, Default)]
pub struct ColoringLayers<'a> {
    /// The destination's initial content (the bloom image, §6.2); black when `None`.
    pub destination: Option<&'a Image>,
    /// The smoke image (§6.3); smoke disabled when `None`.
    pub smoke: Option<&'a Image>,
    /// A custom mask (§6.4): inside it the original is taken as if the source were above the threshold.
    pub custom_mask: Option<&'a Mask>,
}

/// Checks a threshold given on the thesis's 0–255 scale.
pub fn check_threshold(threshold: f64) -> Result<f32, NodeError> {
    if !(0.0..=255.0).contains(&threshold) {
        return Err(NodeError::port("threshold", format!("{threshold} is outside 0–255 (the thesis uses about 30)")));
    }
    Ok(threshold as f32)
}

/// Algorithm 2 of the thesis (§6.1.1) on all three channels.
///
/// `source` is the gray flame (gray or RGBA, whose luma is used), `original` the colour frame;
/// `threshold` is on the 0–255 scale. Where `source·255 > threshold` (or inside the custom mask)
/// the original colour is copied; below it the original fades linearly into the destination plus
/// smoke: `min(1, s·original + (1 − s)·(destination + smoke))` with `s = source·255 / threshold`.
/// The output is opaque RGBA.
pub fn original_coloring(
    source: &Image,
    original: &Image,
    threshold: f64,
    layers: ColoringLayers<'_>,
) -> Result<Image, NodeError> {
    let t = check_threshold(threshold)? / 255.0;
    check_size(source, original, "original")?;
    if let Some(d) = layers.destination {
        check_size(source, d, "destination")?;
    }
    if let Some(s) = layers.smoke {
        check_size(source, s, "smoke")?;
    }
    if let Some(m) = layers.custom_mask {
        if (m.width(), m.height()) != source.size() {
            return Err(NodeError::port(
                "custom_mask",
                format!(
                    "'custom_mask' is {}x{} but the source is {}; both must have the same size",
                    m.width(),
                    m.height(),
                    size_text(source)
                ),
            ));
        }
    }
    let (w, h) = source.size();
    let n = w as usize * h as usize;
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let src = intensity(source, i);
        let orig = rgb(original, i);
        let in_mask = layers.custom_mask.is_some_and(|m| m.data()[i] != 0);
        let px = if src > t || in_mask {
            orig
        } else {
            // Linearly diminish colours below the threshold (t = 0 only reaches here for src = 0).
            let scale_src = if t > 0.0 { (src / t).max(0.0) } else { 0.0 };
            let scale_dest = 1.0 - scale_src;
            let dest = layers.destination.map_or([0.0; 3], |d| rgb(d, i));
            let smoke = layers.smoke.map_or([0.0; 3], |s| rgb(s, i));
            std::array::from_fn(|c| (scale_src * orig[c] + scale_dest * dest[c] + smoke[c] * scale_dest).min(1.0))
        };
        out.extend_from_slice(&[px[0], px[1], px[2], 1.0]);
    }
    Image::from_vec(w, h, Channels::Rgba, out).ok_or_else(|| NodeError::msg("image data does not match its size"))
}

fn threshold_port() -> PortDesc {
    PortDesc::float("threshold", 30.0, (0.0, 255.0), "Source intensity (0–255) above which the original colour is copied")
}

fn original_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.original_coloring",
        CATEGORY,
        TimeDep::PerFrame,
        "Colours a gray flame with the original video frame (Eigenfires thesis §6.1.1, Algorithm 2), empty destination, no smoke.\n\
         Pixels whose source intensity is above the threshold take the original colour; below it the colour fades \
         linearly to black. Output is opaque RGBA. For bloom and smoke layers use imaging.original_coloring_layered.",
    )
    .input(PortDesc::new("source", PortType::Image, "Gray flame (a reconstruction or a pre-processed frame)"))
    .input(PortDesc::new("original", PortType::Image, "Original colour frame, same size and pose as the source"))
    .input(threshold_port())
    .output("image", PortType::Image, "Coloured flame (RGBA)")
}

fn layered_ports(d: NodeDesc) -> NodeDesc {
    d.input(PortDesc::new("source", PortType::Image, "Gray flame (a reconstruction or a pre-processed frame)"))
        .input(PortDesc::new("original", PortType::Image, "Original colour frame, same size and pose as the source"))
        .input(PortDesc::new(
            "destination",
            PortType::Image,
            "Initial destination: the bloom image (§6.2), or black (imaging.constant_color) for none",
        ))
        .input(PortDesc::new("smoke", PortType::Image, "Smoke image (§6.3, imaging.smoke), or black for none"))
}

fn original_layered_desc() -> NodeDesc {
    layered_ports(NodeDesc::new(
        "imaging.original_coloring_layered",
        CATEGORY,
        TimeDep::PerFrame,
        "Algorithm 2 of the Eigenfires thesis (§6.1.1) with a bloom destination (§6.2) and smoke (§6.3).\n\
         Above the threshold the original colour is copied; below it the result is \
         min(1, s·original + (1 − s)·(destination + smoke)), s = source / threshold. A black layer is the same as \
         disabling it.",
    ))
    .input(threshold_port())
    .output("image", PortType::Image, "Coloured flame (RGBA)")
}

fn original_masked_desc() -> NodeDesc {
    layered_ports(NodeDesc::new(
        "imaging.original_coloring_masked",
        CATEGORY,
        TimeDep::PerFrame,
        "Algorithm 2 (Eigenfires thesis §6.1.1) with bloom, smoke and a custom mask (§6.4).\n\
         The custom mask is an extra layer that admits more pixels of the original: inside it the original colour \
         is copied as if the source were above the threshold (smoke or glow removed before training comes back).",
    ))
    .input(PortDesc::new("custom_mask", PortType::Mask, "Extra regions where the original colour is taken (§6.4)"))
    .input(threshold_port())
    .output("image", PortType::Image, "Coloured flame (RGBA)")
}

fn cook_original(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let img = original_coloring(i.image("source")?, i.image("original")?, i.float("threshold")?, ColoringLayers::default())?;
    Ok(vec![Value::Image(Arc::new(img))])
}

fn cook_original_layered(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let layers = ColoringLayers { destination: Some(i.image("destination")?), smoke: Some(i.image("smoke")?), custom_mask: None };
    let img = original_coloring(i.image("source")?, i.image("original")?, i.float("threshold")?, layers)?;
    Ok(vec![Value::Image(Arc::new(img))])
}

fn cook_original_masked(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let layers = ColoringLayers {
        destination: Some(i.image("destination")?),
        smoke: Some(i.image("smoke")?),
        custom_mask: Some(i.mask("custom_mask")?),
    };
    let img = original_coloring(i.image("source")?, i.image("original")?, i.float("threshold")?, layers)?;
    Ok(vec![Value::Image(Arc::new(img))])
}

// ---------------------------------------------------------------------------------------------
// HLS and synthetic coloring (§6.1.2)
// ---------------------------------------------------------------------------------------------

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

    /// Parses `"pos:r,g,b; pos:r,g,b; …"` (components in 0..1), e.g. [`DEFAULT_RAMP`].
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut stops = Vec::new();
        for part in text.split(';').map(str::trim).filter(|p| !p.is_empty()) {
            let (pos, col) = part.split_once(':').ok_or_else(|| format!("stop '{part}' is not of the form pos:r,g,b"))?;
            let pos: f32 = pos.trim().parse().map_err(|_| format!("stop '{part}': '{pos}' is not a number"))?;
            let comps: Vec<f32> = col
                .split(',')
                .map(|c| c.trim().parse::<f32>().map_err(|_| format!("stop '{part}': '{c}' is not a number")))
                .collect::<Result<_, _>>()?;
            let [r, g, b] = comps[..] else {
                return Err(format!("stop '{part}' needs three colour components r,g,b"));
            };
            stops.push((pos, [r, g, b]));
        }
        ColorRamp::new(stops)
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
pub fn synthetic_coloring(source: &Image, blend: &Blend<'_>) -> Result<Image, NodeError> {
    if let Blend::Texture(t) = blend {
        check_size(source, t, "texture")?;
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
    Image::from_vec(w, h, Channels::Rgba, out).ok_or_else(|| NodeError::msg("image data does not match its size"))
}

fn synthetic_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.synthetic_coloring",
        CATEGORY,
        TimeDep::PerFrame,
        "Colours a gray flame by HLS transfer (Eigenfires thesis §6.1.2): lightness from the source, hue and saturation from a blend colour.\n\
         mode solid uses one colour; ramp indexes a colour ramp by the source intensity and transfers its hue and \
         saturation; ramp_direct uses the ramp colour itself (the intensity → colour transfer function of the \
         flame-model renderer). Ramp text: `pos:r,g,b; …` with components in 0..1. For a texture use \
         imaging.synthetic_coloring_texture.",
    )
    .input(PortDesc::new("source", PortType::Image, "Gray flame (RGBA uses its HLS lightness)"))
    .input(PortDesc::choice("mode", &["solid", "ramp", "ramp_direct"], "solid", "Where the hue and saturation come from"))
    .input(PortDesc::color("color", [1.0, 0.5, 0.1, 1.0], "Blend colour of mode solid (orange)"))
    .input(PortDesc::string("ramp", DEFAULT_RAMP, "Colour ramp of modes ramp and ramp_direct: pos:r,g,b; …"))
    .output("image", PortType::Image, "Coloured flame (RGBA)")
}

fn cook_synthetic(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let source = i.image("source")?;
    let mode = i.choice("mode")?;
    let img = match mode {
        "solid" => {
            let c = i.color("color")?;
            synthetic_coloring(source, &Blend::Solid([c[0], c[1], c[2]]))?
        }
        "ramp" | "ramp_direct" => {
            let ramp = ColorRamp::parse(i.string("ramp")?).map_err(|m| NodeError::port("ramp", m))?;
            let blend = if mode == "ramp" { Blend::Ramp(&ramp) } else { Blend::RampDirect(&ramp) };
            synthetic_coloring(source, &blend)?
        }
        other => return Err(NodeError::port("mode", format!("unknown mode '{other}' (solid, ramp, ramp_direct)"))),
    };
    Ok(vec![Value::Image(Arc::new(img))])
}

fn synthetic_texture_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.synthetic_coloring_texture",
        CATEGORY,
        TimeDep::PerFrame,
        "Colours a gray flame with the hue and saturation of a texture of the same size (Eigenfires thesis §6.1.2, HLS transfer).",
    )
    .input(PortDesc::new("source", PortType::Image, "Gray flame (RGBA uses its HLS lightness)"))
    .input(PortDesc::new("texture", PortType::Image, "Blend texture, same size as the source"))
    .output("image", PortType::Image, "Coloured flame (RGBA)")
}

fn cook_synthetic_texture(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let img = synthetic_coloring(i.image("source")?, &Blend::Texture(i.image("texture")?))?;
    Ok(vec![Value::Image(Arc::new(img))])
}

// ---------------------------------------------------------------------------------------------
// Alpha
// ---------------------------------------------------------------------------------------------

/// How colour relates to alpha in an output file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaMode {
    /// Colour independent of alpha (the in-memory convention).
    Straight,
    /// Colour multiplied by alpha (what game engines and compositors blend fastest).
    Premultiplied,
}

impl AlphaMode {
    /// Parses `straight` / `premultiplied`.
    pub fn parse(name: &str, port: &str) -> Result<Self, NodeError> {
        match name {
            "straight" => Ok(AlphaMode::Straight),
            "premultiplied" => Ok(AlphaMode::Premultiplied),
            other => Err(NodeError::port(port, format!("unknown alpha mode '{other}' (straight, premultiplied)"))),
        }
    }

    /// The option name.
    pub fn name(self) -> &'static str {
        match self {
            AlphaMode::Straight => "straight",
            AlphaMode::Premultiplied => "premultiplied",
        }
    }

    /// The image converted from straight alpha to this mode (gray images have no alpha and pass).
    pub fn apply(self, img: &Image) -> Image {
        match self {
            AlphaMode::Straight => img.clone(),
            AlphaMode::Premultiplied => premultiply(img),
        }
    }
}

/// Straight → premultiplied alpha (RGB × A); gray images are returned unchanged.
pub fn premultiply(img: &Image) -> Image {
    let mut out = img.clone();
    if img.channels() == Channels::Rgba {
        for p in out.data_mut().chunks_exact_mut(4) {
            let a = p[3];
            p[0] *= a;
            p[1] *= a;
            p[2] *= a;
        }
    }
    out
}

/// Premultiplied → straight alpha (RGB ÷ A; colour 0 where A is 0); gray images are returned unchanged.
pub fn unpremultiply(img: &Image) -> Image {
    let mut out = img.clone();
    if img.channels() == Channels::Rgba {
        for p in out.data_mut().chunks_exact_mut(4) {
            let a = p[3];
            for c in &mut p[..3] {
                *c = if a > 0.0 { *c / a } else { 0.0 };
            }
        }
    }
    out
}

fn premultiply_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.premultiply",
        CATEGORY,
        TimeDep::PerFrame,
        "Converts between straight and premultiplied alpha (RGB × A, or RGB ÷ A with 0 where A = 0).",
    )
    .input(PortDesc::new("image", PortType::Image, "RGBA image (gray passes through)"))
    .input(PortDesc::choice("direction", &["premultiply", "unpremultiply"], "premultiply", "Which way to convert"))
    .output("image", PortType::Image, "Converted image")
}

fn cook_premultiply(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let img = i.image("image")?;
    let out = match i.choice("direction")? {
        "premultiply" => premultiply(img),
        "unpremultiply" => unpremultiply(img),
        other => return Err(NodeError::port("direction", format!("unknown direction '{other}'"))),
    };
    Ok(vec![Value::Image(Arc::new(out))])
}

/// `image` as RGBA with its alpha replaced by the intensity of `matte` (clamped to 0..1).
pub fn set_alpha(image: &Image, matte: &Image) -> Result<Image, NodeError> {
    check_size(image, matte, "matte")?;
    let mut out = image.to_rgba();
    let n = out.data().len() / 4;
    for i in 0..n {
        let a = intensity(matte, i).clamp(0.0, 1.0);
        out.data_mut()[4 * i + 3] = a;
    }
    Ok(out)
}

fn set_alpha_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.set_alpha",
        CATEGORY,
        TimeDep::PerFrame,
        "Replaces an image's alpha with a matte, e.g. the bloom matte (bloom + source) of Eigenfires thesis §6.2.
         Colours stay as they are (straight alpha); an RGBA matte gives its luma.",
    )
    .input(PortDesc::new("image", PortType::Image, "Colour image (gray is promoted to RGBA)"))
    .input(PortDesc::new("matte", PortType::Image, "Alpha matte, same size"))
    .output("image", PortType::Image, "RGBA image with the matte as alpha")
}

fn cook_set_alpha(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Image(Arc::new(set_alpha(i.image("image")?, i.image("matte")?)?))])
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn gray(w: u32, h: u32, data: &[f32]) -> Image {
        Image::from_vec(w, h, Channels::Gray, data.to_vec()).unwrap()
    }

    fn rgba(w: u32, h: u32, data: &[f32]) -> Image {
        Image::from_vec(w, h, Channels::Rgba, data.to_vec()).unwrap()
    }

    fn solid(w: u32, h: u32, c: [f32; 3]) -> Image {
        let data: Vec<f32> = (0..w * h).flat_map(|_| [c[0], c[1], c[2], 1.0]).collect();
        rgba(w, h, &data)
    }

    fn px(img: &Image, x: u32) -> [f32; 4] {
        let p = img.pixel(x, 0);
        [p[0], p[1], p[2], p[3]]
    }

    fn close(a: [f32; 4], b: [f32; 4]) -> bool {
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-5)
    }

    #[test]
    fn algorithm2_copies_above_and_fades_at_and_below_the_threshold() {
        // Threshold 30: source values (×255) 60, 31, 30, 15, 0.
        let src = gray(5, 1, &[60.0 / 255.0, 31.0 / 255.0, 30.0 / 255.0, 15.0 / 255.0, 0.0]);
        let orig = solid(5, 1, [0.8, 0.4, 0.2]);
        let out = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap();
        assert!(close(px(&out, 0), [0.8, 0.4, 0.2, 1.0]));
        assert!(close(px(&out, 1), [0.8, 0.4, 0.2, 1.0]));
        // At the threshold: scaleSrc = 1, the original colour (continuous with the branch above).
        assert!(close(px(&out, 2), [0.8, 0.4, 0.2, 1.0]));
        // Half the threshold: half the colour over the empty destination.
        assert!(close(px(&out, 3), [0.4, 0.2, 0.1, 1.0]));
        assert!(close(px(&out, 4), [0.0, 0.0, 0.0, 1.0]));
    }

    #[test]
    fn algorithm2_with_destination_and_smoke_saturates() {
        let src = gray(3, 1, &[100.0 / 255.0, 15.0 / 255.0, 0.0]);
        let orig = solid(3, 1, [0.8, 0.4, 0.2]);
        let dest = solid(3, 1, [0.2, 0.2, 0.2]);
        let smoke = solid(3, 1, [0.1, 0.9, 0.0]);
        let layers = ColoringLayers { destination: Some(&dest), smoke: Some(&smoke), custom_mask: None };
        let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
        // Above: the original, smoke and destination ignored.
        assert!(close(px(&out, 0), [0.8, 0.4, 0.2, 1.0]));
        // s = 0.5: 0.5·orig + 0.5·(dest + smoke).
        assert!(close(px(&out, 1), [0.55, 0.75, 0.2, 1.0]));
        // s = 0: dest + smoke, green saturated at 1.
        let smoke_hot = solid(3, 1, [0.1, 0.95, 0.0]);
        let layers = ColoringLayers { destination: Some(&dest), smoke: Some(&smoke_hot), custom_mask: None };
        let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
        assert!(close(px(&out, 2), [0.3, 1.0, 0.2, 1.0]));
    }

    #[test]
    fn black_layers_equal_disabled_layers() {
        let src = gray(4, 1, &[0.5, 0.1, 0.05, 0.0]);
        let orig = solid(4, 1, [0.9, 0.5, 0.1]);
        let black = solid(4, 1, [0.0; 3]);
        let plain = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap();
        let layers = ColoringLayers { destination: Some(&black), smoke: Some(&black), custom_mask: None };
        assert_eq!(original_coloring(&src, &orig, 30.0, layers).unwrap(), plain);
    }

    #[test]
    fn custom_mask_admits_extra_original_pixels() {
        let src = gray(2, 1, &[0.0, 0.0]);
        let orig = solid(2, 1, [0.3, 0.3, 0.3]);
        let mask = Mask::from_vec(2, 1, vec![0, 255]).unwrap();
        let layers = ColoringLayers { custom_mask: Some(&mask), ..Default::default() };
        let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
        assert!(close(px(&out, 0), [0.0, 0.0, 0.0, 1.0]));
        assert!(close(px(&out, 1), [0.3, 0.3, 0.3, 1.0]));
    }

    #[test]
    fn bad_sizes_and_thresholds_are_clear_errors() {
        let src = gray(2, 1, &[0.0, 0.0]);
        let orig = solid(3, 1, [0.3; 3]);
        let e = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap_err().to_string();
        assert!(e.contains("'original' is 3x1 but the source is 2x1"), "{e}");
        let orig = solid(2, 1, [0.3; 3]);
        for bad in [-1.0, 256.0, f64::NAN] {
            let e = original_coloring(&src, &orig, bad, ColoringLayers::default()).unwrap_err().to_string();
            assert!(e.contains("threshold") && e.contains("outside 0–255"), "{e}");
        }
        let smoke = solid(1, 1, [0.0; 3]);
        let layers = ColoringLayers { smoke: Some(&smoke), ..Default::default() };
        assert!(original_coloring(&src, &orig, 30.0, layers).unwrap_err().to_string().contains("'smoke'"));
    }

    #[test]
    fn zero_threshold_does_not_divide_by_zero() {
        let src = gray(2, 1, &[0.0, 0.01]);
        let orig = solid(2, 1, [0.5; 3]);
        let out = original_coloring(&src, &orig, 0.0, ColoringLayers::default()).unwrap();
        assert!(out.data().iter().all(|v| v.is_finite()));
        assert!(close(px(&out, 1), [0.5, 0.5, 0.5, 1.0]));
    }

    #[test]
    fn hls_of_pure_colours() {
        let cases = [
            ([1.0, 0.0, 0.0], [0.0, 0.5, 1.0]),
            ([0.0, 1.0, 0.0], [120.0, 0.5, 1.0]),
            ([0.0, 0.0, 1.0], [240.0, 0.5, 1.0]),
            ([1.0, 1.0, 0.0], [60.0, 0.5, 1.0]),
            ([1.0, 1.0, 1.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
            ([0.5, 0.5, 0.5], [0.0, 0.5, 0.0]),
        ];
        for (rgb, hls) in cases {
            let got = rgb_to_hls(rgb);
            assert!(got.iter().zip(&hls).all(|(a, b)| (a - b).abs() < 1e-5), "{rgb:?}: {got:?} vs {hls:?}");
            let back = hls_to_rgb(got);
            assert!(back.iter().zip(&rgb).all(|(a, b)| (a - b).abs() < 1e-5), "{rgb:?} -> {back:?}");
        }
    }

    proptest! {
        #[test]
        fn hls_round_trips_mixed_colours(r in 0.0f32..=1.0, g in 0.0f32..=1.0, b in 0.0f32..=1.0) {
            let back = hls_to_rgb(rgb_to_hls([r, g, b]));
            prop_assert!(back.iter().zip(&[r, g, b]).all(|(x, y)| (x - y).abs() < 1e-4), "{:?} -> {:?}", [r, g, b], back);
        }

        #[test]
        fn premultiply_then_unpremultiply_is_identity_where_alpha_is_positive(
            c in proptest::array::uniform3(0.0f32..=1.0), a in 0.01f32..=1.0
        ) {
            let img = rgba(1, 1, &[c[0], c[1], c[2], a]);
            let pre = premultiply(&img);
            prop_assert!((pre.data()[0] - c[0] * a).abs() < 1e-6);
            prop_assert_eq!(pre.data()[3], a);
            let back = unpremultiply(&pre);
            prop_assert!(back.data().iter().zip(img.data()).all(|(x, y)| (x - y).abs() < 1e-4));
        }
    }

    #[test]
    fn set_alpha_takes_the_matte() {
        let out = set_alpha(&solid(2, 1, [0.5; 3]), &gray(2, 1, &[0.25, 2.0])).unwrap();
        assert_eq!(out.data(), &[0.5, 0.5, 0.5, 0.25, 0.5, 0.5, 0.5, 1.0]);
        assert!(set_alpha(&solid(2, 1, [0.5; 3]), &gray(1, 1, &[0.0])).unwrap_err().to_string().contains("'matte'"));
    }

    #[test]
    fn unpremultiply_of_zero_alpha_is_black() {
        let back = unpremultiply(&rgba(1, 1, &[0.5, 0.5, 0.5, 0.0]));
        assert_eq!(back.data(), &[0.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn synthetic_keeps_lightness_and_takes_the_blend_hue() {
        let src = gray(3, 1, &[0.0, 0.5, 1.0]);
        let out = synthetic_coloring(&src, &Blend::Solid([1.0, 0.5, 0.0])).unwrap();
        let mid = out.pixel(1, 0);
        let hls = rgb_to_hls([mid[0], mid[1], mid[2]]);
        assert!((hls[0] - 30.0).abs() < 1e-3 && (hls[1] - 0.5).abs() < 1e-5 && (hls[2] - 1.0).abs() < 1e-5, "{hls:?}");
        assert_eq!(&out.pixel(0, 0)[..3], &[0.0, 0.0, 0.0]);
        assert_eq!(&out.pixel(2, 0)[..3], &[1.0, 1.0, 1.0]);
        let tex = solid(2, 1, [0.0, 0.0, 1.0]);
        assert!(synthetic_coloring(&src, &Blend::Texture(&tex)).unwrap_err().to_string().contains("'texture' is 2x1"));
    }

    #[test]
    fn ramp_interpolates_and_clamps() {
        let ramp = ColorRamp::parse("0:0,0,0; 1:1,0.5,0").unwrap();
        assert_eq!(ramp.color_at(0.5), [0.5, 0.25, 0.0]);
        assert_eq!(ramp.color_at(-1.0), [0.0, 0.0, 0.0]);
        assert_eq!(ramp.color_at(2.0), [1.0, 0.5, 0.0]);
        assert!(ColorRamp::parse(DEFAULT_RAMP).is_ok());
        assert!(ColorRamp::parse("0:1,2").unwrap_err().contains("three"));
        assert!(ColorRamp::parse("").is_err());
        let ramped = synthetic_coloring(&gray(1, 1, &[0.5]), &Blend::RampDirect(&ramp)).unwrap();
        assert_eq!(ramped.data(), &[0.5, 0.25, 0.0, 1.0]);
    }
}
