//! The pressure projection (Fedkiw, Stam & Jensen 2001 §3; Bridson, "Fluid Simulation for
//! Computer Graphics", ch. 5): the velocity on the staggered grid is made divergence-free (or
//! to diverge by the combustion's expansion) by solving a Poisson equation for the pressure
//! with conjugate gradients preconditioned by a multigrid V-cycle ([`super::multigrid`]), to a
//! stated tolerance on every fluid voxel's divergence, then subtracting its gradient.
//!
//! Voxels are fluid (solved for), open air (pressure 0: the edge of the active bricks) or solid
//! (no flow through their faces). A voxel is fluid when it is not solid and the voxels after it
//! on all three axes are active, so every face of every fluid voxel is stored: a voxel's lower
//! faces live with it, its upper faces with the next voxels.

use rayon::prelude::*;

use super::multigrid::{FLUID, Level, OPEN, SOLID, apply, hierarchy, v_cycle};
use super::state::{SimState, upper_face};
use crate::grid::halo::{TILE, gather, t};
use crate::grid::{NONE, Topology, VOXELS, slot, voxel};

/// What a projection reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Projection {
    /// Conjugate-gradient iterations taken.
    pub iterations: u32,
    /// The largest |∇·u − target| (1/s) over the fluid voxels afterwards.
    pub max_divergence: f32,
}

/// Each voxel's kind for the solve: solid where `solid` says, fluid where the next voxel on
/// every axis is active, open air elsewhere.
pub fn kinds(top: &Topology, solid: &[bool]) -> Vec<u8> {
    let mut kind = vec![OPEN; top.voxels()];
    kind.par_chunks_mut(VOXELS).enumerate().for_each(|(b, k)| {
        let n = top.neighbors(b);
        let upper = [n[slot(1, 0, 0)] != NONE, n[slot(0, 1, 0)] != NONE, n[slot(0, 0, 1)] != NONE];
        for (i, out) in k.iter_mut().enumerate() {
            let local = [i & 7, (i >> 3) & 7, i >> 6];
            *out = if solid[b * VOXELS + i] {
                SOLID
            } else if (0..3).all(|a| local[a] < 7 || upper[a]) {
                FLUID
            } else {
                OPEN
            };
        }
    });
    kind
}

/// Makes solid every fluid voxel that no path through fluid voxels leads from to open air: a
/// pocket walled in by a collider (between logs, inside a hollow mesh) has no pressure to push
/// against, and its Poisson equation would be singular, with no solution when gas flows in.
/// A breadth-first walk from the fluid voxels beside open air (sequential: the pockets are rare
/// and the walk is one pass over the voxels).
pub fn seal_pockets(top: &Topology, kind: &mut [u8]) {
    let n = kind.len();
    let mut reached = vec![false; n];
    let mut queue: Vec<usize> = Vec::new();
    let neighbour = |at: usize, d: usize| -> Option<usize> {
        let (b, i) = (at / VOXELS, at % VOXELS);
        let (axis, up) = (d / 2, d % 2 == 1);
        let shift = 3 * axis;
        let local = (i >> shift) & 7;
        if (up && local < 7) || (!up && local > 0) {
            return Some(if up { at + (1 << shift) } else { at - (1 << shift) });
        }
        let mut o = [0; 3];
        o[axis] = if up { 1 } else { -1 };
        let nb = top.neighbors(b)[slot(o[0], o[1], o[2])];
        (nb != NONE).then(|| nb as usize * VOXELS + if up { i - (7 << shift) } else { i + (7 << shift) })
    };
    for at in 0..n {
        if kind[at] == FLUID && (0..6).any(|d| neighbour(at, d).is_none_or(|m| kind[m] == OPEN)) {
            reached[at] = true;
            queue.push(at);
        }
    }
    while let Some(at) = queue.pop() {
        for d in 0..6 {
            if let Some(m) = neighbour(at, d)
                && kind[m] == FLUID
                && !reached[m]
            {
                reached[m] = true;
                queue.push(m);
            }
        }
    }
    for (k, r) in kind.iter_mut().zip(&reached) {
        if *k == FLUID && !r {
            *k = SOLID;
        }
    }
}

/// The flux out of each fluid voxel, Σ over axes of (upper face − lower face), in world units
/// per second (the divergence times the voxel size); 0 elsewhere.
pub fn net_flux(top: &Topology, vel: &[Vec<f32>; 3], kind: &[u8]) -> Vec<f32> {
    let mut out = vec![0.0; top.voxels()];
    out.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
        for (i, v) in o.iter_mut().enumerate() {
            if kind[b * VOXELS + i] != FLUID {
                continue;
            }
            *v = (0..3).map(|a| upper_face(top, &vel[a], b, i, a).unwrap_or(0.0) - vel[a][b * VOXELS + i]).sum();
        }
    });
    out
}

