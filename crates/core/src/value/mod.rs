//! Port types and the values that flow along edges: scalars, images, masks and lazy clips.

use std::fmt;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::Arc;

pub mod clip;
mod compact;
pub mod frame_cache;

use crate::fingerprint::{Fingerprinter, hash_f32s};
pub use crate::learned::{ArModel, FlameModel, ParamSeries};
pub use crate::mesh::{CharMark, FlameRoot, Mesh, NO_NEIGHBOR, SpreadState};
pub use clip::{Clip, FrameSource};

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
    /// A wind field description (Perry 1994 §3.2.3), evaluated by the particle nodes.
    WindField,
    /// A set of particles (flame roots, flame trajectories, lights).
    Particles,
    /// Mass-spring flame cloths at one moment (mass-spring flame project 2019).
    ClothState,
    /// An Eigenfires basis: mean image, eigenvectors and eigenvalues (thesis §4.2).
    Basis,
    /// Eigenfires weights, frames × components (thesis §4.3 eq. 18).
    Weights,
    /// A sequence of database frames and synthesized weight vectors (thesis §5.1 motion lists).
    FrameList,
    /// A time series of flame-model parameter vectors x_t (Stich & Magnor §3).
    ParamSeries,
    /// A learned auto-regressive process (Stich & Magnor §4).
    ArModel,
    /// The generic flame model: parameter sizes and eigenflames (Stich & Magnor §3).
    FlameModel,
    /// A triangle mesh with face adjacency (Perry 1994 §3.3.2).
    Mesh,
    /// A fire spreading over a mesh at one moment (Perry 1994 §3.3–3.4).
    SpreadState,
    /// A time-varying sequence of the inner type.
    Clip(Box<PortType>),
}

impl PortType {
    /// `Clip<inner>`.
    pub fn clip_of(inner: PortType) -> PortType {
        PortType::Clip(Box::new(inner))
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
        !matches!(
            self,
            PortType::Image
                | PortType::Mask
                | PortType::Contours
                | PortType::WindField
                | PortType::Particles
                | PortType::ClothState
                | PortType::Basis
                | PortType::Weights
                | PortType::FrameList
                | PortType::ParamSeries
                | PortType::ArModel
                | PortType::FlameModel
                | PortType::Mesh
                | PortType::SpreadState
                | PortType::Clip(_)
        )
    }
}

impl fmt::Display for PortType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PortType::Clip(inner) => write!(f, "Clip<{inner}>"),
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

/// The large-scale part `w_L(p, t)` of a [`WindField`] (Perry 1994 §3.2.3, §3.4).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum LargeWind {
    /// No large-scale wind.
    #[default]
    None,
    /// A constant wind vector.
    Constant([f32; 3]),
    /// A Rankine vortex around the vertical axis through `center`: tangential speed grows
    /// linearly to `strength` at `radius`, then falls off as `1/r`.
    Vortex {
        /// A point on the vortex axis.
        center: [f32; 3],
        /// Tangential speed at `radius` (positive: counter-clockwise seen from above).
        strength: f32,
        /// Core radius.
        radius: f32,
    },
    /// The wind felt by flames on an object moving with this velocity: its negative (§3.4).
    MovingObject([f32; 3]),
}

/// The wind `u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t)` of Perry 1994 §3.2.3, as data; the
/// particle nodes evaluate it. `w_S` is eq. 3.1: `((p − p(0))·ĵ) C ∇N(k_p p − k_s T ĵ)`.
#[derive(Clone, Debug, PartialEq)]
pub struct WindField {
    /// Gravity `g` (Perry: `−ĵ`).
    pub gravity: [f32; 3],
    /// Convection coefficient `k_g` (Perry: 1.0).
    pub k_g: f32,
    /// Large-scale wind `w_L`.
    pub large: LargeWind,
    /// Flame noisiness `C` of eq. 3.1.
    pub noise_c: f32,
    /// Inverse inter-flame cohesion `k_p`: the scale of positions in noise space.
    pub k_p: f32,
    /// Flame sampling `k_s`: how fast time moves down through the noise field (per frame).
    pub k_s: f32,
    /// Seed of the noise field.
    pub seed: u32,
    /// World length of one unit of the height factor of eq. 3.1 (the paper measures height in
    /// unit-time integration steps; smaller values bend flames more).
    pub height_unit: f32,
}

