//! Port types and the values that flow along edges: scalars, images, masks and lazy clips.

use std::fmt;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::Arc;

mod animated;
pub mod clip;
mod compact;
pub mod frame_cache;
pub mod points;
pub mod ramp;

use crate::fingerprint::{Fingerprinter, hash_f32s};
mod custom;

pub use animated::animated_param;
pub use clip::{Clip, FrameSource};
pub use custom::{CustomValue, TypeInfo, ValueType};
pub use points::{Place, Points};
pub use ramp::RampKeys;

/// The closed set of types a port can carry.
///
/// `Clip(T)` is a time-varying sequence of `T`. Connecting a `Clip(T)` output to a `T` input of a
/// per-frame node lifts that node over time (its outputs become clips); nothing else converts
/// implicitly.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum PortType {
    /// 64-bit float.
    Float,
    /// 64-bit signed integer.
    Int,
    /// Boolean.
    Bool,
    /// Linear RGBA colour.
    Color,
    /// Two floats.
    Vec2,
    /// Three floats.
    Vec3,
    /// Free text.
    String,
    /// Keys over a position in 0..1 with this many components each: a colour ramp (4) or a
    /// scalar curve (1), written `[(position, value), …]`.
    Ramp(usize),
    /// Timed places on a surface (positions or faces), written `[(x, y, z), (seconds, face(F)), …]`.
    Points,
    /// A file-system path; relative paths resolve against the graph file's folder.
    Path,
    /// One of a fixed list of names (the port description lists them).
    Enum,
    /// An f32 image, gray or RGBA.
    Image,
    /// A binary mask (0 or 255 per pixel).
    Mask,
    /// Polygons traced from a mask, with hierarchy depth and area.
    Contours,
    /// A type declared by a node crate with [`ValueType`] (meshes, learned models, wind fields,
    /// cloth states…): never a parameter, always connected.
    Custom(&'static TypeInfo),
    /// A time-varying sequence of the inner type.
    Clip(Box<PortType>),
}

impl PortType {
    /// `Clip<inner>`.
    pub fn clip_of(inner: PortType) -> PortType {
        PortType::Clip(Box::new(inner))
    }

    /// The port type of values of `T`, a type declared by a node crate.
    pub fn of<T: ValueType>() -> PortType {
        PortType::Custom(T::INFO)
    }

    /// The element type of a clip type, `None` for per-frame types.
    pub fn clip_element(&self) -> Option<&PortType> {
        match self {
            PortType::Clip(inner) => Some(inner),
            _ => None,
        }
    }

    /// Types that can be written as a constant parameter in a graph file.
    pub fn is_parameter(&self) -> bool {
        !matches!(self, PortType::Image | PortType::Mask | PortType::Contours | PortType::Custom(_) | PortType::Clip(_))
    }
}

impl fmt::Display for PortType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PortType::Clip(inner) => write!(f, "Clip<{inner}>"),
            PortType::Custom(info) => f.write_str(info.name),
            PortType::Ramp(4) => f.write_str("ColorRamp"),
            PortType::Ramp(1) => f.write_str("Curve"),
            PortType::Ramp(n) => write!(f, "Ramp{n}"),
            other => write!(f, "{other:?}"),
        }
    }
}

/// Channel layout of an [`Image`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channels {
    /// One plane of intensity.
    Gray,
    /// Interleaved red, green, blue, alpha (straight alpha).
    Rgba,
}

impl Channels {
    /// Number of interleaved floats per pixel.
    pub fn count(self) -> usize {
        match self {
            Channels::Gray => 1,
            Channels::Rgba => 4,
        }
    }
}

/// An f32 image with interleaved channels; nominal range 0..1, values above 1 are HDR.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    channels: Channels,
    data: Vec<f32>,
}

impl Image {
    /// A black (and, for RGBA, fully transparent) image.
    pub fn new(width: u32, height: u32, channels: Channels) -> Self {
        let len = width as usize * height as usize * channels.count();
        Image { width, height, channels, data: vec![0.0; len] }
    }

