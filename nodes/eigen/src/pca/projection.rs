//! Projection into fire space (thesis §4.3, eq. 18) and reconstruction from weights (§4.8,
//! eq. 22), each as one matrix product over many frames.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef};
use rayon::prelude::*;

use super::training::{lift, par};
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
    let n = basis.pixels();
    if e > basis.components() || e > weights.components {
        return Err(format!("{e} components asked; the basis has {} and the weights {}", basis.components(), weights.components));
    }
    let f = weights.frames;
    let mut out: Vec<f32> = Vec::with_capacity(n * f);
    for _ in 0..f {
        out.extend_from_slice(&basis.mean);
    }
    if e > 0 && f > 0 {
        let u = MatRef::from_column_major_slice(&basis.eigenvectors[..n * e], n, e);
        let w = MatRef::from_column_major_slice(&weights.data, weights.components, f).subrows(0, e);
        let dst = MatMut::from_column_major_slice_mut(&mut out, n, f);
        lift(dst, Accum::Add, u, w);
    }
    Ok(out)
}
