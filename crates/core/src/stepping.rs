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
    /// Callers stepping right now: the frame each started from and the frame it steps to.
    in_flight: Vec<(usize, usize)>,
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
        let inner = Inner { current: None, checkpoints: BTreeMap::new(), bytes: 0, in_flight: Vec::new() };
        SteppingCache { initial, every: every.max(1), budget, inner: Mutex::new(inner), stepped: AtomicUsize::new(0) }
    }

    /// Frames stepped so far (calls of the step function).
    pub fn frames_stepped(&self) -> usize {
        self.stepped.load(Ordering::Relaxed)
    }

    fn lock(&self) -> Result<MutexGuard<'_, Inner<S>>, NodeError> {
        self.inner.lock().map_err(|_| NodeError::msg("the stepping cache was poisoned by an earlier panic"))
    }

    /// Whether a caller is stepping right now from a frame at or before `index`: a caller wanting
    /// frame `index` does better to wait for it (for the later state it leaves, or for the frame
    /// itself when it steps past it and the simulation keeps the frames it passes) than to step
    /// again from an earlier state.
    pub fn busy_before(&self, index: usize) -> bool {
        self.lock().is_ok_and(|c| c.in_flight.iter().any(|(from, _)| *from <= index))
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
            let picked = match c.current.take() {
                Some((f, s)) if f <= index => (f, s),
                other => {
                    c.current = other;
                    c.checkpoints
                        .range(..=index)
                        .next_back()
                        .map(|(f, s)| (*f, s.clone()))
                        .unwrap_or_else(|| (0, self.initial.clone()))
                }
            };
            c.in_flight.push((picked.0, index));
            picked
        };
        let flight = (frame, index);
        let result = self.advance(&mut frame, &mut state, index, ctx, &mut step);
        let mut c = self.lock()?;
        if let Some(k) = c.in_flight.iter().position(|f| *f == flight) {
            c.in_flight.swap_remove(k);
        }
        result?;
        let out = finish(&state);
        // Another caller may have left a later state meanwhile; keep the later one.
        if c.current.as_ref().is_none_or(|(f, _)| *f <= frame) {
            c.current = Some((frame, state));
        }
        Ok(out)
    }

    /// Steps `state` from `frame` to `index`, keeping checkpoints on the way.
    fn advance(
        &self,
        frame: &mut usize,
        state: &mut S,
        index: usize,
        ctx: &CookCtx,
        step: &mut impl FnMut(&mut S, usize) -> Result<(), NodeError>,
    ) -> Result<(), NodeError> {
        while *frame < index {
            ctx.check_cancel()?;
            step(state, *frame + 1)?;
            *frame += 1;
            self.stepped.fetch_add(1, Ordering::Relaxed);
            if (*frame).is_multiple_of(self.every) {
                let mut c = self.lock()?;
                let bytes = state.bytes();
                if !c.checkpoints.contains_key(frame) && c.bytes + bytes <= self.budget {
                    c.bytes += bytes;
                    c.checkpoints.insert(*frame, state.clone());
                }
            }
        }
        Ok(())
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
    fn a_caller_stepping_from_an_earlier_frame_is_seen_as_busy() {
        let cache = SteppingCache::new(Counter(Vec::new()), 4, 1 << 20);
        let ctx = CookCtx::default();
        assert!(!cache.busy_before(3));
        let seen = cache.at(
            6,
            &ctx,
            |_, _| {
                assert!(cache.busy_before(0) && cache.busy_before(9), "stepping from 0 is busy before every frame");
                Ok(())
            },
            |_| (),
        );
        assert!(seen.is_ok());
        assert!(!cache.busy_before(9), "nobody steps once it returned");
        let later = cache.at(
            8,
            &ctx,
            |_, _| {
                assert!(!cache.busy_before(5), "stepping from 6 is not busy before 5");
                Ok(())
            },
            |_| (),
        );
        assert!(later.is_ok());
        let _ = cache.at(12, &ctx, |_, f| if f == 10 { Err(NodeError::msg("diverged")) } else { Ok(()) }, |_| ());
        assert!(!cache.busy_before(20), "a failed step leaves no one in flight");
    }

    #[test]
    fn an_error_while_stepping_is_returned() {
        let cache = SteppingCache::new(Counter(Vec::new()), 4, 1 << 20);
        let e = cache.at(3, &CookCtx::default(), |_, f| if f == 2 { Err(NodeError::msg("diverged")) } else { Ok(()) }, |_| ());
        assert!(e.is_err());
    }
}
