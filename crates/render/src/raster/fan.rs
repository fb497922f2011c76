//! Fuzzy particles (Perry 1994 §3.2.1) on the scanline path: the fan's set-up when it is drawn,
//! and its rasterization row by row as the lower envelope of its rim edges.

use glam::Vec4;

use super::isa::Isa;
use super::lanes::FAN_LANES;
use super::{Band, SUB, SVert, edge_fn};

/// Most rim vertices a particle may have and still take the scanline fast path (its per-pixel
/// cost grows with the side count; Perry's particles have 3–20 sides).
pub(super) const MAX_FAN: usize = 64;

/// One rim edge of a fuzzy particle, `[b, c, p, q, reach]`: the affine function
/// `L(p) = 1 + b·dx + c·dy` of the pixel offset `(dx, dy)` from the particle's centre, 1 at the
/// centre and 0 on the edge's line; that line's crossing of row `dy` at `dx = p + q·dy`
/// (`p = −1/b`, `q = −c/b`; both 0 for a horizontal edge); and how far from the centre its fan
/// triangle reaches, in pixels, signed so that the rows of its half it crosses are those with
/// `reach ≤ ±dy` (− for the rows above the centre, + below). Inside the fan triangle of the edge
/// `L` is exactly the centre vertex's barycentric weight.
pub(super) type FanEdge = [f32; 5];

/// A fan edge during setup: the edge, the halves its triangle reaches (bit 0: rows at or above
/// the centre, bit 1: at or below), its side (0 left-facing, 1 right-facing, 2 horizontal) and the
/// y range of its ends relative to the centre, in pixels.
pub(super) type KeptEdge = (FanEdge, u8, u8, (f32, f32));

/// Slack on [`FanEdge`]'s reach test, in pixels: taking an edge a row does not cross is harmless
/// (its `L` is not the smallest there), missing one is not.
const REACH_SLACK: f32 = 1e-3;

/// A fuzzy particle ready for scanline rasterization: a convex polygon around `(cx, cy)` whose
/// colour is `edge + (center − edge)·L` with `L = min_k L_k` (the Gouraud fan, computed per row
/// as the lower envelope of the rim edges' functions instead of triangle by triangle).
#[derive(Clone, Copy, Debug)]
pub(super) struct FanSetup {
    cx: f32,
    cy: f32,
    /// Pixel rows touched, inclusive, clamped to the viewport.
    rows: (i32, i32),
    /// First of this fan's edges in `DrawList::fan_edges`: the edges whose fan triangles reach
    /// the rows at or above the centre (`dy ≤ 0`), then those reaching the rows at or below it (a
    /// row needs only the triangles it crosses); each half ordered left-facing (`b > 0`),
    /// right-facing (`b < 0`), then horizontal, with these counts.
    pub(super) first: u32,
    pub(super) counts: [[u8; 3]; 2],
    /// Alpha within [0, 1] and colour ≥ 0 at the centre and at the rim (so everywhere between):
    /// additive blending needs no clamping of the source.
    pub(super) in_range: bool,
    /// Straight RGBA at the rim and centre − rim.
    edge: [f32; 4],
    delta: [f32; 4],
    /// Depth at the centre and its gradient in x and y per pixel (depth is affine in screen
    /// space over a planar polygon).
    z: [f32; 3],
}

