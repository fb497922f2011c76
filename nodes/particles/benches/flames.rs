//! Perry particle flames: simulate + render one frame at 1280×720 for 1 … 10,000 flames
//! (25 steps, 20 triangles each). Target: ≥ 30 frames/s at 1,000 flames on 2 cores.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pyrograph_nodes_particles::flame::{FlameParams, Layout, Root, layout_roots, simulate_frame};
use pyrograph_nodes_particles::render::render_particles;
use pyrograph_nodes_particles::swept::Exposure;
use pyrograph_nodes_particles::types::WindField;
use pyrograph_render::Particles;
use pyrograph_render::{Blend, Camera, View};

/// Flames on a square grid filling the view (flame size shrinks as the count grows, like a
/// fire seen from further away), camera framing the grid.
fn scene(n: usize) -> (Vec<Root>, FlameParams, View) {
    let cols = (n as f32).sqrt().ceil();
    let spacing = 2.0;
    let roots = layout_roots(Layout::Grid, n, Vec3::ZERO, spacing, 0.0, Vec3::Y, 0.0, 1);
    let extent = cols * spacing;
    let cam = Camera::new(
        Vec3::new(0.0, extent * 0.45 + 3.0, extent * 0.9 + 10.0),
        Vec3::new(0.0, 2.5, 0.0),
        Vec3::Y,
        40.0,
        0.1,
        10_000.0,
    )
    .expect("valid camera");
    let view = View::new(cam, 1280, 720).expect("valid view");
    (roots, FlameParams::default(), view)
}

fn flames(c: &mut Criterion) {
    let mut group = c.benchmark_group("flames_1280x720");
    group.sample_size(10);
    let wind = WindField::default();
    for n in [1usize, 10, 100, 1_000, 10_000] {
        let (roots, params, view) = scene(n);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("simulate", n), &n, |b, _| {
            b.iter(|| black_box(simulate_frame(&roots, &wind, &params, 7).expect("simulates")))
        });
        let frame = simulate_frame(&roots, &wind, &params, 7).expect("simulates");
        group.bench_with_input(BenchmarkId::new("render", n), &n, |b, _| {
            b.iter(|| {
                black_box(render_particles(
                    &view,
                    &frame,
                    Exposure::Continuous,
                    Blend::Additive,
                    [0.0, 0.0, 0.0, 1.0],
                    None,
                    &Particles::default(),
                ))
            })
        });
        group.bench_with_input(BenchmarkId::new("simulate+render", n), &n, |b, _| {
            b.iter(|| {
                let frame = simulate_frame(&roots, &wind, &params, 7).expect("simulates");
                black_box(render_particles(
                    &view,
                    &frame,
                    Exposure::Continuous,
                    Blend::Additive,
                    [0.0, 0.0, 0.0, 1.0],
                    None,
                    &Particles::default(),
                ))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, flames);
criterion_main!(benches);
