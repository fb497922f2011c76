//! A directional light's transmittance volume by one sweep through the bricks instead of a ray
//! per voxel: voxels are visited slice by slice along the light's dominant axis, starting on the
//! light's side, and each voxel's transmittance is its upstream neighbour's (one slice toward the
//! light, read bilinearly from the slice already done) times the segment's Beer–Lambert factor.
//! A ray per voxel costs the length of its shadow in samples; the sweep costs four reads per
//! voxel. The bilinear reads blur a shadow by about a voxel per √(slices travelled), soft as smoke
//! shadows are. Written by hand: it walks pyrograph's own brick layout.

use std::collections::BTreeMap;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::light::{Sampler, exit_distance, ray_transmittance};
use crate::grid::sample::floor_i;
use crate::grid::{DIM, NONE, Topology, VOXELS, Volume, slot, voxel};

/// The fraction of a directional light from `toward` (unit, toward the light) reaching each voxel
/// centre of `v` through `density` (`extinction` per unit density per world unit).
pub fn directional_transmittance(v: &Volume, density: &[f32], extinction: f32, toward: Vec3) -> Vec<f32> {
    let top = &v.topology;
    let Some((lo, hi)) = top.voxel_bounds() else { return Vec::new() };
    let k = toward.abs().max_position();
    let sign = if toward[k] > 0.0 { 1 } else { -1 };
    // One slice toward the light: exactly one voxel along the dominant axis.
    let u = toward / toward[k].abs();
    let step = u.length() * v.transform.voxel_size as f32;
    let (i1, i2) = ((k + 1) % 3, (k + 2) % 3);
    let sampler = Sampler::new(v, density);
    let bounds = (v.transform.to_world(lo.as_vec3() - 0.5), v.transform.to_world(hi.as_vec3() + 0.5));
    // Brick layers along the dominant axis, the light's side first.
    let mut layers: BTreeMap<i32, Vec<usize>> = BTreeMap::new();
    for (b, c) in top.coords().iter().enumerate() {
        layers.entry(c[k]).or_default().push(b);
    }
    let order: Vec<&Vec<usize>> = if sign > 0 { layers.values().rev().collect() } else { layers.values().collect() };
    let slices: Vec<i32> = if sign > 0 { (0..DIM as i32).rev().collect() } else { (0..DIM as i32).collect() };
    let mut out = vec![1.0f32; top.voxels()];
    // Per row and column across the light's axis (the same in every brick and slice): the upstream
    // corner and the upper corner's weight.
    let across = |axis: usize| -> [(i32, f32); DIM] {
        std::array::from_fn(|a| {
            let q = a as f32 + u[axis];
            let c = floor_i(q);
            (c, q - c as f32)
        })
    };
    let (across1, across2) = (across(i1), across(i2));
    for bricks in order {
        for &j in &slices {
            let done: Vec<(usize, [f32; DIM * DIM])> = bricks
                .par_iter()
                .map(|&b| {
                    let tile = upstream(top, &out, density, b, (k, sign), j);
                    let mut slice = [1.0f32; DIM * DIM];
                    for (n, t) in slice.iter_mut().enumerate() {
                        let mut local = IVec3::ZERO;
                        local[k] = j;
                        local[i1] = (n % DIM) as i32;
                        local[i2] = (n / DIM) as i32;
                        let here = density[b * VOXELS + voxel(local.x as usize, local.y as usize, local.z as usize)];
                        let at = [across1[n % DIM], across2[n / DIM]];
                        *t = voxel_transmittance(&tile, here, at, extinction, step).unwrap_or_else(|| {
                            let p = v.transform.to_world((top.origin(b) + local).as_vec3());
                            // The light comes from outside the sweep: a ray in voxel steps.
                            let length = exit_distance(p, toward, bounds.0, bounds.1);
                            ray_transmittance(&sampler, p, toward, length, extinction, v.transform.voxel_size as f32)
                        });
                    }
                    (b, slice)
                })
                .collect();
            for (b, slice) in done {
                for (n, t) in slice.iter().enumerate() {
                    let mut local = IVec3::ZERO;
                    local[k] = j;
                    local[i1] = (n % DIM) as i32;
                    local[i2] = (n / DIM) as i32;
                    out[b * VOXELS + voxel(local.x as usize, local.y as usize, local.z as usize)] = *t;
                }
            }
        }
    }
    out
}

