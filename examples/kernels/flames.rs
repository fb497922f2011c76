//! Bloom, cloth and ARP kernels.

use std::path::PathBuf;

use clap::Args;
use pyrograph_core::{Channels, CookCtx, Image};
use pyrograph_nodes_cloth::sim::{ClothParams, Simulation, grid_roots};
use pyrograph_nodes_flame_model::arp::{ArSampler, LearnOptions, learn};
use pyrograph_nodes_flame_model::model::{FitSettings, fit_gray_frames, gray_plane};
use pyrograph_nodes_imaging::bloom::{BloomParams, bloom as bloom_image};
use pyrograph_nodes_imaging::io::load_image;

use crate::npy::{expect_rank, read_f32, write};
use crate::{Timing, report};

#[derive(Args)]
pub struct BloomArgs {
    /// H×W×3 float32 RGB frame.
    #[arg(long)]
    input: PathBuf,
    /// H×W×3 float32 bloomed frame out.
    #[arg(long)]
    output: PathBuf,
}

pub fn bloom(a: &BloomArgs, t: Timing) -> Result<String, String> {
    let f = read_f32(&a.input)?;
    let &[h, w, c] = expect_rank(&f, 3, "frame")? else { return Err("frame: want H×W×3".into()) };
    if c != 3 {
        return Err(format!("frame: {c} channels, want 3"));
    }
    let rgba: Vec<f32> = f.data.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
    let image = Image::from_vec(w as u32, h as u32, Channels::Rgba, rgba).ok_or("frame size mismatch")?;
    let params = BloomParams::default();
    let (times, out) = t.run(|| bloom_image(&image, &params).map_err(|e| e.to_string()))?;
    let rgb: Vec<f32> = out.image.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    write(&a.output, &[h, w, 3], &rgb)?;
    Ok(report("bloom", &times, serde_json::json!({ "width": w, "height": h, "sigmas": params.sigmas() })))
}

#[derive(Args)]
pub struct ClothArgs {
    /// Number of flames (16 × 32 masses each).
    #[arg(long)]
    flames: usize,
    /// Sub-steps (1/120 s each) per timed run.
    #[arg(long)]
    steps: usize,
    /// N×32×16×2 float32: each mass's (x, y) displacement from rest after the last run.
    #[arg(long)]
    output: PathBuf,
}

/// The numpy peer's model (../shared/peers/mass_spring.py) in the node's terms: 16 × 32 masses,
/// structural springs only, spacing 0.02, mass 1, k 2000, spring damping 2, drag 0.5, buoyancy
/// 0.5, and a constant wind of 0.3 across (on all the time, no per-flame jitter) so that both
/// sides integrate the same forces; sub-steps of 1/120 s, semi-implicit Euler, bottom row pinned.
pub fn peer_params() -> ClothParams {
    ClothParams {
        grid_width: 16,
        grid_height: 32,
        flame_width: 15.0 * 0.02,
        flame_height: 31.0 * 0.02,
        mass: 1.0,
        stiffness: 2000.0,
        damping: 2.0,
        shear: false,
        bend: false,
        drag: 0.5,
        buoyancy: 0.5.into(),
        wind: [0.3, 0.0, 0.0].into(),
        wind_on: 1.0,
        wind_off: 0.0,
        wind_jitter: 0.0,
        dt: 1.0 / 120.0,
        fps: 24.0,
        ..ClothParams::default()
    }
}

pub fn cloth(a: &ClothArgs, t: Timing) -> Result<String, String> {
    let p = peer_params();
    let roots = grid_roots(a.flames, 1.5);
    let fresh = || Simulation::new(&p, &roots).map_err(|e| e.to_string());
    let rest = fresh()?.snapshot();
    let (times, sim) = t.run_with(fresh, |sim| {
        let mut sim = sim?;
        let (_, h) = sim.substeps();
        sim.substep(h, a.steps);
        Ok(sim)
    })?;
    let end = sim.snapshot();
    let (gw, gh) = (p.grid_width, p.grid_height);
    let moved: Vec<f32> = end.positions.iter().zip(&rest.positions).flat_map(|(q, r)| [q[0] - r[0], q[1] - r[1]]).collect();
    if end.positions.iter().any(|q| q[2] != 0.0 || !q[0].is_finite() || !q[1].is_finite()) {
        return Err("the cloth left its plane or diverged".into());
    }
    write(&a.output, &[a.flames, gh, gw, 2], &moved)?;
    let per_step: Vec<f64> = times.iter().map(|s| s / a.steps.max(1) as f64).collect();
    Ok(report("cloth_step", &per_step, serde_json::json!({ "flames": a.flames, "steps_per_run": a.steps })))
}

#[derive(Args)]
pub struct ArpArgs {
    /// Folder of the footage's PNG frames (fit, then EM learning, both untimed).
    #[arg(long)]
    frames: PathBuf,
    /// Steps sampled per timed run.
    #[arg(long)]
    steps: usize,
    /// Folder for the learned model as .npy (a, d, b, offset, scale, initial), read by the peer.
    #[arg(long)]
    model_dir: PathBuf,
    /// steps×D float64 samples of the last run.
    #[arg(long)]
    output: PathBuf,
    #[arg(long, default_value_t = 7)]
    seed: u64,
}

pub fn arp(a: &ArpArgs, t: Timing) -> Result<String, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(&a.frames)
        .map_err(|e| format!("{}: {e}", a.frames.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    files.sort();
    let images = files.iter().map(|f| load_image(f).map_err(|e| e.to_string())).collect::<Result<Vec<_>, _>>()?;
    let size = images.first().ok_or("no PNG frames")?.size();
    let planes: Vec<Vec<f32>> = images.iter().map(gray_plane).collect();
    let fit = fit_gray_frames(&planes, size, &FitSettings::default(), 29.97)?;
    let model = learn(&fit.params, &LearnOptions::default(), &CookCtx::new()).map_err(|e| e.to_string())?;
    let (d, k) = (model.dim(), model.order);
    std::fs::create_dir_all(&a.model_dir).map_err(|e| format!("{}: {e}", a.model_dir.display()))?;
    let dir = &a.model_dir;
    write(&dir.join("a.npy"), &[k, d, d], &model.a)?;
    write(&dir.join("d.npy"), &[d], &model.d)?;
    write(&dir.join("b.npy"), &[d, d], &model.b)?;
    write(&dir.join("offset.npy"), &[d], &model.offset)?;
    write(&dir.join("scale.npy"), &[d], &model.scale)?;
    write(&dir.join("initial.npy"), &[k, d], &model.initial)?;
    let (times, samples) = t.run(|| {
        let mut s = ArSampler::new(&model, a.seed).map_err(|e| e.to_string())?;
        let mut out = vec![0.0_f64; a.steps * d];
        for row in out.chunks_exact_mut(d) {
            s.step(row);
        }
        Ok(out)
    })?;
    write(&a.output, &[a.steps, d], &samples)?;
    let per_step: Vec<f64> = times.iter().map(|s| s / a.steps.max(1) as f64).collect();
    Ok(report("arp_sample", &per_step, serde_json::json!({ "dim": d, "order": k, "steps_per_run": a.steps })))
}
