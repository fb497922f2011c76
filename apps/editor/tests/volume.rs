//! A volume simulation in the editor: playing its preview shows each frame as the simulation
//! steps to it, in order, while the window keeps drawing.

use std::sync::Arc;
use std::time::{Duration, Instant};

use eframe::egui;
use egui_kittest::Harness;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue, Registry};

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    let mut h = Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    h.run_steps(8);
    h
}

fn vec3(x: f64, y: f64, z: f64) -> ParamValue {
    ParamValue::List(vec![ParamValue::Float(x), ParamValue::Float(y), ParamValue::Float(z)])
}

/// A sphere of smoke rising for 16 frames, seen through volume.preview.
fn plume() -> GraphDoc {
    let mut doc = GraphDoc::new();
    doc.add_node(
        "source",
        NodeDoc::new("volume.source")
            .param("center", vec3(0.0, 0.3, 0.0))
            .param("radius", ParamValue::Float(0.25))
            .param("smoke_rate", ParamValue::Float(4.0)),
    );
    doc.add_node(
        "sim",
        NodeDoc::new("volume.simulate").param("frames", ParamValue::Int(16)).param("voxel_size", ParamValue::Float(0.08)),
    );
    doc.add_node(
        "view",
        NodeDoc::new("volume.preview")
            .param("width", ParamValue::Int(96))
            .param("height", ParamValue::Int(128))
            .param("center", vec3(0.0, 1.2, 0.0))
            .param("size", ParamValue::Float(3.0)),
    );
    doc.connect("source.source", "sim.source");
    doc.connect("sim.volume", "view.volume");
    doc
}

#[test]
fn a_playing_simulation_shows_its_frames_as_they_arrive_and_the_window_keeps_drawing() {
    let mut ed = Editor::new(Arc::new(pyrograph_frontend::registry()) as Arc<Registry>);
    ed.edit(None, |d| *d = plume());
    ed.select("view");
    let mut h = harness(EditorApp::new(ed));
    // Play starts on a clip that is there: wait for frame 0.
    let start = Instant::now();
    while h.state().editor.preview().and_then(|p| p.clip_len).is_none() && start.elapsed() < Duration::from_secs(60) {
        h.step();
        std::thread::sleep(Duration::from_millis(4));
    }
    h.state_mut().playback.set_realtime(false);
    h.state_mut().playback.set_playing(true);
    let (mut shown, mut times): (Vec<(usize, Vec<u8>)>, Vec<f64>) = (Vec::new(), Vec::new());
    let start = Instant::now();
    while shown.len() < 12 && start.elapsed() < Duration::from_secs(120) {
        let t = Instant::now();
        h.step();
        times.push(t.elapsed().as_secs_f64() * 1000.0);
        let preview = h.state().editor.preview().cloned();
        if let Some(p) = preview
            && let (Some(r), Some(image)) = (&p.request, &p.image)
            && shown.last().is_none_or(|(f, _)| *f != r.frame)
        {
            assert_eq!(p.clip_len, Some(16), "{:?}", p.error);
            shown.push((r.frame, image.rgba.clone()));
        }
        std::thread::sleep(Duration::from_millis(4));
    }
    let frames: Vec<usize> = shown.iter().map(|(f, _)| *f).collect();
    assert!(frames.len() >= 12, "frames arrived: {frames:?} in {:.1} s", start.elapsed().as_secs_f64());
    assert!(frames.windows(2).all(|w| w[1] == w[0] + 1), "every frame, in order: {frames:?}");
    assert!(shown.windows(2).all(|w| w[0].1 != w[1].1), "each frame shows the smoke moved on");
    times.sort_by(f64::total_cmp);
    let (median, worst) = (times[times.len() / 2], times[times.len() - 1]);
    eprintln!("{} frames, {} draws, median {median:.1} ms, worst {worst:.1} ms", frames.len(), times.len());
    // Drawn between frames, not once per frame: at least two draws a frame (a frame of this
    // plume steps in a few milliseconds, so the count is not much more).
    assert!(times.len() > 2 * frames.len(), "the window drew between frames: {} draws for {} frames", times.len(), frames.len());
    assert!(median < 30.0 && worst < 150.0, "draws while simulating: median {median:.1} ms, worst {worst:.1} ms");
}