impl FanSetup {
    /// The scanline form of the fan whose centre is `vs[0]` and rim the rest of `vs`, its edges
    /// pushed to `fan_edges` (`scratch` is a working list, reused); `None` (nothing pushed) when
    /// it cannot take that path: degenerate, not convex around its centre, beyond the far plane
    /// or too many sides.
    pub(super) fn new(
        vs: &[SVert],
        rows: (i64, i64),
        center: [f32; 4],
        edge: [f32; 4],
        fan_edges: &mut Vec<FanEdge>,
        scratch: &mut Vec<KeptEdge>,
    ) -> Option<FanSetup> {
        let n = vs.len() - 1;
        if !(3..=MAX_FAN).contains(&n) {
            return None;
        }
        let (c, rim) = (&vs[0], &vs[1..]);
        if vs.iter().any(|v| !(0.0..=1.0).contains(&v.z)) {
            return None;
        }
        // Each kept edge with the halves its fan triangle reaches (bit 0: rows at or above the
        // centre, bit 1: at or below) and its side (0 left-facing, 1 right-facing, 2 horizontal).
        let mut kept = std::mem::take(scratch);
        kept.clear();
        let mut sign = 0i64;
        for k in 0..n {
            let (p, q) = (&rim[k], &rim[(k + 1) % n]);
            let (ex, ey) = (q.x - p.x, q.y - p.y);
            if ex == 0 && ey == 0 {
                continue; // Two rim vertices snapped together: the edge vanishes, its triangle too.
            }
            let ec = edge_fn(p, q, c.x, c.y);
            if ec == 0 || (sign != 0 && ec.signum() != sign) {
                *scratch = kept;
                return None;
            }
            sign = ec.signum();
            let (exf, eyf, ecf, sub) = (ex as f64, ey as f64, ec as f64, SUB as f64);
            // One division for all four coefficients: 1/ec = ey·r and 1/ey = ec·r.
            let edge = if ey != 0 {
                let r = 1.0 / (ecf * eyf);
                [-eyf * eyf * sub * r, exf * eyf * sub * r, ecf * ecf * r / sub, exf * ecf * r, 0.0].map(|v| v as f32)
            } else {
                [0.0, (exf * sub / ecf) as f32, 0.0, 0.0, 0.0]
            };
            let b = edge[0];
            let (py, qy) = (p.y - c.y, q.y - c.y);
            let halves = u8::from(py.min(qy) <= 0) | (u8::from(py.max(qy) >= 0) << 1);
            let side = if b > 0.0 {
                0
            } else if b < 0.0 {
                1
            } else {
                2
            };
            let (ymin, ymax) = (py.min(qy) as f32 / SUB as f32, py.max(qy) as f32 / SUB as f32);
            kept.push((edge, halves, side, (ymin, ymax)));
        }
        if kept.len() < 3 {
            *scratch = kept;
            return None;
        }
        let first = fan_edges.len();
        let mut counts = [[0u8; 3]; 2];
        for (half, count) in counts.iter_mut().enumerate() {
            for (side, count) in count.iter_mut().enumerate() {
                let group = fan_edges.len();
                for (e, halves, s, (ymin, ymax)) in &kept {
                    if halves & (1 << half) != 0 && usize::from(*s) == side {
                        let mut e = *e;
                        e[4] = if half == 0 { *ymin } else { -*ymax };
                        fan_edges.push(e);
                        *count += 1;
                    }
                }
                // Nearest reach first, so a row's edges are a prefix of the group.
                fan_edges[group..].sort_unstable_by(|a, b| a[4].total_cmp(&b[4]));
            }
        }
        *scratch = kept;
        // Depth plane through the centre and the two rim vertices spanning the largest area
        // (found with exact fixed-point cross products).
        let (x0, y0) = (rim[0].x - c.x, rim[0].y - c.y);
        let far = rim[1..].iter().max_by_key(|v| ((v.y - c.y) * x0 - (v.x - c.x) * y0).abs()).unwrap_or(&rim[0]);
        let px = |v: &SVert| ((v.x - c.x) as f64 / SUB as f64, (v.y - c.y) as f64 / SUB as f64, (v.z - c.z) as f64);
        let (p0, best) = (px(&rim[0]), px(far));
        let det = p0.0 * best.1 - best.0 * p0.1;
        let (gx, gy) = if det.abs() > 1e-9 {
            ((p0.2 * best.1 - best.2 * p0.1) / det, (p0.0 * best.2 - best.0 * p0.2) / det)
        } else {
            (0.0, 0.0)
        };
        let delta = std::array::from_fn(|i| center[i] - edge[i]);
        let in_range = [center, edge].iter().all(|c| (0.0..=1.0).contains(&c[3]) && c[..3].iter().all(|&v| v >= 0.0));
        Some(FanSetup {
            cx: c.x as f32 / SUB as f32,
            cy: c.y as f32 / SUB as f32,
            rows: (rows.0 as i32, rows.1 as i32),
            first: first as u32,
            counts,
            in_range,
            edge,
            delta,
            z: [c.z, gx as f32, gy as f32],
        })
    }
}

/// Scanline rasterization of a fuzzy particle within one band. Per row: the span is the
/// intersection of the rim edges' half-planes `L_k ≥ 0` (pixel centres in `[x_left, x_right)`),
/// and the colour follows the lower envelope `min_k L_k` (inside the fan triangle of edge k,
/// `L_k` is the smallest; see [`fill_fan_span`]).
#[inline(always)]
pub(super) fn raster_fan<I: Isa, const ADD_IN_RANGE: bool>(
    isa: I,
    band: &mut Band<'_>,
    f: &FanSetup,
    halves: [&[FanEdge]; 2],
    blend: impl Fn(&mut [f32; 4], Vec4),
) {
    let r0 = f.rows.0.max(band.y0 as i32);
    let r1 = f.rows.1.min(band.y1 as i32 - 1);
    let w = band.width as i32;
    let mut offsets = [[0.0f32; 2]; MAX_FAN];
    for y in r0..=r1 {
        let dy = y as f32 + 0.5 - f.cy;
        let half = usize::from(dy > 0.0);
        let (edges, [left, right, _]) = (halves[half], f.counts[half].map(usize::from));
        let (lefts, rest) = edges.split_at(left);
        let (rights, flats) = rest.split_at(right);
        // The edges whose fan triangles this row crosses: a prefix of each group.
        let limit = if half == 0 { dy } else { -dy } + REACH_SLACK;
        let (lefts, rights, flats) = (crossed(lefts, limit), crossed(rights, limit), crossed(flats, limit));
        // Where each edge's line crosses the row, relative to the centre: the span is right of
        // every left-facing edge's crossing and left of every right-facing one's.
        let cross = |&[_, _, p, q, _]: &FanEdge| p + q * dy;
        let xl = lefts.iter().map(cross).fold(f32::NEG_INFINITY, |m, x| if x > m { x } else { m });
        let xr = rights.iter().map(cross).fold(f32::INFINITY, |m, x| if x < m { x } else { m });
        // Written so an unbounded side (no such edge) also skips the row.
        if !(xl < xr && xl.is_finite() && xr.is_finite()) {
            continue;
        }
        let px0 = ceil_i32(f.cx + xl - 0.5).max(0);
        let px1 = (ceil_i32(f.cx + xr - 0.5) - 1).min(w - 1);
        if px0 > px1 {
            continue;
        }
        let line = (y as usize - band.y0) * band.width;
        let zrow = f.z[0] + f.z[2] * dy;
        let mut count = 0;
        // A loop per group: a chained iterator branched at every edge on which group it was in.
        for group in [lefts, rights, flats] {
            for [b, c, ..] in group {
                offsets[count] = [1.0 + c * dy, *b];
                count += 1;
            }
        }
        let env = &offsets[..count];
        let span = line + px0 as usize..line + px1 as usize + 1;
        let xd0 = px0 as f32 + 0.5 - f.cx;
        let z = (zrow + f.z[1] * xd0, f.z[1]);
        if band.has_opaque {
            let depth = Some((&band.depth[span.clone()], z));
            fill_fan_span::<_, ADD_IN_RANGE>(isa, &mut band.color[span], depth, xd0, env, f, &blend);
        } else {
            fill_fan_span::<_, ADD_IN_RANGE>(isa, &mut band.color[span], None, xd0, env, f, &blend);
        }
    }
}

