//! Draw lists and the band-parallel rasterizer.
//!
//! Geometry is transformed, clipped (near plane plus a guard band) and snapped to 1/256-pixel
//! fixed point when it is added to a [`DrawList`], and binned into horizontal bands of
//! [`BAND_ROWS`] rows. [`render`] then rasterizes the bands in parallel: each band walks its
//! primitives in submission order with integer edge functions and the top-left fill rule, so
//! triangles that share an edge (the fan of a fuzzy particle) never touch a pixel twice.
//! Opaque primitives are drawn first (depth test and write), blended ones after (depth test only).
//!
//! The files split it by topic, in layers, each importing only from those before it: `view`
//! (camera, viewport, clipping), `isa` (the instruction set a band is drawn with, and the `Avx2`
//! proof that the CPU has AVX2), `lanes` (the lane counts and per-lane data the portable code
//! and the kernels share), `texture` (bilinear sampling), `avx2` (the AVX2 kernels, reachable
//! only through that proof), `fan` (particles on the scanline path), `tiles` (triangles, small
//! ones in vector tiles), `framebuffer` (the frame and its straight alpha) and `draw` (draw
//! lists). This file holds the types and helpers they all share (snapped vertices, bands, edge
//! functions, blending) and the band-parallel driver on top.

use glam::{BVec4A, Vec3, Vec4, Vec4Swizzles};
use pyrograph_core::{Channels, Image};
use rayon::prelude::*;

mod avx2;
mod draw;
mod fan;
mod framebuffer;
mod isa;
mod lanes;
mod texture;
mod tiles;
mod view;

#[cfg(test)]
mod tests;

pub use draw::{DrawList, TextureId};
pub use framebuffer::Framebuffer;
use framebuffer::write_straight_uninit;
use isa::{Avx2, Isa, Portable};
pub use texture::sample_bilinear;
pub use view::View;

/// Rows per band: the unit of parallel work. 32 rather than 16: a swept flame's strip or
/// triangle that straddles two bands is set up in both, and at 1280×720 the burning cube's
/// frame took 6 % less time, the 1,000-flame frame 4 % less and cloth the same (BENCHMARKS.md,
/// issue 45); 23 bands still keep two threads evenly busy.
pub const BAND_ROWS: usize = 32;
/// Sub-pixel precision: 1/256 pixel.
const SUB: i64 = 256;
/// Largest viewport side.
pub const MAX_SIZE: u32 = 16384;

/// How a primitive's colour combines with the framebuffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Blend {
    /// Replaces colour (alpha becomes 1) and writes depth: solid meshes.
    Opaque,
    /// Porter–Duff "over" with the source alpha.
    Over,
    /// Adds `rgb·a` and `a` to the framebuffer, each component saturating at 1 (Perry 1994 §3.2.2).
    Additive,
}

/// A world-space vertex with straight RGBA and texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// World position.
    pub position: Vec3,
    /// Straight RGBA.
    pub color: [f32; 4],
    /// Texture coordinates (0,0 top-left of the texture), ignored without a texture.
    pub uv: [f32; 2],
}

impl Vertex {
    /// A vertex without texture coordinates.
    pub fn new(position: Vec3, color: [f32; 4]) -> Self {
        Vertex { position, color, uv: [0.0, 0.0] }
    }
}

/// A screen-space vertex: pixel coordinates (x right, y down, pixel centres at +0.5), depth in 0..1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    /// Pixel x.
    pub x: f32,
    /// Pixel y.
    pub y: f32,
    /// Depth, 0 (near) to 1 (far).
    pub depth: f32,
    /// Straight RGBA.
    pub color: [f32; 4],
    /// Texture coordinates.
    pub uv: [f32; 2],
}

/// Rounds half away from zero, without a libm call; saturates like `as`.
#[inline(always)]
fn round_i64(v: f32) -> i64 {
    (v + 0.5f32.copysign(v)) as i64
}

/// `floor(a / SUB)`.
fn floor_sub(a: i64) -> i64 {
    a >> 8
}

/// `ceil(a / SUB)`.
fn ceil_sub(a: i64) -> i64 {
    -((-a) >> 8)
}

