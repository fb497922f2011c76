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
//!
//! One file per topic (original colouring, synthetic colouring with HLS and ramps, alpha), their
//! items re-exported here.

use pyrograph_core::{Channels, Image, NodeError, port};

mod alpha;
mod original;
mod synthetic;

pub use alpha::*;
pub use original::*;
pub use synthetic::*;

fn size_text(img: &Image) -> String {
    format!("{}x{}", img.width(), img.height())
}

/// Why colouring failed, by the input it concerns: each colouring node names the matching port.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ColoringError {
    /// The threshold is outside 0–255.
    #[error("{0}")]
    Threshold(String),
    /// The original frame's size is not the source's.
    #[error("the original frame {0}")]
    Original(String),
    /// The destination layer's size is not the source's.
    #[error("the destination layer {0}")]
    Destination(String),
    /// The smoke layer's size is not the source's.
    #[error("the smoke layer {0}")]
    SmokeLayer(String),
    /// The custom mask's size is not the source's.
    #[error("the custom mask {0}")]
    CustomMask(String),
    /// The blend texture's size is not the source's.
    #[error("the texture {0}")]
    Texture(String),
    /// The matte's size is not the image's.
    #[error("the matte {0}")]
    Matte(String),
    /// Anything no input is to blame for.
    #[error("{0}")]
    Message(String),
}

/// A colouring error on the port of the colouring nodes it concerns.
impl From<ColoringError> for NodeError {
    fn from(e: ColoringError) -> NodeError {
        // A size error names its input in front of what is wrong with it.
        let sized = |port: &str, m: String| NodeError::port(port, format!("'{port}' {m}"));
        match e {
            ColoringError::Threshold(m) => NodeError::port(port!(ColoringThreshold, threshold), m),
            ColoringError::Original(m) => sized(port!(ColoringFrames, original), m),
            ColoringError::Destination(m) => sized(port!(ColoringLayerInputs, destination), m),
            ColoringError::SmokeLayer(m) => sized(port!(ColoringLayerInputs, smoke), m),
            ColoringError::CustomMask(m) => sized(port!(OriginalColoringMasked, custom_mask), m),
            ColoringError::Texture(m) => sized(port!(SyntheticColoringTexture, texture), m),
            ColoringError::Matte(m) => sized(port!(SetAlpha, matte), m),
            ColoringError::Message(m) => NodeError::msg(m),
        }
    }
}

/// Checks that `other` has the size of `source`; the error says so, for the node to put the
/// input's name in front (`'matte' is 4x4 but the source is 8x8; ...`).
pub fn check_size(source: &Image, other: &Image) -> Result<(), String> {
    if source.size() != other.size() {
        return Err(format!("is {} but the source is {}; both must have the same size", size_text(other), size_text(source)));
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

#[cfg(test)]
mod tests;
