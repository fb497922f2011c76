//! Fires in scene plates (issue 65): several fires in one frame are all kept and listed, and a
//! fire with no single axis is left upright with a warning that says why. The plates are made
//! from the shared candle clip with ffmpeg — two candles side by side, the candle stretched into a
//! wide fire — and run through `graphs/preprocess-auto.ron` with only the input path changed; the
//! masks are compared with the untouched clip's, mapped through the same construction. The candle
//! is also set in a lit room (a brick wall in the flame's hues, lamps and a window as bright as it)
//! and filmed from a shaken camera, and must be masked as it is on black.

use std::path::Path;

use image::GrayImage;
use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, ParamValue, Value};
use pyrograph_frontend::imaging::preprocess::regions::FireRegions;
use pyrograph_frontend::imaging::preprocess::stabilize::Rigid;
use pyrograph_testing::{footage, workspace};

#[path = "support/plates.rs"]
mod plates;
use plates::{ffmpeg_frames, iou, median};

/// Frames of each plate: enough for the clip-wide judgement and the smoothing window.
const FRAMES: usize = 24;

/// The frame shown in the README's picture of a scene plate.
const PICTURED: usize = 12;

/// `FRAMES` frames of the candle clip through the ffmpeg `filter`, as PNG frames in `dir/name`.
fn make_clip(dir: &Path, name: &str, filter: &str) -> std::path::PathBuf {
    let candle = footage().join("candle-black/frames/frame_%04d.png");
    ffmpeg_frames(dir, name, &["-framerate", "24", "-i", candle.to_str().unwrap()], filter, FRAMES)
}

/// What the graph made of one plate.
struct Outcome {
    /// The crop box: x, y, width, height.
    crop: [u32; 4],
    /// Frame [`PICTURED`] of the output (the cut-out, straightened crop), as gray.
    output: Option<GrayImage>,
    /// Each frame's mask placed back into the plate's frame.
    masks: Vec<GrayImage>,
    /// Fires above the size per frame.
    counts: Vec<i64>,
    /// Each frame's turn.
    turned: Vec<f64>,
    /// The outline's elongation per frame.
    elongation: Vec<f64>,
    /// Each frame's fires' areas, largest first.
    areas: Vec<Vec<f64>>,
    warnings: Vec<String>,
}

fn cook(frames: &Path, size: (u32, u32)) -> Outcome {
    cook_with(frames, size, &[])
}

