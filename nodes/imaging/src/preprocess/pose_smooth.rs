//! `imaging.smooth_angle`: the per-frame lean of `imaging.pose_normalize`, smoothed over the clip
//! so straightening a flicking flame does not make the whole frame wobble (issue 27). The thesis
//! (§3.4) normalizes each frame on its own; on moving footage the fitted axis jitters by a few
//! degrees from frame to frame, and turning the frame by it adds that jitter to the background
//! and the flame's base.

use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, NodeError, PortType, Value, port};

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

pyrograph_core::node! {
    /// Smooths the per-frame lean of imaging.pose_normalize over the clip (extends Eigenfires thesis §3.4 to moving footage): a median of 2·median_radius + 1 frames drops single-frame outliers, then a Gaussian of sigma frames (edges mirrored) removes the jitter.
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
    }
    /// Smoothed angle per frame, in degrees
    -> angle: ClipOf<f64>
}

impl Cook for SmoothAngle {
    fn cook(self, ctx: &CookCtx) -> Result<ClipOf<f64>, NodeError> {
        let clip: &Clip = &self.angle;
        if clip.is_empty() {
            return Err(NodeError::port(port!(SmoothAngle, angle), "the angle clip has no frames"));
        }
        // Every frame's angle cooks the per-frame chain above it: in parallel, in frame order.
        use rayon::prelude::*;
        let values = (0..clip.len())
            .into_par_iter()
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

    #[test]
    fn the_node_returns_a_clip_of_the_same_length() {
        let frames = (0..6).map(|i| Value::Float(f64::from(i % 2) * 4.0)).collect();
        let node =
            SmoothAngle { angle: ClipOf::new(Clip::from_frames(PortType::Float, 24.0, frames)), median_radius: 0, sigma: 1.0 };
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
