//! The per-frame Eigenfires pre-processing chain of the OpenCV peer (`peers/hsv_contour.py`):
//! RGB→HSV with three ranges OR-ed, open + close with a 5×5 ellipse, contour tracing, dropping
//! contours under 100 px², Douglas–Peucker 2.0 and a line fit on the largest contour.
//! Criterion reports the time per frame on synthetic 1280×720 and 480×480 flames.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pyrograph_core::{Channels, Image};
use pyrograph_nodes_imaging::preprocess::contours::{remove_holes, simplify_closed, trace_contours};
use pyrograph_nodes_imaging::preprocess::hsv::{Blend, HsvLayer, HsvRange, hsv_mask, rgb_to_hsv};
use pyrograph_nodes_imaging::preprocess::morphology::{Element, KernelShape, MorphOp, morphology, structuring_element};
use pyrograph_nodes_imaging::preprocess::pose::{Weighting, flame_axis, main_contour};
use pyrograph_testing::XorShift;
use std::hint::black_box;

/// The shared xorshift, so frames are reproducible without a random-number crate.
struct Rng(XorShift);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0.next_f32()
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

/// Like the peer's `flame_frame`: a few tilted Gaussian flames (red body, yellow core, blue base)
/// painted over a dark background, plus noise.
fn flame_frame(rng: &mut Rng, w: u32, h: u32) -> Image {
    let (wf, hf) = (w as f32, h as f32);
    let background = rng.range(5.0, 20.0) / 255.0;
    let mut data = vec![background; w as usize * h as usize * 4];
    let palette = [([230.0, 40.0, 10.0], 1.0, 0.0), ([255.0, 220.0, 30.0], 0.55, 0.08), ([40.0, 90.0, 255.0], 0.35, 0.20)];
    for _ in 0..4 {
        let (cx, cy) = (rng.range(0.15, 0.85) * wf, rng.range(0.35, 0.75) * hf);
        let (sx, sy) = (rng.range(0.02, 0.06) * wf, rng.range(0.08, 0.20) * hf);
        let (s, c) = rng.range(-0.3, 0.3).sin_cos();
        for (rgb, k, dy) in palette {
            for (i, px) in data.chunks_exact_mut(4).enumerate() {
                let (x, y) = ((i % w as usize) as f32 - cx, (i / w as usize) as f32 - (cy + dy * hf));
                let (u, v) = (x * c + y * s, -x * s + y * c);
                let g = (-0.5 * ((u / (k * sx)).powi(2) + (v / (k * sy)).powi(2))).exp();
                for (ch, &col) in px.iter_mut().zip(&rgb) {
                    *ch = *ch * (1.0 - g) + g * col / 255.0;
                }
            }
        }
    }
    for px in data.chunks_exact_mut(4) {
        for ch in px.iter_mut().take(3) {
            *ch = (*ch + (rng.next() - 0.5) * 12.0 / 255.0).clamp(0.0, 1.0);
        }
        px[3] = 1.0;
    }
    Image::from_vec(w, h, Channels::Rgba, data).expect("frame size")
}

/// The peer's ranges (OpenCV half-hues ×2), all OR-ed.
fn layers() -> Vec<HsvLayer> {
    let range = |h_min, h_max, s_min, v_min| HsvRange { h_min, h_max, s_min, s_max: 255.0, v_min, v_max: 255.0 };
    [range(200.0, 260.0, 80.0, 60.0), range(0.0, 30.0, 100.0, 80.0), range(30.0, 70.0, 80.0, 100.0)]
        .into_iter()
        .map(|range| HsvLayer { range, blend: Blend::Add })
        .collect()
}

/// One frame of the chain; returns the numbers the peer reports (kept contours, polygon and
/// contour sizes, line angle) so nothing is optimized away.
fn process(frame: &Image, layers: &[HsvLayer], element: &Element) -> (usize, usize, usize, f64) {
    let mask = hsv_mask(frame, layers).expect("RGBA frame");
    let mask = morphology(&morphology(&mask, MorphOp::Open, element), MorphOp::Close, element);
    // The peer traces the whole tree (RETR_TREE) and only drops small areas.
    let kept = remove_holes(&trace_contours(&mask), u32::MAX, 100.0);
    let Some(largest) = main_contour(&kept) else { return (0, 0, 0, 0.0) };
    let poly = simplify_closed(&largest.points, 2.0);
    let angle = flame_axis(largest, Weighting::Uniform).map_or(0.0, |a| a.angle_deg);
    (kept.contours.len(), poly.len(), largest.points.len(), angle)
}

