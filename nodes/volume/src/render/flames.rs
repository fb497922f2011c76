//! Particle flames and sparks inside the smoke: Perry's flames (drawn as `particles.render_flames`
//! draws them, added to saturation) are light, not matter, so they neither absorb nor hide the smoke
//! behind them; the smoke in front of a flame dims it. Each particle (each step of a trajectory) is
//! dimmed by the transmittance of the smoke between it and the camera, as game engines fog
//! particles per vertex: a particle is a fraction of a voxel to a few voxels across, and the
//! smoke's transmittance changes over voxels, so one value per particle is what a per-pixel depth
//! lookup would give at far less cost. The opaque mesh hides the flames behind it (a holdout in
//! the same rasterization), so the flames, the mesh and the smoke share one depth order.

use glam::Vec3;
use pyrograph_nodes_particles::lit_mesh::holdout_mesh;
use pyrograph_nodes_particles::render::particle_lists;
use pyrograph_nodes_particles::swept::Exposure;
use pyrograph_nodes_particles::types::Mesh;
use pyrograph_render::{Blend, Particles, View};
use rayon::prelude::*;

use super::light::{Sampler, ray_transmittance};
use super::march::slab;
use crate::grid::Volume;

/// How the smoke dims the flames: its extinction per unit density per world unit and the march
/// step in world units.
#[derive(Clone, Copy, Debug)]
pub struct Smoke {
    /// Extinction per unit of density per world unit.
    pub extinction: f32,
    /// March step, world units.
    pub step: f32,
}

/// `particles` with each one's alpha (centre and rim) scaled by the transmittance of `v`'s density
/// from it to `eye`: an additive particle adds `rgb × alpha`, so its light arrives dimmed by the smoke.
pub fn through_smoke(v: &Volume, smoke: Smoke, eye: Vec3, particles: &Particles) -> Particles {
    let (Some(density), Some((lo, hi))) = (v.scalar("density"), v.topology.voxel_bounds()) else {
        return particles.clone();
    };
    let sampler = Sampler::new(v, density);
    let (lo, hi) = (v.transform.to_world(lo.as_vec3() - 0.5), v.transform.to_world(hi.as_vec3() + 0.5));
    let mut out = particles.clone();
    out.particles.par_iter_mut().for_each(|q| {
        let p = Vec3::from_array(q.position);
        let length = (eye - p).length();
        let dir = (eye - p) / length.max(1e-30);
        let Some((t0, t1)) = slab(p, dir, lo, hi) else { return };
        let (t0, t1) = (t0.max(0.0), t1.min(length));
        if t1 <= t0 {
            return;
        }
        let t = ray_transmittance(&sampler, p + dir * t0, dir, t1 - t0, smoke.extinction, smoke.step);
        q.center[3] *= t;
        q.edge[3] *= t;
    });
    out
}

/// The light of `families` (flames, sparks) through `view`, each particle dimmed by the smoke in
/// front of it and hidden behind `mesh`: premultiplied RGBA per pixel (row major), alpha the
/// particles' own coverage (what additive blending accumulates).
pub fn flame_light(
    view: &View,
    v: &Volume,
    smoke: Smoke,
    families: &[&Particles],
    exposure: Exposure,
    mesh: &Mesh,
) -> Vec<[f32; 4]> {
    let eye = view.camera().position();
    let mut lists = Vec::new();
    if !mesh.triangles.is_empty() {
        lists.push(holdout_mesh(view, mesh));
    }
    for family in families.iter().filter(|f| !f.particles.is_empty()) {
        lists.extend(particle_lists(view, &through_smoke(v, smoke, eye, family), exposure, Blend::Additive));
    }
    let frame = pyrograph_render::render(view, &lists, [0.0; 4]);
    let (w, h) = (view.width(), view.height());
    let pixel = |(x, y)| {
        let [r, g, b, a] = frame.premultiplied(x, y);
        // Over the holdout the alpha is the mesh's; the flames' own is their brightest channel
        // (as the flame renderer's emission pass gives it).
        let a = if frame.depth(x, y) < 1.0 { r.max(g).max(b).min(1.0) } else { a };
        [r, g, b, a]
    };
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(pixel).collect()
}
