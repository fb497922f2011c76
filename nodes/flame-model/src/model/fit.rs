//! Fitting the generic flame model to gray flame frames (Stich & Magnor §3, §3.1, §3.2).
//!
//! Per frame: threshold, keep the single plume (frames with two or more disjoint plumes are
//! skipped, §5), geometric moments up to order 3 (eq. 1) give the centroid, the main axes and the
//! flame height (from the second-order moment along the main axis). Over the clip the main axes
//! fix one normalization frame (a base anchor and an axis direction), so every frame is measured
//! in the same coordinates. The flame is cut into N_s height slices; each slice's own moments
//! across the axis give its centre (path) and spread (width), which are sampled at N_p and N_w
//! equidistant heights. Each frame is then normalized: slices centred and scaled by the cubic
//! splines through those samples (exactly the inverse of the renderer's deformation), the height
//! scaled to 1, and the intensity scaled to the clip's average. PCA of the normalized images
//! (the Eigenfires code) gives the eigenflames and the N_e appearance weights (§3.2).

use rayon::prelude::*;

use super::fit_settings::{CutBase, FitSettings};
use super::plume::{Frame, Plume, analyse_frame};
use super::quality::{EdgeReport, FrameQuality, train_scored};
use super::shape::{Spline, slice_value};
use crate::values::{FlameModel, ParamSeries};
use pyrograph_core::frames::list_for_message;
use pyrograph_nodes_eigen::pca::Database;

/// The result of a fit.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// The generic flame model.
    pub model: FlameModel,
    /// One parameter row per kept frame.
    pub params: ParamSeries,
    /// Indices of the kept frames (rows of `params`).
    pub kept: Vec<usize>,
    /// Frames skipped for showing two or more plumes.
    pub skipped_plumes: Vec<usize>,
    /// Frames skipped for holding no flame.
    pub skipped_empty: Vec<usize>,
    /// Frames dropped because the eigenflames reconstruct them worse than `max_residual`.
    pub skipped_quality: Vec<usize>,
    /// Fit quality of every frame that held one flame (kept or dropped by quality), in frame order.
    pub quality: Vec<FrameQuality>,
    /// What the user should know about the clip (flame cut by an edge, frames dropped).
    pub warnings: Vec<String>,
}

/// Column names of a parameter row: `path_0.., width_0.., eig_0.., height`.
pub fn param_names(path: usize, width: usize, eigen: usize) -> Vec<String> {
    let mut names: Vec<String> = (0..path).map(|k| format!("path_{k}")).collect();
    names.extend((0..width).map(|k| format!("width_{k}")));
    names.extend((0..eigen).map(|k| format!("eig_{k}")));
    names.push("height".into());
    names
}

/// Height of knot `k` of `n` equidistant samples on 0..1 (the middle for one sample).
pub fn knot(k: usize, n: usize) -> f64 {
    if n <= 1 { 0.5 } else { k as f64 / (n - 1) as f64 }
}

/// The normalization frame shared by all frames of a fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame0 {
    /// Base anchor (frame pixels).
    pub anchor: [f64; 2],
    /// Unit main axis, base → tip.
    pub axis: [f64; 2],
}

impl Frame0 {
    /// The axis turned +90° (x right, y down): points right for an upright flame.
    pub fn across(&self) -> [f64; 2] {
        [-self.axis[1], self.axis[0]]
    }
}

/// Per-frame shape: height, path and width samples, and the normalized image.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// Flame height in pixels.
    pub height: f64,
    /// Path samples (pixels across the axis).
    pub path: Vec<f64>,
    /// Width samples (σ across the axis, pixels).
    pub width: Vec<f64>,
}

/// Smallest width (pixels) a slice is given, so the normalization stays invertible.
pub const MIN_WIDTH: f64 = 0.5;

