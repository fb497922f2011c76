//! Textures: bilinear, clamp-to-edge sampling of RGBA images.

use glam::Vec4;
use pyrograph_core::{Channels, Image};

use super::lanes::{Footprints, SMALL_LANES};

/// An RGBA texture's samples, checked once per triangle instead of once per pixel.
pub(super) struct Texels<'a> {
    data: &'a [f32],
    pub(super) width: usize,
    pub(super) height: usize,
}

impl<'a> Texels<'a> {
    /// `None` for an empty or non-RGBA image (which samples as transparent black).
    #[inline(always)]
    pub(super) fn new(img: &'a Image) -> Option<Texels<'a>> {
        let (width, height) = (img.width() as usize, img.height() as usize);
        (width > 0 && height > 0 && img.channels() == Channels::Rgba).then(|| Texels { data: img.data(), width, height })
    }

    /// Bilinear, clamp-to-edge sample at `(u, v)` (0,0 = top-left corner), four channels at once.
    #[inline(always)]
    pub(super) fn sample(&self, u: f32, v: f32) -> Vec4 {
        let (fx, fy) = self.texel_coords(u, v);
        self.sample_at(fx, fy)
    }

    /// The texel-space position of `(u, v)`, clamped to the texel centres at the edges.
    #[inline(always)]
    fn texel_coords(&self, u: f32, v: f32) -> (f32, f32) {
        let (w, h) = (self.width, self.height);
        ((u * w as f32 - 0.5).clamp(0.0, (w - 1) as f32), (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32))
    }

    /// Bilinear sample at a position from [`Texels::texel_coords`].
    #[inline(always)]
    fn sample_at(&self, fx: f32, fy: f32) -> Vec4 {
        // Both ≥ 0 after the clamp (a NaN clamps to NaN and casts to 0): truncation is floor.
        let (x0, y0) = (fx as usize, fy as usize);
        self.bilinear(x0, y0, fx - x0 as f32, fy - y0 as f32)
    }

    /// [`Texels::sample_at`] of eight positions from [`Texels::texel_coords`] at once, as far
    /// as it goes without reading texels: in lanes, so the float-to-integer conversions (each a
    /// dozen scalar instructions, with their saturation checks) vectorize. The same values as
    /// `sample_at`'s: `max(fx, 0)` is `fx` for the clamped coordinates and 0 for a NaN, which
    /// `as usize` makes 0 too.
    #[inline(always)]
    pub(super) fn footprints(&self, u: &[f32; SMALL_LANES], v: &[f32; SMALL_LANES]) -> Footprints {
        let mut f = Footprints { x: [0; SMALL_LANES], y: [0; SMALL_LANES], tx: [0.0; SMALL_LANES], ty: [0.0; SMALL_LANES] };
        for i in 0..SMALL_LANES {
            let (fx, fy) = self.texel_coords(u[i], v[i]);
            (f.x[i], f.y[i]) = (lane_floor(fx), lane_floor(fy));
            (f.tx[i], f.ty[i]) = (fx - f.x[i] as f32, fy - f.y[i] as f32);
        }
        f
    }

    /// The bilinear blend of texel `(x0, y0)` (inside the texture) and its neighbours right
    /// and below (clamped to the edge), with weights `tx` and `ty`.
    #[inline(always)]
    pub(super) fn bilinear(&self, x0: usize, y0: usize, tx: f32, ty: f32) -> Vec4 {
        let (w, h) = (self.width, self.height);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let at = |x: usize, y: usize| {
            let i = (y * w + x) * 4;
            Vec4::from_slice(&self.data[i..i + 4])
        };
        let top = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
        let bottom = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

/// Bilinear, clamp-to-edge sample of an RGBA image at `(u, v)` (0,0 = top-left corner);
/// transparent black for an empty or non-RGBA image.
pub fn sample_bilinear(img: &Image, u: f32, v: f32) -> [f32; 4] {
    Texels::new(img).map_or([0.0; 4], |t| t.sample(u, v).to_array())
}

/// `fx as usize` of [`Texels::sample_at`] for a clamped texel coordinate (`0 ≤ fx ≤ width − 1`,
/// or NaN, which gives 0), in a form that vectorizes: a plain truncating conversion, its
/// operand kept within `[0, 2^30]` so that it is always defined.
#[inline(always)]
pub(super) fn lane_floor(fx: f32) -> i32 {
    const LIMIT: f32 = (1u32 << 30) as f32;
    let f = if fx > 0.0 { fx } else { 0.0 };
    let f = if f < LIMIT { f } else { LIMIT };
    // SAFETY: `f` is finite and within `[0, 2^30]`, so it truncates to an `i32` exactly.
    unsafe { f.to_int_unchecked::<i32>() }
}
