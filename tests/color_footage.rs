//! Original colouring (Eigenfires thesis §6.1.1, Algorithm 2) on real footage, through
//! `graphs/tealight-color.ron`: inside the flame the coloured output keeps the original video's
//! colours, and outside it (no bloom or smoke layers) it is black.

use std::sync::Arc;

use pyrograph_frontend::core::{BuildOptions, Clip, CookCtx, Evaluator, Graph, Image, Value};
use pyrograph_frontend::imaging::color::{ColoringLayers, original_coloring};
use pyrograph_testing::{footage, workspace};

fn clip(eval: &mut Evaluator, graph: &Graph, output: &str) -> Clip {
    match eval.output(graph, output, &CookCtx::new()).unwrap_or_else(|e| panic!("{output}: {e}")) {
        Value::Clip(c) => c,
        other => panic!("{output}: expected a clip, got {}", other.type_name()),
    }
}

fn frame(c: &Clip, i: usize) -> Arc<Image> {
    c.image(i, &CookCtx::new()).unwrap()
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn original_coloring_keeps_the_flame_colours_and_blacks_out_the_rest() {
    // The graph reads ${PYROGRAPH_FOOTAGE} itself, so the default folder will not do.
    assert!(std::env::var_os("PYROGRAPH_FOOTAGE").is_some(), "set PYROGRAPH_FOOTAGE to the shared footage folder");
    let dir = footage();
    assert!(dir.join("tealight-candle/candle.mp4").exists(), "no tealight-candle/candle.mp4 under {}", dir.display());
    let path = workspace().join("graphs/tealight-color.ron");
    let (_, graph) =
        Graph::load(&path, &pyrograph_frontend::registry(), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let mut eval = Evaluator::new();
    let (source, original, colored) =
        (clip(&mut eval, &graph, "source.image"), clip(&mut eval, &graph, "pre.crop"), clip(&mut eval, &graph, "color.image"));
    let threshold = 30.0f32 / 255.0;
    let (mut err_sum, mut inside, mut outside) = (0.0f64, 0usize, 0usize);
    for i in [0, 21, 42, 63] {
        let (src, orig, col) = (frame(&source, i), frame(&original, i), frame(&colored, i));
        assert_eq!(src.size(), orig.size(), "source and original must line up");
        let plain = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap();
        for (k, &s) in src.data().iter().enumerate() {
            let o = &orig.data()[4 * k..4 * k + 3];
            if s > threshold {
                // Inside the flame, with or without bloom and smoke, the original colour is kept.
                for (c, &oc) in o.iter().enumerate() {
                    err_sum += f64::from((col.data()[4 * k + c] - oc).abs());
                    err_sum += f64::from((plain.data()[4 * k + c] - oc).abs());
                }
                inside += 1;
            } else if s == 0.0 {
                // Outside (source exactly 0) the plain Algorithm 2 result is black.
                assert_eq!(&plain.data()[4 * k..4 * k + 3], &[0.0, 0.0, 0.0], "frame {i} pixel {k}");
                outside += 1;
            }
        }
    }
    assert!(inside > 1000 && outside > 10_000, "a flame and a background in every frame: {inside} inside, {outside} outside");
    let mean = err_sum / (inside as f64 * 6.0);
    // Stated bound: mean absolute colour error inside the flame below 0.5 / 255 (it is 0: a copy).
    assert!(mean < 0.5 / 255.0, "mean colour error inside the flame {mean}");
}
