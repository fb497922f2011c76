//! Eigenfires motion transitions on real footage (never committed), measured in PCA space in all
//! components: on the candle, whose gentle sway makes a cut visible, every method keeps the seam
//! within 1.5× the 95th percentile of the clip's own consecutive-frame distances while the direct
//! cut exceeds it; on the tea-light scenario of `graphs/eigenfires-tealight.ron`, every method
//! builds and stays within the clip's largest step.

use std::ops::RangeInclusive;

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue};
use pyrograph_frontend::eigen::motion::{Method, transition};
use pyrograph_frontend::eigen::transition::{distance, lowpass_kernel};
use pyrograph_frontend::eigen::values::{FrameItem, Weights};
use pyrograph_testing::{footage, workspace};

/// Eigenfires weights of footage `source` (a video or frame folder) after the gray-producing
/// node `pre` (its input `pre_in`, output `pre_out`), at 150×150.
fn pca_weights(source: &std::path::Path, pre: NodeDoc, (pre_in, pre_out): (&str, &str)) -> Weights {
    let root = workspace();
    let mut doc = GraphDoc::new();
    doc.add_node("video", NodeDoc::new("imaging.load_sequence").param("path", ParamValue::String(source.display().to_string())));
    doc.add_node("pre", pre);
    doc.add_node(
        "small",
        NodeDoc::new("imaging.resize").param("width", ParamValue::Int(150)).param("height", ParamValue::Int(150)),
    );
    doc.add_node("pca", NodeDoc::new("eigen.eigenfires"));
    doc.edges = vec![
        ("video.clip".into(), format!("pre.{pre_in}")),
        (format!("pre.{pre_out}"), "small.image".into()),
        ("small.image".into(), "pca.clip1".into()),
    ];
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), &root.join("graphs"), &BuildOptions::default())
        .unwrap_or_else(|d| panic!("{d}"));
    let out = Evaluator::new().output(&g, "pca.weights", &CookCtx::new()).unwrap();
    match out.downcast::<Weights>() {
        Some(w) => w.as_ref().clone(),
        None => panic!("expected weights, got {}", out.type_name()),
    }
}

/// The training weights of the tealight database, as the example graph builds it.
fn tealight_weights() -> Weights {
    let pre = NodeDoc::new("graph.include").param("path", ParamValue::String("presets/preprocess-tealight.ron".into()));
    pca_weights(&footage().join("tealight-candle/candle.mp4"), pre, ("image", "gray"))
}

/// The Eigenfires weights of the candle clip: its frames in gray, at 150×150 like the tea-light's.
fn candle_weights() -> Weights {
    pca_weights(&footage().join("candle-black/frames"), NodeDoc::new("imaging.to_gray"), ("image", "image"))
}

fn row(w: &Weights, f: usize) -> Vec<f32> {
    w.row(f).unwrap().to_vec()
}

fn p95_consecutive(w: &Weights, e: usize) -> f64 {
    let mut d: Vec<f64> = (1..w.frames).map(|f| distance(w.row(f - 1).unwrap(), w.row(f).unwrap(), e)).collect();
    d.sort_by(f64::total_cmp);
    d[(d.len() as f64 * 0.95) as usize]
}

/// Largest jump from the last untouched frame of `x`, through the transition, to the first
/// untouched frame of `y`.
fn largest_jump(w: &Weights, x: &RangeInclusive<usize>, y: &RangeInclusive<usize>, method: &Method, e: usize) -> (f64, usize) {
    let t = transition(w, x, y, method).unwrap_or_else(|m| panic!("{method:?}: {m}"));
    let mut seq = vec![row(w, x.end() - t.trim_end)];
    for item in &t.items {
        seq.push(match item {
            FrameItem::Frame(f) => row(w, *f as usize),
            FrameItem::Weights(v) => v.clone(),
        });
    }
    seq.push(row(w, y.start() + t.trim_start));
    (seq.windows(2).map(|p| distance(&p[0], &p[1], e)).fold(0.0, f64::max), t.items.len())
}

