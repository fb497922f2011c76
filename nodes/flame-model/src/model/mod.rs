//! The generic flame model of Stich & Magnor, "Learning Flames" (§3, §3.1, §3.2): nodes
//! `flame_model.fit` (frames → model + parameter series) and `flame_model.render`
//! (model + parameter series → gray and coloured frames).

pub mod fit;
pub mod fit_settings;
pub mod plume;
pub mod quality;
pub mod render;
pub mod shape;

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use crate::values::{FlameModel, ParamSeries};
use pyrograph_core::ValueType;
use pyrograph_core::declare::{ClipOf, Cook};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, CookCtx, FrameSource, Image, NodeError, PortType, Value, port};
use pyrograph_nodes_imaging::color::{ColorRamp, DEFAULT_RAMP};
use rayon::prelude::*;

pub use fit::{fit_frames, fit_gray_frames};
pub use fit_settings::{CutBase, FitSettings};
pub use plume::{Frame, Plume, analyse_frame};
pub use quality::FrameQuality;
pub use render::{Alpha, RenderSettings, colorize, render_frame};

/// Category of the learned-flame nodes in the editor.
pub const CATEGORY: &str = "Flame model";

/// Luma of an image as one gray plane (Rec. 601 weights for RGBA, as `imaging.to_gray`).
pub fn gray_plane(img: &Image) -> Vec<f32> {
    match img.channels() {
        Channels::Gray => img.data().to_vec(),
        Channels::Rgba => img.data().chunks_exact(4).map(|p| 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]).collect(),
    }
}

// ---------------------------------------------------------------------------------------------
// flame_model.fit
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Fits Stich & Magnor's generic flame model to flame footage (Learning Flames §3, §3.1, §3.2).
    ///
    /// Each frame's gray intensity is thresholded and its geometric moments up to order 3 (eq. 1) give the
    /// centroid, the main axes and the flame height (height_sigmas × σ along the main axis). The clip's mean
    /// main axis and base point fix the normalization frame. Each flame is cut into n_s height slices whose own
    /// moments give the path (centre across the axis) and the width (σ across the axis), sampled at n_p and n_w
    /// equidistant heights. Slices are centred and scaled by the cubic splines through those samples, the
    /// height scaled to 1 and (optionally) the intensity to the clip's average; PCA of these normalized
    /// images gives the eigenflames and n_e appearance weights per frame (fewer if the frames do not vary
    /// that much). Frames with two or more disjoint plumes (and frames with no flame) are skipped, as in §5, and
    /// with max_residual so are frames the eigenflames reconstruct badly; `skipped` counts them all, `quality` scores
    /// every frame. The threshold is relative to the clip's peak brightness by default. A clip whose flame base is
    /// outside the picture is refused (cut_base). Parameter rows are [path_0.., width_0.., eig_0.., height] in pixels.
    #[node("flame_model.fit", "Flame model", WholeClip)]
    pub struct FitModel {
        /// Flame frames on a dark background (gray or RGBA; RGBA uses luma).
        clip: ClipOf<Arc<Image>>,
        /// The fit's settings.
        settings: FitSettings,
    }
    pub struct FitModelOut {
        /// The generic flame model: normalization frame and eigenflames.
        model: Arc<FlameModel>,
        /// One parameter row per kept frame: path, width, eigenflame weights, height.
        params: Arc<ParamSeries>,
        /// Frames skipped: two or more disjoint plumes, no flame, or dropped by max_residual.
        skipped: usize,
        /// Fit quality of every frame holding one flame: its frame, the eigenflames' relative reconstruction error
        /// (residual), whether the flame touches an edge of the picture (1/0) and whether it is a row of params (1/0).
        quality: Arc<ParamSeries>,
    }
}