/// Measures the N_s height slices of one plume in frame `f0` for a flame of `height` pixels and
/// samples path and width at equidistant heights (§3.1).
pub fn measure_shape(plume: &Plume, f0: &Frame0, height: f64, s: &FitSettings) -> Shape {
    let ns = s.n_s.max(1);
    let across = f0.across();
    let mut acc = vec![[0.0_f64; 3]; ns];
    for y in 0..plume.height {
        for x in 0..plume.width {
            let val = plume.data[y * plume.width + x];
            if val <= 0.0 {
                continue;
            }
            let dx = (plume.x0 + x) as f64 + 0.5 - f0.anchor[0];
            let dy = (plume.y0 + y) as f64 + 0.5 - f0.anchor[1];
            let v = (dx * f0.axis[0] + dy * f0.axis[1]) / height;
            if v < -s.v_below || v > 1.0 + s.v_above {
                continue;
            }
            let t = dx * across[0] + dy * across[1];
            let j = ((v * ns as f64).floor().max(0.0) as usize).min(ns - 1);
            let w = f64::from(val);
            acc[j][0] += w;
            acc[j][1] += w * t;
            acc[j][2] += w * t * t;
        }
    }
    let peak = acc.iter().map(|a| a[0]).fold(0.0, f64::max);
    let valid: Vec<bool> = acc.iter().map(|a| a[0] > 1e-3 * peak && peak > 0.0).collect();
    let stats: Vec<Option<(f64, f64)>> = acc
        .iter()
        .zip(&valid)
        .map(|(a, &ok)| {
            ok.then(|| {
                let mean = a[1] / a[0];
                (mean, (a[2] / a[0] - mean * mean).max(0.0).sqrt().max(MIN_WIDTH))
            })
        })
        .collect();
    // Empty slices take the nearest measured slice's values.
    let filled: Vec<(f64, f64)> = (0..ns)
        .map(|j| {
            (0..ns)
                .flat_map(|d| [j.checked_sub(d), Some(j + d)])
                .flatten()
                .filter(|&k| k < ns)
                .find_map(|k| stats[k])
                .unwrap_or((0.0, MIN_WIDTH))
        })
        .collect();
    let path_slices: Vec<f64> = filled.iter().map(|p| p.0).collect();
    let width_slices: Vec<f64> = filled.iter().map(|p| p.1).collect();
    Shape {
        height,
        path: (0..s.n_p).map(|k| slice_value(&path_slices, knot(k, s.n_p))).collect(),
        width: (0..s.n_w).map(|k| slice_value(&width_slices, knot(k, s.n_w)).max(MIN_WIDTH)).collect(),
    }
}

/// Normalizes one plume into a `norm_size` image: the inverse of [`crate::model::render`]'s
/// deformation, sampled bilinearly.
pub fn normalize(plume: &Plume, f0: &Frame0, shape: &Shape, s: &FitSettings) -> Vec<f32> {
    let (nw, nh) = (s.norm_size().0 as usize, s.norm_size().1 as usize);
    let path = Spline::new(&shape.path);
    let width = Spline::new(&shape.width);
    let across = f0.across();
    let (v0, v1) = (-s.v_below, 1.0 + s.v_above);
    let mut out = vec![0.0_f32; nw * nh];
    for (r, row) in out.chunks_exact_mut(nw).enumerate() {
        let v = v1 - (r as f64 + 0.5) / nh as f64 * (v1 - v0);
        let (p, w) = (path.at(v), width.at(v).max(MIN_WIDTH));
        let base = [f0.anchor[0] + v * shape.height * f0.axis[0], f0.anchor[1] + v * shape.height * f0.axis[1]];
        for (c, o) in row.iter_mut().enumerate() {
            let u = -s.u_extent + (c as f64 + 0.5) / nw as f64 * 2.0 * s.u_extent;
            let t = p + u * w;
            *o = plume.sample(base[0] + t * across[0], base[1] + t * across[1]);
        }
    }
    out
}

