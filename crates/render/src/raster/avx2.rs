//! The AVX2 kernels, each reachable only through a method of the [`Avx2`] token.
//!
//! Each kernel is a `#[target_feature(enable = "avx2")]` function: running one on a CPU
//! without AVX2 is undefined behaviour. They are called only from the methods of [`Avx2`],
//! which only [`Avx2::detect`] creates, after checking the CPU (see the `isa` module). The
//! kernels compute with the data of the `lanes` and `texture` modules and know nothing of the
//! portable code that calls them. No kernel uses FMA: each is bit-identical to the portable code
//! it replaces.

use super::isa::Avx2;
use super::lanes::{FAN_LANES, SmallTri, TileShading};
use super::texture::Texels;
#[cfg(target_arch = "x86_64")]
use {
    super::add_in_range,
    super::lanes::{Footprints, SMALL_LANES, TileLanes},
    glam::Vec4,
};

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// `envelope` (see the `fan` module) with four independent chains of minima.
    #[inline(always)]
    pub(super) fn envelope(self, env: &[[f32; 2]], base: f32) -> [f32; FAN_LANES] {
        // SAFETY: `self` proves that the CPU supports AVX2 (see `Avx2::detect`).
        unsafe { envelope_avx2(env, base) }
    }

    /// A particle's row span blended with `add_in_range` and no depth test, two pixels per
    /// register (see [`add_span_avx2`]).
    #[inline(always)]
    pub(super) fn add_span(self, color: &mut [[f32; 4]], xd0: f32, env: &[[f32; 2]], edge: [f32; 4], delta: [f32; 4]) {
        // SAFETY: `self` proves that the CPU supports AVX2 (see `Avx2::detect`).
        unsafe { add_span_avx2(color, xd0, env, edge, delta) }
    }

    /// `tile_lanes` (see the `tiles` module) in AVX2 intrinsics.
    #[inline(always)]
    pub(super) fn tile_lanes<const W: usize>(
        self,
        t: &SmallTri,
        w: [i32; 3],
        rows_left: usize,
        tex: Option<&Texels<'_>>,
    ) -> Option<TileShading> {
        // SAFETY: `self` proves that the CPU supports AVX2 (see `Avx2::detect`).
        unsafe { tile_lanes_avx2::<W>(t, w, rows_left, tex) }
    }

    /// Converts the first pixels of `color` to straight alpha, two per register (see
    /// [`straight_pairs_avx2`]), and returns how many.
    ///
    /// # Safety
    /// `out` must be valid for writes of `4 · color.len()` samples.
    #[inline(always)]
    pub(super) unsafe fn straight_pairs(self, color: &[[f32; 4]], out: *mut f32) -> usize {
        // SAFETY: `self` proves that the CPU supports AVX2 (see `Avx2::detect`); `out`'s extent
        // is the caller's.
        unsafe { straight_pairs_avx2(color, out) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl Avx2 {
    /// Unreachable: there is no `Avx2` here.
    #[inline(always)]
    pub(super) fn envelope(self, _env: &[[f32; 2]], _base: f32) -> [f32; FAN_LANES] {
        match self {}
    }

    /// Unreachable: there is no `Avx2` here.
    #[inline(always)]
    pub(super) fn add_span(self, _color: &mut [[f32; 4]], _xd0: f32, _env: &[[f32; 2]], _edge: [f32; 4], _delta: [f32; 4]) {
        match self {}
    }

    /// Unreachable: there is no `Avx2` here.
    #[inline(always)]
    pub(super) fn tile_lanes<const W: usize>(
        self,
        _t: &SmallTri,
        _w: [i32; 3],
        _rows_left: usize,
        _tex: Option<&Texels<'_>>,
    ) -> Option<TileShading> {
        match self {}
    }

    /// Unreachable: there is no `Avx2` here.
    #[inline(always)]
    pub(super) unsafe fn straight_pairs(self, _color: &[[f32; 4]], _out: *mut f32) -> usize {
        match self {}
    }
}

/// `envelope` (see the `fan` module) in AVX2 with four running minima merged at the end. Written
/// with intrinsics because a single chain of `vminps` waits out its latency (4 cycles on recent
/// Intel cores) at every edge, and the compiler, given the independent chains in plain Rust, split
/// them across mismatched registers and branched on the merge (measured 13 % slower than one
/// chain); this form was 5 % faster at 1,000 flames. Bit-identical to the portable loop: the same
/// separate multiply and add per lane (no FMA), and the minimum of non-NaN values does not depend
/// on the order (`vminps(v, m)` keeps `m` when `v` is NaN, as `lane_min` does).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn envelope_avx2(env: &[[f32; 2]], base: f32) -> [f32; FAN_LANES] {
    lanes(envelope_m256(env, base))
}

/// The eight lanes of `v`, in order.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lanes(v: std::arch::x86_64::__m256) -> [f32; FAN_LANES] {
    // SAFETY: `__m256` and `[f32; 8]` are both 32 bytes of eight `f32` lanes in order.
    unsafe { std::mem::transmute::<std::arch::x86_64::__m256, [f32; FAN_LANES]>(v) }
}

