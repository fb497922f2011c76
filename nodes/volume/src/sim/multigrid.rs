//! The multigrid preconditioner of the pressure solve, after McAdams, Sifakis & Teran 2010 ("A
//! parallel multigrid Poisson solver for fluids simulation on large grids"), on sparse bricks:
//! each coarser level halves the resolution (a coarse voxel covers 2³ fine ones, so a coarse
//! brick covers 2³ fine bricks), is re-discretised with the same 7-point stencil, and is
//! smoothed by red-black Gauss–Seidel. A V-cycle with red-then-black sweeps on the way down and
//! black-then-red on the way up, with restriction proportional to the transpose of
//! prolongation, is a symmetric operator, as conjugate gradients needs of a preconditioner.

use glam::IVec3;
use rayon::prelude::*;

use crate::grid::halo::{TILE, gather, t};
use crate::grid::{NONE, Topology, VOXELS, voxel};

/// A voxel whose pressure is solved for.
pub const FLUID: u8 = 0;
/// A voxel of open air: pressure 0 (the edge of the active region).
pub const OPEN: u8 = 1;
/// A voxel inside a collider: no flow through its faces.
pub const SOLID: u8 = 2;

/// Smoothing sweeps (each red then black) before and after the coarse correction.
const SWEEPS: usize = 2;
/// Sweeps on the coarsest level.
const COARSEST_SWEEPS: usize = 16;
/// Levels are added while the coarsest has more bricks than this.
const COARSEST_BRICKS: usize = 2;
/// At most this many levels.
const MAX_LEVELS: usize = 8;

/// One level of the hierarchy: its bricks, each voxel's kind, and the diagonal of its 7-point
/// Laplacian (the number of non-solid neighbours; 0 for voxels that are not solved for).
pub struct Level {
    /// The bricks.
    pub top: Topology,
    /// [`FLUID`], [`OPEN`] or [`SOLID`] per voxel.
    pub kind: Vec<u8>,
    /// The Laplacian's diagonal per voxel, 0 where the voxel is not [`FLUID`].
    pub diag: Vec<f32>,
    /// For each brick of this level, its brick on the next coarser level (filled when that
    /// level is built).
    parent: Vec<u32>,
    /// For each brick, the eight bricks of the next finer level it covers ([`NONE`] if absent).
    children: Vec<[u32; 8]>,
}

impl Level {
    /// A level of `top` whose voxel kinds are `kind`.
    pub fn new(top: Topology, kind: Vec<u8>) -> Level {
        let diag = diagonal(&top, &kind);
        Level { parent: vec![NONE; top.len()], children: Vec::new(), top, kind, diag }
    }

    /// Fluid voxels.
    pub fn unknowns(&self) -> usize {
        self.kind.iter().filter(|k| **k == FLUID).count()
    }
}

/// The number of non-solid face neighbours of each fluid voxel (inactive neighbours are open
/// air); 0 for the others. A fluid voxel walled in on all six sides is left out of the solve.
fn diagonal(top: &Topology, kind: &[u8]) -> Vec<f32> {
    let mut diag = vec![0.0; top.voxels()];
    let kinds: Vec<f32> = kind.iter().map(|k| f32::from(*k == SOLID)).collect();
    diag.par_chunks_mut(VOXELS).enumerate().for_each(|(b, d)| {
        let mut tile = [0.0; TILE];
        gather(top, &kinds, b, 0.0, &mut tile);
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let i = voxel(x as usize, y as usize, z as usize);
                    if kind[b * VOXELS + i] != FLUID {
                        continue;
                    }
                    let c = t(x, y, z);
                    let solid = tile[c - 1] + tile[c + 1] + tile[c - 10] + tile[c + 10] + tile[c - 100] + tile[c + 100];
                    d[i] = 6.0 - solid;
                }
            }
        }
    });
    diag
}

/// The hierarchy from `finest` down to a level of a couple of bricks.
pub fn hierarchy(finest: Level) -> Vec<Level> {
    let mut levels = vec![finest];
    while levels.len() < MAX_LEVELS {
        let fine = levels.last_mut().expect("at least the finest level");
        if fine.top.len() <= COARSEST_BRICKS {
            break;
        }
        let coarse = coarsen(fine);
        if coarse.top.len() == fine.top.len() && coarse.unknowns() == fine.unknowns() {
            break;
        }
        levels.push(coarse);
    }
    levels
}

