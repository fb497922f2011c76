//! Perry particle flames: simulate + render one frame at 1280×720 for 1 … 10,000 flames
//! (25 steps, 20 triangles each). Target: ≥ 30 frames/s at 1,000 flames on 2 cores.
//!
//! `wind_1000` compares the 1,000-flame `simulate` frame in the static wind with the same frame
//! in an animated wind (a keyed gust and an expression for C), sampled at the frame as the flame
//! node does. Target: animated ≤ 1.05 × static.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use pyrograph_core::declare::Declared;
use pyrograph_core::{Inputs, ParamValue, Value};
use pyrograph_nodes_particles::flame::{FlameParams, Layout, Root, layout_roots, simulate_frame};
use pyrograph_nodes_particles::render::render_particles;
use pyrograph_nodes_particles::swept::Exposure;
use pyrograph_nodes_particles::types::WindField;
use pyrograph_nodes_particles::wind::WindFieldNode;
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

/// The frame both winds are simulated at: the animated one samples to the static one's values here.
const FRAME: usize = 7;

/// A wind field as `particles.wind_field` makes it: its ports' defaults, with `large_scale` constant,
/// `wind` keyed (a gust from frame 40) and `noise_c` an expression that is the default 0.04 at
/// frame 7. Read through the node's own port reader, so every sample is range-checked as in a graph.
fn animated_wind() -> WindField {
    let desc = WindFieldNode::desc();
    let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().expect("every wind port has a default")).collect();
    let mut set = |name: &str, value: Value| {
        let i = desc.input_index(name).expect("a wind_field port");
        values[i] = value;
    };
    let animated = |text: &str, port: &str| {
        let ty = &desc.inputs[desc.input_index(port).expect("a wind_field port")].ty;
        let anim = pyrograph_core::value::animated_param(&ParamValue::parse_cli(text), ty).expect("valid").expect("animated");
        Value::Anim(Arc::new(anim))
    };
    set("large_scale", Value::Enum("constant".into()));
    set("wind", animated("(keys([(0, 0.0), (40, 0.0), (46, 2.4, ease), (64, 0.3)]), 0, 0)", "wind"));
    set("noise_c", animated("expr(\"0.04 - 0.01 * (1 - cos((frame - 7) * 0.3))\")", "noise_c"));
    let node = WindFieldNode::read(&Inputs::new(&desc, &values)).expect("valid wind ports");
    node.field().expect("a valid wind field")
}

/// The flame parameters with `size` keyed as `particles.particle_flame` reads it (range-checked):
/// 1.0, the default, at frame 7, growing to 1.6 by frame 30.
fn animated_size(params: &FlameParams) -> FlameParams {
    use pyrograph_core::declare::{Anim, Port};
    use pyrograph_nodes_particles::flame::ParticleFlame;
    let desc = ParticleFlame::desc();
    let port = &desc.inputs[desc.input_index("size").expect("a particle_flame port")];
    let keys = ParamValue::parse_cli("keys([(0, 1.0), (7, 1.0, ease), (30, 1.6)])");
    let anim = pyrograph_core::value::animated_param(&keys, &port.ty).expect("valid").expect("animated");
    let size = <Anim<f32> as Port>::from_port(&Value::Anim(Arc::new(anim)), port).expect("in range");
    FlameParams { size, ..params.clone() }
}

fn wind(c: &mut Criterion) {
    let (roots, params, _) = scene(1_000);
    let keyed = animated_size(&params);
    let still = WindField::default();
    let moving = animated_wind();
    assert!(moving.animation.is_some(), "the wind is animated");
    // Outside the timing: sampled at FRAME, the animated wind has the static one's values (a zero
    // constant w_L, C = 0.04), so both rows simulate the same frame and differ only by the sampling.
    let sampled = moving.at_frame(FRAME as f64, 24.0).expect("samples");
    let sized = keyed.at_frame(FRAME as f64, 24.0).expect("samples");
    let want = simulate_frame(&roots, &still, &params, FRAME).expect("simulates");
    // `assert!` rather than `assert_eq!`: a mismatch would print 25,000 particles twice.
    assert!(simulate_frame(&roots, &sampled, &sized, FRAME).expect("simulates") == want, "same frame");
    assert_ne!(keyed.at_frame(20.0, 24.0).expect("samples").size.value(), sized.size.value(), "the size grows by frame 20");
    let gust = moving.at_frame(50.0, 24.0).expect("samples");
    assert_ne!(gust.large, sampled.large, "the gust blows by frame 50");

    let mut group = c.benchmark_group("wind_1000");
    group.sample_size(10);
    group.bench_function("static", |b| {
        b.iter(|| black_box(simulate_frame(&roots, &still, &params, black_box(FRAME)).expect("simulates")))
    });
    group.bench_function("animated", |b| {
        b.iter(|| {
            // As the flame node's frame source: sample the wind and the size at the frame, then simulate.
            let wind = moving.at_frame(black_box(FRAME) as f64, 24.0).expect("samples");
            let p = keyed.at_frame(black_box(FRAME) as f64, 24.0).expect("samples");
            black_box(simulate_frame(&roots, &wind, &p, FRAME).expect("simulates"))
        })
    });
    // The difference on its own: sampling the wind (clone, keys, expression, range checks).
    group.bench_function("sample_only", |b| {
        b.iter(|| black_box(moving.at_frame(black_box(FRAME) as f64, 24.0).expect("samples")))
    });
    group.finish();
}

criterion_group!(benches, flames, wind);
criterion_main!(benches);