/// Cells of an upstream tile: a brick's slice with a one-voxel border, 10 × 10.
const TILE: usize = (DIM + 2) * (DIM + 2);

/// The slice one voxel toward the light from brick `b`'s slice `j` along axis `k` (the light on
/// the `sign` side), with a one-voxel border across the axis: per cell the transmittance done so
/// far and the density, `None` where no brick is active. Cell `(a1, a2)` (each in `-1..=8`, along
/// the axes after `k`) is at `(a1 + 1) + 10 (a2 + 1)`. Read once per brick and slice, so the 64
/// voxels' bilinear reads need no brick look-ups.
fn upstream(
    top: &Topology,
    done: &[f32],
    density: &[f32],
    b: usize,
    (k, sign): (usize, i32),
    j: i32,
) -> [Option<(f32, f32)>; TILE] {
    let n = top.neighbors(b);
    let (i1, i2) = ((k + 1) % 3, (k + 2) % 3);
    // Brick-local voxel index = x + 8 y + 64 z: the stride of each axis.
    let stride = |axis: usize| 1usize << (3 * axis);
    let along = j + sign;
    let (dk, lk) = (along >> 3, (along & 7) as usize);
    let mut tile = [None; TILE];
    for a2 in -1..=DIM as i32 {
        let (d2, l2) = (a2 >> 3, (a2 & 7) as usize);
        for a1 in -1..=DIM as i32 {
            let (d1, l1) = (a1 >> 3, (a1 & 7) as usize);
            let mut d = [0i32; 3];
            (d[k], d[i1], d[i2]) = (dk, d1, d2);
            let nb = n[slot(d[0], d[1], d[2])];
            if nb != NONE {
                let at = nb as usize * VOXELS + lk * stride(k) + l1 * stride(i1) + l2 * stride(i2);
                tile[(a1 + 1) as usize + (DIM + 2) * (a2 + 1) as usize] = Some((done[at], density[at]));
            }
        }
    }
    tile
}

/// The transmittance at a voxel (its density `here`) from its upstream neighbour one slice toward
/// the light in `tile` ([`upstream`]): `(cell, fraction)` per axis across the light's, the lower
/// upstream corner's tile coordinate and the bilinear weight of the upper one. `None` when a
/// corner of that neighbour is in no active brick (the light then comes from outside the sweep: a
/// ray finds it).
#[inline]
fn voxel_transmittance(
    tile: &[Option<(f32, f32)>; TILE],
    here: f32,
    across: [(i32, f32); 2],
    extinction: f32,
    step: f32,
) -> Option<f32> {
    let [(c1, f1), (c2, f2)] = across;
    let (mut t, mut rho) = (0.0f32, 0.0f32);
    for corner in 0..4 {
        let (up1, up2) = (corner & 1 != 0, corner & 2 != 0);
        let w = if up1 { f1 } else { 1.0 - f1 } * if up2 { f2 } else { 1.0 - f2 };
        if w <= 0.0 {
            continue;
        }
        let (done, density) = tile[(c1 + i32::from(up1) + 1) as usize + (DIM + 2) * (c2 + i32::from(up2) + 1) as usize]?;
        t += w * done;
        rho += w * density.max(0.0);
    }
    let optical = here.max(0.0) + rho;
    // Nothing to cross (most of a sweep): exp(−0) is 1 and spares the call.
    Some(if optical == 0.0 { t } else { t * (-extinction * step * 0.5 * optical).exp() })
}
