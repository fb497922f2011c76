//! Eq. 21 distances in fire space, recognition (§4.5) and frame ranges.

use std::ops::RangeInclusive;

use crate::values::Weights;
use rayon::prelude::*;

/// Eq. 21 over the first `e` components.
pub fn distance(a: &[f32], b: &[f32], e: usize) -> f64 {
    sq_distance(&a[..e], &b[..e]).sqrt()
}

/// `‖a − b‖²` over the whole slices: the differences are squared and summed in 16 independent f32
/// lanes (the compiler vectorises them) and the lanes are added in f64, so a 1,100-component
/// distance costs one pass over the two rows. The result is symmetric bit for bit.
fn sq_distance(a: &[f32], b: &[f32]) -> f64 {
    const LANES: usize = 16;
    let mut acc = [0.0_f32; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            let d = x[l] - y[l];
            acc[l] += d * d;
        }
    }
    acc.iter().map(|&v| f64::from(v)).sum::<f64>() + tail
}

pub(super) fn row(db: &Weights, i: usize) -> &[f32] {
    &db.data[i * db.components..(i + 1) * db.components]
}

/// Database rows per parallel task of a distance pass.
const ROWS_PER_TASK: usize = 128;

/// Distances (eq. 21) from `query` to every database frame, in parallel.
pub fn distances_to(db: &Weights, query: &[f32], e: usize) -> Vec<f64> {
    let q = &query[..e];
    let mut out = vec![0.0_f64; db.frames];
    out.par_chunks_mut(ROWS_PER_TASK).enumerate().for_each(|(t, chunk)| {
        for (k, d) in chunk.iter_mut().enumerate() {
            *d = sq_distance(&row(db, t * ROWS_PER_TASK + k)[..e], q).sqrt();
        }
    });
    out
}

/// Distances from database frames `a` and `b` to every database frame in one parallel pass over
/// the weights (each row is read once for both).
pub(super) fn distances_from_two(db: &Weights, a: usize, b: usize, e: usize) -> (Vec<f64>, Vec<f64>) {
    let (qa, qb) = (&row(db, a)[..e], &row(db, b)[..e]);
    let mut da = vec![0.0_f64; db.frames];
    let mut dbv = vec![0.0_f64; db.frames];
    da.par_chunks_mut(ROWS_PER_TASK).zip(dbv.par_chunks_mut(ROWS_PER_TASK)).enumerate().for_each(|(t, (oa, ob))| {
        for (k, (x, y)) in oa.iter_mut().zip(ob.iter_mut()).enumerate() {
            let r = &row(db, t * ROWS_PER_TASK + k)[..e];
            *x = sq_distance(r, qa).sqrt();
            *y = sq_distance(r, qb).sqrt();
        }
    });
    (da, dbv)
}

/// Distance between database frames `a` and `b`.
pub fn frame_distance(db: &Weights, a: usize, b: usize, e: usize) -> f64 {
    distance(row(db, a), row(db, b), e)
}

/// Eq. 21 recognition (§4.5): the database frame nearest to `query` whose distance is at least
/// `theta_min` (closer frames are rejected as near-copies) and that is not `excluded`.
pub fn recognize(db: &Weights, query: &[f32], e: usize, theta_min: f64, excluded: &[bool]) -> Option<(usize, f64)> {
    distances_to(db, query, e)
        .into_iter()
        .enumerate()
        .filter(|&(i, d)| d >= theta_min && !excluded.get(i).copied().unwrap_or(false))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Checks that a frame range is non-empty and inside a database of `frames` frames.
pub fn check_range(r: &RangeInclusive<usize>, frames: usize, what: &str) -> Result<(), String> {
    if r.is_empty() {
        return Err(format!("{what} {}-{} is empty (its end is before its start)", r.start(), r.end()));
    }
    if *r.end() >= frames {
        return Err(format!("{what} {}-{} goes past the database's last frame {}", r.start(), r.end(), frames.saturating_sub(1)));
    }
    Ok(())
}

/// A mask of excluded frames: all of `ranges`, plus `near` frames before `alpha` and after `beta`.
pub fn exclusion_mask(frames: usize, ranges: &[RangeInclusive<usize>]) -> Vec<bool> {
    let mut ex = vec![false; frames];
    for r in ranges {
        for i in r.clone() {
            if let Some(x) = ex.get_mut(i) {
                *x = true;
            }
        }
    }
    ex
}
