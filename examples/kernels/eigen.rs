//! Eigenfires kernels (thesis ch. 4–5): End Growing, batch reconstruction and training.

use std::path::PathBuf;

use clap::Args;
use pyrograph_nodes_eigen::pca;
use pyrograph_nodes_eigen::transition::end_growing;
use pyrograph_nodes_eigen::values::{Basis, FrameRef, Weights};

use crate::npy::{expect_rank, read_f32, write};
use crate::{Timing, report};

#[derive(Args)]
pub struct EndGrowArgs {
    /// M×E float32 weights.
    #[arg(long)]
    weights: PathBuf,
    #[arg(long)]
    alpha: usize,
    #[arg(long)]
    beta: usize,
    /// Algorithm 1's max_steps (it takes at most ceil(max_steps / 2) steps of two frames).
    #[arg(long)]
    max_steps: usize,
    /// Components used (0: all).
    #[arg(long, default_value_t = 0)]
    components: usize,
    #[arg(long)]
    theta: f64,
    /// Optimize_Path after the join.
    #[arg(long, default_value_t = false)]
    optimize: bool,
    /// JSON with the path, the shared frame and the steps taken.
    #[arg(long)]
    output: PathBuf,
}

pub fn end_grow(a: &EndGrowArgs, t: Timing) -> Result<String, String> {
    let w = read_f32(&a.weights)?;
    let &[m, e] = expect_rank(&w, 2, "weights")? else { return Err("weights: want M×E".into()) };
    let db = Weights::new(m, e, w.data).ok_or("weights size mismatch")?;
    let comps = if a.components == 0 { e } else { a.components };
    let excluded = vec![false; m];
    let (times, r) = t.run(|| end_growing(&db, a.alpha, a.beta, a.max_steps, comps, a.theta, &excluded, a.optimize))?;
    let out = serde_json::json!({ "path": r.path, "shared": r.shared, "steps": r.steps });
    std::fs::write(&a.output, out.to_string()).map_err(|e| format!("{}: {e}", a.output.display()))?;
    Ok(report("endgrow", &times, serde_json::json!({ "m": m, "e": comps, "steps": r.steps, "path_len": r.path.len() })))
}

#[derive(Args)]
pub struct ReconstructArgs {
    /// P float32 mean image.
    #[arg(long)]
    mean: PathBuf,
    /// E×P float32 eigenfires (one per row).
    #[arg(long)]
    basis: PathBuf,
    /// B×E float32 weights.
    #[arg(long)]
    weights: PathBuf,
    /// B×P float32 images out.
    #[arg(long)]
    output: PathBuf,
}

/// The JSON line naming the library of the Eigenfires products (`PYROGRAPH_BLAS`, see
/// `pyrograph_nodes_eigen::blas`).
pub fn products() -> String {
    let products = pyrograph_nodes_eigen::blas::openblas().map_or("faer (no OpenBLAS found)".to_string(), |b| b.config.clone());
    serde_json::json!({ "op": "products", "products": products }).to_string()
}

pub fn reconstruct(a: &ReconstructArgs, t: Timing) -> Result<String, String> {
    let mean = read_f32(&a.mean)?;
    let u = read_f32(&a.basis)?;
    let w = read_f32(&a.weights)?;
    let &[e, p] = expect_rank(&u, 2, "basis")? else { return Err("basis: want E×P".into()) };
    let &[b, we] = expect_rank(&w, 2, "weights")? else { return Err("weights: want B×E".into()) };
    if mean.data.len() != p || we != e {
        return Err(format!("mean has {} samples, basis {e}×{p}, weights {b}×{we}: sizes disagree", mean.data.len()));
    }
    // The basis has no image size of its own here: a 1-pixel-high image of P samples.
    let basis = Basis {
        width: p as u32,
        height: 1,
        mean: mean.data,
        // Where `database::load` puts a loaded basis (numpy's arrays get the same advice).
        eigenvectors: {
            let mut v = pyrograph_nodes_eigen::pages::with_capacity_huge(u.data.len());
            v.extend_from_slice(&u.data);
            drop(u);
            v
        },
        eigenvalues: vec![1.0; e],
        sources: Vec::new(),
    };
    let weights = Weights::new(b, e, w.data).ok_or("weights size mismatch")?;
    let (times, images) = t.run(|| pca::reconstruct(&basis, &weights, e))?;
    write(&a.output, &[b, p], &images)?;
    Ok(report("reconstruct", &times, serde_json::json!({ "batch": b, "e": e, "pixels": p })))
}

#[derive(Args)]
pub struct TrainArgs {
    /// M×H×W float32 frames.
    #[arg(long)]
    frames: PathBuf,
    /// Eigenfires kept (E).
    #[arg(long)]
    components: usize,
    /// Eigenvectors written to `<prefix>vectors.npy` (the first K, K×P).
    #[arg(long, default_value_t = 20)]
    keep_vectors: usize,
    /// Output prefix: `<prefix>eigenvalues.npy` (E, f64), `<prefix>vectors.npy`, `<prefix>weights.npy` (M×E).
    #[arg(long)]
    output_prefix: String,
}

pub fn train(a: &TrainArgs, t: Timing) -> Result<String, String> {
    let f = read_f32(&a.frames)?;
    let &[m, h, w] = expect_rank(&f, 3, "frames")? else { return Err("frames: want M×H×W".into()) };
    let sources: Vec<FrameRef> = (0..m).map(|i| FrameRef { clip: 0, index: i as u32 }).collect();
    let (times, db) =
        t.run_with(|| f.data.clone(), |frames| pca::train(w as u32, h as u32, frames, sources.clone(), a.components))?;
    let basis = &db.basis;
    let (e, p) = (basis.components(), basis.pixels());
    let k = a.keep_vectors.min(e);
    write(&PathBuf::from(format!("{}eigenvalues.npy", a.output_prefix)), &[e], &basis.eigenvalues)?;
    write(&PathBuf::from(format!("{}vectors.npy", a.output_prefix)), &[k, p], &basis.eigenvectors[..k * p])?;
    write(&PathBuf::from(format!("{}weights.npy", a.output_prefix)), &[m, db.weights.components], &db.weights.data)?;
    Ok(report("train", &times, serde_json::json!({ "frames": m, "width": w, "height": h, "e": e })))
}
