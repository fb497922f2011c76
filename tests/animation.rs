//! Animated parameters end to end, through the `pyrograph` binary: a campfire whose keyed wind
//! gusts at frame 40 leans after 40 and not before (measured in the frames), and the same graph
//! rendered in chunks of 8 frames, each by its own process as farm tasks do, equals one full
//! render byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

use pyrograph_testing::workspace;

/// Small enough for a debug build: 192×108, 40 flames, 72 frames.
const SMALL: &[&str] = &["--set", "fire.width=192", "--set", "fire.height=108", "--set", "fire.flames=40"];

fn render(out: &Path, frames: Option<&str>, extra: &[&str]) {
    let graph = workspace().join("graphs/campfire-gust.ron");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pyrograph"));
    cmd.args(["render", graph.to_str().unwrap(), "--out", out.to_str().unwrap()]).args(SMALL).args(extra);
    if let Some(f) = frames {
        cmd.args(["--frames", f]);
    }
    let o = cmd.output().expect("the binary runs");
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}

fn frame(dir: &Path, i: usize) -> PathBuf {
    dir.join(format!("campfire-gust/campfire-gust_{i:04}.png"))
}

/// The luminance-weighted x of the bright (flame) pixels, in pixels.
fn flame_x(path: &Path) -> f64 {
    let img = image::open(path).unwrap().to_luma8();
    let (mut sum, mut wx) = (0.0, 0.0);
    for (x, _, p) in img.enumerate_pixels() {
        let v = f64::from(p.0[0]);
        if v > 90.0 {
            sum += v;
            wx += v * f64::from(x);
        }
    }
    assert!(sum > 0.0, "{} has flame pixels", path.display());
    wx / sum
}

#[test]
fn a_keyed_gust_leans_the_campfire_after_frame_40_and_not_before_and_chunks_equal_a_full_render() {
    let dir = tempfile::tempdir().unwrap();
    let (gust, still, chunks) = (dir.path().join("gust"), dir.path().join("still"), dir.path().join("chunks"));
    render(&gust, None, &[]);
    render(&still, None, &["--set", "fire.wind=(0, 0, 0)"]);

    // Before the gust the keyed wind is exactly zero: the frames are the still fire's, byte for byte.
    for i in 0..=40 {
        assert_eq!(std::fs::read(frame(&gust, i)).unwrap(), std::fs::read(frame(&still, i)).unwrap(), "frame {i}");
    }
    // In the gust (x wind from the left, peaking at 46) the flames lean right.
    let shift: Vec<f64> = (44..=56).map(|i| flame_x(&frame(&gust, i)) - flame_x(&frame(&still, i))).collect();
    let mean = shift.iter().sum::<f64>() / shift.len() as f64;
    assert!(mean > 4.0, "the flames lean with the gust: mean shift {mean:.2} px over frames 44-56 ({shift:?})");

    // Farm tasks: chunks of 8 frames, each rendered by a process of its own.
    for start in (0..72).step_by(8) {
        render(&chunks, Some(&format!("{start}-{}", start + 7)), &[]);
    }
    for i in 0..72 {
        assert_eq!(std::fs::read(frame(&gust, i)).unwrap(), std::fs::read(frame(&chunks, i)).unwrap(), "frame {i}");
    }
}

fn run(args: &[&str]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_pyrograph")).args(args).output().expect("the binary runs");
    (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

/// `pyrograph check` of a graph including the campfire preset with `fire`'s parameters `params`.
fn check_campfire(params: &str) -> (bool, String) {
    let dir = tempfile::tempdir().unwrap();
    let preset = workspace().join("graphs/presets/campfire.ron");
    let text = format!(
        "(version: 4, interface: (outputs: {{\"clip\": \"fire.clip\"}}), nodes: {{\"fire\": (type: \"graph.include\", \
         params: {{\"path\": {:?}, {params}}})}})",
        preset.to_str().unwrap()
    );
    let graph = dir.path().join("g.ron");
    std::fs::write(&graph, text).unwrap();
    run(&["check", graph.to_str().unwrap()])
}

#[test]
fn info_lists_the_animated_parameters_and_bad_ones_are_named_with_node_port_and_column() {
    let graph = workspace().join("graphs/campfire-gust.ron");
    let (ok, text) = run(&["info", graph.to_str().unwrap()]);
    assert!(ok, "{text}");
    assert!(text.contains("animated parameters:") && text.contains("fire/wind.wind = (keys([(0, 0.0), (40, 0.0)"), "{text}");

    let (ok, text) = check_campfire("\"wind\": (expr(\"1 +* 2\"), 0, 0)");
    assert!(!ok && text.contains("'fire'") && text.contains("wind") && text.contains("column 4"), "{text}");
    let (ok, text) = check_campfire("\"wind\": (keys([(0, 1.0), (10, 2.0), (5, 0.0)]), 0, 0)");
    assert!(!ok && text.contains("component 1 (x)") && text.contains("key 3 at frame 5"), "{text}");
    // The bloom is a per-frame node fed the rendered clip: an expression on it is sampled per frame.
    let (ok, text) = check_campfire("\"bloom\": expr(\"0.3 + 0.1 * sin(time)\")");
    assert!(ok, "{text}");
    // The flame count is read once, by a source node: keys on it are refused, not frozen.
    let (ok, text) = check_campfire("\"flames\": keys([(0, 40), (30, 80)])");
    assert!(!ok && text.contains("'flames' is animated, but nothing samples it over time"), "{text}");
}
