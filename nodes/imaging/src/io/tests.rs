//! Tests of the loaders and writers in `io/`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyrograph_core::{Channels, Clip, CookCtx, FrameSet, Image, PortType, Value};
use pyrograph_testing::footage;

use super::*;
use crate::color::AlphaMode;

#[test]
fn write_image_writes_once_and_refuses_to_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("still.png");
    let img = gray(2, 1, &[0.0, 1.0]);
    let png = OutputFormat::Png { sixteen_bit: false };
    write_image(&img, &path, png, false).unwrap();
    assert_eq!(load_image(&path).unwrap(), img);
    assert!(write_image(&img, &path, png, false).unwrap_err().to_string().contains("already exists"));
    write_image(&img, &path, png, true).unwrap();
}

use crate::testing::{gray, rgba};

fn clip_of(images: Vec<Image>) -> Clip {
    let frames = images.into_iter().map(|i| Value::Image(Arc::new(i))).collect();
    Clip::from_frames(PortType::Image, 24.0, frames)
}

fn options(pattern: PathBuf, format: OutputFormat) -> WriteOptions {
    WriteOptions { pattern, format, start: 0, overwrite: false, frames: None, skip_existing: false, alpha: AlphaMode::Straight }
}

fn assert_close(a: &[f32], b: &[f32], tol: f32) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= tol, "{a:?} vs {b:?}");
    }
}

#[test]
fn hash_pattern_parses_and_formats() {
    let p = FramePattern::parse("frame_####.png").unwrap().unwrap();
    assert_eq!(p, FramePattern { prefix: "frame_".into(), width: 4, suffix: ".png".into() });
    assert_eq!(p.file_name(7), "frame_0007.png");
    assert_eq!(p.file_name(12345), "frame_12345.png");
}

#[test]
fn printf_pattern_parses_and_formats() {
    let p = FramePattern::parse("f%04d.exr").unwrap().unwrap();
    assert_eq!(p, FramePattern { prefix: "f".into(), width: 4, suffix: ".exr".into() });
    assert_eq!(p.file_name(3), "f0003.exr");
    assert_eq!(FramePattern::parse("f%d.png").unwrap().unwrap().file_name(42), "f42.png");
}

#[test]
fn missing_or_double_placeholder_is_reported() {
    assert_eq!(FramePattern::parse("frame.png").unwrap(), None);
    assert!(FramePattern::parse("a_##_b_##.png").is_err());
    let err = output_pattern(Path::new("/tmp/out/frame.png")).map_err(WriteSequence::node_error).unwrap_err();
    assert!(err.to_string().contains("no frame-number placeholder"), "{err}");
    assert!(err.to_string().contains("pattern"), "{err}");
}

#[test]
fn pattern_matches_only_its_own_padding() {
    let p = FramePattern::parse("frame_####.png").unwrap().unwrap();
    assert_eq!(p.number_of("frame_0012.png"), Some(12));
    assert_eq!(p.number_of("frame_12345.png"), Some(12345));
    assert_eq!(p.number_of("frame_012.png"), None);
    assert_eq!(p.number_of("frame_00012.png"), None);
    assert_eq!(p.number_of("frame_00a2.png"), None);
    assert_eq!(p.number_of("other_0012.png"), None);
}

#[test]
fn natural_order_puts_2_before_10() {
    let mut names = vec!["f10.png", "f2.png", "f1.png"];
    names.sort_by(|a, b| natural_cmp(a, b));
    assert_eq!(names, ["f1.png", "f2.png", "f10.png"]);
}

#[test]
fn png8_round_trips_rgba_and_gray() {
    let dir = tempfile::tempdir().unwrap();
    let img = rgba(2, 1, &[0.0, 0.5, 1.0, 1.0, 0.25, 0.75, 0.1, 0.5]);
    let clip = clip_of(vec![img.clone(), img.clone()]);
    let ctx = CookCtx::new();
    let written =
        write_sequence(&clip, &options(dir.path().join("c_####.png"), OutputFormat::Png { sixteen_bit: false }), &ctx).unwrap();
    assert_eq!(written, [dir.path().join("c_0000.png"), dir.path().join("c_0001.png")]);
    let back = load_image(&written[1]).unwrap();
    assert_eq!(back.channels(), Channels::Rgba);
    assert_close(back.data(), img.data(), 0.5 / 255.0 + 1e-6);

    let g = gray(3, 1, &[0.0, 0.5, 1.0]);
    write_sequence(
        &clip_of(vec![g.clone()]),
        &options(dir.path().join("g_%02d.png"), OutputFormat::Png { sixteen_bit: false }),
        &ctx,
    )
    .unwrap();
    let back = load_image(&dir.path().join("g_00.png")).unwrap();
    assert_eq!(back.channels(), Channels::Gray);
    assert_close(back.data(), g.data(), 0.5 / 255.0 + 1e-6);
}