    /// Wraps existing interleaved data; `None` when its length does not match the size.
    pub fn from_vec(width: u32, height: u32, channels: Channels, data: Vec<f32>) -> Option<Self> {
        (data.len() == width as usize * height as usize * channels.count()).then_some(Image { width, height, channels, data })
    }

    /// Builds a gray image from a function of the pixel coordinates.
    pub fn gray_from_fn(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Self {
        let data = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect();
        Image { width, height, channels: Channels::Gray, data }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Channel layout.
    pub fn channels(&self) -> Channels {
        self.channels
    }

    /// Interleaved samples, row-major from the top-left.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// Mutable interleaved samples.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Consumes the image, returning its samples.
    pub fn into_vec(self) -> Vec<f32> {
        self.data
    }

    /// The samples of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> &[f32] {
        let n = self.channels.count();
        let i = (y as usize * self.width as usize + x as usize) * n;
        &self.data[i..i + n]
    }

    /// Bytes held by the samples (used for cache budgets).
    pub fn byte_size(&self) -> usize {
        self.data.len() * std::mem::size_of::<f32>()
    }

    /// This image as RGBA: gray is replicated into RGB with alpha 1.
    pub fn to_rgba(&self) -> Image {
        match self.channels {
            Channels::Rgba => self.clone(),
            Channels::Gray => {
                let data = self.data.iter().flat_map(|&v| [v, v, v, 1.0]).collect();
                Image { width: self.width, height: self.height, channels: Channels::Rgba, data }
            }
        }
    }
}

/// A binary mask: one byte per pixel, 0 outside and 255 inside (imageproc's convention).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

impl Mask {
    /// An empty (all-outside) mask.
    pub fn new(width: u32, height: u32) -> Self {
        Mask { width, height, data: vec![0; width as usize * height as usize] }
    }

    /// Wraps existing bytes; `None` when the length does not match. Non-zero bytes become 255.
    pub fn from_vec(width: u32, height: u32, mut data: Vec<u8>) -> Option<Self> {
        if data.len() != width as usize * height as usize {
            return None;
        }
        data.iter_mut().for_each(|v| *v = if *v == 0 { 0 } else { 255 });
        Some(Mask { width, height, data })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// One byte per pixel, row-major.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// Whether pixel `(x, y)` is inside.
    pub fn get(&self, x: u32, y: u32) -> bool {
        self.data[y as usize * self.width as usize + x as usize] != 0
    }
}

/// One closed polygon traced from a mask.
#[derive(Clone, Debug, PartialEq)]
pub struct Contour {
    /// Vertices in pixel coordinates (x right, y down), in border-following order.
    pub points: Vec<[f32; 2]>,
    /// Nesting depth: 0 for outermost borders, 1 for the holes in them, 2 for islands in holes, …
    pub depth: u32,
    /// Index of the enclosing contour in the same list, if any.
    pub parent: Option<usize>,
    /// Enclosed area in square pixels (shoelace formula, always positive).
    pub area: f64,
}

impl Contour {
    /// Whether this contour bounds a hole (odd depth).
    pub fn is_hole(&self) -> bool {
        self.depth % 2 == 1
    }
}

/// The contours of one mask, with the size of the image they were traced in.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Contours {
    /// Width of the source image.
    pub width: u32,
    /// Height of the source image.
    pub height: u32,
    /// Contours, parents before their children.
    pub contours: Vec<Contour>,
}

/// A value on a port.
#[derive(Clone, Debug)]
pub enum Value {
    /// See [`PortType::Float`].
    Float(f64),
    /// See [`PortType::Int`].
    Int(i64),
    /// See [`PortType::Bool`].
    Bool(bool),
    /// See [`PortType::Color`].
    Color([f32; 4]),
    /// See [`PortType::Vec2`].
    Vec2([f64; 2]),
    /// See [`PortType::Vec3`].
    Vec3([f64; 3]),
    /// See [`PortType::String`].
    String(String),
    /// See [`PortType::Path`].
    Path(PathBuf),
    /// See [`PortType::Ramp`].
    Ramp(Arc<RampKeys>),
    /// See [`PortType::Points`].
    Points(Arc<Points>),
    /// See [`PortType::Enum`]: the chosen option's name.
    Enum(String),
    /// See [`PortType::Image`].
    Image(Arc<Image>),
    /// See [`PortType::Mask`].
    Mask(Arc<Mask>),
    /// See [`PortType::Contours`].
    Contours(Arc<Contours>),
    /// See [`PortType::Custom`]; [`Value::custom`] wraps one, [`Value::downcast`] unwraps it.
    Custom(Arc<dyn CustomValue>),
    /// See [`PortType::Clip`].
    Clip(Clip),
    /// A parameter that changes over time (keys or an expression), of the port type it samples
    /// to; the evaluator or the node samples it at the frame it computes (see [`crate::anim`]).
    Anim(Arc<crate::anim::Animated>),
}

impl Value {
    /// The type of this value.
    pub fn port_type(&self) -> PortType {
        match self {
            Value::Float(_) => PortType::Float,
            Value::Int(_) => PortType::Int,
            Value::Bool(_) => PortType::Bool,
            Value::Color(_) => PortType::Color,
            Value::Vec2(_) => PortType::Vec2,
            Value::Vec3(_) => PortType::Vec3,
            Value::String(_) => PortType::String,
            Value::Path(_) => PortType::Path,
            Value::Ramp(r) => PortType::Ramp(r.width()),
            Value::Points(_) => PortType::Points,
            Value::Enum(_) => PortType::Enum,
            Value::Image(_) => PortType::Image,
            Value::Mask(_) => PortType::Mask,
            Value::Contours(_) => PortType::Contours,
            Value::Custom(v) => PortType::Custom(v.type_info()),
            Value::Clip(c) => PortType::clip_of(c.element().clone()),
            Value::Anim(a) => a.port_type(),
        }
    }

