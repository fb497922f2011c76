//! Plates made from the shared footage for the footage tests: frames through an ffmpeg filter,
//! the overlap of two masks, and a median.
#![allow(dead_code)] // Each test file uses its own part.

use std::path::{Path, PathBuf};
use std::process::Command;

use image::GrayImage;

/// `count` frames of the ffmpeg `input` (its arguments up to and with `-i FILE`) through the
/// ffmpeg `filter`, as PNG frames in `dir/name`.
pub fn ffmpeg_frames(dir: &Path, name: &str, input: &[&str], filter: &str, count: usize) -> PathBuf {
    let frames = dir.join(name);
    std::fs::create_dir_all(&frames).unwrap();
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(input)
        .args(["-frames:v", &count.to_string(), "-vf", filter])
        .arg(frames.join("f_%04d.png"))
        .output()
        .expect("ffmpeg runs (the CI installs it)");
    assert!(o.status.success(), "ffmpeg {filter}: {}", String::from_utf8_lossy(&o.stderr));
    frames
}

/// Intersection over union of two masks (set where over 127); 1 when both are empty.
pub fn iou(a: &GrayImage, b: &GrayImage) -> f64 {
    let (mut inter, mut union) = (0u64, 0u64);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let (x, y) = (p[0] > 127, q[0] > 127);
        inter += u64::from(x && y);
        union += u64::from(x || y);
    }
    if union == 0 { 1.0 } else { inter as f64 / union as f64 }
}

/// The middle value of `v` (the upper one of the two middle values for an even count).
pub fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
