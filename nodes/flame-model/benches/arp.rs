//! Learning flames §4: EM learning of the K = 2 ARP on the 26 parameters of the 150 real
//! candle-black frames (target ≤ 2 s; the paper's Matlab took 30 min), and sampling (target
//! ≥ 1,000,000 steps/s). Peer: ../shared/peers/ar_fit.py (statsmodels OLS VAR(2) fit, numpy
//! sampling).

mod common;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pyrograph_core::CookCtx;
use pyrograph_nodes_flame_model::arp::{ArSampler, LearnOptions, learn};
use pyrograph_nodes_flame_model::model::{FitSettings, fit_gray_frames};

fn arp(c: &mut Criterion) {
    let Some((frames, size)) = common::candle_frames() else { return };
    let fit = fit_gray_frames(&frames, size, &FitSettings::default(), 29.97).expect("candle fits");
    let series = fit.params;
    eprintln!("series: {} frames x {} parameters", series.frames, series.dim());
    let opts = LearnOptions::default();
    let mut group = c.benchmark_group("arp");
    group.sample_size(10);
    group.bench_function("learn_candle_150x26_k2", |b| b.iter(|| learn(black_box(&series), &opts, &CookCtx::new()).unwrap()));
    let model = learn(&series, &opts, &CookCtx::new()).unwrap();
    eprintln!("EM iterations: {}", model.log_likelihood.len());
    const STEPS: usize = 100_000;
    group.throughput(Throughput::Elements(STEPS as u64));
    group.bench_function("sample_100k_steps", |b| {
        let mut s = ArSampler::new(&model, 7).unwrap();
        let mut row = vec![0.0; s.dim()];
        b.iter(|| {
            for _ in 0..STEPS {
                s.step(&mut row);
            }
            black_box(&row);
        })
    });
    group.finish();
}

criterion_group!(benches, arp);
criterion_main!(benches);