/// Fits the model to analysed frames (see [`analyse_frame`]) of a `frame_size` clip at `fps`.
pub fn fit_frames(frames: &[Frame], frame_size: (u32, u32), s: &FitSettings, fps: f64) -> Result<Fit, String> {
    check_settings(s)?;
    let Sorted { kept, skipped_plumes, skipped_empty, flames } = sort_frames(frames, s)?;
    let (axes, f0) = normalization_frame(&flames, s)?;
    let edges = EdgeReport::of(&flames, frame_size, f0.axis);
    let mut warnings = Vec::new();
    if let Some(base) = edges.base_cut() {
        match s.cut_base {
            CutBase::Refuse => return Err(format!("{base} (cut_base: warn fits it anyway)")),
            CutBase::Warn => warnings.push(base),
        }
    }
    warnings.extend(edges.tip_cut());
    let (shaped, data, target) = normalized_images(&flames, &axes, &f0, s);
    let (db, residuals, used) = train_without_outliers(s, &data, &kept)?;
    let mut is_used = vec![false; shaped.len()];
    used.iter().for_each(|&f| is_used[f] = true);
    let skipped_quality: Vec<usize> = (0..shaped.len()).filter(|&f| !is_used[f]).map(|f| kept[f]).collect();
    if !skipped_quality.is_empty() {
        warnings.push(format!(
            "{} of {} frames dropped: the eigenflames reconstruct them with a relative error above max_residual {} ({})",
            skipped_quality.len(),
            shaped.len(),
            s.max_residual,
            list_for_message(&skipped_quality)
        ));
    }
    let quality: Vec<FrameQuality> = (0..shaped.len())
        .map(|f| FrameQuality { frame: kept[f], residual: residuals[f], edge: edges.touches[f], used: is_used[f] })
        .collect();
    let shaped: Vec<&Shaped> = used.iter().map(|&f| &shaped[f]).collect();
    let kept: Vec<usize> = used.iter().map(|&f| kept[f]).collect();
    let (model, params) = model_and_params(db, &shaped, &f0, target, frame_size, s, fps)?;
    Ok(Fit { model, params, kept, skipped_plumes, skipped_empty, skipped_quality, quality, warnings })
}

/// The frames of a clip sorted by what they hold.
struct Sorted<'a> {
    /// Frames holding one flame.
    kept: Vec<usize>,
    /// Frames showing two or more plumes.
    skipped_plumes: Vec<usize>,
    /// Frames holding no flame.
    skipped_empty: Vec<usize>,
    /// The flame of each kept frame.
    flames: Vec<&'a Plume>,
}

/// Sorts `frames` by what they hold; fewer than two frames of one flame is an error saying why.
fn sort_frames<'a>(frames: &'a [Frame], s: &FitSettings) -> Result<Sorted<'a>, String> {
    let mut kept = Vec::new();
    let mut skipped_plumes = Vec::new();
    let mut skipped_empty = Vec::new();
    let mut flames = Vec::new();
    for (i, f) in frames.iter().enumerate() {
        match f {
            Frame::Flame(p) => {
                kept.push(i);
                flames.push(p);
            }
            Frame::Empty => skipped_empty.push(i),
            Frame::Plumes(_) => skipped_plumes.push(i),
        }
    }
    if flames.is_empty() {
        return Err(if skipped_plumes.is_empty() {
            format!(
                "no flame found in any of the {} frames: every pixel is at or below the gray value {} (`threshold`, times the clip's peak brightness when relative_threshold is on; lower it, or check the footage is a bright flame on a dark background)",
                frames.len(),
                s.threshold
            )
        } else {
            format!(
                "all {} frames with a flame show two or more disjoint plumes, which the model cannot represent",
                skipped_plumes.len()
            )
        });
    }
    if flames.len() < 2 {
        return Err(format!("only {} frame holds a single flame; eigenflames need at least 2", flames.len()));
    }
    Ok(Sorted { kept, skipped_plumes, skipped_empty, flames })
}

/// A flame's main axis (unit direction) and its major σ along it.
type Axis = ([f64; 2], f64);

/// A frame's shape and its normalized image.
type Shaped = (Shape, Vec<f32>);