#[test]
fn png16_round_trips_within_16_bit_quantization() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let img = rgba(1, 1, &[0.123_456, 0.5, 0.999, 0.3]);
    let g = gray(2, 1, &[0.333_333, 0.777_777]);
    let fmt = OutputFormat::Png { sixteen_bit: true };
    write_sequence(&clip_of(vec![img.clone()]), &options(dir.path().join("c_#.png"), fmt), &ctx).unwrap();
    write_sequence(&clip_of(vec![g.clone()]), &options(dir.path().join("g_#.png"), fmt), &ctx).unwrap();
    assert_close(load_image(&dir.path().join("c_0.png")).unwrap().data(), img.data(), 0.5 / 65535.0 + 1e-6);
    let back = load_image(&dir.path().join("g_0.png")).unwrap();
    assert_eq!(back.channels(), Channels::Gray);
    assert_close(back.data(), g.data(), 0.5 / 65535.0 + 1e-6);
}

/// Two renders of one frame must be the same file, so a farm can check outputs by their hash:
/// the exr crate's parallel compression writes chunks in the order they finish.
#[test]
fn an_exr_is_the_same_bytes_every_time() {
    let (w, h) = (96, 512);
    let mut rng = pyrograph_testing::Lcg::new(7);
    let img = rgba(w, h, &(0..w * h * 4).map(|_| rng.next_f32() * 4.0).collect::<Vec<f32>>());
    for half in [true, false] {
        let first = encode_image(&img, OutputFormat::Exr { half }).unwrap();
        for _ in 0..8 {
            assert!(encode_image(&img, OutputFormat::Exr { half }).unwrap() == first, "half {half}: another byte order");
        }
    }
}

#[test]
fn exr_half_and_float_round_trip_keeping_hdr() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let img = rgba(2, 1, &[0.1, 2.5, 17.0, 1.0, 0.0, 0.3, 0.7, 0.25]);
    let g = gray(1, 2, &[0.2, 5.5]);
    for (half, tol) in [(true, 2e-3_f32), (false, 0.0)] {
        let fmt = OutputFormat::Exr { half };
        let tag = if half { "h" } else { "f" };
        write_sequence(&clip_of(vec![img.clone()]), &options(dir.path().join(format!("{tag}c_####.exr")), fmt), &ctx).unwrap();
        write_sequence(&clip_of(vec![g.clone()]), &options(dir.path().join(format!("{tag}g_####.exr")), fmt), &ctx).unwrap();
        let back = load_image(&dir.path().join(format!("{tag}c_0000.exr"))).unwrap();
        assert_eq!(back.size(), (2, 1));
        // Half floats keep about three significant digits.
        let rel: Vec<f32> = back.data().iter().zip(img.data()).map(|(b, a)| (b - a) / a.max(1.0)).collect();
        assert_close(&rel, &[0.0; 8], tol);
        let back = load_image(&dir.path().join(format!("{tag}g_0000.exr"))).unwrap();
        assert_eq!(back.channels(), Channels::Gray);
        let rel: Vec<f32> = back.data().iter().zip(g.data()).map(|(b, a)| (b - a) / a.max(1.0)).collect();
        assert_close(&rel, &[0.0; 2], tol);
    }
}

#[test]
fn writer_refuses_to_overwrite_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    std::fs::write(dir.path().join("f_0001.png"), b"keep me").unwrap();
    let clip = clip_of(vec![gray(1, 1, &[0.5]); 3]);
    let opts = options(dir.path().join("f_####.png"), OutputFormat::Png { sixteen_bit: false });
    let err = write_sequence(&clip, &opts, &ctx).unwrap_err().to_string();
    assert!(err.contains("f_0001.png") && err.contains("overwrite"), "{err}");
    assert!(!dir.path().join("f_0000.png").exists());
    assert!(!dir.path().join("f_0002.png").exists());
    assert_eq!(std::fs::read(dir.path().join("f_0001.png")).unwrap(), b"keep me");

    let opts = WriteOptions { overwrite: true, ..opts };
    assert_eq!(write_sequence(&clip, &opts, &ctx).unwrap().len(), 3);
    assert_eq!(load_image(&dir.path().join("f_0001.png")).unwrap().size(), (1, 1));
}

