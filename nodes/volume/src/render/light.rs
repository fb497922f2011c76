//! Lights on a volume: directional (the sun) and point lights (the flames' lights, the fire's
//! own glow), the Henyey–Greenstein phase function, and each light's transmittance through the
//! smoke precomputed once per frame as a field on the volume's bricks (a "deep shadow" volume,
//! as production volume renderers cache light; Fedkiw, Stam & Jensen 2001 §4 render their smoke
//! the same way), so a camera sample reads its shadow with one interpolation instead of marching
//! toward every light.

use std::f32::consts::PI;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::grid::sample::{Corners, corners, floor_i};
use crate::grid::{NONE, Topology, VOXELS, Volume, brick_of, slot};

/// Where a light is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Infinitely far along this unit direction (from the volume toward the light).
    Directional(Vec3),
    /// At a world position; falls off with the inverse square of the distance.
    Point(Vec3),
}

/// A light: where, and its colour times intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Where.
    pub kind: LightKind,
    /// Radiance scale per channel.
    pub color: Vec3,
}

impl Light {
    /// The unit direction from world point `p` toward the light and the light's strength there
    /// (before shadowing); point lights closer than `min_distance` are held at that distance.
    #[inline]
    pub fn toward(&self, p: Vec3, min_distance: f32) -> (Vec3, Vec3) {
        match self.kind {
            LightKind::Directional(d) => (d, self.color),
            LightKind::Point(at) => {
                let v = at - p;
                let d2 = v.length_squared().max(min_distance * min_distance);
                (v.normalize_or(Vec3::Y), self.color / d2)
            }
        }
    }
}

/// The Henyey–Greenstein phase function (per steradian) for the cosine between the light's
/// direction of travel and the scattered direction, anisotropy `g` in (−1, 1).
#[inline]
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = (1.0 + g * g - 2.0 * g * cos).max(1e-6);
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// Reads a scalar field of a volume at world points by trilinear interpolation (0 outside the
/// active bricks).
pub struct Sampler<'a> {
    top: &'a Topology,
    field: &'a [f32],
    origin: Vec3,
    inv_h: f32,
}

impl<'a> Sampler<'a> {
    /// A sampler of `field` (one value per voxel of `v`).
    pub fn new(v: &'a Volume, field: &'a [f32]) -> Sampler<'a> {
        let t = &v.transform;
        let origin = Vec3::new(t.origin[0] as f32, t.origin[1] as f32, t.origin[2] as f32);
        Sampler { top: &v.topology, field, origin, inv_h: (1.0 / t.voxel_size) as f32 }
    }

    /// The world position of index-space point 0 (voxel 0's centre).
    #[inline]
    pub fn origin_world(&self) -> Vec3 {
        self.origin
    }

    /// World point `w` in index space (voxel centres at integers).
    #[inline]
    pub fn index(&self, w: Vec3) -> Vec3 {
        (w - self.origin) * self.inv_h
    }

    /// The brick holding index-space point `p`'s nearest voxel, if active, through a one-brick
    /// memo: successive samples along a ray fall in the same brick several times running, and the
    /// next brick is usually a neighbour of the last, read from its neighbour table; only a ray
    /// coming from an inactive brick probes the hash map.
    #[inline(always)]
    pub fn brick_cached(&self, p: Vec3, memo: &mut (IVec3, Option<usize>)) -> Option<usize> {
        // The point is inside the volume's bounds, so small and finite.
        let c = brick_of(IVec3::new(floor_i(p.x + 0.5), floor_i(p.y + 0.5), floor_i(p.z + 0.5)));
        if c != memo.0 {
            self.enter(c, memo);
        }
        memo.1
    }

    /// Moves `memo` to brick coordinate `c` (out of line: once per brick crossed).
    #[inline(never)]
    fn enter(&self, c: IVec3, memo: &mut (IVec3, Option<usize>)) {
        let next = match memo.1 {
            Some(b) if (c - memo.0).abs().max_element() <= 1 => {
                let d = c - memo.0;
                let nb = self.top.neighbors(b)[slot(d.x, d.y, d.z)];
                (nb != NONE).then_some(nb as usize)
            }
            _ => self.top.find(c).map(|b| b as usize),
        };
        *memo = (c, next);
    }

    /// The eight voxels around index-space point `p` and their weights, looked up from brick `b`
    /// (the brick of [`Sampler::brick_cached`]): they read any field on the same bricks.
    #[inline]
    pub fn corners(&self, b: usize, p: Vec3) -> Corners {
        corners(self.top, b, p)
    }

    /// The value at index-space point `p`, looked up from brick `b` (the brick of [`Sampler::brick_cached`]).
    #[inline]
    pub fn at(&self, b: usize, p: Vec3) -> f32 {
        corners(self.top, b, p).sample(self.field)
    }
}