impl Default for WindField {
    fn default() -> Self {
        WindField {
            gravity: [0.0, -1.0, 0.0],
            k_g: 1.0,
            large: LargeWind::None,
            noise_c: 0.04,
            k_p: 1.0,
            k_s: 0.1,
            seed: 0,
            height_unit: 1.0,
        }
    }
}

/// One particle: a camera-facing fuzzy N-gon (Perry 1994 §3.2.1), or a root, or a light.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Particle {
    /// World position.
    pub position: [f32; 3],
    /// Velocity (for roots: the initial direction of the flame).
    pub velocity: [f32; 3],
    /// Half extents of the N-gon along the billboard's x and y.
    pub size: [f32; 2],
    /// Straight RGBA of the centre vertex.
    pub center: [f32; 4],
    /// Straight RGBA of the rim vertices.
    pub edge: [f32; 4],
    /// A free scalar: the age for flame particles, the intensity for lights.
    pub weight: f32,
    /// Which flame (or other group) the particle belongs to.
    pub group: u32,
}

/// A set of particles at one moment.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Particles {
    /// The particles, in drawing order.
    pub particles: Vec<Particle>,
    /// Triangles per particle N-gon.
    pub sides: u32,
    /// Simulation time, in frames.
    pub time: f32,
}

/// Mass-spring flames at one moment (mass-spring flame project 2019, after Balci & Foroosh 2006):
/// `flames` cloths of `width × height` masses each, in flame-local coordinates (x across, y up,
/// z toward the viewer) around a world root, so a renderer can turn each one to face its camera.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ClothState {
    /// Masses per row.
    pub width: u32,
    /// Rows of masses; row 0 is the pinned bottom row.
    pub height: u32,
    /// World position of each flame's root (the centre of its pinned bottom row).
    pub roots: Vec<[f32; 3]>,
    /// Per-flame seed (a renderer picks a built-in texture from it).
    pub seeds: Vec<u32>,
    /// Local mass positions, flame-major, then row-major from the bottom row:
    /// `flames × height × width`.
    pub positions: Vec<[f32; 3]>,
    /// Simulation time in seconds.
    pub time: f32,
}

impl ClothState {
    /// Number of flames.
    pub fn flames(&self) -> usize {
        self.roots.len()
    }

    /// The local positions of flame `i`, `None` past the last.
    pub fn flame(&self, i: usize) -> Option<&[[f32; 3]]> {
        let n = self.width as usize * self.height as usize;
        self.positions.get(i * n..(i + 1) * n)
    }
}

/// Where a database frame came from: which training clip (0-based) and which frame of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct FrameRef {
    /// Index of the training clip.
    pub clip: u32,
    /// Frame index within that clip.
    pub index: u32,
}

/// An Eigenfires basis (thesis §4.2): the mean image Ψ (eq. 12), the eigenvectors `u_k` of the
/// covariance (eq. 15–17) sorted by decreasing eigenvalue `λ_k` (eq. 13), and where each training
/// frame came from. Gray `width × height` images are vectors of `N = width·height` samples.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Basis {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The mean image Ψ, `N` samples row-major.
    pub mean: Vec<f32>,
    /// The eigenvectors, one after another (`components × N`, component-major): eigenvector `k`
    /// is `eigenvectors[k·N..(k+1)·N]` (a column-major `N × components` matrix).
    pub eigenvectors: Vec<f32>,
    /// Eigenvalues λ_k (eq. 13), largest first, one per eigenvector.
    pub eigenvalues: Vec<f64>,
    /// Source clip and frame of each training frame (the rows of its training weights).
    pub sources: Vec<FrameRef>,
}

impl Basis {
    /// Samples per image, `N`.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Number of eigenvectors `E`.
    pub fn components(&self) -> usize {
        self.eigenvalues.len()
    }