const _: () = assert!(SUB == 1 << 8, "floor_sub and ceil_sub shift by log2(SUB)");

/// A snapped screen vertex; colour and uv are pre-multiplied by `iw` (1/w) for
/// perspective-correct interpolation.
#[derive(Clone, Copy, Debug)]
struct SVert {
    x: i64,
    y: i64,
    z: f32,
    iw: f32,
    c: [f32; 4],
    uv: [f32; 2],
}

/// Rows `y0..y1` of the framebuffer.
struct Band<'a> {
    color: &'a mut [[f32; 4]],
    depth: &'a mut [f32],
    width: usize,
    y0: usize,
    y1: usize,
    /// Whether any opaque primitive touches this band (otherwise depth is 1 everywhere,
    /// blended primitives skip the depth test and `depth` is not used: `render_image` leaves it
    /// empty).
    has_opaque: bool,
}

/// `(b − a) × (p − a)` in fixed point: positive when `p` is on the inner side of a
/// positively-oriented triangle.
#[inline(always)]
fn edge_fn(a: &SVert, b: &SVert, px: i64, py: i64) -> i64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}

/// Top-left rule for an edge `a → b` of a positively oriented triangle (y down).
fn is_top_left(a: &SVert, b: &SVert) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Blends straight-alpha `src` into the premultiplied framebuffer pixel `dst`.
pub fn blend_pixel(dst: &mut [f32; 4], src: [f32; 4], blend: Blend) {
    blend_vec4(dst, Vec4::from_array(src), blend);
}

/// [`blend_pixel`], four channels at once.
#[inline(always)]
fn blend_vec4(dst: &mut [f32; 4], src: Vec4, blend: Blend) {
    let a = src.w.clamp(0.0, 1.0);
    let rgb = BVec4A::new(true, true, true, false);
    let d = Vec4::from_array(*dst);
    *dst = match blend {
        Blend::Opaque => Vec4::select(rgb, src, Vec4::ONE),
        // rgb: src·a + dst·(1 − a); alpha: a + dst·(1 − a).
        Blend::Over => Vec4::select(rgb, src, Vec4::ONE) * a + d * (1.0 - a),
        Blend::Additive => (d + Vec4::select(rgb, src.max(Vec4::ZERO), Vec4::ONE) * a).min(Vec4::ONE),
    }
    .to_array();
}

/// Additive blending of a straight-alpha source already known to have alpha in [0, 1] and colour
/// ≥ 0 (see `FanSetup::in_range`): [`blend_pixel`]'s `Additive` without its clamps, four lanes
/// at once.
#[inline(always)]
fn add_in_range(dst: &mut [f32; 4], src: Vec4) {
    let weight = Vec4::select(BVec4A::new(true, true, true, false), src.wwww(), Vec4::ONE);
    *dst = (Vec4::from_array(*dst) + src * weight).min(Vec4::ONE).to_array();
}

/// Rasterizes every list's primitives that touch band `bi` into `band`: opaque ones first
/// (depth test and write), then blended ones (depth test only where something opaque was drawn).
fn raster_band(lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    match Avx2::detect() {
        Some(avx2) => avx2.raster_band(lists, view, bi, band),
        None => raster_band_generic(Portable, lists, view, bi, band),
    }
}

