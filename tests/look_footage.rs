//! The candle graph against the shared candle footage (issue 28): the flames' area, height and
//! width vary over time like the real candle's (coefficient of variation within 30 %, lag-1
//! autocorrelation within 0.15), and show no more banding than the footage does, at the graph's
//! step count and at half of it.

use pyrograph::look::{ClipLook, FlameLook, Series, footage_look, graph_look};
use pyrograph_testing::{footage, workspace};

/// Luminance above which a pixel is flame, in the footage and in the renders.
const THRESHOLD: f32 = 0.25;

/// One measured quantity of a flame.
type Quantity = fn(&FlameLook) -> Series;

fn candles(sets: &[&str], steps: usize) -> ClipLook {
    let graph = workspace().join("graphs/candles.ron");
    let mut all = vec!["render.ground=false"];
    all.extend(sets);
    graph_look(&graph, "render.image", &all, THRESHOLD, steps).expect("the candle graph cooks")
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn candle_graph_moves_like_the_candle_footage_and_shows_no_bands() {
    let real = footage_look(&footage().join("candle-black/frames"), usize::MAX, THRESHOLD, 25).expect("footage frames");
    assert_eq!(real.flames.len(), 1, "one candle in the footage: {real:?}");
    let ours = candles(&[], 25);
    let half = candles(&["flames.steps=12"], 12);
    println!("footage    {}", real.summary());
    println!("candles    {}", ours.summary());
    println!("half steps {}", half.summary());
    let quantities: [(&str, Quantity); 3] = [("area", |l| l.area), ("height", |l| l.height), ("width", |l| l.width)];
    for (name, q) in quantities {
        let (cv_real, cv_ours) = (real.mean(|l| q(l).cv), ours.mean(|l| q(l).cv));
        let (lag_real, lag_ours) = (real.mean(|l| q(l).lag1), ours.mean(|l| q(l).lag1));
        assert!(
            (cv_ours - cv_real).abs() <= 0.3 * cv_real,
            "{name}: coefficient of variation {cv_ours:.3} against the footage's {cv_real:.3}"
        );
        assert!((lag_ours - lag_real).abs() <= 0.15, "{name}: lag-1 autocorrelation {lag_ours:.3} against {lag_real:.3}");
    }
    let footage_banding = real.mean(|l| l.banding);
    for (look, steps) in [(&ours, 25), (&half, 12)] {
        let b = look.mean(|l| l.banding);
        assert!(b <= footage_banding, "{steps} steps: banding {b:.2e} above the footage's {footage_banding:.2e}");
    }
}

/// The learned candle (Stich & Magnor, `graphs/learning-flames-candle.ron`) against the clip it
/// was trained on, in image space: the AR(2) fit reproduces its parameters' statistics by
/// construction, so the check that matters is what the rendered flames do — their area, height,
/// width and energy vary like the real flame's (coefficient of variation within 30 %, lag-1 and
/// lag-2 autocorrelation within 0.15). 1200 synthesized frames, since the lag-2 autocorrelation of
/// one 300-frame draw wanders by about 0.1 from model to model (0.33–0.44 for the height).
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn learned_candle_moves_like_its_training_clip_in_image_space() {
    let frames = footage().join("candle-black/frames");
    let real = footage_look(&frames, usize::MAX, THRESHOLD, 25).expect("footage frames");
    let graph = workspace().join("graphs/learning-flames-candle.ron");
    let path = format!("frames.path={:?}", frames.display().to_string());
    let learned =
        graph_look(&graph, "render.color", &[&path, "sample.frames=1200"], THRESHOLD, 25).expect("the learned candle cooks");
    println!("footage {}", real.summary());
    println!("learned {}", learned.summary());
    assert_eq!(learned.flames.len(), 1, "{learned:?}");
    let quantities: [(&str, Quantity); 4] =
        [("area", |l| l.area), ("height", |l| l.height), ("width", |l| l.width), ("energy", |l| l.energy)];
    for (name, q) in quantities {
        let (a, b) = (q(&real.flames[0]), q(&learned.flames[0]));
        assert!(
            (b.cv - a.cv).abs() <= 0.3 * a.cv,
            "{name}: coefficient of variation {:.3} against the footage's {:.3}",
            b.cv,
            a.cv
        );
        assert!((b.lag1 - a.lag1).abs() <= 0.15, "{name}: lag-1 {:.3} against {:.3}", b.lag1, a.lag1);
        assert!((b.lag2 - a.lag2).abs() <= 0.15, "{name}: lag-2 {:.3} against {:.3}", b.lag2, a.lag2);
    }
}
