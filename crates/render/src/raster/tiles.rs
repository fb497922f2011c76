//! Triangles: the general per-pixel loop over a triangle's bounding box, and small triangles in
//! tiles of eight vector lanes.

use glam::Vec4;
use pyrograph_core::Image;

use super::isa::Isa;
use super::lanes::{SMALL_LANES, SmallTri, TileLanes, TileShading};
use super::texture::Texels;
use super::{Band, Blend, SUB, SVert, blend_vec4, ceil_sub, edge_fn, floor_sub, is_top_left};

/// Rasterizes triangle `abc` (either orientation; colour and uv pre-multiplied by `iw`) into
/// `band` with the instruction set `isa`: a triangle of at most [`SMALL_LANES`] pixels across
/// in vector tiles when `SMALL`, any other with a per-pixel loop over its bounding box.
#[inline(always)]
pub(super) fn raster_tri<const SMALL: bool, I: Isa>(
    isa: I,
    band: &mut Band<'_>,
    a: &SVert,
    b: &SVert,
    c: &SVert,
    blend: Blend,
    tex: Option<&Image>,
) {
    let area = edge_fn(a, b, c.x, c.y);
    let (b, c, area) = match area.cmp(&0) {
        std::cmp::Ordering::Equal => return,
        std::cmp::Ordering::Less => (c, b, -area),
        std::cmp::Ordering::Greater => (b, c, area),
    };
    let x0 = ceil_sub(a.x.min(b.x).min(c.x) - SUB / 2).max(0);
    let x1 = floor_sub(a.x.max(b.x).max(c.x) - SUB / 2).min(band.width as i64 - 1);
    let y0 = ceil_sub(a.y.min(b.y).min(c.y) - SUB / 2).max(band.y0 as i64);
    let y1 = floor_sub(a.y.max(b.y).max(c.y) - SUB / 2).min(band.y1 as i64 - 1);
    if x0 > x1 || y0 > y1 {
        return;
    }
    // Edge functions at the first pixel centre (top-left bias folded in, so a pixel is covered
    // when all three are >= 0; the bias is below one fixed-point unit of area), and their steps.
    let (px, py) = (x0 * SUB + SUB / 2, y0 * SUB + SUB / 2);
    let edges = [(b, c), (c, a), (a, b)];
    let mut row = [0i64; 3];
    let mut dx = [0i64; 3];
    let mut dy = [0i64; 3];
    for (k, (p, q)) in edges.iter().enumerate() {
        row[k] = edge_fn(p, q, px, py) - i64::from(!is_top_left(p, q));
        dx[k] = -(q.y - p.y) * SUB;
        dy[k] = (q.x - p.x) * SUB;
    }
    let inv_area = 1.0 / area as f32;
    let [ca, cb, cc] = [a, b, c].map(|v| Vec4::from_array(v.c));
    let tex = tex.and_then(Texels::new);
    let depth_write = blend == Blend::Opaque;
    let depth_test = depth_write || band.has_opaque;
    if SMALL && x1 - x0 < SMALL_LANES as i64 && small_extent(a, b, c) {
        let tri = SmallTri {
            x0: x0 as usize,
            span: (x1 - x0) as usize,
            row: row.map(|r| r as i32),
            dx: dx.map(|d| d as i32),
            // The steps per row fit an `i32` like the edge functions (see `small_extent`).
            dy: dy.map(|d| d as i32),
            inv_area,
            z: [a.z, b.z, c.z],
            iw: [a.iw, b.iw, c.iw],
            u: [a.uv[0], b.uv[0], c.uv[0]],
            v: [a.uv[1], b.uv[1], c.uv[1]],
            colors: [ca, cb, cc],
        };
        let shade = PixelShade { tex: tex.as_ref(), blend, depth_test, depth_write };
        let rows = (y0 as usize, y1 as usize);
        // As many rows per tile as the box's width leaves lanes for: a dense cloth's triangles
        // are 2–4 pixels wide, so one row per call left most lanes empty.
        match tri.span {
            0..=1 => small_tri_tiles::<2, _>(isa, band, &tri, rows, &shade),
            2..=3 => small_tri_tiles::<4, _>(isa, band, &tri, rows, &shade),
            _ => small_tri_tiles::<8, _>(isa, band, &tri, rows, &shade),
        }
        return;
    }
    let wide = x1 - x0 >= 8;
    for y in y0..=y1 {
        let mut w = row;
        let line = (y as usize - band.y0) * band.width;
        let (mut lo, mut hi) = (x0, x1);
        if wide {
            // Jump to the covered run of the row: an edge with a positive x step holds from some
            // x on, one with a negative step up to some x.
            for k in 0..3 {
                if dx[k] > 0 && w[k] < 0 {
                    lo = lo.max(x0 + (-w[k] + dx[k] - 1) / dx[k]);
                } else if dx[k] < 0 {
                    hi = if w[k] < 0 { -1 } else { hi.min(x0 + w[k] / -dx[k]) };
                } else if dx[k] == 0 && w[k] < 0 {
                    hi = -1;
                }
            }
            if lo <= hi {
                for k in 0..3 {
                    w[k] += dx[k] * (lo - x0);
                }
            }
        }
        for x in lo..=hi {
            if w[0] >= 0 && w[1] >= 0 && w[2] >= 0 {
                let l1 = w[1] as f32 * inv_area;
                let l2 = w[2] as f32 * inv_area;
                let l0 = 1.0 - l1 - l2;
                let z = a.z * l0 + b.z * l1 + c.z * l2;
                let i = line + x as usize;
                if (0.0..=1.0).contains(&z) && (!depth_test || z <= band.depth[i]) {
                    let iw = a.iw * l0 + b.iw * l1 + c.iw * l2;
                    let inv = 1.0 / iw;
                    let mut src = (ca * l0 + cb * l1 + cc * l2) * inv;
                    if let Some(t) = &tex {
                        let u = (a.uv[0] * l0 + b.uv[0] * l1 + c.uv[0] * l2) * inv;
                        let v = (a.uv[1] * l0 + b.uv[1] * l1 + c.uv[1] * l2) * inv;
                        src *= t.sample(u, v);
                    }
                    blend_vec4(&mut band.color[i], src, blend);
                    if depth_write {
                        band.depth[i] = z;
                    }
                }
            }
            w[0] += dx[0];
            w[1] += dx[1];
            w[2] += dx[2];
        }
        row[0] += dy[0];
        row[1] += dy[1];
        row[2] += dy[2];
    }
}

