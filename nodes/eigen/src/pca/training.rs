//! Eigenfires training (thesis §4.2, eq. 12–17; weights eq. 18) by Turk and Pentland's M×M
//! trick, with the frames in memory; the decomposition and the weights are shared with the
//! out-of-core path ([`super::blocks`]).

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use rayon::prelude::*;

use super::simd::{accumulate, accumulate4, scale, subtract, sum_of_squares};
use crate::blas::{self, OpenBlas};
use crate::values::{Basis, FrameRef, Weights};

/// A trained Eigenfires database: the basis and the weights of its training frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Database {
    /// Mean, eigenfires, eigenvalues and frame sources.
    pub basis: Basis,
    /// Training frames × components (eq. 18 for every training frame).
    pub weights: Weights,
}

/// Eigenvalues of `L` below this fraction of the largest count as zero (not meaningful). `L` is
/// accumulated in f32 (relative precision ≈ 6e-8 per product sum), so anything under 1e-6 of the
/// largest is rounding noise, i.e. singular values under 1e-3 of the largest.
pub const RELATIVE_EIGENVALUE_FLOOR: f64 = 1e-6;

pub(crate) fn par() -> Par {
    Par::rayon(0)
}

/// `L = AᵀA` for the `m` columns of `a` (`n × m`, column-major), widened to f64. `L` is
/// symmetric: only its lower triangle is computed (half the flops, BLAS's `syrk`), by OpenBLAS
/// when the system has it, else by faer.
pub(super) fn gram_matrix(a: &[f32], n: usize, m: usize, blas: Option<&OpenBlas>) -> Mat<f64> {
    let mut lower = vec![0.0_f32; m * m];
    if !blas.is_some_and(|b| b.gram_lower(n, m, a, &mut lower)) {
        let a = MatRef::from_column_major_slice(a, n, m);
        triangular::matmul(
            MatMut::from_column_major_slice_mut(&mut lower, m, m),
            BlockStructure::TriangularLower,
            Accum::Replace,
            a.transpose(),
            BlockStructure::Rectangular,
            a,
            BlockStructure::Rectangular,
            1.0,
            par(),
        );
    }
    Mat::<f64>::from_fn(m, m, |i, j| f64::from(lower[i.max(j) + i.min(j) * m]))
}

/// `U = A · V` written over `A` itself (pixels × frames, column-major, `frames.len() = n·m`):
/// eigenfire `l` takes the place of frame `l`, and the returned buffer holds the first `e` of
/// them. Each band of pixel rows is multiplied into a small scratch matrix and then copied over
/// its own rows, which no other band reads, so the bands run in parallel. Writing over the
/// frames saves a fresh `n·e` buffer: at 500 frames of 205×335 and E 250 its 69 MB cost 40–60 ms
/// of page faults on one core, a third of the product itself, and the frames' pages need not be
/// returned and taken again. The first `e` columns are given back with a shrinking `realloc`
/// (a page remap for buffers this size, not a copy).
pub(super) fn lift_in_place(mut frames: Vec<f32>, n: usize, m: usize, v: MatRef<'_, f32>) -> Vec<f32> {
    let e = v.ncols();
    debug_assert_eq!((frames.len(), v.nrows()), (n * m, m));
    if e == 0 {
        return Vec::new();
    }
    let mut bands = Vec::with_capacity(n.div_ceil(IN_PLACE_BAND_ROWS));
    let mut rest = MatMut::from_column_major_slice_mut(&mut frames, n, m);
    while rest.nrows() > 0 {
        let rows = IN_PLACE_BAND_ROWS.min(rest.nrows());
        let (band, below) = rest.split_at_row_mut(rows);
        bands.push(band);
        rest = below;
    }
    bands.into_par_iter().for_each_init(
        || Mat::<f32>::zeros(IN_PLACE_BAND_ROWS, e),
        |scratch, band| {
            let rows = band.nrows();
            let mut out = scratch.as_mut().subrows_mut(0, rows);
            matmul(out.as_mut(), Accum::Replace, band.as_ref(), v, 1.0, Par::Seq);
            band.subcols_mut(0, e).copy_from(out.as_ref());
        },
    );
    frames.truncate(n * e);
    frames.shrink_to_fit();
    frames
}