/// Makes `state.vel` diverge by `target` (1/s per voxel; empty for none) within `tolerance`,
/// with solid voxels' faces closed, in at most `max_iterations` conjugate-gradient iterations.
pub fn project(state: &mut SimState, solid: &[bool], target: &[f32], tolerance: f32, max_iterations: u32) -> Projection {
    let top = state.top.clone();
    let h = state.voxel_size;
    let mut kind = kinds(&top, solid);
    seal_pockets(&top, &mut kind);
    close_solids(&top, &mut state.vel, &kind);
    if top.is_empty() {
        return Projection::default();
    }
    let level = Level::new((*top).clone(), kind);
    // b = target·h − flux: the pressure's Laplacian must remove the flux beyond the target.
    let flux = net_flux(&top, &state.vel, &level.kind);
    let b: Vec<f32> = (0..top.voxels())
        .into_par_iter()
        .map(|i| if level.diag[i] > 0.0 { target.get(i).map_or(0.0, |t| t * h) - flux[i] } else { 0.0 })
        .collect();
    let mut x: Vec<f32> =
        state.pressure.iter().zip(&level.diag).map(|(p, d)| if *d > 0.0 && p.is_finite() { *p } else { 0.0 }).collect();
    let levels = hierarchy(level);
    let stop = tolerance * h;
    let mut iterations = 0;
    // The recurrence's residual drifts from the true one in f32: restart from the true residual
    // until that is below the tolerance too.
    while iterations < max_iterations {
        let done = pcg(&levels, &b, &mut x, 0.5 * stop, max_iterations - iterations, &mut iterations);
        let mut r = vec![0.0; x.len()];
        apply(&levels[0], &x, &mut r);
        let worst = r.par_iter().zip(b.par_iter()).map(|(a, b)| (b - a).abs()).reduce(|| 0.0, f32::max);
        if worst <= stop || !done {
            break;
        }
    }
    let level = &levels[0];
    subtract_gradient(&top, &mut state.vel, &level.kind, &x);
    state.pressure = x;
    let flux = net_flux(&top, &state.vel, &level.kind);
    let max_divergence = flux
        .par_iter()
        .zip(level.diag.par_iter())
        .enumerate()
        .map(|(i, (f, d))| if *d > 0.0 { (f / h - target.get(i).copied().unwrap_or(0.0)).abs() } else { 0.0 })
        .reduce(|| 0.0, f32::max);
    Projection { iterations, max_divergence }
}

/// Preconditioned conjugate gradients on `A x = b` from the given `x`, until every residual is
/// at most `stop`; `false` when `budget` iterations ran out first.
fn pcg(levels: &[Level], b: &[f32], x: &mut [f32], stop: f32, budget: u32, iterations: &mut u32) -> bool {
    let level = &levels[0];
    let n = x.len();
    let mut r = vec![0.0; n];
    apply(level, x, &mut r);
    r.par_iter_mut().zip(b.par_iter()).for_each(|(r, b)| *r = b - *r);
    if max_abs(&r) <= stop {
        return true;
    }
    let mut z = v_cycle(levels, &r);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut q = vec![0.0; n];
    for _ in 0..budget {
        *iterations += 1;
        apply(level, &p, &mut q);
        let pq = dot(&p, &q);
        if pq <= 0.0 || !pq.is_finite() {
            return true;
        }
        let alpha = (rz / pq) as f32;
        x.par_iter_mut().zip(p.par_iter()).for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(q.par_iter()).for_each(|(r, q)| *r -= alpha * q);
        if max_abs(&r) <= stop {
            return true;
        }
        z = v_cycle(levels, &r);
        let rz_new = dot(&r, &z);
        if rz == 0.0 || !rz_new.is_finite() {
            return true;
        }
        let beta = (rz_new / rz) as f32;
        rz = rz_new;
        p.par_iter_mut().zip(z.par_iter()).for_each(|(p, z)| *p = z + beta * *p);
    }
    false
}

/// A dot product summed per brick in f64 and the bricks' sums added in order, so the result
/// does not depend on the number of threads.
fn dot(a: &[f32], b: &[f32]) -> f64 {
    let parts: Vec<f64> = a
        .par_chunks(VOXELS)
        .zip(b.par_chunks(VOXELS))
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| f64::from(*x) * f64::from(*y)).sum())
        .collect();
    parts.iter().sum()
}

fn max_abs(a: &[f32]) -> f32 {
    a.par_iter().map(|v| v.abs()).reduce(|| 0.0, f32::max)
}