    /// Eigenvector `k` (0-based), `None` past the last.
    pub fn eigenvector(&self, k: usize) -> Option<&[f32]> {
        let n = self.pixels();
        self.eigenvectors.get(k * n..(k + 1) * n)
    }
}

/// Eigenfires weights (thesis §4.3 eq. 18): one row Ω of `components` weights per frame.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Weights {
    /// Number of rows (frames).
    pub frames: usize,
    /// Number of columns (components).
    pub components: usize,
    /// Row-major `frames × components`.
    pub data: Vec<f32>,
}

impl Weights {
    /// Wraps row-major data; `None` if its length is not `frames × components`.
    pub fn new(frames: usize, components: usize, data: Vec<f32>) -> Option<Self> {
        (frames.checked_mul(components)? == data.len()).then_some(Weights { frames, components, data })
    }

    /// Row `i` (the weights of frame `i`), `None` past the last.
    pub fn row(&self, i: usize) -> Option<&[f32]> {
        self.data.get(i * self.components..(i + 1) * self.components)
    }
}

/// One entry of a [`FrameList`].
#[derive(Clone, Debug, PartialEq)]
pub enum FrameItem {
    /// A database frame: a row of the training weights (and a frame of a training clip).
    Frame(u32),
    /// A synthesized weight vector (a low-pass morph, a hand-edited flame).
    Weights(Vec<f32>),
}