/// Pixel rows per band of [`lift_in_place`]: its scratch (rows × E) stays in the L2 cache.
const IN_PLACE_BAND_ROWS: usize = 256;

/// The mean of `m` frames of `n` samples (eq. 12), accumulated in f64. Each task sums a run of
/// pixels over every frame, reading each frame's run front to back (the frames are streamed once,
/// in long contiguous reads that the prefetcher follows), into an accumulator that stays in cache.
fn mean_image(frames: &[f32], n: usize, m: usize) -> Vec<f32> {
    // One run per thread, at most 64 Ki pixels (its f64 accumulator, 512 KiB, stays in L2).
    let run = n.div_ceil(rayon::current_num_threads()).clamp(4096, 1 << 16);
    let mut mean = vec![0.0_f32; n];
    mean.par_chunks_mut(run).enumerate().for_each(|(c, chunk)| {
        let p0 = c * run;
        let mut acc = vec![0.0_f64; chunk.len()];
        let acc = &mut acc[..];
        let col = |f: usize| &frames[f * n + p0..f * n + p0 + chunk.len()];
        let mut f = 0;
        while f + 4 <= m {
            accumulate4(acc, [col(f), col(f + 1), col(f + 2), col(f + 3)]);
            f += 4;
        }
        for f in f..m {
            accumulate(acc, col(f));
        }
        chunk.iter_mut().zip(acc.iter()).for_each(|(o, a)| *o = (a / m as f64) as f32);
    });
    mean
}

/// Trains an Eigenfires basis (§4.2) on `frames`: `M = sources.len()` gray images of
/// `width × height`, frame `n` at `frames[n·N..(n+1)·N]`. `frames` is consumed (made mean-free in
/// place). Keeps every meaningful eigenfire (at most `M − 1`), or the first `max_components` when
/// that is non-zero. Training weights come from the decomposition itself (`ω_l(n) = √μ_l v_l(n)`),
/// which equals the projection of eq. 18.
pub fn train(
    width: u32,
    height: u32,
    mut frames: Vec<f32>,
    sources: Vec<FrameRef>,
    max_components: usize,
) -> Result<Database, String> {
    let (n, m) = database_shape(width, height, &sources)?;
    if frames.len() != n * m {
        return Err(format!("frame data holds {} samples, expected {m} frames of {n}", frames.len()));
    }

    // Eq. 12: the mean image, accumulated in f64.
    let mean = mean_image(&frames, n, m);
    // Φ_n = I_n − Ψ, in place.
    frames.par_chunks_mut(n).for_each(|col| subtract(col, &mean));

    // Eq. 16: L = AᵀA (M × M), accumulated in f32 as numpy's float32 gram-trick peer does (the
    // products' blocked kernels sum in registers, so the sum over N pixels stays accurate), then
    // widened to f64 for the eigen decomposition.
    let gram = gram_matrix(&frames, n, m, blas::openblas());
    let dec = decompose(&gram, max_components)?;
    drop(gram);

    // Eq. 17: eigenfire_l = Σ_n V_ln Φ_n, normalised (eq. 14), written over the frames.
    let eigenvectors = lift_in_place(frames, n, m, dec.v_scaled.as_ref());
    finish(width, height, mean, eigenvectors, &dec, sources)
}

/// Pixels per frame `N` and frames `M` of a database, checked: frames not empty, `M ≥ 2`.
pub(crate) fn database_shape(width: u32, height: u32, sources: &[FrameRef]) -> Result<(usize, usize), String> {
    let n = width as usize * height as usize;
    let m = sources.len();
    if n == 0 {
        return Err("the frames are empty (0 pixels)".into());
    }
    if m < 2 {
        return Err(format!("PCA needs at least 2 frames, got {m}"));
    }
    Ok((n, m))
}

