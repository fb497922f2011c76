//! The Eigenfires pre-processing graphs on real footage (never committed to this repository):
//! `graphs/preprocess-candle.ron` and `graphs/preprocess-tealight.ron` cook and write clean
//! gray flame sequences; on the tea-light the glowing wax and glass stay outside the mask while
//! the flame, blue base included, is inside.

use std::path::{Path, PathBuf};
use std::process::Command;

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Value};
use pyrograph_testing::{footage, workspace};

fn render(graph: &str, out: &Path, frames: &str) {
    let graph = workspace().join("graphs").join(graph);
    let o = Command::new(env!("CARGO_BIN_EXE_pyrograph"))
        .args(["render", graph.to_str().unwrap(), "--out", out.to_str().unwrap(), "--frames", frames])
        .args(["--node", "write_gray", "--node", "write_mask"])
        .env("PYROGRAPH_FOOTAGE", footage())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}

fn gray(path: &Path) -> image::GrayImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_luma8()
}

/// (hue 0–360, saturation 0–255, value 0–255) of an 8-bit RGB pixel, as eq. 3 of the thesis.
fn hsv(r: f32, g: f32, b: f32) -> (f32, f32, f32) {
    let v = r.max(g).max(b);
    let d = v - r.min(g).min(b);
    let s = if v > 0.0 { 255.0 * d / v } else { 0.0 };
    let h = if d == 0.0 {
        0.0
    } else if v == r {
        60.0 * (g - b) / d
    } else if v == g {
        120.0 + 60.0 * (b - r) / d
    } else {
        240.0 + 60.0 * (r - g) / d
    };
    ((h + 360.0) % 360.0, s, v)
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn candle_preprocessing_writes_an_upright_clean_flame_for_every_frame() {
    let out = tempfile::tempdir().unwrap();
    render("preprocess-candle.ron", out.path(), "0-149");
    let dir = out.path().join("preprocess-candle");
    let mut leans = Vec::new();
    for f in 0..150 {
        let mask = gray(&dir.join(format!("mask_{f:04}.png")));
        let g = gray(&dir.join(format!("gray_{f:04}.png")));
        assert_eq!(g.dimensions(), (200, 240));
        let inside = mask.pixels().filter(|p| p[0] > 127).count();
        assert!((600..20_000).contains(&inside), "frame {f}: flame mask of {inside} px");
        // Background removed: the frame's border is black in the output.
        let border_max = (0..200).flat_map(|x| [g.get_pixel(x, 0)[0], g.get_pixel(x, 239)[0]]).max().unwrap();
        assert!(border_max < 10, "frame {f}: border pixel {border_max}");
        assert!(g.pixels().map(|p| p[0]).max().unwrap() > 200, "frame {f}: the flame is kept bright");
        leans.push(lean_of(&g));
    }
    let mean = leans.iter().map(|a| a.abs()).sum::<f64>() / leans.len() as f64;
    println!("candle: mean |lean| after pose normalization {mean:.2}°");
    assert!(mean < 3.0, "flames stand upright after pose normalization (mean |lean| {mean:.2}°)");
}

/// Lean from vertical (degrees) of the bright part (> 50 %) of a gray frame. A frame without a
/// flame is a failure, not 0°.
fn lean_of(g: &image::GrayImage) -> f64 {
    axis_of(g).unwrap_or_else(|| panic!("no flame contour in a {}x{} frame", g.width(), g.height())).angle_deg
}

/// The pipeline's flame axis (main contour, uniform weights) of the bright part of a gray frame.
fn axis_of(g: &image::GrayImage) -> Option<pyrograph_frontend::imaging::preprocess::pose::FlameAxis> {
    use pyrograph_frontend::imaging::preprocess::{contours::trace_contours, pose};
    let bits = g.pixels().map(|p| if p[0] > 127 { 255 } else { 0 }).collect();
    let mask = pyrograph_frontend::core::Mask::from_vec(g.width(), g.height(), bits).unwrap();
    let contours = trace_contours(&mask);
    pose::main_contour(&contours).and_then(|c| pose::flame_axis(c, pose::Weighting::Uniform))
}

/// Pose normalization measures what it undoes: real candle frames, turned by known angles about
/// their flame's root with imageproc's rotation (not the pipeline's warp), read back as one lean
/// plus the known turn, within 0.5° for every turn. (The lean is taken as the mean over the
/// turned copies, since each copy is resampled alike and the untouched frame is not.)
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn pose_normalization_recovers_known_rotations_of_real_frames() {
    use imageproc::geometric_transformations::{Border, Interpolation, rotate};
    let dir = footage().join("candle-black/frames");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert!(files.len() >= 150, "{} frames in {}", files.len(), dir.display());
    let turns = [-20.0f64, -10.0, 5.0, 15.0, 30.0];
    let mut worst: f64 = 0.0;
    for file in files.iter().step_by(30) {
        // At twice the resolution (bilinear), so the mask's pixel staircase, which a rotation
        // re-draws, moves the fitted axis by less than the 0.5° asked of it.
        let shot = gray(file);
        let frame = image::imageops::resize(&shot, shot.width() * 2, shot.height() * 2, image::imageops::FilterType::Triangle);
        let axis = axis_of(&frame).unwrap_or_else(|| panic!("{}: no flame", file.display()));
        let root = (axis.root[0] as f32, axis.root[1] as f32);
        // imageproc turns clockwise on screen for a positive angle: the tip moves right, which
        // the axis reports as a positive lean.
        let leans: Vec<f64> = turns
            .iter()
            .map(|turn| {
                let turned =
                    rotate(&frame, root, turn.to_radians() as f32, Interpolation::Bilinear, Border::Constant(image::Luma([0u8])));
                lean_of(&turned) - turn
            })
            .collect();
        let lean = leans.iter().sum::<f64>() / leans.len() as f64;
        for (turn, l) in turns.iter().zip(&leans) {
            println!(
                "{}: turned {turn:+}° reads the lean as {l:.2}° (mean {lean:.2}°, untouched {:.2}°)",
                file.display(),
                axis.angle_deg
            );
            worst = worst.max((l - lean).abs());
        }
    }
    println!("worst deviation of a turned copy's lean from the mean: {worst:.2}°");
    assert!(worst <= 0.5, "a known rotation was read back {worst:.2}° off");
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn tealight_mask_excludes_the_glowing_wax_and_glass_and_keeps_the_blue_base() {
    const FRAMES: usize = 120;
    let out = tempfile::tempdir().unwrap();
    render("preprocess-tealight.ron", out.path(), &format!("0-{}", FRAMES - 1));
    let dir = out.path().join("preprocess-tealight");

    // The same crop of the original frames, for colour checks.
    let (frames, ctx) = tealight_crop();

    let (mut wax_inside, mut wax_total, mut with_base) = (0usize, 0usize, 0usize);
    for f in 0..FRAMES {
        let mask = gray(&dir.join(format!("mask_{f:04}.png")));
        let rgb = frames.image(f, &ctx).unwrap();
        let mut base_inside = false;
        for y in 0..300u32 {
            for x in 0..300u32 {
                let p = rgb.pixel(x, y);
                let (h, s, v) = hsv(p[0] * 255.0, p[1] * 255.0, p[2] * 255.0);
                let masked = mask.get_pixel(x, y)[0] > 127;
                // Lit wax and frosted glass: pink-white, moderately saturated, bright.
                if (h >= 350.0 || h <= 20.0) && (60.0..=110.0).contains(&s) && v >= 150.0 && !(110..=190).contains(&x) {
                    wax_total += 1;
                    wax_inside += usize::from(masked);
                }
                // The violet-blue base of the flame, below its luminous zone.
                if (300.0..=350.0).contains(&h) && s >= 90.0 && (110.0..=200.0).contains(&v) && masked {
                    base_inside = true;
                }
            }
        }
        with_base += usize::from(base_inside);
        let inside = mask.pixels().filter(|p| p[0] > 127).count();
        assert!(inside > 300, "frame {f}: flame mask of only {inside} px");
    }
    assert!(wax_total > 100_000, "the test region holds glowing wax and glass ({wax_total} px)");
    let leak = wax_inside as f64 / wax_total as f64;
    println!(
        "tealight: {:.3} % of {wax_total} wax/glass pixels inside the mask; blue base inside in {with_base}/{FRAMES} frames",
        leak * 100.0
    );
    assert!(leak < 0.01, "{:.2} % of the glowing wax/glass pixels are inside the mask", leak * 100.0);
    assert!(with_base * 10 >= FRAMES * 8, "blue base inside the mask in only {with_base} of {FRAMES} frames");
}

/// The tea-light video cropped as the tealight preset crops it (300×300 at 90, 100), as a clip of
/// the original colours, and the context to read it with.
fn tealight_crop() -> (pyrograph_frontend::core::Clip, CookCtx) {
    let mut doc = GraphDoc::new();
    let video = footage().join("tealight-candle/candle.mp4");
    doc.add_node("v", NodeDoc::new("imaging.load_sequence").param("path", ParamValue::String(video.display().to_string())));
    doc.add_node(
        "crop",
        NodeDoc::new("imaging.crop")
            .param("x", ParamValue::Int(90))
            .param("y", ParamValue::Int(100))
            .param("width", ParamValue::Int(300))
            .param("height", ParamValue::Int(300)),
    );
    doc.connect("v.clip", "crop.image");
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), Path::new("."), &BuildOptions::default()).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(frames) = Evaluator::new().output(&g, "crop.image", &ctx).unwrap() else { panic!("expected a clip") };
    (frames, ctx)
}

