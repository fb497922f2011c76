//! Helpers for the unit tests of the node modules: cooking a node on values as the graph would,
//! reading its inputs, and small images.

use std::sync::Arc;

use pyrograph_core::{Channels, Image, Value};

pub(crate) use pyrograph_core::testing::{cook_values as cook_node, read};

/// An image as an input value.
pub(crate) fn image_value(img: Image) -> Value {
    Value::Image(Arc::new(img))
}

/// A `w × h` RGBA image of `data`.
pub(crate) fn rgba(w: u32, h: u32, data: &[f32]) -> Image {
    Image::from_vec(w, h, Channels::Rgba, data.to_vec()).unwrap()
}

/// A `w × h` gray image of `data`.
pub(crate) fn gray(w: u32, h: u32, data: &[f32]) -> Image {
    Image::from_vec(w, h, Channels::Gray, data.to_vec()).unwrap()
}

/// Asserts that `a` and `b` agree to 1e-5 everywhere.
pub(crate) fn assert_close(a: &[f32], b: &[f32]) {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-5, "{a:?} vs {b:?}");
    }
}
