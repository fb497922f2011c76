//! Out-of-core Eigenfires training: the PCA of [`pca::train`](crate::pca::train) with at most two
//! blocks of frames in memory, for databases larger than memory (issue 23: 10,000 frames of
//! 410×670 are 11 GB as f32).
//!
//! The M×M trick needs the frames only through products: the mean (eq. 12) is a sum over frames,
//! the Gram matrix `L = AᵀA` (eq. 16) is assembled from the block products `A_aᵀ A_b`, and the
//! eigenfires `U = A V Λ^{-1/2}` (eq. 17) are a sum over blocks of `A_b V_b`. So the frames are
//! read block by block: once for the mean, `B(B+1)/2` block pairs for `L` (B blocks, each block
//! held while the later ones stream past it), once more for the lift. The eigen decomposition and
//! the weights are shared with the in-memory path. Given a scratch folder, the first pass keeps
//! the frames in a [`FrameStore`] and the later passes read them from there instead of decoding or
//! cooking them again.

use std::ops::Range;
use std::path::Path;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef};
use rayon::prelude::*;

use super::training::{Database, database_shape, decompose, finish, par};
use crate::frame_store::FrameStore;
use crate::values::FrameRef;

/// Fills the buffer with frames `range` of the database, one `N`-sample gray frame after another.
pub type ReadFrames<'a> = dyn Fn(Range<usize>, &mut [f32]) -> Result<(), String> + Sync + 'a;

/// Where [`train_blocks`] gets its frames and reports how far it is.
pub struct BlockSource<'a> {
    /// Reads frames from their origin (the clips).
    pub read: &'a ReadFrames<'a>,
    /// A folder for the scratch [`FrameStore`]; `None` reads every pass from `read`. When the
    /// store cannot be created or written (no room), the passes read from `read` instead: the
    /// same frames, only slower.
    pub scratch: Option<&'a Path>,
    /// Called with (frames read so far, frames to read over all passes).
    pub progress: &'a (dyn Fn(usize, usize) + Sync + 'a),
}

