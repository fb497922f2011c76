//! Perry's fire spread over meshes (Perry 1994 §3.3–3.4).
//!
//! `burning_cube_1280x720`: the mean frame of `graphs/burning-cube.ron` over frames 48–95 (the
//! fire spreading over most of the cube), cooked through the graph's own nodes (the writer left
//! out): `spread` is one frame of the spread clip (spread step + state), `spread+char` adds the
//! char discs, and `frame` is the full pipeline (spread + char + root flames + flame lights +
//! render at 1280×720). Each iteration pulls the window's frames in order from a fresh evaluator
//! warmed up to its start, so frame n after frame n − 1 costs what it costs in a real cook.
//! Target: ≥ 24 frames/s.
//!
//! `spread_step`: `Spread::step` alone (move, double-burn test, insertion, flame drops, char) on a
//! large plane grid (Perry's typical 0.5-unit polygons) with 16 ignitions grown until the
//! boundary holds ≈ 10,000 control points.

use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pyrograph_core::{BuildOptions, Clip, CookCtx, Evaluator, Graph, GraphDoc, Registry, Value};
use pyrograph_nodes_particles::mesh::{build_mesh, plane};
use pyrograph_nodes_particles::spread::{Ignition, Spread, SpreadParams, Surface};
use pyrograph_nodes_particles::types::SpreadState;

/// First frame of the timed window (the fire covers most of the near side) and its length.
const WINDOW: (usize, usize) = (48, 48);

/// `graphs/burning-cube.ron` without its writer (an imaging node, not needed to time a frame).
fn burning_cube() -> Graph {
    let dir = pyrograph_testing::workspace().join("graphs");
    let mut doc = GraphDoc::load(&dir.join("burning-cube.ron")).unwrap_or_else(|d| panic!("{d}"));
    doc.nodes.0.retain(|(_, node)| node.type_name.starts_with("particles."));
    let kept: Vec<String> = doc.nodes.0.iter().map(|(id, _)| format!("{id}.")).collect();
    doc.edges.retain(|(a, b)| [a, b].iter().all(|e| kept.iter().any(|k| e.starts_with(k.as_str()))));
    let mut registry = Registry::with_builtins();
    pyrograph_nodes_particles::register(&mut registry);
    Graph::build(&doc, &registry, &dir, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"))
}

/// The clip at `endpoint` from a fresh evaluator (fresh caches).
fn clip(graph: &Graph, endpoint: &str) -> Clip {
    match Evaluator::new().output(graph, endpoint, &CookCtx::new()) {
        Ok(Value::Clip(clip)) => clip,
        Ok(other) => panic!("{endpoint} is not a clip: {}", other.summary()),
        Err(e) => panic!("{endpoint}: {e}"),
    }
}

/// `iters` times the mean cost of one frame of `endpoint` over the whole [`WINDOW`]: every
/// iteration pulls all its frames in order from a fresh evaluator warmed up to its start. (Timing
/// only the first few frames of the window would understate it: the fire, and the frame cost,
/// grow through the window.)
fn window_mean(graph: &Graph, endpoint: &str, iters: u64) -> Duration {
    let ctx = CookCtx::new();
    let (first, len) = WINDOW;
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        let clip = clip(graph, endpoint);
        black_box(clip.get(first - 1, &ctx).expect("warm-up frame cooks"));
        let start = Instant::now();
        for f in first..first + len {
            black_box(clip.get(f, &ctx).expect("frame cooks"));
        }
        total += start.elapsed() / len as u32;
    }
    total
}

fn burning_cube_frame(c: &mut Criterion) {
    let graph = burning_cube();
    let spread = clip(&graph, "spread.spread");
    let ctx = CookCtx::new();
    for f in [WINDOW.0, WINDOW.0 + WINDOW.1] {
        if let Some(s) = spread.get(f, &ctx).ok().and_then(|v| v.downcast::<SpreadState>()) {
            let points: usize = s.boundaries.iter().map(Vec::len).sum();
            println!(
                "burning cube frame {f}: {points} control points, {} live flames, {} char marks",
                s.roots.len(),
                s.char_marks.len()
            );
        }
    }
    let mut group = c.benchmark_group("burning_cube_1280x720");
    group.sample_size(10);
    group.throughput(Throughput::Elements(1));
    for (name, endpoint) in [("spread", "spread.spread"), ("spread+char", "char.char"), ("frame", "render.image")] {
        group.bench_function(name, |b| b.iter_custom(|iters| window_mean(&graph, endpoint, iters)));
    }
    group.finish();
}

/// A 22 × 22 plane of 0.5-unit quads (Perry's typical edge length) with 4 × 4 ignitions lit a
/// quarter second apart, in still air, grown until the rings hold ≈ `target` control points.
/// Still air keeps every ring a circle of live points (in wind the inserted points fold the
/// front, so most of the count would be extinguished points); staggered rings keep the total
/// from jumping by powers of two, as every gap of a circle splits at once.
fn big_spread(target: usize) -> Spread {
    let mesh = build_mesh(&plane(22.0, 44), 0, true).expect("plane builds");
    let surface = Arc::new(Surface::new(&mesh).expect("plane is a surface"));
    let ignitions = (0..16)
        .map(|k| {
            let p = Vec3::new(-7.5 + 5.0 * (k % 4) as f32, 0.0, -7.5 + 5.0 * (k / 4) as f32);
            let (face, bary, _) = surface.nearest(p);
            Ignition { face, bary, time: 0.25 * k as f32 }
        })
        .collect();
    let params = SpreadParams { d_s: 0.02, ..SpreadParams::default() };
    let mut spread = Spread::new(surface, ignitions, params, 24.0).expect("valid spread");
    while spread.point_count() < target {
        spread.step(DT, &still);
        assert!(spread.time() < 60.0, "the spread stalled at {} points", spread.point_count());
    }
    spread
}

/// Length of one spread step: one frame at 24 frames/s.
const DT: f32 = 1.0 / 24.0;

fn still(_: Vec3) -> Vec3 {
    Vec3::ZERO
}

fn spread_step(c: &mut Criterion) {
    let spread = big_spread(10_000);
    let state = spread.state();
    let n = spread.point_count();
    let alive = spread.loops().iter().flatten().filter(|p| p.alive).count();
    println!(
        "spread step: {n} control points ({alive} moving) in {} rings after {:.2} s, {} live flame roots, {} char marks",
        spread.loops().len(),
        spread.time(),
        state.roots.len(),
        state.char_marks.len()
    );
    let mut group = c.benchmark_group("spread_step");
    group.sample_size(20);
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function(format!("{n}_points"), |b| {
        b.iter_batched_ref(|| spread.clone(), |s| s.step(DT, &still), BatchSize::LargeInput)
    });
    group.finish();
}

criterion_group!(benches, burning_cube_frame, spread_step);
criterion_main!(benches);
