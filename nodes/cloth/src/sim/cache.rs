//! The stepping cache behind `cloth.mass_spring_flame`'s clip: a [`SteppingCache`] of
//! [`Simulation`]s plus the snapshots of recently passed frames.

use std::cell::Cell;
use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Mutex};

use pyrograph_core::stepping::{Checkpoint, SteppingCache};
use pyrograph_core::{CookCtx, FrameSource, NodeError, Value};

use super::simulation::Simulation;
use crate::state::ClothState;

/// Checkpoints of the full state are kept every this many frames (within [`CHECKPOINT_BUDGET`]).
pub const CHECKPOINT_EVERY: usize = 24;
/// Bytes of full-state checkpoints one clip keeps.
pub const CHECKPOINT_BUDGET: usize = 256 << 20;
/// Bytes of recently passed frame snapshots one clip keeps (for parallel pulls).
pub const SNAPSHOT_BUDGET: usize = 128 << 20;

impl Checkpoint for Simulation {
    fn bytes(&self) -> usize {
        Simulation::bytes(self)
    }
}

/// Snapshots of recently passed frames, oldest dropped first beyond [`SNAPSHOT_BUDGET`].
#[derive(Default)]
struct Snapshots {
    by_frame: BTreeMap<usize, Arc<ClothState>>,
    order: VecDeque<usize>,
    bytes: usize,
}

impl Snapshots {
    fn put(&mut self, frame: usize, s: &Arc<ClothState>) {
        if self.by_frame.contains_key(&frame) {
            return;
        }
        self.bytes += Value::custom(s.clone()).byte_size();
        self.by_frame.insert(frame, s.clone());
        self.order.push_back(frame);
        while self.bytes > SNAPSHOT_BUDGET && self.order.len() > 1 {
            let Some(old) = self.order.pop_front() else { break };
            if let Some(v) = self.by_frame.remove(&old) {
                self.bytes -= Value::custom(v).byte_size();
            }
        }
    }
}

/// A clip of cloth states backed by a stepping cache: frame `n` after frame `n − 1` costs one
/// frame of steps; an earlier frame restarts from the nearest checkpoint (or the start).
pub struct ClothSource {
    frames: usize,
    cache: SteppingCache<Simulation>,
    snapshots: Mutex<Snapshots>,
}

impl ClothSource {
    /// A source of `frames` frames starting from `initial` (frame 0 is the cloth at rest).
    pub fn new(initial: Simulation, frames: usize) -> Self {
        let cache = SteppingCache::new(initial, CHECKPOINT_EVERY, CHECKPOINT_BUDGET);
        ClothSource { frames, cache, snapshots: Mutex::new(Snapshots::default()) }
    }

    /// Frames of simulation stepped so far (each is all the sub-steps of one frame).
    pub fn frames_stepped(&self) -> usize {
        self.cache.frames_stepped()
    }

    fn lock(&self) -> Result<std::sync::MutexGuard<'_, Snapshots>, NodeError> {
        self.snapshots.lock().map_err(|_| NodeError::msg("the cloth cache was poisoned by an earlier panic"))
    }

    /// The state at `index`.
    pub fn state(&self, index: usize, ctx: &CookCtx) -> Result<Arc<ClothState>, NodeError> {
        if let Some(s) = self.lock()?.by_frame.get(&index) {
            return Ok(s.clone());
        }
        // The snapshot of the last frame stepped, which is the one asked for.
        let last = Cell::new(None);
        let step = |sim: &mut Simulation, frame: usize| {
            sim.step_frame()?;
            let snap = Arc::new(sim.snapshot());
            self.lock()?.put(frame, &snap);
            last.set(Some(snap));
            Ok(())
        };
        let snap = self.cache.at(index, ctx, step, |sim| last.take().unwrap_or_else(|| Arc::new(sim.snapshot())))?;
        self.lock()?.put(index, &snap);
        Ok(snap)
    }
}

impl FrameSource for ClothSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::custom(self.state(index, ctx)?))
    }
}
