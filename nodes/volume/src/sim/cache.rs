//! The stepping cache behind `volume.simulate`'s clip: frame `i` of the clip is the state after
//! `i + 1` frames of simulation (so frame 0 already shows the first frame's emission), stepped on
//! demand from the nearest state the cache holds.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use pyrograph_core::declare::AnimError;
use pyrograph_core::stepping::SteppingCache;
use pyrograph_core::{CookCtx, FrameSource, NodeError, Value};
use pyrograph_nodes_particles::types::WindField;
use pyrograph_nodes_particles::wind::WindSampler;

use super::params::SimParams;
use super::state::SimState;
use super::step::{Setup, SimError, substep, substeps};
use crate::grid::{SimStats, Volume};
use crate::source::value::SourceError;
use crate::source::{Splat, VolumeSource};

/// Frames between kept checkpoints.
const CHECKPOINT_EVERY: usize = 8;
/// Bytes of checkpoints one clip keeps.
const CHECKPOINT_BUDGET: usize = 512 << 20;
/// Bytes of recently stepped frames one clip keeps for callers that waited for them.
const RECENT_BUDGET: usize = 256 << 20;

/// Why a frame could not be stepped.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// An emitter could not give its splats.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// An animated parameter or the wind could not be sampled.
    #[error(transparent)]
    Param(#[from] AnimError),
    /// The solver refused the step (the voxel budget, a diverged state).
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A node error met on the way (the cook cancelled between sub-steps), passed on as it is.
    #[error(transparent)]
    Node(#[from] NodeError),
}

impl From<StepError> for NodeError {
    fn from(e: StepError) -> Self {
        match e {
            StepError::Source(e) => e.into(),
            StepError::Param(e) => e.into(),
            // The voxel budget's message names its limit and how to raise it.
            StepError::Sim(e) => NodeError::msg(e.to_string()),
            StepError::Node(e) => e,
        }
    }
}

/// Everything a simulation reads besides its state.
pub struct Simulation {
    /// The parameters (animated ones sampled per sub-step).
    pub params: SimParams,
    /// Frames per second.
    pub fps: f64,
    /// The emitters.
    pub sources: Vec<Arc<VolumeSource>>,
    /// The wind, if any.
    pub wind: Option<WindField>,
    /// Colliders, noise, bounds, solver settings.
    pub setup: Setup,
}

impl Simulation {
    /// Steps `state` over frame `frame` (1-based: the sub-steps covering seconds
    /// `(frame − 1) / fps .. frame / fps`).
    pub fn step_frame(&self, state: &mut SimState, frame: usize, ctx: &CookCtx) -> Result<(), StepError> {
        let fps = self.fps;
        let start = (frame - 1) as f64;
        let first = self.splats_at(start, ctx)?;
        let p = &self.params;
        let n = substeps(state, &first, (1.0 / fps) as f32, p.cfl, p.min_substeps, p.max_substeps);
        let dt = (1.0 / (fps * f64::from(n))) as f32;
        let mut stats = SimStats { substeps: n, ..SimStats::default() };
        // On a pool thread: a sub-step starts a few hundred parallel loops, and one started from
        // outside the pool is handed over to it and waited for (two thread wake-ups each).
        rayon::scope(|_| self.substeps(state, (start, n, dt), &first, &mut stats, ctx))?;
        state.stats = stats;
        Ok(())
    }

    /// Every emitter's splats at frame time `t`.
    fn splats_at(&self, t: f64, ctx: &CookCtx) -> Result<Vec<Splat>, SourceError> {
        let mut all = Vec::new();
        for s in &self.sources {
            all.extend(s.splats(t, self.fps, ctx)?);
        }
        Ok(all)
    }

    /// Steps `state` through the `n` sub-steps of `dt` seconds of the frame starting at frame
    /// time `start`, the first with the splats `first`.
    fn substeps(
        &self,
        state: &mut SimState,
        (start, n, dt): (f64, u32, f32),
        first: &[Splat],
        stats: &mut SimStats,
        ctx: &CookCtx,
    ) -> Result<(), StepError> {
        let fps = self.fps;
        let p = &self.params;
        let still = match &self.wind {
            Some(w) if w.animation.is_none() => Some(WindSampler::at_rate(w, fps)),
            _ => None,
        };
        for s in 0..n {
            ctx.check_cancel()?;
            let t = start + f64::from(s) / f64::from(n);
            let splats = if s == 0 { first.to_vec() } else { self.splats_at(t, ctx)? };
            let step_params = p.at(t, fps)?;
            let sampled = match (&self.wind, &still) {
                (Some(w), None) => Some(WindSampler::at_rate(&w.at_frame(t, fps)?, fps)),
                _ => None,
            };
            let wind = still.as_ref().or(sampled.as_ref());
            let projection = substep(state, &self.setup, &step_params, &splats, wind, dt)?;
            stats.max_divergence = projection.max_divergence;
            stats.pressure_iterations = projection.iterations;
        }
        Ok(())
    }
}

/// Volumes of frames stepped while other callers waited for them, oldest dropped first beyond
/// [`RECENT_BUDGET`] (the newest is always kept).
#[derive(Default)]
struct Recent {
    by_frame: BTreeMap<usize, Arc<Volume>>,
    bytes: usize,
}

impl Recent {
    fn put(&mut self, frame: usize, v: &Arc<Volume>) {
        let size = |v: &Volume| v.topology.voxels() * 28 + 64;
        if self.by_frame.insert(frame, v.clone()).is_none() {
            self.bytes += size(v);
        }
        while self.bytes > RECENT_BUDGET && self.by_frame.len() > 1 {
            let Some((_, old)) = self.by_frame.pop_first() else { break };
            self.bytes -= size(&old);
        }
    }
}

/// A `Clip<Volume>` source. Frames are best asked for in order: a caller asking for a frame that
/// another caller is stepping through waits for it (running the pool's other work meanwhile)
/// instead of simulating it again from an earlier state.
pub struct VolumeFrames {
    frames: usize,
    sim: Simulation,
    cache: SteppingCache<SimState>,
    recent: Mutex<Recent>,
    waiting: AtomicUsize,
}

impl VolumeFrames {
    /// `frames` frames of `sim`, starting from an empty grid at voxel size `voxel_size`.
    pub fn new(sim: Simulation, frames: usize, voxel_size: f32) -> Self {
        let cache = SteppingCache::new(SimState::new(voxel_size), CHECKPOINT_EVERY, CHECKPOINT_BUDGET);
        VolumeFrames { frames, sim, cache, recent: Mutex::new(Recent::default()), waiting: AtomicUsize::new(0) }
    }

    /// Frames of simulation stepped so far.
    pub fn frames_stepped(&self) -> usize {
        self.cache.frames_stepped()
    }

    fn recent(&self, index: usize) -> Option<Arc<Volume>> {
        self.recent.lock().ok()?.by_frame.get(&index).cloned()
    }

    fn keep(&self, index: usize, v: &Arc<Volume>) {
        if let Ok(mut r) = self.recent.lock() {
            r.put(index, v);
        }
    }

    /// The volume at clip frame `index`.
    pub fn volume(&self, index: usize, ctx: &CookCtx) -> Result<Arc<Volume>, NodeError> {
        self.waiting.fetch_add(1, Ordering::SeqCst);
        let waited = self.wait_for(index, ctx);
        self.waiting.fetch_sub(1, Ordering::SeqCst);
        if let Some(v) = waited? {
            return Ok(v);
        }
        let step = |s: &mut SimState, frame: usize| {
            self.sim.step_frame(s, frame, ctx)?;
            // A frame on the way, which a waiting caller may want.
            if frame != index + 1 && self.waiting.load(Ordering::SeqCst) > 0 {
                self.keep(frame - 1, &Arc::new(s.snapshot()));
            }
            Ok(())
        };
        let v = self.cache.at(index + 1, ctx, step, |s| Arc::new(s.snapshot()))?;
        self.keep(index, &v);
        Ok(v)
    }

    /// Waits while another caller steps from a frame at or before `index`; the volume, if it
    /// stepped through it and kept it.
    fn wait_for(&self, index: usize, ctx: &CookCtx) -> Result<Option<Arc<Volume>>, NodeError> {
        loop {
            if let Some(v) = self.recent(index) {
                return Ok(Some(v));
            }
            if !self.cache.busy_before(index + 1) {
                return Ok(None);
            }
            ctx.check_cancel()?;
            if !matches!(rayon::yield_now(), Some(rayon::Yield::Executed)) {
                std::thread::sleep(Duration::from_micros(200));
            }
        }
    }
}

impl FrameSource for VolumeFrames {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::custom(self.volume(index, ctx)?))
    }
}
