//! Tests on the real flame footage in ../shared/footage (never committed to this repository).
//! Run with `PYROGRAPH_FOOTAGE=/abs/path cargo test --workspace -- --ignored`.

use std::process::Command;

use pyrograph_testing::{footage, workspace};

fn pyrograph(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pyrograph")).args(args).env("PYROGRAPH_FOOTAGE", footage()).output().expect("binary runs")
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn candle_gray_graph_writes_150_gray_frames_of_the_cropped_flame() {
    let out = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/candle-gray.ron");
    let o = pyrograph(&["render", graph.to_str().unwrap(), "--out", out.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let dir = out.path().join("candle-gray");
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert_eq!(files.len(), 150);
    let first = image::open(&files[0]).unwrap();
    assert_eq!((first.width(), first.height()), (200, 240));
    assert_eq!(first.color(), image::ColorType::L8, "gray PNG");
    let luma = first.to_luma8();
    let brightest = luma.pixels().map(|p| p[0]).max().unwrap();
    let corner = luma.get_pixel(0, 0)[0];
    assert!(brightest > 200 && corner < 30, "the crop holds the bright flame on a dark ground ({brightest}, {corner})");
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn tealight_video_loads_through_ffmpeg_as_796_frames_of_480x480() {
    use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Value};
    let video = footage().join("tealight-candle/candle.mp4");
    let mut doc = GraphDoc::new();
    doc.add_node("video", NodeDoc::new("imaging.load_sequence").param("path", ParamValue::String(video.display().to_string())));
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), std::path::Path::new("."), &BuildOptions::default()).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&g, "video.clip", &ctx).unwrap() else { panic!("expected a clip") };
    assert_eq!(clip.len(), 796);
    for i in [0, 400, 795] {
        assert_eq!(clip.image(i, &ctx).unwrap().size(), (480, 480), "frame {i}");
    }
    assert!((clip.fps() - 30.0).abs() < 0.1, "fps {}", clip.fps());
}

/// Summed blue over summed red of a frame's pixels: the bloom's tint dominates the halo.
fn blue_over_red(path: &std::path::Path) -> f64 {
    let img = image::open(path).unwrap().to_rgb8();
    let (r, b) = img.pixels().fold((0.0, 0.0), |(r, b), p| (r + f64::from(p[0]), b + f64::from(p[2])));
    b / r.max(1.0)
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn the_tealight_whose_tint_is_keyed_turns_from_orange_to_blue() {
    let out = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/tealight-timed.ron");
    let o = pyrograph(&["render", graph.to_str().unwrap(), "--out", out.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let frame = |i: usize| out.path().join(format!("tealight-timed/timed_{i:04}.png"));
    // The tint is orange until frame 16 and blue from frame 48 (keyed per component).
    let (early, late) = (blue_over_red(&frame(4)), blue_over_red(&frame(60)));
    assert!(early < 0.9 && late > 1.0 && late > 1.5 * early, "blue/red: frame 4 {early:.3}, frame 60 {late:.3}");
    assert!(out.path().join("tealight-timed-strip.png").exists());
}
