//! Background cooking: one worker thread owns the one [`Evaluator`] of the session, so its cache
//! survives edits and a parameter change re-cooks only the dirty downstream.
//!
//! The UI thread sends [`CookRequest`]s and polls [`CookOutcome`]s; it never waits for a cook.
//! A new request cancels the one in flight (its finished nodes stay cached). Previews are
//! converted to plain pixels on the worker, so the UI only uploads a texture. While the preview
//! plays, the worker reads ahead: once a frame's preview is sent it cooks the next frames of the
//! clip into the frame cache, so the request for the next frame, which the UI makes only when it
//! draws the current one (at most once a display refresh), finds it cooked.

use std::collections::BTreeMap;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use pyrograph_frontend::core::{
    CancelToken, Clip, CookCtx, CookResult, CookSettings, Evaluator, Graph, Image, PortType, Progress, Value,
};

/// A callback the worker calls when something changed (the app asks egui to repaint).
pub type Notify = Arc<dyn Fn() + Send + Sync>;

/// What the preview wants to see: one output of one node, at one frame of a clip.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PreviewRequest {
    /// Node id.
    pub node: String,
    /// Output index in the node's description.
    pub output: usize,
    /// Frame index, for clips.
    pub frame: usize,
}

/// One job for the worker.
#[derive(Clone)]
pub struct CookRequest {
    /// The validated graph to cook.
    pub graph: Arc<Graph>,
    /// Node ids whose cones are cooked.
    pub targets: Vec<String>,
    /// The output to turn into a preview, if any.
    pub preview: Option<PreviewRequest>,
    /// A second output to preview beside it (the B viewer of an A/B compare).
    pub compare: Option<PreviewRequest>,
    /// Render settings; `Some` for a render of the sinks.
    pub render: Option<CookSettings>,
}

/// RGBA8 pixels ready to upload as a texture.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewImage {
    /// `[width, height]`.
    pub size: [usize; 2],
    /// Unmultiplied RGBA bytes, row-major.
    pub rgba: Vec<u8>,
}

/// What the preview shows.
#[derive(Clone, Debug, Default)]
pub struct Preview {
    /// The request it answers.
    pub request: Option<PreviewRequest>,
    /// Pixels to show (an image, a mask, or the background under contours).
    pub image: Option<PreviewImage>,
    /// Polylines in image pixel coordinates (contours), drawn over `image`.
    pub contours: Vec<Vec<[f32; 2]>>,
    /// Size of the image the contours were traced in.
    pub contour_size: Option<[u32; 2]>,
    /// A one-line description of the value (`Image 64x64 Rgba`, `0.5`).
    pub summary: String,
    /// Frames in the clip, when the output is a clip.
    pub clip_len: Option<usize>,
    /// Frames per second of the clip.
    pub fps: f64,
    /// Why there is nothing to show.
    pub error: Option<String>,
}

/// The result of one request.
#[derive(Clone, Debug, Default)]
pub struct CookOutcome {
    /// Sequence number of the request (increasing).
    pub seq: u64,
    /// Node ids actually cooked (not served from the cache), in cook order.
    pub log: Vec<String>,
    /// Per-node errors of the cooked cone (cancellations excluded).
    pub node_errors: BTreeMap<String, String>,
    /// Per-node warnings reported in this cook (a clamped pose angle, an empty mask, ...);
    /// nodes served from the cache report none.
    pub node_warnings: BTreeMap<String, Vec<String>>,
    /// The preview, when one was asked for.
    pub preview: Option<Preview>,
    /// The B viewer's preview, when one was asked for.
    pub compare: Option<Preview>,
    /// Whether the cook was cancelled.
    pub cancelled: bool,
    /// Whether this was a render of the sinks.
    pub render: bool,
    /// Wall time of the cook.
    pub elapsed: Duration,
}

/// What the worker is doing, for the progress bar.
#[derive(Clone, Debug, Default)]
pub struct CookStatus {
    /// Whether a cook is running.
    pub running: bool,
    /// The node being cooked.
    pub node: Option<String>,
    /// Frames done / total of the node pulling a clip.
    pub frames: Option<(usize, usize)>,
    /// Nodes finished in this cook.
    pub nodes_done: usize,
    /// Nodes in the cone being cooked (an upper bound: cached nodes finish instantly).
    pub nodes_total: usize,
}

struct Job {
    seq: u64,
    request: CookRequest,
    cancel: CancelToken,
    /// Frames of the previewed clip to cook after the preview is sent.
    read_ahead: usize,
}

