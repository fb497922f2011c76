//! Fits the generic flame model (Stich & Magnor §3) to the 150 real candle-black frames and
//! renders them back. Run with `PYROGRAPH_FOOTAGE=/abs/path cargo test -p pyrograph-nodes-flame-model -- --ignored`.

use std::path::PathBuf;

use pyrograph_nodes_flame_model::model::{FitSettings, RenderSettings, fit_gray_frames, gray_plane, render_frame};
use pyrograph_nodes_flame_model::values::ParamSeries;
use pyrograph_nodes_imaging::io::load_image;
use pyrograph_testing::footage;
use rayon::prelude::*;

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
    // Measured 0.054 mean and 0.072 worst (2026-11-25): limits a third above that, so a regression
    // of the fit or the renderer shows (the earlier 0.25 / 0.35 let a 4× regression pass).
    assert!(mean < 0.07 && worst < 0.10, "mean {mean}, worst {worst}");
}

/// Mean, standard deviation and lag-1 / lag-2 autocorrelation of one column.
fn column_stats(v: &[f64]) -> [f64; 4] {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    let acf = |lag: usize| -> f64 {
        let c: f64 = v.windows(lag + 1).map(|w| (w[0] - mean) * (w[lag] - mean)).sum::<f64>() / n;
        if var > 0.0 { c / var } else { 0.0 }
    };
    [mean, var.sqrt(), acf(1), acf(2)]
}

fn columns(p: &ParamSeries) -> Vec<Vec<f64>> {
    (0..p.dim()).map(|c| (0..p.frames).map(|r| p.row(r).unwrap()[c]).collect()).collect()
}

/// Realism (Stich & Magnor §4.3): 600 synthesized frames against the 150 training frames.
///
/// One 600-frame draw of a process whose lag-1 autocorrelation is 0.95 has a sample mean that
/// wanders by about a quarter of a standard deviation from seed to seed, so the statistics of the
/// *process* are taken as the average over 48 independent 600-frame draws (seeds 1–48); the spread
/// of single draws is printed beside them. Means are compared on the scale of the parameter
/// (10 % of max(|mean|, sd), since the eigenflame weights and path offsets have means near 0),
/// standard deviations relative to the training one, autocorrelations absolutely.
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn synthesized_flames_match_the_training_statistics() {
    use pyrograph_nodes_flame_model::arp::{Controls, LearnOptions, learn, sample};
    let (frames, size) = candle_frames();
    let fit = fit_gray_frames(&frames, size, &FitSettings::default(), 29.97).unwrap();
    let t0 = std::time::Instant::now();
    let opts = LearnOptions::default();
    let model = learn(&fit.params, &opts, &pyrograph_core::CookCtx::new()).unwrap();
    println!(
        "learned K = 2 on {} x {} in {:.2?}, {} EM iterations",
        fit.params.frames,
        fit.params.dim(),
        t0.elapsed(),
        model.log_likelihood.len()
    );
    let real: Vec<[f64; 4]> = columns(&fit.params).iter().map(|c| column_stats(c)).collect();
    let seeds: Vec<u64> = (1..=48).collect();
    let draws: Vec<Vec<[f64; 4]>> = seeds
        .par_iter()
        .map(|&seed| {
            let synth = sample(&model, 600, 0, seed, &Controls::default()).unwrap();
            columns(&synth).iter().map(|c| column_stats(c)).collect()
        })
        .collect();
    let error = |s: &[f64; 4], r: &[f64; 4]| -> [f64; 4] {
        [(s[0] - r[0]).abs() / r[0].abs().max(r[1]), (s[1] - r[1]).abs() / r[1], (s[2] - r[2]).abs(), (s[3] - r[3]).abs()]
    };
    let mut worst = [0.0f64; 4];
    let mut worst_single = [0.0f64; 4];
    let mut failures = Vec::new();
    for (c, r) in real.iter().enumerate() {
        let mut avg = [0.0; 4];
        for d in &draws {
            for k in 0..4 {
                avg[k] += d[c][k] / draws.len() as f64;
            }
            let e = error(&d[c], r);
            for k in 0..4 {
                worst_single[k] = worst_single[k].max(e[k]);
            }
        }
        let e = error(&avg, r);
        for k in 0..4 {
            worst[k] = worst[k].max(e[k]);
        }
        if e.iter().any(|e| *e > 0.1) {
            failures.push(format!("{}: real {r:.3?} synthesized {avg:.3?}", fit.params.names[c]));
        }
    }
    println!(
        "worst of 26 parameters, 48-draw average: mean {:.3}, sd {:.3}, lag-1 {:.3}, lag-2 {:.3}",
        worst[0], worst[1], worst[2], worst[3]
    );
    println!(
        "worst single 600-frame draw: mean {:.3}, sd {:.3}, lag-1 {:.3}, lag-2 {:.3}",
        worst_single[0], worst_single[1], worst_single[2], worst_single[3]
    );
    assert!(failures.is_empty(), "{} parameters off:\n{}", failures.len(), failures.join("\n"));
}