/// Checks once, before timing, that the fast stages give exactly what the definitions give on the
/// bench frames: the per-pixel HSV fold, imageproc's grayscale morphology and `find_contours`.
fn check_against_reference(frame: &Image, layers: &[HsvLayer], element: &Element) {
    use imageproc::morphology::{grayscale_dilate, grayscale_erode};
    let mask = hsv_mask(frame, layers).expect("RGBA frame");
    let want: Vec<u8> = frame
        .data()
        .chunks_exact(4)
        .map(|px| {
            let hsv = rgb_to_hsv(px[0], px[1], px[2]);
            if layers.iter().fold(false, |acc, l| l.blend.apply(acc, l.range.contains(hsv))) { 255 } else { 0 }
        })
        .collect();
    assert!(mask.data() == want.as_slice(), "hsv_mask differs from the per-pixel definition");
    let (w, h) = (mask.width(), mask.height());
    let gray = image::GrayImage::from_raw(w, h, mask.data().to_vec()).expect("mask size");
    let e = element.to_imageproc();
    let reference = grayscale_erode(&grayscale_dilate(&grayscale_dilate(&grayscale_erode(&gray, &e), &e), &e), &e);
    let closed = morphology(&morphology(&mask, MorphOp::Open, element), MorphOp::Close, element);
    assert!(closed.data() == reference.as_raw().as_slice(), "open + close differs from imageproc");
    let traced = trace_contours(&closed);
    let reference = imageproc::contours::find_contours::<i32>(&reference);
    assert_eq!(traced.contours.len(), reference.len(), "contour count differs from imageproc");
    for (c, r) in traced.contours.iter().zip(&reference) {
        let pts: Vec<[f32; 2]> = r.points.iter().map(|p| [p.x as f32, p.y as f32]).collect();
        assert!(c.points == pts && c.parent == r.parent, "a contour differs from imageproc's");
        assert_eq!(c.area, imageproc::geometry::contour_area(&r.points));
    }
}

fn bench_chain(c: &mut Criterion) {
    let element = structuring_element(KernelShape::Ellipse, 5).expect("odd size");
    let layers = layers();
    let mut group = c.benchmark_group("hsv_contour_per_frame");
    group.sample_size(20);
    for (w, h) in [(1280, 720), (480, 480)] {
        let mut rng = Rng(XorShift(0x9E37_79B9_7F4A_7C15 ^ u64::from(w)));
        let frames: Vec<Image> = (0..4).map(|_| flame_frame(&mut rng, w, h)).collect();
        for frame in &frames {
            check_against_reference(frame, &layers, &element);
        }
        group.throughput(Throughput::Elements(1));
        group.bench_with_input(BenchmarkId::from_parameter(format!("{w}x{h}")), &frames, |b, frames| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) % frames.len();
                black_box(process(black_box(&frames[i]), &layers, &element))
            })
        });
    }
    if let Some(frames) = tealight_frames(100) {
        group.bench_with_input(BenchmarkId::from_parameter("tealight_480x480"), &frames, |b, frames| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) % frames.len();
                black_box(process(black_box(&frames[i]), &layers, &element))
            })
        });
    }
    group.finish();
}

/// The first `count` frames of the real tealight clip (`tealight-candle/candle.mp4` under
/// [`pyrograph_testing::footage`]), decoded through `imaging.load_sequence`'s loader; `None`
/// (the case is skipped, with a note) when the footage or ffmpeg is missing.
fn tealight_frames(count: usize) -> Option<Vec<Image>> {
    let root = pyrograph_testing::footage();
    let ctx = pyrograph_core::CookCtx::new();
    let clip = match pyrograph_nodes_imaging::io::LoadSequence::load(&root.join("tealight-candle/candle.mp4"), 0.0, &ctx) {
        Ok(clip) => clip,
        Err(e) => {
            eprintln!("skipping the tealight case: {e}");
            return None;
        }
    };
    (0..count.min(clip.len())).map(|i| clip.image(i, &ctx).ok().map(|img| (*img).clone())).collect()
}

/// Each stage of [`process`] on its own, fed with the previous stage's real output, so a
/// regression (or the hot spot) shows up by name.
fn bench_stages(c: &mut Criterion) {
    let element = structuring_element(KernelShape::Ellipse, 5).expect("odd size");
    let layers = layers();
    let mut group = c.benchmark_group("hsv_contour_stages");
    group.sample_size(20);
    for (w, h) in [(1280, 720), (480, 480)] {
        let mut rng = Rng(XorShift(0x9E37_79B9_7F4A_7C15 ^ u64::from(w)));
        let frame = flame_frame(&mut rng, w, h);
        let raw = hsv_mask(&frame, &layers).expect("RGBA frame");
        let opened = morphology(&raw, MorphOp::Open, &element);
        let closed = morphology(&opened, MorphOp::Close, &element);
        let traced = trace_contours(&closed);
        let size = format!("{w}x{h}");
        group.bench_with_input(BenchmarkId::new("hsv_mask", &size), &frame, |b, f| b.iter(|| hsv_mask(black_box(f), &layers)));
        group.bench_with_input(BenchmarkId::new("open", &size), &raw, |b, m| {
            b.iter(|| morphology(black_box(m), MorphOp::Open, &element))
        });
        group.bench_with_input(BenchmarkId::new("close", &size), &opened, |b, m| {
            b.iter(|| morphology(black_box(m), MorphOp::Close, &element))
        });
        group
            .bench_with_input(BenchmarkId::new("trace_contours", &size), &closed, |b, m| b.iter(|| trace_contours(black_box(m))));
        group.bench_with_input(BenchmarkId::new("filter_simplify_fit", &size), &traced, |b, t| {
            b.iter(|| {
                let kept = remove_holes(black_box(t), u32::MAX, 100.0);
                let Some(largest) = main_contour(&kept) else { return (0, 0, 0.0) };
                let poly = simplify_closed(&largest.points, 2.0);
                let angle = flame_axis(largest, Weighting::Uniform).map_or(0.0, |a| a.angle_deg);
                (kept.contours.len(), poly.len(), angle)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_chain, bench_stages);
criterion_main!(benches);