#[test]
fn writer_premultiplies_rgba_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let clip = clip_of(vec![rgba(1, 1, &[0.8, 0.4, 1.0, 0.5])]);
    let fmt = OutputFormat::Exr { half: false };
    let straight = options(dir.path().join("s_#.exr"), fmt);
    let pre = WriteOptions { alpha: AlphaMode::Premultiplied, ..options(dir.path().join("p_#.exr"), fmt) };
    let s = write_sequence(&clip, &straight, &ctx).unwrap();
    let p = write_sequence(&clip, &pre, &ctx).unwrap();
    assert_close(load_image(&s[0]).unwrap().data(), &[0.8, 0.4, 1.0, 0.5], 1e-6);
    assert_close(load_image(&p[0]).unwrap().data(), &[0.4, 0.2, 0.5, 0.5], 1e-6);
}

#[test]
fn writer_honours_frame_range_start_and_creates_folders() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let clip = clip_of((0..5).map(|i| gray(1, 1, &[i as f32 / 4.0])).collect());
    let opts = WriteOptions {
        start: 100,
        frames: Some(FrameSet::range(1, 2)),
        ..options(dir.path().join("a/b/x_###.png"), OutputFormat::Png { sixteen_bit: false })
    };
    let written = write_sequence(&clip, &opts, &ctx).unwrap();
    assert_eq!(written, [dir.path().join("a/b/x_101.png"), dir.path().join("a/b/x_102.png")]);
    assert_close(load_image(&written[1]).unwrap().data(), &[0.5], 0.5 / 255.0 + 1e-6);
    let outside = WriteOptions { frames: Some(FrameSet::range(3, 5)), ..opts };
    assert!(write_sequence(&clip, &outside, &ctx).unwrap_err().to_string().contains("0-4"));
}

#[test]
fn writer_takes_stepped_frames_and_lists() {
    let dir = tempfile::tempdir().unwrap();
    let clip = clip_of((0..10).map(|i| gray(1, 1, &[i as f32 / 9.0])).collect());
    let frames: FrameSet = "0-9:4,7".parse().unwrap();
    let opts =
        WriteOptions { frames: Some(frames), ..options(dir.path().join("f_#.png"), OutputFormat::Png { sixteen_bit: false }) };
    let written = write_sequence(&clip, &opts, &CookCtx::new()).unwrap();
    let names: Vec<String> = written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["f_0.png", "f_4.png", "f_7.png", "f_8.png"]);
}

#[test]
fn skip_existing_writes_only_the_missing_frames_and_leaves_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let clip = clip_of((0..6).map(|i| gray(1, 1, &[i as f32 / 5.0])).collect());
    let opts = options(dir.path().join("f_#.png"), OutputFormat::Png { sixteen_bit: false });
    let all = write_sequence(&clip, &opts, &ctx).unwrap();
    let whole: Vec<Vec<u8>> = all.iter().map(|p| std::fs::read(p).unwrap()).collect();
    // A crash took frames 2 and 5; frame 3 holds something else that must survive.
    std::fs::remove_file(&all[2]).unwrap();
    std::fs::remove_file(&all[5]).unwrap();
    std::fs::write(&all[3], b"kept").unwrap();
    assert!(write_sequence(&clip, &opts, &ctx).is_err(), "without skip_existing the existing files are refused");
    let resumed = write_sequence(&clip, &WriteOptions { skip_existing: true, ..opts }, &ctx).unwrap();
    assert_eq!(resumed, [all[2].clone(), all[5].clone()]);
    assert_eq!(std::fs::read(&all[3]).unwrap(), b"kept");
    for i in [0, 1, 2, 4, 5] {
        assert_eq!(std::fs::read(&all[i]).unwrap(), whole[i], "frame {i} is the same as an uninterrupted render");
    }
}