/// [`cook`] with parameters of the graph's nodes set: `(node, parameter, value)`.
fn cook_with(frames: &Path, size: (u32, u32), sets: &[(&str, &str, ParamValue)]) -> Outcome {
    let mut doc = GraphDoc::load(&workspace().join("graphs/preprocess-auto.ron")).unwrap();
    doc.set_param("frames", "path", ParamValue::String(frames.display().to_string())).unwrap();
    for (node, param, value) in sets {
        doc.set_param(node, param, value.clone()).unwrap();
    }
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), &workspace().join("graphs"), &BuildOptions::default()).unwrap();
    let (mut ev, ctx) = (Evaluator::new(), CookCtx::new());
    let mut value = |port: &str| ev.output(&g, port, &ctx).unwrap_or_else(|e| panic!("{port}: {e}"));
    let int = |v: Value| match v {
        Value::Int(n) => n,
        other => panic!("{other:?}"),
    };
    let (x, y, width, height) = (int(value("crop.x")), int(value("crop.y")), int(value("crop.width")), int(value("crop.height")));
    let clip = |v: Value| match v {
        Value::Clip(c) => c,
        other => panic!("{other:?}"),
    };
    let (masks, counts, turned, elongation) =
        (clip(value("flame.mask")), clip(value("fires.count")), clip(value("pose.turned")), clip(value("lean.elongation")));
    let regions = clip(value("fires.regions"));
    let output = clip(value("pose.image"));
    let mut out = Outcome {
        crop: [x, y, width, height].map(|v| v as u32),
        output: None,
        masks: Vec::new(),
        counts: Vec::new(),
        turned: Vec::new(),
        elongation: Vec::new(),
        areas: Vec::new(),
        warnings: Vec::new(),
    };
    for i in 0..masks.len() {
        let Value::Mask(m) = masks.get(i, &ctx).unwrap() else { panic!("mask {i}") };
        let crop = GrayImage::from_raw(m.width(), m.height(), m.data().to_vec()).unwrap();
        let mut full = GrayImage::new(size.0, size.1);
        image::imageops::replace(&mut full, &crop, x, y);
        out.masks.push(full);
        out.counts.push(int(counts.get(i, &ctx).unwrap()));
        let float = |v: Value| if let Value::Float(f) = v { f } else { panic!("{v:?}") };
        out.turned.push(float(turned.get(i, &ctx).unwrap()));
        out.elongation.push(float(elongation.get(i, &ctx).unwrap()));
        let r = regions.get(i, &ctx).unwrap().downcast::<FireRegions>().unwrap();
        out.areas.push(r.regions.iter().map(|r| r.area).collect());
        if i == PICTURED {
            let Value::Image(img) = output.get(i, &ctx).unwrap() else { panic!("output {i}") };
            let bytes = img.data().iter().map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
            out.output = GrayImage::from_raw(img.width(), img.height(), bytes);
        }
    }
    out.warnings = ctx.warnings().into_iter().map(|w| w.message).collect();
    out
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn two_candles_are_both_kept_and_a_wide_fire_and_a_pair_are_left_upright_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let base = cook(&make_clip(dir.path(), "base", "null"), (854, 480));
    // The half of the frame around the candle, twice side by side: two candles 427 px apart.
    let pair = cook(&make_clip(dir.path(), "pair", "crop=427:480:213:0,split[a][b];[a][b]hstack"), (854, 480));
    // The candle stretched four times wider: one fire about as wide as it is tall.
    let wide = cook(&make_clip(dir.path(), "wide", "scale=3416:480:flags=bicubic,crop=854:480:1281:0"), (854, 480));
    let report = |name: &str, o: &Outcome| {
        eprintln!(
            "{name}: fires per frame {:?}, areas {:?}, median elongation {:.2}, turned {:?}, warnings {:?}",
            o.counts,
            o.areas,
            median(&o.elongation),
            o.turned,
            o.warnings
        )
    };
    report("base", &base);
    report("pair", &pair);
    report("wide", &wide);

    // The untouched candle: one fire, straightened as before, no new warning.
    assert!(base.counts.iter().all(|c| *c == 1), "{:?}", base.counts);
    assert!(!base.warnings.iter().any(|w| w.contains("left upright")), "{:?}", base.warnings);

    // The pair: both candles kept in every frame, each where the untouched clip's mask puts it.
    assert!(pair.counts.iter().all(|c| *c == 2), "two fires in every frame: {:?}", pair.counts);
    let mut ious = Vec::new();
    for (two, one) in pair.masks.iter().zip(&base.masks) {
        let half = image::imageops::crop_imm(one, 213, 0, 427, 480).to_image();
        let mut want = GrayImage::new(854, 480);
        image::imageops::replace(&mut want, &half, 0, 0);
        image::imageops::replace(&mut want, &half, 427, 0);
        ious.push(iou(two, &want));
    }
    let worst = ious.iter().cloned().fold(1.0, f64::min);
    eprintln!("pair: IoU against the untouched mask twice, worst {worst:.3}, median {:.3}", median(&ious));
    assert!(worst >= 0.9, "{ious:?}");
    // The crop framing one of the two: the second by rank (equal fires rank left to right).
    let right = cook_with(
        &dir.path().join("pair"),
        (854, 480),
        &[("crop", "fires", ParamValue::String("index".into())), ("crop", "index", ParamValue::Int(1))],
    );
    eprintln!("pair, crop around fire 1: box x {} width {}, fires {:?}", right.crop[0], right.crop[2], right.counts);
    assert!(right.crop[0] > 427 && right.counts.iter().all(|c| *c == 1), "{:?} {:?}", right.crop, right.counts);
    assert!(pair.crop[0] < 427 && pair.crop[0] + pair.crop[2] > 427, "all: one box around both {:?}", pair.crop);
    for (name, o, reason) in [("pair", &pair, "several separate fires"), ("wide", &wide, "as wide as it is tall")] {
        assert!(o.turned.iter().all(|t| *t == 0.0), "{name}: turned {:?}", o.turned);
        let upright: Vec<&String> = o.warnings.iter().filter(|w| w.contains("left upright")).collect();
        assert_eq!(upright.len(), 1, "{name}: {:?}", o.warnings);
        assert!(upright[0].contains(reason), "{name}: {}", upright[0]);
        assert!(!o.warnings.iter().any(|w| w.contains("max_angle")), "{name}: not turned to the limit: {:?}", o.warnings);
    }
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn the_glow_of_a_tealights_holder_is_not_taken_for_a_second_fire() {
    let dir = tempfile::tempdir().unwrap();
    // From 5 s on: the clip's first second is shaken by hand.
    let tealight = footage().join("tealight-candle/candle.mp4");
    let frames = ffmpeg_frames(dir.path(), "tea", &["-ss", "5", "-i", tealight.to_str().unwrap()], "null", FRAMES);
    let o = cook(&frames, (480, 480));
    eprintln!("tealight: fires per frame {:?}, areas {:?}, warnings {:?}", o.counts, o.areas, o.warnings);
    assert!(o.counts.iter().all(|c| *c == 1), "{:?}", o.areas);
    assert!(!o.warnings.iter().any(|w| w.contains("left upright")), "{:?}", o.warnings);
}