    /// Wraps a value of a type declared by a node crate.
    pub fn custom<T: ValueType>(v: Arc<T>) -> Value {
        Value::Custom(v)
    }

    /// The `T` inside, if this is a custom value of type `T`.
    pub fn downcast<T: ValueType>(&self) -> Option<Arc<T>> {
        match self {
            Value::Custom(v) => {
                let any: Arc<dyn std::any::Any + Send + Sync> = v.clone();
                any.downcast::<T>().ok()
            }
            _ => None,
        }
    }

    /// Short name of the value's type for messages.
    pub fn type_name(&self) -> String {
        self.port_type().to_string()
    }

    /// A content hash: equal values hash equal, so unchanged outputs stop re-cooking downstream.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fingerprinter::new();
        self.hash_into(&mut h);
        h.finish()
    }

    /// Feeds the value's content into a hasher.
    pub fn hash_into(&self, h: &mut Fingerprinter) {
        std::mem::discriminant(self).hash(h);
        match self {
            Value::Float(v) => v.to_bits().hash(h),
            Value::Int(v) => v.hash(h),
            Value::Bool(v) => v.hash(h),
            Value::Color(c) => c.iter().for_each(|v| v.to_bits().hash(h)),
            Value::Vec2(c) => c.iter().for_each(|v| v.to_bits().hash(h)),
            Value::Vec3(c) => c.iter().for_each(|v| v.to_bits().hash(h)),
            Value::String(s) | Value::Enum(s) => s.hash(h),
            Value::Path(p) => p.hash(h),
            Value::Ramp(r) => r.hash_into(h),
            Value::Points(p) => p.hash_into(h),
            Value::Image(img) => {
                (img.width, img.height, img.channels).hash(h);
                hash_f32s(h, &img.data);
            }
            Value::Mask(m) => {
                (m.width, m.height).hash(h);
                h.write(&m.data);
            }
            Value::Contours(c) => {
                (c.width, c.height, c.contours.len()).hash(h);
                for k in &c.contours {
                    (k.depth, k.parent, k.area.to_bits(), k.points.len()).hash(h);
                    k.points.iter().for_each(|p| (p[0].to_bits(), p[1].to_bits()).hash(h));
                }
            }
            Value::Custom(v) => {
                v.type_info().name.hash(h);
                v.hash_value(h);
            }
            Value::Clip(c) => c.fingerprint().hash(h),
            Value::Anim(a) => a.hash_into(h),
        }
    }

