//! Eigenfires training (thesis §4.2, eq. 12–17; weights eq. 18) by Turk and Pentland's M×M
//! trick, with the frames in memory; the decomposition and the weights are shared with the
//! out-of-core path ([`super::blocks`]).

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use rayon::prelude::*;

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

/// Pixel rows per task of the eigenfire lift.
pub(super) const LIFT_BAND_ROWS: usize = 1024;

/// `u = a · v` for a tall `a` (pixels × frames), split into bands of pixel rows that each rayon
/// task multiplies on its own. At the thesis size (274,700 × 2,197 times 2,197 × 1,100) this ran
/// 1.2–1.4× faster than handing the whole product to faer's parallel matmul, which splits the
/// work inside each block instead; every band reads its slice of `a` once and writes its rows
/// of `u` once. The same holds for reconstruction's `images += basis · weights`.
pub(super) fn lift(u: MatMut<'_, f32>, accum: Accum, a: MatRef<'_, f32>, v: MatRef<'_, f32>) {
    let mut bands = Vec::with_capacity(u.nrows().div_ceil(LIFT_BAND_ROWS));
    let mut rest = u;
    let mut r0 = 0;
    while rest.nrows() > 0 {
        let rows = LIFT_BAND_ROWS.min(rest.nrows());
        let (band, below) = rest.split_at_row_mut(rows);
        bands.push((r0, band));
        rest = below;
        r0 += rows;
    }
    bands.into_par_iter().for_each(|(r0, band)| {
        let rows = band.nrows();
        matmul(band, accum, a.subrows(r0, rows), v, 1.0, Par::Seq);
    });
}

/// Frees `data` on a short-lived thread: returning a few GB of centred frames to the system
/// takes ~0.1 ms per MB of page unmapping, which the caller need not wait for.
fn release_in_background(data: Vec<f32>) {
    // When no thread can be started, the closure and with it `data` are dropped right here.
    let _ = std::thread::Builder::new().name("pca-release".into()).spawn(move || drop(data));
}

/// `Σ x²` in f64, in eight independent partial sums (one running sum is a chain of dependent
/// additions that runs at a quarter of the speed and does not vectorize).
fn sum_of_squares(u: &[f32]) -> f64 {
    let mut acc = [0.0_f64; 8];
    let mut blocks = u.chunks_exact(8);
    for block in blocks.by_ref() {
        for (a, &x) in acc.iter_mut().zip(block) {
            *a += f64::from(x) * f64::from(x);
        }
    }
    let tail: f64 = blocks.remainder().iter().map(|&x| f64::from(x) * f64::from(x)).sum();
    acc.iter().sum::<f64>() + tail
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
    let mut mean = vec![0.0_f32; n];
    mean.par_chunks_mut(4096).enumerate().for_each(|(c, chunk)| {
        let p0 = c * 4096;
        let mut acc = vec![0.0_f64; chunk.len()];
        for f in 0..m {
            let col = &frames[f * n + p0..f * n + p0 + chunk.len()];
            acc.iter_mut().zip(col).for_each(|(a, &v)| *a += f64::from(v));
        }
        chunk.iter_mut().zip(&acc).for_each(|(o, a)| *o = (a / m as f64) as f32);
    });
    // Φ_n = I_n − Ψ, in place.
    frames.par_chunks_mut(n).for_each(|col| col.iter_mut().zip(&mean).for_each(|(v, &mu)| *v -= mu));

    // Eq. 16: L = AᵀA (M × M) as one f32 matrix product (as numpy's float32 gram-trick peer does;
    // faer's blocked kernels accumulate in registers, so the sum over N pixels stays accurate),
    // then widened to f64 for the eigen decomposition.
    // L is symmetric: only its lower triangle is computed (half the flops, as BLAS's syrk).
    let a = MatRef::from_column_major_slice(&frames, n, m);
    let mut gram32 = Mat::<f32>::zeros(m, m);
    triangular::matmul(
        gram32.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        a.transpose(),
        BlockStructure::Rectangular,
        a,
        BlockStructure::Rectangular,
        1.0,
        par(),
    );
    let gram = Mat::<f64>::from_fn(m, m, |i, j| f64::from(gram32[(i.max(j), i.min(j))]));
    drop(gram32);

    let dec = decompose(&gram, max_components)?;
    drop(gram);

    // Eq. 17: eigenfire_l = Σ_n V_ln Φ_n, normalised (eq. 14).
    let mut eigenvectors = vec![0.0_f32; n * dec.e];
    if dec.e > 0 {
        lift(MatMut::from_column_major_slice_mut(&mut eigenvectors, n, dec.e), Accum::Replace, a, dec.v_scaled.as_ref());
    }
    release_in_background(frames);
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
            u.iter_mut().for_each(|x| *x = (f64::from(*x) * inv) as f32);
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