/// A motion list (thesis §5.1): the frames of an animation, each a database frame or a
/// synthesized weight vector.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FrameList {
    /// The frames in playing order.
    pub items: Vec<FrameItem>,
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
    /// See [`PortType::Enum`]: the chosen option's name.
    Enum(String),
    /// See [`PortType::Image`].
    Image(Arc<Image>),
    /// See [`PortType::Mask`].
    Mask(Arc<Mask>),
    /// See [`PortType::Contours`].
    Contours(Arc<Contours>),
    /// See [`PortType::WindField`].
    WindField(Arc<WindField>),
    /// See [`PortType::Particles`].
    Particles(Arc<Particles>),
    /// See [`PortType::ClothState`].
    ClothState(Arc<ClothState>),
    /// See [`PortType::Basis`].
    Basis(Arc<Basis>),
    /// See [`PortType::Weights`].
    Weights(Arc<Weights>),
    /// See [`PortType::FrameList`].
    FrameList(Arc<FrameList>),
    /// See [`PortType::ParamSeries`].
    ParamSeries(Arc<ParamSeries>),
    /// See [`PortType::ArModel`].
    ArModel(Arc<ArModel>),
    /// See [`PortType::FlameModel`].
    FlameModel(Arc<FlameModel>),
    /// See [`PortType::Mesh`].
    Mesh(Arc<Mesh>),
    /// See [`PortType::SpreadState`].
    SpreadState(Arc<SpreadState>),
    /// See [`PortType::Clip`].
    Clip(Clip),
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
            Value::Enum(_) => PortType::Enum,
            Value::Image(_) => PortType::Image,
            Value::Mask(_) => PortType::Mask,
            Value::Contours(_) => PortType::Contours,
            Value::WindField(_) => PortType::WindField,
            Value::Particles(_) => PortType::Particles,
            Value::ClothState(_) => PortType::ClothState,
            Value::Basis(_) => PortType::Basis,
            Value::Weights(_) => PortType::Weights,
            Value::FrameList(_) => PortType::FrameList,
            Value::ParamSeries(_) => PortType::ParamSeries,
            Value::ArModel(_) => PortType::ArModel,
            Value::FlameModel(_) => PortType::FlameModel,
            Value::Mesh(_) => PortType::Mesh,
            Value::SpreadState(_) => PortType::SpreadState,
            Value::Clip(c) => PortType::clip_of(c.element().clone()),
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
            Value::WindField(w) => format!("{w:?}").hash(h),
            Value::Particles(p) => {
                (p.particles.len(), p.sides, p.time.to_bits()).hash(h);
                for q in &p.particles {
                    let floats = [q.position.as_slice(), &q.velocity, &q.size, &q.center, &q.edge, &[q.weight]];
                    floats.iter().for_each(|f| hash_f32s(h, f));
                    q.group.hash(h);
                }
            }
            Value::ClothState(c) => {
                (c.width, c.height, c.roots.len(), &c.seeds, c.positions.len(), c.time.to_bits()).hash(h);
                c.roots.iter().chain(&c.positions).for_each(|p| hash_f32s(h, p));
            }
            Value::Basis(b) => {
                (b.width, b.height, b.eigenvalues.len(), &b.sources).hash(h);
                b.eigenvalues.iter().for_each(|v| v.to_bits().hash(h));
                hash_f32s(h, &b.mean);
                hash_f32s(h, &b.eigenvectors);
            }
            Value::Weights(w) => {
                (w.frames, w.components).hash(h);
                hash_f32s(h, &w.data);
            }
            Value::FrameList(l) => {
                l.items.len().hash(h);
                for item in &l.items {
                    match item {
                        FrameItem::Frame(f) => (0u8, f).hash(h),
                        FrameItem::Weights(w) => {
                            (1u8, w.len()).hash(h);
                            hash_f32s(h, w);
                        }
                    }
                }
            }
            Value::ParamSeries(v) => v.hash_into(h),
            Value::ArModel(v) => v.hash_into(h),
            Value::FlameModel(v) => v.hash_into(h),
            Value::Mesh(v) => v.hash_into(h),
            Value::SpreadState(v) => v.hash_into(h),
            Value::Clip(c) => c.fingerprint().hash(h),
        }
    }

    /// Approximate memory held by the value.
    pub fn byte_size(&self) -> usize {
        match self {
            Value::Image(img) => img.byte_size(),
            Value::Mask(m) => m.data.len(),
            Value::Contours(c) => c.contours.iter().map(|k| k.points.len() * 8 + 48).sum(),
            Value::Particles(p) => p.particles.len() * std::mem::size_of::<Particle>(),
            Value::ClothState(c) => (c.roots.len() + c.positions.len()) * 12 + c.seeds.len() * 4,
            Value::Basis(b) => (b.mean.len() + b.eigenvectors.len()) * 4 + b.eigenvalues.len() * 8 + b.sources.len() * 8,
            Value::Weights(w) => w.data.len() * 4,
            Value::FrameList(l) => {
                l.items.iter().map(|i| if let FrameItem::Weights(w) = i { w.len() * 4 + 32 } else { 32 }).sum()
            }
            Value::ParamSeries(v) => v.byte_size(),
            Value::ArModel(v) => v.byte_size(),
            Value::FlameModel(v) => v.byte_size(),
            Value::Mesh(v) => v.byte_size(),
            Value::SpreadState(v) => v.byte_size(),
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
            Value::Image(img) => format!("Image {}x{} {:?}", img.width, img.height, img.channels),
            Value::Mask(m) => format!("Mask {}x{}", m.width, m.height),
            Value::Contours(c) => format!("Contours {} in {}x{}", c.contours.len(), c.width, c.height),
            Value::WindField(w) => {
                format!("WindField k_g={} C={} k_p={} k_s={} w_L={:?}", w.k_g, w.noise_c, w.k_p, w.k_s, w.large)
            }
            Value::Particles(p) => format!("Particles {} ({}-gons)", p.particles.len(), p.sides),
            Value::ClothState(c) => format!("ClothState {} flames of {}x{} masses", c.flames(), c.width, c.height),
            Value::Basis(b) => {
                format!("Basis {} components of {}x{} from {} frames", b.components(), b.width, b.height, b.sources.len())
            }
            Value::Weights(w) => format!("Weights {} frames x {} components", w.frames, w.components),
            Value::FrameList(l) => format!("FrameList {} frames", l.items.len()),
            Value::ParamSeries(v) => v.summary(),
            Value::ArModel(v) => v.summary(),
            Value::FlameModel(v) => v.summary(),
            Value::Mesh(v) => v.summary(),
            Value::SpreadState(v) => v.summary(),
            Value::Clip(c) => format!("Clip<{}> {} frames @ {} fps", c.element(), c.len(), c.fps()),
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
