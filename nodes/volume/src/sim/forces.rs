//! The forces on the air (Fedkiw, Stam & Jensen 2001 §3.1–3.3): buoyancy from temperature and
//! smoke weight on the vertical faces (eq. 8), vorticity confinement (eq. 9–11), curl-noise
//! turbulence inside the plume (Bridson, Hourihan & Nordenstam 2007, "Curl-Noise for Procedural
//! Fluid Flow"), and wind: the air is pulled toward the velocity of a `particles.wind_field`.

use glam::Vec3;
use pyrograph_nodes_particles::types::WindField;
use pyrograph_nodes_particles::wind::WindSampler;
use rayon::prelude::*;

use super::advect::{local, lower_neighbor};
use super::params::StepParams;
use super::state::{DENSITY, SimState, TEMPERATURE};
use crate::grid::VOXELS;
use crate::grid::halo::{TILE, gather, t};

/// The noise fields of the turbulence: three Perlin lattices whose gradients make the curl of a
/// vector potential.
pub struct Turbulence {
    potentials: [WindSampler; 3],
    /// World size of a swirl.
    pub scale: f32,
    /// Noise units per second the field drifts.
    pub speed: f32,
}

impl Turbulence {
    /// The turbulence of `seed`.
    pub fn new(seed: u32, scale: f32, speed: f32) -> Turbulence {
        let lattice =
            |k: u32| WindSampler::new(&WindField { seed: seed.wrapping_mul(3).wrapping_add(k), ..WindField::default() });
        Turbulence { potentials: [lattice(0), lattice(1), lattice(2)], scale, speed }
    }

    /// The curl of the potential at world point `p`, time `t` seconds: divergence-free, of
    /// magnitude about 1.
    pub fn curl(&self, p: Vec3, t: f32) -> Vec3 {
        let q = p / self.scale + Vec3::new(0.31, -1.0, 0.17) * (t * self.speed);
        let [a, b, c] = [0, 1, 2].map(|k| self.potentials[k].noise_gradient(q));
        Vec3::new(c.y - b.z, a.z - c.x, b.x - a.y)
    }
}

/// What the forces read besides the state and the step's parameters.
pub struct Forces<'a> {
    /// The wind field at this sub-step (sampled), if any.
    pub wind: Option<&'a WindSampler>,
    /// The turbulence.
    pub turbulence: &'a Turbulence,
    /// Time of the sub-step in seconds.
    pub time: f32,
}

/// Adds `dt` seconds of every force to the velocity.
pub fn apply(state: &mut SimState, p: &StepParams, f: &Forces, dt: f32) {
    buoyancy(state, p, dt);
    // The centred forces cost a velocity interpolation and an acceleration field: only when used.
    if p.vorticity > 0.0 || p.turbulence > 0.0 {
        let mut accel = vec![Vec3::ZERO; state.top.voxels()];
        if p.vorticity > 0.0 {
            confinement(state, &state.centred_velocity(), p.vorticity, &mut accel);
        }
        if p.turbulence > 0.0 {
            turbulence(state, f.turbulence, p.turbulence, f.time, &mut accel);
        }
        add_centred(state, &accel, dt);
    }
    if let Some(w) = f.wind.filter(|_| p.wind_drag > 0.0) {
        wind(state, w, 1.0 - (-p.wind_drag * dt).exp());
    }
}

/// Eq. 8 on the vertical faces: f = −α ρ + β T, the two averaged over the voxels the face
/// separates.
fn buoyancy(state: &mut SimState, p: &StepParams, dt: f32) {
    let top = state.top.clone();
    let (t_field, d_field) = (&state.scalars[TEMPERATURE], &state.scalars[DENSITY]);
    state.vel[1].par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
        let (mut tt, mut td) = ([0.0; TILE], [0.0; TILE]);
        gather(&top, t_field, b, 0.0, &mut tt);
        gather(&top, d_field, b, 0.0, &mut td);
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let c = t(x, y, z);
                    let temp = 0.5 * (tt[c] + tt[c - 10]);
                    let dens = 0.5 * (td[c] + td[c - 10]);
                    o[crate::grid::voxel(x as usize, y as usize, z as usize)] += dt * (p.buoyancy * temp - p.smoke_weight * dens);
                }
            }
        }
    });
}

