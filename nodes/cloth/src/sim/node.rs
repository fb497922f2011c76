//! The `cloth.mass_spring_flame` node: where the flames stand, how many frames, and the
//! [`ClothParams`] group; its clip is backed by a [`ClothSource`].

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Clip, ClipOf, CookCtx, NodeError, PortType, Value, port};

use super::cache::ClothSource;
use super::cloth_params::ClothParams;
use super::simulation::{Simulation, grid_roots};
use crate::state::ClothState;
use pyrograph_render::Particles;

pyrograph_core::node! {
    /// Mass-spring flames, the silk torch of the mass-spring flame project 2019 (after Balci & Foroosh 2006):
    /// each flame is a grid_width × grid_height cloth of masses joined by horizontal and vertical Hooke springs
    /// f = −k·Δl with a damper (§Internal Forces, Equation 4), plus optional shear and bend springs for
    /// stability (Provot 1995). The bottom row is pinned; buoyancy pushes every mass up so the cloth "falls
    /// upwards", and wind is a force vector applied in impulses, wind_on seconds on and wind_off seconds off
    /// (§External Forces: 1 s on, 5 s off). Integration is semi-implicit Euler, v += f/m·dt, x += v·dt
    /// (§Integration, Equations 1–3), in equal sub-steps no longer than dt, so any fps is stable; dt is
    /// checked against the stability limit ≈ 2·√(m/k_eff). Flames stand on a grid of `count` (or at the
    /// points of a connected particles.roots), each with its own random wind phase, strength and seed.
    /// Deterministic for a seed; the clip steps a cache, so frame n after n − 1 costs one frame. Render with
    /// cloth.cloth_render or cloth.cloth_render_textured.
    #[node("cloth.mass_spring_flame", "Cloth", Simulation)]
    pub struct MassSpringFlame {
        /// Optional flame roots (particles.roots); when none are connected, `count` flames stand on a grid.
        roots: Arc<Particles> = Arc::new(Particles::default()),
        /// Flames on the grid when no roots are connected (the project: 9 … 144).
        #[range(1, 1_000_000)]
        count: usize = 9,
        /// Distance between grid flames.
        #[range(0.0, 1e6)]
        spacing: f32 = 1.5,
        /// Number of frames.
        #[range(1, 100_000)]
        frames: usize = 120,
        /// The simulation.
        params: ClothParams,
    }
    /// Per frame, every flame's cloth.
    -> cloth: ClipOf<Arc<ClothState>>
}

impl Cook for MassSpringFlame {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<ClothState>>, NodeError> {
        let params = self.params;
        params.validate()?;
        let roots: Vec<Vec3> = if self.roots.particles.is_empty() {
            if !self.spacing.is_finite() {
                return Err(NodeError::port(port!(MassSpringFlame, spacing), "must be finite"));
            }
            grid_roots(self.count, self.spacing)
        } else {
            self.roots.particles.iter().map(|q| Vec3::from_array(q.position)).collect()
        };
        if let Some(k) = roots.iter().position(|r| !r.is_finite()) {
            return Err(NodeError::port(port!(MassSpringFlame, roots), format!("root {k} has a non-finite position")));
        }
        let frames = self.frames;
        if frames == 0 {
            return Err(NodeError::port(port!(MassSpringFlame, frames), "must be at least 1"));
        }
        let sim = Simulation::new(&params, &roots)?;
        let mut h = Fingerprinter::new();
        "cloth.mass_spring_flame".hash(&mut h);
        Value::custom(self.roots.clone()).hash_into(&mut h);
        roots.iter().for_each(|r| r.to_array().map(f32::to_bits).hash(&mut h));
        format!("{params:?}").hash(&mut h);
        frames.hash(&mut h);
        let clip =
            Clip::new(PortType::of::<ClothState>(), params.fps as f64, h.finish(), Arc::new(ClothSource::new(sim, frames)));
        Ok(ClipOf::new(clip))
    }
}
