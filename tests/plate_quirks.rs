//! Real plates as they come (issue 47): quirks of real files, made from the shared footage with
//! ffmpeg, each loaded through `imaging.load_sequence` and checked pixel for pixel against
//! ffmpeg's own decode of the same file, with the warning where one is due.

use std::path::{Path, PathBuf};
use std::process::Command;

use pyrograph_frontend::core::{CookCtx, Image};
use pyrograph_nodes_imaging::io::{Gaps, LoadSequence, SequenceOptions, open_sequence};
use pyrograph_testing::footage;

/// Runs ffmpeg with `args` (quiet, no stdin) and asserts it succeeded.
fn ffmpeg(args: &[&str]) {
    let out = Command::new("ffmpeg").args(["-v", "error", "-nostdin", "-y"]).args(args).output().expect("ffmpeg runs");
    assert!(out.status.success(), "ffmpeg {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// 48 frames of the tea-light cut to 480 × 320 (not square, so a quarter turn shows), H.264 with
/// a keyframe every 12 frames, no audio.
fn base_clip(dir: &Path) -> PathBuf {
    let source = footage().join("tealight-candle/candle.mp4");
    let out = dir.join("base.mp4");
    let crop = ["-vf", "crop=480:320:0:80", "-c:v", "libx264", "-g", "12", "-pix_fmt", "yuv420p"];
    ffmpeg(&[&["-i", s(&source), "-frames:v", "48", "-an"][..], &crop, &[s(&out)]].concat());
    out
}

/// Every frame of `path` as ffmpeg decodes it with `filters`, as packed samples of `pix_fmt`.
fn decoded(path: &Path, filters: &[&str], pix_fmt: &str, frame_bytes: usize) -> Vec<Vec<u8>> {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-i", s(path)])
        .args(filters)
        .args(["-map", "0:v:0", "-vsync", "passthrough", "-f", "rawvideo", "-pix_fmt", pix_fmt, "-"])
        .output()
        .expect("ffmpeg runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(out.stdout.len() % frame_bytes, 0);
    out.stdout.chunks_exact(frame_bytes).map(<[u8]>::to_vec).collect()
}

/// Asserts every frame of `clip` is `want` (packed 8-bit RGB).
fn assert_frames(clip: &pyrograph_frontend::core::Clip, want: &[Vec<u8>], ctx: &CookCtx) {
    assert_eq!(clip.len(), want.len());
    for (i, frame) in want.iter().enumerate() {
        assert!(rgb24(&clip.image(i, ctx).unwrap()) == *frame, "frame {i}");
    }
}

/// Asserts the cook gave exactly one warning, saying `what`.
fn one_warning(ctx: &CookCtx, what: &str) {
    let warnings = ctx.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].message.contains(what), "{}", warnings[0].message);
}

/// An image's RGB as 8-bit samples.
fn rgb24(img: &Image) -> Vec<u8> {
    img.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).map(|v| (v * 255.0).round() as u8).collect()
}

/// An image's RGBA (or RGB) as 16-bit little-endian samples.
fn sixteen(img: &Image, alpha: bool) -> Vec<u8> {
    let n = if alpha { 4 } else { 3 };
    img.data().chunks_exact(4).flat_map(|p| p[..n].to_vec()).flat_map(|v| ((v * 65535.0).round() as u16).to_le_bytes()).collect()
}

