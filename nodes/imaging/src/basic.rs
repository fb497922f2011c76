//! Basic image operations: gray conversion, crop, resize, clip trimming, compositing, constant
//! colour and mask display.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use image::imageops::{self, FilterType};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, ClipOf, Cook, CookCtx, FrameSource, Image, Mask, NodeError, Registry, Value, port};

use crate::convert;

/// Adds the basic imaging node types.
pub fn register(registry: &mut Registry) {
    registry.add(ToGray::node());
    registry.add(Crop::node());
    registry.add(Resize::node());
    registry.add(TimeRange::node());
    registry.add(Composite::node());
    registry.add(ConstantColor::node());
    registry.add(MaskToImage::node());
}

/// Largest width or height the nodes here create.
pub const MAX_SIZE: i64 = 16384;

/// Largest pixel offset accepted by `crop`.
const MAX_OFFSET: i64 = 1 << 20;

fn image_size_text(img: &Image) -> String {
    format!("{}x{}", img.width(), img.height())
}

// ---------------------------------------------------------------------------------------------
// imaging.to_gray
// ---------------------------------------------------------------------------------------------

pyrograph_core::choice! {
    /// How colour is reduced to one intensity.
    pub enum GrayMode {
        /// 0.299 R + 0.587 G + 0.114 B (OpenCV's `COLOR_RGB2GRAY`, used by the Eigenfires thesis).
        Rec601 = "rec601",
        /// 0.2126 R + 0.7152 G + 0.0722 B (sRGB / HDTV primaries).
        Rec709 = "rec709",
        /// (R + G + B) / 3.
        Average = "average",
        /// max(R, G, B).
        Max = "max",
    }
}

impl GrayMode {
    fn apply(self, r: f32, g: f32, b: f32) -> f32 {
        match self {
            GrayMode::Rec601 => 0.299 * r + 0.587 * g + 0.114 * b,
            GrayMode::Rec709 => 0.2126 * r + 0.7152 * g + 0.0722 * b,
            GrayMode::Average => (r + g + b) / 3.0,
            GrayMode::Max => r.max(g).max(b),
        }
    }
}

pyrograph_core::node! {
    /// Converts an image to one gray channel.
    ///
    /// Alpha is dropped; a gray input passes through unchanged.
    #[node("imaging.to_gray", "Imaging", PerFrame)]
    pub struct ToGray {
        /// The image to convert.
        image: Arc<Image>,
        /// Weights: rec601 (OpenCV), rec709, average or max of R, G, B.
        mode: GrayMode = GrayMode::Rec601,
    }
    pub struct ToGrayOut {
        /// The gray image.
        image: Arc<Image>,
    }
}

/// The gray version of `img` (alpha ignored).
pub fn to_gray(img: &Image, mode: GrayMode) -> Image {
    match img.channels() {
        Channels::Gray => img.clone(),
        Channels::Rgba => {
            let data = img.data().chunks_exact(4).map(|p| mode.apply(p[0], p[1], p[2])).collect();
            Image::from_vec(img.width(), img.height(), Channels::Gray, data)
                .unwrap_or_else(|| Image::new(img.width(), img.height(), Channels::Gray))
        }
    }
}

