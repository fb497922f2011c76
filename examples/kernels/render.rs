//! The volume-render row of the peer harness: `volume.render`'s march (the sun's transmittance
//! volume by a sweep, then a ray per pixel in half-voxel steps: Beer–Lambert segments, single
//! scattering with a Henyey–Greenstein phase and an ambient term, early termination) on a dense
//! N³ box of smoke, against the same march written for NVIDIA Warp's CPU device
//! (`benches/peers/warp_render.py`). Both sides build the smoke from a formula, so no input
//! file, and write the frame for the harness to compare.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use glam::{IVec3, Vec3, Vec4};
use pyrograph_nodes_volume::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS, Volume};
use pyrograph_nodes_volume::render::light::{Light, LightKind};
use pyrograph_nodes_volume::render::march::{Look, Octaves, render};
use pyrograph_render::{Camera, View};

use crate::smoke::blob;
use crate::{Timing, npy, report};

#[derive(Args)]
pub struct RenderArgs {
    /// Voxels along each side of the box (a multiple of 8).
    #[arg(long, default_value_t = 128)]
    n: usize,
    /// Frame width in pixels.
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Frame height in pixels.
    #[arg(long, default_value_t = 360)]
    height: u32,
    /// Writes the frame as an H×W×4 float32 `.npy` (straight RGBA).
    #[arg(long)]
    output: Option<PathBuf>,
}

/// The scene both sides render, as the Warp script has it: the box is the unit cube (voxel size
/// 1/N, voxel centres at (i + ½)/N), the smoke twice [`blob`]'s warm puff, a camera in front and
/// above, the sun from the upper right.
pub const EYE: [f32; 3] = [0.5, 0.55, 2.0];
pub const TARGET: [f32; 3] = [0.5, 0.4, 0.5];
pub const FOV: f32 = 40.0;
pub const SUN: [f32; 3] = [0.5, 1.0, 0.3];
pub const SUN_COLOR: f32 = 6.0;

fn scene(n: usize) -> Volume {
    let bricks = (n / 8) as i32;
    let top = Topology::new(
        (0..bricks * bricks * bricks).map(|k| IVec3::new(k % bricks, (k / bricks) % bricks, k / (bricks * bricks))).collect(),
    );
    let mut density = vec![0.0; top.voxels()];
    for (b, c) in top.coords().iter().enumerate() {
        for i in 0..VOXELS {
            let g = *c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
            density[b * VOXELS + i] = 2.0 * blob(n, g.x as usize, g.y as usize, g.z as usize);
        }
    }
    let h = 1.0 / n as f64;
    Volume {
        transform: Transform { voxel_size: h, origin: [0.5 * h; 3] },
        topology: Arc::new(top),
        fields: vec![Field { name: "density".into(), data: FieldData::Scalar(density) }],
        time: 0.0,
        stats: SimStats::default(),
    }
}

/// Renders the box once per timed run.
pub fn render_box(a: &RenderArgs, t: Timing) -> Result<String, String> {
    let n = a.n;
    if n == 0 || !n.is_multiple_of(8) {
        return Err(format!("--n must be a positive multiple of 8, got {n}"));
    }
    let v = scene(n);
    let camera = Camera::new(Vec3::from(EYE), Vec3::from(TARGET), Vec3::Y, FOV, 0.1, 100.0).map_err(|e| e.to_string())?;
    let view = View::new(camera, a.width, a.height).map_err(|e| e.to_string())?;
    let sun = [Light { kind: LightKind::Directional(Vec3::from(SUN).normalize()), color: Vec3::splat(SUN_COLOR) }];
    let look = Look {
        extinction: 8.0,
        albedo: Vec3::splat(0.85),
        anisotropy: 0.3,
        ambient: Vec3::splat(0.2),
        exposure: 0.0,
        glow: 0.0,
        kelvin: [1000.0, 2600.0],
        step: 0.5,
        background: Vec4::new(0.0, 0.0, 0.0, 1.0),
        seed: 0,
        octaves: Octaves::SINGLE,
    };
    let (times, img) = t.run(|| Ok(render(&v, &view, &sun, &look)))?;
    if let Some(path) = &a.output {
        npy::write(path, &[a.height as usize, a.width as usize, 4], img.data())?;
    }
    Ok(report("render", &times, serde_json::json!({"n": n, "width": a.width, "height": a.height})))
}