#[test]
fn output_format_follows_the_extension() {
    let png = output_format(Path::new("a_#.PNG"), BitDepth::Sixteen, ExrType::Half).unwrap();
    assert_eq!(png, OutputFormat::Png { sixteen_bit: true });
    let exr = output_format(Path::new("a_#.exr"), BitDepth::Eight, ExrType::Float).unwrap();
    assert_eq!(exr, OutputFormat::Exr { half: false });
    let err = output_format(Path::new("a_#.tif"), BitDepth::Eight, ExrType::Half).map_err(WriteSequence::node_error).unwrap_err();
    assert!(err.to_string().contains("pattern"));
}

#[test]
fn loads_a_folder_a_pattern_and_a_single_file() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let clip = clip_of((0..3).map(|i| gray(2, 2, &[i as f32 / 2.0; 4])).collect());
    write_sequence(&clip, &options(dir.path().join("s_####.png"), OutputFormat::Png { sixteen_bit: false }), &ctx).unwrap();
    std::fs::write(dir.path().join("notes.txt"), b"ignored").unwrap();

    let from_dir = LoadSequence::load(dir.path(), 0.0, &ctx).unwrap();
    assert_eq!((from_dir.len(), from_dir.fps()), (3, DEFAULT_FPS));
    assert_close(from_dir.image(2, &ctx).unwrap().data(), &[1.0; 4], 1e-6);

    let from_pattern = LoadSequence::load(&dir.path().join("s_%04d.png"), 30.0, &ctx).unwrap();
    assert_eq!((from_pattern.len(), from_pattern.fps()), (3, 30.0));
    assert_eq!(from_pattern.fingerprint(), from_dir.fingerprint());
    assert_close(from_pattern.image(1, &ctx).unwrap().data(), &[0.5; 4], 0.5 / 255.0 + 1e-6);

    let single = LoadSequence::load(&dir.path().join("s_0001.png"), 0.0, &ctx).unwrap();
    assert_eq!(single.len(), 1);
}

/// Frames 0-9 of a gray ramp written as `s_####.png`, except the numbers in `skip`.
fn sequence_with_gaps(dir: &Path, skip: &[usize]) {
    let ctx = CookCtx::new();
    let clip = clip_of((0..10).map(|i| gray(2, 2, &[i as f32 / 9.0; 4])).collect());
    write_sequence(&clip, &options(dir.join("s_####.png"), OutputFormat::Png { sixteen_bit: false }), &ctx).unwrap();
    for i in skip {
        std::fs::remove_file(dir.join(format!("s_{i:04}.png"))).unwrap();
    }
}

#[test]
fn a_sequence_with_missing_numbers_is_refused_naming_them_or_held() {
    let dir = tempfile::tempdir().unwrap();
    sequence_with_gaps(dir.path(), &[3, 6, 7]);
    let ctx = CookCtx::new();
    for path in [dir.path().join("s_####.png"), dir.path().to_path_buf()] {
        let err = LoadSequence::load(&path, 0.0, &ctx).unwrap_err().to_string();
        assert!(err.contains("frames 3, 6-7 are missing (3 of the numbers 0-9)") && err.contains("hold"), "{err}");
        let held = open_sequence(
            &path,
            &SequenceOptions { gaps: Gaps::Hold, ..SequenceOptions::default() },
            &ctx,
            LoadSequence::node_error,
        )
        .unwrap();
        assert_eq!(held.len(), 10, "every number keeps its frame");
        // Frame 3 repeats frame 2; frames 6 and 7 repeat frame 5; the others are their own.
        for (i, source) in [0, 1, 2, 2, 4, 5, 5, 5, 8, 9].into_iter().enumerate() {
            assert_close(held.image(i, &ctx).unwrap().data(), &[source as f32 / 9.0; 4], 0.5 / 255.0 + 1e-6);
        }
    }
    let one = tempfile::tempdir().unwrap();
    sequence_with_gaps(one.path(), &[4]);
    let err = LoadSequence::load(one.path(), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("frame 4 is missing (1 of the numbers 0-9)"), "{err}");
    // A folder of unrelated names is no numbered sequence: nothing is missing from it.
    let loose = tempfile::tempdir().unwrap();
    for name in ["a1.png", "b7.png"] {
        std::fs::copy(dir.path().join("s_0000.png"), loose.path().join(name)).unwrap();
    }
    assert_eq!(LoadSequence::load(loose.path(), 0.0, &ctx).unwrap().len(), 2);
    // A reference still of another type beside the frames is not a frame.
    std::fs::write(loose.path().join("reference.tif"), b"not read").unwrap();
    assert_eq!(LoadSequence::load(loose.path(), 0.0, &ctx).unwrap().len(), 2);
}

