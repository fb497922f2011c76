//! Bloom of the OpenCV peer (`peers/bloom.py`): `max(src, 0.4 Σ GaussianBlur(src, σ))` for
//! σ = 32, 16, 8, 4 on a 1280×720 RGB frame (Eigenfires thesis §6.2). Criterion reports the time
//! per frame of `imaging.bloom`'s function and of the fast blur alone.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pyrograph_core::{Channels, Image};
use pyrograph_nodes_imaging::bloom::{BloomParams, bloom};
use pyrograph_nodes_imaging::filters::{Plane, gaussian_sum};
use std::hint::black_box;

/// A synthetic flame frame: a few soft bright blobs (red body, yellow core) on a dark background.
fn flame_frame(w: u32, h: u32) -> Image {
    let blobs = [(0.3f32, 0.6f32, 60.0f32), (0.55, 0.5, 90.0), (0.75, 0.65, 40.0)];
    let data = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .flat_map(|(x, y)| {
            let v: f32 = blobs
                .iter()
                .map(|&(cx, cy, r)| {
                    let (dx, dy) = (x as f32 - cx * w as f32, (y as f32 - cy * h as f32) * 0.6);
                    (-(dx * dx + dy * dy) / (2.0 * r * r)).exp()
                })
                .sum::<f32>()
                .min(1.0);
            [v, v * v * 0.8, v.powi(4) * 0.5, 1.0]
        })
        .collect();
    Image::from_vec(w, h, Channels::Rgba, data).unwrap_or_else(|| Image::new(w, h, Channels::Rgba))
}

fn bench_bloom(c: &mut Criterion) {
    let (w, h) = (1280, 720);
    let frame = flame_frame(w, h);
    let params = BloomParams { passes: 4, sigma: 32.0, shrink: 0.5, strength: 0.4, ..BloomParams::default() };
    let mut g = c.benchmark_group("bloom");
    g.throughput(Throughput::Elements(u64::from(w * h)));
    g.bench_function("rgb_1280x720_4pass_32_16_8_4", |b| b.iter(|| bloom(black_box(&frame), black_box(&params))));
    let plane = Plane { width: w as usize, height: h as usize, data: frame.data().iter().step_by(4).copied().collect() };
    g.bench_function("gaussian_sum_one_plane_1280x720", |b| {
        b.iter(|| gaussian_sum(black_box(&plane), black_box(&[32.0, 16.0, 8.0, 4.0]), 0.4))
    });
    g.finish();
}

criterion_group!(benches, bench_bloom);
criterion_main!(benches);
