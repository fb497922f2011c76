//! Playing a preset in the editor's preview as an artist does (issue 45): the real app over the
//! real cook worker, driven the way eframe drives it — a UI pass whenever egui was asked to
//! repaint (the worker's "frame ready" ping, the player's timer), at most once per refresh of a
//! 60 Hz display (vsync), never busy-looping, so the cook has the cores a window would leave it. Each pass is the editor's whole egui pass plus
//! tessellation at 1600×1000, and a new preview frame is turned into an egui texture (the
//! `TextureHandle::set` of the app; the GPU's copy of its 0.9 MB is not in it: there is no GPU).
//!
//!     cargo bench -p pyrograph-editor --bench playback [-- --loops N] [-- --realtime] [-- --volume]
//!
//! For each preset (campfire, candles; 48 frames at 640×360 each), it opens the graph, selects the
//! node the graph writes, waits for frame 0, then presses Play and counts, per loop through the
//! clip, the frames shown, the loop's frames per second and the frames dropped. Loop 1 is cold
//! (every frame renders); later loops replay frames from the editor's 1 GiB frame cache.
//! By default real time is off (every frame shown as soon as it has cooked: how fast the preset
//! can play); `--realtime` plays at the clip's rate, dropping frames the cook is late for.
//!
//! `--volume` plays the campfire-with-smoke preset's `volume.render` (node `view`, at the preset's
//! 256×320) instead: loop 1 simulates and renders, then the render's exposure is nudged (as an
//! artist adjusting the look does), so loop 2 renders every frame again from the simulation the
//! editor has cached, and loop 3 replays the frame cache.

use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use eframe::egui;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{FrameCache, ParamValue};

/// A 60 Hz display's refresh period: the shortest time between two UI passes.
const VSYNC: Duration = Duration::from_micros(16_667);

/// When the next UI pass is due: eframe's repaint requests, as the app would get them.
#[derive(Default)]
struct Wake {
    due: Mutex<Option<Instant>>,
    cv: Condvar,
}

impl Wake {
    fn request(&self, delay: Duration) {
        let when = Instant::now() + delay;
        let mut due = self.due.lock().unwrap();
        *due = Some(due.map_or(when, |d| d.min(when)));
        self.cv.notify_all();
    }

    /// Sleeps until a pass is due (or `limit` passes) and takes the request.
    fn wait(&self, limit: Instant) {
        let mut due = self.due.lock().unwrap();
        loop {
            let now = Instant::now();
            match *due {
                Some(d) if d <= now => break,
                _ if now >= limit => break,
                Some(d) => due = self.cv.wait_timeout(due, d.min(limit) - now).unwrap().0,
                None => due = self.cv.wait_timeout(due, limit - now).unwrap().0,
            }
        }
        *due = None;
    }
}

struct Ui {
    ctx: egui::Context,
    app: EditorApp,
    wake: Arc<Wake>,
    born: Instant,
    passes: u64,
    pass_time: Duration,
    /// Where texture uploads are copied to (reused, as a driver's staging buffer is).
    uploaded: Vec<u8>,
}

impl Ui {
    fn new(editor: Editor) -> Self {
        let ctx = egui::Context::default();
        let wake = Arc::new(Wake::default());
        let w = wake.clone();
        ctx.set_request_repaint_callback(move |info| w.request(info.delay));
        Ui {
            ctx,
            app: EditorApp::new(editor),
            wake,
            born: Instant::now(),
            passes: 0,
            pass_time: Duration::ZERO,
            uploaded: Vec::new(),
        }
    }

    fn pass(&mut self) {
        let start = Instant::now();
        self.passes += 1;
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1600.0, 1000.0))),
            time: Some(self.born.elapsed().as_secs_f64()),
            ..Default::default()
        };
        let app = &mut self.app;
        let out = self.ctx.run_ui(input, |ui| app.ui(ui));
        std::hint::black_box(self.ctx.tessellate(out.shapes, out.pixels_per_point).len());
        // What a renderer uploads: the new textures' pixels, copied as glTexImage2D reads them.
        let mut delta = out.textures_delta;
        for d in delta.set.values().flatten() {
            let egui::ImageData::Color(image) = &d.image;
            self.uploaded.clear();
            self.uploaded.extend_from_slice(image.as_raw());
            std::hint::black_box(&self.uploaded);
        }
        delta.clear();
        self.pass_time += start.elapsed();
    }

    /// Runs passes as repaints are asked for until `done` holds or `limit` passes.
    fn run_until(&mut self, limit: Duration, mut done: impl FnMut(&EditorApp) -> bool) -> bool {
        let end = Instant::now() + limit;
        loop {
            let started = Instant::now();
            self.pass();
            if done(&self.app) {
                return true;
            }
            if Instant::now() >= end {
                return false;
            }
            self.wake.wait(end);
            // Vsync: eframe's swap blocks until the display's next refresh, so passes come at
            // most at its rate however often a repaint is asked for.
            if let Some(rest) = (started + VSYNC).checked_duration_since(Instant::now()) {
                std::thread::sleep(rest);
            }
        }
    }

    /// The frame the preview shows, and the serial of the preview.
    fn shown(&self) -> (Option<usize>, u64) {
        (shown_frame(&self.app.editor), self.app.editor.preview_serial())
    }
}

