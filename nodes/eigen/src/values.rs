//! The Eigenfires value types (thesis §4–5): bases, weights and motion lists.

use std::hash::Hash;

use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

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

const EIGEN_COLOR: [u8; 3] = [200, 180, 140];

impl ValueType for Basis {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "Basis",
        doc: "An Eigenfires basis: mean image, eigenvectors and eigenvalues (thesis §4.2).",
        color: EIGEN_COLOR,
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.width, self.height, self.eigenvalues.len(), &self.sources).hash(h);
        self.eigenvalues.iter().for_each(|v| v.to_bits().hash(h));
        hash_f32s(h, &self.mean);
        hash_f32s(h, &self.eigenvectors);
    }

    fn byte_size(&self) -> usize {
        (self.mean.len() + self.eigenvectors.len()) * 4 + self.eigenvalues.len() * 8 + self.sources.len() * 8
    }

    fn summary(&self) -> String {
        format!("Basis {} components of {}x{} from {} frames", self.components(), self.width, self.height, self.sources.len())
    }
}

impl ValueType for Weights {
    const INFO: &'static TypeInfo =
        &TypeInfo { name: "Weights", doc: "Eigenfires weights, frames × components (thesis §4.3 eq. 18).", color: EIGEN_COLOR };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.frames, self.components).hash(h);
        hash_f32s(h, &self.data);
    }

    fn byte_size(&self) -> usize {
        self.data.len() * 4
    }

    fn summary(&self) -> String {
        format!("Weights {} frames x {} components", self.frames, self.components)
    }
}

impl ValueType for FrameList {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "FrameList",
        doc: "A sequence of database frames and synthesized weight vectors (thesis §5.1 motion lists).",
        color: EIGEN_COLOR,
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        self.items.len().hash(h);
        for item in &self.items {
            match item {
                FrameItem::Frame(f) => (0u8, f).hash(h),
                FrameItem::Weights(w) => {
                    (1u8, w.len()).hash(h);
                    hash_f32s(h, w);
                }
            }
        }
    }

    fn byte_size(&self) -> usize {
        self.items.iter().map(|i| if let FrameItem::Weights(w) = i { w.len() * 4 + 32 } else { 32 }).sum()
    }

    fn summary(&self) -> String {
        format!("FrameList {} frames", self.items.len())
    }
}