/// Trains an Eigenfires basis from frames read through `source`, `block` frames at a time (at
/// most `2·block·N` samples in memory besides the eigenfires). Same results as
/// [`pca::train`](crate::pca::train) up to rounding.
pub fn train_blocks(
    width: u32,
    height: u32,
    sources: Vec<FrameRef>,
    max_components: usize,
    block: usize,
    source: &BlockSource<'_>,
) -> Result<Database, String> {
    let (n, m) = database_shape(width, height, &sources)?;
    let block = block.clamp(1, m);
    let blocks: Vec<Range<usize>> = (0..m).step_by(block).map(|s| s..(s + block).min(m)).collect();
    let mut here = vec![0.0_f32; block * n];
    let mut there = vec![0.0_f32; block * n];
    // Frames read over all passes: the mean, each block with the blocks after it, the lift.
    let total = 2 * m + blocks.iter().map(|ra| ra.len() + (m - ra.end)).sum::<usize>();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = |frames: usize| {
        let now = done.fetch_add(frames, std::sync::atomic::Ordering::Relaxed) + frames;
        (source.progress)(now, total);
    };
    let mut store = source.scratch.and_then(|dir| FrameStore::new(dir, n).ok());

    // Eq. 12: the mean image, accumulated in f64 over the blocks.
    let mut acc = vec![0.0_f64; n];
    for r in &blocks {
        let frames = &mut here[..r.len() * n];
        (source.read)(r.clone(), frames)?;
        if store.as_ref().is_some_and(|s| s.write(r.clone(), frames).is_err()) {
            store = None;
        }
        tick(r.len());
        let frames = &*frames;
        acc.par_chunks_mut(4096).enumerate().for_each(|(c, chunk)| {
            let p0 = c * 4096;
            for f in 0..r.len() {
                let col = &frames[f * n + p0..f * n + p0 + chunk.len()];
                chunk.iter_mut().zip(col).for_each(|(a, &v)| *a += f64::from(v));
            }
        });
    }
    let mean: Vec<f32> = acc.iter().map(|a| (a / m as f64) as f32).collect();
    drop(acc);
    let centred = |r: &Range<usize>, out: &mut [f32]| -> Result<(), String> {
        match &store {
            // A store that fails to read back falls back to the origin: the same frames.
            Some(s) => s.read(r.clone(), out).or_else(|_| (source.read)(r.clone(), out))?,
            None => (source.read)(r.clone(), out)?,
        }
        tick(r.len());
        out.par_chunks_mut(n).for_each(|col| col.iter_mut().zip(&mean).for_each(|(v, &mu)| *v -= mu));
        Ok(())
    };

    // Eq. 16: L = AᵀA from the block products A_aᵀ A_b (b ≥ a; L is symmetric).
    let mut gram = Mat::<f64>::zeros(m, m);
    for (ia, ra) in blocks.iter().enumerate() {
        let la = ra.len();
        centred(ra, &mut here[..la * n])?;
        let a = MatRef::from_column_major_slice(&here[..la * n], n, la);
        for rb in &blocks[ia..] {
            let lb = rb.len();
            let b = if rb == ra {
                a
            } else {
                centred(rb, &mut there[..lb * n])?;
                MatRef::from_column_major_slice(&there[..lb * n], n, lb)
            };
            let mut g = Mat::<f32>::zeros(la, lb);
            matmul(g.as_mut(), Accum::Replace, a.transpose(), b, 1.0, par());
            for i in 0..la {
                for j in 0..lb {
                    let v = f64::from(g[(i, j)]);
                    gram[(ra.start + i, rb.start + j)] = v;
                    gram[(rb.start + j, ra.start + i)] = v;
                }
            }
        }
    }
    // The eigen decomposition of an M × M matrix needs about three of them (M = 10,000: 2.4 GB);
    // the blocks are given back first and taken again for the lift.
    drop((here, there));
    let dec = decompose(&gram, max_components)?;
    drop(gram);

    // Eq. 17: U = Σ_b A_b V_b Λ^{-1/2}, one block at a time.
    let mut here = vec![0.0_f32; block * n];
    let mut eigenvectors = vec![0.0_f32; n * dec.e];
    if dec.e > 0 {
        for r in &blocks {
            let lb = r.len();
            centred(r, &mut here[..lb * n])?;
            let a = MatRef::from_column_major_slice(&here[..lb * n], n, lb);
            let v = dec.v_scaled.as_ref().subrows(r.start, lb);
            let dst = MatMut::from_column_major_slice_mut(&mut eigenvectors, n, dec.e);
            matmul(dst, Accum::Add, a, v, 1.0, par());
        }
    }
    drop(here);
    finish(width, height, mean, eigenvectors, &dec, sources)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pca::tests::{random_frames, sources};
    use crate::pca::train;

    fn blockwise(w: u32, h: u32, frames: &[f32], m: usize, max: usize, block: usize) -> Database {
        let n = w as usize * h as usize;
        let read = |r: Range<usize>, out: &mut [f32]| -> Result<(), String> {
            out.copy_from_slice(&frames[r.start * n..r.end * n]);
            Ok(())
        };
        train_blocks(w, h, sources(m), max, block, &BlockSource { read: &read, scratch: None, progress: &|_, _| {} }).unwrap()
    }

    /// Trains with a scratch folder; returns the database, the frames read from the origin and the
    /// last progress report.
    fn with_store(frames: &[f32], m: usize, block: usize, scratch: &Path) -> (Database, usize, (usize, usize)) {
        let (w, h) = (7, 5);
        let n = 35;
        let reads = std::sync::atomic::AtomicUsize::new(0);
        let read = |r: Range<usize>, out: &mut [f32]| -> Result<(), String> {
            reads.fetch_add(r.len(), std::sync::atomic::Ordering::Relaxed);
            out.copy_from_slice(&frames[r.start * n..r.end * n]);
            Ok(())
        };
        let last = std::sync::Mutex::new((0, 0));
        let progress = |done: usize, total: usize| *last.lock().unwrap() = (done, total);
        let source = BlockSource { read: &read, scratch: Some(scratch), progress: &progress };
        let db = train_blocks(w, h, sources(m), 0, block, &source).unwrap();
        let last = *last.lock().unwrap();
        (db, reads.into_inner(), last)
    }

    #[test]
    fn a_scratch_store_reads_each_frame_once_and_changes_nothing() {
        let m = 17;
        let frames = random_frames(7, 5, m, 3);
        let plain = blockwise(7, 5, &frames, m, 0, 4);
        let dir = tempfile::tempdir().unwrap();
        let (stored, reads, (done, total)) = with_store(&frames, m, 4, dir.path());
        assert_eq!(stored, plain, "the same frames give the same database, bit for bit");
        assert_eq!(reads, m, "the origin is read once, by the first pass");
        // 5 blocks (4, 4, 4, 4, 1): mean 17; Gram, each block with the frames after it,
        // 17 + 13 + 9 + 5 + 1; lift 17.
        assert_eq!((done, total), (79, 79));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "the scratch file is gone");
        // A folder that cannot hold the store: every pass reads the origin, with the same result.
        let (fallback, reads, _) = with_store(&frames, m, 4, &dir.path().join("missing"));
        assert_eq!(fallback, plain);
        assert_eq!(reads, 79);
    }

    #[test]
    fn blocks_give_the_in_memory_basis() {
        let (w, h, m) = (12, 10, 41);
        let frames = random_frames(w, h, m, 7);
        let whole = train(w, h, frames.clone(), sources(m), 0).unwrap();
        // 41 frames in blocks of 6: a short last block, and block pairs on both sides of the diagonal.
        let parts = blockwise(w, h, &frames, m, 0, 6);
        assert_eq!(parts.basis.components(), whole.basis.components());
        let close = |a: &[f32], b: &[f32], tol: f32| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        assert!(close(&parts.basis.mean, &whole.basis.mean, 1e-6));
        // Every eigenfire agrees: the angle between the two is below 1e-3 (cos > 1 − 5e-7).
        for k in 0..whole.basis.components() {
            let (u, v) = (parts.basis.eigenvector(k).unwrap(), whole.basis.eigenvector(k).unwrap());
            let cos: f64 = u.iter().zip(v).map(|(a, b)| f64::from(*a) * f64::from(*b)).sum();
            assert!(cos > 1.0 - 5e-7, "eigenfire {k}: cos {cos}");
        }
        for (a, b) in parts.basis.eigenvalues.iter().zip(&whole.basis.eigenvalues) {
            assert!((a - b).abs() <= 1e-5 * b.abs().max(1e-9), "{a} vs {b}");
        }
        assert!(close(&parts.weights.data, &whole.weights.data, 1e-3));
    }

    #[test]
    fn one_block_and_capped_components_work_too() {
        let (w, h, m) = (8, 8, 20);
        let frames = random_frames(w, h, m, 9);
        let whole = train(w, h, frames.clone(), sources(m), 5).unwrap();
        for block in [1, 3, 20, 100] {
            let parts = blockwise(w, h, &frames, m, 5, block);
            assert_eq!(parts.basis.components(), 5, "block {block}");
            let cos: f64 = parts
                .basis
                .eigenvector(0)
                .unwrap()
                .iter()
                .zip(whole.basis.eigenvector(0).unwrap())
                .map(|(a, b)| f64::from(*a) * f64::from(*b))
                .sum();
            assert!(cos > 1.0 - 5e-7, "block {block}: cos {cos}");
        }
    }

    #[test]
    fn read_errors_reach_the_caller() {
        let read = |r: Range<usize>, _: &mut [f32]| -> Result<(), String> { Err(format!("frame {} is unreadable", r.start)) };
        let source = BlockSource { read: &read, scratch: None, progress: &|_, _| {} };
        let err = train_blocks(4, 4, sources(10), 0, 4, &source).unwrap_err();
        assert!(err.contains("frame 0 is unreadable"), "{err}");
    }
}