/// The frame whose picture the preview shows.
fn shown_frame(ed: &Editor) -> Option<usize> {
    ed.preview().filter(|p| p.image.is_some()).and_then(|p| p.request.as_ref()).map(|r| r.frame)
}

struct LoopStats {
    shown: usize,
    seconds: f64,
    dropped: u64,
}

fn play(graph: &str, node: &str, loops: usize, realtime: bool, retouch: Option<(&str, f64)>) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs");
    let mut ed = Editor::with_default_registry();
    ed.add_preset_dir(root.join("presets"));
    let opened = Instant::now();
    ed.begin_open(&root.join(graph));
    let mut ui = Ui::new(ed);
    ui.app.select_on_open = Some(node.to_string());
    let first = ui.run_until(Duration::from_secs(300), |app| {
        app.editor.preview().is_some_and(|p| p.image.is_some() && p.clip_len.is_some())
    });
    assert!(first, "{graph}: no preview of '{node}' within 300 s");
    let to_first = opened.elapsed().as_secs_f64();
    let (len, fps) = ui.app.editor.preview().map(|p| (p.clip_len.unwrap_or(0), p.fps)).unwrap();
    assert!(len > 1, "{graph}: '{node}' is not a clip");
    ui.app.playback.set_realtime(realtime);
    ui.app.playback.set_playing(true);
    let mut stats = Vec::new();
    for _ in 0..loops {
        let (passes, busy) = (ui.passes, ui.pass_time);
        let start = Instant::now();
        let dropped = ui.app.playback.dropped;
        let (mut last, mut serial) = ui.shown();
        let mut shown = 0usize;
        let ok = ui.run_until(Duration::from_secs(600), |app| {
            let frame = shown_frame(&app.editor);
            if app.editor.preview_serial() != serial {
                serial = app.editor.preview_serial();
                if frame.is_some() && frame != last {
                    shown += 1;
                    // A loop ends on the first frame shown after the clip wrapped around.
                    let wrapped = frame < last;
                    last = frame;
                    return wrapped;
                }
            }
            false
        });
        assert!(ok, "{graph}: a loop did not finish within 600 s");
        let seconds = start.elapsed().as_secs_f64();
        stats.push(LoopStats { shown, seconds, dropped: ui.app.playback.dropped - dropped });
        if let (1, Some((param, value))) = (stats.len(), retouch) {
            // A look change downstream of the simulation: the next loop re-renders from its cache.
            ui.app.editor.set_param(node, param, ParamValue::Float(value)).unwrap();
        }
        let per_pass = (ui.pass_time - busy).as_secs_f64() * 1e3 / (ui.passes - passes).max(1) as f64;
        eprintln!("  {graph} loop {}: {} passes, {per_pass:.2} ms a UI pass", stats.len(), ui.passes - passes);
    }
    ui.app.playback.set_playing(false);
    let mode = if realtime { format!("real time at {fps} fps") } else { "every frame, as fast as it cooks".into() };
    println!("{graph} ({node}, {len} frames at {fps} fps), {mode}; first frame after {to_first:.2} s");
    for (i, s) in stats.iter().enumerate() {
        let kind = match (i, retouch) {
            (0, _) => "cold",
            (1, Some(_)) => "re-rendered from the cached simulation",
            _ => "cached",
        };
        println!(
            "  loop {} ({kind}): {} frames shown in {:.3} s = {:.1} fps, {} dropped",
            i + 1,
            s.shown,
            s.seconds,
            s.shown as f64 / s.seconds,
            s.dropped
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let realtime = args.iter().any(|a| a == "--realtime");
    let loops = args
        .iter()
        .position(|a| a == "--loops")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(2usize)
        .max(1);
    // As the editor's binary sets it (main.rs): a 1 GiB frame cache, 8-bit frames packed.
    FrameCache::global().set_budget(1 << 30);
    FrameCache::global().set_compact(true);
    let threads = std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "all cores".into());
    println!("editor playback: rayon threads {threads}, UI 1600x1000");
    if args.iter().any(|a| a == "--volume") {
        play("presets/campfire-smoke.ron", "view", loops.max(3), realtime, Some(("exposure", 7.5)));
        return;
    }
    for (graph, node) in [("campfire.ron", "fire"), ("candles.ron", "render")] {
        play(graph, node, loops, realtime, None);
    }
}