    /// Approximate memory held by the value.
    pub fn byte_size(&self) -> usize {
        match self {
            Value::Image(img) => img.byte_size(),
            Value::Mask(m) => m.data.len(),
            Value::Contours(c) => c.contours.iter().map(|k| k.points.len() * 8 + 48).sum(),
            Value::Custom(v) => v.value_bytes(),
            Value::String(s) | Value::Enum(s) => s.len(),
            _ => std::mem::size_of::<Value>(),
        }
    }

    /// A one-line human description (`Image 480×480 Rgba`, `Clip<Image> 150 frames`, `0.5`).
    pub fn summary(&self) -> String {
        match self {
            Value::Float(v) => format!("{v}"),
            Value::Int(v) => format!("{v}"),
            Value::Bool(v) => format!("{v}"),
            Value::Color(c) => format!("({}, {}, {}, {})", c[0], c[1], c[2], c[3]),
            Value::Vec2(c) => format!("({}, {})", c[0], c[1]),
            Value::Vec3(c) => format!("({}, {}, {})", c[0], c[1], c[2]),
            Value::String(s) | Value::Enum(s) => s.clone(),
            Value::Path(p) => p.display().to_string(),
            Value::Ramp(r) => r.summary(),
            Value::Points(p) => p.summary(),
            Value::Image(img) => format!("Image {}x{} {:?}", img.width, img.height, img.channels),
            Value::Mask(m) => format!("Mask {}x{}", m.width, m.height),
            Value::Contours(c) => format!("Contours {} in {}x{}", c.contours.len(), c.width, c.height),
            Value::Custom(v) => v.value_summary(),
            Value::Clip(c) => format!("Clip<{}> {} frames @ {} fps", c.element(), c.len(), c.fps()),
            Value::Anim(a) => a.summary(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_type_displays_its_element() {
        assert_eq!(PortType::clip_of(PortType::Image).to_string(), "Clip<Image>");
        assert_eq!(PortType::Float.to_string(), "Float");
    }

    #[test]
    fn gray_to_rgba_replicates_with_opaque_alpha() {
        let img = Image::gray_from_fn(2, 1, |x, _| x as f32 * 0.5);
        let rgba = img.to_rgba();
        assert_eq!(rgba.data(), &[0.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 1.0]);
    }

    #[test]
    fn equal_images_share_a_fingerprint_and_different_ones_do_not() {
        let a = Value::Image(Arc::new(Image::gray_from_fn(3, 3, |x, y| (x + y) as f32)));
        let b = Value::Image(Arc::new(Image::gray_from_fn(3, 3, |x, y| (x + y) as f32)));
        let c = Value::Image(Arc::new(Image::gray_from_fn(3, 3, |x, y| (x * y) as f32)));
        assert_eq!(a.fingerprint(), b.fingerprint());
        assert_ne!(a.fingerprint(), c.fingerprint());
    }

    #[test]
    fn mask_from_vec_normalises_to_255_and_checks_length() {
        let m = Mask::from_vec(2, 1, vec![0, 7]).unwrap();
        assert_eq!(m.data(), &[0, 255]);
        assert!(Mask::from_vec(2, 2, vec![0]).is_none());
    }

    #[test]
    fn clip_rejects_out_of_range_frames_and_materializes_in_order() {
        let frames = (0..5).map(Value::Int).collect();
        let clip = Clip::from_frames(PortType::Int, 24.0, frames);
        let ctx = crate::ctx::CookCtx::default();
        assert!(clip.get(5, &ctx).is_err());
        let all = clip.materialize(&ctx).unwrap();
        let ints: Vec<i64> = all.iter().map(|v| if let Value::Int(i) = v { *i } else { -1 }).collect();
        assert_eq!(ints, vec![0, 1, 2, 3, 4]);
    }
}
