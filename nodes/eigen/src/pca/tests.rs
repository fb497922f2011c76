//! Tests of the Eigenfires PCA, and the test data other modules' tests share.

use std::sync::Arc;

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use pyrograph_core::{Channels, Clip, CookCtx, Image, NodeError, PortType, Value};
use pyrograph_testing::lcg;

use super::clips::train_from_clips;
use super::nodes::Eigenfires;
use super::projection::{LIFT_BAND_ROWS, lift_onto, reconstruct_with};
use super::projection::{project, reconstruct};
use super::training::{gram_matrix, lift_in_place, train};
use crate::values::FrameRef;

/// `m` random gray frames of `w × h` (one after another).
pub fn random_frames(w: u32, h: u32, m: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..w as usize * h as usize * m).map(|_| lcg(&mut s)).collect()
}

pub fn sources(m: usize) -> Vec<FrameRef> {
    (0..m).map(|i| FrameRef { clip: 0, index: i as u32 }).collect()
}

#[test]
fn out_of_core_training_from_clips_matches_the_in_memory_cook() {
    let (w, h) = (6u32, 5u32);
    let n = (w * h) as usize;
    let frames = random_frames(w, h, 23, 4);
    let img =
        |f: usize| Value::Image(Arc::new(Image::from_vec(w, h, Channels::Gray, frames[f * n..(f + 1) * n].to_vec()).unwrap()));
    let clip1 = Clip::from_frames(PortType::Image, 24.0, (0..15).map(img).collect());
    let empty = Clip::from_frames(PortType::Image, 24.0, Vec::new());
    let clip3 = Clip::from_frames(PortType::Image, 24.0, (15..23).map(img).collect());
    let clips = [&clip1, &empty, &clip3];
    let ctx = CookCtx::new();
    let out = train_from_clips(&clips, (w, h), 0, 4, &ctx).unwrap();
    let b = &out.basis;
    let whole = train(w, h, frames.clone(), sources(23), 0).unwrap();
    assert_eq!(b.components(), whole.basis.components());
    assert_eq!(b.sources[15], FrameRef { clip: 2, index: 0 }, "frames keep their clip and index");
    for k in 0..b.components() {
        let cos: f64 = b
            .eigenvector(k)
            .unwrap()
            .iter()
            .zip(whole.basis.eigenvector(k).unwrap())
            .map(|(x, y)| f64::from(*x) * f64::from(*y))
            .sum();
        assert!(cos > 1.0 - 5e-7, "eigenfire {k}: cos {cos}");
    }
    // A frame of the wrong size is reported with its clip and index.
    let odd = Clip::from_frames(PortType::Image, 24.0, vec![img(0), Value::Image(Arc::new(Image::new(2, 2, Channels::Gray)))]);
    let err = train_from_clips(&[&odd], (w, h), 0, 1, &ctx).unwrap_err().to_string();
    assert!(err.contains("frame 1 is 2x2"), "{err}");
    // In the second clip, it is that clip's port, named once; a cancelled cook stays cancelled.
    let ports = ["clip1", "clip2", "clip3"];
    let err = Eigenfires::clip_error(&ports, train_from_clips(&[&clip1, &odd], (w, h), 0, 1, &ctx).unwrap_err());
    assert_eq!(
        err,
        NodeError::port("clip2", "frame 1 is 2x2 but the database frames are 6x5; every frame must be the same size")
    );
    let cancelled = CookCtx::new();
    cancelled.cancel_token().cancel();
    let err = train_from_clips(&[&clip1], (w, h), 0, 1, &cancelled).unwrap_err();
    assert!(Eigenfires::clip_error(&ports, err).is_cancelled());
}

#[test]
fn full_rank_reconstruction_equals_the_input() {
    let (w, h, m) = (9, 7, 12);
    let frames = random_frames(w, h, m, 1);
    let db = train(w, h, frames.clone(), sources(m), 0).unwrap();
    assert_eq!(db.basis.components(), m - 1, "E = M − 1");
    let rec = reconstruct(&db.basis, &db.weights, m - 1).unwrap();
    let err: f64 = rec.iter().zip(&frames).map(|(a, b)| f64::from(a - b).powi(2)).sum::<f64>().sqrt();
    let norm: f64 = frames.iter().map(|a| f64::from(*a).powi(2)).sum::<f64>().sqrt();
    assert!(err / norm < 1e-3, "relative error {}", err / norm);
}

