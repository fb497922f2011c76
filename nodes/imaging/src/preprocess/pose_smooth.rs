//! `imaging.smooth_angle`: the per-frame lean of `imaging.pose_normalize`, smoothed over the clip
//! so straightening a flicking flame does not make the whole frame wobble (issue 27). The thesis
//! (§3.4) normalizes each frame on its own; on moving footage the fitted axis jitters by a few
//! degrees from frame to frame, and turning the frame by it adds that jitter to the background
//! and the flame's base.

use pyrograph_core::{Clip, ClipOf, Contour, Cook, CookCtx, NodeError, PortType, Value, port};

/// The median of each window of `2·radius + 1` values, the window shrinking symmetrically at the
/// ends (so it stays centred): one frame whose fit failed (an empty mask reads 0°) cannot pull
/// its neighbours.
pub fn median_filter(values: &[f64], radius: usize) -> Vec<f64> {
    let n = values.len();
    (0..n)
        .map(|i| {
            let r = radius.min(i).min(n - 1 - i);
            let (lo, hi) = (i - r, i + r + 1);
            let mut w: Vec<f64> = values[lo..hi].to_vec();
            w.sort_by(f64::total_cmp);
            w[w.len() / 2]
        })
        .collect()
}

/// A Gaussian of `sigma` frames over `values`, the edges mirrored (so the first and last frames
/// are not pulled towards zero); `sigma` 0 returns the values.
pub fn gaussian_filter(values: &[f64], sigma: f64) -> Vec<f64> {
    if sigma <= 0.0 || values.len() < 2 {
        return values.to_vec();
    }
    let r = (3.0 * sigma).ceil() as isize;
    let n = values.len() as isize;
    let weights: Vec<f64> = (-r..=r).map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let total: f64 = weights.iter().sum();
    // Mirror about the ends (…, v2, v1, v0, v1, v2, …), folding again for windows longer than the clip.
    let at = |mut j: isize| {
        let period = 2 * (n - 1);
        j = j.rem_euclid(period);
        if j >= n { values[(period - j) as usize] } else { values[j as usize] }
    };
    (0..n).map(|i| (-r..=r).zip(&weights).map(|(k, w)| w * at(i + k)).sum::<f64>() / total).collect()
}

