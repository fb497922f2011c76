//! Perry's flames read as one continuous shape: the banding measure (`pyrograph::look`) of the
//! candle graph stays below a bound at its own step count and at half of it, while the same
//! flames drawn as discrete steps — the banded look of before — exceed it by far.

use std::path::PathBuf;

use pyrograph::look::graph_look;
use pyrograph_testing::workspace;

/// Above this, a flame's vertical profile has visible bands (the discrete steps measure 0.015 at 25
/// steps and 0.15 at 12; the candle footage 1e-4).
const BANDING_BOUND: f64 = 5e-4;

fn candles() -> PathBuf {
    workspace().join("graphs/candles.ron")
}

/// The candle graph's first 12 frames, flames alone (no lit table), with `sets` applied.
fn banding(sets: &[&str], steps: usize) -> f64 {
    let mut all = vec!["render.ground=false", "flames.frames=12"];
    all.extend(sets);
    let look = graph_look(&candles(), "render.image", &all, 0.25, steps).expect("the candle graph cooks");
    assert_eq!(look.flames.len(), 5, "five candles: {look:?}");
    look.mean(|f| f.banding)
}

#[test]
fn candle_flames_show_no_bands_at_their_step_count_or_half_of_it() {
    for (sets, steps) in [(vec![], 25), (vec!["flames.steps=12"], 12)] {
        let continuous = banding(&sets, steps);
        let mut discrete_sets = sets.clone();
        discrete_sets.push("render.exposure=steps");
        let discrete = banding(&discrete_sets, steps);
        println!("{steps} steps: continuous {continuous:.2e}, discrete {discrete:.2e}");
        assert!(continuous < BANDING_BOUND, "{steps} steps: banding {continuous:.2e} ≥ {BANDING_BOUND:.0e}");
        assert!(discrete > 10.0 * BANDING_BOUND, "{steps} steps drawn as steps: banding {discrete:.2e} — the measure is blind");
    }
}