#[test]
fn the_banded_lift_equals_one_product_and_covers_a_partial_last_band() {
    let (n, m, e) = (2 * LIFT_BAND_ROWS + 37, 6, 4);
    let a_data = random_frames(n as u32, 1, m, 11);
    let v_data = random_frames(m as u32, 1, e, 12);
    let base = random_frames(n as u32, 1, 1, 13);
    let a = MatRef::from_column_major_slice(&a_data, n, m);
    let v = MatRef::from_column_major_slice(&v_data, m, e);
    let mut banded = vec![f32::NAN; n * e];
    lift_onto(MatMut::from_column_major_slice_mut(&mut banded, n, e), &base, a, v);
    let mut whole = vec![0.0_f32; n * e];
    matmul(MatMut::from_column_major_slice_mut(&mut whole, n, e), Accum::Replace, a, v, 1.0, Par::Seq);
    for (i, (x, y)) in banded.iter().zip(&whole).enumerate() {
        let y = y + base[i % n];
        assert!((x - y).abs() <= 1e-5 * y.abs().max(1.0), "entry {i}: {x} vs {y}");
    }
}

#[test]
fn the_lift_over_the_frames_equals_one_product() {
    // More bands than one, a partial last band, and E < M so the frames past E are dropped.
    let (n, m, e) = (3 * 256 + 41, 7, 5);
    let a_data = random_frames(n as u32, 1, m, 21);
    let v_data = random_frames(m as u32, 1, e, 22);
    let v = MatRef::from_column_major_slice(&v_data, m, e);
    let mut whole = vec![0.0_f32; n * e];
    let a = MatRef::from_column_major_slice(&a_data, n, m);
    matmul(MatMut::from_column_major_slice_mut(&mut whole, n, e), Accum::Replace, a, v, 1.0, Par::Seq);
    let lifted = lift_in_place(a_data.clone(), n, m, v);
    assert_eq!(lifted.len(), n * e);
    for (i, (x, y)) in lifted.iter().zip(&whole).enumerate() {
        assert!((x - y).abs() <= 1e-5 * y.abs().max(1.0), "entry {i}: {x} vs {y}");
    }
    assert!(lift_in_place(a_data, n, m, v.subcols(0, 0)).is_empty());
}

#[test]
fn eigenvectors_are_orthonormal_and_eigenvalues_descend() {
    let (w, h, m) = (10, 10, 20);
    let db = train(w, h, random_frames(w, h, m, 2), sources(m), 0).unwrap();
    let b = &db.basis;
    for k in 0..b.components() {
        for l in 0..=k {
            let dot: f64 =
                b.eigenvector(k).unwrap().iter().zip(b.eigenvector(l).unwrap()).map(|(x, y)| f64::from(*x) * f64::from(*y)).sum();
            let want = if k == l { 1.0 } else { 0.0 };
            assert!((dot - want).abs() < 1e-4, "u{k}·u{l} = {dot}");
        }
    }
    assert!(b.eigenvalues.windows(2).all(|p| p[0] >= p[1]), "{:?}", b.eigenvalues);
    assert!(b.eigenvalues.iter().all(|&l| l > 0.0));
}

#[test]
fn training_weights_equal_their_projection() {
    let (w, h, m) = (8, 6, 15);
    let frames = random_frames(w, h, m, 3);
    let db = train(w, h, frames.clone(), sources(m), 0).unwrap();
    let projected = project(&db.basis, &frames, db.basis.components()).unwrap();
    let scale = db.weights.data.iter().fold(0.0_f32, |a, v| a.max(v.abs()));
    for (a, b) in projected.data.iter().zip(&db.weights.data) {
        assert!((a - b).abs() < 1e-4 * scale, "{a} vs {b}");
    }
}