/// The lit room the candle is set in: a brick wall in the flame's own hues (brightness 0.2–0.45),
/// two lamps and a lit window as bright as the flame, all still. At any point, so a shaken camera
/// sees past the frame's edge.
fn room(x: f32, y: f32) -> [f32; 3] {
    let noise = (((x as i64).wrapping_mul(73_856_093) ^ (y as i64).wrapping_mul(19_349_663)).rem_euclid(1000)) as f32 / 1000.0;
    let texture = 0.32 + 0.07 * (x * 0.045).sin() * (y * 0.06).cos() + 0.05 * (x * 0.17 + y * 0.09).sin() + 0.03 * noise;
    let row = (y / 40.0).floor();
    let offset = if row.rem_euclid(2.0) == 0.0 { 0.0 } else { 40.0 };
    let mortar = y.rem_euclid(40.0) < 3.0 || (x + offset).rem_euclid(80.0) < 3.0;
    let v = if mortar { 0.6 * texture } else { texture };
    let mut c = [v, 0.72 * v, 0.5 * v];
    let mut mix = |k: f32, to: [f32; 3]| c = [0, 1, 2].map(|i| c[i] + k.clamp(0.0, 1.0) * (to[i] - c[i]));
    for (cx, cy, r) in [(150.0, 120.0, 26.0), (700.0, 345.0, 32.0)] {
        mix((r - (x - cx).hypot(y - cy)) / 6.0, [1.0, 0.8, 0.42]);
    }
    let pane = (560.0..700.0).contains(&x) && (40.0..150.0).contains(&y) && (x - 630.0).abs() > 3.0 && (y - 95.0).abs() > 3.0;
    if pane {
        mix(1.0, [1.0, 0.88, 0.55]);
    }
    c
}

/// `FRAMES` frames of the candle clip set in [`room`] (light adds: a screen blend), each seen
/// through the camera motion of its frame in `shake` (a scene point at `p` is at `shake(p)`), as
/// PNG frames in `dir/name`.
fn room_plate(dir: &Path, name: &str, shake: &[Rigid]) -> std::path::PathBuf {
    let out = dir.join(name);
    std::fs::create_dir_all(&out).unwrap();
    for (t, motion) in shake.iter().enumerate().take(FRAMES) {
        let candle = image::open(footage().join(format!("candle-black/frames/frame_{t:04}.png"))).unwrap().to_rgb32f();
        let (w, h) = candle.dimensions();
        let centre = [f64::from(w) / 2.0, f64::from(h) / 2.0];
        let undo = motion.inverse();
        let plate = image::Rgb32FImage::from_fn(w, h, |x, y| {
            let [px, py] = undo.apply([f64::from(x) + 0.5, f64::from(y) + 0.5], centre);
            let (px, py) = (px as f32 - 0.5, py as f32 - 0.5);
            let light = if px < 0.0 || py < 0.0 || px > (w - 1) as f32 || py > (h - 1) as f32 {
                [0.0; 3]
            } else {
                [0, 1, 2].map(|k| sharp_sample(&candle, px, py, k))
            };
            let wall = room(px, py);
            image::Rgb([0, 1, 2].map(|k| 1.0 - (1.0 - wall[k]) * (1.0 - light[k])))
        });
        image::DynamicImage::ImageRgb32F(plate).to_rgb8().save(out.join(format!("f_{t:04}.png"))).unwrap();
    }
    out
}

