//! UI frames per second of the canvas on generated graphs of 300 and 5,000 nodes, the way a user's hand
//! drives it: panning (scroll) and zooming (pinch / Ctrl+scroll), with every node in view and
//! zoomed in on a part. A frame is egui's whole UI pass over the editor plus tessellation into
//! triangles, the CPU work of one frame (the GPU's drawing is not included).

use criterion::{Criterion, criterion_group, criterion_main};
use eframe::egui;
use pyrograph_editor::layout::generated_graph;
use pyrograph_editor::{Editor, EditorApp};

struct Ui {
    ctx: egui::Context,
    app: EditorApp,
    frame: u64,
}

impl Ui {
    fn new(nodes: usize) -> Self {
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        let doc = generated_graph(nodes);
        ed.edit(None, |d| *d = doc);
        let mut app = EditorApp::new(ed);
        app.canvas.frame_all();
        let mut ui = Ui { ctx: egui::Context::default(), app, frame: 0 };
        for _ in 0..10 {
            ui.step(Vec::new());
        }
        ui
    }

    fn step(&mut self, events: Vec<egui::Event>) -> usize {
        self.frame += 1;
        let mut events = events;
        events.insert(0, egui::Event::PointerMoved(egui::pos2(500.0, 450.0)));
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1600.0, 1000.0))),
            time: Some(self.frame as f64 / 60.0),
            events,
            ..Default::default()
        };
        let app = &mut self.app;
        let out = self.ctx.run_ui(input, |ui| app.ui(ui));
        self.ctx.tessellate(out.shapes, out.pixels_per_point).len()
    }
}

fn canvas(c: &mut Criterion) {
    for nodes in [300, 5000] {
        graph_of(c, nodes);
    }
}

/// Pan and zoom with the whole graph in view, and pan zoomed in, on a generated graph of `nodes`.
fn graph_of(c: &mut Criterion, nodes: usize) {
    let mut group = c.benchmark_group(format!("editor_{nodes}_nodes"));
    group.sample_size(30);
    let mut ui = Ui::new(nodes);
    assert_eq!(ui.app.editor.doc().nodes.0.len(), nodes);
    // Every node is on the canvas up to the culling threshold; above it, the nearest ones.
    let held = ui.app.canvas.node_ids().len();
    assert!(held == nodes || held <= pyrograph_editor::culling::MAX_HELD, "{held} of {nodes} held");
    let mut k = 0u64;
    group.bench_function("pan_all_in_view", |b| {
        b.iter(|| {
            k += 1;
            let dx = if k % 60 < 30 { 8.0 } else { -8.0 };
            ui.step(vec![egui::Event::MouseWheel {
                unit: egui::MouseWheelUnit::Point,
                delta: egui::vec2(dx, 0.0),
                modifiers: egui::Modifiers::NONE,
                phase: egui::TouchPhase::Move,
            }])
        })
    });
    group.bench_function("zoom_all_in_view", |b| {
        b.iter(|| {
            k += 1;
            let z = if k % 40 < 20 { 1.02 } else { 1.0 / 1.02 };
            ui.step(vec![egui::Event::Zoom(z)])
        })
    });
    // Zoomed in on one corner: most nodes are off screen.
    let mut near = Ui::new(nodes);
    for _ in 0..60 {
        near.step(vec![egui::Event::Zoom(1.08)]);
    }
    group.bench_function("pan_zoomed_in", |b| {
        b.iter(|| {
            k += 1;
            let dy = if k % 60 < 30 { 8.0 } else { -8.0 };
            near.step(vec![egui::Event::MouseWheel {
                unit: egui::MouseWheelUnit::Point,
                delta: egui::vec2(0.0, dy),
                modifiers: egui::Modifiers::NONE,
                phase: egui::TouchPhase::Move,
            }])
        })
    });
    group.finish();
    let scale = ui.app.canvas.transform().scaling;
    eprintln!(
        "{nodes} nodes: all-in-view scale {scale:.3} ({held} held), zoomed-in scale {:.3} ({} held)",
        near.app.canvas.transform().scaling,
        near.app.canvas.node_ids().len()
    );
}

criterion_group!(benches, canvas);
criterion_main!(benches);