#[test]
fn eigenvalues_are_the_variance_along_each_eigenfire() {
    // Eq. 13: λ_k = (1/M) Σ (u_kᵀ Φ_n)².
    let (w, h, m) = (6, 6, 10);
    let db = train(w, h, random_frames(w, h, m, 4), sources(m), 0).unwrap();
    for k in 0..db.basis.components() {
        let var: f64 = (0..m).map(|n| f64::from(db.weights.row(n).unwrap()[k]).powi(2)).sum::<f64>() / m as f64;
        assert!((var - db.basis.eigenvalues[k]).abs() < 1e-4 * db.basis.eigenvalues[0], "k={k}");
    }
}

#[test]
fn max_components_caps_and_repeated_frames_reduce_the_rank() {
    let (w, h) = (5, 5);
    let one = random_frames(w, h, 3, 5);
    let mut frames = one.clone();
    frames.extend_from_slice(&one); // 6 frames, only 3 distinct: rank 2
    let db = train(w, h, frames, sources(6), 0).unwrap();
    assert_eq!(db.basis.components(), 2);
    let db = train(w, h, random_frames(w, h, 10, 6), sources(10), 4).unwrap();
    assert_eq!(db.basis.components(), 4);
    assert_eq!(db.weights.components, 4);
}

#[test]
fn identical_frames_and_a_single_frame_are_errors() {
    let one = random_frames(4, 4, 1, 7);
    assert!(train(4, 4, one.clone(), sources(1), 0).unwrap_err().contains("at least 2"));
    let twice = [one.clone(), one].concat();
    assert!(train(4, 4, twice, sources(2), 0).unwrap_err().contains("identical"));
}

#[test]
fn reconstruction_with_fewer_components_is_the_projection_onto_them() {
    let (w, h, m) = (7, 7, 10);
    let frames = random_frames(w, h, m, 8);
    let db = train(w, h, frames, sources(m), 0).unwrap();
    let rec = reconstruct(&db.basis, &db.weights, 3).unwrap();
    // Projecting the 3-component reconstruction gives back the first 3 weights.
    let back = project(&db.basis, &rec, 3).unwrap();
    for f in 0..m {
        for k in 0..3 {
            assert!((back.row(f).unwrap()[k] - db.weights.row(f).unwrap()[k]).abs() < 1e-3);
        }
    }
    assert!(reconstruct(&db.basis, &db.weights, m).is_err());
}

/// Both product paths, OpenBLAS's (when the system has it) and faer's, give the same Gram
/// matrix and the same reconstructions within f32 rounding; CI installs OpenBLAS, so without
/// this the faer path, every machine's fallback, would go untested there.
#[test]
fn faer_and_openblas_products_agree() {
    let (w, h, m) = (37, 29, 14);
    let frames = random_frames(w, h, m, 5);
    let n = (w * h) as usize;
    let with_faer = gram_matrix(&frames, n, m, None);
    let norm = (0..m).map(|i| with_faer[(i, i)]).fold(0.0, f64::max);
    assert!(norm > 0.0);
    let db = train(w, h, frames, sources(m), 0).unwrap();
    let e = db.basis.components();
    let via_faer = reconstruct_with(&db.basis, &db.weights, e, None).unwrap();
    let Some(blas) = crate::blas::openblas() else {
        eprintln!("OpenBLAS is not installed here: only faer's products ran");
        return;
    };
    let via_blas = gram_matrix(&random_frames(w, h, m, 5), n, m, Some(blas));
    for i in 0..m {
        for j in 0..m {
            let d = (via_blas[(i, j)] - with_faer[(i, j)]).abs();
            assert!(d <= 1e-5 * norm, "L[{i}, {j}]: {} vs {}", via_blas[(i, j)], with_faer[(i, j)]);
        }
    }
    let via_blas = reconstruct_with(&db.basis, &db.weights, e, Some(blas)).unwrap();
    assert_eq!(via_blas.len(), via_faer.len());
    for (k, (a, b)) in via_blas.iter().zip(&via_faer).enumerate() {
        assert!((a - b).abs() <= 1e-5, "sample {k}: {a} vs {b}");
    }
}