/// The handle the UI thread keeps.
pub struct Cooker {
    jobs: Option<Sender<Job>>,
    outcomes: Receiver<CookOutcome>,
    status: Arc<Mutex<CookStatus>>,
    notify: Arc<Mutex<Option<Notify>>>,
    current: Option<CancelToken>,
    read_ahead: usize,
    next_seq: u64,
    pending: u64,
    answered: u64,
    worker: Option<JoinHandle<()>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Default for Cooker {
    fn default() -> Self {
        Cooker::new()
    }
}

impl Cooker {
    /// Starts the worker thread with a fresh evaluator.
    pub fn new() -> Self {
        let (job_tx, job_rx) = channel::<Job>();
        let (out_tx, out_rx) = channel::<CookOutcome>();
        let status = Arc::new(Mutex::new(CookStatus::default()));
        let notify: Arc<Mutex<Option<Notify>>> = Arc::new(Mutex::new(None));
        let worker = {
            let status = status.clone();
            let notify = notify.clone();
            std::thread::Builder::new()
                .name("pyrograph-cook".into())
                .spawn(move || worker_loop(job_rx, out_tx, status, notify))
                .ok()
        };
        Cooker {
            jobs: Some(job_tx),
            outcomes: out_rx,
            status,
            notify,
            current: None,
            read_ahead: 0,
            next_seq: 1,
            pending: 0,
            answered: 0,
            worker,
        }
    }

    /// Sets the callback called when progress or a result arrives.
    pub fn set_notify(&self, notify: Notify) {
        *lock(&self.notify) = Some(notify);
    }

    /// How many frames after a previewed clip frame the worker cooks ahead (0: none; the app
    /// sets it while the preview plays).
    pub fn set_read_ahead(&mut self, frames: usize) {
        self.read_ahead = frames;
    }

    /// Queues a request, cancelling the one in flight. Returns its sequence number.
    pub fn submit(&mut self, request: CookRequest) -> u64 {
        self.cancel();
        let seq = self.next_seq;
        self.next_seq += 1;
        let cancel = CancelToken::new();
        self.current = Some(cancel.clone());
        if let Some(tx) = &self.jobs
            && tx.send(Job { seq, request, cancel, read_ahead: self.read_ahead }).is_ok()
        {
            self.pending = seq;
            lock(&self.status).running = true;
        }
        seq
    }

    /// Asks the running cook to stop.
    pub fn cancel(&mut self) {
        if let Some(c) = self.current.take() {
            c.cancel();
        }
    }

    /// The next finished outcome, if any.
    pub fn poll(&mut self) -> Option<CookOutcome> {
        match self.outcomes.try_recv() {
            Ok(o) => {
                self.answered = self.answered.max(o.seq);
                Some(o)
            }
            Err(TryRecvError::Empty | TryRecvError::Disconnected) => None,
        }
    }

    /// Whether the latest request has not been answered yet.
    pub fn is_busy(&self) -> bool {
        self.pending > self.answered
    }

    /// The sequence number of the latest request.
    pub fn latest(&self) -> u64 {
        self.pending
    }