/// [`envelope_avx2`] left in its register.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn envelope_m256(env: &[[f32; 2]], base: f32) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::{_mm256_add_ps, _mm256_min_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setr_ps};
    const _: () = assert!(FAN_LANES == 8, "one __m256 per block");
    let xd = _mm256_add_ps(_mm256_set1_ps(base), _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0));
    let line = |&[offset, slope]: &[f32; 2]| _mm256_add_ps(_mm256_set1_ps(offset), _mm256_mul_ps(_mm256_set1_ps(slope), xd));
    let mut m = [_mm256_set1_ps(f32::INFINITY); 4];
    let mut quads = env.chunks_exact(4);
    for quad in &mut quads {
        for (m, e) in m.iter_mut().zip(quad) {
            *m = _mm256_min_ps(line(e), *m);
        }
    }
    for (m, e) in m.iter_mut().zip(quads.remainder()) {
        *m = _mm256_min_ps(line(e), *m);
    }
    _mm256_min_ps(_mm256_min_ps(m[0], m[1]), _mm256_min_ps(m[2], m[3]))
}

/// A span of `fill_fan_span` (see the `fan` module) blended with [`add_in_range`] (`blend` there)
/// and no depth test, two pixels per AVX register instead of one per SSE register: the particles'
/// usual case, where the per-pixel blend had become the larger half of a fan row's time. Written
/// for the whole span (the constants set up once, the envelope kept in its register, the pixel
/// pairs addressed directly) because the per-block form's slicing and set-up cost as much as its
/// blending. The same operations in the same order per channel as the portable loop, so
/// bit-identical: the clamp as `min(1, max(0, l))` (what `f32::clamp` computes for a non-NaN `l`;
/// the envelope is never NaN), `edge + delta·l`, then `min(dst + src·[a, a, a, 1], 1)`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add_span_avx2(color: &mut [[f32; 4]], xd0: f32, env: &[[f32; 2]], edge: [f32; 4], delta: [f32; 4]) {
    use std::arch::x86_64::{
        _mm256_add_ps, _mm256_blend_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps, _mm256_mul_ps, _mm256_permutevar8x32_ps,
        _mm256_set1_ps, _mm256_setr_epi32, _mm256_setr_ps, _mm256_setzero_ps, _mm256_shuffle_ps, _mm256_storeu_ps,
    };
    let twice = |[x, y, z, w]: [f32; 4]| _mm256_setr_ps(x, y, z, w, x, y, z, w);
    let (one, e, d) = (_mm256_set1_ps(1.0), twice(edge), twice(delta));
    for (block, dst) in color.chunks_mut(FAN_LANES).enumerate() {
        let l = envelope_m256(env, xd0 + (block * FAN_LANES) as f32);
        let clamped = _mm256_min_ps(one, _mm256_max_ps(_mm256_setzero_ps(), l));
        let p = dst.as_mut_ptr().cast::<f32>();
        for k in 0..dst.len() / 2 {
            let k = 2 * k as i32;
            let lk = _mm256_permutevar8x32_ps(clamped, _mm256_setr_epi32(k, k, k, k, k + 1, k + 1, k + 1, k + 1));
            let src = _mm256_add_ps(e, _mm256_mul_ps(d, lk));
            let weight = _mm256_blend_ps::<0b1000_1000>(_mm256_shuffle_ps::<0xff>(src, src), one);
            // SAFETY: pixels `k` and `k + 1` are in `dst` (`k + 1 < dst.len()`), so `p + 4k` is
            // the start of their eight contiguous `f32`s; the unaligned load and store accept
            // any address.
            unsafe {
                let px = p.add(4 * k as usize);
                let sum = _mm256_add_ps(_mm256_loadu_ps(px), _mm256_mul_ps(src, weight));
                _mm256_storeu_ps(px, _mm256_min_ps(sum, one));
            }
        }
        if let Some(last) = dst.len().checked_sub(1).filter(|n| n % 2 == 0) {
            add_in_range(&mut dst[last], Vec4::from_array(edge) + Vec4::from_array(delta) * lanes(l)[last].clamp(0.0, 1.0));
        }
    }
}

