//! Big and hostile documents in the editor: a chain of 100,000 nodes and an include bomb open on
//! a loader thread while frames keep being drawn, the canvas holds a bounded part of a big
//! graph (culling), and a refused graph opens with the error in the status line and on the node.

use std::path::{Path, PathBuf};

use std::time::{Duration, Instant};

use eframe::egui;
use egui_kittest::Harness;
use pyrograph_editor::culling::MAX_HELD;
use pyrograph_editor::{Editor, EditorApp};

fn chain(dir: &Path, n: usize) -> PathBuf {
    let path = dir.join("chain.ron");
    std::fs::write(&path, pyrograph_testing::chain_ron(n)).unwrap();
    path
}

/// Opens `file` through the app as the File menu does, drawing frames until it is adopted;
/// returns the harness, how many frames were drawn meanwhile and the slowest frame.
fn open(file: &Path) -> (Harness<'static, EditorApp>, usize, Duration) {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut h = Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), {
        let mut app = EditorApp::new(ed);
        app.editor.begin_open(file);
        app
    });
    let (mut frames, mut slowest) = (0, Duration::ZERO);
    let started = Instant::now();
    while h.state().editor.opening().is_some() {
        let t = Instant::now();
        h.run_steps(1);
        slowest = slowest.max(t.elapsed());
        frames += 1;
        std::thread::sleep(Duration::from_millis(2));
        assert!(started.elapsed() < Duration::from_secs(120), "the open never finished");
    }
    for _ in 0..6 {
        let t = Instant::now();
        h.run_steps(1);
        eprintln!("frame after open: {:?}", t.elapsed());
        slowest = slowest.max(t.elapsed());
    }
    (h, frames, slowest)
}

#[test]
fn a_chain_of_100000_nodes_opens_while_frames_are_drawn_and_the_canvas_holds_a_bounded_part() {
    let dir = tempfile::tempdir().unwrap();
    let file = chain(dir.path(), 100_000);
    let (mut h, frames, slowest) = open(&file);
    eprintln!("100,000-node chain: {frames} frames drawn while it opened, slowest frame {slowest:?}");
    assert!(frames >= 2, "the window kept drawing while the file was read ({frames} frames)");
    let ed = &h.state().editor;
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics.first());
    assert_eq!(ed.validation().graph.as_ref().map(|g| g.node_count()), Some(100_000));
    assert_eq!(ed.path(), Some(file.as_path()));
    let held = h.state().canvas.node_ids().len();
    assert!(held > 0 && held <= MAX_HELD, "the canvas holds {held} nodes");
    assert_eq!(h.state().canvas.culled.map(|c| c.1), Some(100_000));
    // An edit re-validates the whole graph on the UI thread (printed, not asserted: TESTING.md).
    let t = Instant::now();
    h.state_mut().editor.edit(None, |d| d.set_param("n5", "b", pyrograph_frontend::core::ParamValue::Float(2.0))).unwrap();
    h.run_steps(1);
    eprintln!("100,000-node chain: one parameter edit and its frame took {:?}", t.elapsed());
    assert!(h.state().editor.is_dirty());
    // Panning far along the chain brings other nodes in, still a bounded number.
    let before: std::collections::HashSet<String> = h.state().canvas.node_ids().into_iter().collect();
    h.event(egui::Event::PointerMoved(egui::pos2(500.0, 450.0)));
    for _ in 0..30 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(-3000.0, 0.0),
            modifiers: egui::Modifiers::NONE,
            phase: egui::TouchPhase::Move,
        });
        h.run_steps(1);
    }
    let after: std::collections::HashSet<String> = h.state().canvas.node_ids().into_iter().collect();
    assert!(after.len() <= MAX_HELD && !after.is_empty() && after != before, "{} held", after.len());
}

#[test]
fn an_include_bomb_opens_with_the_node_limit_error_shown() {
    let dir = tempfile::tempdir().unwrap();
    let file = pyrograph_testing::include_bomb(dir.path(), 30, false);
    let (h, _, slowest) = open(&file);
    eprintln!("include bomb: slowest frame {slowest:?}");
    let ed = &h.state().editor;
    let status = ed.status().map(|s| s.text.clone()).unwrap_or_default();
    assert!(status.contains("1 problem(s)") && status.contains("more than the 1000000 pyrograph builds"), "{status}");
    assert!(ed.node_problems("a").iter().any(|p| p.contains("--max-nodes")), "{:?}", ed.node_problems("a"));
    assert_eq!(h.state().canvas.node_ids().len(), 3, "the two includes and their sum are on the canvas");
}