impl Cook for FitModel {
    fn cook(self, ctx: &CookCtx) -> Result<FitModelOut, NodeError> {
        let (clip, s) = (&*self.clip, &self.settings);
        let port = port!(FitModel, clip);
        if clip.is_empty() {
            return Err(NodeError::port(port, "the clip has no frames"));
        }
        let size = clip.image(0, ctx).map_err(|e| NodeError::port(port, e.to_string()))?.size();
        // A relative threshold needs the clip's peak before any frame is thresholded: one more
        // pass over the frames, keeping one number per frame rather than the frames.
        let peaks: Vec<f32> = if s.relative_threshold {
            (0..clip.len())
                .into_par_iter()
                .map(|f| {
                    ctx.check_cancel()?;
                    let img = clip.image(f, ctx).map_err(|e| NodeError::port(port, e.to_string()))?;
                    Ok(fit::frame_peak(&gray_plane(&img)))
                })
                .collect::<Result<_, NodeError>>()?
        } else {
            Vec::new()
        };
        let s = &fit::absolute(s, &peaks);
        let frames: Vec<Frame> = (0..clip.len())
            .into_par_iter()
            .map(|f| {
                ctx.check_cancel()?;
                let img = clip.image(f, ctx).map_err(|e| NodeError::port(port, e.to_string()))?;
                if img.size() != size {
                    return Err(NodeError::port(
                        port,
                        format!(
                            "frame {f} is {}x{} but frame 0 is {}x{}; every frame must be the same size",
                            img.width(),
                            img.height(),
                            size.0,
                            size.1
                        ),
                    ));
                }
                let a = analyse_frame(&gray_plane(&img), size.0 as usize, size.1 as usize, s);
                ctx.frame_progress(f + 1, clip.len());
                Ok(a)
            })
            .collect::<Result<_, NodeError>>()?;
        let fit = fit_frames(&frames, size, s, clip.fps()).map_err(|m| NodeError::port(port, m))?;
        for w in &fit.warnings {
            ctx.warn(w.clone());
        }
        let skipped = fit.skipped_plumes.len() + fit.skipped_empty.len() + fit.skipped_quality.len();
        let names = ["frame", "residual", "edge", "used"].map(String::from).to_vec();
        let rows = fit
            .quality
            .iter()
            .flat_map(|q| [q.frame as f64, q.residual, f64::from(u8::from(q.edge)), f64::from(u8::from(q.used))])
            .collect();
        let quality =
            ParamSeries::new(names, fit.quality.len(), rows, clip.fps()).ok_or_else(|| NodeError::port(port, "quality rows"))?;
        Ok(FitModelOut { model: Arc::new(fit.model), params: Arc::new(fit.params), skipped, quality: Arc::new(quality) })
    }
}

