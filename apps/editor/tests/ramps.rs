//! The ramp editor in the inspector, driven as an artist does it: a click on the gradient
//! bar adds a key with the colour the ramp has there, dragging a key's handle moves it along the
//! bar, and one undo takes the whole drag back.

use eframe::egui::{self, Event, Modifiers, PointerButton, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

use pyrograph_editor::gradient::read_keys;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::GraphDoc;

const GRAPH: &str = r#"(
    version: 4,
    nodes: {
        "card": (type: "imaging.constant_color", params: {"width": 8, "height": 4}, pos: (0, 0)),
        "tint": (type: "imaging.synthetic_coloring", params: {"mode": "ramp", "ramp": [(0, (0, 0, 0)), (1, (1, 0.5, 0))]}, pos: (320, 0)),
    },
    edges: [("card.image", "tint.source")],
)"#;

fn positions(app: &EditorApp) -> Vec<f64> {
    let v = app.editor.doc().node("tint").unwrap().params["ramp"].clone();
    read_keys(&v, 3).expect("the ramp stays typed keys").iter().map(|(p, _)| *p).collect()
}

fn press(h: &mut Harness<'_, EditorApp>, pos: Pos2, pressed: bool) {
    h.event(Event::PointerButton { pos, button: PointerButton::Primary, pressed, modifiers: Modifiers::NONE });
    h.run_steps(1);
}

#[test]
fn a_click_on_the_bar_adds_a_key_a_drag_moves_one_and_undo_takes_the_drag_back() {
    let mut ed = Editor::with_default_registry();
    ed.edit(None, |d| *d = GraphDoc::from_ron(GRAPH).unwrap());
    ed.seal();
    ed.auto_cook = false;
    let mut h = Harness::builder()
        .with_size(egui::vec2(1400.0, 900.0))
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), EditorApp::new(ed));
    h.run_steps(8);
    let node = h.state().canvas.node_screen_rect("tint").expect("tint on screen");
    h.event(Event::PointerMoved(node.center()));
    h.run_steps(1);
    press(&mut h, node.center(), true);
    press(&mut h, node.center(), false);
    h.run_steps(3);
    assert_eq!(h.state().editor.current(), Some("tint"));

    // Click the bar a quarter of the way along.
    let bar = h.get_by_label("ramp ramp").rect();
    let at = Pos2::new(bar.left() + bar.width() * 0.25, bar.center().y);
    h.event(Event::PointerMoved(at));
    h.run_steps(1);
    press(&mut h, at, true);
    press(&mut h, at, false);
    h.run_steps(3);
    let p = positions(h.state());
    assert_eq!(p.len(), 3, "a key was added: {p:?} {:?} bar {bar:?}", h.state().editor.status().map(|s| s.text.clone()));
    assert!((p[1] - 0.25).abs() < 0.01, "where the bar was clicked: {p:?}");
    h.state_mut().editor.seal();

    // Drag the first key half-way along, a frame per small move.
    let from = h.get_by_label("key 1 of ramp").rect().center();
    let to = from + egui::vec2(bar.width() * 0.5, 0.0);
    h.event(Event::PointerMoved(from));
    h.run_steps(1);
    press(&mut h, from, true);
    for k in 1..=10 {
        h.event(Event::PointerMoved(from + (to - from) * (k as f32 / 10.0)));
        h.run_steps(1);
    }
    press(&mut h, to, false);
    h.run_steps(3);
    let p = positions(h.state());
    assert_eq!(p.len(), 3, "{p:?}");
    assert!((p[1] - 0.5).abs() < 0.02 && p[0] > 0.2, "the key moved past the added one, to the pointer: {p:?}");

    // One undo takes the whole drag back.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    let p = positions(h.state());
    assert!(p[0] == 0.0 && (p[1] - 0.25).abs() < 0.01 && p[2] == 1.0, "the keys are back: {p:?}");
}
