//! Projection into fire space (thesis §4.3, eq. 18) and reconstruction from weights (§4.8,
//! eq. 22), each as one matrix product over many frames.

use faer::linalg::matmul::matmul;
use faer::reborrow::ReborrowMut;
use faer::{Accum, ColRef, MatMut, MatRef, Par};
use rayon::prelude::*;

use super::training::par;
use crate::blas::{self, OpenBlas};
use crate::pages;
use crate::values::{Basis, Weights};

/// Eq. 18 for many frames at once: the weights `Ωᵀ = U_Eᵀ (I − Ψ)` of the frames in `frames`
/// (`F` images of the basis size, one after another), with the first `e` eigenfires.
/// Returns `F × e` row-major weights.
pub fn project(basis: &Basis, frames: &[f32], e: usize) -> Result<Weights, String> {
    let n = basis.pixels();
    if e > basis.components() {
        return Err(format!("{e} components asked, the basis has {}", basis.components()));
    }
    if n == 0 || !frames.len().is_multiple_of(n) {
        return Err(format!("frame data of {} samples is not a whole number of {n}-sample frames", frames.len()));
    }
    let f = frames.len() / n;
    let mut phi = frames.to_vec();
    phi.par_chunks_mut(n).for_each(|col| col.iter_mut().zip(&basis.mean).for_each(|(v, &mu)| *v -= mu));
    let mut out = vec![0.0_f32; f * e];
    if e > 0 && f > 0 {
        let u = MatRef::from_column_major_slice(&basis.eigenvectors[..n * e], n, e);
        let phi = MatRef::from_column_major_slice(&phi, n, f);
        let dst = MatMut::from_column_major_slice_mut(&mut out, e, f);
        matmul(dst, Accum::Replace, u.transpose(), phi, 1.0, par());
    }
    Weights::new(f, e, out).ok_or_else(|| "weights size mismatch".to_string())
}

/// Eq. 22 for many frames as one matrix product: `I = U_E Ω + Ψ` for every row of `weights`,
/// using its first `e` columns. Returns the images' samples one after another (`rows × N`).
pub fn reconstruct(basis: &Basis, weights: &Weights, e: usize) -> Result<Vec<f32>, String> {
    if e > basis.components() || e > weights.components {
        return Err(format!("{e} components asked; the basis has {} and the weights {}", basis.components(), weights.components));
    }
    reconstruct_with(basis, weights, e, blas::openblas())
}

/// [`reconstruct`] with the product by OpenBLAS when given, else by faer.
pub(super) fn reconstruct_with(basis: &Basis, weights: &Weights, e: usize, blas: Option<&OpenBlas>) -> Result<Vec<f32>, String> {
    let n = basis.pixels();
    let f = weights.frames;
    if e == 0 || f == 0 {
        return Ok(basis.mean.repeat(f));
    }
    let u = &basis.eigenvectors[..n * e];
    if let Some(blas) = blas {
        let mut out = pages::repeat_huge(&basis.mean, f);
        if blas.gemm_add(u, e, &weights.data, weights.components, f, &mut out) {
            return Ok(out);
        }
    }
    // Zeroed pages from the system, each first written by the band that owns it.
    let mut out = vec![0.0_f32; n * f];
    let u = MatRef::from_column_major_slice(u, n, e);
    let w = MatRef::from_column_major_slice(&weights.data, weights.components, f).subrows(0, e);
    lift_onto(MatMut::from_column_major_slice_mut(&mut out, n, f), &basis.mean, u, w);
    Ok(out)
}

/// Pixel rows per task of [`lift_onto`].
pub(super) const LIFT_BAND_ROWS: usize = 256;

/// `out = base + a · v` (`base` added to every column) for a tall `a` (pixels × E), split into
/// bands of pixel rows that each rayon task fills with `base` and multiplies into on its own.
/// At the thesis size (274,700 × 1,100 times 1,100 × 64) bands of 256 rows ran 10 % faster than
/// 1,024 and than one faer product over the whole (which splits the work inside each block
/// instead); every band reads its slice of `a` once and writes its rows of `out` while they
/// are in cache, where filling the whole output with the mean first costs a pass over it.
pub(super) fn lift_onto(out: MatMut<'_, f32>, base: &[f32], a: MatRef<'_, f32>, v: MatRef<'_, f32>) {
    let mut bands = Vec::with_capacity(out.nrows().div_ceil(LIFT_BAND_ROWS));
    let mut rest = out;
    let mut r0 = 0;
    while rest.nrows() > 0 {
        let rows = LIFT_BAND_ROWS.min(rest.nrows());
        let (band, below) = rest.split_at_row_mut(rows);
        bands.push((r0, band));
        rest = below;
        r0 += rows;
    }
    bands.into_par_iter().for_each(|(r0, mut band)| {
        let rows = band.nrows();
        let base = ColRef::from_slice(&base[r0..r0 + rows]);
        for j in 0..band.ncols() {
            band.rb_mut().col_mut(j).copy_from(base);
        }
        matmul(band, Accum::Add, a.subrows(r0, rows), v, 1.0, Par::Seq);
    });
}
