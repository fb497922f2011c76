//! Rows with no peer (the papers' own frame-rate targets): one 1280×720 frame of 1,000 particle
//! flames, of 144 cloth flames, and of the burning cube, each timed per frame as its criterion
//! bench does (nodes/particles/benches/flames.rs, nodes/cloth/benches/cloth.rs,
//! nodes/particles/benches/spread.rs).

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use glam::Vec3;
use pyrograph_core::{BuildOptions, Clip, CookCtx, Evaluator, Graph, GraphDoc, Registry, Value};
use pyrograph_nodes_cloth::render::{RenderParams, Textures, render_cloth};
use pyrograph_nodes_cloth::sim::{ClothParams, Simulation, grid_roots};
use pyrograph_nodes_particles::flame::{FlameParams, Layout, layout_roots, simulate_frame};
use pyrograph_nodes_particles::mesh::{build_mesh, plane};
use pyrograph_nodes_particles::render::render_particles;
use pyrograph_nodes_particles::spread::{Ignition, Spread, SpreadParams, Surface};
use pyrograph_nodes_particles::swept::Exposure;
use pyrograph_nodes_particles::types::WindField;
use pyrograph_render::{Blend, Camera, Particles, View};

use crate::{Timing, report};

#[derive(Args)]
pub struct FramesArgs {
    /// Frames per timed run.
    #[arg(long, default_value_t = 24)]
    frames: usize,
    /// Flames (default: the harness's row, 1,000 particle flames or 144 cloth flames); the scaling
    /// sweep (benches/scaling/run.py) varies it.
    #[arg(long)]
    flames: Option<usize>,
}

/// 1,000 particle flames (or `--flames`) on a grid (the flames bench's scene, the camera backing
/// off as the grid grows): simulate + render per frame.
pub fn particles(a: &FramesArgs, t: Timing) -> Result<String, String> {
    let n = a.flames.unwrap_or(1000).max(1);
    let spacing = 2.0;
    let roots = layout_roots(Layout::Grid, n, Vec3::ZERO, spacing, 0.0, Vec3::Y, 0.0, 1);
    let extent = (n as f32).sqrt().ceil() * spacing;
    let eye = Vec3::new(0.0, extent * 0.45 + 3.0, extent * 0.9 + 10.0);
    let cam = Camera::new(eye, Vec3::new(0.0, 2.5, 0.0), Vec3::Y, 40.0, 0.1, 10_000.0).map_err(|e| e.to_string())?;
    let view = View::new(cam, 1280, 720).map_err(|e| e.to_string())?;
    let (wind, params) = (WindField::default(), FlameParams::default());
    let (times, _) = t.run(|| {
        let mut lit = 0.0_f64;
        for _ in 0..a.frames {
            // Frame 7 every time, as the criterion bench (a frame costs the same at any time).
            let frame = simulate_frame(&roots, &wind, &params, 7).map_err(|e| e.to_string())?;
            let img = render_particles(
                &view,
                &frame,
                Exposure::Continuous,
                Blend::Additive,
                [0.0, 0.0, 0.0, 1.0],
                None,
                &Particles::default(),
            );
            lit += f64::from(img.data()[img.data().len() / 2]);
        }
        Ok(lit)
    })?;
    per_frame("particle_flames_frame", &times, a.frames, serde_json::json!({ "flames": n }))
}

/// 144 cloth flames (or `--flames`) with the node's default springs: a 24 fps frame's sub-steps +
/// textured render, the camera framing the grid as the cloth bench's does.
pub fn cloth_frame(a: &FramesArgs, t: Timing) -> Result<String, String> {
    let n = a.flames.unwrap_or(144).max(1);
    let target = Vec3::new(0.0, 1.0, 0.0);
    // 12 columns (144 flames) at the harness's distance; fewer columns than 3 framed as 3.
    let s = (n as f32).sqrt().ceil().max(3.0) / 12.0;
    let cam =
        Camera::new(target + Vec3::new(0.0, 8.0, 26.0) * s, target, Vec3::Y, 40.0, 0.1, 1000.0).map_err(|e| e.to_string())?;
    let view = View::new(cam, 1280, 720).map_err(|e| e.to_string())?;
    let rp = RenderParams::default();
    let (times, _) = t.run_with(
        || Simulation::new(&ClothParams::default(), &grid_roots(n, 1.5)).map_err(|e| e.to_string()),
        |sim| {
            let mut sim = sim?;
            for _ in 0..a.frames {
                sim.step_frame().map_err(|e| e.to_string())?;
                std::hint::black_box(render_cloth(&view, &sim.snapshot(), Textures::Builtin, &rp));
            }
            Ok(())
        },
    )?;
    per_frame("cloth_frame", &times, a.frames, serde_json::json!({ "flames": n }))
}