/// Consecutive-frame distances of `w` in its first `e` components, sorted.
fn consecutive(w: &Weights, e: usize) -> Vec<f64> {
    let mut d: Vec<f64> = (1..w.frames).map(|f| distance(w.row(f - 1).unwrap(), w.row(f).unwrap(), e)).collect();
    d.sort_by(f64::total_cmp);
    d
}

/// On the candle (a gentle sway, so a cut between distant moments is a visible jump), every
/// transition method brings the seam's largest jump, measured in all PCA components, within
/// 1.5× the 95th percentile of the clip's own consecutive-frame distances — which the direct cut
/// at the same seam exceeds, so the bound can see a bad transition. (On the tea-light the clip's
/// own flicker is larger than a cut: a direct cut between frames 199 and 500 measures 29.9
/// against a p95 of 34.5, so no such bound can tell a transition from a cut there.)
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn every_transition_on_the_candle_stays_within_the_clips_own_motion_where_a_cut_does_not() {
    let w = candle_weights();
    assert_eq!(w.frames, 150);
    let full = w.components;
    let e_detect = 100.min(full);
    let d = consecutive(&w, full);
    let (p50, p95) = (d[d.len() / 2], p95_consecutive(&w, full));
    // The searches' minimum distance on this clip's scale: its median consecutive-frame step.
    let methods = [
        ("lowpass", Method::LowPass { components: full, kernel: lowpass_kernel("box3").unwrap(), span: 2 }),
        ("direct_bridging", Method::DirectBridging { steps: 6, components: e_detect, theta_min: p50 }),
        ("end_growing", Method::EndGrowing { steps: 40, components: e_detect, theta_min: p50, exclude: 7 }),
    ];
    let (t1, t2) = (20..=49, 90..=119);
    let cut = distance(w.row(*t1.end()).unwrap(), w.row(*t2.start()).unwrap(), full);
    println!("direct cut 49→90: jump {cut:.3}, p95 {p95:.3}, ratio {:.2}", cut / p95);
    assert!(cut > 1.5 * p95, "the direct cut ({cut:.3}) is within 1.5 × p95 ({p95:.3}): the bound would see nothing");
    let mut failures = Vec::new();
    for (name, method) in &methods {
        let (jump, n) = largest_jump(&w, &t1, &t2, method, full);
        println!("{name}: {n} frames, largest jump {jump:.3} in all {full} components, ratio {:.2}", jump / p95);
        if jump > 1.5 * p95 {
            failures.push(format!("{name}: largest jump {jump:.3} > 1.5 × p95 {p95:.3}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The tea-light scenario of `graphs/eigenfires-tealight.ron`: every method builds its transitions
/// between the two motions and back, and none makes the seam jump beyond the clip's own largest
/// consecutive-frame distance, in all components.
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn every_transition_on_the_tealight_builds_and_stays_within_the_clips_largest_step() {
    let w = tealight_weights();
    assert_eq!(w.frames, 796);
    let (t1, t2) = (100..=199, 500..=599);
    let e_detect = 100.min(w.components);
    let full = w.components;
    let methods = [
        ("lowpass", Method::LowPass { components: full, kernel: lowpass_kernel("box3").unwrap(), span: 2 }),
        ("direct_bridging", Method::DirectBridging { steps: 6, components: e_detect, theta_min: 10.0 }),
        ("end_growing", Method::EndGrowing { steps: 40, components: e_detect, theta_min: 10.0, exclude: 7 }),
    ];
    let largest = *consecutive(&w, full).last().unwrap();
    for (name, method) in &methods {
        for (x, y, seam) in [(&t1, &t2, "T1→T2"), (&t2, &t1, "T2→T1 loop")] {
            let (jump, n) = largest_jump(&w, x, y, method, full);
            println!("{name} {seam}: {n} frames, largest jump {jump:.3}, the clip's largest step {largest:.3}");
            assert!(jump <= largest, "{name} {seam}: largest jump {jump:.3} beyond the clip's largest step {largest:.3}");
        }
    }
}