/// The kept eigenpairs of the Gram matrix `L` (eq. 16).
pub(crate) struct Decomposition {
    /// Eigenfires kept, `E`.
    pub e: usize,
    /// Eigenvalues μ_l of `L`, descending.
    pub mus: Vec<f64>,
    /// `V_E Λ^{-1/2}` (`M × E`), the lift's right factor (eq. 17).
    pub v_scaled: Mat<f32>,
    /// `V_E`, eigenvector `l` at `[l·M..(l+1)·M]`.
    pub v_kept: Vec<f64>,
}

/// Eigen-decomposes the Gram matrix (its lower triangle is read), keeps every meaningful
/// eigenpair (or the first `max_components`), in descending order with a deterministic sign.
pub(crate) fn decompose(gram: &Mat<f64>, max_components: usize) -> Result<Decomposition, String> {
    let m = gram.nrows();
    let eig = gram.self_adjoint_eigen(Side::Lower).map_err(|e| format!("eigen decomposition failed: {e:?}"))?;
    let s = eig.S().column_vector();
    let v = eig.U();
    // Descending order; faer returns them ascending.
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&x, &y| s[y].total_cmp(&s[x]));
    let mu_max = s[order[0]];
    if mu_max.is_nan() || mu_max <= 0.0 {
        return Err("all frames are identical: there is no variation to analyse".into());
    }
    let available = order.iter().take(m - 1).filter(|&&i| s[i] > mu_max * RELATIVE_EIGENVALUE_FLOOR).count();
    let e = if max_components == 0 { available } else { max_components.min(available) };

    // Scaled eigenvectors V_E Λ^{-1/2}, with a deterministic sign (largest entry positive).
    let mut v_scaled = Mat::<f32>::zeros(m, e);
    let mut v_kept = vec![0.0_f64; m * e];
    let mut mus = Vec::with_capacity(e);
    for (l, &i) in order.iter().take(e).enumerate() {
        let mu = s[i];
        let col = v.col(i);
        let (mut big, mut sign) = (0.0_f64, 1.0_f64);
        for r in 0..m {
            if col[r].abs() > big {
                big = col[r].abs();
                sign = col[r].signum();
            }
        }
        for r in 0..m {
            let x = col[r] * sign;
            v_kept[l * m + r] = x;
            v_scaled[(r, l)] = (x / mu.sqrt()) as f32;
        }
        mus.push(mu);
    }

    Ok(Decomposition { e, mus, v_scaled, v_kept })
}

/// Normalises the lifted eigenfires (eq. 14) and forms the training weights
/// `ω_l(n) = u_lᵀ Φ_n = √μ_l v_l(n)` (eq. 18).
pub(crate) fn finish(
    width: u32,
    height: u32,
    mean: Vec<f32>,
    mut eigenvectors: Vec<f32>,
    dec: &Decomposition,
    sources: Vec<FrameRef>,
) -> Result<Database, String> {
    let n = width as usize * height as usize;
    let (m, e, mus, v_kept) = (sources.len(), dec.e, &dec.mus, &dec.v_kept);
    eigenvectors.par_chunks_mut(n).for_each(|u| {
        let norm = sum_of_squares(u).sqrt();
        if norm > 0.0 {
            // One division per eigenfire, not per pixel (f64 division is 4–5× a multiply).
            let inv = 1.0 / norm;
            scale(u, inv);
        }
    });

    // Training weights ω_l(n) = u_lᵀ Φ_n = √μ_l v_l(n).
    let mut weights = vec![0.0_f32; m * e];
    for (row, w) in weights.chunks_mut(e.max(1)).enumerate().take(m) {
        for l in 0..e {
            w[l] = (mus[l].sqrt() * v_kept[l * m + row]) as f32;
        }
    }
    let eigenvalues = mus.iter().map(|mu| mu / m as f64).collect();
    let basis = Basis { width, height, mean, eigenvectors, eigenvalues, sources };
    let weights = Weights::new(m, e, weights).ok_or("weights size mismatch")?;
    Ok(Database { basis, weights })
}
