//! Image sizes shared by the nodes that make or check them: the largest they create and the
//! `WxH` text their errors show.

use pyrograph_core::Image;

/// Largest width or height the imaging nodes create (`imaging.resize`, `imaging.constant_color`).
pub const MAX_SIZE: i64 = 16384;

/// The size of `img` as errors show it: `640x480`.
pub(crate) fn image_size_text(img: &Image) -> String {
    format!("{}x{}", img.width(), img.height())
}
