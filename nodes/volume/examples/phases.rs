//! Times each phase of a campfire-like simulation's sub-steps (emit, advect, burn, forces,
//! project) and prints the active voxels, the solver's iterations and the divergence per frame.
//!
//!     cargo run --release -p pyrograph-nodes-volume --example phases -- [frames] [voxel_size]
//!     cargo run --release -p pyrograph-nodes-volume --example phases -- dense N [steps]
//!
//! `dense N` fills an N³ box of voxels with warm smoke (every brick active) and times its steps:
//! the memory of a dense domain of that size. Each run ends with the process's peak resident
//! memory (VmHWM).

use std::sync::Arc;
use std::time::{Duration, Instant};

use pyrograph_core::CookCtx;
use pyrograph_core::declare::Anim;
use pyrograph_nodes_volume::sim::collide::Solids;
use pyrograph_nodes_volume::sim::forces::{self, Forces, Turbulence};
use pyrograph_nodes_volume::sim::step::{Setup, brick_bounds, next_topology, substeps};
use pyrograph_nodes_volume::sim::{SimParams, SimState, advect, combust, emit, pressure};
use pyrograph_nodes_volume::source::{Emitter, Geometry, Rates, TimedPoint, VolumeSource};

fn peak_rss_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok());
    kb.unwrap_or(0.0) / 1024.0
}

