//! Helpers for the unit tests of the node modules: cooking a node on values as the graph would,
//! reading its inputs, and small images.

use std::sync::Arc;

use pyrograph_core::declare::Declared;
use pyrograph_core::{Channels, Cook, CookCtx, Image, Inputs, NodeError, Value};

/// Cooks node `T` on `values` (one per input, in port order) as the graph would.
pub(crate) fn cook_node<T: Cook>(values: &[Value]) -> Result<Vec<Value>, NodeError> {
    let node = T::node();
    node.cook(&Inputs::new(node.desc(), values), &CookCtx::new())
}

/// Reads node `T`'s inputs from `values`, as a cook does first.
pub(crate) fn read<T: Declared>(values: &[Value]) -> Result<T, NodeError> {
    T::read(&Inputs::new(&T::desc(), values))
}

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