/// `tile_lanes` (see the `tiles` module) in AVX2 intrinsics, one register per quantity: the
/// compiler left the portable loops partly scalar (the coverage mask and the texel conversions lane
/// by lane), and a dense cloth's triangles spend most of their time here. Bit-identical to it: the
/// same exact integer edge functions, the same separate multiplies and adds in the same order (no
/// FMA), an exact division, and `max`/`min` operand orders that give `f32::clamp`'s result for
/// every input, a NaN included (see `lane_floor` and [`Texels::texel_coords`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn tile_lanes_avx2<const W: usize>(t: &SmallTri, w: [i32; 3], rows_left: usize, tex: Option<&Texels<'_>>) -> Option<TileShading> {
    use std::arch::x86_64::*;
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    // SAFETY: `[i32; 8]` is 32 bytes, what the unaligned load reads.
    let (col, row) = unsafe { (_mm256_loadu_si256(col.as_ptr().cast()), _mm256_loadu_si256(row.as_ptr().cast())) };
    let edge = |e: usize| {
        let steps = _mm256_add_epi32(
            _mm256_mullo_epi32(_mm256_set1_epi32(t.dx[e]), col),
            _mm256_mullo_epi32(_mm256_set1_epi32(t.dy[e]), row),
        );
        _mm256_add_epi32(_mm256_set1_epi32(w[e]), steps)
    };
    let (w0, w1, w2) = (edge(0), edge(1), edge(2));
    let signs = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_or_si256(_mm256_or_si256(w0, w1), w2))) as u32;
    let mask = !signs & 0xff & TileLanes::<W>::inside(t.span, rows_left);
    if mask == 0 {
        return None;
    }
    let inv_area = _mm256_set1_ps(t.inv_area);
    let l1 = _mm256_mul_ps(_mm256_cvtepi32_ps(w1), inv_area);
    let l2 = _mm256_mul_ps(_mm256_cvtepi32_ps(w2), inv_area);
    let l0 = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(1.0), l1), l2);
    let lerp = |k: [f32; 3]| {
        let a = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(k[0]), l0), _mm256_mul_ps(_mm256_set1_ps(k[1]), l1));
        _mm256_add_ps(a, _mm256_mul_ps(_mm256_set1_ps(k[2]), l2))
    };
    let (z, inv) = (lerp(t.z), _mm256_div_ps(_mm256_set1_ps(1.0), lerp(t.iw)));
    let foot = tex.map(|tx| {
        let coords = |uv: [f32; 3], size: usize| {
            let s = _mm256_mul_ps(_mm256_mul_ps(lerp(uv), inv), _mm256_set1_ps(size as f32));
            let f = _mm256_sub_ps(s, _mm256_set1_ps(0.5));
            // `clamp(0, size − 1)`: `max(0, f)` and `min(limit, ·)` keep their second operand,
            // so a NaN passes through as it does `f32::clamp`.
            let f = _mm256_min_ps(_mm256_set1_ps((size - 1) as f32), _mm256_max_ps(_mm256_setzero_ps(), f));
            // `lane_floor`: `max(f, 0)` turns a NaN into 0, then the limit, then truncation.
            let limited = _mm256_min_ps(_mm256_max_ps(f, _mm256_setzero_ps()), _mm256_set1_ps((1u32 << 30) as f32));
            let x = _mm256_cvttps_epi32(limited);
            (lanes_i32(x), lanes(_mm256_sub_ps(f, _mm256_cvtepi32_ps(x))))
        };
        let ((x, tx_), (y, ty)) = (coords(t.u, tx.width), coords(t.v, tx.height));
        Footprints { x, y, tx: tx_, ty }
    });
    Some(TileShading { mask, l: [lanes(l0), lanes(l1), lanes(l2)], z: lanes(z), inv: lanes(inv), foot })
}

