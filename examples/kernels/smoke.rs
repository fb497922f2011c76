//! The smoke-step row of the peer harness: `volume.simulate`'s sub-step (MacCormack advection
//! of the scalars and the staggered velocity, cooling and dissipation, buoyancy, the MGPCG
//! pressure projection to its tolerance) on a dense N³ box of warm smoke, against the same step
//! written for NVIDIA Warp's CPU device (`benches/peers/warp_smoke.py`). Both sides start from
//! the same blob (a formula, so no input file) and write the fields after the run for the
//! harness to compare.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use glam::IVec3;
use pyrograph_nodes_volume::grid::{Topology, VOXELS, voxel};
use pyrograph_nodes_volume::sim::collide::Solids;
use pyrograph_nodes_volume::sim::forces::Turbulence;
use pyrograph_nodes_volume::sim::state::{DENSITY, TEMPERATURE};
use pyrograph_nodes_volume::sim::step::substep;
use pyrograph_nodes_volume::sim::{Setup, SimState, StepParams};

use crate::{Timing, npy, report};

#[derive(Args)]
pub struct SmokeArgs {
    /// Voxels along each side of the box (a multiple of 8).
    #[arg(long, default_value_t = 128)]
    n: usize,
    /// Sub-steps per timed run (each run starts from the blob again).
    #[arg(long, default_value_t = 4)]
    steps: usize,
    /// Writes density, temperature and the three staggered velocity components after the last
    /// run as a 5×N×N×N float32 `.npy` (z, y, x; x fastest).
    #[arg(long)]
    output: Option<PathBuf>,
}

/// The sub-step's parameters, as the Warp script has them: no fuel burns, so no expansion; no
/// vorticity, turbulence or wind.
pub const PARAMS: StepParams = StepParams {
    buoyancy: 2.0,
    smoke_weight: 0.1,
    burn_rate: 6.0,
    ignition: 0.2,
    heat: 1.5,
    smoke: 0.6,
    flame: 1.0,
    expansion: 0.0,
    cooling: 0.6,
    flame_cooling: 8.0,
    dissipation: 0.05,
    fuel_dissipation: 1.0,
    vorticity: 0.0,
    turbulence: 0.0,
    wind_drag: 0.0,
};
/// Seconds per sub-step.
pub const DT: f32 = 1.0 / 48.0;
/// The projection's tolerance on the divergence (1/s) and its iteration budget.
pub const TOLERANCE: f32 = 0.01;
pub const MAX_ITERATIONS: u32 = 200;

/// The blob both sides start from: density and temperature falling linearly from 1 at
/// (N/2, N/4, N/2) to 0 at N/6 voxels away, computed in f64 as numpy does.
pub fn blob(n: usize, x: usize, y: usize, z: usize) -> f32 {
    let c = [n as f64 / 2.0, n as f64 / 4.0, n as f64 / 2.0];
    let d = ((x as f64 - c[0]).powi(2) + (y as f64 - c[1]).powi(2) + (z as f64 - c[2]).powi(2)).sqrt();
    (1.0 - d / (n as f64 / 6.0)).clamp(0.0, 1.0) as f32
}

fn initial(n: usize) -> SimState {
    let bricks = (n / 8) as i32;
    let top = Topology::new(
        (0..bricks * bricks * bricks).map(|k| IVec3::new(k % bricks, (k / bricks) % bricks, k / (bricks * bricks))).collect(),
    );
    let mut s = SimState::new(1.0 / n as f32);
    let mut warm = vec![0.0; top.voxels()];
    for (b, c) in top.coords().iter().enumerate() {
        for i in 0..VOXELS {
            let g = *c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
            warm[b * VOXELS + i] = blob(n, g.x as usize, g.y as usize, g.z as usize);
        }
    }
    let voxels = top.voxels();
    s.top = Arc::new(top);
    s.scalars = [warm.clone(), warm, vec![0.0; voxels], vec![0.0; voxels]];
    s.vel = std::array::from_fn(|_| vec![0.0; voxels]);
    s.pressure = vec![0.0; voxels];
    s
}

/// Steps the blob `--steps` times per run; the time of a run is per sub-step.
pub fn smoke(a: &SmokeArgs, t: Timing) -> Result<String, String> {
    let n = a.n;
    if n == 0 || !n.is_multiple_of(8) {
        return Err(format!("--n must be a positive multiple of 8, got {n}"));
    }
    let bricks = (n / 8) as i32;
    let setup = Setup {
        solids: Solids::default(),
        turbulence: Turbulence::new(0, 0.5, 0.5),
        bounds: (IVec3::ZERO, IVec3::splat(bricks - 1)),
        // Every brick of the box stays active, as in the dense peer.
        cutoff: -1.0,
        tolerance: TOLERANCE,
        max_iterations: MAX_ITERATIONS,
        max_voxels: u64::MAX,
    };
    let mut iterations = Vec::new();
    let (times, state) = t.run_with(
        || initial(n),
        |mut s| {
            iterations.clear();
            for _ in 0..a.steps {
                let p = substep(&mut s, &setup, &PARAMS, &[], None, DT).map_err(|e| e.to_string())?;
                iterations.push(p.iterations);
            }
            Ok(s)
        },
    )?;
    if let Some(path) = &a.output {
        let fields = [&state.scalars[DENSITY], &state.scalars[TEMPERATURE], &state.vel[0], &state.vel[1], &state.vel[2]];
        let mut dense = vec![0.0f32; 5 * n * n * n];
        for (f, field) in fields.iter().enumerate() {
            for (b, c) in state.top.coords().iter().enumerate() {
                for i in 0..VOXELS {
                    let (x, y, z) = (i & 7, (i >> 3) & 7, i >> 6);
                    debug_assert_eq!(voxel(x, y, z), i);
                    let g = (*c * 8).as_uvec3();
                    let (x, y, z) = (g.x as usize + x, g.y as usize + y, g.z as usize + z);
                    dense[((f * n + z) * n + y) * n + x] = field[b * VOXELS + i];
                }
            }
        }
        npy::write(path, &[5, n, n, n], &dense)?;
    }
    let per_step: Vec<f64> = times.iter().map(|s| s / a.steps.max(1) as f64).collect();
    Ok(report("smoke", &per_step, serde_json::json!({"n": n, "steps": a.steps, "iterations": iterations})))
}
