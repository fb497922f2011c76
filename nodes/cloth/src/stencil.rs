//! The grid stencil of the mass-spring flames (mass-spring flame project 2019 §Internal Forces,
//! §Integration): on a `width × height` grid every spring family (horizontal, vertical, the two
//! shear diagonals, the two bend spans) joins mass `i` to mass `i + offset`, so the forces of a
//! family are one straight loop over contiguous slices (`pos[i]` against `pos[i + offset]`) that
//! the compiler vectorizes, with no index lists, no gathers and no branches; the few springs that
//! would wrap around a row edge are cut afterwards. Each flame's masses (a few KB) stay in the L1
//! cache for all the sub-steps of a call, and the scratch arrays are per thread, so a step
//! allocates nothing.

use std::cell::RefCell;

use glam::Vec3;

/// Below this length a spring's direction is taken from a vector this long (no division by zero).
const MIN_LENGTH: f32 = 1e-12;

/// One family of equal springs in a grid: mass `i` (row-major, `width` masses per row) joined to
/// mass `i + offset` for every `i < masses − offset`, except the `cut` ones whose far end would
/// leave the row.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringFamily {
    /// Index distance between the two ends, `rows · width + cols`.
    pub offset: usize,
    /// Rest length of the spring starting at each mass (measured from the rest positions, so a
    /// cloth at rest feels exactly no force); 0 for cut springs.
    pub rest: Vec<f32>,
    /// `k · rest` of each spring as the kernel computes it (`(k·|d|²)·(1/|d|)`), so that a
    /// spring at rest gives exactly zero force; 0 for cut springs.
    pub kr: Vec<f32>,
    /// Starting masses of the springs that wrap around a row edge and are not springs at all.
    pub cut: Vec<u32>,
    /// Spring constant.
    pub k: f32,
    /// Damping along the spring.
    pub c: f32,
}

impl SpringFamily {
    /// Whether the spring from mass `i` exists (is not cut).
    pub fn contains(&self, i: usize) -> bool {
        i < self.rest.len() && self.cut.binary_search(&(i as u32)).is_err()
    }
}

/// The springs of a `width × height` grid cloth as families of offsets; the bottom row (the first
/// `width` masses) is pinned.
#[derive(Clone, Debug, PartialEq)]
pub struct GridStencil {
    /// Masses per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The spring families.
    pub families: Vec<SpringFamily>,
}

impl GridStencil {
    /// An empty stencil for a `width × height` grid.
    pub fn new(width: usize, height: usize) -> Self {
        GridStencil { width, height, families: Vec::new() }
    }

    /// Number of masses.
    pub fn masses(&self) -> usize {
        self.width * self.height
    }

    /// Adds the family of springs from `(row, col)` to `(row + rows, col + cols)` with constant `k`
    /// and damping `c`, rest lengths measured on `rest` (one array per axis, row-major). A family
    /// that does not fit the grid adds nothing.
    pub fn add_family(&mut self, rows: usize, cols: isize, k: f32, c: f32, rest: &[Vec<f32>; 3]) {
        let (w, n) = (self.width, self.masses());
        let offset = rows * w;
        let Some(offset) = offset.checked_add_signed(cols) else { return };
        if offset == 0 || offset >= n || cols.unsigned_abs() >= w || rest.iter().any(|r| r.len() != n) {
            return;
        }
        let m = n - offset;
        let (mut lengths, mut kr) = (vec![0.0f32; m], vec![0.0f32; m]);
        let mut cut = Vec::new();
        for i in 0..m {
            let col = (i % w) as isize + cols;
            if col < 0 || col >= w as isize {
                cut.push(i as u32);
                continue;
            }
            let j = i + offset;
            let (dx, dy, dz) = (rest[0][j] - rest[0][i], rest[1][j] - rest[1][i], rest[2][j] - rest[2][i]);
            let (l2, inv) = squared_and_inverse(dx * dx + dy * dy + dz * dz);
            lengths[i] = l2 * inv;
            kr[i] = (k * l2) * inv;
        }
        self.families.push(SpringFamily { offset, rest: lengths, kr, cut, k, c });
    }
}

