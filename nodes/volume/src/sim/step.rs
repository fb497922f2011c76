//! One sub-step of the simulation (Fedkiw, Stam & Jensen 2001 §3; Bridson ch. 2's splitting):
//! grow or shrink the active bricks, emit, advect, burn, add forces, project; and the frame that
//! strings sub-steps together, CFL-limited.

use std::collections::HashSet;

use glam::{IVec3, Vec3};
use pyrograph_core::limits;
use pyrograph_nodes_particles::wind::WindSampler;
use rayon::prelude::*;

use super::collide::Solids;
use super::forces::{Forces, Turbulence};
use super::params::StepParams;
use super::pressure::{Projection, project};
use super::state::SimState;
use super::{advect, combust, emit, forces};
use crate::grid::{Topology, VOXELS};
use crate::source::Splat;

/// Why a simulation stopped.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SimError {
    /// The active region would outgrow the voxel budget.
    #[error(
        "the simulation would need {needed} active voxels at {seconds:.3} s, over the limit of {limit} active voxels; \
         {hint}, or make voxel_size larger, the bounds smaller or the smoke fade sooner (dissipation, cutoff)"
    )]
    VoxelLimit {
        /// Voxels the next sub-step would make active.
        needed: u64,
        /// The budget.
        limit: u64,
        /// Simulation time.
        seconds: f64,
        /// How to raise the budget.
        hint: String,
    },
    /// A value became infinite or NaN.
    #[error(
        "the simulation became non-finite at {seconds:.3} s (a force or rate too strong for the voxel size; lower it or raise max_substeps)"
    )]
    Diverged {
        /// Simulation time.
        seconds: f64,
    },
}

/// What stays the same over a whole simulation.
pub struct Setup {
    /// Solid voxels.
    pub solids: Solids,
    /// The turbulence noise.
    pub turbulence: Turbulence,
    /// Brick bounds the active region may not leave (inclusive).
    pub bounds: (IVec3, IVec3),
    /// A brick stays active while a scalar in it exceeds this.
    pub cutoff: f32,
    /// Pressure tolerance on the divergence (1/s).
    pub tolerance: f32,
    /// Most conjugate-gradient iterations per solve.
    pub max_iterations: u32,
    /// Most active voxels (the process's `--max-voxels` when the node runs).
    pub max_voxels: u64,
}

/// The bricks of the next sub-step: every brick whose scalars exceed the cutoff and every brick a
/// splat touches, each with its 26 neighbours, inside the bounds. Refused before anything is
/// allocated when it would exceed the voxel budget.
pub fn next_topology(state: &SimState, splat_bricks: &[IVec3], setup: &Setup) -> Result<Topology, SimError> {
    let top = &state.top;
    let live: Vec<bool> = (0..top.len())
        .into_par_iter()
        .map(|b| state.scalars.iter().any(|f| f[b * VOXELS..(b + 1) * VOXELS].iter().any(|v| *v > setup.cutoff)))
        .collect();
    let seeds = top.coords().iter().zip(&live).filter(|(_, l)| **l).map(|(c, _)| *c).chain(splat_bricks.iter().copied());
    let mut set = HashSet::new();
    let limit = setup.max_voxels;
    for c in seeds {
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let n = c + IVec3::new(dx, dy, dz);
                    if n.cmpge(setup.bounds.0).all() && n.cmple(setup.bounds.1).all() {
                        set.insert(n);
                    }
                }
            }
        }
        if set.len() as u64 * VOXELS as u64 > limit {
            let needed = set.len() as u64 * VOXELS as u64;
            let hint = limits::raise_hint("--max-voxels", "PYROGRAPH_MAX_VOXELS", needed.max(limit * 2));
            return Err(SimError::VoxelLimit { needed, limit, seconds: state.time, hint });
        }
    }
    Ok(Topology::new(set.into_iter().collect()))
}

/// One sub-step of `dt` seconds with the parameters `p`, the splats and the wind of its time.
pub fn substep(
    state: &mut SimState,
    setup: &Setup,
    p: &StepParams,
    splats: &[Splat],
    wind: Option<&WindSampler>,
    dt: f32,
) -> Result<Projection, SimError> {
    let h = state.voxel_size;
    let top = next_topology(state, &emit::bricks(splats, h), setup)?;
    state.retopologize(top);
    emit::emit(state, splats, dt);
    advect::advect(state, dt);
    let target = combust::combust(state, p, dt);
    let f = Forces { wind, turbulence: &setup.turbulence, time: state.time as f32 };
    forces::apply(state, p, &f, dt);
    let solid = setup.solids.mask(&state.top);
    let projection = project(state, &solid, &target, setup.tolerance, setup.max_iterations);
    clear_solids(state, &solid);
    state.time += f64::from(dt);
    let finite = |f: &Vec<f32>| f.par_iter().all(|v| v.is_finite());
    if !projection.max_divergence.is_finite() || !state.vel.iter().chain(&state.scalars).all(finite) {
        return Err(SimError::Diverged { seconds: state.time });
    }
    Ok(projection)
}

/// Nothing stays inside a collider.
fn clear_solids(state: &mut SimState, solid: &[bool]) {
    if !solid.iter().any(|s| *s) {
        return;
    }
    for f in state.scalars.iter_mut() {
        f.par_iter_mut().zip(solid.par_iter()).for_each(|(v, s)| {
            if *s {
                *v = 0.0;
            }
        });
    }
}

/// The fastest face velocity, world units per second.
pub fn max_speed(state: &SimState) -> f32 {
    state.vel.iter().map(|v| v.par_iter().map(|x| x.abs()).reduce(|| 0.0, f32::max)).fold(0.0, f32::max)
}

/// Sub-steps for a frame of `frame_dt` seconds: enough that nothing moves more than `cfl` voxels
/// in one, given the fastest flow and the fastest emitter, within `min..=max`.
pub fn substeps(state: &SimState, splats: &[Splat], frame_dt: f32, cfl: f32, min: u32, max: u32) -> u32 {
    let emitted = splats.iter().map(|s| s.velocity.length()).fold(0.0, f32::max);
    let speed = max_speed(state).max(emitted);
    let needed = (speed * frame_dt / (cfl * state.voxel_size)).ceil();
    if needed.is_finite() { (needed as u32).clamp(min, max) } else { max }
}

/// The brick bounds of a world-space box at voxel size `h`.
pub fn brick_bounds(lo: [f32; 3], hi: [f32; 3], h: f32) -> (IVec3, IVec3) {
    let b = |p: [f32; 3], round: fn(f32) -> f32| {
        let v = Vec3::from_array(p) / h / 8.0;
        IVec3::new(round(v.x) as i32, round(v.y) as i32, round(v.z) as i32)
    };
    (b(lo, f32::floor), b(hi, f32::floor))
}
