//! What the portable code and the AVX2 kernels exchange, lane by lane: the lane counts, a small
//! triangle's set-up, a tile's lane layout and what its lanes need before shading.
//!
//! These sit below both sides (the `fan`, `tiles` and `texture` modules, and the kernels of the
//! `avx2` module) so that the kernels depend on the data they compute with, never on the
//! portable code that calls them.

use glam::Vec4;

/// Pixels per block of `fill_fan_span` (see the `fan` module): the lower envelope is evaluated
/// for a block at a time so the loop over edges vectorizes.
pub(super) const FAN_LANES: usize = 8;

/// Lanes of `small_tri_tile` (see the `tiles` module): triangles whose bounding box is at most
/// this many pixels wide are rasterized a tile of rows at a time in vector lanes.
pub(super) const SMALL_LANES: usize = 8;

/// A triangle set up for `small_tri_tile` (see the `tiles` module): the edge functions at the
/// first pixel of its box (top-left bias folded in) and their x and y steps, in `i32` (see
/// `small_extent` there), and its vertices' attributes (colour and uv pre-multiplied by `iw`).
pub(super) struct SmallTri {
    pub(super) x0: usize,
    /// Pixels of the box right of `x0` (`< SMALL_LANES`).
    pub(super) span: usize,
    pub(super) row: [i32; 3],
    pub(super) dx: [i32; 3],
    pub(super) dy: [i32; 3],
    pub(super) inv_area: f32,
    pub(super) z: [f32; 3],
    pub(super) iw: [f32; 3],
    pub(super) u: [f32; 3],
    pub(super) v: [f32; 3],
    pub(super) colors: [Vec4; 3],
}

/// The pixel of each lane of a tile `W` pixels wide: its column and row in the tile.
pub(super) struct TileLanes<const W: usize>;

impl<const W: usize> TileLanes<W> {
    pub(super) const COL: [i32; SMALL_LANES] = Self::lanes(true);
    pub(super) const ROW: [i32; SMALL_LANES] = Self::lanes(false);

    const fn lanes(col: bool) -> [i32; SMALL_LANES] {
        let mut a = [0; SMALL_LANES];
        let mut i = 0;
        while i < SMALL_LANES {
            a[i] = if col { i % W } else { i / W } as i32;
            i += 1;
        }
        a
    }

    /// The lanes of the columns `0..=span` (`span < W`) of the rows `0..=rows_left` of the tile.
    #[inline(always)]
    pub(super) fn inside(span: usize, rows_left: usize) -> u32 {
        // One row's columns, repeated in every row of the tile.
        let (one_row, every_row) = ((2u32 << span) - 1, Self::every_row());
        let rows = (rows_left + 1).min(SMALL_LANES / W);
        (one_row * every_row) & (u32::MAX >> (32 - rows * W))
    }

    /// Bit 0 of every row of the tile.
    const fn every_row() -> u32 {
        let mut m = 0;
        let mut r = 0;
        while r < SMALL_LANES / W {
            m |= 1 << (r * W);
            r += 1;
        }
        m
    }
}

/// What `small_tri_tile` (see the `tiles` module) needs per lane before shading: the covered
/// lanes (bit `i` for lane `i`), the barycentric weights, depth, `1/w` and, for a textured
/// triangle, the texel footprints.
pub(super) struct TileShading {
    pub(super) mask: u32,
    pub(super) l: [[f32; SMALL_LANES]; 3],
    pub(super) z: [f32; SMALL_LANES],
    pub(super) inv: [f32; SMALL_LANES],
    pub(super) foot: Option<Footprints>,
}

/// Where the bilinear samples of [`SMALL_LANES`] pixels read (`Texels::footprints`, see the
/// `texture` module): the top-left texel of each and the weights of the texels right of and below
/// it.
pub(super) struct Footprints {
    pub(super) x: [i32; SMALL_LANES],
    pub(super) y: [i32; SMALL_LANES],
    pub(super) tx: [f32; SMALL_LANES],
    pub(super) ty: [f32; SMALL_LANES],
}