/// Whether a triangle's edge functions, evaluated anywhere within its bounding box widened by
/// [`SMALL_LANES`] pixels (and one row), fit an `i32`: both sides of its box below 64 pixels
/// bound them by `2 · (64·SUB) · (73·SUB) < 2^31`, and their steps per row by `64·SUB²`.
/// (A tile of [`small_tri_tile`] reaches at most `SMALL_LANES / 2 − 1` rows below the box, and
/// the steps between tiles `SMALL_LANES / 2` rows, both inside that margin.)
#[inline(always)]
fn small_extent(a: &SVert, b: &SVert, c: &SVert) -> bool {
    let span = |p: i64, q: i64, r: i64| p.max(q).max(r) - p.min(q).min(r);
    span(a.x, b.x, c.x) < 64 * SUB && span(a.y, b.y, c.y) < 64 * SUB
}

/// How a covered pixel is shaded and blended.
struct PixelShade<'t, 'a> {
    tex: Option<&'t Texels<'a>>,
    blend: Blend,
    depth_test: bool,
    depth_write: bool,
}

/// The rows `rows.0..=rows.1` of a small triangle, in tiles of `W` pixels by
/// `SMALL_LANES / W` rows.
#[inline(always)]
fn small_tri_tiles<const W: usize, I: Isa>(
    isa: I,
    band: &mut Band<'_>,
    t: &SmallTri,
    rows: (usize, usize),
    shade: &PixelShade<'_, '_>,
) {
    let tall = (SMALL_LANES / W) as i32;
    let mut w = t.row;
    for y in (rows.0..=rows.1).step_by(SMALL_LANES / W) {
        small_tri_tile::<W, _>(isa, band, t, w, (y, rows.1 - y), shade);
        for (w, d) in w.iter_mut().zip(t.dy) {
            *w += d * tall;
        }
    }
}

