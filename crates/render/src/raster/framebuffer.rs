//! The rendered frame and its conversion from premultiplied to straight alpha.

use std::mem::MaybeUninit;

use glam::{BVec4A, Vec4};
use pyrograph_core::{Channels, Image};
use rayon::prelude::*;

use super::BAND_ROWS;
use super::isa::Avx2;

/// A rendered frame: premultiplied RGBA and depth.
#[derive(Clone, Debug, PartialEq)]
pub struct Framebuffer {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) color: Vec<[f32; 4]>,
    pub(super) depth: Vec<f32>,
}

impl Framebuffer {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Premultiplied RGBA of pixel `(x, y)`.
    pub fn premultiplied(&self, x: u32, y: u32) -> [f32; 4] {
        self.color[y as usize * self.width as usize + x as usize]
    }

    /// Depth of pixel `(x, y)` (1 where no opaque primitive was drawn).
    pub fn depth(&self, x: u32, y: u32) -> f32 {
        self.depth[y as usize * self.width as usize + x as usize]
    }

    /// The frame as a straight-alpha RGBA image. Additive light can make premultiplied colour
    /// exceed alpha; such pixels get `alpha = max(r, g, b)` so that compositing the image over
    /// black gives back exactly the rendered colour.
    pub fn to_image(&self) -> Image {
        let mut image = Image::new(self.width, self.height, Channels::Rgba);
        let w = self.width as usize;
        image
            .data_mut()
            .par_chunks_mut(w * 4 * BAND_ROWS)
            .zip(self.color.par_chunks(w * BAND_ROWS))
            .for_each(|(out, color)| write_straight(color, out));
        image
    }
}

/// Premultiplied pixels to straight-alpha RGBA samples (see [`Framebuffer::to_image`]).
pub(super) fn write_straight(color: &[[f32; 4]], out: &mut [f32]) {
    let out = &mut out[..4 * color.len()];
    // SAFETY: `out` holds the four samples of every pixel of `color`.
    let done = unsafe { straight_vectorized(color, out.as_mut_ptr()) };
    for (p, o) in color[done..].iter().zip(out[4 * done..].chunks_exact_mut(4)) {
        o.copy_from_slice(&straight(*p));
    }
}

/// [`write_straight`] into samples not yet initialised; every sample of `out` (4 per pixel of
/// `color`) is written.
pub(super) fn write_straight_uninit(color: &[[f32; 4]], out: &mut [MaybeUninit<f32>]) {
    let out = &mut out[..4 * color.len()];
    // SAFETY: `out` holds the four samples of every pixel of `color` (`MaybeUninit<f32>` has
    // the layout of `f32`), and only initialised values are written through the pointer.
    let done = unsafe { straight_vectorized(color, out.as_mut_ptr().cast()) };
    for (p, o) in color[done..].iter().zip(out[4 * done..].chunks_exact_mut(4)) {
        for (slot, v) in o.iter_mut().zip(straight(*p)) {
            slot.write(v);
        }
    }
}

/// Converts the first pixels of `color` with the AVX2 kernel where the CPU has AVX2; returns
/// how many (the rest are left to [`straight`]).
///
/// # Safety
/// `out` must be valid for writes of `4 · color.len()` samples.
unsafe fn straight_vectorized(color: &[[f32; 4]], out: *mut f32) -> usize {
    match Avx2::detect() {
        // SAFETY: `out`'s extent is the caller's.
        Some(avx2) => unsafe { avx2.straight_pairs(color, out) },
        None => 0,
    }
}

/// One premultiplied pixel as straight alpha.
#[inline(always)]
pub(super) fn straight(p: [f32; 4]) -> [f32; 4] {
    let p = Vec4::from_array(p);
    let a = p.max_element().min(1.0);
    let rgb = BVec4A::new(true, true, true, false);
    if a == 1.0 {
        // The usual pixel over an opaque background (and every pixel of saturated additive
        // light): dividing by 1 changes nothing, so skip the division.
        Vec4::select(rgb, p.min(Vec4::ONE), Vec4::ONE).to_array()
    } else if a > 0.0 {
        Vec4::select(rgb, (p / a).min(Vec4::ONE), Vec4::splat(a)).to_array()
    } else {
        [0.0; 4]
    }
}
