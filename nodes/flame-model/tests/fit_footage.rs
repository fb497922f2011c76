//! Fits the generic flame model (Stich & Magnor §3) to the 150 real candle-black frames and
//! renders them back. Run with `PYROGRAPH_FOOTAGE=/abs/path cargo test -p pyrograph-nodes-flame-model -- --ignored`.

use std::path::PathBuf;

use pyrograph_nodes_flame_model::model::{FitSettings, RenderSettings, fit_gray_frames, gray_plane, render_frame};
use pyrograph_nodes_imaging::io::load_image;
use rayon::prelude::*;

/// PYROGRAPH_FOOTAGE, else `<workspace>/../shared/footage`.
fn footage() -> PathBuf {
    std::env::var_os("PYROGRAPH_FOOTAGE")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/footage"))
}

fn candle_frames() -> (Vec<Vec<f32>>, (u32, u32)) {
    let dir = footage().join("candle-black/frames");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    files.sort();
    let images: Vec<_> = files.par_iter().map(|f| load_image(f).unwrap()).collect();
    let size = images[0].size();
    (images.iter().map(gray_plane).collect(), size)
}

fn relative_error(a: &[f32], b: &[f32]) -> f64 {
    let err: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>().sqrt();
    let norm: f64 = b.iter().map(|y| f64::from(*y).powi(2)).sum::<f64>().sqrt();
    err / norm
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn candle_black_fits_a_26_parameter_model_and_renders_back() {
    let (frames, size) = candle_frames();
    assert_eq!(frames.len(), 150);
    let s = FitSettings::default();
    let fit = fit_gray_frames(&frames, size, &s, 29.97).unwrap();
    let m = &fit.model;
    println!(
        "kept {} frames, skipped {} (plumes) + {} (empty); axis {:?}, anchor {:?}",
        fit.kept.len(),
        fit.skipped_plumes.len(),
        fit.skipped_empty.len(),
        m.axis,
        m.anchor
    );
    assert_eq!(fit.params.dim(), 26, "N_p = N_w = 10, N_e = 5, height");
    assert!(fit.kept.len() >= 140, "a steady candle: nearly every frame is one plume");
    // An upright flame: the main axis within 10° of vertical, the base in the lower half.
    assert!(m.axis[1] < -0.98, "axis {:?}", m.axis);
    assert!(m.anchor[1] > f64::from(size.1) / 2.0 && m.anchor[1] < f64::from(size.1));

    let column = |name: &str| -> Vec<f64> {
        let c = fit.params.names.iter().position(|n| n == name).unwrap();
        (0..fit.params.frames).map(|r| fit.params.row(r).unwrap()[c]).collect()
    };
    let range =
        |v: &[f64]| (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
    let heights = range(&column("height"));
    let widths = range(&column("width_3"));
    let paths = range(&column("path_9"));
    let eig = range(&column("eig_0"));
    println!("height {heights:.1?} px, width_3 {widths:.2?} px, path_9 {paths:.2?} px, eig_0 {eig:.3?}");
    println!("eigenvalues {:?}", m.eigenvalues);
    assert!(heights.0 > 40.0 && heights.1 < 480.0, "heights {heights:?}");
    assert!(widths.0 > 1.0 && widths.1 < 100.0, "widths {widths:?}");
    assert!(paths.0 > -60.0 && paths.1 < 60.0, "paths {paths:?}");

    // Reconstruction of training frames with the 5 eigenflames.
    let rows: Vec<usize> = (0..fit.params.frames).step_by(15).collect();
    let errors: Vec<f64> = rows
        .par_iter()
        .map(|&r| {
            let img = render_frame(m, fit.params.row(r).unwrap(), &RenderSettings::default(), r).unwrap();
            let clean: Vec<f32> = frames[fit.kept[r]].iter().map(|&v| if v > s.threshold { v } else { 0.0 }).collect();
            relative_error(img.data(), &clean)
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let worst = errors.iter().cloned().fold(0.0, f64::max);
    println!("relative L2 reconstruction error (N_e = 5) over {} frames: mean {mean:.3}, worst {worst:.3}", errors.len());
    assert!(mean < 0.25 && worst < 0.35, "mean {mean}, worst {worst}");
}