/// One tile of a small triangle, `W` pixels wide from `t.x0` and `SMALL_LANES / W` rows down
/// from `y` (lane `i` is pixel `(i % W, i / W)`; lanes past `t.span` or past the last of the
/// `rows_left` rows are off): coverage, barycentric weights, depth, `1/w` and the texel
/// footprints of all [`SMALL_LANES`] pixels at once (vector lanes, branch-free), then colour,
/// texture and blending for the covered pixels only. Each lane does exactly the arithmetic of
/// the per-pixel loop of [`raster_tri`] (the edge functions are exact integers however they are
/// stepped), so the pixels are bit-identical to it; tiny triangles (a dense cloth or mesh far
/// from the camera covers 2–4 pixels per triangle) spend most of their time on coverage tests
/// and set-up that this does eight at a time.
#[inline(always)]
fn small_tri_tile<const W: usize, I: Isa>(
    isa: I,
    band: &mut Band<'_>,
    t: &SmallTri,
    w: [i32; 3],
    (y, rows_left): (usize, usize),
    shade: &PixelShade<'_, '_>,
) {
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    let lanes = match isa.avx2() {
        Some(avx2) => avx2.tile_lanes::<W>(t, w, rows_left, shade.tex),
        None => tile_lanes::<W>(t, w, rows_left, shade.tex),
    };
    let Some(TileShading { mask, l: [l0, l1, l2], z, inv, foot }) = lanes else { return };
    let mut mask = mask;
    let [ca, cb, cc] = t.colors;
    let first = (y - band.y0) * band.width + t.x0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let p = first + row[i] as usize * band.width + col[i] as usize;
        if !((0.0..=1.0).contains(&z[i]) && (!shade.depth_test || z[i] <= band.depth[p])) {
            continue;
        }
        let mut src = (ca * l0[i] + cb * l1[i] + cc * l2[i]) * inv[i];
        if let (Some(tx), Some(f)) = (shade.tex, &foot) {
            src *= tx.bilinear(f.x[i] as usize, f.y[i] as usize, f.tx[i], f.ty[i]);
        }
        blend_vec4(&mut band.color[p], src, shade.blend);
        if shade.depth_write {
            band.depth[p] = z[i];
        }
    }
}

/// The lanes of a tile of [`small_tri_tile`] whose top-left pixel has edge functions `w`;
/// `None` when it covers no pixel.
#[inline(always)]
fn tile_lanes<const W: usize>(t: &SmallTri, w: [i32; 3], rows_left: usize, tex: Option<&Texels<'_>>) -> Option<TileShading> {
    const N: usize = SMALL_LANES;
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    let mut we = [[0i32; N]; 3];
    for (e, we) in we.iter_mut().enumerate() {
        for i in 0..N {
            we[i] = w[e] + t.dx[e] * col[i] + t.dy[e] * row[i];
        }
    }
    // A pixel is covered when no edge function is negative: when their OR has no sign bit.
    let covered = (0..N).filter(|&i| (we[0][i] | we[1][i] | we[2][i]) >= 0);
    let mask = covered.fold(0u32, |m, i| m | 1 << i) & TileLanes::<W>::inside(t.span, rows_left);
    if mask == 0 {
        return None;
    }
    let (mut l0, mut l1, mut l2, mut z, mut inv) = ([0.0f32; N], [0.0f32; N], [0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        l1[i] = we[1][i] as f32 * t.inv_area;
        l2[i] = we[2][i] as f32 * t.inv_area;
        l0[i] = 1.0 - l1[i] - l2[i];
        z[i] = t.z[0] * l0[i] + t.z[1] * l1[i] + t.z[2] * l2[i];
        inv[i] = 1.0 / (t.iw[0] * l0[i] + t.iw[1] * l1[i] + t.iw[2] * l2[i]);
    }
    let foot = tex.map(|tx| {
        let (mut u, mut v) = ([0.0f32; N], [0.0f32; N]);
        for i in 0..N {
            u[i] = (t.u[0] * l0[i] + t.u[1] * l1[i] + t.u[2] * l2[i]) * inv[i];
            v[i] = (t.v[0] * l0[i] + t.v[1] * l1[i] + t.v[2] * l2[i]) * inv[i];
        }
        tx.footprints(&u, &v)
    });
    Some(TileShading { mask, l: [l0, l1, l2], z, inv, foot })
}
