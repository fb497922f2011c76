//! Tests of the video reader: probing, seeking, and the quirks of real files.

use super::probe::{ffprobe_fields, last_frame_index};
use super::*;
use crate::io::LoadSequence;

#[test]
fn probe_output_parses_size_rate_and_count() {
    let info = parse_probe("width=480\nheight=270\nr_frame_rate=30/1\navg_frame_rate=30000/1001\nnb_frames=796\n").unwrap();
    assert_eq!((info.width, info.height, info.frames), (480, 270, Some(796)));
    assert!((info.fps.unwrap() - 29.97).abs() < 0.01);
    assert!(!info.constant_rate, "an average rate below the base rate is variable");
    let info = parse_probe("width=4\nheight=2\navg_frame_rate=0/0\nr_frame_rate=25/1\nnb_frames=N/A").unwrap();
    assert_eq!((info.fps, info.frames), (Some(25.0), None));
    let info = parse_probe("width=4\nheight=2\navg_frame_rate=24/1\nr_frame_rate=24/1\nnb_frames=10").unwrap();
    assert!(info.constant_rate);
    assert_eq!(parse_probe("height=2"), None);
}

#[test]
fn missing_ffmpeg_names_the_fix() {
    let err = probe_video("pyrograph-no-such-ffprobe", Path::new("/tmp/clip.mp4")).unwrap_err().to_string();
    assert!(err.contains("install ffmpeg (apt-get install ffmpeg)") && err.contains("PNG frames"), "{err}");
}

#[test]
fn rgb24_frames_become_opaque_rgba() {
    let img = rgb24_to_image(2, 1, &[255, 0, 51, 0, 255, 0]).unwrap();
    let want = [1.0, 0.0, 0.2, 1.0, 0.0, 1.0, 0.0, 1.0];
    assert!(img.data().iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6));
    assert!(rgb24_to_image(2, 2, &[0; 6]).is_err());
}

/// A `frames`-frame 128×96 test video at 24 fps (ffmpeg's `testsrc2`, a counter in every
/// frame, a keyframe every 12 frames), written with `extra` output options.
fn make_video(dir: &Path, name: &str, frames: usize, extra: &[&str]) -> PathBuf {
    let path = dir.join(name);
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-f", "lavfi", "-i"])
        .arg(format!("testsrc2=size=128x96:rate=24:duration={}", frames as f64 / 24.0))
        .args(["-c:v", "libx264", "-g", "12", "-pix_fmt", "yuv420p"])
        .args(extra)
        .arg(&path)
        .status()
        .expect("ffmpeg runs");
    assert!(status.success());
    path
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn seeking_gives_the_frames_an_in_order_walk_gives() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_video(dir.path(), "t.mp4", 90, &[]);
    let ctx = CookCtx::new();
    let walk = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    assert_eq!((walk.len(), walk.fps()), (90, 24.0));
    let frames: Vec<Arc<Image>> = (0..90).map(|i| walk.image(i, &ctx).unwrap()).collect();
    assert!(frames.windows(2).all(|w| w[0].data() != w[1].data()), "every frame differs (the counter runs)");
    // A second clip of the same file, asked out of order: every answer seeks or skips.
    let jump = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    for i in [75, 3, 50, 89, 20, 21, 60, 0, 12, 11, 88, 47] {
        assert!(jump.image(i, &ctx).unwrap().data() == frames[i].data(), "frame {i} differs after a seek");
    }
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_truncated_video_names_the_frame_and_keeps_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_video(dir.path(), "t.mp4", 240, &["-movflags", "+faststart"]);
    // Cut the file in half: the header still states 240 frames.
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    assert_eq!(clip.len(), 240);
    let out = dir.path().join("out").join("f_####.png");
    let options = crate::io::WriteOptions {
        pattern: out.clone(),
        format: crate::io::OutputFormat::Png { sixteen_bit: false },
        start: 0,
        overwrite: false,
        frames: None,
        skip_existing: false,
        alpha: crate::color::AlphaMode::Straight,
    };
    let err = crate::io::write_sequence(&clip, &options, &ctx).unwrap_err().to_string();
    assert!(err.contains("truncated or corrupt") && err.contains("before frame"), "{err}");
    assert!(dir.path().join("out/f_0000.png").exists(), "frames decoded before the cut are written and stay");
}