/// The next coarser level of `fine` (and `fine`'s parent table): a coarse voxel is fluid if any
/// of its eight children is, solid if all eight are, open air otherwise.
fn coarsen(fine: &mut Level) -> Level {
    let top = Topology::new(fine.top.coords().iter().map(|c| IVec3::new(c.x >> 1, c.y >> 1, c.z >> 1)).collect());
    let mut children = vec![[NONE; 8]; top.len()];
    for (b, c) in fine.top.coords().iter().enumerate() {
        let p = top.find(IVec3::new(c.x >> 1, c.y >> 1, c.z >> 1)).expect("the coarse level covers every fine brick");
        fine.parent[b] = p;
        let oct = (c.x & 1) | ((c.y & 1) << 1) | ((c.z & 1) << 2);
        children[p as usize][oct as usize] = b as u32;
    }
    let mut kind = vec![OPEN; top.voxels()];
    kind.par_chunks_mut(VOXELS).zip(children.par_iter()).for_each(|(k, ch)| {
        for (i, out) in k.iter_mut().enumerate() {
            let (x, y, z) = (i & 7, (i >> 3) & 7, i >> 6);
            let oct = (x >> 2) | ((y >> 2) << 1) | ((z >> 2) << 2);
            let fb = ch[oct];
            if fb == NONE {
                continue;
            }
            let (fx, fy, fz) = ((x & 3) * 2, (y & 3) * 2, (z & 3) * 2);
            let (mut fluid, mut solid) = (false, 0);
            for c in 0..8 {
                let fi = voxel(fx + (c & 1), fy + ((c >> 1) & 1), fz + (c >> 2));
                match fine.kind[fb as usize * VOXELS + fi] {
                    FLUID => fluid = true,
                    SOLID => solid += 1,
                    _ => {}
                }
            }
            *out = if fluid {
                FLUID
            } else if solid == 8 {
                SOLID
            } else {
                OPEN
            };
        }
    });
    let mut level = Level::new(top, kind);
    level.children = children;
    level
}

/// `out = A x` on a level (0 at voxels not solved for).
pub fn apply(level: &Level, x: &[f32], out: &mut [f32]) {
    each_brick(out, |b, o| {
        let mut tile = [0.0; TILE];
        gather(&level.top, x, b, 0.0, &mut tile);
        let diag = &level.diag[b * VOXELS..(b + 1) * VOXELS];
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let i = voxel(x as usize, y as usize, z as usize);
                    let c = t(x, y, z);
                    let sum = tile[c - 1] + tile[c + 1] + tile[c - 10] + tile[c + 10] + tile[c - 100] + tile[c + 100];
                    o[i] = if diag[i] > 0.0 { diag[i] * tile[c] - sum } else { 0.0 };
                }
            }
        }
    });
}

/// One Gauss–Seidel half-sweep over the voxels of one colour (`(x + y + z) mod 2`), from `x`
/// into `out` (the other colour copied), solving `A x = b`.
fn sweep(level: &Level, x: &[f32], b: &[f32], colour: usize, out: &mut [f32]) {
    each_brick(out, |bi, o| {
        let mut tile = [0.0; TILE];
        gather(&level.top, x, bi, 0.0, &mut tile);
        let range = bi * VOXELS..(bi + 1) * VOXELS;
        let (diag, rhs) = (&level.diag[range.clone()], &b[range.clone()]);
        o.copy_from_slice(&x[range]);
        // Only the voxels of this colour change: every second one along each row.
        for z in 0..8i32 {
            for y in 0..8i32 {
                for xx in (((y + z) as usize + colour) & 1..8).step_by(2) {
                    let i = voxel(xx, y as usize, z as usize);
                    if diag[i] > 0.0 {
                        let c = t(xx as i32, y, z);
                        let sum = tile[c - 1] + tile[c + 1] + tile[c - 10] + tile[c + 10] + tile[c - 100] + tile[c + 100];
                        o[i] = (rhs[i] + sum) / diag[i];
                    }
                }
            }
        }
    });
}

/// Red-black sweeps: `count` times the two colours in `order`.
fn smooth(level: &Level, x: &mut Vec<f32>, b: &[f32], count: usize, order: [usize; 2], scratch: &mut Vec<f32>) {
    for _ in 0..count {
        for colour in order {
            sweep(level, x, b, colour, scratch);
            std::mem::swap(x, scratch);
        }
    }
}