/// How much longer than wide the region inside an outline is: the square root of the ratio of
/// the principal second moments of its polygon (Green's theorem over the edges), so an ellipse
/// reads the ratio of its axes whatever its lean, a disc 1, and a degenerate outline 0.
pub fn outline_elongation(contour: &Contour) -> f64 {
    let p = &contour.points;
    let n = p.len();
    if n < 3 {
        return 0.0;
    }
    // Sums over the edges of the polygon's area and first and second moments (times 2, 6, 12, 24).
    let (mut a, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let (x0, y0) = (f64::from(p[k][0]), f64::from(p[k][1]));
        let (x1, y1) = (f64::from(p[(k + 1) % n][0]), f64::from(p[(k + 1) % n][1]));
        let c = x0 * y1 - x1 * y0;
        a += c;
        (sx, sy) = (sx + (x0 + x1) * c, sy + (y0 + y1) * c);
        sxx += (x0 * x0 + x0 * x1 + x1 * x1) * c;
        syy += (y0 * y0 + y0 * y1 + y1 * y1) * c;
        sxy += (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * c;
    }
    if a.abs() < 1e-9 {
        return 0.0;
    }
    let area = 0.5 * a;
    let (cx, cy) = (sx / (6.0 * area), sy / (6.0 * area));
    let (vxx, vyy, vxy) = (sxx / (12.0 * area) - cx * cx, syy / (12.0 * area) - cy * cy, sxy / (24.0 * area) - cx * cy);
    let (half_sum, root) = (0.5 * (vxx + vyy), (0.25 * (vxx - vyy).powi(2) + vxy * vxy).sqrt());
    let (major, minor) = (half_sum + root, half_sum - root);
    if major <= 0.0 {
        return 0.0;
    }
    // A region of no width: as long as a very long one.
    if minor <= major * 1e-12 { 1e6 } else { (major / minor).sqrt() }
}

/// What the clip's outlines say about straightening it, when they say there is no single axis
/// to straighten: the reason, in the user's terms. A frame counts when its outline was fitted
/// (`elongation` > 0). Judged over the clip, not per frame, so a whole shot is treated one way:
/// - several separate fires in at least half the frames (`fires`; a row of candles, a forest fire
///   seen through trees): one lean cannot straighten them all;
/// - an outline about as wide as tall (median elongation under `min_elongation`: a log pile, a
///   fireplace, a frame-filling blaze), whose principal axis follows the logs or the firebox
///   rather than the flames;
/// - an axis that swings (the fitted lean's median absolute deviation over the clip, scaled to a
///   standard deviation, over `max_swing` degrees): a fire whose shape has no lasting direction.
pub fn no_single_axis(angles: &[f64], elongation: &[f64], fires: &[i64], min_elongation: f64, max_swing: f64) -> Option<String> {
    let fitted: Vec<usize> = (0..elongation.len().min(angles.len())).filter(|i| elongation[*i] > 0.0).collect();
    if fitted.is_empty() {
        return None;
    }
    let n = fitted.len();
    let several = fitted.iter().filter(|i| fires.get(**i).is_some_and(|f| *f > 1)).count();
    if 2 * several >= n {
        return Some(format!("{several} of its {n} frames hold several separate fires"));
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let elongated = median(fitted.iter().map(|i| elongation[*i]).collect());
    if elongated < min_elongation {
        return Some(format!(
            "its outline is about as wide as it is tall: median elongation {elongated:.2}, under min_elongation {min_elongation}"
        ));
    }
    let centre = median(fitted.iter().map(|i| angles[*i]).collect());
    let swing = 1.4826 * median(fitted.iter().map(|i| (angles[*i] - centre).abs()).collect());
    if swing > max_swing {
        return Some(format!("its fitted axis swings about ±{swing:.0}° from frame to frame, over max_swing ({max_swing}°)"));
    }
    None
}

/// The warning for a clip left upright, with its reason.
pub fn upright_warning(reason: &str) -> String {
    format!(
        "left upright: the fire has no single axis to straighten ({reason}), so no frame is turned; to straighten one \
         flame, keep only it (imaging.fire_regions' select) or crop to it"
    )
}

pyrograph_core::node! {
    /// Smooths the per-frame lean of imaging.pose_normalize over the clip (extends Eigenfires thesis §3.4 to moving footage): a median of 2·median_radius + 1 frames drops single-frame outliers, then a Gaussian of sigma frames (edges mirrored) removes the jitter.
    ///
    /// With pose_normalize's elongation and fires connected it first judges, over the whole clip, whether the fire has a single axis at all: several separate fires in half the frames, an outline less than min_elongation times longer than wide (a log pile, a fireplace), or an axis swinging more than max_swing degrees leave every frame upright (angle 0), with a warning that says which.
    ///
    /// Connect pose_normalize's angle (a clip when it runs per frame) here and this node's angle to a second pose_normalize's lean with use_lean on: the frames are then straightened by the smoothed lean.
    #[node("imaging.smooth_angle", "Pre-processing", WholeClip)]
    pub struct SmoothAngle {
        /// Per-frame angle in degrees (imaging.pose_normalize's angle)
        angle: ClipOf<f64>,
        /// Half-width of the median window in frames (0: none)
        #[range(0, 100)]
        median_radius: usize = 2,
        /// Gaussian sigma in frames (0: none)
        #[range(0.0, 100.0)]
        sigma: f64 = 2.0,
        /// Per-frame elongation of the outline (imaging.pose_normalize's elongation): connect it, and fires, for the judgement of fires with no single axis
        elongation: ClipOf<f64> = ClipOf::new(Clip::from_frames(PortType::Float, 24.0, Vec::new())),
        /// Per-frame count of separate fires (imaging.pose_normalize's fires)
        fires: ClipOf<i64> = ClipOf::new(Clip::from_frames(PortType::Int, 24.0, Vec::new())),
        /// With elongation connected: a fire whose outline is, over the clip, less than this many times longer than wide has no single axis and is left upright
        #[range(1.0, 10.0)]
        min_elongation: f64 = 1.4,
        /// With elongation connected: a fitted axis swinging more than this (degrees, as a standard deviation over the clip) has no lasting direction and is left upright
        #[range(0.0, 180.0)]
        max_swing: f64 = 15.0,
    }
    /// Smoothed angle per frame, in degrees
    -> angle: ClipOf<f64>
}

impl SmoothAngle {
    /// Reads a clip of numbers an input carries (empty when the input is not connected).
    fn numbers<T>(
        clip: &Clip,
        ctx: &CookCtx,
        read: impl Fn(&Value) -> Option<T> + Sync,
        port: &'static str,
    ) -> Result<Vec<T>, NodeError>
    where
        T: Send,
    {
        use rayon::prelude::*;
        (0..clip.len())
            .into_par_iter()
            .with_min_len(crate::media::long_runs(clip.len()))
            .map(|i| {
                ctx.check_cancel()?;
                let v = clip.get(i, ctx)?;
                read(&v).ok_or_else(|| NodeError::port(port, format!("frame {i} is {}, not a number", v.summary())))
            })
            .collect()
    }
}

impl Cook for SmoothAngle {
    fn cook(self, ctx: &CookCtx) -> Result<ClipOf<f64>, NodeError> {
        let clip: &Clip = &self.angle;
        if clip.is_empty() {
            return Err(NodeError::port(port!(SmoothAngle, angle), "the angle clip has no frames"));
        }
        // Every frame's angle cooks the per-frame chain above it: in parallel, in frame order,
        // each thread along long runs of frames (a video decodes forward; see auto_crop).
        use rayon::prelude::*;
        let values = (0..clip.len())
            .into_par_iter()
            .with_min_len(crate::media::long_runs(clip.len()))
            .map(|i| {
                ctx.check_cancel()?;
                match clip.get(i, ctx)? {
                    Value::Float(v) if v.is_finite() => Ok(v),
                    Value::Float(v) => Err(NodeError::port(port!(SmoothAngle, angle), format!("frame {i} has the angle {v}"))),
                    other => {
                        Err(NodeError::port(port!(SmoothAngle, angle), format!("frame {i} is {}, not an angle", other.summary())))
                    }
                }
            })
            .collect::<Result<Vec<f64>, NodeError>>()?;
        let elongation = Self::numbers(
            &self.elongation,
            ctx,
            |v| if let Value::Float(x) = v { Some(*x) } else { None },
            port!(SmoothAngle, elongation),
        )?;
        let fires =
            Self::numbers(&self.fires, ctx, |v| if let Value::Int(n) = v { Some(*n) } else { None }, port!(SmoothAngle, fires))?;
        for (len, port) in [(elongation.len(), port!(SmoothAngle, elongation)), (fires.len(), port!(SmoothAngle, fires))] {
            if len != 0 && len != values.len() {
                return Err(NodeError::port(port, format!("{len} frames, but the angle clip has {}", values.len())));
            }
        }
        if let Some(reason) = no_single_axis(&values, &elongation, &fires, self.min_elongation, self.max_swing) {
            ctx.warn(upright_warning(&reason));
            let frames = vec![Value::Float(0.0); values.len()];
            return Ok(ClipOf::new(Clip::from_frames(PortType::Float, clip.fps(), frames)));
        }
        let smooth = gaussian_filter(&median_filter(&values, self.median_radius), self.sigma);
        let frames = smooth.into_iter().map(Value::Float).collect();
        Ok(ClipOf::new(Clip::from_frames(PortType::Float, clip.fps(), frames)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_outlier_is_dropped_and_jitter_shrinks() {
        // A flame leaning 10° with about ±3° of jitter and one failed frame reading 0°.
        let mut v: Vec<f64> = (0..60).map(|i| 10.0 + 3.0 * (f64::from(i) * 2.3).sin()).collect();
        v[27] = 0.0;
        let s = gaussian_filter(&median_filter(&v, 2), 2.0);
        assert_eq!(s.len(), 60);
        let rms = |x: &[f64]| (x.iter().map(|a| (a - 10.0).powi(2)).sum::<f64>() / x.len() as f64).sqrt();
        let (before, after) = (rms(&v), rms(&s));
        assert!(after < 0.35 * before, "jitter {before:.2}° → {after:.2}°");
        assert!((s[27] - 10.0).abs() < 1.5, "the outlier is gone: {}", s[27]);
    }

    #[test]
    fn edges_are_mirrored_and_a_ramp_stays_a_ramp() {
        let ramp: Vec<f64> = (0..20).map(f64::from).collect();
        let s = gaussian_filter(&ramp, 1.5);
        // Inside, a straight line is its own average.
        for i in 5..15 {
            assert!((s[i] - ramp[i]).abs() < 1e-9, "{i}: {}", s[i]);
        }
        // A constant stays constant up to the ends (no pull towards 0).
        let c = gaussian_filter(&[7.0; 5], 4.0);
        assert!(c.iter().all(|x| (x - 7.0).abs() < 1e-12), "{c:?}");
        assert_eq!(gaussian_filter(&[1.0, 2.0], 0.0), vec![1.0, 2.0]);
        assert_eq!(median_filter(&[3.0], 5), vec![3.0]);
    }

    #[test]
    fn a_graph_straightens_by_the_smoothed_lean() {
        use crate::io::{OutputFormat, write_image};
        use crate::preprocess::pose::tests::ellipse_mask;
        use pyrograph_core::{BuildOptions, Channels, Evaluator, Graph, GraphDoc, Image, Registry};
        // Twelve frames of a flame leaning 20° whose fitted lean jitters by up to 5°.
        let dir = tempfile::tempdir().unwrap();
        let jitter = [4.0, -3.0, 5.0, -4.0, 2.0, -5.0, 3.0, -2.0, 4.0, -3.0, 5.0, -4.0];
        for (i, j) in jitter.iter().enumerate() {
            let m = ellipse_mask(96, 96, (48.0, 50.0), (7.0, 28.0), 20.0 + j);
            let data = m.data().iter().flat_map(|&v| if v > 0 { [1.0; 4] } else { [0.0, 0.0, 0.0, 1.0] }).collect();
            let img = Image::from_vec(96, 96, Channels::Rgba, data).unwrap();
            write_image(&img, &dir.path().join(format!("f_{i:02}.png")), OutputFormat::Png { sixteen_bit: false }, false)
                .unwrap();
        }
        let doc = GraphDoc::from_ron(
            r#"(version: 1, nodes: {
                "frames": (type: "imaging.load_sequence", params: {"path": "."}),
                "mask": (type: "imaging.hsv_mask", params: {"layer1_enabled": true, "layer1_h_min": 0.0, "layer1_h_max": 360.0,
                    "layer1_s_min": 0.0, "layer1_s_max": 255.0, "layer1_v_min": 128.0, "layer1_v_max": 255.0,
                    "layer2_enabled": false, "layer3_enabled": false}),
                "contours": (type: "imaging.contours"),
                "pose": (type: "imaging.pose_normalize"),
                "smooth": (type: "imaging.smooth_angle", params: {"median_radius": 1, "sigma": 2.0}),
                "steady": (type: "imaging.pose_normalize", params: {"use_lean": true}),
            }, edges: [
                ("frames.clip", "mask.image"), ("mask.mask", "contours.mask"),
                ("frames.clip", "pose.image"), ("contours.contours", "pose.contours"), ("pose.angle", "smooth.angle"),
                ("frames.clip", "steady.image"), ("contours.contours", "steady.contours"), ("smooth.angle", "steady.lean"),
            ])"#,
        )
        .unwrap();
        let mut r = Registry::with_builtins();
        crate::register(&mut r);
        let g = Graph::build(&doc, &r, dir.path(), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
        let ctx = CookCtx::new();
        let mut ev = Evaluator::new();
        let turns = |ev: &mut Evaluator, endpoint: &str| -> Vec<f64> {
            let Value::Clip(c) = ev.output(&g, endpoint, &ctx).unwrap() else { panic!("{endpoint} is not a clip") };
            (0..c.len()).map(|i| if let Value::Float(v) = c.get(i, &ctx).unwrap() { v } else { f64::NAN }).collect()
        };
        let (raw, steady) = (turns(&mut ev, "pose.turned"), turns(&mut ev, "steady.turned"));
        assert_eq!((raw.len(), steady.len()), (12, 12));
        let spread = |x: &[f64]| {
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            (x.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
        };
        assert!((spread(&raw) - 3.6).abs() < 1.0, "the fitted lean follows the jitter: {raw:?}");
        assert!(spread(&steady) < 0.4 * spread(&raw), "smoothed turns {steady:?} against {raw:?}");
        let mean = steady.iter().sum::<f64>() / 12.0;
        assert!((mean - 20.0).abs() < 1.5, "still straightened by about 20°: {mean}");
    }

    /// The node over these per-frame angles, elongations and fire counts (empty: not connected).
    fn smoother(angles: &[f64], elongation: &[f64], fires: &[i64]) -> SmoothAngle {
        fn clip<T>(t: PortType, v: Vec<Value>) -> ClipOf<T> {
            ClipOf::new(Clip::from_frames(t, 24.0, v))
        }
        SmoothAngle {
            angle: clip(PortType::Float, angles.iter().map(|a| Value::Float(*a)).collect()),
            median_radius: 0,
            sigma: 1.0,
            elongation: clip(PortType::Float, elongation.iter().map(|a| Value::Float(*a)).collect()),
            fires: clip(PortType::Int, fires.iter().map(|n| Value::Int(*n)).collect()),
            min_elongation: 1.4,
            max_swing: 15.0,
        }
    }

    #[test]
    fn a_fire_with_no_single_axis_is_left_upright_and_the_warning_says_why() {
        let lean = [12.0, 13.0, 11.5, 12.5, 12.0, 13.5];
        let ctx = CookCtx::new();
        let angles = |n: SmoothAngle, ctx: &CookCtx| -> Vec<f64> {
            let out = n.cook(ctx).unwrap();
            (0..out.len()).map(|i| if let Value::Float(v) = out.get(i, ctx).unwrap() { v } else { f64::NAN }).collect()
        };
        // A flame three times longer than wide, one fire, a steady lean: straightened.
        let flame = angles(smoother(&lean, &[3.0; 6], &[1; 6]), &ctx);
        assert!(flame.iter().all(|a| (a - 12.5).abs() < 1.5), "{flame:?}");
        assert!(ctx.warnings().is_empty());
        // Unconnected judgement inputs: straightened as before.
        assert!(angles(smoother(&lean, &[], &[]), &ctx).iter().all(|a| *a > 10.0));
        for (elongation, fires, swing, reason) in
            [(1.1, 1, 0.0, "as wide as it is tall"), (3.0, 2, 0.0, "several separate fires"), (3.0, 1, 30.0, "swings")]
        {
            let ctx = CookCtx::new();
            let swung: Vec<f64> = lean.iter().enumerate().map(|(i, a)| a + if i % 2 == 0 { swing } else { -swing }).collect();
            let out = angles(smoother(&swung, &[elongation; 6], &[fires; 6]), &ctx);
            assert!(out.iter().all(|a| *a == 0.0), "{reason}: {out:?}");
            let w: Vec<String> = ctx.warnings().into_iter().map(|w| w.message).collect();
            assert!(w.len() == 1 && w[0].contains("left upright") && w[0].contains(reason), "{w:?}");
        }
        // A judgement input of another length is refused, naming it.
        let e = smoother(&lean, &[3.0; 4], &[]).cook(&CookCtx::new()).unwrap_err().to_string();
        assert!(e.contains("elongation") && e.contains("4 frames"), "{e}");
    }

    #[test]
    fn elongation_is_the_ratio_of_an_outlines_axes_whatever_its_lean() {
        use crate::preprocess::contours::trace_contours;
        use crate::preprocess::pose::main_contour;
        use crate::preprocess::pose::tests::ellipse_mask;
        for (axes, lean) in [((10.0, 30.0), 0.0), ((10.0, 30.0), 50.0), ((20.0, 20.0), 0.0), ((30.0, 12.0), 0.0)] {
            let m = ellipse_mask(128, 128, (64.0, 64.0), axes, lean);
            let e = outline_elongation(main_contour(&trace_contours(&m)).unwrap());
            let want = axes.0.max(axes.1) / axes.0.min(axes.1);
            assert!((e - want).abs() < 0.15 * want, "{axes:?} at {lean}°: {e} against {want}");
        }
    }

    #[test]
    fn the_node_returns_a_clip_of_the_same_length() {
        let angles: Vec<f64> = (0..6).map(|i| f64::from(i % 2) * 4.0).collect();
        let node = smoother(&angles, &[], &[]);
        let ctx = CookCtx::new();
        let out = node.cook(&ctx).unwrap();
        assert_eq!(out.len(), 6);
        let mid = match out.get(3, &ctx).unwrap() {
            Value::Float(v) => v,
            other => panic!("{other:?}"),
        };
        assert!(mid > 0.5 && mid < 3.5, "pulled towards the mean: {mid}");
    }
}