/// Closes every face of every solid voxel (the collider is at rest).
fn close_solids(top: &Topology, vel: &mut [Vec<f32>; 3], kind: &[u8]) {
    let solid: Vec<f32> = kind.iter().map(|k| f32::from(*k == SOLID)).collect();
    for (a, v) in vel.iter_mut().enumerate() {
        v.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
            let mut tile = [0.0; TILE];
            gather(top, &solid, b, 0.0, &mut tile);
            let step = [1, 10, 100][a];
            for z in 0..8 {
                for y in 0..8 {
                    for x in 0..8 {
                        let c = t(x, y, z);
                        if tile[c] > 0.0 || tile[c - step] > 0.0 {
                            o[voxel(x as usize, y as usize, z as usize)] = 0.0;
                        }
                    }
                }
            }
        });
    }
}

/// u −= ∇p on every face beside a fluid voxel and away from solids (pressure 0 outside the
/// fluid voxels).
fn subtract_gradient(top: &Topology, vel: &mut [Vec<f32>; 3], kind: &[u8], p: &[f32]) {
    let fluid: Vec<f32> = kind.iter().map(|k| f32::from(*k == FLUID)).collect();
    let solid: Vec<f32> = kind.iter().map(|k| f32::from(*k == SOLID)).collect();
    for (a, v) in vel.iter_mut().enumerate() {
        v.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
            let (mut tp, mut tf, mut ts) = ([0.0; TILE], [0.0; TILE], [0.0; TILE]);
            gather(top, p, b, 0.0, &mut tp);
            gather(top, &fluid, b, 0.0, &mut tf);
            gather(top, &solid, b, 0.0, &mut ts);
            let step = [1, 10, 100][a];
            for z in 0..8 {
                for y in 0..8 {
                    for x in 0..8 {
                        let c = t(x, y, z);
                        let beside_fluid = tf[c] > 0.0 || tf[c - step] > 0.0;
                        let beside_solid = ts[c] > 0.0 || ts[c - step] > 0.0;
                        if beside_fluid && !beside_solid {
                            o[voxel(x as usize, y as usize, z as usize)] -= tp[c] - tp[c - step];
                        }
                    }
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::IVec3;
    use std::sync::Arc;

    fn block() -> Topology {
        Topology::new((0..27).map(|k| IVec3::new(k % 3, (k / 3) % 3, k / 9)).collect())
    }

    fn at(top: &Topology, v: IVec3) -> usize {
        top.find(v / 8).unwrap() as usize * VOXELS + voxel((v.x & 7) as usize, (v.y & 7) as usize, (v.z & 7) as usize)
    }

    /// A solid shell of half-width 3 around voxel (12, 12, 12).
    fn shell(top: &Topology) -> Vec<bool> {
        let mut solid = vec![false; top.voxels()];
        for z in 0..24 {
            for y in 0..24 {
                for x in 0..24 {
                    let d = (IVec3::new(x, y, z) - 12).abs().max_element();
                    solid[at(top, IVec3::new(x, y, z))] = d == 3;
                }
            }
        }
        solid
    }

    #[test]
    fn a_pocket_walled_in_by_a_collider_is_sealed_and_open_fluid_is_not() {
        let top = block();
        let mut kind = kinds(&top, &shell(&top));
        assert_eq!(kind[at(&top, IVec3::splat(12))], FLUID);
        seal_pockets(&top, &mut kind);
        assert_eq!(kind[at(&top, IVec3::splat(12))], SOLID, "inside the shell");
        assert_eq!(kind[at(&top, IVec3::new(14, 10, 11))], SOLID, "inside the shell");
        assert_eq!(kind[at(&top, IVec3::new(3, 3, 3))], FLUID, "outside it");
        assert_eq!(kind[at(&top, IVec3::new(23, 3, 3))], OPEN, "the last layer before inactive bricks");
    }

    #[test]
    fn a_projection_meets_its_tolerance_around_a_collider_and_with_a_sealed_pocket() {
        let top = block();
        let mut state = SimState::new(0.1);
        state.top = Arc::new(top.clone());
        let n = top.voxels();
        let mut seed = 12345u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 2001) as f32 / 1000.0 - 1.0
        };
        state.vel = std::array::from_fn(|_| (0..n).map(|_| rnd()).collect());
        state.pressure = vec![0.0; n];
        state.scalars = std::array::from_fn(|_| vec![0.0; n]);
        let solid = shell(&top);
        let before = net_flux(&top, &state.vel, &kinds(&top, &solid)).iter().map(|f| (f / 0.1).abs()).fold(0.0, f32::max);
        let p = project(&mut state, &solid, &[], 1e-3, 500);
        println!("divergence {before} → {} in {} iterations", p.max_divergence, p.iterations);
        assert!(before > 1.0 && p.max_divergence <= 1e-3, "{p:?}");
        assert!(state.vel.iter().all(|v| v.iter().all(|x| x.is_finite())));
        // The faces of solid voxels are closed.
        let s = at(&top, IVec3::new(9, 12, 12));
        assert!(solid[s] && state.vel.iter().all(|v| v[s] == 0.0));
    }
}