/// Each flame's main axis and major σ, and the normalization frame: the mean main axis
/// (averaged as doubled angles, orientation-free) and the mean base point.
fn normalization_frame(flames: &[&Plume], s: &FitSettings) -> Result<(Vec<Axis>, Frame0), String> {
    let axes: Vec<Axis> = flames
        .iter()
        .map(|p| p.moments.main_axes().map(|(d, major, _)| (d, major)).ok_or("a plume has no intensity"))
        .collect::<Result<_, _>>()?;
    let (c2, s2) = axes.iter().fold((0.0, 0.0), |(c, sn), (d, _)| {
        let th = d[1].atan2(d[0]);
        (c + (2.0 * th).cos(), sn + (2.0 * th).sin())
    });
    let th = 0.5 * s2.atan2(c2);
    let mut axis = [th.cos(), th.sin()];
    if axis[1] > 0.0 || (axis[1] == 0.0 && axis[0] < 0.0) {
        axis = [-axis[0], -axis[1]];
    }
    let mut anchor = [0.0, 0.0];
    for (p, (_, major)) in flames.iter().zip(&axes) {
        let c = p.moments.centroid().ok_or("a plume has no intensity")?;
        anchor[0] += c[0] - s.base_sigmas * major * axis[0];
        anchor[1] += c[1] - s.base_sigmas * major * axis[1];
    }
    anchor = [anchor[0] / flames.len() as f64, anchor[1] / flames.len() as f64];
    Ok((axes, Frame0 { anchor, axis }))
}

/// Per frame: height from the second-order moment along the main axis, slices, normalization;
/// then the normalized images one after another, scaled to the clip's average intensity
/// `target` (returned) when `normalize_intensity` is on.
fn normalized_images(flames: &[&Plume], axes: &[Axis], f0: &Frame0, s: &FitSettings) -> (Vec<Shaped>, Vec<f32>, f64) {
    let shaped: Vec<Shaped> = flames
        .par_iter()
        .zip(axes)
        .map(|(p, (_, major))| {
            let shape = measure_shape(p, f0, (s.height_sigmas * major).max(1.0), s);
            let img = normalize(p, f0, &shape, s);
            (shape, img)
        })
        .collect();

    let n = s.norm_size().0 as usize * s.norm_size().1 as usize;
    let mut data = Vec::with_capacity(n * shaped.len());
    let means: Vec<f64> = shaped.iter().map(|(_, img)| img.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64).collect();
    let target = means.iter().sum::<f64>() / means.len() as f64;
    for ((_, img), &m) in shaped.iter().zip(&means) {
        let gain = if s.normalize_intensity && m > 0.0 { (target / m) as f32 } else { 1.0 };
        data.extend(img.iter().map(|v| v * gain));
    }
    (shaped, data, target)
}

/// The eigenflames of the normalized images `data` (one per kept frame), trained again without
/// the frames they reconstruct worse than `max_residual`: the database, every frame's residual
/// and the frames used.
fn train_without_outliers(s: &FitSettings, data: &[f32], kept: &[usize]) -> Result<(Database, Vec<f64>, Vec<usize>), String> {
    let all: Vec<usize> = (0..kept.len()).collect();
    let (mut db, mut residuals) = train_scored(s, data, &all, kept)?;
    let mut used = all;
    if s.max_residual > 0.0 {
        let good: Vec<usize> = used.iter().copied().filter(|&f| residuals[f] <= s.max_residual).collect();
        if good.len() < used.len() {
            if good.len() < 2 {
                let mut sorted = residuals.clone();
                sorted.sort_by(f64::total_cmp);
                return Err(format!(
                    "only {} of {} frames are reconstructed within max_residual {}: raise it to at least {:.3} to keep two",
                    good.len(),
                    used.len(),
                    s.max_residual,
                    sorted.get(1).copied().unwrap_or(0.0)
                ));
            }
            // The eigenflames of the good frames alone; the dropped frames keep their first-pass
            // scores, the kept ones are scored again (and may then exceed the limit a little).
            let (db2, r2) = train_scored(s, data, &good, kept)?;
            for (&f, r) in good.iter().zip(r2) {
                residuals[f] = r;
            }
            db = db2;
            used = good;
        }
    }
    Ok((db, residuals, used))
}

