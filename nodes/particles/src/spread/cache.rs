//! The stepping cache behind `particles.fire_spread`'s clip: a [`SteppingCache`] of [`Spread`]s.

use std::sync::Arc;

use pyrograph_core::stepping::{Checkpoint, SteppingCache};
use pyrograph_core::{CookCtx, FrameSource, NodeError, Value};

use super::front::{Spread, spread_wind};
use crate::types::WindField;

/// Frames between kept checkpoints of the stepping cache.
const CHECKPOINT_EVERY: usize = 16;
/// Bytes of checkpoints kept per clip.
const CHECKPOINT_BUDGET: usize = 256 << 20;

impl Checkpoint for Spread {
    fn bytes(&self) -> usize {
        Spread::bytes(self)
    }
}

/// A `Clip<SpreadState>` source: frame n after frame n − 1 costs one frame of steps.
pub struct SpreadSource {
    wind: WindField,
    frames: usize,
    substeps: usize,
    fps: f32,
    cache: SteppingCache<Spread>,
}

impl SpreadSource {
    /// A source of `frames` frames at `fps`, each `substeps` steps, frame 0 at ignition.
    pub fn new(initial: Spread, wind: WindField, frames: usize, fps: f32, substeps: usize) -> Self {
        let cache = SteppingCache::new(initial, CHECKPOINT_EVERY, CHECKPOINT_BUDGET);
        SpreadSource { wind, frames, substeps: substeps.max(1), fps, cache }
    }

    /// `finish` of the simulation at frame `index`.
    fn with_spread<R>(&self, index: usize, ctx: &CookCtx, finish: impl FnOnce(&Spread) -> R) -> Result<R, NodeError> {
        let still = spread_wind(&self.wind);
        let (fps, substeps) = (f64::from(self.fps), self.substeps);
        let dt = 1.0 / (self.fps * substeps as f32);
        // Stepping to frame `frame` covers (frame − 1, frame]; each sub-step samples the animated
        // K and wind at its start, so a gust or a change of K reaches the front when it happens.
        let step = |sim: &mut Spread, frame: usize| {
            for s in 0..substeps {
                let t = frame as f64 - 1.0 + s as f64 / substeps as f64;
                sim.follow(t, fps)?;
                if self.wind.animation.is_some() {
                    sim.step(dt, &spread_wind(&self.wind.at_frame(t, fps)?));
                } else {
                    sim.step(dt, &still);
                }
            }
            Ok(())
        };
        self.cache.at(index, ctx, step, finish)
    }

    /// The simulation at frame `index`.
    pub fn spread(&self, index: usize, ctx: &CookCtx) -> Result<Spread, NodeError> {
        self.with_spread(index, ctx, Spread::clone)
    }
}

impl FrameSource for SpreadSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::custom(Arc::new(self.with_spread(index, ctx, Spread::state)?)))
    }
}