/// The hand-labelled flame outlines of tests/data/tealight-flame-labels.json, filled, one 300×300
/// mask per labelled frame (the tealight preset's crop).
fn tealight_labels() -> Vec<(usize, image::GrayImage)> {
    let doc: serde_json::Value = serde_json::from_str(include_str!("data/tealight-flame-labels.json")).unwrap();
    let frames = doc["frames"].as_object().unwrap();
    let mut out: Vec<(usize, image::GrayImage)> = frames
        .iter()
        .map(|(f, poly)| {
            let points: Vec<imageproc::point::Point<i32>> = poly
                .as_array()
                .unwrap()
                .iter()
                .map(|p| imageproc::point::Point::new(p[0].as_i64().unwrap() as i32, p[1].as_i64().unwrap() as i32))
                .collect();
            let mut m = image::GrayImage::new(300, 300);
            imageproc::drawing::draw_polygon_mut(&mut m, &points, image::Luma([255]));
            (f.parse().unwrap(), m)
        })
        .collect();
    out.sort_by_key(|(f, _)| *f);
    out
}

/// How a mask scores against a hand label over the whole crop.
struct LabelScore {
    /// Intersection over union.
    iou: f64,
    /// Share of the mask inside the label (what keeps the wax and glass out).
    precision: f64,
    /// Share of the label's pixels at or below [`TEALIGHT_BASE_ROW`] (its blue base) in the mask.
    base: f64,
}