/// The generic flame model and its parameter rows (path, width, eigenflame weights, height) of
/// the `shaped` frames used, from the eigenflames `db` trained on them.
fn model_and_params(
    db: Database,
    shaped: &[&Shaped],
    f0: &Frame0,
    target: f64,
    frame_size: (u32, u32),
    s: &FitSettings,
    fps: f64,
) -> Result<(FlameModel, ParamSeries), String> {
    let e = db.basis.components();
    let names = param_names(s.n_p, s.n_w, e);
    let dim = names.len();
    let mut rows = Vec::with_capacity(dim * shaped.len());
    for (f, (shape, _)) in shaped.iter().enumerate() {
        rows.extend_from_slice(&shape.path);
        rows.extend_from_slice(&shape.width);
        let w = db.weights.row(f).ok_or("missing weights row")?;
        rows.extend(w.iter().map(|&x| f64::from(x)));
        rows.push(shape.height);
    }
    let mean_params = (0..dim).map(|c| rows.iter().skip(c).step_by(dim).sum::<f64>() / shaped.len() as f64).collect();
    let params = ParamSeries::new(names, shaped.len(), rows, fps).ok_or("parameter rows have the wrong size")?;
    let model = FlameModel {
        path_samples: s.n_p,
        width_samples: s.n_w,
        eigenflames: e,
        width: s.norm_size().0,
        height: s.norm_size().1,
        mean: db.basis.mean,
        basis: db.basis.eigenvectors,
        eigenvalues: db.basis.eigenvalues,
        frame_size,
        anchor: f0.anchor,
        axis: f0.axis,
        v_range: [-s.v_below, 1.0 + s.v_above],
        u_extent: s.u_extent,
        mean_intensity: if s.normalize_intensity { target } else { 0.0 },
        mean_params,
    };
    Ok((model, params))
}

/// Analyses and fits row-major gray frames of one size (the node pulls clip frames instead).
pub fn fit_gray_frames(frames: &[Vec<f32>], frame_size: (u32, u32), s: &FitSettings, fps: f64) -> Result<Fit, String> {
    let (w, h) = (frame_size.0 as usize, frame_size.1 as usize);
    if let Some(i) = frames.iter().position(|f| f.len() != w * h) {
        return Err(format!("frame {i} has {} samples, expected {w}x{h}", frames[i].len()));
    }
    let peaks: Vec<f32> = frames.par_iter().map(|f| frame_peak(f)).collect();
    let s = &absolute(s, &peaks);
    let analysed: Vec<Frame> = frames.par_iter().map(|f| analyse_frame(f, w, h, s)).collect();
    fit_frames(&analysed, frame_size, s, fps)
}

/// The lowest clip peak a relative threshold is scaled by: two stops under full scale.
pub const MIN_PEAK: f32 = 0.25;

/// A frame's brightest finite gray value (0 for an empty frame).
pub fn frame_peak(gray: &[f32]) -> f32 {
    gray.iter().copied().filter(|v| v.is_finite()).fold(0.0, f32::max)
}

/// The settings with an absolute threshold: a relative one times the median of the frames'
/// `peaks` (a median, so a few flares or dark frames do not move it), taken as [`MIN_PEAK`] to 1.
pub fn absolute(s: &FitSettings, peaks: &[f32]) -> FitSettings {
    if !s.relative_threshold || peaks.is_empty() {
        return FitSettings { relative_threshold: false, ..s.clone() };
    }
    let mut sorted = peaks.to_vec();
    sorted.sort_by(f32::total_cmp);
    // A clip without a flame has a low peak too: a relative threshold would make its noise a
    // flame. Footage more than two stops under full scale needs a lower `threshold` instead.
    let peak = sorted[sorted.len() / 2].clamp(MIN_PEAK, 1.0);
    FitSettings { threshold: s.threshold * peak, relative_threshold: false, ..s.clone() }
}

fn check_settings(s: &FitSettings) -> Result<(), String> {
    if s.n_p == 0 || s.n_w == 0 || s.n_e == 0 || s.n_s == 0 {
        return Err("n_p, n_w, n_e and n_s must each be at least 1".into());
    }
    if s.norm_size().0 < 2 || s.norm_size().1 < 2 {
        return Err("the normalized image must be at least 2x2".into());
    }
    if !(s.height_sigmas > 0.0 && s.u_extent > 0.0 && s.v_below >= 0.0 && s.v_above >= 0.0) {
        return Err("height_sigmas and u_extent must be positive, v_below and v_above non-negative".into());
    }
    Ok(())
}
