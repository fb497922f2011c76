//! Learning flames §3: fitting the generic flame model to the 150 candle-black frames, and
//! rendering 480×480 frames from parameter rows (gray, then the colour ramp). Target ≥ 200
//! rendered frames/s.

mod common;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pyrograph_nodes_flame_model::model::{FitSettings, RenderSettings, fit_gray_frames, render_frame};

fn model(c: &mut Criterion) {
    let Some((frames, size)) = common::candle_frames() else { return };
    let s = FitSettings::default();
    let mut group = c.benchmark_group("flame_model");
    group.sample_size(10);
    group.throughput(Throughput::Elements(frames.len() as u64));
    group.bench_function("fit_candle_150", |b| b.iter(|| fit_gray_frames(black_box(&frames), size, &s, 29.97).unwrap()));
    let fit = fit_gray_frames(&frames, size, &s, 29.97).unwrap();
    let settings = RenderSettings { size: (480, 480), ..RenderSettings::default() };
    const FRAMES: usize = 30;
    group.throughput(Throughput::Elements(FRAMES as u64));
    group.bench_function("render_480x480_x30", |b| {
        b.iter(|| {
            for r in 0..FRAMES {
                black_box(render_frame(&fit.model, fit.params.row(r).unwrap(), &settings, r).unwrap());
            }
        })
    });
    group.finish();
}

criterion_group!(benches, model);
criterion_main!(benches);
