//! The context of a cook: cancellation, progress reporting and render settings. Its own
//! module, depending on nothing but errors, so node types, values and the frame cache can take a
//! `CookCtx` without reaching into the evaluator.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::NodeError;

/// What a long cook reports while it runs.
#[derive(Clone, Debug, PartialEq)]
pub enum Progress {
    /// A node started cooking.
    NodeStarted {
        /// Its id.
        node: Arc<str>,
    },
    /// A node finished (successfully or not).
    NodeFinished {
        /// Its id.
        node: Arc<str>,
        /// Whether it succeeded.
        ok: bool,
    },
    /// A node pulled one more frame of a clip.
    Frame {
        /// The node doing the pulling.
        node: Arc<str>,
        /// Frames done so far.
        done: usize,
        /// Frames in all.
        total: usize,
    },
}

/// A progress callback; called from worker threads.
pub type ProgressFn = Arc<dyn Fn(&Progress) + Send + Sync>;

/// A shared flag that stops a cook at the next node or frame boundary.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token that is not cancelled.
    pub fn new() -> Self {
        CancelToken::default()
    }
    /// Asks running cooks to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
    /// Whether cancellation was asked for.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
    /// Clears the flag so the token can be used again.
    pub fn reset(&self) {
        self.0.store(false, Ordering::SeqCst);
    }
}

/// Settings of one render that sinks (writers) obey.
#[derive(Clone, Debug, Default)]
pub struct CookSettings {
    /// Frames to write (`--frames 0-99`, `1,5,9-12`, a farm task's chunk); all when `None`.
    pub frames: Option<crate::frames::FrameSet>,
    /// Leave frames whose files exist alone (`--skip-existing`): a re-queued task redoes only
    /// what is missing. Files are written atomically, so an existing file is a whole one.
    pub skip_existing: bool,
    /// Replace existing files even where a writer's `overwrite` parameter is off.
    pub overwrite: bool,
    /// Folder for scratch files of out-of-core work (`--cache-dir`); the system's temp folder
    /// when `None`.
    pub cache_dir: Option<std::path::PathBuf>,
    /// Folder of simulation caches (`--sim-cache`, a farm job's Simulate step): a simulation
    /// node reads its frames from there instead of stepping.
    pub sim_cache: Option<std::path::PathBuf>,
}

/// Something a node noticed that does not stop the cook but may make its result not what the
/// user wants ("the flame touches the bottom edge in 87 % of frames"), with what to change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// The node that reported it.
    pub node: Option<Arc<str>>,
    /// What it noticed.
    pub message: String,
}

/// Context of a cook: cancellation, progress, render settings and the node being cooked.
#[derive(Clone, Default)]
pub struct CookCtx {
    cancel: CancelToken,
    progress: Option<ProgressFn>,
    settings: Arc<CookSettings>,
    node: Option<Arc<str>>,
    written: Arc<std::sync::Mutex<Vec<std::path::PathBuf>>>,
    warnings: Arc<std::sync::Mutex<Vec<Warning>>>,
    frame_log: Option<Arc<std::sync::Mutex<FrameLog>>>,
}

/// The `(node, frame)` pairs per-frame nodes computed, in order.
type FrameLog = Vec<(Arc<str>, usize)>;