/// The coarse right-hand side: half the sum of each coarse voxel's eight children's residuals
/// (the factor makes the re-discretised coarse Laplacian, 4× the fine one per unit length,
/// consistent).
fn restrict(coarse: &Level, r: &[f32], out: &mut [f32]) {
    each_brick(out, |cb, o| {
        let ch = &coarse.children[cb];
        o.fill(0.0);
        for (oct, fb) in ch.iter().enumerate() {
            if *fb == NONE {
                continue;
            }
            let off = ((oct & 1) * 4, ((oct >> 1) & 1) * 4, (oct >> 2) * 4);
            let rf = &r[*fb as usize * VOXELS..(*fb as usize + 1) * VOXELS];
            for (i, v) in rf.iter().enumerate() {
                let ci = voxel(off.0 + ((i & 7) >> 1), off.1 + (((i >> 3) & 7) >> 1), off.2 + ((i >> 6) >> 1));
                o[ci] += 0.5 * v;
            }
        }
        for (i, v) in o.iter_mut().enumerate() {
            if coarse.diag[cb * VOXELS + i] == 0.0 {
                *v = 0.0;
            }
        }
    });
}

/// Adds the coarse correction to each fine fluid voxel (piecewise constant prolongation).
fn prolong(fine: &Level, coarse: &[f32], x: &mut [f32]) {
    each_brick(x, |fb, o| {
        let c = fine.top.coords()[fb];
        let p = fine.parent[fb] as usize;
        let off = (((c.x & 1) * 4) as usize, ((c.y & 1) * 4) as usize, ((c.z & 1) * 4) as usize);
        for (i, v) in o.iter_mut().enumerate() {
            if fine.diag[fb * VOXELS + i] > 0.0 {
                let ci = voxel(off.0 + ((i & 7) >> 1), off.1 + (((i >> 3) & 7) >> 1), off.2 + ((i >> 6) >> 1));
                *v += coarse[p * VOXELS + ci];
            }
        }
    });
}

/// Levels of fewer bricks than this are worked on the calling thread: a coarse level's sweep
/// is a few microseconds of work, less than waking another thread for it, and the coarsest
/// level alone is swept 64 times a V-cycle.
const PARALLEL_BRICKS: usize = 16;

/// Runs `f(brick, that brick's values)` over every brick of `out`, in parallel when there are
/// enough of them.
fn each_brick(out: &mut [f32], f: impl Fn(usize, &mut [f32]) + Sync + Send) {
    if out.len() / VOXELS < PARALLEL_BRICKS {
        out.chunks_mut(VOXELS).enumerate().for_each(|(b, o)| f(b, o));
    } else {
        out.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| f(b, o));
    }
}

/// `z = M⁻¹ r`: one V-cycle from zero.
pub fn v_cycle(levels: &[Level], r: &[f32]) -> Vec<f32> {
    let n = levels.len();
    let mut bs: Vec<Vec<f32>> = Vec::with_capacity(n);
    let mut xs: Vec<Vec<f32>> = Vec::with_capacity(n);
    bs.push(r.to_vec());
    for l in 0..n {
        let level = &levels[l];
        let mut x = vec![0.0; level.top.voxels()];
        let mut scratch = vec![0.0; level.top.voxels()];
        if l + 1 == n {
            smooth(level, &mut x, &bs[l], COARSEST_SWEEPS, [0, 1], &mut scratch);
            smooth(level, &mut x, &bs[l], COARSEST_SWEEPS, [1, 0], &mut scratch);
            xs.push(x);
            break;
        }
        smooth(level, &mut x, &bs[l], SWEEPS, [0, 1], &mut scratch);
        // scratch = b − A x
        apply(level, &x, &mut scratch);
        each_brick(&mut scratch, |k, s| s.iter_mut().zip(&bs[l][k * VOXELS..(k + 1) * VOXELS]).for_each(|(s, b)| *s = b - *s));
        let mut coarse_b = vec![0.0; levels[l + 1].top.voxels()];
        restrict(&levels[l + 1], &scratch, &mut coarse_b);
        bs.push(coarse_b);
        xs.push(x);
    }
    for l in (0..n - 1).rev() {
        let (fine, coarse) = xs.split_at_mut(l + 1);
        prolong(&levels[l], &coarse[0], &mut fine[l]);
        let mut scratch = vec![0.0; levels[l].top.voxels()];
        smooth(&levels[l], &mut fine[l], &bs[l], SWEEPS, [1, 0], &mut scratch);
    }
    xs.swap_remove(0)
}
