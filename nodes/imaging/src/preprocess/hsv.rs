//! `imaging.hsv_mask`: the multi-layer HSV colour mask of the Eigenfires thesis (§3.2, eq. 3–4, Fig. 17).

use pyrograph_core::{
    Channels, CookCtx, FnNode, Image, Inputs, Mask, Node, NodeDesc, NodeError, PortDesc, PortType, TimeDep, Value,
};
use rayon::prelude::*;
use std::sync::Arc;

use crate::convert::unit_to_u8;

/// How one layer's mask combines with the masks of the layers above it (thesis Fig. 17).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Union: inside if inside either.
    Add,
    /// Removes this layer's pixels from the running mask.
    Subtract,
    /// Symmetric difference (exclusive or).
    Difference,
    /// Intersection: inside only if inside both.
    Intersect,
}

impl Blend {
    /// Names used by the `blend` parameters, in the order the editor lists them.
    pub const NAMES: [&'static str; 4] = ["add", "subtract", "difference", "intersect"];

    /// Parses a parameter value.
    pub fn parse(name: &str) -> Option<Blend> {
        match name {
            "add" => Some(Blend::Add),
            "subtract" => Some(Blend::Subtract),
            "difference" => Some(Blend::Difference),
            "intersect" => Some(Blend::Intersect),
            _ => None,
        }
    }

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

/// The mask of eq. 4 repeated over `layers` and blended in order, starting from an empty mask.
///
/// Errors if `image` is not RGBA (the hue of a gray image is undefined), naming port `image`.
pub fn hsv_mask(image: &Image, layers: &[HsvLayer]) -> Result<Mask, NodeError> {
    if image.channels() != Channels::Rgba {
        return Err(NodeError::port("image", "needs an RGBA image: hue is undefined for a gray image"));
    }
    let (w, h) = image.size();
    let mut out = vec![0u8; w as usize * h as usize];
    // Rows are independent, so one rayon task per row keeps 1280×720 frames well under a millisecond per core.
    out.par_chunks_mut(w.max(1) as usize).zip(image.data().par_chunks(w.max(1) as usize * 4)).for_each(|(row, src)| {
        for (m, px) in row.iter_mut().zip(src.chunks_exact(4)) {
            let hsv = rgb_to_hsv(px[0], px[1], px[2]);
            let inside = layers.iter().fold(false, |acc, l| l.blend.apply(acc, l.range.contains(hsv)));
            *m = if inside { 255 } else { 0 };
        }
    });
    Mask::from_vec(w, h, out).ok_or_else(|| NodeError::msg("internal: mask size mismatch"))
}

/// Default layers, converted from the OpenCV peer's half-hue ranges (×2):
/// blue (100,80,60)–(130,255,255), red (0,100,80)–(15,255,255), yellow (15,80,100)–(35,255,255).
const DEFAULTS: [(&str, bool, HsvRange); 3] = [
    ("blue", true, HsvRange { h_min: 200.0, h_max: 260.0, s_min: 80.0, s_max: 255.0, v_min: 60.0, v_max: 255.0 }),
    ("red", false, HsvRange { h_min: 0.0, h_max: 30.0, s_min: 100.0, s_max: 255.0, v_min: 80.0, v_max: 255.0 }),
    ("yellow", false, HsvRange { h_min: 30.0, h_max: 70.0, s_min: 80.0, s_max: 255.0, v_min: 100.0, v_max: 255.0 }),
];

fn layer_ports(desc: NodeDesc, n: usize, colour: &str, enabled: bool, r: &HsvRange) -> NodeDesc {
    let p = |s: &str| format!("layer{n}_{s}");
    let doc = |s: &str| format!("Layer {n} ({colour} by default): {s}");
    desc.input(PortDesc::bool(&p("enabled"), enabled, &doc("whether this layer contributes")))
        .input(PortDesc::float(
            &p("h_min"),
            f64::from(r.h_min),
            (0.0, 360.0),
            &doc("lowest hue in degrees; above h_max wraps past red"),
        ))
        .input(PortDesc::float(&p("h_max"), f64::from(r.h_max), (0.0, 360.0), &doc("highest hue in degrees")))
        .input(PortDesc::float(&p("s_min"), f64::from(r.s_min), (0.0, 255.0), &doc("lowest saturation (0–255)")))
        .input(PortDesc::float(&p("s_max"), f64::from(r.s_max), (0.0, 255.0), &doc("highest saturation (0–255)")))
        .input(PortDesc::float(&p("v_min"), f64::from(r.v_min), (0.0, 255.0), &doc("lowest value (0–255)")))
        .input(PortDesc::float(&p("v_max"), f64::from(r.v_max), (0.0, 255.0), &doc("highest value (0–255)")))
        .input(PortDesc::choice(&p("blend"), &Blend::NAMES, "add", &doc("how it combines with the layers above: add = union")))
}

/// Description of `imaging.hsv_mask`.
pub fn desc() -> NodeDesc {
    let d = NodeDesc::new(
        "imaging.hsv_mask",
        "Pre-processing",
        TimeDep::PerFrame,
        "Binary mask of up to three HSV colour ranges blended in order (Eigenfires thesis §3.2, eq. 3–4, Fig. 17).\n\
         Each enabled layer selects pixels whose hue (0–360°), saturation and value (0–255) lie in its inclusive \
         ranges and combines them into the running mask (starting empty) by add (union), subtract, difference or \
         intersect. A hue range with min > max wraps past red. Defaults are the OpenCV peer's blue, red and yellow \
         flame ranges (half-hues ×2); the image must be RGBA.",
    )
    .input(PortDesc::new("image", PortType::Image, "RGBA frame to segment"));
    let d = DEFAULTS.iter().enumerate().fold(d, |d, (i, (colour, on, r))| layer_ports(d, i + 1, colour, *on, r));
    d.output("mask", PortType::Mask, "255 where the blended layers select the pixel")
}

fn read_range(inputs: &Inputs<'_>, n: usize) -> Result<HsvRange, NodeError> {
    let get = |s: &str| inputs.float(&format!("layer{n}_{s}")).map(|v| v as f32);
    let r = HsvRange {
        h_min: get("h_min")?,
        h_max: get("h_max")?,
        s_min: get("s_min")?,
        s_max: get("s_max")?,
        v_min: get("v_min")?,
        v_max: get("v_max")?,
    };
    for (what, lo, hi) in [("s", r.s_min, r.s_max), ("v", r.v_min, r.v_max)] {
        if lo > hi {
            return Err(NodeError::port(
                format!("layer{n}_{what}_min"),
                format!("{lo} is above layer{n}_{what}_max {hi}; only hue ranges wrap"),
            ));
        }
    }
    Ok(r)
}

/// Reads the enabled layers from the node's parameters.
pub fn read_layers(inputs: &Inputs<'_>) -> Result<Vec<HsvLayer>, NodeError> {
    let mut layers = Vec::with_capacity(DEFAULTS.len());
    for n in 1..=DEFAULTS.len() {
        if !inputs.bool(&format!("layer{n}_enabled"))? {
            continue;
        }
        let port = format!("layer{n}_blend");
        let name = inputs.choice(&port)?;
        let blend = Blend::parse(name).ok_or_else(|| NodeError::port(&port, format!("unknown blend mode '{name}'")))?;
        layers.push(HsvLayer { range: read_range(inputs, n)?, blend });
    }
    Ok(layers)
}

fn cook(inputs: &Inputs<'_>, _ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let image = inputs.image("image")?;
    let layers = read_layers(inputs)?;
    Ok(vec![Value::Mask(Arc::new(hsv_mask(image, &layers)?))])
}

/// The `imaging.hsv_mask` node.
pub fn node() -> Arc<dyn Node> {
    FnNode::new(desc(), cook)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let layers: Vec<HsvLayer> = DEFAULTS.iter().map(|(_, _, r)| HsvLayer { range: *r, blend: Blend::Add }).collect();
        assert_eq!(bits(&hsv_mask(&img, &layers).unwrap()), [1, 1, 1, 0]);
    }

    #[test]
    fn gray_image_is_an_error_naming_the_image_port() {
        let gray = Image::new(2, 2, Channels::Gray);
        let err = hsv_mask(&gray, &[]).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "image"), "{err}");
    }

    fn node_inputs(overrides: &[(&str, Value)]) -> (NodeDesc, Vec<Value>) {
        let d = desc();
        let mut values: Vec<Value> =
            d.inputs.iter().map(|p| p.default.clone().unwrap_or_else(|| Value::Image(Arc::new(rgba(&[RED]))))).collect();
        for (name, v) in overrides {
            let i = d.input_index(name).unwrap();
            values[i] = v.clone();
        }
        (d, values)
    }

    #[test]
    fn saturation_min_above_max_names_the_port() {
        let (d, values) = node_inputs(&[
            ("layer2_enabled", Value::Bool(true)),
            ("layer2_s_min", Value::Float(200.0)),
            ("layer2_s_max", Value::Float(100.0)),
        ]);
        let err = cook(&Inputs::new(&d, &values), &CookCtx::new()).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "layer2_s_min"), "{err}");
    }

    #[test]
    fn node_with_all_layers_keeps_red() {
        let (d, values) = node_inputs(&[("layer2_enabled", Value::Bool(true)), ("layer3_enabled", Value::Bool(true))]);
        let out = cook(&Inputs::new(&d, &values), &CookCtx::new()).unwrap();
        let Value::Mask(m) = &out[0] else { panic!("not a mask") };
        assert_eq!(bits(m), [1]);
    }
}
