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
use crate::grid::{Topology, VOXELS, slot};
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

/// The bricks of the next sub-step, for a sub-step of `dt` seconds: every brick whose scalars
/// exceed the cutoff, with those of its 26 neighbours the smoke could reach within the sub-step,
/// and every brick a splat touches with all 26 neighbours, inside the bounds. Refused before
/// anything is allocated when it would exceed the voxel budget.
pub fn next_topology(state: &SimState, splat_bricks: &[IVec3], setup: &Setup, dt: f32) -> Result<Topology, SimError> {
    let top = &state.top;
    let per_voxel = dt / state.voxel_size;
    // Per live brick, which neighbour directions to activate (a bit per slot of 27).
    let grow: Vec<u32> = (0..top.len()).into_par_iter().map(|b| reach_mask(state, b, setup.cutoff, per_voxel)).collect();
    let seeds = top.coords().iter().zip(&grow).filter(|(_, g)| **g != 0).map(|(c, g)| (*c, *g));
    let seeds = seeds.chain(splat_bricks.iter().map(|c| (*c, ALL)));
    let mut set = HashSet::new();
    let limit = setup.max_voxels;
    for (c, mask) in seeds {
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let n = c + IVec3::new(dx, dy, dz);
                    let wanted = mask & (1 << slot(dx, dy, dz)) != 0;
                    if wanted && n.cmpge(setup.bounds.0).all() && n.cmple(setup.bounds.1).all() {
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

/// Every neighbour slot.
const ALL: u32 = (1 << 27) - 1;

/// The neighbour slots brick `b` must keep active (0 when its scalars are all at or under the
/// cutoff): itself, and each neighbour whose side the brick's smoke lies within reach of, so
/// smoke never moves into a brick that is not active, while a brick whose smoke sits in its
/// middle, or whose flow leads away from a side, keeps no neighbour there (a one-brick margin all
/// round makes the active region of a plume about half again as large as the smoke).
///
/// The reach towards a side is how far the brick's fastest flow that way carries in two
/// sub-steps, plus one voxel for the trilinear stencil (MacCormack's correction is clamped to
/// what the forward step read, so it carries nothing farther). Two sub-steps, because a brick
/// made active starts at rest and has flow only after that sub-step's projection: smoke reaching
/// it in its first sub-step would find nothing there pulling it in, and be lost.
fn reach_mask(state: &SimState, b: usize, cutoff: f32, per_voxel: f32) -> u32 {
    let range = b * VOXELS..(b + 1) * VOXELS;
    let (mut lo, mut hi) = ([8usize; 3], [0usize; 3]);
    for i in 0..VOXELS {
        if state.scalars.iter().any(|f| f[range.start + i] > cutoff) {
            let l = [i & 7, (i >> 3) & 7, i >> 6];
            for a in 0..3 {
                lo[a] = lo[a].min(l[a]);
                hi[a] = hi[a].max(l[a]);
            }
        }
    }
    if lo[0] == 8 {
        return 0;
    }
    // Voxels the flow carries towards the lower and the upper side of each axis in two sub-steps.
    let reach = |a: usize, sign: f32| {
        let fastest = state.vel[a][range.clone()].iter().fold(0.0f32, |m, v| m.max(sign * v));
        (2.0 * fastest * per_voxel).min(8.0).ceil() as usize + 1
    };
    let ok = |a: usize, d: i32| match d {
        -1 => lo[a] < reach(a, -1.0),
        1 => hi[a] + reach(a, 1.0) > 7,
        _ => true,
    };
    let mut mask = 0;
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                if ok(0, dx) && ok(1, dy) && ok(2, dz) {
                    mask |= 1 << slot(dx, dy, dz);
                }
            }
        }
    }
    mask
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
    let top = next_topology(state, &emit::bricks(splats, h), setup, dt)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::voxel;
    use crate::sim::collide::Solids;
    use crate::sim::state::DENSITY;

    fn setup() -> Setup {
        Setup {
            solids: Solids::default(),
            turbulence: Turbulence::new(0, 1.0, 0.0),
            bounds: (IVec3::splat(-100), IVec3::splat(100)),
            cutoff: 0.002,
            tolerance: 0.01,
            max_iterations: 50,
            max_voxels: 1 << 30,
        }
    }

    /// One brick at rest holding smoke in the voxel `at`, stepped with velocity `speed` (voxels
    /// per sub-step along +x).
    fn one_brick(at: [usize; 3], speed: f32) -> SimState {
        let mut state = SimState::new(1.0);
        state.top = std::sync::Arc::new(Topology::new(vec![IVec3::ZERO]));
        state.scalars = std::array::from_fn(|_| vec![0.0; VOXELS]);
        state.scalars[DENSITY][voxel(at[0], at[1], at[2])] = 1.0;
        state.vel = std::array::from_fn(|a| vec![if a == 0 { speed } else { 0.0 }; VOXELS]);
        state.pressure = vec![0.0; VOXELS];
        state
    }

    fn neighbours(state: &SimState) -> Vec<IVec3> {
        let mut c = next_topology(state, &[], &setup(), 1.0).unwrap().coords().to_vec();
        c.sort_by_key(|c| (c.z, c.y, c.x));
        c
    }

    #[test]
    fn a_brick_keeps_only_the_neighbours_its_smoke_can_reach_in_a_sub_step() {
        // Smoke in the middle at rest: within a voxel of no side.
        assert_eq!(neighbours(&one_brick([4, 4, 4], 0.0)), vec![IVec3::ZERO]);
        // Smoke against the lower x side: that neighbour too.
        assert_eq!(neighbours(&one_brick([0, 4, 4], 0.0)), vec![IVec3::new(-1, 0, 0), IVec3::ZERO]);
        // In a corner: the seven bricks around that corner.
        assert_eq!(neighbours(&one_brick([7, 7, 7], 0.0)).len(), 8);
        // Flow of 1.5 voxels a sub-step carries three voxels in two sub-steps, and the stencil
        // one more: from voxel 4 it reaches the upper x side (4 voxels away) but not the lower
        // one (5 away), from voxel 3 the lower one; flow of one voxel reaches neither from 4.
        assert_eq!(neighbours(&one_brick([4, 4, 4], 1.5)), vec![IVec3::ZERO, IVec3::new(1, 0, 0)]);
        assert_eq!(neighbours(&one_brick([4, 4, 4], -1.5)), vec![IVec3::ZERO]);
        assert_eq!(neighbours(&one_brick([3, 4, 4], -1.5)), vec![IVec3::new(-1, 0, 0), IVec3::ZERO]);
        assert_eq!(neighbours(&one_brick([4, 4, 4], 1.0)), vec![IVec3::ZERO]);
        // Nothing above the cutoff keeps nothing.
        let mut empty = one_brick([4, 4, 4], 0.0);
        empty.scalars[DENSITY][voxel(4, 4, 4)] = 0.001;
        assert!(neighbours(&empty).is_empty());
    }

    #[test]
    fn smoke_carried_across_bricks_is_not_lost_to_inactive_ones() {
        // A blob carried along +x at 3 voxels a sub-step (the default CFL) through twenty
        // sub-steps, the active bricks chosen afresh before each, as a simulation does: a brick
        // made active starts at rest and has the flow only from the next sub-step on (a
        // simulation's projection gives it). Uniform flow by whole voxels moves the blob exactly:
        // whatever reaches a brick before it has flow vanishes.
        let mut state = one_brick([3, 3, 3], 3.0);
        for i in 0..VOXELS {
            let p = advect::local(i) - glam::Vec3::splat(3.5);
            state.scalars[DENSITY][i] = (-p.length_squared() / 3.0).exp();
        }
        let mass = |s: &SimState| s.scalars[DENSITY].iter().map(|v| f64::from(*v)).sum::<f64>();
        let before = mass(&state);
        let flow = |state: &mut SimState| {
            let n = state.top.voxels();
            state.vel = std::array::from_fn(|a| vec![if a == 0 { 3.0 } else { 0.0 }; n]);
        };
        // The blob fills its brick from the start: its first neighbours get their flow before it
        // moves, as they would have while it grew.
        let top = next_topology(&state, &[], &setup(), 1.0).unwrap();
        state.retopologize(top);
        flow(&mut state);
        for _ in 0..20 {
            let top = next_topology(&state, &[], &setup(), 1.0).unwrap();
            state.retopologize(top);
            advect::advect(&mut state, 1.0);
            flow(&mut state);
        }
        let after = mass(&state);
        let reach = state.top.voxel_bounds().unwrap();
        assert!(reach.1.x >= 60, "the blob travelled: {reach:?}");
        assert!((after - before).abs() < 0.02 * before, "mass {before} became {after}");
    }
}