/// The fraction of `light`'s light that reaches each voxel centre of `v` through the density
/// (`extinction` per unit density per world unit), marched toward the light in steps of `step`
/// world units until it leaves the active bricks' bounds or reaches a point light. Bricks flagged
/// in `skip` (nothing there scatters light: [`super::clear::clear_bricks`]) are left at 1 unmarched.
pub fn transmittance(v: &Volume, density: &[f32], extinction: f32, light: &Light, step: f32, skip: &[bool]) -> Vec<f32> {
    let top = &v.topology;
    let Some((lo, hi)) = top.voxel_bounds() else { return Vec::new() };
    let sampler = Sampler::new(v, density);
    let (bmin, bmax) = (v.transform.to_world(lo.as_vec3() - 0.5), v.transform.to_world(hi.as_vec3() + 0.5));
    let mut out = vec![1.0; top.voxels()];
    out.par_chunks_mut(VOXELS).enumerate().filter(|(b, _)| !skip.get(*b).copied().unwrap_or(false)).for_each(|(b, o)| {
        let base = top.origin(b);
        for (i, t) in o.iter_mut().enumerate() {
            let ijk = base + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
            let p = v.transform.to_world(ijk.as_vec3());
            let (dir, limit) = match light.kind {
                LightKind::Directional(d) => (d, f32::INFINITY),
                LightKind::Point(at) => ((at - p).normalize_or(Vec3::Y), (at - p).length()),
            };
            *t = ray_transmittance(&sampler, p, dir, exit_distance(p, dir, bmin, bmax).min(limit), extinction, step);
        }
    });
    out
}

/// The transmittance from world point `p` along unit `dir` over `length` world units, marched in
/// steps of `step` (half a step first, so a voxel's own density counts half: the light arrives at
/// its centre), stopping once the optical depth passes 12.
pub fn ray_transmittance(sampler: &Sampler, p: Vec3, dir: Vec3, length: f32, extinction: f32, step: f32) -> f32 {
    let (mut s, mut depth) = (0.5 * step, 0.0);
    let mut memo = (IVec3::MAX, None);
    while s < length {
        let q = sampler.index(p + dir * s);
        depth += sampler.brick_cached(q, &mut memo).map_or(0.0, |b| sampler.at(b, q));
        if depth * step * extinction > 12.0 {
            break;
        }
        s += step;
    }
    (-extinction * depth * step).exp()
}

/// How far a ray from `p` (inside the box) along unit `d` travels before it leaves the box.
#[inline]
pub fn exit_distance(p: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let mut t = f32::INFINITY;
    for k in 0..3 {
        if d[k] > 1e-12 {
            t = t.min((hi[k] - p[k]) / d[k]);
        } else if d[k] < -1e-12 {
            t = t.min((lo[k] - p[k]) / d[k]);
        }
    }
    t.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_phase_function_integrates_to_one_and_leans_forward() {
        for g in [-0.6, 0.0, 0.3, 0.8] {
            let n = 20_000;
            let total: f32 = (0..n)
                .map(|k| {
                    let cos = -1.0 + 2.0 * (k as f32 + 0.5) / n as f32;
                    henyey_greenstein(cos, g) * 2.0 * PI * (2.0 / n as f32)
                })
                .sum();
            assert!((total - 1.0).abs() < 2e-3, "g {g}: {total}");
        }
        assert!(henyey_greenstein(1.0, 0.5) > 10.0 * henyey_greenstein(-1.0, 0.5));
    }
}
