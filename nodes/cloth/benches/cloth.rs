//! Mass-spring flame benchmarks (mass-spring flame project 2019 §Results, Tables 1–4): simulation
//! sub-steps per second for the project's flame counts and beyond (the numpy peer's structural
//! model, like for like, and the node's default cloth with shear and bend springs), and simulate +
//! render frames per second at 1280×720 for the same counts.

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
        buoyancy: 0.5.into(),
        wind: [0.3, 0.0, 0.0].into(),
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

/// A 1280×720 view that frames a grid of `n` flames: the 144-flame camera of
/// `graphs/mass-spring-144.ron` (12 columns), moved back in proportion to the grid's width, and no
/// closer than for 3 columns (one flame would otherwise fill the frame).
fn framing(n: usize) -> Option<View> {
    let cols = (n as f32).sqrt().ceil().max(3.0);
    let s = cols / 12.0;
    let target = Vec3::new(0.0, 1.0, 0.0);
    let cam = Camera::new(target + Vec3::new(0.0, 8.0, 26.0) * s, target, Vec3::Y, 40.0, 0.1, 1000.0).ok()?;
    View::new(cam, 1280, 720).ok()
}

/// One frame per call: every sub-step of a 24 fps frame (25 of 1/600 s for the node's default
/// cloth), then the textured render at 1280×720, for the project's sweep of flame counts.
fn frame_group(c: &mut Criterion, name: &str, params: &ClothParams, counts: &[usize]) {
    let mut g = c.benchmark_group("cloth_frame_1280x720");
    g.sample_size(10);
    let rp = RenderParams::default();
    for &n in counts {
        let (Some(view), Ok(mut sim)) = (framing(n), Simulation::new(params, &grid_roots(n, 1.5))) else { continue };
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

fn simulate_and_render(c: &mut Criterion) {
    // The node's default cloth (structural + shear + bend springs) over the sweep, and at 144
    // flames the same cloth with the project's springs only (horizontal and vertical,
    // §Internal Forces).
    frame_group(c, "simulate_render", &ClothParams::default(), &COUNTS);
    let structural = ClothParams { shear: false, bend: false, ..ClothParams::default() };
    frame_group(c, "simulate_render_structural", &structural, &[144]);
}

criterion_group!(benches, simulation_steps, simulate_and_render);
criterion_main!(benches);