impl CookCtx {
    /// A context with no progress reporting that is never cancelled.
    pub fn new() -> Self {
        CookCtx::default()
    }
    /// Uses `token` for cancellation.
    pub fn with_cancel(mut self, token: CancelToken) -> Self {
        self.cancel = token;
        self
    }
    /// Reports progress to `f`.
    pub fn with_progress(mut self, f: ProgressFn) -> Self {
        self.progress = Some(f);
        self
    }
    /// Uses render settings.
    pub fn with_settings(mut self, settings: CookSettings) -> Self {
        self.settings = Arc::new(settings);
        self
    }
    /// Records every frame a per-frame node computes (not served from the frame cache), for
    /// recompute tests; off by default, since a long render would grow the log with its length.
    pub fn with_frame_log(mut self) -> Self {
        self.frame_log = Some(Arc::default());
        self
    }
    /// Notes that the node being cooked computed frame `frame` (when the frame log is on).
    pub fn log_frame(&self, frame: usize) {
        if let (Some(log), Some(node)) = (&self.frame_log, &self.node)
            && let Ok(mut l) = log.lock()
        {
            l.push((node.clone(), frame));
        }
    }
    /// Takes the `(node, frame)` pairs computed since the last take, in the order they were
    /// computed (empty without [`CookCtx::with_frame_log`]).
    pub fn take_frame_log(&self) -> Vec<(String, usize)> {
        let Some(log) = &self.frame_log else { return Vec::new() };
        log.lock().map(|mut l| l.drain(..).map(|(n, f)| (n.to_string(), f)).collect()).unwrap_or_default()
    }
    /// The render settings.
    pub fn settings(&self) -> &CookSettings {
        &self.settings
    }
    /// The cancellation token.
    pub fn cancel_token(&self) -> &CancelToken {
        &self.cancel
    }
    /// `Err(Cancelled)` once cancellation was asked for.
    pub fn check_cancel(&self) -> Result<(), NodeError> {
        if self.cancel.is_cancelled() { Err(NodeError::Cancelled) } else { Ok(()) }
    }
    /// Notes a file a writer has finished writing (for the render's manifest).
    pub fn record_written(&self, path: &std::path::Path) {
        if let Ok(mut w) = self.written.lock() {
            w.push(path.to_path_buf());
        }
    }
    /// The files writers finished in cooks with this context (and contexts made from it), in
    /// the order they were finished.
    pub fn written(&self) -> Vec<std::path::PathBuf> {
        self.written.lock().map(|w| w.clone()).unwrap_or_default()
    }
    /// Reports a warning for the node being cooked; the same warning of the same node is kept
    /// once, however many times it is reported (a per-frame node may report it every frame).
    pub fn warn(&self, message: impl Into<String>) {
        let warning = Warning { node: self.node.clone(), message: message.into() };
        if let Ok(mut w) = self.warnings.lock()
            && !w.contains(&warning)
        {
            w.push(warning);
        }
    }
    /// The warnings of cooks with this context (and contexts made from it), in the order they
    /// were first reported. Nodes served from a cache do not report theirs again.
    pub fn warnings(&self) -> Vec<Warning> {
        self.warnings.lock().map(|w| w.clone()).unwrap_or_default()
    }
    /// The id of the node being cooked, if any.
    pub fn node_id(&self) -> Option<&str> {
        self.node.as_deref()
    }
    /// Reports per-frame progress of the current node.
    pub fn frame_progress(&self, done: usize, total: usize) {
        if let (Some(f), Some(node)) = (&self.progress, &self.node) {
            f(&Progress::Frame { node: node.clone(), done, total });
        }
    }
    pub(crate) fn report(&self, p: Progress) {
        if let Some(f) = &self.progress {
            f(&p);
        }
    }
    /// This context as node `id` uses it: its frame progress is reported under that id (front
    /// ends pulling a clip's frames report them for the node that made the clip).
    pub fn for_node(&self, id: &Arc<str>) -> CookCtx {
        CookCtx { node: Some(id.clone()), ..self.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_name_their_node_and_are_kept_once() {
        let ctx = CookCtx::new();
        let crop = ctx.for_node(&Arc::from("crop"));
        crop.warn("the flame touches the bottom edge");
        crop.warn("the flame touches the bottom edge");
        ctx.for_node(&Arc::from("mask")).warn("the flame touches the bottom edge");
        let w = ctx.warnings();
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(w[0].node.as_deref(), Some("crop"));
        assert_eq!(w[1].node.as_deref(), Some("mask"));
    }
}
