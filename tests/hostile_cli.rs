//! Hostile inputs through the CLI that need a tool the unit tests do not: a video whose frames
//! are larger than the pixel budget is refused when it is probed, before a frame is decoded.

use std::process::Command;

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_video_over_the_pixel_budget_is_refused_when_probed() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("small.mp4");
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i", "color=c=red:s=64x48:d=0.2:r=25", "-pix_fmt", "yuv420p"])
        .arg(&video)
        .status()
        .expect("ffmpeg runs");
    assert!(made.success());
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {"v": (type: "imaging.load_sequence", params: {"path": "small.mp4"})}, edges: [])"#,
    )
    .unwrap();
    let check = |budget: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_pyrograph"));
        c.arg("check").arg(&graph);
        if let Some(b) = budget {
            c.env("PYROGRAPH_MAX_PIXELS", b);
        }
        let o = c.output().expect("the binary runs");
        (o.status.code(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
    };
    let (code, text) = check(Some("1000"));
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("small.mp4: the file declares 64 × 48 pixels (3072 pixels), more than the 1000 pixels"), "{text}");
    let (code, text) = check(None);
    assert_eq!(code, Some(0), "within the default budget: {text}");
}
