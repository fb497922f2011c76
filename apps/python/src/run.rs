//! Running a cook from Python: the work runs on its own thread with the GIL released, while the
//! calling thread waits in short slices, forwards progress to the Python callback and checks
//! for Ctrl-C. A KeyboardInterrupt (or an exception raised by the callback) cancels the cook
//! through its `CancelToken`; the cook stops at the next node or frame, and the exception is
//! raised once the worker has let go of the evaluator, so the next cook starts clean.

use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use pyrograph_frontend::core::{CancelToken, CookCtx, CookSettings, Progress};

/// How long the waiting thread sleeps between checks for Ctrl-C and progress.
const SLICE: Duration = Duration::from_millis(20);

/// Runs `work` off the GIL with a context that reports to `progress` (a callable taking one
/// dict) and is cancelled by Ctrl-C.
pub fn run<T, F>(py: Python<'_>, settings: CookSettings, progress: Option<&Bound<'_, PyAny>>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&CookCtx) -> T + Send,
{
    let token = CancelToken::new();
    let (tx, rx) = mpsc::channel::<Progress>();
    let mut ctx = CookCtx::new().with_cancel(token.clone()).with_settings(settings);
    if progress.is_some() {
        ctx = ctx.with_progress(Arc::new(move |p: &Progress| {
            // The receiver outlives the cook; a send can only fail after it is gone.
            let _ = tx.send(p.clone());
        }));
    }
    std::thread::scope(|s| {
        let worker = s.spawn(move || work(&ctx));
        let mut pending: Option<PyErr> = None;
        let mut rx = rx;
        loop {
            let (back, events) = py.detach(move || {
                let mut events = Vec::new();
                if let Ok(first) = rx.recv_timeout(SLICE) {
                    events.push(first);
                    events.extend(rx.try_iter());
                }
                (rx, events)
            });
            rx = back;
            if pending.is_none()
                && let Some(cb) = progress
            {
                for e in &events {
                    if let Err(err) = event_dict(py, e).and_then(|d| cb.call1((d,))) {
                        token.cancel();
                        pending = Some(err);
                        break;
                    }
                }
            }
            if pending.is_none()
                && let Err(err) = py.check_signals()
            {
                token.cancel();
                pending = Some(err);
            }
            if worker.is_finished() {
                break;
            }
        }
        let joined = py.detach(|| worker.join());
        // Events sent after the last slice (the final frames) still reach the callback.
        if pending.is_none()
            && let Some(cb) = progress
        {
            for e in rx.try_iter() {
                if let Err(err) = event_dict(py, &e).and_then(|d| cb.call1((d,))) {
                    pending = Some(err);
                    break;
                }
            }
        }
        match (pending, joined) {
            (Some(err), _) => Err(err),
            (None, Ok(value)) => Ok(value),
            (None, Err(panic)) => {
                let what = panic
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| panic.downcast_ref::<&str>().copied())
                    .unwrap_or("unknown panic");
                Err(crate::errors::graph_error(py, None, None, &format!("internal error while cooking: {what}")))
            }
        }
    })
}

/// A progress event as the dict the callback receives: `event` is `"node_started"`,
/// `"node_finished"` (with `ok`) or `"frame"` (with `done` and `total`).
fn event_dict<'py>(py: Python<'py>, e: &Progress) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match e {
        Progress::NodeStarted { node } => {
            d.set_item("event", "node_started")?;
            d.set_item("node", &**node)?;
        }
        Progress::NodeFinished { node, ok } => {
            d.set_item("event", "node_finished")?;
            d.set_item("node", &**node)?;
            d.set_item("ok", *ok)?;
        }
        Progress::Frame { node, done, total } => {
            d.set_item("event", "frame")?;
            d.set_item("node", &**node)?;
            d.set_item("done", *done)?;
            d.set_item("total", *total)?;
        }
    }
    Ok(d)
}
