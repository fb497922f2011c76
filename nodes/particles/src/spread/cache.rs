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
        let wind = spread_wind(&self.wind);
        let dt = 1.0 / (self.fps * self.substeps as f32);
        let step = |sim: &mut Spread, _| {
            for _ in 0..self.substeps {
                sim.step(dt, &wind);
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