/// [`raster_band`] with the instruction set `isa`: inlined into its caller so that the AVX2
/// instance is compiled with AVX2 enabled (see `Avx2::raster_band`).
#[inline(always)]
fn raster_band_generic<I: Isa>(isa: I, lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    band.has_opaque = band_has_opaque(lists, view, bi);
    for pass in 0..2 {
        for list in lists.iter().filter(|l| usable(l, view)) {
            for &p in &list.bins[pass][bi] {
                list.raster_prim(isa, p, band);
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// Rasterizes band `bi` as `raster_band` does, compiled for AVX2 (see [`Isa`]).
    #[inline(always)]
    fn raster_band(self, lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
        // SAFETY: `self` proves that the CPU supports AVX2 (see `Avx2::detect`).
        unsafe { raster_band_avx2(self, lists, view, bi, band) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl Avx2 {
    /// Unreachable: there is no `Avx2` here.
    #[inline(always)]
    fn raster_band(self, _lists: &[DrawList], _view: &View, _bi: usize, _band: &mut Band<'_>) {
        match self {}
    }
}

/// `raster_band_generic` compiled for AVX2: the kernels inline, and the portable code around
/// them may use AVX2 too (the particle envelope runs 8 lanes wide). Results are bit-identical
/// to the baseline build: no fused multiply-adds, no library calls.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn raster_band_avx2(avx2: Avx2, lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    raster_band_generic(avx2, lists, view, bi, band)
}

/// Whether `list` was built for a view of `view`'s size (others are skipped).
fn usable(list: &DrawList, view: &View) -> bool {
    list.view.width == view.width && list.view.height == view.height
}

/// Whether any opaque primitive touches band `bi`: only then is its depth buffer read or written.
fn band_has_opaque(lists: &[DrawList], view: &View, bi: usize) -> bool {
    lists.iter().any(|l| usable(l, view) && !l.bins[0][bi].is_empty())
}

/// A straight-alpha background colour as a premultiplied framebuffer pixel.
fn premultiply(background: [f32; 4]) -> [f32; 4] {
    let a = background[3].clamp(0.0, 1.0);
    [background[0] * a, background[1] * a, background[2] * a, a]
}

/// Rasterizes `lists` (in order) over a `background` (straight RGBA), bands in parallel,
/// keeping the premultiplied colour and the depth of every pixel.
pub fn render(view: &View, lists: &[DrawList], background: [f32; 4]) -> Framebuffer {
    let (w, h) = (view.width as usize, view.height as usize);
    let mut color = vec![premultiply(background); w * h];
    let mut depth = vec![1.0f32; w * h];
    color.par_chunks_mut(w * BAND_ROWS).zip(depth.par_chunks_mut(w * BAND_ROWS)).enumerate().for_each(|(bi, (c, d))| {
        let y0 = bi * BAND_ROWS;
        let mut band = Band { y1: y0 + c.len() / w, color: c, depth: d, width: w, y0, has_opaque: false };
        raster_band(lists, view, bi, &mut band);
    });
    Framebuffer { width: view.width, height: view.height, color, depth }
}

/// [`render`] straight to an RGBA image (as [`Framebuffer::to_image`]), without keeping a
/// full-frame premultiplied buffer: each band is rasterized into a small per-thread buffer that
/// stays in cache and is converted as soon as it is done. This is the fast path of the
/// render nodes.
pub fn render_image(view: &View, lists: &[DrawList], background: [f32; 4]) -> Image {
    let w = view.width as usize;
    let len = w * view.height as usize * 4;
    let bg = premultiply(background);
    // Every sample is written below, so the frame is not zeroed first (zeroing 15 MB at
    // 1280×720 took 1.9 ms on one core, half the cost of an empty frame).
    let mut data: Vec<f32> = Vec::with_capacity(len);
    data.spare_capacity_mut()[..len].par_chunks_mut(w * 4 * BAND_ROWS).enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(color, depth): &mut (Vec<[f32; 4]>, Vec<f32>), (bi, out)| {
            let rows = out.len() / (4 * w);
            color.clear();
            color.resize(rows * w, bg);
            depth.clear();
            if band_has_opaque(lists, view, bi) {
                // Otherwise nothing reads or writes depth (see `Band::has_opaque`).
                depth.resize(rows * w, 1.0);
            }
            let y0 = bi * BAND_ROWS;
            let mut band = Band { color, depth, width: w, y0, y1: y0 + rows, has_opaque: false };
            raster_band(lists, view, bi, &mut band);
            write_straight_uninit(color, out);
        },
    );
    // SAFETY: the chunks cover `[0, len)` of the spare capacity exactly (`len` is a multiple of
    // `4·w`, each chunk `4·w·rows` samples), and `write_straight_uninit` writes all four samples
    // of each of the chunk's `w·rows` pixels; a panic in a band propagates before this line.
    unsafe { data.set_len(len) };
    Image::from_vec(view.width, view.height, Channels::Rgba, data)
        .unwrap_or_else(|| Image::new(view.width, view.height, Channels::Rgba))
}