/// Per-thread scratch of the kernel: forces, and per family the force of the spring starting at
/// each mass, `offset` places in (reused, so no step allocates).
#[derive(Debug, Default)]
pub struct Scratch {
    f: [Vec<f32>; 3],
    g: Vec<[Vec<f32>; 3]>,
}

impl Scratch {
    /// Sizes the arrays for `st`: `g` of a family with offset `o` holds `n + o` values, the spring
    /// starting at mass `j` at `o + j`, zeros before (`[0, o)`: no spring ends below the grid) and
    /// after (`[n, n + o)`: none starts past its end).
    fn fit(&mut self, st: &GridStencil) {
        let n = st.masses();
        for v in &mut self.f {
            v.resize(n, 0.0);
        }
        self.g.resize_with(st.families.len(), Default::default);
        for (g, fam) in self.g.iter_mut().zip(&st.families) {
            let o = fam.offset;
            for v in g.iter_mut() {
                v.resize(n + o, 0.0);
                v[..o].fill(0.0);
                v[n..].fill(0.0);
            }
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Runs `f` with this thread's scratch (a fresh one if it is already in use).
pub fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => f(&mut s),
        Err(_) => f(&mut Scratch::default()),
    })
}

/// Constants of one call to [`advance`].
#[derive(Clone, Copy, Debug)]
pub struct StepConsts {
    /// Mass of every mass point.
    pub mass: f32,
    /// Air drag.
    pub drag: f32,
    /// Sub-step length in seconds.
    pub h: f32,
    /// Number of sub-steps.
    pub steps: usize,
    /// Time of the first sub-step in seconds.
    pub t0: f64,
}

/// Advances one flame `c.steps` semi-implicit Euler sub-steps on the stencil `st` (§Integration
/// eq. 1–3): forces of every spring family (Hooke plus a damper along the spring, §Internal
/// Forces eq. 4), `external(t)` and drag on every mass; then `v += f/m·h`, `x += v·h` for every
/// mass above the pinned bottom row. Returns whether the positions are all finite afterwards
/// (a non-finite velocity makes its position non-finite); `false`, with nothing done, when the
/// arrays do not match the stencil.
pub fn advance(
    st: &GridStencil,
    pos: &mut [Vec<f32>; 3],
    vel: &mut [Vec<f32>; 3],
    scratch: &mut Scratch,
    c: StepConsts,
    external: &dyn Fn(f64) -> Vec3,
) -> bool {
    let n = st.masses();
    let fits = |f: &SpringFamily| f.offset > 0 && f.offset + f.kr.len() == n;
    if pos.iter().chain(vel.iter()).any(|a| a.len() != n)
        || !st.families.iter().all(fits)
        || st.width > n
        || st.families.len() > MAX_FAMILIES
    {
        return false;
    }
    scratch.fit(st);
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above; the function only lets the compiler
        // vectorize safe code with it.
        return unsafe { advance_avx2(st, pos, vel, scratch, c, external) };
    }
    advance_generic(st, pos, vel, scratch, c, external)
}

/// [`advance_generic`] compiled for AVX2 (8 lanes of f32). Results are bit-identical to the
/// baseline build: the kernel has no fused multiply-adds and no library calls.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn advance_avx2(
    st: &GridStencil,
    pos: &mut [Vec<f32>; 3],
    vel: &mut [Vec<f32>; 3],
    scratch: &mut Scratch,
    c: StepConsts,
    external: &dyn Fn(f64) -> Vec3,
) -> bool {
    advance_generic(st, pos, vel, scratch, c, external)
}

/// `1/√x` for `x > 0` in plain float and integer operations that vectorize (no square root, no
/// division): the classic bit-level first guess and two Newton steps, within a few ulps.
#[inline(always)]
pub fn inv_sqrt(x: f32) -> f32 {
    let y = f32::from_bits(0x5f37_5a86u32.wrapping_sub(x.to_bits() >> 1));
    let hx = 0.5 * x;
    let y = y * (1.5 - hx * y * y);
    y * (1.5 - hx * y * y)
}

