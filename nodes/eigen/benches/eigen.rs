//! Eigenfires workloads at the thesis' sizes (§7.1): training (PCA + projection of the training
//! frames) at 500 frames of 205×335 and at 2,197 frames of 410×670 (~10 GB: frames plus
//! eigenfires), End Growing over 2,197 frames at E = 1,100 (Table 2) and batch reconstruction
//! with 1,100 eigenfires. Frames are synthetic. Comparisons with numpy (same inputs, same outputs,
//! alternating) are made by the peer harness, benches/peers/run.py. Run one case with e.g.
//! `cargo bench -p pyrograph-nodes-eigen -- training/500`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use pyrograph_nodes_eigen::pca::{reconstruct, train};
use pyrograph_nodes_eigen::transition::end_growing;
use pyrograph_nodes_eigen::values::{Basis, FrameRef, Weights};
use pyrograph_testing::{XorShift, lcg};

/// Smooth moving blobs with a little noise: flame-like variation with a decaying spectrum.
fn frames(w: u32, h: u32, m: usize) -> Vec<f32> {
    let n = w as usize * h as usize;
    let mut out = vec![0.0_f32; n * m];
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    for (f, frame) in out.chunks_mut(n).enumerate() {
        let t = f as f32 * 0.07;
        let (cx, cy) = (0.5 + 0.15 * (t * 1.3).sin(), 0.6 + 0.1 * (t * 0.7).cos());
        let s = 0.08 + 0.03 * (t * 2.1).sin();
        for (i, v) in frame.iter_mut().enumerate() {
            let (x, y) = ((i % w as usize) as f32 / w as f32, (i / w as usize) as f32 / h as f32);
            let noise = rng.next_f32();
            *v = (-((x - cx).powi(2) + (y - cy).powi(2)) / s).exp() + 0.02 * noise;
        }
    }
    out
}

fn sources(m: usize) -> Vec<FrameRef> {
    (0..m).map(|i| FrameRef { clip: 0, index: i as u32 }).collect()
}

fn training(c: &mut Criterion) {
    let mut g = c.benchmark_group("training");
    g.sample_size(10);
    // E as the numpy peer's runs: 250 of 500 frames, 1,100 of 2,197.
    for (label, w, h, m, e) in [("500x205x335_E250", 205, 335, 500, 250), ("2197x410x670_E1100", 410, 670, 2197, 1100)] {
        g.bench_function(label, |b| {
            b.iter_batched(
                || frames(w, h, m),
                |data| black_box(train(w, h, data, sources(m), e)),
                criterion::BatchSize::PerIteration,
            )
        });
    }
    g.finish();
}

/// A synthetic 2,197-frame database of E = 1,100 weights: a slow random walk with a decaying spectrum.
fn walk_weights(m: usize, e: usize) -> Weights {
    let mut seed = 7_u64;
    let mut cur = vec![0.0_f32; e];
    let mut data = Vec::with_capacity(m * e);
    for _ in 0..m {
        for (k, v) in cur.iter_mut().enumerate() {
            let r = lcg(&mut seed) - 0.5;
            *v = 0.95 * *v + r / (1.0 + k as f32 * 0.05);
        }
        data.extend_from_slice(&cur);
    }
    Weights::new(m, e, data).unwrap_or_default()
}

fn transitions(c: &mut Criterion) {
    let db = walk_weights(2197, 1100);
    let ex = vec![false; db.frames];
    // A bench that times an error path measures nothing: the join must succeed, and the steps it
    // took are printed (max_steps 26 allows at most 13 steps of two frames).
    match end_growing(&db, 100, 1800, 26, 1100, 0.5, &ex, true) {
        Ok(r) => eprintln!("End Growing: joined in {} steps, {} frames between α and β", r.steps, r.path.len()),
        Err(e) => panic!("End Growing did not join the ends, so there is nothing to time: {e}"),
    }
    c.bench_function("end_growing/max_26_steps_2197x1100", |b| {
        b.iter(|| black_box(end_growing(&db, 100, 1800, 26, 1100, 0.5, &ex, true)))
    });
}

fn reconstruction(c: &mut Criterion) {
    // The thesis size (410×670 px) at E = 1,100, as the numpy peer's `reconstruct` op measures.
    let (w, h, e, f) = (410_u32, 670_u32, 1100_usize, 64_usize);
    let n = w as usize * h as usize;
    let basis = Basis {
        width: w,
        height: h,
        mean: vec![0.2; n],
        eigenvectors: (0..n * e).map(|i| ((i % 97) as f32 - 48.0) * 1e-4).collect(),
        eigenvalues: (0..e).map(|k| 1.0 / (1.0 + k as f64)).collect(),
        sources: sources(f),
    };
    let weights = walk_weights(f, e);
    c.bench_function("reconstruct/64_frames_410x670_E1100", |b| b.iter(|| black_box(reconstruct(&basis, &weights, e))));
}

criterion_group!(benches, training, transitions, reconstruction);
criterion_main!(benches);