impl Cook for ToGray {
    fn cook(self, _: &CookCtx) -> Result<ToGrayOut, NodeError> {
        Ok(ToGrayOut { image: Arc::new(to_gray(&self.image, self.mode)) })
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.crop
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Cuts a rectangle out of an image.
    #[node("imaging.crop", "Imaging", PerFrame)]
    pub struct Crop {
        /// The image to crop.
        image: Arc<Image>,
        /// Left edge of the rectangle, in pixels from the left.
        #[range(0, MAX_OFFSET)]
        x: u32 = 0,
        /// Top edge of the rectangle, in pixels from the top.
        #[range(0, MAX_OFFSET)]
        y: u32 = 0,
        /// Width of the rectangle; 0 = up to the right edge.
        #[range(0, MAX_OFFSET)]
        width: u32 = 0,
        /// Height of the rectangle; 0 = up to the bottom edge.
        #[range(0, MAX_OFFSET)]
        height: u32 = 0,
    }
    pub struct CropOut {
        /// The cropped image.
        image: Arc<Image>,
    }
}

/// Resolves one axis of a crop: `(start, length)` within `size`, or an error naming the ports.
fn crop_span(start: u32, len: u32, size: u32, ports: (&str, &str), img: &Image) -> Result<(u32, u32), NodeError> {
    if start >= size {
        return Err(NodeError::port(ports.0, format!("{start} is outside the {} image", image_size_text(img))));
    }
    let len = if len == 0 { size - start } else { len };
    if u64::from(start) + u64::from(len) > u64::from(size) {
        return Err(NodeError::port(
            ports.1,
            format!("{} + {len} reaches past the edge of the {} image", start, image_size_text(img)),
        ));
    }
    Ok((start, len))
}

/// The `width × height` rectangle at `(x, y)`; 0 sizes reach the right / bottom edge.
pub fn crop(img: &Image, x: u32, y: u32, width: u32, height: u32) -> Result<Image, NodeError> {
    let (x, w) = crop_span(x, width, img.width(), (port!(Crop, x), port!(Crop, width)), img)?;
    let (y, h) = crop_span(y, height, img.height(), (port!(Crop, y), port!(Crop, height)), img)?;
    let n = img.channels().count();
    let row_len = img.width() as usize * n;
    let data: Vec<f32> = img
        .data()
        .chunks_exact(row_len)
        .skip(y as usize)
        .take(h as usize)
        .flat_map(|row| row.iter().skip(x as usize * n).take(w as usize * n).copied())
        .collect();
    Image::from_vec(w, h, img.channels(), data)
        .ok_or_else(|| NodeError::port(port!(Crop, image), "image data does not match its size"))
}

impl Cook for Crop {
    fn cook(self, _: &CookCtx) -> Result<CropOut, NodeError> {
        Ok(CropOut { image: Arc::new(crop(&self.image, self.x, self.y, self.width, self.height)?) })
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.resize
// ---------------------------------------------------------------------------------------------

pyrograph_core::choice! {
    /// A resampling filter of `imaging.resize`.
    pub enum ResizeFilter {
        /// The nearest pixel.
        Nearest = "nearest",
        /// Linear interpolation (a triangle filter).
        Bilinear = "bilinear",
        /// The Catmull–Rom cubic.
        CatmullRom = "catmull_rom",
        /// Lanczos with a window of 3.
        Lanczos3 = "lanczos3",
    }
}

impl ResizeFilter {
    /// The `image` crate's filter.
    pub fn filter_type(self) -> FilterType {
        match self {
            ResizeFilter::Nearest => FilterType::Nearest,
            ResizeFilter::Bilinear => FilterType::Triangle,
            ResizeFilter::CatmullRom => FilterType::CatmullRom,
            ResizeFilter::Lanczos3 => FilterType::Lanczos3,
        }
    }
}

pyrograph_core::node! {
    /// Scales an image to a new size.
    ///
    /// A width or height of 0 keeps the aspect ratio from the other one.
    #[node("imaging.resize", "Imaging", PerFrame)]
    pub struct Resize {
        /// The image to scale.
        image: Arc<Image>,
        /// New width; 0 = from height, keeping the aspect ratio.
        #[range(0, MAX_SIZE)]
        width: u32 = 0,
        /// New height; 0 = from width, keeping the aspect ratio.
        #[range(0, MAX_SIZE)]
        height: u32 = 0,
        /// Resampling filter.
        filter: ResizeFilter = ResizeFilter::Bilinear,
    }
    pub struct ResizeOut {
        /// The scaled image.
        image: Arc<Image>,
    }
}

/// The output size, filling a 0 side from the other one to keep the aspect ratio.
pub fn resize_target(img: &Image, width: u32, height: u32) -> Result<(u32, u32), NodeError> {
    let (w0, h0) = (f64::from(img.width()), f64::from(img.height()));
    if img.width() == 0 || img.height() == 0 {
        return Err(NodeError::port(port!(Resize, image), format!("cannot resize an empty {} image", image_size_text(img))));
    }
    let scaled = |v: f64| (v.round() as u32).max(1);
    match (width, height) {
        (0, 0) => Err(NodeError::port(port!(Resize, width), "width and height are both 0; set at least one of them")),
        (0, h) => Ok((scaled(w0 * f64::from(h) / h0), h)),
        (w, 0) => Ok((w, scaled(h0 * f64::from(w) / w0))),
        (w, h) => Ok((w, h)),
    }
}

/// `img` scaled to `width × height` (0 keeps the aspect ratio) with `filter`.
pub fn resize(img: &Image, width: u32, height: u32, filter: FilterType) -> Result<Image, NodeError> {
    let (w, h) = resize_target(img, width, height)?;
    // imageops clamps float samples to 0..1; scaling into that range first keeps HDR values.
    let peak = img.data().iter().fold(1.0_f32, |m, &v| m.max(v));
    let scale = |img: Image, k: f32| -> Image {
        let mut img = img;
        if k != 1.0 {
            img.data_mut().iter_mut().for_each(|v| *v *= k);
        }
        img
    };
    let normalised = scale(img.clone(), 1.0 / peak);
    let resized = match img.channels() {
        Channels::Gray => convert::from_gray32f(imageops::resize(&convert::to_gray32f(&normalised), w, h, filter)),
        Channels::Rgba => convert::from_rgba32f(imageops::resize(&convert::to_rgba32f(&normalised), w, h, filter)),
    };
    Ok(scale(resized, peak))
}

impl Cook for Resize {
    fn cook(self, _: &CookCtx) -> Result<ResizeOut, NodeError> {
        Ok(ResizeOut { image: Arc::new(resize(&self.image, self.width, self.height, self.filter.filter_type())?) })
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.time_range
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Keeps the frames first..=last of a clip.
    ///
    /// Frames are pulled from the source clip only when asked for.
    #[node("imaging.time_range", "Imaging", WholeClip)]
    pub struct TimeRange {
        /// The clip to trim.
        clip: ClipOf<Arc<Image>>,
        /// First frame kept (0-based).
        #[range(0, 1i64 << 40)]
        first: i64 = 0,
        /// Last frame kept, inclusive; negative counts from the end (-1 = last frame).
        #[range(-(1i64 << 40), 1i64 << 40)]
        last: i64 = -1,
    }
    pub struct TimeRangeOut {
        /// The trimmed clip.
        clip: ClipOf<Arc<Image>>,
    }
}

/// Frames `first..first + len` of another clip.
struct RangeSource {
    clip: Clip,
    first: usize,
    len: usize,
}

impl FrameSource for RangeSource {
    fn len(&self) -> usize {
        self.len
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        self.clip.get(self.first + index, ctx)
    }
}

/// Resolves `first..=last` (negative `last` counts from the end) against a clip of `len` frames.
pub fn resolve_range(len: usize, first: i64, last: i64) -> Result<(usize, usize), NodeError> {
    let frames = |len: usize| {
        if len == 0 { "it has no frames".to_string() } else { format!("frames 0-{}", len - 1) }
    };
    let len_i = i64::try_from(len).unwrap_or(i64::MAX);
    if first < 0 || first >= len_i {
        return Err(NodeError::port(
            port!(TimeRange, first),
            format!("frame {first} is outside the {len}-frame clip ({})", frames(len)),
        ));
    }
    let last_abs = if last < 0 { len_i + last } else { last };
    if last_abs < 0 || last_abs >= len_i {
        return Err(NodeError::port(
            port!(TimeRange, last),
            format!("frame {last} is outside the {len}-frame clip ({})", frames(len)),
        ));
    }
    if last_abs < first {
        return Err(NodeError::port(
            port!(TimeRange, last),
            format!("the range {first}-{last_abs} is empty: last must not be before first (the clip has {len} frames)"),
        ));
    }
    // Both are within 0..len, so they fit usize.
    Ok((first as usize, last_abs as usize))
}

/// The frames `first..=last` of `clip`, computed lazily from it.
pub fn time_range(clip: &Clip, first: i64, last: i64) -> Result<Clip, NodeError> {
    let (first, last) = resolve_range(clip.len(), first, last)?;
    let mut h = Fingerprinter::new();
    ("imaging.time_range", clip.fingerprint(), first, last).hash(&mut h);
    let source = RangeSource { clip: clip.clone(), first, len: last - first + 1 };
    Ok(Clip::new(clip.element().clone(), clip.fps(), h.finish(), Arc::new(source)))
}

impl Cook for TimeRange {
    fn cook(self, _: &CookCtx) -> Result<TimeRangeOut, NodeError> {
        Ok(TimeRangeOut { clip: ClipOf::new(time_range(&self.clip, self.first, self.last)?) })
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.composite
// ---------------------------------------------------------------------------------------------

pyrograph_core::choice! {
    /// How the foreground's colour combines with the background's.
    pub enum BlendMode {
        /// Porter–Duff over with straight alpha.
        Over = "over",
        /// a + b (not clamped: HDR allowed).
        Add = "add",
        /// 1 − (1 − a)(1 − b).
        Screen = "screen",
        /// max(a, b).
        Max = "max",
        /// a × b.
        Multiply = "multiply",
    }
}

impl BlendMode {
    /// The blended colour of one channel (`over` is the foreground itself).
    fn blend(self, a: f32, b: f32) -> f32 {
        match self {
            BlendMode::Over => b,
            BlendMode::Add => a + b,
            BlendMode::Screen => 1.0 - (1.0 - a) * (1.0 - b),
            BlendMode::Max => a.max(b),
            BlendMode::Multiply => a * b,
        }
    }
}

pyrograph_core::node! {
    /// Combines a foreground image b onto a background a.
    ///
    /// The foreground's weight is opacity × its alpha. `over` is Porter–Duff over with straight alpha; the other
    /// modes mix the background's colour towards mode(a, b) by that weight and combine alphas as over does. A gray
    /// input is promoted to RGBA when the other is RGBA; two gray inputs give a gray result.
    #[node("imaging.composite", "Imaging", PerFrame)]
    pub struct Composite {
        /// Background.
        a: Arc<Image>,
        /// Foreground, same size as a.
        b: Arc<Image>,
        /// How b combines with a.
        mode: BlendMode = BlendMode::Over,
        /// Strength of the foreground.
        #[range(0.0, 1.0)]
        opacity: f32 = 1.0,
    }
    pub struct CompositeOut {
        /// The composite.
        image: Arc<Image>,
    }
}

/// One straight-alpha RGBA pixel of `b` combined onto `a` with foreground weight `opacity`.
fn composite_rgba(a: &[f32], b: &[f32], mode: BlendMode, opacity: f32) -> [f32; 4] {
    let (aa, ba) = (a[3], b[3]);
    let w = opacity * ba;
    let alpha = w + aa * (1.0 - w);
    let mut out = [0.0, 0.0, 0.0, alpha];
    for c in 0..3 {
        out[c] = match mode {
            // Straight-alpha over: premultiply, combine, un-premultiply.
            BlendMode::Over if alpha > 0.0 => (b[c] * w + a[c] * aa * (1.0 - w)) / alpha,
            BlendMode::Over => 0.0,
            _ => a[c] + w * (mode.blend(a[c], b[c]) - a[c]),
        };
    }
    out
}

/// `b` combined onto `a`; both must have the same size.
pub fn composite(a: &Image, b: &Image, mode: BlendMode, opacity: f32) -> Result<Image, NodeError> {
    if a.size() != b.size() {
        return Err(NodeError::port(
            port!(Composite, b),
            format!("b is {} but a is {}; composite needs images of the same size", image_size_text(b), image_size_text(a)),
        ));
    }
    let (w, h) = a.size();
    let both_gray = a.channels() == Channels::Gray && b.channels() == Channels::Gray;
    let data: Vec<f32> = if both_gray {
        a.data().iter().zip(b.data()).map(|(&x, &y)| x + opacity * (mode.blend(x, y) - x)).collect()
    } else {
        let (a, b) = (a.to_rgba(), b.to_rgba());
        a.data().chunks_exact(4).zip(b.data().chunks_exact(4)).flat_map(|(p, q)| composite_rgba(p, q, mode, opacity)).collect()
    };
    let channels = if both_gray { Channels::Gray } else { Channels::Rgba };
    Image::from_vec(w, h, channels, data)
        .ok_or_else(|| NodeError::port(port!(Composite, a), "image data does not match its size"))
}

impl Cook for Composite {
    fn cook(self, _: &CookCtx) -> Result<CompositeOut, NodeError> {
        Ok(CompositeOut { image: Arc::new(composite(&self.a, &self.b, self.mode, self.opacity)?) })
    }
}

// ---------------------------------------------------------------------------------------------
// imaging.constant_color / imaging.mask_to_image
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// An RGBA image filled with one colour.
    #[node("imaging.constant_color", "Imaging", Source)]
    pub struct ConstantColor {
        /// Width in pixels.
        #[range(1, MAX_SIZE)]
        width: u32 = 512,
        /// Height in pixels.
        #[range(1, MAX_SIZE)]
        height: u32 = 512,
        /// The fill colour (linear RGBA, straight alpha).
        color: [f32; 4] = [0.0, 0.0, 0.0, 1.0],
    }
    pub struct ConstantColorOut {
        /// The filled image.
        image: Arc<Image>,
    }
}

/// A `width × height` RGBA image of `color`.
pub fn constant_color(width: u32, height: u32, color: [f32; 4]) -> Image {
    let data = std::iter::repeat_n(color, width as usize * height as usize).flatten().collect();
    Image::from_vec(width, height, Channels::Rgba, data).unwrap_or_else(|| Image::new(width, height, Channels::Rgba))
}

/// `v` when it is a size the nodes here create (1..=[`MAX_SIZE`]), else an error on `port`: the
/// port's range is only a hint to editors, and a 0 or huge image would fail later and less clearly.
fn check_size(v: u32, port: &str) -> Result<u32, NodeError> {
    if v >= 1 && i64::from(v) <= MAX_SIZE { Ok(v) } else { Err(NodeError::port(port, format!("{v} is outside 1..={MAX_SIZE}"))) }
}

impl Cook for ConstantColor {
    fn cook(self, _: &CookCtx) -> Result<ConstantColorOut, NodeError> {
        let width = check_size(self.width, port!(ConstantColor, width))?;
        let height = check_size(self.height, port!(ConstantColor, height))?;
        Ok(ConstantColorOut { image: Arc::new(constant_color(width, height, self.color)) })
    }
}

pyrograph_core::node! {
    /// Turns a mask into a gray image (0 outside, 1 inside), so masks can be viewed, composited and written.
    #[node("imaging.mask_to_image", "Imaging", PerFrame)]
    pub struct MaskToImage {
        /// The mask.
        mask: Arc<Mask>,
    }
    pub struct MaskToImageOut {
        /// The gray image.
        image: Arc<Image>,
    }
}

impl Cook for MaskToImage {
    fn cook(self, _: &CookCtx) -> Result<MaskToImageOut, NodeError> {
        Ok(MaskToImageOut { image: Arc::new(convert::mask_to_image(&self.mask)) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::params::Declared;
    use pyrograph_core::{Inputs, PortType};

    /// Cooks node `T` on `values` (one per input, in port order) as the graph would.
    fn cook_node<T: Cook>(values: &[Value]) -> Result<Vec<Value>, NodeError> {
        let node = T::node();
        node.cook(&Inputs::new(node.desc(), values), &CookCtx::new())
    }

    /// Reads node `T`'s inputs from `values`, as a cook does first.
    fn read<T: Declared>(values: &[Value]) -> Result<T, NodeError> {
        T::read(&Inputs::new(&T::desc(), values))
    }

    fn image_value(img: Image) -> Value {
        Value::Image(Arc::new(img))
    }

    fn rgba(w: u32, h: u32, data: &[f32]) -> Image {
        Image::from_vec(w, h, Channels::Rgba, data.to_vec()).unwrap()
    }

    fn gray(w: u32, h: u32, data: &[f32]) -> Image {
        Image::from_vec(w, h, Channels::Gray, data.to_vec()).unwrap()
    }

    fn assert_close(a: &[f32], b: &[f32]) {
        assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-5, "{a:?} vs {b:?}");
        }
    }

    fn int_clip(n: i64) -> Clip {
        Clip::from_frames(PortType::Int, 12.0, (0..n).map(Value::Int).collect())
    }

    fn ints(clip: &Clip) -> Vec<i64> {
        let ctx = CookCtx::new();
        (0..clip.len()).map(|i| if let Ok(Value::Int(v)) = clip.get(i, &ctx) { v } else { -1 }).collect()
    }

    #[test]
    fn gray_modes_give_their_weights() {
        let img = rgba(1, 1, &[1.0, 0.5, 0.25, 0.3]);
        let g = |m| to_gray(&img, m).data()[0];
        assert!((g(GrayMode::Rec601) - (0.299 + 0.587 * 0.5 + 0.114 * 0.25)).abs() < 1e-6);
        assert!((g(GrayMode::Rec709) - (0.2126 + 0.7152 * 0.5 + 0.0722 * 0.25)).abs() < 1e-6);
        assert!((g(GrayMode::Average) - 1.75 / 3.0).abs() < 1e-6);
        assert_eq!(g(GrayMode::Max), 1.0);
        assert_eq!(to_gray(&img, GrayMode::Max).channels(), Channels::Gray);
        let already = gray(2, 1, &[0.1, 0.2]);
        assert_eq!(to_gray(&already, GrayMode::Rec709), already);
        let err = read::<ToGray>(&[image_value(already), Value::Enum("luma".into())]).unwrap_err().to_string();
        assert!(err.contains("mode"), "{err}");
    }

    #[test]
    fn crop_cuts_the_rectangle_and_zero_reaches_the_edge() {
        let img = Image::gray_from_fn(4, 3, |x, y| (y * 4 + x) as f32);
        let c = crop(&img, 1, 1, 2, 2).unwrap();
        assert_eq!((c.size(), c.data()), ((2, 2), &[5.0, 6.0, 9.0, 10.0][..]));
        let c = crop(&img, 2, 1, 0, 0).unwrap();
        assert_eq!((c.size(), c.data()), ((2, 2), &[6.0, 7.0, 10.0, 11.0][..]));
        let c = crop(&rgba(2, 1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]), 1, 0, 1, 1).unwrap();
        assert_eq!(c.data(), &[5.0, 6.0, 7.0, 8.0]);
    }

    #[test]
    fn crop_outside_the_image_names_port_and_size() {
        let img = Image::gray_from_fn(4, 3, |_, _| 0.0);
        let err = crop(&img, 4, 0, 0, 0).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, message } if port == "x" && message.contains("4x3")), "{err}");
        let err = crop(&img, 1, 0, 4, 0).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, message } if port == "width" && message.contains("4x3")), "{err}");
        let err = crop(&img, 0, 1, 0, 3).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "height"), "{err}");
    }

    #[test]
    fn resize_keeps_aspect_and_values() {
        let img = Image::gray_from_fn(4, 2, |_, _| 0.5);
        assert_eq!(resize_target(&img, 2, 0).unwrap(), (2, 1));
        assert_eq!(resize_target(&img, 0, 4).unwrap(), (8, 4));
        assert!(resize_target(&img, 0, 0).unwrap_err().to_string().contains("both 0"));
        let r = resize(&img, 2, 0, FilterType::Triangle).unwrap();
        assert_eq!((r.size(), r.channels()), ((2, 1), Channels::Gray));
        assert_close(r.data(), &[0.5, 0.5]);
        let px = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let r = resize(&px, 2, 2, FilterType::Nearest).unwrap();
        assert_close(r.data(), &[0.2, 0.4, 0.6, 1.0].repeat(4));
    }

    #[test]
    fn resize_nearest_picks_pixels_and_hdr_survives() {
        let img = gray(2, 1, &[0.0, 1.0]);
        let r = resize(&img, 4, 1, FilterType::Nearest).unwrap();
        assert_close(r.data(), &[0.0, 0.0, 1.0, 1.0]);
        let hdr = gray(2, 2, &[4.0; 4]);
        let r = resize(&hdr, 1, 1, FilterType::Triangle).unwrap();
        assert_close(r.data(), &[4.0]);
        assert_eq!(ResizeFilter::parse("bilinear").unwrap().filter_type(), FilterType::Triangle);
        let values = [image_value(img), Value::Int(1), Value::Int(1), Value::Enum("cubic".into())];
        assert!(read::<Resize>(&values).unwrap_err().to_string().contains("filter"));
    }

    #[test]
    fn time_range_maps_frames_lazily() {
        let clip = int_clip(5);
        assert_eq!(ints(&time_range(&clip, 1, 3).unwrap()), [1, 2, 3]);
        assert_eq!(ints(&time_range(&clip, 2, -1).unwrap()), [2, 3, 4]);
        assert_eq!(ints(&time_range(&clip, 0, -2).unwrap()), [0, 1, 2, 3]);
        let trimmed = time_range(&clip, 4, 4).unwrap();
        assert_eq!((ints(&trimmed), trimmed.fps()), (vec![4], 12.0));
        assert_ne!(time_range(&clip, 0, 1).unwrap().fingerprint(), time_range(&clip, 1, 2).unwrap().fingerprint());
    }

    #[test]
    fn time_range_errors_name_port_and_length() {
        let clip = int_clip(5);
        let err = time_range(&clip, 5, -1).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, message } if port == "first" && message.contains("5-frame")), "{err}");
        let err = time_range(&clip, 0, 5).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, message } if port == "last" && message.contains("0-4")), "{err}");
        let err = time_range(&clip, 3, 2).unwrap_err();
        assert!(matches!(&err, NodeError::Port { port, message } if port == "last" && message.contains("empty")), "{err}");
        assert!(time_range(&int_clip(0), 0, -1).is_err());
    }

    #[test]
    fn composite_modes_on_one_pixel() {
        let a = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let b = rgba(1, 1, &[0.5, 0.5, 0.5, 1.0]);
        let run = |m| composite(&a, &b, m, 1.0).unwrap().into_vec();
        assert_close(&run(BlendMode::Over), &[0.5, 0.5, 0.5, 1.0]);
        assert_close(&run(BlendMode::Add), &[0.7, 0.9, 1.1, 1.0]);
        assert_close(&run(BlendMode::Screen), &[0.6, 0.7, 0.8, 1.0]);
        assert_close(&run(BlendMode::Max), &[0.5, 0.5, 0.6, 1.0]);
        assert_close(&run(BlendMode::Multiply), &[0.1, 0.2, 0.3, 1.0]);
        assert_close(&composite(&a, &b, BlendMode::Add, 0.5).unwrap().into_vec(), &[0.45, 0.65, 0.85, 1.0]);
    }

    #[test]
    fn over_uses_straight_alpha() {
        let a = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let half = rgba(1, 1, &[1.0, 0.0, 0.0, 0.5]);
        assert_close(&composite(&a, &half, BlendMode::Over, 1.0).unwrap().into_vec(), &[0.6, 0.2, 0.3, 1.0]);
        // Half-transparent red over half-transparent blue: alpha 0.75, colour weighted 2:1 to red.
        let blue = rgba(1, 1, &[0.0, 0.0, 1.0, 0.5]);
        assert_close(&composite(&blue, &half, BlendMode::Over, 1.0).unwrap().into_vec(), &[2.0 / 3.0, 0.0, 1.0 / 3.0, 0.75]);
        let clear = rgba(1, 1, &[0.0; 4]);
        assert_close(&composite(&clear, &clear, BlendMode::Over, 1.0).unwrap().into_vec(), &[0.0; 4]);
    }

    #[test]
    fn composite_promotes_gray_and_checks_sizes() {
        let g = gray(1, 1, &[0.5]);
        let both = composite(&g, &gray(1, 1, &[0.25]), BlendMode::Add, 1.0).unwrap();
        assert_eq!((both.channels(), both.data()), (Channels::Gray, &[0.75][..]));
        let mixed = composite(&g, &rgba(1, 1, &[0.1, 0.2, 0.3, 1.0]), BlendMode::Multiply, 1.0).unwrap();
        assert_eq!(mixed.channels(), Channels::Rgba);
        assert_close(mixed.data(), &[0.05, 0.1, 0.15, 1.0]);
        let err = composite(&g, &gray(2, 1, &[0.0, 0.0]), BlendMode::Over, 1.0).unwrap_err().to_string();
        assert!(err.contains("2x1") && err.contains("1x1"), "{err}");
    }

    #[test]
    fn constant_color_fills_every_pixel() {
        let img = constant_color(2, 1, [0.1, 0.2, 0.3, 0.4]);
        assert_eq!((img.size(), img.channels()), ((2, 1), Channels::Rgba));
        assert_eq!(img.data(), &[0.1, 0.2, 0.3, 0.4, 0.1, 0.2, 0.3, 0.4]);
    }

    #[test]
    fn cooks_read_their_ports() {
        let values: Vec<Value> = ConstantColor::desc().inputs.iter().map(|p| p.default.clone().unwrap()).collect();
        let out = cook_node::<ConstantColor>(&values).unwrap();
        assert!(matches!(&out[0], Value::Image(img) if img.size() == (512, 512) && img.pixel(3, 3) == [0.0, 0.0, 0.0, 1.0]));

        let values = [Value::Mask(Arc::new(Mask::from_vec(2, 1, vec![0, 255]).unwrap()))];
        let out = cook_node::<MaskToImage>(&values).unwrap();
        assert!(matches!(&out[0], Value::Image(img) if img.data() == [0.0, 1.0] && img.channels() == Channels::Gray));

        let values = [image_value(gray(2, 2, &[0.0; 4])), Value::Int(0), Value::Int(0), Value::Int(3), Value::Int(0)];
        let err = cook_node::<Crop>(&values).unwrap_err().to_string();
        assert!(err.contains("width") && err.contains("2x2"), "{err}");
    }
}