#[test]
fn the_last_frame_time_gives_the_count() {
    assert_eq!(last_frame_index("1.166667\n1.625000\n1.583333\n", 0.0, 24.0), Some(39));
    assert_eq!(last_frame_index("N/A\n2.5,\n", 0.5, 10.0), Some(20));
    assert_eq!(last_frame_index("", 0.0, 24.0), None);
    assert_eq!(last_frame_index("N/A\n", 0.0, 24.0), None);
}

/// Writes `to` from `from` with ffmpeg, `before` going before the input and `args` after it
/// (a stream copy, a trim, a tag).
fn remux(before: &[&str], from: &Path, args: &[&str], to: &Path) {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin"])
        .args(before)
        .arg("-i")
        .arg(from)
        .args(args)
        .arg(to)
        .status()
        .unwrap();
    assert!(status.success());
}

/// Every frame of `path` as ffmpeg itself decodes it with `filters` (packed RGB, 128×96).
fn ffmpeg_frames(path: &Path, filters: &[&str]) -> Vec<Vec<u8>> {
    ffmpeg_decode(path, filters, "rgb24", 128 * 96 * 3)
}

/// Every frame of `path` as ffmpeg decodes it with `filters`, as `pix_fmt` frames of `frame_bytes`.
fn ffmpeg_decode(path: &Path, filters: &[&str], pix_fmt: &str, frame_bytes: usize) -> Vec<Vec<u8>> {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-i"])
        .arg(path)
        .args(filters)
        .args(["-map", "0:v:0", "-vsync", "passthrough", "-f", "rawvideo", "-pix_fmt", pix_fmt, "-"])
        .output()
        .expect("ffmpeg runs");
    assert!(out.status.success());
    out.stdout.chunks_exact(frame_bytes).map(<[u8]>::to_vec).collect()
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_header_that_overstates_the_count_loses_only_the_missing_frames() {
    let dir = tempfile::tempdir().unwrap();
    let full = make_video(dir.path(), "t.mp4", 48, &[]);
    // A trim by stream copy, as editing tools make: the file keeps all 48 samples (and states
    // 48 frames) while its edit list hides the first 8, so 40 decode.
    let path = dir.path().join("trimmed.mp4");
    remux(&["-ss", "0.3"], &full, &["-c", "copy"], &path);
    let stated = parse_probe(&ffprobe_fields("ffprobe", &path, &[], "stream=width,height,nb_frames").unwrap());
    assert_eq!(stated.and_then(|i| i.frames), Some(48), "the header states 48 frames");
    let want = ffmpeg_frames(&path, &[]);
    assert_eq!(want.len(), 40, "ffmpeg decodes 40");

    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    assert_eq!(clip.len(), 40);
    let warnings = ctx.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].message.contains("states 48 frames but 40 decode"), "{}", warnings[0].message);
    for (i, frame) in want.iter().enumerate() {
        assert!(rgb24(&clip.image(i, &ctx).unwrap()) == *frame, "frame {i} differs from ffmpeg's decode");
    }
    // Asked out of order, each answer seeks: the same frames.
    let jump = video_clip(&path, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
    for i in [39, 5, 30, 0, 17, 38] {
        assert!(rgb24(&jump.image(i, &ctx).unwrap()) == want[i], "frame {i} differs after a seek");
    }
    // The untouched file keeps its stated count and gives no warning.
    let ctx = CookCtx::new();
    assert_eq!(video_clip(&full, 0.0, &ctx, LoadSequence::node_error).unwrap().len(), 48);
    assert!(ctx.warnings().is_empty());
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_cancelled_read_leaves_the_clip_usable() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_video(dir.path(), "t.mp4", 48, &[]);
    let token = pyrograph_core::CancelToken::new();
    let ctx = CookCtx::new().with_cancel(token.clone());
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    let a = clip.image(10, &ctx).unwrap();
    token.cancel();
    assert!(clip.image(30, &ctx).is_err(), "a cancelled cook stops");
    token.reset();
    assert!(clip.image(10, &ctx).unwrap().data() == a.data());
    let fresh = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    assert!(clip.image(30, &ctx).unwrap().data() == fresh.image(30, &ctx).unwrap().data());
}

