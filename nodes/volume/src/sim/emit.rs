//! Emission: each [`Splat`] is a soft sphere whose weight falls from 1 at its centre to 0 at its
//! rim, w = (1 − (d/r)²)². Fuel and smoke are added at their rates times the weight, the
//! temperature is raised to at least the splat's times the weight, and the air is pulled to the
//! splat's velocity by the weight. A splat smaller than a voxel is widened to one, so none falls
//! between voxel centres. Splats are binned by brick and each brick is written by one thread, in
//! splat order, so the result does not depend on the number of threads.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::advect::local;
use super::state::SimState;
use crate::grid::{Topology, VOXELS, brick_of};
use crate::source::Splat;

/// The voxel box a splat touches, in index space.
fn reach(s: &Splat, h: f32) -> (IVec3, IVec3, f32) {
    let r = s.radius.max(h);
    let c = s.position / h;
    ((c - r / h).ceil().as_ivec3(), (c + r / h).floor().as_ivec3(), r)
}

/// The bricks the splats touch.
pub fn bricks(splats: &[Splat], h: f32) -> Vec<IVec3> {
    let mut out = Vec::new();
    for s in splats {
        let (lo, hi, _) = reach(s, h);
        let (blo, bhi) = (brick_of(lo), brick_of(hi));
        for z in blo.z..=bhi.z {
            for y in blo.y..=bhi.y {
                for x in blo.x..=bhi.x {
                    out.push(IVec3::new(x, y, z));
                }
            }
        }
    }
    out.sort_unstable_by_key(|c| (c.z, c.y, c.x));
    out.dedup();
    out
}

/// The splats touching each brick of `top`, in splat order.
fn bins(top: &Topology, splats: &[Splat], h: f32) -> Vec<Vec<u32>> {
    let mut bins = vec![Vec::new(); top.len()];
    for (k, s) in splats.iter().enumerate() {
        let (lo, hi, _) = reach(s, h);
        let (blo, bhi) = (brick_of(lo), brick_of(hi));
        for z in blo.z..=bhi.z {
            for y in blo.y..=bhi.y {
                for x in blo.x..=bhi.x {
                    if let Some(b) = top.find(IVec3::new(x, y, z)) {
                        bins[b as usize].push(k as u32);
                    }
                }
            }
        }
    }
    bins
}

/// Emits `dt` seconds of every splat into `state` (whose bricks must already cover them).
pub fn emit(state: &mut SimState, splats: &[Splat], dt: f32) {
    if splats.is_empty() {
        return;
    }
    let h = state.voxel_size;
    let top = state.top.clone();
    let bins = bins(&top, splats, h);
    // Per voxel: fuel and smoke added, temperature floor, velocity pull (weighted sum) and weight.
    let mut scratch = vec![[0.0f32; 8]; top.voxels()];
    scratch.par_chunks_mut(VOXELS).zip(bins.par_iter()).enumerate().for_each(|(b, (acc, bin))| {
        let base = top.origin(b);
        for k in bin {
            let s = &splats[*k as usize];
            let (lo, hi, r) = reach(s, h);
            let (lo, hi) = ((lo - base).max(IVec3::ZERO), (hi - base).min(IVec3::splat(7)));
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let i = crate::grid::voxel(x as usize, y as usize, z as usize);
                        let d2 = ((base.as_vec3() + local(i)) * h - s.position).length_squared() / (r * r);
                        if d2 >= 1.0 {
                            continue;
                        }
                        let w = (1.0 - d2) * (1.0 - d2);
                        let a = &mut acc[i];
                        a[0] += s.fuel * w * dt;
                        a[1] += s.smoke * w * dt;
                        a[2] = a[2].max(s.temperature * w);
                        a[3] += s.velocity.x * w;
                        a[4] += s.velocity.y * w;
                        a[5] += s.velocity.z * w;
                        a[6] += w;
                        a[7] = a[7].max(w);
                    }
                }
            }
        }
    });
    // In the order of `state::DENSITY`, `TEMPERATURE`, `FUEL`.
    let [density, temperature, fuel, _] = &mut state.scalars;
    fuel.par_iter_mut().zip(&scratch).for_each(|(f, a)| *f += a[0]);
    density.par_iter_mut().zip(&scratch).for_each(|(d, a)| *d += a[1]);
    temperature.par_iter_mut().zip(&scratch).for_each(|(t, a)| *t = t.max(a[2]));
    for (axis, v) in state.vel.iter_mut().enumerate() {
        v.par_iter_mut().zip(&scratch).for_each(|(u, a)| {
            if a[6] > 0.0 {
                let target = Vec3::new(a[3], a[4], a[5]) / a[6];
                *u += (target[axis] - *u) * a[7];
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Topology;
    use crate::sim::state::{DENSITY, FUEL, TEMPERATURE};

    #[test]
    fn a_splat_adds_its_rates_with_a_soft_rim_and_pulls_the_air() {
        let h = 0.1;
        let s = Splat { position: Vec3::splat(0.4), radius: 0.3, fuel: 2.0, smoke: 1.0, temperature: 3.0, velocity: Vec3::Y };
        let mut state = SimState::new(h);
        state.retopologize(Topology::new(bricks(&[s], h)));
        assert_eq!(state.top.len(), 1, "a splat inside one brick touches one brick");
        emit(&mut state, &[s], 0.5);
        let at = |x, y, z| crate::grid::voxel(x, y, z);
        assert!((state.scalars[FUEL][at(4, 4, 4)] - 1.0).abs() < 1e-5, "fuel 2/s for 0.5 s at the centre");
        assert!((state.scalars[DENSITY][at(4, 4, 4)] - 0.5).abs() < 1e-5);
        assert!((state.scalars[TEMPERATURE][at(4, 4, 4)] - 3.0).abs() < 1e-5);
        assert!((state.vel[1][at(4, 4, 4)] - 1.0).abs() < 1e-5);
        let rim = state.scalars[FUEL][at(6, 4, 4)];
        assert!(rim > 0.0 && rim < 0.5, "a soft rim: {rim}");
        assert_eq!(state.scalars[FUEL][at(0, 0, 0)], 0.0, "outside the sphere");
    }
}
