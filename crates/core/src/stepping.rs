//! A checkpointed stepping cache for simulations that can only be advanced a frame at a time
//! (fire spread, mass-spring cloth): a clip backed by one serves frame `n` after frame `n − 1`
//! for the cost of one frame of steps, and an earlier frame from the nearest kept checkpoint
//! (or the start) instead of from frame 0.
//!
//! The simulation is taken out of the cache while a caller steps it, so no lock is held while
//! the stepping runs (it may use rayon, and other frames may be pulled in parallel).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use crate::ctx::CookCtx;
use crate::error::NodeError;

/// A simulation state a [`SteppingCache`] can keep.
pub trait Checkpoint: Clone + Send {
    /// Approximate bytes held, counted against the checkpoint budget.
    fn bytes(&self) -> usize;
}

struct Inner<S> {
    /// The last state reached and its frame.
    current: Option<(usize, S)>,
    checkpoints: BTreeMap<usize, S>,
    bytes: usize,
}

/// Frames of a simulation, stepped on demand from the nearest earlier state it holds.
pub struct SteppingCache<S> {
    initial: S,
    every: usize,
    budget: usize,
    inner: Mutex<Inner<S>>,
    stepped: AtomicUsize,
}

impl<S: Checkpoint> SteppingCache<S> {
    /// A cache whose frame 0 is `initial`, keeping a checkpoint every `every` frames while they
    /// fit in `budget` bytes.
    pub fn new(initial: S, every: usize, budget: usize) -> Self {
        let inner = Inner { current: None, checkpoints: BTreeMap::new(), bytes: 0 };
        SteppingCache { initial, every: every.max(1), budget, inner: Mutex::new(inner), stepped: AtomicUsize::new(0) }
    }

    /// Frames stepped so far (calls of the step function).
    pub fn frames_stepped(&self) -> usize {
        self.stepped.load(Ordering::Relaxed)
    }

    fn lock(&self) -> Result<MutexGuard<'_, Inner<S>>, NodeError> {
        self.inner.lock().map_err(|_| NodeError::msg("the stepping cache was poisoned by an earlier panic"))
    }

    /// `finish` of the state at frame `index`. `step` advances a state by one frame; it is given
    /// the frame it reaches. Cancellation is checked before every frame.
    pub fn at<R>(
        &self,
        index: usize,
        ctx: &CookCtx,
        mut step: impl FnMut(&mut S, usize) -> Result<(), NodeError>,
        finish: impl FnOnce(&S) -> R,
    ) -> Result<R, NodeError> {
        let (mut frame, mut state) = {
            let mut c = self.lock()?;
            match c.current.take() {
                Some((f, s)) if f <= index => (f, s),
                other => {
                    c.current = other;
                    c.checkpoints
                        .range(..=index)
                        .next_back()
                        .map(|(f, s)| (*f, s.clone()))
                        .unwrap_or_else(|| (0, self.initial.clone()))
                }
            }
        };
        while frame < index {
            ctx.check_cancel()?;
            step(&mut state, frame + 1)?;
            frame += 1;
            self.stepped.fetch_add(1, Ordering::Relaxed);
            if frame % self.every == 0 {
                let mut c = self.lock()?;
                let bytes = state.bytes();
                if !c.checkpoints.contains_key(&frame) && c.bytes + bytes <= self.budget {
                    c.bytes += bytes;
                    c.checkpoints.insert(frame, state.clone());
                }
            }
        }
        let out = finish(&state);
        let mut c = self.lock()?;
        // Another caller may have left a later state meanwhile; keep the later one.
        if c.current.as_ref().is_none_or(|(f, _)| *f <= frame) {
            c.current = Some((frame, state));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone)]
    struct Counter(Vec<usize>);

    impl Checkpoint for Counter {
        fn bytes(&self) -> usize {
            8 * self.0.len()
        }
    }

    #[test]
    fn sequential_frames_cost_one_step_and_earlier_ones_restart_from_a_checkpoint() {
        let cache = SteppingCache::new(Counter(Vec::new()), 4, 1 << 20);
        let ctx = CookCtx::default();
        let step = |s: &mut Counter, f: usize| {
            s.0.push(f);
            Ok(())
        };
        for k in 0..10 {
            assert_eq!(cache.at(k, &ctx, step, |s| s.0.clone()).unwrap(), (1..=k).collect::<Vec<_>>());
        }
        assert_eq!(cache.frames_stepped(), 9);
        // Frame 6 restarts from the checkpoint at 4: two steps.
        assert_eq!(cache.at(6, &ctx, step, |s| s.0.len()).unwrap(), 6);
        assert_eq!(cache.frames_stepped(), 11);
    }

    #[test]
    fn an_error_while_stepping_is_returned() {
        let cache = SteppingCache::new(Counter(Vec::new()), 4, 1 << 20);
        let e = cache.at(3, &CookCtx::default(), |_, f| if f == 2 { Err(NodeError::msg("diverged")) } else { Ok(()) }, |_| ());
        assert!(e.is_err());
    }
}