/// Channel `k` of `img` at `(x, y)` (pixel indices), Catmull-Rom: a camera that moves records a
/// sharp picture, and bilinear resampling would blur the flame's edge by up to half a pixel more
/// than any camera does (the held frames are resampled again, and the mask follows that edge).
fn sharp_sample(img: &image::Rgb32FImage, x: f32, y: f32, k: usize) -> f32 {
    let (w, h) = img.dimensions();
    let weights = |t: f32| {
        let (t2, t3) = (t * t, t * t * t);
        [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
    };
    let (x0, y0) = (x.floor(), y.floor());
    let (wx, wy) = (weights(x - x0), weights(y - y0));
    let at = |dx: i64, dy: i64| {
        let xx = (x0 as i64 + dx).clamp(0, i64::from(w) - 1) as u32;
        let yy = (y0 as i64 + dy).clamp(0, i64::from(h) - 1) as u32;
        img.get_pixel(xx, yy)[k]
    };
    let v: f32 = (0..4).map(|j| wy[j] * (0..4).map(|i| wx[i] * at(i as i64 - 1, j as i64 - 1)).sum::<f32>()).sum();
    // Within the four nearest pixels, as a lens's picture has no ringing.
    let near = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
    v.clamp(near.iter().cloned().fold(f32::MAX, f32::min), near.iter().cloned().fold(f32::MIN, f32::max))
}

/// A handheld camera's shake: frame 0 as filmed, then a random turn up to ±1.5° and shift up to
/// ±8 px about it per frame (a fixed seed).
fn shake() -> Vec<Rigid> {
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % 20_001) as f64 / 10_000.0 - 1.0
    };
    (0..FRAMES)
        .map(|t| {
            if t == 0 {
                Rigid::default()
            } else {
                Rigid { angle: 1.5f64.to_radians() * next(), shift: [8.0 * next(), 8.0 * next()] }
            }
        })
        .collect()
}

#[test]
#[ignore = "needs footage: set PYROGRAPH_FOOTAGE or run from CI"]
fn a_candle_in_a_lit_room_is_masked_as_on_black_even_from_a_shaken_camera() {
    let dir = tempfile::tempdir().unwrap();
    let base = cook(&make_clip(dir.path(), "base", "null"), (854, 480));
    let still = vec![Rigid::default(); FRAMES];
    let lit = cook(&room_plate(dir.path(), "lit", &still), (854, 480));
    let shaken = cook(&room_plate(dir.path(), "shaken", &shake()), (854, 480));
    for (name, o) in [("lit", &lit), ("shaken", &shaken)] {
        let ious: Vec<f64> = o.masks.iter().zip(&base.masks).map(|(m, b)| iou(m, b)).collect();
        let worst = ious.iter().cloned().fold(1.0, f64::min);
        eprintln!(
            "{name}: IoU against the candle on black, worst {worst:.4}, median {:.4}; fires {:?}; warnings {:?}",
            median(&ious),
            o.counts,
            o.warnings
        );
        // Light adds: over the wall the flame's edge pixels are brighter than over black, and the
        // mask is a pixel wider all round (its area 10 % larger); held frames are resampled once.
        assert!(worst >= 0.9, "{name}: {ious:?}");
        assert!(o.counts.iter().all(|c| *c == 1), "{name}: the lamps and the window are not fires: {:?}", o.areas);
    }
    if std::env::var_os("REGENERATE").is_some() {
        let plate = image::open(dir.path().join(format!("lit/f_{PICTURED:04}.png"))).unwrap().to_rgb8();
        let picture = scene_picture(&plate, &lit);
        picture.save(workspace().join("docs/images/scene-plate-room.png")).unwrap();
    }
}

/// The README's picture of a scene plate: the plate with the crop box drawn on it, the mask in
/// the box, and the output, side by side at the plate's half height.
fn scene_picture(plate: &image::RgbImage, o: &Outcome) -> image::RgbImage {
    use image::imageops::{FilterType, resize};
    let [x, y, w, h] = o.crop;
    let mut boxed = plate.clone();
    let orange = image::Rgb([255, 150, 40]);
    for t in 0..3 {
        let rect = imageproc::rect::Rect::at((x + t) as i32, (y + t) as i32).of_size(w - 2 * t, h - 2 * t);
        imageproc::drawing::draw_hollow_rect_mut(&mut boxed, rect, orange);
    }
    let height = plate.height() / 2;
    let fit = |img: &image::RgbImage| {
        let width = (img.width() * height).div_ceil(img.height());
        resize(img, width, height, FilterType::Triangle)
    };
    let mask = image::imageops::crop_imm(&o.masks[PICTURED], x, y, w, h).to_image();
    let gray = |g: &GrayImage| image::DynamicImage::ImageLuma8(g.clone()).to_rgb8();
    let panels = [fit(&boxed), fit(&gray(&mask)), fit(&gray(o.output.as_ref().expect("the pictured frame")))];
    let gap = 8;
    let width = panels.iter().map(|p| p.width()).sum::<u32>() + gap * (panels.len() as u32 - 1);
    let mut out = image::RgbImage::from_pixel(width, height, image::Rgb([24, 24, 24]));
    let mut left = 0;
    for p in &panels {
        image::imageops::replace(&mut out, p, i64::from(left), 0);
        left += p.width() + gap;
    }
    out
}
