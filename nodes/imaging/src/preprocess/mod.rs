//! Eigenfires pre-processing (thesis ch. 3): HSV masks, morphology, contours, hole removal,
//! Douglas–Peucker, Hermite background removal and pose normalization.
//!
//! Each submodule keeps its algorithm in plain functions (called directly by tests and the
//! `preprocess` bench) and wraps them in thin node types registered here.

pub mod contours;
pub mod fire_cues;
pub mod hermite;
pub mod hsv;
pub mod hsv_auto;
pub mod morphology;
pub mod pose;
pub mod pose_smooth;
pub mod regions;
pub mod stabilize;

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::{BuildOptions, Channels, CookCtx, Evaluator, Graph, Image, Value};
    use std::sync::Arc;

    fn preset_path() -> std::path::PathBuf {
        pyrograph_testing::workspace().join("graphs/presets/preprocess.ron")
    }

    /// A synthetic RGBA flame: a yellow core in an orange body leaning right, on black.
    fn flame_frame(w: u32, h: u32) -> Image {
        let m = pose::tests::ellipse_mask(w, h, (f64::from(w) / 2.0, f64::from(h) / 2.0), (8.0, 24.0), 20.0);
        let core = pose::tests::ellipse_mask(w, h, (f64::from(w) / 2.0, f64::from(h) / 2.0), (4.0, 14.0), 20.0);
        let data = m
            .data()
            .iter()
            .zip(core.data())
            .flat_map(|(&o, &c)| match (o, c) {
                (_, 255) => [1.0, 0.9, 0.3, 1.0],
                (255, _) => [1.0, 0.4, 0.0, 1.0],
                _ => [0.02, 0.02, 0.02, 1.0],
            })
            .collect();
        Image::from_vec(w, h, Channels::Rgba, data).unwrap()
    }

    #[test]
    fn every_node_is_registered_under_pre_processing() {
        let mut r = pyrograph_core::Registry::new();
        crate::register(&mut r);
        for want in [
            "imaging.hsv_mask",
            "imaging.morphology",
            "imaging.gaussian_blur",
            "imaging.contours",
            "imaging.hole_removal",
            "imaging.simplify_contours",
            "imaging.contour_mask",
            "imaging.contour_overlay",
            "imaging.hermite_background",
            "imaging.hermite_background_masked",
            "imaging.pose_normalize",
        ] {
            let d = r.desc(want).unwrap_or_else(|| panic!("{want} missing"));
            assert!(d.category == "Pre-processing" && d.doc.contains('§'), "{want}: {} / {}", d.category, d.doc);
        }
    }

    #[test]
    fn preset_loads_and_stands_a_leaning_flame_upright() {
        let mut r = pyrograph_core::Registry::with_builtins();
        crate::register(&mut r);
        let (_, mut g) = Graph::load(&preset_path(), &r, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
        let src = g.index("src").unwrap();
        g.set_const(src, 0, Value::Image(Arc::new(flame_frame(96, 96))));
        let mut ev = Evaluator::new();
        let ctx = CookCtx::new();
        let Value::Float(angle) = ev.output(&g, "pose.angle", &ctx).unwrap() else { panic!("angle is not a Float") };
        assert!((angle - 20.0).abs() < 2.0, "angle {angle}");
        let Value::Image(gray) = ev.output(&g, "pose.image", &ctx).unwrap() else { panic!("not an image") };
        assert_eq!((gray.channels(), gray.size()), (Channels::Gray, (96, 96)));
        assert!(gray.data().iter().any(|&v| v > 0.5));
    }
}
