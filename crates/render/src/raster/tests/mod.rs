//! The rasterizer's unit tests, one file per part: the AVX2 kernel against the portable one,
//! draw lists, triangle fans, the framebuffer's conversions and strips; `support` holds what
//! they share.

mod avx2;
mod draw;
mod fan;
mod framebuffer;
mod strip;
mod support;