#[derive(Args)]
pub struct CubeArgs {
    /// The graph (default: graphs/burning-cube.ron).
    #[arg(long)]
    graph: Option<PathBuf>,
}

/// `graphs/burning-cube.ron` without its writer: the mean frame over frames 48–95, pulled in order
/// from a fresh evaluator warmed up to frame 47 (as the spread bench).
pub fn cube(a: &CubeArgs, t: Timing) -> Result<String, String> {
    let path = a.graph.clone().unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("graphs/burning-cube.ron"));
    let dir = path.parent().map(PathBuf::from).unwrap_or_default();
    let mut doc = GraphDoc::load(&path).map_err(|d| d.to_string())?;
    doc.nodes.0.retain(|(_, node)| node.type_name.starts_with("particles."));
    let kept: Vec<String> = doc.nodes.0.iter().map(|(id, _)| format!("{id}.")).collect();
    doc.edges.retain(|(a, b)| [a, b].iter().all(|e| kept.iter().any(|k| e.starts_with(k.as_str()))));
    let mut registry = Registry::with_builtins();
    pyrograph_nodes_particles::register(&mut registry);
    let graph = Graph::build(&doc, &registry, &dir, &BuildOptions::default()).map_err(|d| d.to_string())?;
    let ctx = CookCtx::new();
    let (first, len) = (48, 48);
    let fresh = || -> Result<Clip, String> {
        match Evaluator::new().output(&graph, "render.image", &ctx) {
            Ok(Value::Clip(clip)) => {
                clip.get(first - 1, &ctx).map_err(|e| e.to_string())?;
                Ok(clip)
            }
            Ok(other) => Err(format!("render.image is not a clip: {}", other.summary())),
            Err(e) => Err(e.to_string()),
        }
    };
    let (times, _) = t.run_with(fresh, |clip| {
        let clip = clip?;
        for f in first..first + len {
            clip.get(f, &ctx).map_err(|e| e.to_string())?;
        }
        Ok(())
    })?;
    per_frame("burning_cube_frame", &times, len, serde_json::json!({ "frames": "48-95" }))
}

fn per_frame(op: &str, times: &[f64], frames: usize, extra: serde_json::Value) -> Result<String, String> {
    let per: Vec<f64> = times.iter().map(|s| s / frames.max(1) as f64).collect();
    Ok(report(op, &per, extra))
}

#[derive(Args)]
pub struct SpreadArgs {
    /// Quads along each side of the 22 × 22 plane (2·d² triangles).
    #[arg(long, default_value_t = 44)]
    divisions: usize,
    /// Spread steps (frames at 24 fps) per timed run.
    #[arg(long, default_value_t = 48)]
    steps: usize,
}

/// Fire spread over a 22 × 22 plane of `divisions`² quads (the spread bench's scene: 16 ignitions
/// a quarter second apart, still air, d_s 0.02): building the surface and `steps` spread steps,
/// reported per step. The front is the same length on every mesh; finer meshes give its control
/// points more faces to cross.
pub fn spread(a: &SpreadArgs, t: Timing) -> Result<String, String> {
    let soup = plane(22.0, a.divisions.max(1));
    let (times, points) = t.run(|| {
        let mesh = build_mesh(&soup, 0, true).map_err(|e| e.to_string())?;
        let surface = Arc::new(Surface::new(&mesh).map_err(|e| e.to_string())?);
        let ignitions = (0..16)
            .map(|k| {
                let p = Vec3::new(-7.5 + 5.0 * (k % 4) as f32, 0.0, -7.5 + 5.0 * (k / 4) as f32);
                let (face, bary, _) = surface.nearest(p);
                Ignition { face, bary, time: 0.25 * k as f32 }
            })
            .collect();
        let params = SpreadParams { d_s: 0.02, ..SpreadParams::default() };
        let mut spread = Spread::new(surface, ignitions, params, 24.0).map_err(|e| e.to_string())?;
        for _ in 0..a.steps {
            spread.step(1.0 / 24.0, &|_| Vec3::ZERO);
        }
        Ok(spread.point_count())
    })?;
    let faces = 2 * a.divisions.max(1) * a.divisions.max(1);
    per_frame("spread_step", &times, a.steps, serde_json::json!({ "faces": faces, "control_points": points }))
}
