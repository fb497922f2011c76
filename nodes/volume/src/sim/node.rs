//! The `volume.simulate` node: sources, wind and a collider in, a clip of volumes out, backed by
//! a [`VolumeFrames`] stepping cache.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::declare::Cook;
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{AtPort, Clip, ClipOf, CookCtx, NodeError, PortType, Value, port};
use pyrograph_nodes_particles::types::{Mesh, WindField};
use pyrograph_nodes_particles::wind::validate_wind;

use super::cache::{Simulation, VolumeFrames};
use super::collide::Solids;
use super::forces::Turbulence;
use super::params::SimParams;
use super::step::{Setup, brick_bounds};
use crate::grid::Volume;
use crate::source::VolumeSource;
use crate::vdb::sim_cache::CachedFrames;

fn no_source() -> Arc<VolumeSource> {
    Arc::new(VolumeSource::default())
}

pyrograph_core::node! {
    /// Fire and smoke as a volume: a sparse grid of 8³ bricks that grows with the smoke and shrinks as it
    /// fades, simulated after Fedkiw, Stam & Jensen 2001 ("Visual Simulation of Smoke": buoyancy from
    /// temperature and smoke weight, eq. 8; vorticity confinement, eq. 9–11) with Nguyen, Fedkiw & Jensen
    /// 2002's reaction (fuel above its ignition temperature burns into heat, smoke and flame, and the burning
    /// gas expands). Each sub-step emits the sources, advects everything by MacCormack with Selle et al.'s
    /// clamp (2008), burns, cools and dissipates, adds buoyancy, confinement, curl-noise turbulence and the pull
    /// of a wind field, and projects the velocity with multigrid-preconditioned conjugate gradients (McAdams et
    /// al. 2010) until every fluid voxel's divergence is below `tolerance`. Sub-steps are CFL-limited; every
    /// animated parameter and source rate is sampled at each. Deterministic; the clip steps a cache, so frame
    /// n after n − 1 costs one frame. Frame i is the state after i + 1 frames. Write with volume.write_vdb; on a
    /// farm, `pyrograph simulate` caches the frames once and renders read them with `--sim-cache`.
    #[node("volume.simulate", "Volume", Simulation)]
    pub struct Simulate {
        /// What emits (volume.source).
        source: Arc<VolumeSource>,
        /// A second source.
        source2: Arc<VolumeSource> = no_source(),
        /// A third source.
        source3: Arc<VolumeSource> = no_source(),
        /// A fourth source.
        source4: Arc<VolumeSource> = no_source(),
        /// Wind (particles.wind_field): its large-scale velocity pulls the air, at `wind_drag`.
        wind: Arc<WindField> = Arc::new(WindField::default()),
        /// A closed mesh the flow goes around (particles.mesh_load).
        collider: Arc<Mesh> = Arc::new(Mesh::default()),
        /// Length and rate of the clip.
        timeline: pyrograph_core::Timeline = pyrograph_core::Timeline { frames: 96, fps: 24.0 },
        /// The simulation.
        params: SimParams,
    }
    /// Per frame, the fire and smoke.
    -> volume: ClipOf<Arc<Volume>>
}

impl Cook for Simulate {
    fn cook(self, ctx: &CookCtx) -> Result<ClipOf<Arc<Volume>>, NodeError> {
        let p = self.params;
        p.validate()?;
        if let (Some(dir), Some(node)) = (&ctx.settings().sim_cache, ctx.node_id()) {
            return Ok(ClipOf::new(cached_clip(dir, node, &p, self.timeline)));
        }
        validate_wind(&self.wind).at_port(port!(Simulate, wind))?;
        let h = p.voxel_size;
        let ground = p.ground.then_some(p.ground_height);
        let solids = Solids::new(ground, &self.collider, h).map_err(|m| NodeError::port(port!(Simulate, collider), m))?;
        let sources: Vec<Arc<VolumeSource>> =
            [self.source, self.source2, self.source3, self.source4].into_iter().filter(|s| !s.emitters.is_empty()).collect();
        let mut fp = Fingerprinter::new();
        "volume.simulate".hash(&mut fp);
        sources.iter().for_each(|s| Value::custom(s.clone()).hash_into(&mut fp));
        Value::custom(self.wind.clone()).hash_into(&mut fp);
        Value::custom(self.collider.clone()).hash_into(&mut fp);
        format!("{p:?}").hash(&mut fp);
        (self.timeline.frames, self.timeline.fps.to_bits()).hash(&mut fp);
        let uses_wind = *self.wind != WindField::default();
        let setup = Setup {
            solids,
            turbulence: Turbulence::new(p.seed, p.turbulence_scale, p.turbulence_speed),
            bounds: brick_bounds(p.bounds_min, p.bounds_max, h),
            cutoff: p.cutoff,
            tolerance: p.tolerance,
            max_iterations: p.max_iterations,
            max_voxels: pyrograph_core::limits::max_voxels(),
        };
        let fps = self.timeline.fps;
        let sim = Simulation { params: p, fps, sources, wind: uses_wind.then(|| (*self.wind).clone()), setup };
        let frames = VolumeFrames::new(sim, self.timeline.frames, h);
        Ok(ClipOf::new(Clip::new(PortType::of::<Volume>(), fps, fp.finish(), Arc::new(frames))))
    }
}

/// The clip of a simulation whose frames were cached by `pyrograph simulate` (`--sim-cache`).
fn cached_clip(dir: &std::path::Path, node: &str, p: &SimParams, timeline: pyrograph_core::Timeline) -> Clip {
    let mut fp = Fingerprinter::new();
    ("volume.simulate from its cache", dir, node, format!("{p:?}"), timeline.frames).hash(&mut fp);
    let frames = CachedFrames { dir: dir.to_path_buf(), node: node.to_string(), frames: timeline.frames };
    Clip::new(PortType::of::<Volume>(), timeline.fps, fp.finish(), Arc::new(frames))
}