#[test]
fn missing_paths_and_unmatched_patterns_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let err = LoadSequence::load(&dir.path().join("nope.png"), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("nope.png") && err.contains("no such file or directory"), "{err}");
    let err = LoadSequence::load(&dir.path().join("f_####.png"), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("no files match"), "{err}");
    let err = LoadSequence::load(dir.path(), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("no image files"), "{err}");
    assert!(load_image(&dir.path().join("x.png")).unwrap_err().to_string().contains("no such file"));
}

#[test]
fn empty_and_corrupt_files_are_reported_by_name_at_cook_time() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    std::fs::write(dir.path().join("empty.png"), b"").unwrap();
    let err = LoadSequence::load(&dir.path().join("empty.png"), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("empty.png"), "{err}");
    // A PNG signature followed by garbage instead of an IHDR chunk.
    let mut corrupt = b"\x89PNG\r\n\x1a\n".to_vec();
    corrupt.extend_from_slice(&[0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6]);
    std::fs::write(dir.path().join("bad.png"), &corrupt).unwrap();
    let err = LoadSequence::load(&dir.path().join("bad.png"), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("bad.png"), "{err}");
    let err = load_image(&dir.path().join("bad.png")).unwrap_err().to_string();
    assert!(err.contains("bad.png"), "{err}");
}

#[test]
fn mismatched_sizes_name_the_odd_file() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = CookCtx::new();
    let fmt = OutputFormat::Png { sixteen_bit: false };
    write_sequence(&clip_of(vec![gray(2, 2, &[0.0; 4]); 2]), &options(dir.path().join("m_####.png"), fmt), &ctx).unwrap();
    let odd = WriteOptions { start: 2, ..options(dir.path().join("m_####.png"), fmt) };
    write_sequence(&clip_of(vec![gray(3, 1, &[0.0; 3])]), &odd, &ctx).unwrap();
    let err = LoadSequence::load(dir.path(), 0.0, &ctx).unwrap_err().to_string();
    assert!(err.contains("m_0002.png") && err.contains("3x1") && err.contains("2x2"), "{err}");
}

#[test]
fn cook_reads_ports_and_reports_frames_written() {
    let dir = tempfile::tempdir().unwrap();
    let clip = Value::Clip(clip_of(vec![gray(1, 1, &[1.0]); 2]));
    let out = pyrograph_core::testing::cook::<WriteSequence>(&[
        ("clip", clip),
        ("pattern", Value::Path(dir.path().join("o_####.png"))),
    ])
    .unwrap();
    assert!(matches!(out[0], Value::Int(2)));
    assert!(matches!(&out[1], Value::Path(p) if p.ends_with("o_0000.png")));
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn loads_the_candle_black_frames() {
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&footage().join("candle-black/frames"), 0.0, &ctx).unwrap();
    assert_eq!(clip.len(), 150);
    let img = clip.image(149, &ctx).unwrap();
    assert_eq!(img.size(), (854, 480));
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn loads_the_tealight_video() {
    let ctx = CookCtx::new();
    let clip = LoadSequence::load(&footage().join("tealight-candle/candle.mp4"), 0.0, &ctx).unwrap();
    assert_eq!(clip.len(), 796);
    assert!(clip.fps() > 0.0);
    let img = clip.image(795, &ctx).unwrap();
    assert_eq!((img.size(), img.channels()), ((480, 480), Channels::Rgba));
}

/// A PNG of a few dozen bytes whose header declares `w` × `h` RGB pixels (and no pixel data).
#[test]
fn a_header_declaring_an_enormous_image_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bomb.png");
    std::fs::write(&path, pyrograph_testing::png_declaring(40_000, 40_000)).unwrap();
    let e = load_image(&path).unwrap_err().to_string();
    assert!(e.contains("bomb.png") && e.contains("declares 40000 × 40000 pixels (1600.0 megapixels)"), "{e}");
    assert!(e.contains("PYROGRAPH_MAX_PIXELS"), "{e}");
    // Within the budget, the same header is read (and then fails on its missing pixels).
    std::fs::write(&path, pyrograph_testing::png_declaring(4, 4)).unwrap();
    let e = load_image(&path).unwrap_err().to_string();
    assert!(!e.contains("declares"), "{e}");
}
