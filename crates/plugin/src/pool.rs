//! Workers shared by every plugin node of a registry: started on first use, at most `cap` at
//! once (the cook's threads each take one while they wait for Python, so per-frame plugin nodes
//! run on as many cores as the rest of the cook), a broken or cancelled one dropped and replaced
//! on the next request.

use std::sync::{Condvar, Mutex};
use std::time::Duration;

use pyrograph_core::CookCtx;

use crate::worker::{Launch, Worker, WorkerError};

/// The workers of one plugin set.
pub struct Pool {
    launch: Launch,
    cap: usize,
    state: Mutex<State>,
    freed: Condvar,
}

#[derive(Default)]
struct State {
    idle: Vec<Worker>,
    live: usize,
}

/// Gives a worker's place back if the code using it panics (the worker itself is dropped, and
/// so killed, while unwinding).
struct Seat<'a>(&'a Pool);

impl Drop for Seat<'_> {
    fn drop(&mut self) {
        self.0.retire();
    }
}

impl Pool {
    /// A pool of at most `cap` workers (at least one).
    pub fn new(launch: Launch, cap: usize) -> Pool {
        Pool { launch, cap: cap.max(1), state: Mutex::new(State::default()), freed: Condvar::new() }
    }

    /// Runs `f` on a worker: an idle one, a new one while under the cap, else the next one given
    /// back. A worker `f` leaves broken (killed on cancel, crashed) is retired, not given back.
    ///
    /// `beyond_cap` starts a worker even when the cap is reached: for a whole-clip node, whose
    /// worker waits while the frames it asks for are cooked, perhaps by plugin nodes upstream that
    /// need workers of their own; waiting for one of the capped workers could wait forever.
    pub fn with_worker<T>(
        &self,
        ctx: Option<&CookCtx>,
        beyond_cap: bool,
        f: impl FnOnce(&mut Worker) -> Result<T, WorkerError>,
    ) -> Result<T, WorkerError> {
        let mut worker = self.take(ctx, beyond_cap)?;
        let seat = Seat(self);
        let out = f(&mut worker);
        std::mem::forget(seat);
        self.give_back(worker);
        out
    }

    fn take(&self, ctx: Option<&CookCtx>, beyond_cap: bool) -> Result<Worker, WorkerError> {
        let poisoned = || WorkerError::Broken("the Python worker pool failed earlier".into());
        let mut state = self.state.lock().map_err(|_| poisoned())?;
        loop {
            if let Some(worker) = state.idle.pop() {
                return Ok(worker);
            }
            if state.live < self.cap || beyond_cap {
                state.live += 1;
                drop(state);
                let started = Worker::start(&self.launch, ctx);
                if started.is_err() {
                    self.retire();
                }
                return started;
            }
            if ctx.is_some_and(|c| c.cancel_token().is_cancelled()) {
                return Err(WorkerError::Cancelled);
            }
            state = self.freed.wait_timeout(state, Duration::from_millis(20)).map_err(|_| poisoned())?.0;
        }
    }

    fn retire(&self) {
        if let Ok(mut s) = self.state.lock() {
            s.live -= 1;
        }
        self.freed.notify_one();
    }

    fn give_back(&self, worker: Worker) {
        // A worker started beyond the cap is not kept once the cook that needed it is done.
        if worker.healthy()
            && let Ok(mut s) = self.state.lock()
            && s.live <= self.cap
        {
            s.idle.push(worker);
            drop(s);
            self.freed.notify_one();
            return;
        }
        drop(worker);
        self.retire();
    }
}