fn score(mask: &image::GrayImage, truth: &image::GrayImage) -> LabelScore {
    let (mut inter, mut union, mut masked, mut low, mut low_hit) = (0usize, 0usize, 0usize, 0usize, 0usize);
    for (x, y, t) in truth.enumerate_pixels() {
        let (a, b) = (mask.get_pixel(x, y)[0] > 127, t[0] > 127);
        inter += usize::from(a && b);
        union += usize::from(a || b);
        masked += usize::from(a);
        if b && y >= TEALIGHT_BASE_ROW {
            low += 1;
            low_hit += usize::from(a);
        }
    }
    let share = |a: usize, b: usize| a as f64 / b.max(1) as f64;
    LabelScore { iou: share(inter, union), precision: share(inter, masked), base: share(low_hit, low) }
}

/// Rows of the crop at and below which the labels hold the flame's violet-blue base.
const TEALIGHT_BASE_ROW: u32 = 258;
/// Limits near what the preset scores (measured 2026-11-26: IoU 0.45–0.69, mean 0.547; precision
/// 0.82–0.98; base covered 18–88 %, mean 49 %). The preset keeps the wax and glass out but finds
/// only about half of the labelled flame: the neck seen through the glass rim, as bright and pale
/// as the lit glass there, and the dimmer half of the blue base are missed.
const TEALIGHT_MIN_IOU: f64 = 0.42;
const TEALIGHT_MEAN_IOU: f64 = 0.52;
const TEALIGHT_MIN_PRECISION: f64 = 0.8;
const TEALIGHT_MEAN_BASE: f64 = 0.4;

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn tealight_mask_matches_hand_labelled_flames() {
    let labels = tealight_labels();
    assert!(labels.len() >= 10, "{} labelled frames", labels.len());
    let list: Vec<String> = labels.iter().map(|(f, _)| f.to_string()).collect();
    let out = tempfile::tempdir().unwrap();
    render("preprocess-tealight.ron", out.path(), &list.join(","));
    let dir = out.path().join("preprocess-tealight");
    let (mut iou, mut base) = (0.0, 0.0);
    for (f, truth) in &labels {
        let mask = gray(&dir.join(format!("mask_{f:04}.png")));
        assert_eq!(mask.dimensions(), truth.dimensions(), "frame {f}");
        let s = score(&mask, truth);
        println!(
            "tealight frame {f}: IoU {:.3} with the hand label, precision {:.2}, base covered {:.0} %",
            s.iou,
            s.precision,
            s.base * 100.0
        );
        assert!(s.iou >= TEALIGHT_MIN_IOU, "frame {f}: IoU {:.3} with the hand-labelled flame", s.iou);
        assert!(s.precision >= TEALIGHT_MIN_PRECISION, "frame {f}: only {:.2} of the mask is flame", s.precision);
        iou += s.iou / labels.len() as f64;
        base += s.base / labels.len() as f64;
    }
    println!("tealight: mean IoU {iou:.3}, mean base covered {:.0} % over {} hand-labelled frames", base * 100.0, labels.len());
    assert!(iou >= TEALIGHT_MEAN_IOU, "mean IoU {iou:.3}");
    assert!(base >= TEALIGHT_MEAN_BASE, "the mask covers {:.0} % of the labelled blue base", base * 100.0);
}