/// The eight lanes of `v`, in order.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lanes_i32(v: std::arch::x86_64::__m256i) -> [i32; SMALL_LANES] {
    // SAFETY: `__m256i` and `[i32; 8]` are both 32 bytes of eight `i32` lanes in order.
    unsafe { std::mem::transmute::<std::arch::x86_64::__m256i, [i32; SMALL_LANES]>(v) }
}

/// `straight` (see the `framebuffer` module) for two pixels per AVX register, branch-free: the same
/// operations as the scalar form, which are SSE operations through glam (the alpha as `maxps` over
/// the same shuffles, `minps` against 1, `divps` by it), so bit-identical. Its two branches are one
/// here: for `a == 1` dividing by `a` changes nothing; `a ≤ 0` is masked to zero. Over a 1280×720
/// frame the scalar form took about 15 instructions per pixel (a tenth of the instructions of a
/// 144-flame cloth frame's drawing). Returns the pixels converted (all but an odd last one).
///
/// # Safety
/// The CPU must support AVX2, and `out` must be valid for writes of `4 · color.len()` samples.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn straight_pairs_avx2(color: &[[f32; 4]], out: *mut f32) -> usize {
    use std::arch::x86_64::{
        _CMP_GT_OQ, _mm256_and_ps, _mm256_blend_ps, _mm256_cmp_ps, _mm256_div_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
        _mm256_set1_ps, _mm256_setzero_ps, _mm256_shuffle_ps, _mm256_storeu_ps,
    };
    let one = _mm256_set1_ps(1.0);
    let pairs = color.len() / 2;
    for (k, pair) in color.chunks_exact(2).enumerate() {
        // SAFETY: `pair` is two pixels, eight contiguous `f32`s.
        let p = unsafe { _mm256_loadu_ps(pair.as_ptr().cast()) };
        // glam's `max_element`: lane 0 of each pixel ends up as the maximum of its four.
        let m = _mm256_max_ps(p, _mm256_shuffle_ps::<0b00_00_11_10>(p, p));
        let m = _mm256_max_ps(m, _mm256_shuffle_ps::<0b00_00_00_01>(m, m));
        // `f32::min(max, 1.0)`: a NaN maximum gives 1, as `minps` keeps its second operand.
        let a = _mm256_min_ps(_mm256_shuffle_ps::<0>(m, m), one);
        let rgb = _mm256_min_ps(_mm256_div_ps(p, a), one);
        let px = _mm256_and_ps(_mm256_blend_ps::<0b1000_1000>(rgb, a), _mm256_cmp_ps::<_CMP_GT_OQ>(a, _mm256_setzero_ps()));
        // SAFETY: pixels `2k` and `2k + 1` are within `color`, so their eight samples within `out`.
        unsafe { _mm256_storeu_ps(out.add(8 * k), px) };
    }
    2 * pairs
}