#[test]
fn rotation_turns_the_size_and_deep_formats_keep_their_bits() {
    let base = "width=1920\nheight=1080\nr_frame_rate=30/1\navg_frame_rate=30/1\n";
    let turned = parse_probe(&format!("{base}pix_fmt=yuv420p\nbits_per_raw_sample=8\nrotation=-90\n")).unwrap();
    assert_eq!((turned.width, turned.height, turned.rotation, turned.bits), (1080, 1920, -90, 8));
    let old_tag = parse_probe(&format!("{base}TAG:rotate=270\n")).unwrap();
    assert_eq!((old_tag.width, old_tag.height), (1080, 1920));
    let upside_down = parse_probe(&format!("{base}rotation=180\n")).unwrap();
    assert_eq!((upside_down.width, upside_down.height), (1920, 1080));
    // hevc states no bits_per_raw_sample: its pixel format's byte order says it is deeper than 8.
    let ten = parse_probe(&format!("{base}pix_fmt=yuv420p10le\nbits_per_raw_sample=N/A\n")).unwrap();
    assert_eq!(ten.bits, 16);
    let ten = parse_probe(&format!("{base}pix_fmt=yuv420p10le\nbits_per_raw_sample=10\n")).unwrap();
    assert_eq!(ten.bits, 10);
    assert_eq!(parse_probe(&format!("{base}pix_fmt=nv12\n")).unwrap().bits, 8);
}

#[test]
fn a_variable_rate_is_resampled_to_its_base_rate_or_the_standard_rate_nearest_its_average() {
    // 24 frames at 24 fps, then 24 at 8 fps: base 24, average 12.8 (64/5).
    let mut packets: Vec<String> = (0..24).map(|i| format!("{:.6},0.041667", f64::from(i) / 24.0)).collect();
    packets.extend((0..24).map(|i| format!("{:.6},0.041667", 1.0 + f64::from(i) / 8.0)));
    packets.reverse(); // packets come in decoding order, not time order
    let v = variable_rate(&packets.join("\n"), Some(12.8), Some(24.0)).unwrap();
    assert_eq!((v.rate, v.source_frames), (24.0, 48));
    assert!((v.seconds - (1.0 + 23.0 / 8.0 + 0.041667)).abs() < 1e-6, "{}", v.seconds);
    // A phone clip: base 120 (its clock), average 29.83: resampled to 29.97.
    let phone: Vec<String> = (0..300).map(|i| format!("{:.6},", f64::from(i) / 29.83)).collect();
    let v = variable_rate(&phone.join("\n"), Some(29.83), Some(120.0)).unwrap();
    assert_eq!(v.rate, 29.97);
    assert!((v.seconds - 300.0 / 29.83).abs() < 1e-3, "a last packet without a duration lasts one step");
    // An average far from every standard rate is kept as it is.
    let v = variable_rate(&phone.join("\n"), Some(17.3), None).unwrap();
    assert_eq!(v.rate, 17.3);
    assert_eq!(variable_rate("0.5,0.1\n", Some(10.0), None), None, "one packet has no rate");
}

