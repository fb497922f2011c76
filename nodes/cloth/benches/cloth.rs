//! Mass-spring flame benchmarks (mass-spring flame project 2019 §Results, Tables 1–4): simulation
//! sub-steps per second for the project's flame counts and beyond, and simulate + render frames
//! per second at 1280×720 for 144 flames.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pyrograph_nodes_cloth::render::{RenderParams, Textures, render_cloth};
use pyrograph_nodes_cloth::sim::{ClothParams, Simulation, grid_roots};
use pyrograph_render::{Camera, View};

const COUNTS: [usize; 14] = [1, 4, 9, 16, 25, 36, 49, 64, 81, 100, 121, 144, 1024, 10000];

fn simulation_steps(c: &mut Criterion) {
    let mut g = c.benchmark_group("cloth_substep");
    g.sample_size(10);
    let p = ClothParams::default();
    for n in COUNTS {
        let Ok(mut sim) = Simulation::new(&p, &grid_roots(n, 1.5)) else { continue };
        let (_, h) = sim.substeps();
        // One sub-step of every flame; throughput counts steps (one per call).
        g.throughput(Throughput::Elements(1));
        g.bench_with_input(BenchmarkId::new("flames", n), &n, |b, _| b.iter(|| sim.substep(h, 1)));
    }
    g.finish();
}

fn simulate_and_render(c: &mut Criterion) {
    let mut g = c.benchmark_group("cloth_frame_1280x720");
    g.sample_size(10);
    let n = 144;
    let Ok(mut sim) = Simulation::new(&ClothParams::default(), &grid_roots(n, 1.5)) else { return };
    let Ok(cam) = Camera::new(Vec3::new(0.0, 9.0, 26.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 0.1, 1000.0) else { return };
    let Ok(view) = View::new(cam, 1280, 720) else { return };
    let rp = RenderParams::default();
    g.throughput(Throughput::Elements(1));
    g.bench_function(BenchmarkId::new("simulate_render", n), |b| {
        b.iter(|| {
            let _ = sim.step_frame();
            render_cloth(&view, &sim.snapshot(), Textures::Builtin, &rp)
        })
    });
    g.finish();
}

criterion_group!(benches, simulation_steps, simulate_and_render);
criterion_main!(benches);
