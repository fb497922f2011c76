//! Mass-spring flame benchmarks (mass-spring flame project 2019 §Results, Tables 1–4): simulation
//! sub-steps per second for the project's flame counts and beyond (the numpy peer's structural
//! model, like for like, and the node's default cloth with shear and bend springs), and simulate + render frames
//! per second at 1280×720 for 144 flames.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pyrograph_nodes_cloth::render::{RenderParams, Textures, render_cloth};
use pyrograph_nodes_cloth::sim::{ClothParams, Simulation, grid_roots};
use pyrograph_render::{Camera, View};

const COUNTS: [usize; 14] = [1, 4, 9, 16, 25, 36, 49, 64, 81, 100, 121, 144, 1024, 10000];

/// The Python peer's model (shared/peers/mass_spring.py), for a like-for-like comparison:
/// 16 × 32 masses per flame, structural (horizontal + vertical) springs only, spacing 0.02,
/// mass 1, k 2000, spring damping 2, drag 0.5, buoyancy 0.5, wind 0.3 across, one step of
/// 1/120 s. (Ours moves in 3-D, the peer in 2-D, so ours carries 1.5× the state.)
fn peer_structural() -> ClothParams {
    ClothParams {
        grid_width: 16,
        grid_height: 32,
        flame_width: 15.0 * 0.02,
        flame_height: 31.0 * 0.02,
        mass: 1.0,
        stiffness: 2000.0,
        damping: 2.0,
        shear: false,
        bend: false,
        drag: 0.5,
        buoyancy: 0.5,
        wind: Vec3::new(0.3, 0.0, 0.0),
        dt: 1.0 / 120.0,
        fps: 24.0,
        ..ClothParams::default()
    }
}

/// One sub-step of every flame per call (throughput counts steps), for each flame count.
fn substep_group(c: &mut Criterion, name: &str, p: &ClothParams, counts: &[usize], steps: usize) {
    let mut g = c.benchmark_group(name);
    g.sample_size(10);
    for &n in counts {
        let Ok(mut sim) = Simulation::new(p, &grid_roots(n, 1.5)) else { continue };
        let (_, h) = sim.substeps();
        g.throughput(Throughput::Elements(steps as u64));
        g.bench_with_input(BenchmarkId::new("flames", n), &n, |b, _| b.iter(|| sim.substep(h, steps)));
    }
    g.finish();
}

fn simulation_steps(c: &mut Criterion) {
    // Like for like with the numpy peer: structural springs only, one step per call.
    substep_group(c, "cloth_substep_structural", &peer_structural(), &COUNTS, 1);
    // The same, a 24 fps frame's 5 sub-steps per call (each flame stays in cache for all five).
    substep_group(c, "cloth_substep_structural_x5", &peer_structural(), &[144, 1024, 10000], 5);
    // The node's default cloth: structural + shear + bend springs, dt 1/600.
    substep_group(c, "cloth_substep", &ClothParams::default(), &COUNTS, 1);
}

fn simulate_and_render(c: &mut Criterion) {
    let mut g = c.benchmark_group("cloth_frame_1280x720");
    g.sample_size(10);
    let n = 144;
    let Ok(cam) = Camera::new(Vec3::new(0.0, 9.0, 26.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 0.1, 1000.0) else { return };
    let Ok(view) = View::new(cam, 1280, 720) else { return };
    let rp = RenderParams::default();
    // The node's default cloth (structural + shear + bend springs), and the same cloth with the
    // project's springs only (horizontal and vertical, §Internal Forces).
    let structural = ClothParams { shear: false, bend: false, ..ClothParams::default() };
    for (name, params) in [("simulate_render", ClothParams::default()), ("simulate_render_structural", structural)] {
        let Ok(mut sim) = Simulation::new(&params, &grid_roots(n, 1.5)) else { continue };
        g.throughput(Throughput::Elements(1));
        g.bench_function(BenchmarkId::new(name, n), |b| {
            b.iter(|| {
                let _ = sim.step_frame();
                render_cloth(&view, &sim.snapshot(), Textures::Builtin, &rp)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, simulation_steps, simulate_and_render);
criterion_main!(benches);
