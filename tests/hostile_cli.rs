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

/// A render into a file system that fills up stops with an error naming the file and the cause;
/// no file is left under a final name half-written (nor a temporary), and the manifest (on
/// another disk) lists exactly the frames that exist, each whole.
///
/// The small file system is a 400 KiB tmpfs mounted in a mount namespace of its own (`unshare`,
/// as root or through a user namespace), so nothing is mounted on the machine; its contents are
/// copied out before the namespace ends.
#[cfg(target_os = "linux")]
#[test]
#[ignore = "needs mount namespaces (unshare) to mount a small tmpfs: .ci/run runs the ignored tests"]
fn a_full_disk_stops_the_render_with_the_file_named_and_no_partial_files() {
    use std::path::Path;
    let dir = tempfile::tempdir().unwrap();
    let (out, copy) = (dir.path().join("out"), dir.path().join("copy"));
    std::fs::create_dir_all(out.join("full")).unwrap();
    std::fs::create_dir_all(&copy).unwrap();
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 4, nodes: {
            "f": (type: "imaging.turbulence_flame", params: {"width": 64, "height": 64, "frames": 60}),
            "w": (type: "imaging.write_sequence", params: {"pattern": "full/frame_####.exr", "exr_type": "float"})},
          edges: [("f.clip", "w.clip")])"#,
    )
    .unwrap();
    let manifest = out.join("manifest.json");
    let script = r#"mount -t tmpfs -o size=400k tmpfs "$1/full" || exit 97
"$2" render "$3" --out "$1" --manifest "$4" > "$5/log" 2>&1
echo $? > "$5/status"
cp -a "$1/full/." "$5/""#;
    let unshare = if nix_root() { vec!["-m"] } else { vec!["-r", "-m"] };
    let status = std::process::Command::new("unshare")
        .args(&unshare)
        .args(["sh", "-c", script, "sh"])
        .args([&out, Path::new(env!("CARGO_BIN_EXE_pyrograph")), &graph, &manifest, &copy])
        .status()
        .expect("unshare runs");
    assert!(status.success(), "the namespace could not be set up (exit {status:?})");
    let log = std::fs::read_to_string(copy.join("log")).unwrap();
    assert_eq!(std::fs::read_to_string(copy.join("status")).unwrap().trim(), "1", "{log}");
    assert!(log.contains("No space left on device") && log.contains("frame_"), "names the file and the cause: {log}");
    assert!(!log.contains("panicked"), "{log}");
    std::fs::remove_file(copy.join("log")).unwrap();
    std::fs::remove_file(copy.join("status")).unwrap();
    let mut left: Vec<String> =
        std::fs::read_dir(&copy).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    assert!(!left.is_empty() && left.len() < 60, "the disk filled part way: {left:?}");
    assert!(left.iter().all(|n| n.starts_with("frame_") && n.ends_with(".exr")), "no temporary is left: {left:?}");
    for name in &left {
        let img = pyrograph_nodes_imaging::io::load_image(&copy.join(name)).unwrap_or_else(|e| panic!("{name} is whole: {e}"));
        assert_eq!((img.width(), img.height()), (64, 64));
    }
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).expect("the manifest is written")).unwrap();
    assert_eq!(m["ok"], false);
    let mut listed: Vec<String> = m["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["path"].as_str().unwrap().trim_start_matches("full/").to_string())
        .collect();
    listed.sort();
    assert_eq!(listed, left, "the manifest lists the frames that exist");
}

#[cfg(target_os = "linux")]
fn nix_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("Uid:")).map(|l| l.split_whitespace().nth(1) == Some("0")))
        .unwrap_or(false)
}