#[test]
fn times_on_the_base_rate_grid_are_a_constant_rate_whatever_the_stated_average() {
    let ntsc: Vec<String> = (0..90).rev().map(|i| format!("{:.6},0.033367", f64::from(i) * 1001.0 / 30000.0)).collect();
    assert!(on_one_grid(&ntsc.join("\n"), 30000.0 / 1001.0));
    // A frame dropped (a gap of two steps) or a frame late by more than half a step: not one grid.
    let mut dropped = ntsc.clone();
    dropped.remove(40);
    assert!(!on_one_grid(&dropped.join("\n"), 30000.0 / 1001.0));
    let mut late = ntsc.clone();
    late[10] = format!("{:.6},", (79.0 + 0.6) * 1001.0 / 30000.0);
    assert!(!on_one_grid(&late.join("\n"), 30000.0 / 1001.0));
    assert!(!on_one_grid("0.0,\n", 24.0) && !on_one_grid("", 24.0));
    // Interlaced 1080i50: frames every 1/25 s, a base rate of 50 fields. Not on the fields' grid
    // (every other slot is empty), on the frames' grid.
    let fields: Vec<String> = (0..50).map(|i| format!("{:.6},0.04", f64::from(i) / 25.0)).collect();
    assert!(!on_one_grid(&fields.join("\n"), 50.0) && on_one_grid(&fields.join("\n"), 25.0));
}

#[test]
fn sixteen_bit_frames_keep_values_between_the_eight_bit_steps() {
    let v: u16 = 1000; // 1000/65535 lies between 3/255 and 4/255
    let px: Vec<u8> = [v, 0, 65535].iter().flat_map(|s| s.to_le_bytes()).collect();
    let img = rgb48_to_image(1, 1, &px).unwrap();
    assert!((img.data()[0] - 1000.0 / 65535.0).abs() < 1e-7 && img.data()[2] == 1.0 && img.data()[3] == 1.0);
    assert!(rgb48_to_image(2, 1, &px).is_err());
}

fn rgb24(img: &Image) -> Vec<u8> {
    img.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).map(|v| (v * 255.0).round() as u8).collect()
}