/// The squared length of a spring vector (kept above `MIN_LENGTH²`) and its inverse length,
/// exactly as the kernel computes them (the rest terms are measured with it, so a cloth at rest
/// feels exactly no force).
#[inline(always)]
pub fn squared_and_inverse(l2: f32) -> (f32, f32) {
    let l2 = if l2 > MIN_LENGTH * MIN_LENGTH { l2 } else { MIN_LENGTH * MIN_LENGTH };
    (l2, inv_sqrt(l2))
}

/// The flame's arrays for one sub-step, sliced to the stencil's size.
struct Flame<'a> {
    p: [&'a mut [f32]; 3],
    v: [&'a mut [f32]; 3],
}

/// Pass 1 of a sub-step: every spring's force from the old state, family by family, into `g`
/// (`Z`: with the z axis; without it the flame is planar, z = 0 everywhere, and stays so).
#[inline(always)]
fn spring_forces<const Z: bool>(st: &GridStencil, fl: &Flame<'_>, g: &mut [[Vec<f32>; 3]]) {
    let [px, py, pz] = &fl.p;
    let [vx, vy, vz] = &fl.v;
    for (fam, [gx, gy, gz]) in st.families.iter().zip(g.iter_mut()) {
        let (o, m) = (fam.offset, fam.kr.len());
        let (k, damp) = (fam.k, fam.c);
        let kr = &fam.kr[..m];
        let (ax, bx, ay, by) = (&px[..m], &px[o..o + m], &py[..m], &py[o..o + m]);
        let (avx, bvx, avy, bvy) = (&vx[..m], &vx[o..o + m], &vy[..m], &vy[o..o + m]);
        let (gx, gy) = (&mut gx[o..o + m], &mut gy[o..o + m]);
        if Z {
            let (az, bz, avz, bvz) = (&pz[..m], &pz[o..o + m], &vz[..m], &vz[o..o + m]);
            let gz = &mut gz[o..o + m];
            for j in 0..m {
                let (dx, dy, dz) = (bx[j] - ax[j], by[j] - ay[j], bz[j] - az[j]);
                let (l2, inv) = squared_and_inverse(dx * dx + dy * dy + dz * dz);
                let dvd = (bvx[j] - avx[j]) * dx + (bvy[j] - avy[j]) * dy + (bvz[j] - avz[j]) * dz;
                // Hooke's law f = −k·Δl (Equation 4) plus a damper along the spring, times the unit
                // direction: s·d = (k·(|d| − rest) + c·(Δv·d)/|d|)·d/|d|, with k·rest as `kr`.
                let s = inv * ((k * l2 + damp * dvd) * inv - kr[j]);
                gx[j] = s * dx;
                gy[j] = s * dy;
                gz[j] = s * dz;
            }
        } else {
            for j in 0..m {
                let (dx, dy) = (bx[j] - ax[j], by[j] - ay[j]);
                let (l2, inv) = squared_and_inverse(dx * dx + dy * dy);
                let dvd = (bvx[j] - avx[j]) * dx + (bvy[j] - avy[j]) * dy;
                let s = inv * ((k * l2 + damp * dvd) * inv - kr[j]);
                gx[j] = s * dx;
                gy[j] = s * dy;
            }
        }
        for &j in &fam.cut {
            let j = j as usize;
            if j < m {
                (gx[j], gy[j]) = (0.0, 0.0);
                if Z {
                    gz[o + j] = 0.0;
                }
            }
        }
    }
}

/// Pass 2 of a sub-step on one axis: each mass gathers the springs starting at it (+g) and
/// ending at it (−g), plus external force `e` and drag; then the semi-implicit Euler update of
/// every mass from `free` on.
#[inline(always)]
fn gather_and_move(p: &mut [f32], v: &mut [f32], f: &mut [f32], g: &[&[f32]], offsets: &[usize], m: AxisMotion) {
    match (g, offsets) {
        // The structural cloth; with shear; with shear and bend: one fused loop, the families'
        // terms added in the same order as below, so the same result without a pass over `f`
        // per family (measured: the per-family passes were 8 % of a 144-flame cloth frame).
        ([a, b], [oa, ob]) => move_fused(p, v, [a, b], [*oa, *ob], m),
        ([a, b, c, d], [oa, ob, oc, od]) => move_fused(p, v, [a, b, c, d], [*oa, *ob, *oc, *od], m),
        ([a, b, c, d, e, f], [oa, ob, oc, od, oe, of]) => move_fused(p, v, [a, b, c, d, e, f], [*oa, *ob, *oc, *od, *oe, *of], m),
        _ => move_by_passes(p, v, f, g, offsets, m),
    }
}

/// [`gather_and_move`] for `K` families in one loop over the masses.
#[inline(always)]
fn move_fused<const K: usize>(p: &mut [f32], v: &mut [f32], g: [&[f32]; K], offsets: [usize; K], m: AxisMotion) {
    let AxisMotion { e, drag, kick, h, free } = m;
    let n = p.len();
    let v = &mut v[..n];
    let starts: [&[f32]; K] = std::array::from_fn(|k| &g[k][..n]);
    let ends: [&[f32]; K] = std::array::from_fn(|k| &g[k][offsets[k]..offsets[k] + n]);
    for i in free..n {
        let mut fi = e - drag * v[i];
        for k in 0..K {
            fi += ends[k][i] - starts[k][i];
        }
        v[i] += fi * kick;
        p[i] += v[i] * h;
    }
}

/// [`gather_and_move`] for any number of families: the forces summed into `f` a family at a time.
#[inline(always)]
fn move_by_passes(p: &mut [f32], v: &mut [f32], f: &mut [f32], g: &[&[f32]], offsets: &[usize], m: AxisMotion) {
    let AxisMotion { e, drag, kick, h, free } = m;
    let n = p.len();
    let (v, f) = (&mut v[..n], &mut f[..n]);
    for i in 0..n {
        f[i] = e - drag * v[i];
    }
    for (g, &o) in g.iter().zip(offsets) {
        let (g0, g1) = (&g[..n], &g[o..o + n]);
        for i in 0..n {
            f[i] += g1[i] - g0[i];
        }
    }
    for i in free..n {
        v[i] += f[i] * kick;
        p[i] += v[i] * h;
    }
}

/// The per-axis constants of one semi-implicit Euler sub-step.
#[derive(Clone, Copy)]
struct AxisMotion {
    /// External force on this axis.
    e: f32,
    drag: f32,
    /// h / mass.
    kick: f32,
    h: f32,
    /// First mass that moves (the pinned bottom row comes before it).
    free: usize,
}

/// Most spring families a stencil has (structural, shear, bend: 6).
const MAX_FAMILIES: usize = 8;

#[inline(always)]
fn advance_generic(
    st: &GridStencil,
    pos: &mut [Vec<f32>; 3],
    vel: &mut [Vec<f32>; 3],
    scratch: &mut Scratch,
    c: StepConsts,
    external: &dyn Fn(f64) -> Vec3,
) -> bool {
    let n = st.masses();
    let [px, py, pz] = pos;
    let [vx, vy, vz] = vel;
    let fl = Flame { p: [&mut px[..n], &mut py[..n], &mut pz[..n]], v: [&mut vx[..n], &mut vy[..n], &mut vz[..n]] };
    let Scratch { f, g } = scratch;
    let (drag, h) = (c.drag, c.h);
    let kick = h / c.mass;
    // The bottom row [0, width) is pinned: only the masses from `free` on move.
    let free = st.width;
    let fams = st.families.len();
    let mut offsets = [0usize; MAX_FAMILIES];
    for (o, fam) in offsets.iter_mut().zip(&st.families) {
        *o = fam.offset;
    }
    let offsets = &offsets[..fams.min(MAX_FAMILIES)];
    // A flame with z = 0 and no z velocity anywhere stays in its plane while the external force
    // has no z part (every z force is proportional to a z difference, a z velocity or e.z):
    // it is stepped in 2-D, with the same results.
    let flat = |a: &[f32]| a.iter().fold(true, |ok, &x| ok & (x == 0.0));
    let mut planar = flat(fl.p[2]) && flat(fl.v[2]);
    for step in 0..c.steps {
        let e = external(c.t0 + step as f64 * h as f64);
        planar &= e.z == 0.0;
        if planar {
            spring_forces::<false>(st, &fl, g);
        } else {
            spring_forces::<true>(st, &fl, g);
        }
        let axes = if planar { 2 } else { 3 };
        for axis in 0..axes {
            let mut ga: [&[f32]; MAX_FAMILIES] = [&[]; MAX_FAMILIES];
            for (slot, gf) in ga.iter_mut().zip(g.iter()) {
                *slot = &gf[axis];
            }
            let (p, v) = (&mut *fl.p[axis], &mut *fl.v[axis]);
            let m = AxisMotion { e: e[axis], drag, kick, h, free };
            gather_and_move(p, v, &mut f[axis], &ga[..offsets.len()], offsets, m);
        }
    }
    finite_positions(&fl.p[0][..], &fl.p[1][..], &fl.p[2][..])
}

#[inline(always)]
fn finite_positions(px: &[f32], py: &[f32], pz: &[f32]) -> bool {
    let finite = |a: &[f32]| a.iter().fold(true, |ok, x| ok & x.is_finite());
    finite(px) & finite(py) & finite(pz)
}

#[cfg(test)]
mod tests {
    use super::*;

    const WIDTH: usize = 16;
    const MASSES: usize = 16 * 32;

    /// A value in `[-0.5, 0.5)`.
    fn centred(state: &mut u64) -> f32 {
        pyrograph_testing::lcg(state) - 0.5
    }

    /// A random axis state for `families` spring families: offsets, spring forces, p, v.
    fn random_axis(families: usize, seed: u64) -> (Vec<usize>, Vec<Vec<f32>>, Vec<f32>, Vec<f32>) {
        let mut s = seed;
        let offsets = [1, WIDTH, WIDTH + 1, WIDTH - 1, 2, 2 * WIDTH][..families].to_vec();
        let g = offsets.iter().map(|o| (0..MASSES + o).map(|_| centred(&mut s)).collect()).collect();
        let (p, v) = (0..MASSES).map(|_| (centred(&mut s), centred(&mut s))).unzip();
        (offsets, g, p, v)
    }

    /// One axis of a sub-step from `random_axis(families, seed)`, by `gather_and_move` (fused
    /// where it can) and by one pass per family: (p, v) bits of each, then of the start.
    fn both_forms(families: usize, seed: u64) -> [(Vec<u32>, Vec<u32>); 3] {
        let (offsets, g, p0, v0) = random_axis(families, seed);
        let m = AxisMotion { e: 0.3, drag: 0.05, kick: 1.0 / 600.0, h: 1.0 / 600.0, free: WIDTH };
        let g: Vec<&[f32]> = g.iter().map(Vec::as_slice).collect();
        let bits = |p: &[f32], v: &[f32]| (p.iter().map(|x| x.to_bits()).collect(), v.iter().map(|x| x.to_bits()).collect());
        let (mut p, mut v, mut f) = (p0.clone(), v0.clone(), vec![0.0; MASSES]);
        gather_and_move(&mut p, &mut v, &mut f, &g, &offsets, m);
        let fused = bits(&p, &v);
        let (mut p, mut v) = (p0.clone(), v0.clone());
        move_by_passes(&mut p, &mut v, &mut f, &g, &offsets, m);
        [fused, bits(&p, &v), bits(&p0, &v0)]
    }

    #[test]
    fn the_fused_gather_moves_masses_bit_identically_to_one_pass_per_family() {
        for families in [2, 4, 6] {
            for seed in 0..5 {
                let [fused, passes, _] = both_forms(families, seed);
                assert!(fused == passes, "{families} families, seed {seed}");
            }
        }
    }

    #[test]
    fn the_pinned_row_stays_and_the_rest_moves_in_either_form() {
        for families in [2, 3, 4, 6] {
            let [fused, passes, (p0, v0)] = both_forms(families, 9);
            for (form, (p, v)) in [("fused", fused), ("passes", passes)] {
                assert_eq!(p[..WIDTH], p0[..WIDTH], "{families} families, {form}: pinned positions");
                assert_eq!(v[..WIDTH], v0[..WIDTH], "{families} families, {form}: pinned velocities");
                assert!(
                    p[WIDTH..].iter().zip(&p0[WIDTH..]).all(|(a, b)| a != b),
                    "{families} families, {form}: free masses move"
                );
            }
        }
    }
}