/// The first edges of `group` (sorted by reach) that reach `limit`.
#[inline(always)]
fn crossed(group: &[FanEdge], limit: f32) -> &[FanEdge] {
    &group[..group.iter().take_while(|e| e[4] <= limit).count()]
}

/// `ceil(x)` for values well inside the `i32` range (no libm call without SSE4.1).
#[inline(always)]
fn ceil_i32(x: f32) -> i32 {
    let i = x as i32;
    i + i32::from((i as f32) < x)
}

/// Blends one row span of a particle starting `xd0` pixels right of its centre: per pixel,
/// `L = min_k (offset_k + slope_k·xd)` over every rim edge, branch-free in blocks of
/// [`FAN_LANES`]. Walking the envelope sector by sector needs fewer multiplies but a
/// data-dependent branch per sector, and particles a few pixels wide cross a sector every
/// three pixels; measured 2–3× slower at 1,000 flames.
///
/// `depth`, where something opaque was drawn in the band, is the span's depth buffer with the
/// particle's depth at the first pixel and its step per pixel.
#[inline(always)]
fn fill_fan_span<I: Isa, const ADD_IN_RANGE: bool>(
    isa: I,
    color: &mut [[f32; 4]],
    depth: Option<(&[f32], (f32, f32))>,
    xd0: f32,
    env: &[[f32; 2]],
    f: &FanSetup,
    blend: &impl Fn(&mut [f32; 4], Vec4),
) {
    // The particles' usual case (additive, in range, nothing opaque to test against) has a
    // kernel for the whole span.
    if let Some(avx2) = isa.avx2().filter(|_| ADD_IN_RANGE && depth.is_none()) {
        avx2.add_span(color, xd0, env, f.edge, f.delta);
        return;
    }
    let (e, d) = (Vec4::from_array(f.edge), Vec4::from_array(f.delta));
    for (block, dst) in color.chunks_mut(FAN_LANES).enumerate() {
        let base = xd0 + (block * FAN_LANES) as f32;
        let xd: [f32; FAN_LANES] = std::array::from_fn(|i| base + i as f32);
        let l = envelope(isa, env, base);
        for (i, px) in dst.iter_mut().enumerate() {
            let visible = depth.is_none_or(|(zb, (z0, dz))| z0 + dz * (xd[i] - xd0) <= zb[block * FAN_LANES + i]);
            if visible {
                blend(px, e + d * l[i].clamp(0.0, 1.0));
            }
        }
    }
}

/// The lower envelope `min_k (offset_k + slope_k·xd)` of a fan row's edges at the
/// [`FAN_LANES`] pixels `xd = base, base + 1, …` (offsets from the particle's centre), with
/// the instruction set `isa`.
#[inline(always)]
pub(super) fn envelope<I: Isa>(isa: I, env: &[[f32; 2]], base: f32) -> [f32; FAN_LANES] {
    if let Some(avx2) = isa.avx2() {
        return avx2.envelope(env, base);
    }
    let xd: [f32; FAN_LANES] = std::array::from_fn(|i| base + i as f32);
    let mut l = [f32::INFINITY; FAN_LANES];
    for &[offset, slope] in env {
        for (li, &x) in l.iter_mut().zip(&xd) {
            *li = lane_min(offset + slope * x, *li);
        }
    }
    l
}

/// `v` if it is below `m`, else `m`: written as a compare, not `f32::min`, so it lowers to one
/// `minps` (a NaN `v` never replaces `m`).
#[inline(always)]
fn lane_min(v: f32, m: f32) -> f32 {
    if v < m { v } else { m }
}