/// The measure above can fail: a mask of everything bright (value ≥ 0.6, the lit wax and glass
/// with the flame) or the right flame shifted by 12 pixels scores below the limits.
#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn tealight_label_score_rejects_a_bright_mask_and_a_shifted_flame() {
    let labels = tealight_labels();
    let (frames, ctx) = tealight_crop();
    let (mut bright, mut shifted) = (Vec::new(), Vec::new());
    for (f, truth) in &labels {
        let rgb = frames.image(*f, &ctx).unwrap();
        let lit = image::GrayImage::from_fn(300, 300, |x, y| {
            let p = rgb.pixel(x, y);
            image::Luma([if p[0].max(p[1]).max(p[2]) >= 0.6 { 255 } else { 0 }])
        });
        let moved =
            image::GrayImage::from_fn(300, 300, |x, y| if x >= 12 { *truth.get_pixel(x - 12, y) } else { image::Luma([0]) });
        bright.push(score(&lit, truth).iou);
        shifted.push(score(&moved, truth).iou);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!("bright mask: mean IoU {:.3}; flame shifted 12 px: {:.3}", mean(&bright), mean(&shifted));
    assert!(mean(&bright) < TEALIGHT_MEAN_IOU, "a mask of everything bright scores {:.3}", mean(&bright));
    assert!(mean(&shifted) < TEALIGHT_MEAN_IOU, "a shifted flame scores {:.3}", mean(&shifted));
}