// ---------------------------------------------------------------------------------------------
// flame_model.render
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Renders Stich & Magnor's generic flame model, one frame per parameter row (Learning Flames §3.1–3.2, §4.3, §5.1).
    ///
    /// The normalized appearance is the mean image plus the eigenflames weighted by the row's eig_k; the
    /// inverse normalization places it in the frame: the height scales the main axis from the base, and the
    /// path and width samples, interpolated by natural cubic splines, shift and stretch every height slice.
    /// Frames are computed lazily (rows in parallel). §5.1's controls: bend adds an offset to the path that
    /// grows with the square of the height (wind), ramped in over bend_ramp frames; height_scale, width_scale
    /// and scale change the flame's height, width and size. `color` maps intensity × exposure through a colour
    /// ramp (the intensity → colour transfer function of §5.1).
    #[node("flame_model.render", "Flame model", PerFrame)]
    pub struct RenderModel {
        /// The fitted generic flame model (flame_model.fit).
        model: Arc<FlameModel>,
        /// Parameter rows (fitted or sampled by flame_model.arp_sample).
        params: Arc<ParamSeries>,
        /// Output width in pixels; 0 = the fitted footage's width.
        #[range(0, 16384)]
        width: u32 = 0,
        /// Output height in pixels; 0 = the fitted footage's height (the base keeps its distance from the bottom).
        #[range(0, 16384)]
        height: u32 = 0,
        /// Overall flame size about its base.
        #[range(0.01, 100.0)]
        scale: f64 = 1.0,
        /// Path offset at the tip in flame heights, growing with height² (wind bends the flame; + = right).
        #[range(-10.0, 10.0)]
        bend: f64 = 0.0,
        /// Frames over which the bend ramps in from 0; 0 = from the first frame.
        #[range(0, 1_000_000)]
        bend_ramp: usize = 0,
        /// Multiplies the height parameter.
        #[range(0.01, 100.0)]
        height_scale: f64 = 1.0,
        /// Multiplies the width parameters.
        #[range(0.01, 100.0)]
        width_scale: f64 = 1.0,
        /// Scale the fitted picture (e.g. an auto crop) to fit the output, so the flame's size does not depend on the
        /// footage's resolution; scale applies on top.
        fit_to_output: bool = false,
        /// Intensity → colour ramp of the color output: `[(position, (r, g, b)), …]`.
        ramp: ColorRamp = ColorRamp::preset(DEFAULT_RAMP),
        /// Intensity multiplier before the colour ramp.
        #[range(0.0, 100.0)]
        exposure: f32 = 1.0,
        /// Alpha of the color output: 1, or the clamped intensity.
        alpha: Alpha = Alpha::Opaque,
        /// Frame rate of the clips; 0 = the parameter series' rate.
        #[range(0.0, 1000.0)]
        fps: f64 = 0.0,
    }
    pub struct RenderModelOut {
        /// Gray flame frames, one per parameter row.
        clip: ClipOf<Arc<Image>>,
        /// RGBA frames coloured by the ramp.
        color: ClipOf<Arc<Image>>,
    }
}

struct RenderSource {
    model: Arc<FlameModel>,
    params: Arc<ParamSeries>,
    settings: RenderSettings,
}

impl FrameSource for RenderSource {
    fn len(&self) -> usize {
        self.params.frames
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        let port = port!(RenderModel, params);
        let row = self.params.row(index).ok_or_else(|| NodeError::port(port, format!("there is no row {index}")))?;
        let img = render_frame(&self.model, row, &self.settings, index).map_err(|m| NodeError::port(port, m))?;
        Ok(Value::Image(Arc::new(img)))
    }
}

struct ColorSource {
    gray: Clip,
    ramp: ColorRamp,
    exposure: f32,
    alpha: Alpha,
}

impl FrameSource for ColorSource {
    fn len(&self) -> usize {
        self.gray.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let g = self.gray.image(index, ctx)?;
        Ok(Value::Image(Arc::new(colorize(&g, &self.ramp, self.exposure, self.alpha))))
    }
}

impl Cook for RenderModel {
    fn cook(self, _: &CookCtx) -> Result<RenderModelOut, NodeError> {
        let RenderModel {
            model,
            params,
            width,
            height,
            scale,
            bend,
            bend_ramp,
            height_scale,
            width_scale,
            fit_to_output,
            ramp,
            exposure,
            alpha,
            fps,
        } = self;
        if params.frames == 0 {
            return Err(NodeError::port(port!(RenderModel, params), "there are no parameter rows to render"));
        }
        if params.dim() != model.dim() {
            return Err(NodeError::port(
                port!(RenderModel, params),
                format!(
                    "rows have {} parameters but the model needs {} (N_p {} + N_w {} + N_e {} + height); use the series of the same fit",
                    params.dim(),
                    model.dim(),
                    model.path_samples,
                    model.width_samples,
                    model.eigenflames
                ),
            ));
        }
        let settings = RenderSettings { size: (width, height), scale, bend, bend_ramp, height_scale, width_scale, fit_to_output };
        if settings.size.0 == 0 && model.frame_size.0 == 0 || settings.size.1 == 0 && model.frame_size.1 == 0 {
            return Err(NodeError::port(port!(RenderModel, width), "the model has no frame size; set width and height"));
        }
        let fps = match fps {
            f if f > 0.0 => f,
            _ if params.fps > 0.0 => params.fps,
            _ => 30.0,
        };
        let mut h = Fingerprinter::new();
        "flame_model.render".hash(&mut h);
        model.hash_into(&mut h);
        params.hash_into(&mut h);
        format!("{settings:?}").hash(&mut h);
        let gray_fp = h.finish();
        format!("{ramp:?}{exposure}{alpha:?}").hash(&mut h);
        let color_fp = h.finish();
        let gray = Clip::new(PortType::Image, fps, gray_fp, Arc::new(RenderSource { model, params, settings }));
        let color =
            Clip::new(PortType::Image, fps, color_fp, Arc::new(ColorSource { gray: gray.clone(), ramp, exposure, alpha }));
        Ok(RenderModelOut { clip: ClipOf::new(gray), color: ClipOf::new(color) })
    }
}