/// Samples that fall between two 8-bit steps: a source whose precision was kept has many.
fn between_eight_bit_steps(img: &Image) -> usize {
    img.data().iter().filter(|v| ((*v * 255.0) - (*v * 255.0).round()).abs() > 0.05).count()
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_header_that_overstates_the_frame_count_loses_only_the_missing_frames() {
    let dir = tempfile::tempdir().unwrap();
    let base = base_clip(dir.path());
    // A trim by stream copy, as editors make: every sample stays (the header states 48 frames)
    // while the edit list hides the first ones.
    let trimmed = dir.path().join("trimmed.mp4");
    ffmpeg(&["-ss", "0.3", "-i", s(&base), "-c", "copy", s(&trimmed)]);
    let want = decoded(&trimmed, &[], "rgb24", 480 * 320 * 3);
    assert!(want.len() < 48 && want.len() > 30, "ffmpeg decodes {}", want.len());
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&trimmed, 0.0, &ctx).unwrap();
    assert_frames(&clip, &want, &ctx);
    one_warning(&ctx, &format!("states 48 frames but {} decode", want.len()));
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_variable_frame_rate_clip_is_resampled_by_timestamps_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let base = base_clip(dir.path());
    // The first second at 30 fps, then every other frame (15 fps): a phone slowing its shutter.
    let vfr = dir.path().join("vfr.mp4");
    ffmpeg(&["-i", s(&base), "-vf", "select='lt(n\\,30)+not(mod(n\\,2))'", "-fps_mode", "vfr", "-c:v", "libx264", s(&vfr)]);
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&vfr, 0.0, &ctx).unwrap();
    assert_eq!(clip.fps(), 30.0, "resampled to its base rate");
    let want = decoded(&vfr, &["-vf", "fps=30"], "rgb24", 480 * 320 * 3);
    assert!(want.len() >= 46, "the held frames are there: {}", want.len());
    assert_frames(&clip, &want, &ctx);
    one_warning(&ctx, "variable frame rate (39 frames over");
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_rotation_tag_is_applied_as_players_apply_it() {
    let dir = tempfile::tempdir().unwrap();
    let base = base_clip(dir.path());
    let turned = dir.path().join("turned.mp4");
    ffmpeg(&["-i", s(&base), "-c", "copy", "-metadata:s:v:0", "rotate=90", s(&turned)]);
    let want = decoded(&turned, &[], "rgb24", 480 * 320 * 3);
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&turned, 0.0, &ctx).unwrap();
    assert_eq!((clip.len(), clip.image(0, &ctx).unwrap().size()), (48, (320, 480)), "a quarter turn stands the frame up");
    assert!(ctx.warnings().is_empty());
    assert_frames(&clip, &want, &ctx);
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_ten_bit_clip_keeps_its_precision() {
    let dir = tempfile::tempdir().unwrap();
    let source = footage().join("tealight-candle/candle.mp4");
    let deep = dir.path().join("ten.mov");
    ffmpeg(&["-i", s(&source), "-frames:v", "12", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p10le", s(&deep)]);
    let want = decoded(&deep, &[], "rgb48le", 480 * 480 * 6);
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&deep, 0.0, &ctx).unwrap();
    assert_eq!((clip.len(), want.len()), (12, 12));
    for (i, frame) in want.iter().enumerate() {
        let img = clip.image(i, &ctx).unwrap();
        assert!(sixteen(&img, false) == *frame, "frame {i}");
        assert!(between_eight_bit_steps(&img) > 10_000, "frame {i} kept no more than 8 bits");
    }
}

/// Six frames of the tea-light as numbered stills `name_0001.ext`… with ffmpeg's `pix_fmt`, softened
/// at 16 bits first so the frames hold values between the 8-bit steps, as a scan or grade does.
fn stills(dir: &Path, name: &str, ext: &str, pix_fmt: &str) -> PathBuf {
    let source = footage().join("tealight-candle/candle.mp4");
    let pattern = dir.join(format!("{name}_%04d.{ext}"));
    let deep = ["-vf", "format=gbrp16le,gblur=sigma=2"];
    ffmpeg(
        &[&["-i", s(&source), "-frames:v", "6", "-an"][..], &deep, &["-pix_fmt", pix_fmt, "-start_number", "1", s(&pattern)]]
            .concat(),
    );
    pattern
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn dpx_and_sixteen_bit_tiff_sequences_load_with_their_precision() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let tiff = stills(dir.path(), "t16", "tif", "rgb48le");
    let dpx16 = stills(dir.path(), "d16", "dpx", "rgb48le");
    let dpx10 = stills(dir.path(), "d10", "dpx", "gbrp10le");
    let dpx8 = stills(dir.path(), "d8", "dpx", "rgb24");
    let (tiff_clip, dpx16_clip) = (LoadSequence::load(&tiff, 0.0, &ctx).unwrap(), LoadSequence::load(&dpx16, 0.0, &ctx).unwrap());
    let (dpx10_clip, dpx8_clip) = (LoadSequence::load(&dpx10, 0.0, &ctx).unwrap(), LoadSequence::load(&dpx8, 0.0, &ctx).unwrap());
    for clip in [&tiff_clip, &dpx16_clip, &dpx10_clip, &dpx8_clip] {
        assert_eq!(clip.len(), 6);
    }
    for n in 1..=6 {
        let file = |pattern: &Path| PathBuf::from(s(pattern).replace("%04d", &format!("{n:04}")));
        let i = n - 1;
        // The TIFF through the image crate, the DPX files through ffmpeg: each against ffmpeg's decode.
        let t = tiff_clip.image(i, &ctx).unwrap();
        assert!(sixteen(&t, false) == decoded(&file(&tiff), &[], "rgb48le", 480 * 480 * 6)[0], "TIFF frame {n}");
        let d16 = dpx16_clip.image(i, &ctx).unwrap();
        assert!(sixteen(&d16, true) == decoded(&file(&dpx16), &[], "rgba64le", 480 * 480 * 8)[0], "16-bit DPX frame {n}");
        let d10 = dpx10_clip.image(i, &ctx).unwrap();
        assert!(sixteen(&d10, true) == decoded(&file(&dpx10), &[], "rgba64le", 480 * 480 * 8)[0], "10-bit DPX frame {n}");
        let d8 = dpx8_clip.image(i, &ctx).unwrap();
        assert!(rgb24(&d8) == decoded(&file(&dpx8), &[], "rgb24", 480 * 480 * 3)[0], "8-bit DPX frame {n}");
        // Two decoders, one picture: the 16-bit TIFF and DPX of the same frame agree exactly.
        assert!(t.data() == d16.data(), "TIFF and DPX of frame {n} differ");
        assert!(between_eight_bit_steps(&t) > 10_000 && between_eight_bit_steps(&d10) > 10_000, "frame {n}");
        // The 10-bit scan is the 16-bit one at 10 bits: within two 10-bit steps (ffmpeg's writer
        // dithers when it drops to 10 bits), far below an 8-bit step's worth of banding.
        let worst = d10.data().iter().zip(d16.data()).map(|(a, b)| (a - b).abs()).fold(0.0_f32, f32::max);
        assert!(worst <= 2.0 / 1023.0, "10-bit DPX frame {n} is {worst} off the 16-bit one");
    }
}

#[test]
#[ignore = "needs footage and ffmpeg: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_sequence_with_two_missing_numbers_is_refused_with_the_list_or_held() {
    let dir = tempfile::tempdir().unwrap();
    let source = footage().join("tealight-candle/candle.mp4");
    let pattern = dir.path().join("f_%04d.png");
    ffmpeg(&["-i", s(&source), "-frames:v", "10", "-an", "-start_number", "1", s(&pattern)]);
    for gone in [4, 7] {
        std::fs::remove_file(dir.path().join(format!("f_{gone:04}.png"))).unwrap();
    }
    let ctx = CookCtx::new();
    let e = LoadSequence::load(&pattern, 0.0, &ctx).unwrap_err().to_string();
    assert!(e.contains("frames 4, 7 are missing (2 of the numbers 1-10)"), "{e}");
    let options = SequenceOptions { gaps: Gaps::Hold, ..SequenceOptions::default() };
    let held = open_sequence(&pattern, &options, &ctx, LoadSequence::node_error).unwrap();
    assert_eq!(held.len(), 10, "every number keeps its time");
    for (i, number) in [1, 2, 3, 3, 5, 6, 6, 8, 9, 10].into_iter().enumerate() {
        let want = decoded(&dir.path().join(format!("f_{number:04}.png")), &[], "rgb24", 480 * 480 * 3);
        assert!(rgb24(&held.image(i, &ctx).unwrap()) == want[0], "frame {i} shows file {number}");
    }
}