    /// A copy of the worker's status.
    pub fn status(&self) -> CookStatus {
        lock(&self.status).clone()
    }
}

impl Drop for Cooker {
    fn drop(&mut self) {
        self.cancel();
        self.jobs = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

fn worker_loop(
    jobs: Receiver<Job>,
    outcomes: Sender<CookOutcome>,
    status: Arc<Mutex<CookStatus>>,
    notify: Arc<Mutex<Option<Notify>>>,
) {
    let mut eval = Evaluator::new();
    let ping = {
        let notify = notify.clone();
        move || {
            if let Some(n) = lock(&notify).clone() {
                n();
            }
        }
    };
    let mut queued: Option<Job> = None;
    while let Some(mut job) = queued.take().or_else(|| jobs.recv().ok()) {
        // Only the newest request matters; older ones were cancelled by the UI.
        while let Ok(newer) = jobs.try_recv() {
            job = newer;
        }
        let total = cone_size(&job.request);
        *lock(&status) = CookStatus { running: true, node: None, frames: None, nodes_done: 0, nodes_total: total };
        ping();
        let (outcome, clip) = run_job(&mut eval, &job, &status, &ping);
        {
            let mut s = lock(&status);
            s.node = None;
            s.frames = None;
            s.running = false;
        }
        let frame = outcome.preview.as_ref().and_then(|p| p.request.as_ref()).map(|r| r.frame);
        if outcomes.send(outcome).is_err() {
            return;
        }
        ping();
        if let (Some(clip), Some(frame)) = (clip.filter(|_| job.read_ahead > 0), frame) {
            match read_ahead(&clip, frame, job.read_ahead, &jobs) {
                Ok(next) => queued = next,
                Err(()) => return,
            }
        }
    }
}

/// Cooks frames `frame + 1 …= frame + count` (wrapping) of `clip` into the frame cache, stopping
/// as soon as a request arrives, which it returns (`Err` when the UI has gone). The frames are
/// not cancelled by that request: each is the next one a playing preview asks for, so a frame
/// under way is finished and found cooked; an edit waits at most for that one frame.
fn read_ahead(clip: &Clip, frame: usize, count: usize, jobs: &Receiver<Job>) -> Result<Option<Job>, ()> {
    let ctx = CookCtx::new();
    for k in 1..=count.min(clip.len().saturating_sub(1)) {
        match jobs.try_recv() {
            Ok(job) => return Ok(Some(job)),
            Err(TryRecvError::Disconnected) => return Err(()),
            Err(TryRecvError::Empty) => {}
        }
        // A frame that fails fails again, with its message, when the preview asks for it.
        let _ = clip.get((frame + k) % clip.len(), &ctx);
    }
    Ok(None)
}

fn cone_size(request: &CookRequest) -> usize {
    let graph = &request.graph;
    let mut seen = std::collections::HashSet::new();
    let mut stack: Vec<_> = request.targets.iter().filter_map(|t| graph.roots(t)).flatten().collect();
    while let Some(i) = stack.pop() {
        if seen.insert(i) {
            stack.extend(graph.upstream(i));
        }
    }
    seen.len()
}

/// Cooks one job: its outcome, and the previewed clip (for reading ahead).
fn run_job(
    eval: &mut Evaluator,
    job: &Job,
    status: &Arc<Mutex<CookStatus>>,
    ping: &(impl Fn() + Send + Sync + Clone + 'static),
) -> (CookOutcome, Option<Clip>) {
    let start = Instant::now();
    let progress = {
        let status = status.clone();
        let ping = ping.clone();
        let last_ping = Arc::new(Mutex::new(Instant::now()));
        Arc::new(move |p: &Progress| {
            {
                let mut s = lock(&status);
                match p {
                    Progress::NodeStarted { node } => {
                        s.node = Some(node.to_string());
                        s.frames = None;
                    }
                    Progress::NodeFinished { .. } => s.nodes_done += 1,
                    Progress::Frame { node, done, total } => {
                        s.node = Some(node.to_string());
                        s.frames = Some((*done, *total));
                    }
                }
            }
            // Repaint at most ~30 times a second from progress.
            let mut last = lock(&last_ping);
            if last.elapsed() > Duration::from_millis(30) {
                *last = Instant::now();
                ping();
            }
        })
    };
    let mut ctx = CookCtx::new().with_cancel(job.cancel.clone()).with_progress(progress);
    let request = &job.request;
    if let Some(settings) = &request.render {
        ctx = ctx.with_settings(settings.clone());
    }
    let targets: Vec<&str> = request.targets.iter().map(String::as_str).collect();
    let mut outcome = CookOutcome { seq: job.seq, render: request.render.is_some(), ..CookOutcome::default() };
    let mut clip = None;
    match eval.cook(&request.graph, &targets, &ctx) {
        Ok(result) => {
            for (node, err) in result.errors() {
                if err.is_cancelled() {
                    outcome.cancelled = true;
                } else {
                    outcome.node_errors.insert(node.to_string(), err.to_string());
                }
            }
            if let Some(pr) = &request.preview {
                if let Ok(Value::Clip(c)) = output_value(&result, &pr.node, pr.output) {
                    clip = Some(c);
                }
                if let Some(b) = &request.compare {
                    outcome.compare = Some(make_preview(&request.graph, &result, b, &ctx));
                }
                let preview = make_preview(&request.graph, &result, pr, &ctx);
                if preview.error.as_deref().is_some_and(|e| e.contains("cancelled")) {
                    outcome.cancelled = true;
                }
                outcome.preview = Some(preview);
            }
        }
        Err(e) => {
            outcome.cancelled = e.is_cancelled();
            if let Some(pr) = &request.preview {
                outcome.preview = Some(Preview { request: Some(pr.clone()), error: Some(e.to_string()), ..Preview::default() });
            }
        }
    }
    if job.cancel.is_cancelled() {
        outcome.cancelled = true;
    }
    outcome.log = eval.take_log();
    for w in ctx.warnings() {
        outcome.node_warnings.entry(w.node.as_deref().unwrap_or_default().to_string()).or_default().push(w.message);
    }
    outcome.elapsed = start.elapsed();
    (outcome, clip)
}

/// The value of output `port` of `node` in a cook result.
fn output_value(result: &CookResult, node: &str, port: usize) -> Result<Value, String> {
    let values = match result.node(node) {
        Some(Ok(v)) => v,
        Some(Err(e)) => return Err(e.to_string()),
        None => return Err(format!("node '{node}' was not cooked")),
    };
    values.get(port).cloned().ok_or_else(|| format!("node '{node}' has no output #{port}"))
}

fn make_preview(graph: &Graph, result: &CookResult, pr: &PreviewRequest, ctx: &CookCtx) -> Preview {
    let mut preview = Preview { request: Some(pr.clone()), ..Preview::default() };
    let value = match output_value(result, &pr.node, pr.output) {
        Ok(v) => v,
        Err(e) => {
            preview.error = Some(e);
            return preview;
        }
    };
    preview.summary = value.summary();
    let frame_value = match &value {
        Value::Clip(clip) => {
            preview.clip_len = Some(clip.len());
            preview.fps = clip.fps();
            if clip.is_empty() {
                preview.error = Some("the clip is empty".into());
                return preview;
            }
            let frame = pr.frame.min(clip.len() - 1);
            match clip.get(frame, ctx) {
                Ok(v) => v,
                Err(e) => {
                    preview.error = Some(e.to_string());
                    return preview;
                }
            }
        }
        other => other.clone(),
    };
    fill_preview(&mut preview, &frame_value);
    if matches!(frame_value, Value::Contours(_)) {
        // Draw contours over the nearest upstream image or mask, at the same frame.
        if let Some(bg) = upstream_image(graph, result, &pr.node, pr.frame, ctx) {
            preview.image = Some(bg);
        }
    }
    preview
}

fn fill_preview(preview: &mut Preview, value: &Value) {
    match value {
        Value::Image(img) => preview.image = Some(image_to_rgba8(img)),
        Value::Mask(m) => {
            let rgba = m.data().iter().flat_map(|&v| [v, v, v, 255]).collect();
            preview.image = Some(PreviewImage { size: [m.width() as usize, m.height() as usize], rgba });
        }
        Value::Contours(c) => {
            preview.contour_size = Some([c.width, c.height]);
            preview.contours = c.contours.iter().map(|k| k.points.clone()).collect();
        }
        Value::Clip(_) => {}
        other => preview.summary = other.summary(),
    }
}

fn upstream_image(graph: &Graph, result: &CookResult, node: &str, frame: usize, ctx: &CookCtx) -> Option<PreviewImage> {
    let mut queue: std::collections::VecDeque<_> = graph.roots(node)?.into_iter().flat_map(|r| graph.upstream(r)).collect();
    let mut seen = std::collections::HashSet::new();
    while let Some(idx) = queue.pop_front() {
        if !seen.insert(idx) {
            continue;
        }
        let gn = graph.node(idx);
        for (port, ty) in gn.out_types.iter().enumerate() {
            let elem = ty.clip_element().unwrap_or(ty);
            if matches!(elem, PortType::Image | PortType::Mask)
                && let Ok(v) = output_value(result, &gn.id, port)
            {
                let v = match v {
                    Value::Clip(c) if !c.is_empty() => c.get(frame.min(c.len() - 1), ctx).ok()?,
                    v => v,
                };
                let mut p = Preview::default();
                fill_preview(&mut p, &v);
                if p.image.is_some() {
                    return p.image;
                }
            }
        }
        queue.extend(graph.upstream(idx));
    }
    None
}

/// Converts an image to RGBA8 for display: composited over dark gray, clamped, and
/// downsampled (nearest) so neither side exceeds 2048 pixels.
pub fn image_to_rgba8(img: &Image) -> PreviewImage {
    let rgba = img.to_rgba();
    let (w, h) = (rgba.width() as usize, rgba.height() as usize);
    let step = w.max(h).div_ceil(2048).max(1);
    let (ow, oh) = (w.div_ceil(step), h.div_ceil(step));
    let data = rgba.data();
    let mut out = Vec::with_capacity(ow * oh * 4);
    let bg = 0.08f32;
    let to_u8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    for y in 0..oh {
        for x in 0..ow {
            let i = ((y * step) * w + x * step) * 4;
            let px = data.get(i..i + 4).unwrap_or(&[0.0, 0.0, 0.0, 0.0]);
            let a = if px[3].is_finite() { px[3].clamp(0.0, 1.0) } else { 0.0 };
            for c in &px[..3] {
                let c = if c.is_finite() { *c } else { 0.0 };
                out.push(to_u8(c * a + bg * (1.0 - a)));
            }
            out.push(255);
        }
    }
    PreviewImage { size: [ow, oh], rgba: out }
}