#[cfg(test)]
mod tests {
    use super::fit::{Frame0, measure_shape, normalize};
    use super::shape::Moments;
    use super::shape::tests::ellipse;
    use super::*;

    /// A synthetic candle flame: a swaying teardrop, brightest low down, `f` varies the shape.
    pub fn flame(w: usize, h: usize, f: usize) -> Vec<f32> {
        let ft = f as f64;
        let height = 90.0 + 10.0 * (0.9 * ft).sin();
        let sway = 7.0 * (0.6 * ft).sin();
        let base = [w as f64 / 2.0, h as f64 - 12.0];
        let mut out = vec![0.0_f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let v = (base[1] - (y as f64 + 0.5)) / height;
                if !(0.0..=1.0).contains(&v) {
                    continue;
                }
                let half =
                    15.0 * (std::f64::consts::PI * (v + 0.08) / 1.08).sin().max(0.0).powf(0.7) * (1.0 + 0.1 * (1.3 * ft).cos());
                let d = (x as f64 + 0.5 - base[0] - sway * v * v) / half.max(1e-6);
                let val = (1.0 - d * d).max(0.0) * (1.0 - 0.6 * v) * (0.9 + 0.1 * (2.1 * ft + 3.0 * v).sin());
                out[y * w + x] = val as f32;
            }
        }
        out
    }

    fn flames(w: usize, h: usize, m: usize) -> Vec<Vec<f32>> {
        (0..m).map(|f| flame(w, h, f)).collect()
    }

    #[test]
    fn normalization_aligns_a_rotated_ellipse_with_the_image_axes() {
        let (w, h) = (200, 200);
        let deg = -60.0_f64; // main axis 60° from the x axis, pointing up-right
        let frames: Vec<Vec<f32>> = (0..4).map(|k| ellipse(w, h, [100.0, 100.0], 60.0 + k as f64, 20.0, deg)).collect();
        // 4σ along the axis is the full length 2a of a uniform ellipse (the default 6σ suits real
        // flames, whose faint tips pull σ in).
        let s = FitSettings {
            threshold: 0.0,
            height_sigmas: 4.0,
            base_sigmas: 2.0,
            v_below: 0.1,
            v_above: 0.1,
            ..FitSettings::default()
        };
        let fit = fit_gray_frames(&frames, (w as u32, h as u32), &s, 24.0).unwrap();
        let m = &fit.model;
        let want = [deg.to_radians().cos(), deg.to_radians().sin()];
        assert!((m.axis[0] - want[0]).abs() < 1e-3 && (m.axis[1] - want[1]).abs() < 1e-3, "axis {:?} vs {want:?}", m.axis);
        // Height 4σ = 2a (the full length of the ellipse), path 0, width at the middle σ = b/2 of that slice.
        let row = fit.params.row(0).unwrap();
        let height = row[row.len() - 1];
        assert!((height - 120.0).abs() < 0.5, "height {height}");
        let dim_p = m.path_samples;
        assert!(row[..dim_p].iter().all(|p| p.abs() < 0.2), "path {:?}", &row[..dim_p]);
        // The anchor is the mean base of the ellipses: the centroid minus 2σ = a (mean 61.5) along the axis.
        let base = [100.0 - 61.5 * want[0], 100.0 - 61.5 * want[1]];
        assert!((m.anchor[0] - base[0]).abs() < 0.3 && (m.anchor[1] - base[1]).abs() < 0.3, "anchor {:?} vs {base:?}", m.anchor);
        // The normalized image's own moments: centred on the middle column, main axis vertical.
        let Frame::Flame(plume) = analyse_frame(&frames[0], w, h, &s) else { panic!("no flame") };
        let f0 = Frame0 { anchor: m.anchor, axis: m.axis };
        let shape = measure_shape(&plume, &f0, height, &s);
        let img = normalize(&plume, &f0, &shape, &s);
        let (nw, nh) = (s.norm_width as usize, s.norm_height as usize);
        let nm = Moments::of_image(&img, nw, nh);
        let (dir, major, minor) = nm.main_axes().unwrap();
        assert!(dir[0].abs() < 1e-3 && dir[1] < 0.0, "normalized main axis {dir:?}");
        assert!(major > 2.0 * minor);
        let c = nm.centroid().unwrap();
        assert!((c[0] - nw as f64 / 2.0).abs() < 0.05, "normalized centroid {c:?}");
        // Width samples follow the ellipse: widest in the middle, σ = half-chord / 2 · (2/√3)… within a pixel.
        let widths = &row[dim_p..dim_p + m.width_samples];
        let mid = widths[m.width_samples / 2];
        assert!(widths[0] < mid && widths[m.width_samples - 1] < mid, "{widths:?}");
        // A uniform chord of half-length c has σ = c/√3; the middle chord is b = 20.
        assert!((mid - 20.0 / 3.0_f64.sqrt()).abs() < 0.8, "mid width {mid}");
    }

    #[test]
    fn fit_then_render_with_all_eigenflames_reconstructs_a_training_frame() {
        let (w, h, m) = (96, 144, 12);
        let frames = flames(w, h, m);
        let s = FitSettings {
            n_e: m,
            normalize_intensity: false,
            norm_width: 64,
            norm_height: 128,
            threshold: 0.0,
            ..FitSettings::default()
        };
        let fit = fit_gray_frames(&frames, (w as u32, h as u32), &s, 24.0).unwrap();
        assert_eq!(fit.model.eigenflames, m - 1, "all M − 1 eigenflames");
        assert_eq!(fit.params.dim(), 10 + 10 + (m - 1) + 1);
        assert_eq!(fit.params.names[0], "path_0");
        assert_eq!(fit.params.names[20], "eig_0");
        assert_eq!(fit.params.names.last().unwrap(), "height");
        let mut worst = 0.0_f64;
        for f in [0, 5, 11] {
            let img = render_frame(&fit.model, fit.params.row(f).unwrap(), &RenderSettings::default(), f).unwrap();
            assert_eq!(img.size(), (w as u32, h as u32));
            let err: f64 = img.data().iter().zip(&frames[f]).map(|(a, b)| f64::from(a - b).powi(2)).sum::<f64>().sqrt();
            let norm: f64 = frames[f].iter().map(|b| f64::from(*b).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(err / norm);
        }
        println!("fit → render relative L2 error with all eigenflames: {worst:.4}");
        // Two bilinear resamplings (frame → 64×128 normalized → frame) blur the edges: the stated bound is 8 %.
        assert!(worst < 0.08, "relative error {worst}");
    }

    #[test]
    fn fewer_eigenflames_cost_accuracy_but_keep_the_shape() {
        let (w, h, m) = (96, 144, 12);
        let frames = flames(w, h, m);
        let s = FitSettings { n_e: 2, threshold: 0.0, ..FitSettings::default() };
        let fit = fit_gray_frames(&frames, (w as u32, h as u32), &s, 24.0).unwrap();
        assert_eq!(fit.params.dim(), 23);
        let img = render_frame(&fit.model, fit.params.row(3).unwrap(), &RenderSettings::default(), 3).unwrap();
        let err: f64 = img.data().iter().zip(&frames[3]).map(|(a, b)| f64::from(a - b).powi(2)).sum::<f64>().sqrt();
        let norm: f64 = frames[3].iter().map(|b| f64::from(*b).powi(2)).sum::<f64>().sqrt();
        assert!(err / norm < 0.2, "relative error {}", err / norm);
    }

    #[test]
    fn a_clip_without_flame_is_an_error() {
        let frames = vec![vec![0.02_f32; 32 * 32]; 5];
        let err = fit_gray_frames(&frames, (32, 32), &FitSettings::default(), 24.0).unwrap_err();
        assert!(err.contains("no flame") && err.contains("threshold"), "{err}");
    }

    #[test]
    fn a_two_plume_frame_is_skipped() {
        let (w, h) = (96, 144);
        let mut frames = flames(w, h, 6);
        // Frame 2: a second, detached plume beside the flame.
        for y in 20..50 {
            for x in 80..92 {
                frames[2][y * w + x] = 0.8;
            }
        }
        // Frame 4: a tiny speck (under min_plume) is removed, not a plume.
        frames[4][5 * w + 5] = 1.0;
        let fit = fit_gray_frames(&frames, (w as u32, h as u32), &FitSettings::default(), 24.0).unwrap();
        assert_eq!(fit.skipped_plumes, vec![2]);
        assert_eq!(fit.kept, vec![0, 1, 3, 4, 5]);
        assert_eq!(fit.params.frames, 5);
        assert!(matches!(analyse_frame(&frames[2], w, h, &FitSettings::default()), Frame::Plumes(2)));
    }

    #[test]
    fn a_clip_with_the_flame_base_outside_the_picture_is_refused_or_fitted_with_a_warning() {
        let (w, h) = (96, 144);
        // The synthetic flame's base is 12 rows above the bottom: cutting 30 rows cuts it off.
        let cut: Vec<Vec<f32>> = flames(w, h, 8).into_iter().map(|f| f[..w * (h - 30)].to_vec()).collect();
        let size = (w as u32, (h - 30) as u32);
        let err = fit_gray_frames(&cut, size, &FitSettings::default(), 24.0).unwrap_err();
        assert!(
            err.contains("touches the bottom edge in 100 % of frames: its base is outside the picture")
                && err.contains("cut_base"),
            "{err}"
        );
        let fit = fit_gray_frames(&cut, size, &FitSettings { cut_base: CutBase::Warn, ..FitSettings::default() }, 24.0).unwrap();
        assert_eq!(fit.warnings.len(), 1, "{:?}", fit.warnings);
        assert!(fit.warnings[0].contains("base is outside"));
        assert!(fit.quality.iter().all(|q| q.edge && q.used));
        // The whole flame: no warning, no edge.
        let whole = fit_gray_frames(&flames(w, h, 8), (w as u32, h as u32), &FitSettings::default(), 24.0).unwrap();
        assert!(whole.warnings.is_empty(), "{:?}", whole.warnings);
        assert!(whole.quality.iter().all(|q| !q.edge));
    }

    #[test]
    fn a_darker_clip_fits_the_same_shapes_with_the_relative_threshold() {
        let (w, h, m) = (96, 144, 8);
        let bright = flames(w, h, m);
        let dark: Vec<Vec<f32>> = bright.iter().map(|f| f.iter().map(|v| 0.4 * v).collect()).collect();
        let size = (w as u32, h as u32);
        let heights = |s: &FitSettings, frames: &[Vec<f32>]| -> Vec<f64> {
            let fit = fit_gray_frames(frames, size, s, 24.0).unwrap();
            (0..m).map(|r| *fit.params.row(r).unwrap().last().unwrap()).collect()
        };
        let s = FitSettings { threshold: 0.2, ..FitSettings::default() };
        let (a, b) = (heights(&s, &bright), heights(&s, &dark));
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6 * x), "{a:?} vs {b:?}");
        // An absolute threshold cuts the darker flame smaller.
        let abs = FitSettings { relative_threshold: false, ..s };
        let c = heights(&abs, &dark);
        assert!(a.iter().zip(&c).all(|(x, y)| y < &(0.98 * x)), "{a:?} vs {c:?}");
    }

    #[test]
    fn frames_the_eigenflames_reconstruct_badly_are_dropped_and_reported() {
        let (w, h, m) = (96, 144, 16);
        let s = FitSettings { n_e: 2, ..FitSettings::default() };
        // Frame 0 is empty, so positions among the flame frames and clip frames differ by one.
        let mut clip = vec![vec![0.0_f32; w * h]];
        clip.extend(flames(w, h, m));
        let size = (w as u32, h as u32);
        let all = fit_gray_frames(&clip, size, &s, 24.0).unwrap();
        assert_eq!(all.quality.len(), m);
        assert_eq!(all.quality[0].frame, 1);
        assert!(all.quality.iter().all(|q| q.used && q.residual > 0.0 && q.residual < 1.0), "{:?}", all.quality);
        let mut sorted: Vec<f64> = all.quality.iter().map(|q| q.residual).collect();
        sorted.sort_by(f64::total_cmp);
        // Between the 12th and 13th smallest: the four worst frames go.
        let limit = 0.5 * (sorted[11] + sorted[12]);
        let worst: Vec<usize> = all.quality.iter().filter(|q| q.residual > limit).map(|q| q.frame).collect();
        assert_eq!(worst.len(), 4);
        let fit = fit_gray_frames(&clip, size, &FitSettings { max_residual: limit, ..s }, 24.0).unwrap();
        assert_eq!(fit.skipped_quality, worst);
        assert_eq!(fit.skipped_empty, vec![0]);
        assert_eq!(fit.params.frames, m - 4);
        assert!(fit.kept.iter().all(|f| *f >= 1 && !worst.contains(f)));
        assert_eq!(fit.quality.iter().filter(|q| !q.used).map(|q| q.frame).collect::<Vec<_>>(), worst);
        assert!(fit.warnings.iter().any(|w| w.contains("4 of 16 frames dropped")), "{:?}", fit.warnings);
        // A limit nothing meets is an error that says what limit keeps two frames.
        let err = fit_gray_frames(&clip, size, &FitSettings { max_residual: 1e-9, ..s }, 24.0).unwrap_err();
        assert!(err.contains("max_residual") && err.contains(&format!("at least {:.3} to keep two", sorted[1])), "{err}");
    }

    #[test]
    fn bend_offsets_the_tip_and_scales_change_the_size() {
        let (w, h, m) = (96, 144, 6);
        let fit = fit_gray_frames(&flames(w, h, m), (w as u32, h as u32), &FitSettings::default(), 24.0).unwrap();
        let row = fit.params.row(0).unwrap();
        let plain = render_frame(&fit.model, row, &RenderSettings::default(), 0).unwrap();
        let bent = render_frame(&fit.model, row, &RenderSettings { bend: 0.2, ..RenderSettings::default() }, 0).unwrap();
        let top_x = |img: &Image| {
            let m = Moments::of_image(&img.data()[..60 * w], w, 60);
            m.centroid().unwrap()[0]
        };
        assert!(top_x(&bent) > top_x(&plain) + 5.0, "{} vs {}", top_x(&bent), top_x(&plain));
        let ramped = RenderSettings { bend: 0.2, bend_ramp: 10, ..RenderSettings::default() };
        assert_eq!(render::bend_at(&ramped, 0), 0.0);
        assert!((render::bend_at(&ramped, 5) - 0.1).abs() < 1e-12);
        let tall = render_frame(&fit.model, row, &RenderSettings { height_scale: 1.2, ..RenderSettings::default() }, 0).unwrap();
        let mass = |img: &Image| img.data().iter().map(|&v| f64::from(v)).sum::<f64>();
        assert!(mass(&tall) > 1.1 * mass(&plain));
        let out = render_frame(&fit.model, row, &RenderSettings { size: (480, 480), ..RenderSettings::default() }, 0).unwrap();
        assert_eq!(out.size(), (480, 480));
        assert!(mass(&out) > 0.9 * mass(&plain) && mass(&out) < 1.1 * mass(&plain));
        // Fitted into an output twice as large (and wider), the flame is twice as tall: four times the mass.
        let fitted = RenderSettings { size: (2 * w as u32 + 40, 2 * h as u32), fit_to_output: true, ..RenderSettings::default() };
        let big = render_frame(&fit.model, row, &fitted, 0).unwrap();
        let ratio = mass(&big) / mass(&plain);
        assert!((ratio - 4.0).abs() < 0.2, "mass ratio {ratio}");
        let rows_of = |img: &Image| {
            let wd = img.width() as usize;
            let lit: Vec<usize> =
                img.data().chunks_exact(wd).enumerate().filter(|(_, r)| r.iter().any(|&v| v > 0.05)).map(|(y, _)| y).collect();
            (lit[0], lit[lit.len() - 1])
        };
        let ((t0, b0), (t1, b1)) = (rows_of(&plain), rows_of(&big));
        assert!(((b1 - t1) as f64 / (b0 - t0) as f64 - 2.0).abs() < 0.1, "heights {} and {}", b0 - t0, b1 - t1);
        assert!(((2 * h - b1) as f64 - 2.0 * (h - b0) as f64).abs() <= 3.0, "the base keeps its scaled distance from the bottom");
    }

    #[test]
    fn a_row_of_the_wrong_length_is_an_error() {
        let (w, h) = (96, 144);
        let fit = fit_gray_frames(&flames(w, h, 4), (w as u32, h as u32), &FitSettings::default(), 24.0).unwrap();
        let err = render_frame(&fit.model, &[1.0; 5], &RenderSettings::default(), 0).unwrap_err();
        assert!(err.contains("needs"), "{err}");
    }

    #[test]
    fn nodes_cook_through_a_graph_of_clips() {
        use pyrograph_core::testing::cook;
        let (w, h) = (64, 96);
        let frames: Vec<Value> = (0..6)
            .map(|f| Value::Image(Arc::new(Image::from_vec(w, h, Channels::Gray, flame(w as usize, h as usize, f)).unwrap())))
            .collect();
        let clip = Clip::from_frames(PortType::Image, 24.0, frames);
        let ctx = CookCtx::new();
        let out = cook::<FitModel>(&[("clip", Value::Clip(clip))]).unwrap();
        let Value::Int(skipped) = out[2] else { panic!() };
        assert_eq!(skipped, 0);
        let quality = out[3].downcast::<ParamSeries>().expect("quality is a parameter series");
        assert_eq!(quality.names, ["frame", "residual", "edge", "used"]);
        assert_eq!(quality.frames, 6);
        assert_eq!(quality.row(5).unwrap()[0], 5.0);
        let rendered = cook::<RenderModel>(&[("model", out[0].clone()), ("params", out[1].clone())]).unwrap();
        let Value::Clip(gray) = &rendered[0] else { panic!() };
        let Value::Clip(color) = &rendered[1] else { panic!() };
        assert_eq!(gray.len(), 6);
        assert_eq!(gray.image(3, &ctx).unwrap().size(), (w, h));
        let c = color.image(3, &ctx).unwrap();
        assert_eq!(c.channels(), Channels::Rgba);
        assert!(c.data().chunks_exact(4).any(|p| p[0] > 0.5));
    }
}
