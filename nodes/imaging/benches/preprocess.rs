//! The per-frame Eigenfires pre-processing chain of the OpenCV peer (`peers/hsv_contour.py`):
//! RGB→HSV with three ranges OR-ed, open + close with a 5×5 ellipse, contour tracing, dropping
//! contours under 100 px², Douglas–Peucker 2.0 and a line fit on the largest contour.
//! Criterion reports the time per frame on synthetic 1280×720 and 480×480 flames.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pyrograph_core::{Channels, Image};
use pyrograph_nodes_imaging::preprocess::contours::{remove_holes, simplify_closed, trace_contours};
use pyrograph_nodes_imaging::preprocess::hsv::{Blend, HsvLayer, HsvRange, hsv_mask};
use pyrograph_nodes_imaging::preprocess::morphology::{KernelShape, MorphOp, morphology, structuring_element};
use pyrograph_nodes_imaging::preprocess::pose::{Weighting, flame_axis, main_contour};
use std::hint::black_box;

/// Deterministic xorshift so frames are reproducible without a random-number crate.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
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
fn process(frame: &Image, layers: &[HsvLayer], element: &imageproc::morphology::Mask) -> (usize, usize, usize, f64) {
    let mask = hsv_mask(frame, layers).expect("RGBA frame");
    let mask = morphology(&morphology(&mask, MorphOp::Open, element), MorphOp::Close, element);
    // The peer traces the whole tree (RETR_TREE) and only drops small areas.
    let kept = remove_holes(&trace_contours(&mask), u32::MAX, 100.0);
    let Some(largest) = main_contour(&kept) else { return (0, 0, 0, 0.0) };
    let poly = simplify_closed(&largest.points, 2.0);
    let angle = flame_axis(largest, Weighting::Uniform).map_or(0.0, |a| a.angle_deg);
    (kept.contours.len(), poly.len(), largest.points.len(), angle)
}

fn bench_chain(c: &mut Criterion) {
    let element = structuring_element(KernelShape::Ellipse, 5).expect("odd size");
    let layers = layers();
    let mut group = c.benchmark_group("hsv_contour_per_frame");
    group.sample_size(20);
    for (w, h) in [(1280, 720), (480, 480)] {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ u64::from(w));
        let frames: Vec<Image> = (0..4).map(|_| flame_frame(&mut rng, w, h)).collect();
        group.throughput(Throughput::Elements(1));
        group.bench_with_input(BenchmarkId::from_parameter(format!("{w}x{h}")), &frames, |b, frames| {
            let mut i = 0;
            b.iter(|| {
                i = (i + 1) % frames.len();
                black_box(process(black_box(&frames[i]), &layers, &element))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_chain);
criterion_main!(benches);