/// Steps a dense N³ box of warm smoke `steps` times.
fn dense(n: i32, steps: usize) {
    use glam::IVec3;
    use pyrograph_nodes_volume::grid::Topology;
    let bricks = n / 8;
    let top = Topology::new(
        (0..bricks * bricks * bricks).map(|k| IVec3::new(k % bricks, (k / bricks) % bricks, k / (bricks * bricks))).collect(),
    );
    let h = 1.0 / n as f32;
    let mut state = SimState::new(h);
    let voxels = top.voxels();
    state.top = Arc::new(top);
    state.scalars = std::array::from_fn(|k| vec![if k < 2 { 0.5 } else { 0.0 }; voxels]);
    state.vel = std::array::from_fn(|_| vec![0.0; voxels]);
    state.pressure = vec![0.0; voxels];
    let p = SimParams { voxel_size: h, turbulence: Anim::constant(1.0), cutoff: 0.0, ..SimParams::default() };
    let setup = Setup {
        solids: Solids::default(),
        turbulence: Turbulence::new(0, 0.25, 0.5),
        bounds: (IVec3::ZERO, IVec3::splat(bricks - 1)),
        cutoff: -1.0,
        tolerance: p.tolerance,
        max_iterations: p.max_iterations,
        max_voxels: 1 << 30,
    };
    let sp = p.at(0.0, 24.0).unwrap();
    let t = Instant::now();
    for _ in 0..steps {
        let pr = pyrograph_nodes_volume::sim::step::substep(&mut state, &setup, &sp, &[], None, 1.0 / 96.0).unwrap();
        println!("{} voxels, {} iterations, divergence {:.1e}", state.top.voxels(), pr.iterations, pr.max_divergence);
    }
    println!(
        "dense {n}³: {:.0} ms per step, peak memory {:.0} MiB ({} threads)",
        t.elapsed().as_secs_f64() * 1e3 / steps as f64,
        peak_rss_mib(),
        rayon::current_num_threads()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("dense") {
        let n = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(128);
        return dense(n, args.get(3).and_then(|a| a.parse().ok()).unwrap_or(3));
    }
    let frames: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(48);
    let h: f32 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(0.06);
    // Sixty points on a 1.2-unit disc a little above the floor, as flame roots on a log pile.
    let points: Vec<TimedPoint> = (0..60)
        .map(|k| {
            let a = k as f32 * 2.399_963;
            let r = 0.9 * ((k as f32 + 0.5) / 60.0).sqrt();
            TimedPoint {
                position: [r * a.cos(), 0.25 + 0.1 * (k % 3) as f32, r * a.sin()],
                velocity: [0.0, 1.0, 0.0],
                start: 0.0,
            }
        })
        .collect();
    let rates = Rates {
        fuel: Anim::constant(3.0),
        smoke: Anim::constant(0.0),
        temperature: Anim::constant(1.0),
        velocity: Anim::constant([0.0, 0.6, 0.0]),
        radius: Anim::constant(0.16),
        inherit: 0.0,
    };
    let source = Arc::new(VolumeSource {
        emitters: vec![Emitter { label: "roots".into(), geometry: Geometry::Points(Arc::new(points)), rates }],
    });
    let p = SimParams {
        voxel_size: h,
        ground: true,
        buoyancy: Anim::constant(3.0),
        smoke_yield: Anim::constant(0.8),
        burn_rate: Anim::constant(5.0),
        turbulence: Anim::constant(2.0),
        turbulence_scale: 0.6,
        bounds_min: [-6.0, -0.5, -6.0],
        bounds_max: [6.0, 12.0, 6.0],
        ..SimParams::default()
    };
    let setup = Setup {
        solids: Solids::new(Some(0.0), &Default::default(), h).unwrap(),
        turbulence: Turbulence::new(p.seed, p.turbulence_scale, p.turbulence_speed),
        bounds: brick_bounds(p.bounds_min, p.bounds_max, h),
        cutoff: p.cutoff,
        tolerance: p.tolerance,
        max_iterations: p.max_iterations,
        max_voxels: 1 << 26,
    };
    let ctx = CookCtx::new();
    let fps = 24.0;
    let mut state = SimState::new(h);
    let mut times = [Duration::ZERO; 7];
    let names = ["topology", "emit", "advect", "burn", "forces", "project", "total"];
    let mut steps = 0;
    let all = Instant::now();
    rayon::scope(|_| {
        for frame in 0..frames {
            let t0 = frame as f64;
            let splats = source.splats(t0, fps, &ctx).unwrap();
            let n = substeps(&state, &splats, (1.0 / fps) as f32, p.cfl, p.min_substeps, p.max_substeps);
            let dt = (1.0 / (fps * f64::from(n))) as f32;
            let mut last = None;
            let frame_start = Instant::now();
            for _ in 0..n {
                let sp = p.at(t0, fps).unwrap();
                let mut lap = Instant::now();
                let mut tick = |k: usize| {
                    times[k] += lap.elapsed();
                    lap = Instant::now();
                };
                let top = next_topology(&state, &emit::bricks(&splats, h), &setup, dt).unwrap();
                state.retopologize(top);
                tick(0);
                emit::emit(&mut state, &splats, dt);
                tick(1);
                advect::advect(&mut state, dt);
                tick(2);
                let target = combust::combust(&mut state, &sp, dt);
                tick(3);
                let time = state.time as f32;
                forces::apply(&mut state, &sp, &Forces { wind: None, turbulence: &setup.turbulence, time }, dt);
                tick(4);
                let solid = setup.solids.mask(&state.top);
                last = Some(pressure::project(&mut state, &solid, &target, p.tolerance, p.max_iterations));
                tick(5);
                state.time += f64::from(dt);
                steps += 1;
            }
            let pr = last.unwrap();
            let top = state.top.voxel_bounds().unwrap();
            println!(
                "frame {frame:3}: {n} sub-steps, {:6.1} ms each, {:8} voxels, {:3} iterations, divergence {:.1e}, height {} voxels",
                frame_start.elapsed().as_secs_f64() * 1e3 / f64::from(n),
                state.top.voxels(),
                pr.iterations,
                pr.max_divergence,
                top.1.y - top.0.y + 1
            );
        }
    });
    times[6] = all.elapsed();
    for (n, t) in names.iter().zip(times) {
        println!("{n:9} {:8.1} ms per step", t.as_secs_f64() * 1e3 / steps as f64);
    }
    println!(
        "{:.1} steps per second over {steps} steps ({} threads)",
        steps as f64 / times[6].as_secs_f64(),
        rayon::current_num_threads()
    );
}