fn rgb48(img: &Image) -> Vec<u8> {
    img.data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .flat_map(|v| ((v * 65535.0).round() as u16).to_le_bytes())
        .collect()
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_ten_bit_clip_keeps_its_precision() {
    let dir = tempfile::tempdir().unwrap();
    let path = make_video(dir.path(), "t.mkv", 12, &["-pix_fmt", "yuv420p10le"]);
    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    let want = ffmpeg_decode(&path, &[], "rgb48le", 128 * 96 * 6);
    assert_eq!((clip.len(), want.len()), (12, 12));
    let mut between = 0;
    for (i, frame) in want.iter().enumerate() {
        let img = clip.image(i, &ctx).unwrap();
        assert!(rgb48(&img) == *frame, "frame {i} differs from ffmpeg's 16-bit decode");
        between += img.data().iter().filter(|v| ((*v * 255.0) - (*v * 255.0).round()).abs() > 0.05).count();
    }
    assert!(between > 1000, "values between the 8-bit steps: {between}");
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_rotation_tag_turns_the_frames_as_players_show_them() {
    let dir = tempfile::tempdir().unwrap();
    let flat = make_video(dir.path(), "t.mp4", 12, &[]);
    let path = dir.path().join("turned.mp4");
    remux(&[], &flat, &["-c", "copy", "-metadata:s:v:0", "rotate=90"], &path);
    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    let upright = video_clip(&flat, 0.0, &ctx, LoadSequence::node_error).unwrap();
    let (a, b) = (clip.image(5, &ctx).unwrap(), upright.image(5, &ctx).unwrap());
    assert_eq!((a.size(), b.size()), ((96, 128), (128, 96)));
    // Turned a quarter counter-clockwise: the upright frame's top-right corner is the top-left.
    let at = |img: &Image, x: u32, y: u32| img.data()[((y * img.width() + x) * 4) as usize..][..3].to_vec();
    let mut same = 0;
    for y in 0..96 {
        for x in 0..128 {
            let turned = at(&a, y, 127 - x);
            same += usize::from(turned.iter().zip(at(&b, x, y)).all(|(p, q)| (p - q).abs() < 0.02));
        }
    }
    assert!(same > 128 * 96 * 9 / 10, "{same} of {} pixels where a quarter turn puts them", 128 * 96);
    // And seeking gives the frames a walk gives.
    let walk: Vec<Arc<Image>> = (0..12).map(|i| clip.image(i, &ctx).unwrap()).collect();
    let jump = video_clip(&path, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
    for i in [9, 2, 11, 0] {
        assert!(jump.image(i, &ctx).unwrap().data() == walk[i].data(), "frame {i}");
    }
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_variable_rate_clip_is_resampled_by_its_timestamps_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    // 24 frames at 24 fps, then every third frame (8 fps) to 4 s: 48 frames over 3.92 s.
    let path = make_video(dir.path(), "vfr.mp4", 96, &["-vf", "select='lt(n\\,24)+not(mod(n\\,3))'", "-fps_mode", "vfr"]);
    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    let want = ffmpeg_frames(&path, &["-vf", "fps=24"]);
    assert_eq!(clip.fps(), 24.0);
    assert_eq!(clip.len(), want.len(), "as many frames as ffmpeg's own resampling gives");
    assert_eq!(clip.len(), 94);
    let warnings = ctx.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let w = &warnings[0].message;
    assert!(
        w.contains("variable frame rate") && w.contains("48 frames over 3.92 s") && w.contains("to 24 fps, 94 frames"),
        "{w}"
    );
    for (i, frame) in want.iter().enumerate() {
        assert!(rgb24(&clip.image(i, &ctx).unwrap()) == *frame, "frame {i} differs from ffmpeg's resampled decode");
    }
    // Frames 24-26 hold one source frame, as its time says.
    assert!(want[24] == want[25] && want[25] == want[26] && want[26] != want[27]);
    // Asked out of order, each answer seeks (to the keyframe before, resampling from there): the
    // frames a walk gives.
    let jump = video_clip(&path, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
    for i in [70, 5, 93, 30, 31, 0, 50, 24, 26] {
        assert!(rgb24(&jump.image(i, &ctx).unwrap()) == want[i], "frame {i} after a seek");
    }
    // The same clip starting 1.5 s into its clock (an offset an editor or a camera leaves): the
    // same frames, walked and sought.
    let late = dir.path().join("late.mp4");
    remux(&[], &path, &["-c", "copy", "-output_ts_offset", "1.5"], &late);
    let late_walk = video_clip(&late, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
    assert_eq!(late_walk.len(), want.len());
    for (i, frame) in want.iter().enumerate() {
        assert!(rgb24(&late_walk.image(i, &ctx).unwrap()) == *frame, "frame {i} of the late clip");
    }
    let late_jump = video_clip(&late, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
    for i in [93, 70, 5, 31, 0, 50] {
        assert!(rgb24(&late_jump.image(i, &ctx).unwrap()) == want[i], "frame {i} of the late clip after a seek");
    }
    // A rate asked for samples there instead.
    let ctx = CookCtx::new();
    let thirty = video_clip(&path, 30.0, &ctx, LoadSequence::node_error).unwrap();
    let want = ffmpeg_frames(&path, &["-vf", "fps=30"]);
    assert_eq!((thirty.len(), thirty.fps()), (want.len(), 30.0));
    for i in [0, 40, want.len() - 1] {
        assert!(rgb24(&thirty.image(i, &ctx).unwrap()) == want[i], "frame {i} at 30 fps");
    }
}

#[test]
#[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
fn a_cut_that_leaves_a_gap_in_the_times_keeps_the_count_that_decodes() {
    let dir = tempfile::tempdir().unwrap();
    let full = make_video(dir.path(), "t.mp4", 96, &[]);
    // A stream copy of the first 40 frames: it states 40 and 40 decode, but a B-frame it dropped
    // leaves a gap, so the last frame's time says 42.
    let path = dir.path().join("cut.mp4");
    remux(&[], &full, &["-frames:v", "40", "-c", "copy"], &path);
    let want = ffmpeg_frames(&path, &[]);
    assert_eq!(want.len(), 40);
    let ctx = CookCtx::new();
    let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
    assert_eq!(clip.len(), 40);
    assert!(ctx.warnings().is_empty(), "{:?}", ctx.warnings());
    for (i, frame) in want.iter().enumerate() {
        assert!(rgb24(&clip.image(i, &ctx).unwrap()) == *frame, "frame {i}");
    }
}