/// Eq. 9–11: ω = ∇ × u, N = ∇|ω| / |∇|ω||, f = ε h (N × ω), at the voxel centres.
fn confinement(state: &SimState, centred: &[[f32; 3]], epsilon: f32, accel: &mut [Vec3]) {
    let top = &state.top;
    let h = state.voxel_size;
    let comps: [Vec<f32>; 3] = std::array::from_fn(|a| centred.par_iter().map(|v| v[a]).collect());
    let mut omega = vec![Vec3::ZERO; centred.len()];
    omega.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
        let mut tiles = [[0.0; TILE]; 3];
        for a in 0..3 {
            gather(top, &comps[a], b, 0.0, &mut tiles[a]);
        }
        let [u, v, w] = &tiles;
        let d = |f: &[f32; TILE], c: usize, s: usize| (f[c + s] - f[c - s]) / (2.0 * h);
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let c = t(x, y, z);
                    o[crate::grid::voxel(x as usize, y as usize, z as usize)] =
                        Vec3::new(d(w, c, 10) - d(v, c, 100), d(u, c, 100) - d(w, c, 1), d(v, c, 1) - d(u, c, 10));
                }
            }
        }
    });
    let magnitude: Vec<f32> = omega.par_iter().map(|w| w.length()).collect();
    accel.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
        let mut tm = [0.0; TILE];
        gather(top, &magnitude, b, 0.0, &mut tm);
        for z in 0..8 {
            for y in 0..8 {
                for x in 0..8 {
                    let c = t(x, y, z);
                    let grad = Vec3::new(tm[c + 1] - tm[c - 1], tm[c + 10] - tm[c - 10], tm[c + 100] - tm[c - 100]);
                    let len = grad.length();
                    if len < 1e-12 {
                        continue;
                    }
                    let i = crate::grid::voxel(x as usize, y as usize, z as usize);
                    o[i] += epsilon * h * (grad / len).cross(omega[b * VOXELS + i]);
                }
            }
        }
    });
}

/// Curl noise scaled by how much plume a voxel holds (temperature plus smoke, up to 1).
fn turbulence(state: &SimState, noise: &Turbulence, amount: f32, time: f32, accel: &mut [Vec3]) {
    let top = &state.top;
    let h = state.voxel_size;
    let (temp, dens) = (&state.scalars[TEMPERATURE], &state.scalars[DENSITY]);
    accel.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
        let base = top.origin(b).as_vec3();
        for (i, a) in o.iter_mut().enumerate() {
            let weight = (temp[b * VOXELS + i] + dens[b * VOXELS + i]).clamp(0.0, 1.0);
            if weight > 0.0 {
                *a += noise.curl((base + local(i)) * h, time) * (amount * weight);
            }
        }
    });
}

/// Adds `dt` times a voxel-centred acceleration to each face: the mean of the two voxels the
/// face separates.
fn add_centred(state: &mut SimState, accel: &[Vec3], dt: f32) {
    let top = state.top.clone();
    for (axis, v) in state.vel.iter_mut().enumerate() {
        v.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
            for (i, u) in o.iter_mut().enumerate() {
                let here = accel[b * VOXELS + i][axis];
                let below = lower_neighbor(&top, b, i, axis).map_or(here, |n| accel[n][axis]);
                *u += dt * 0.5 * (here + below);
            }
        });
    }
}

/// Pulls each face's velocity a fraction `pull` of the way to the wind's large-scale velocity
/// at the face.
fn wind(state: &mut SimState, wind: &WindSampler, pull: f32) {
    let top = state.top.clone();
    let h = state.voxel_size;
    for (axis, v) in state.vel.iter_mut().enumerate() {
        let mut shift = Vec3::ZERO;
        shift[axis] = -0.5;
        v.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
            let base = top.origin(b).as_vec3();
            for (i, u) in o.iter_mut().enumerate() {
                let target = wind.large((base + local(i) + shift) * h)[axis];
                *u += (target - *u) * pull;
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curl_noise_is_divergence_free() {
        let noise = Turbulence::new(7, 0.5, 1.0);
        let e = 1e-3;
        for p in [Vec3::new(0.1, 0.2, 0.3), Vec3::new(-1.3, 0.7, 2.2), Vec3::new(3.0, -2.0, 0.5)] {
            let div = (noise.curl(p + Vec3::X * e, 0.4).x - noise.curl(p - Vec3::X * e, 0.4).x
                + noise.curl(p + Vec3::Y * e, 0.4).y
                - noise.curl(p - Vec3::Y * e, 0.4).y
                + noise.curl(p + Vec3::Z * e, 0.4).z
                - noise.curl(p - Vec3::Z * e, 0.4).z)
                / (2.0 * e);
            let size = noise.curl(p, 0.4).length();
            assert!(div.abs() < 0.05 * (1.0 + size / 0.5), "{p}: divergence {div}, |curl| {size}");
            assert!(size > 0.0);
        }
    }
}
