//! Keyframing in the editor: key edits through `Editor` (one undo step each, a drag one step,
//! values outside the port's range refused), and through the UI as an artist does it — the key
//! toggle in the inspector, the playhead, the curve editor's handles, the key strip under the
//! scrubber, Delete and undo. The graph: a procedural flame clip into `imaging.bloom`, a per-frame
//! node whose `strength` (Float, 0..4) is sampled at each frame.

use eframe::egui::{self, Event, Modifiers, PointerButton, Pos2, accesskit::Role, accesskit::Toggled};
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
mod common;

use common::settle;
use pyrograph_editor::keys::KeyList;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{GraphDoc, ParamValue};

const GRAPH: &str = r#"(
    version: 4,
    nodes: {
        "flame": (type: "imaging.turbulence_flame", params: {"width": 48, "height": 64, "frames": 24, "octaves": 2}, pos: (0, 0)),
        "bloom": (type: "imaging.bloom", params: {"strength": 0.4, "sigma": 4.0, "passes": 2}, pos: (320, 0)),
    },
    edges: [("flame.clip", "bloom.image")],
)"#;

fn editor() -> Editor {
    let mut ed = Editor::with_default_registry();
    let doc = GraphDoc::from_ron(GRAPH).expect("the test graph parses");
    ed.edit(None, |d| *d = doc);
    ed.seal();
    assert!(ed.validation().diagnostics.is_empty(), "the graph checks: {:?}", ed.validation().diagnostics);
    ed
}

fn strength(ed: &Editor) -> ParamValue {
    ed.doc().node("bloom").unwrap().params["strength"].clone()
}

/// The keys of bloom.strength as (frame, value).
fn keys(ed: &Editor) -> Vec<(f64, f64)> {
    KeyList::read(&strength(ed)).map(|l| l.keys.iter().map(|k| (k.frame, k.value)).collect()).unwrap_or_default()
}

#[test]
fn key_edits_are_single_undo_steps_and_out_of_range_values_are_refused() {
    let mut ed = editor();
    ed.auto_cook = false;
    // A key on a constant: keys([(0, 0.4)]), the graph still checks; undo gives the constant back.
    assert!(ed.toggle_key("bloom", "strength", 0.0).unwrap());
    assert_eq!(keys(&ed), [(0.0, 0.4)]);
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    assert!(ed.undo());
    assert_eq!(strength(&ed), ParamValue::Float(0.4));
    assert!(ed.redo());

    // A second key takes the value the curve has there, then a new value.
    assert_eq!(ed.set_key("bloom", "strength", 10.0, 1.5).unwrap(), 1);
    assert!(ed.toggle_key("bloom", "strength", 5.0).unwrap(), "a key is set at 5");
    let mid = keys(&ed)[1];
    assert_eq!(mid.0, 5.0);
    assert!(mid.1 > 0.4 && mid.1 < 1.5, "the key holds the curve's value at 5: {mid:?}");
    assert!(!ed.toggle_key("bloom", "strength", 5.0).unwrap(), "and toggling again removes it");
    assert_eq!(keys(&ed), [(0.0, 0.4), (10.0, 1.5)]);

    // Outside the range 0..=4: refused, with the reason in the status line.
    let before = ed.doc().clone();
    let err = ed.set_key("bloom", "strength", 20.0, 9.0).unwrap_err();
    assert!(err.contains("outside the range 0..=4"), "{err}");
    let status = ed.status().unwrap();
    assert!(status.error && status.text == err, "{:?}", status.text);
    assert!(ed.move_key("bloom", "strength", 1, 10.0, -1.0).is_err());
    assert_eq!(ed.doc(), &before, "nothing changed");

    // A drag: many moves of one key, one undo step; past its neighbour it reorders.
    let mut index = 1;
    for (f, v) in [(8.0, 1.0), (4.0, 1.2), (-3.0, 1.4)] {
        index = ed.move_key("bloom", "strength", index, f, v).unwrap();
    }
    ed.seal();
    assert_eq!(index, 0, "moved past frame 0, it is the first key");
    assert_eq!(keys(&ed), [(-3.0, 1.4), (0.0, 0.4)]);
    assert!(ed.move_key("bloom", "strength", 0, 0.0, 1.0).unwrap_err().contains("already at frame 0"));
    assert!(ed.undo());
    assert_eq!(keys(&ed), [(0.0, 0.4), (10.0, 1.5)], "the whole drag undoes at once");

    // Deleting both keys leaves the constant the last one held.
    ed.delete_key("bloom", "strength", 0).unwrap();
    ed.delete_key("bloom", "strength", 0).unwrap();
    assert_eq!(strength(&ed), ParamValue::Float(1.5));

    // Copy and paste at another frame; keys on a non-number or an expression are refused.
    ed.undo();
    ed.undo();
    assert_eq!(ed.copy_keys("bloom", "strength", &[0, 1]), 2);
    ed.paste_keys("bloom", "strength", 20.0).unwrap();
    assert_eq!(keys(&ed), [(0.0, 0.4), (10.0, 1.5), (20.0, 0.4), (30.0, 1.5)]);
    assert!(ed.toggle_key("bloom", "tint_color", 0.0).unwrap_err().contains("keys are set on Float, Int and Bool"));
    ed.set_param("bloom", "strength", ParamValue::parse_cli("expr(0.5 + 0.1 * sin(time))")).unwrap();
    assert!(ed.toggle_key("bloom", "strength", 0.0).unwrap_err().contains("expression"));
    assert!(ed.validation().diagnostics.is_empty(), "an expression checks too: {:?}", ed.validation().diagnostics);
}

// ----- through the UI -----

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    let mut h = Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    h.run_steps(8);
    h
}

fn click(h: &mut Harness<'_, EditorApp>, pos: Pos2) {
    h.event(Event::PointerMoved(pos));
    h.run_steps(1);
    h.event(Event::PointerButton { pos, button: PointerButton::Primary, pressed: true, modifiers: Modifiers::NONE });
    h.run_steps(1);
    h.event(Event::PointerButton { pos, button: PointerButton::Primary, pressed: false, modifiers: Modifiers::NONE });
    h.run_steps(2);
}

/// A drag as a hand makes it: press, a frame per small move, release.
fn drag(h: &mut Harness<'_, EditorApp>, from: Pos2, to: Pos2) {
    h.event(Event::PointerMoved(from));
    h.run_steps(1);
    h.event(Event::PointerButton { pos: from, button: PointerButton::Primary, pressed: true, modifiers: Modifiers::NONE });
    h.run_steps(1);
    for k in 1..=12 {
        h.event(Event::PointerMoved(from + (to - from) * (k as f32 / 12.0)));
        h.run_steps(1);
    }
    h.event(Event::PointerButton { pos: to, button: PointerButton::Primary, pressed: false, modifiers: Modifiers::NONE });
    h.run_steps(3);
}

/// The editor with bloom.strength set to `keys` and bloom selected, cooked.
fn keyed(keys: &str) -> Harness<'static, EditorApp> {
    let mut ed = editor();
    ed.set_param("bloom", "strength", ParamValue::parse_cli(keys)).unwrap();
    ed.seal();
    ed.select("bloom");
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    h
}

#[test]
fn keys_set_with_the_toggle_move_in_the_curve_editor_and_undo() {
    let mut h = harness(EditorApp::new(editor()));
    assert!(h.query_by_label("Curves · bloom").is_none(), "no curve editor before anything is animated");
    // Select the node with a click on the canvas, as a user does.
    let node = h.state().canvas.node_screen_rect("bloom").expect("bloom on screen");
    click(&mut h, node.center());
    assert_eq!(h.state().editor.current(), Some("bloom"));
    settle(&mut h);
    assert_eq!(h.state().editor.preview().and_then(|p| p.clip_len), Some(24), "the preview is the bloomed clip");

    // The key toggle at frame 0: a key with the constant's value.
    assert_eq!(h.get_by_label("key strength").accesskit_node().toggled(), Some(Toggled::False));
    h.get_by_label("key strength").click();
    h.run_steps(3);
    assert_eq!(keys(&h.state().editor), [(0.0, 0.4)]);
    assert_eq!(h.get_by_label("key strength").accesskit_node().toggled(), Some(Toggled::True), "filled: a key here");
    assert!(h.query_by_label("Curves · bloom").is_some(), "the curve editor opens on the keyed node");

    // Move the playhead: a click on the curve editor's background at frame 12.
    let view = h.state().key_ui.view().expect("the curve view");
    let at12 = view.to_screen(12.0, (view.values.0 + view.values.1) / 2.0 + (view.values.1 - view.values.0) * 0.3);
    click(&mut h, at12);
    assert_eq!(h.state().editor.frame(), 12, "the playhead moved to frame 12");
    settle(&mut h);
    assert_eq!(h.get_by_label("key strength").accesskit_node().toggled(), Some(Toggled::False), "hollow: animated, no key here");

    // A second key at 12, then the view fitted to both keys.
    h.get_by_label("key strength").click();
    h.run_steps(3);
    assert_eq!(keys(&h.state().editor), [(0.0, 0.4), (12.0, 0.4)]);
    h.get_by_label("Frame").click();
    h.run_steps(3);
    let view = h.state().key_ui.view().unwrap();
    assert!(view.frames.0 <= 0.0 && view.frames.1 >= 12.0 && view.frames.1 < 20.0, "fitted to the keys: {view:?}");

    // Drag key 2 right by 4 frames' worth and up by 40 pixels.
    let handle = h.get_by_label("key 2 of strength").rect().center();
    assert!((handle - view.to_screen(12.0, 0.4)).length() < 1.5, "the handle is drawn at its key");
    let dx = view.to_screen(16.0, 0.4).x - view.to_screen(12.0, 0.4).x;
    let to = handle + egui::vec2(dx + 3.0, -40.0);
    drag(&mut h, handle, to);
    let (_, want) = view.from_screen(to);
    let pixel = (view.values.1 - view.values.0) / f64::from(view.rect.height());
    let ks = keys(&h.state().editor);
    assert_eq!(ks.len(), 2, "{ks:?}");
    assert_eq!(ks[1].0, 16.0, "the frame snapped to the whole frame under the pointer: {ks:?}");
    assert!((ks[1].1 - want).abs() < 2.0 * pixel && ks[1].1 > 0.4, "the value followed the pointer: {ks:?}, want {want}");
    assert_eq!(ks[0], (0.0, 0.4), "the other key did not move");

    // The inspector shows the value sampled at the playhead (frame 12, between the keys).
    let shown = h.state().editor.scalar_at("bloom", &h.state().editor.scalar_port("bloom", "strength").unwrap(), 12.0).unwrap();
    assert!(shown > 0.4 && shown < ks[1].1, "{shown}");
    assert!(h.query_by_label(&pyrograph_editor::state::value_text(shown)).is_some(), "the row shows {shown}");

    // One undo takes the whole drag back.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    assert_eq!(keys(&h.state().editor), [(0.0, 0.4), (12.0, 0.4)], "the key is back where it was");
    // The undo re-cooks the preview: wait for it, so that the panels do not move under the
    // pointer between finding the tick and clicking it (a loaded machine finished the cook there).
    settle(&mut h);

    // The key strip under the scrubber: a tick per key; clicking one moves the playhead there and
    // selects it, and Delete deletes it (one undo step).
    let tick = h.get_by_label("strength @ 0 = 0.4").rect().center();
    click(&mut h, tick);
    assert_eq!(h.state().editor.frame(), 0);
    assert_eq!(h.state().key_ui.selected(), [("strength".to_string(), 0.0)]);
    h.key_press(egui::Key::Delete);
    h.run_steps(3);
    assert_eq!(keys(&h.state().editor), [(12.0, 0.4)]);
    assert!(h.state().editor.doc().node("bloom").is_some(), "Delete took the key, not the node");
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    assert_eq!(keys(&h.state().editor), [(0.0, 0.4), (12.0, 0.4)]);
}

#[test]
fn a_drag_above_the_range_stops_at_its_end_and_an_expression_is_typed_in_the_row() {
    let mut h = keyed("keys([(0, 3.5), (10, 3.9, ease)])");
    let handle = h.get_by_label("key 2 of strength").rect().center();
    drag(&mut h, handle, handle - egui::vec2(0.0, 300.0));
    let ks = keys(&h.state().editor);
    assert_eq!(ks[1], (10.0, 4.0), "held at the range's end, 4");
    let text = KeyList::read(&strength(&h.state().editor)).unwrap().to_param(false).to_string();
    assert!(text.contains("ease"), "the interpolation is kept: {text}");

    // The wheel zooms the frames about the pointer; F over the panel fits the view to the keys.
    let fitted = h.state().key_ui.view().unwrap();
    let span = |v: &pyrograph_editor::key_ui::CurveView| v.frames.1 - v.frames.0;
    h.event(Event::PointerMoved(fitted.rect.center()));
    h.run_steps(1);
    h.event(Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, 120.0),
        phase: egui::TouchPhase::Move,
        modifiers: Modifiers::NONE,
    });
    h.run_steps(20);
    let zoomed = h.state().key_ui.view().unwrap();
    assert!(span(&zoomed) < 0.8 * span(&fitted), "zoomed in: {fitted:?} -> {zoomed:?}");
    let selected_nodes = h.state().editor.selection().to_vec();
    h.key_press(egui::Key::F);
    h.run_steps(3);
    let refit = h.state().key_ui.view().unwrap();
    assert_eq!(refit.frames, fitted.frames, "fitted to the keys 0..10 again, not {zoomed:?}");
    assert!(refit.frames.0 < 0.0 && refit.frames.1 > 10.0 && refit.frames.1 < 14.0, "{refit:?}");
    assert_eq!(h.state().editor.selection(), selected_nodes);

    // The row's text field takes an expression; the curve editor draws it without handles.
    let written = strength(&h.state().editor).to_string();
    let w = written.clone();
    h.get_by(move |n| n.role() == Role::TextInput && n.value().as_deref() == Some(w.as_str())).focus();
    h.run_steps(1);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    h.event(Event::Text("expr(\"2 + sin(time)\")".into()));
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    assert_eq!(
        strength(&h.state().editor),
        ParamValue::Call("expr".into(), Box::new(ParamValue::String("2 + sin(time)".into())))
    );
    assert!(h.query_by_label("key 1 of strength").is_none(), "no handles on an expression");
    assert!(h.query_by_label("Curves · bloom").is_some());
}

#[test]
fn a_colour_is_keyed_per_component_by_its_toggle_and_one_undo_takes_a_toggle_back() {
    use pyrograph_editor::state::vector_keys::all_keyed_at;
    let mut ed = editor();
    ed.select("bloom");
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    let tint = |h: &Harness<'_, EditorApp>| h.state().editor.doc().node("bloom").unwrap().params.get("tint_color").cloned();
    assert_eq!(tint(&h), None, "the default colour, unset");
    h.get_by_label("key tint_color").click();
    h.run_steps(3);
    let keyed = tint(&h).expect("the colour is set");
    assert!(all_keyed_at(&keyed, 4, 0.0), "every component keyed at frame 0: {keyed}");
    assert_eq!(h.get_by_label("key tint_color").accesskit_node().toggled(), Some(Toggled::True));

    // At frame 10 the toggle is hollow; a click keys all four components there too.
    h.state_mut().editor.set_frame(10);
    settle(&mut h);
    assert_eq!(h.get_by_label("key tint_color").accesskit_node().toggled(), Some(Toggled::False));
    h.get_by_label("key tint_color").click();
    h.run_steps(3);
    let both = tint(&h).unwrap();
    assert!(all_keyed_at(&both, 4, 0.0) && all_keyed_at(&both, 4, 10.0), "{both}");
    assert!(h.state().editor.validation().diagnostics.is_empty(), "{:?}", h.state().editor.validation().diagnostics);

    // Clicked again, the keys at 10 go; one undo brings them back.
    h.get_by_label("key tint_color").click();
    h.run_steps(3);
    assert_eq!(tint(&h).as_ref(), Some(&keyed), "back to the keys at frame 0 alone");
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    assert_eq!(tint(&h), Some(both));
}

#[test]
fn a_selected_keys_tangent_handle_drags_its_slope_in_one_undo_step() {
    let mut h = keyed("keys([(0, 0.4), (12, 1.2), (24, 0.8)])");
    assert!(h.query_by_label("tangent out of key 2 of strength").is_none(), "no tangent handles before a key is selected");
    let key = h.get_by_label("key 2 of strength").rect().center();
    click(&mut h, key);
    assert_eq!(h.state().key_ui.selected(), [("strength".to_string(), 12.0)]);
    // Key 2 is a peak: the smooth curve is flat there, so its handle points straight ahead.
    let out = h.get_by_label("tangent out of key 2 of strength").rect().center();
    assert!((out.y - key.y).abs() < 1.5 && out.x > key.x + 20.0, "flat at the peak: key {key:?}, handle {out:?}");

    // Drag it up by 30 pixels: the key's slope becomes the line from the key to the pointer.
    let view = h.state().key_ui.view().unwrap();
    let to = out - egui::vec2(0.0, 30.0);
    drag(&mut h, out, to);
    let want = pyrograph_editor::tangents::slope_to(&view, 12.0, 1.2, to).unwrap();
    assert!(want > 0.0, "{want}");
    let text = strength(&h.state().editor).to_string();
    assert!(text.contains(&format!("tangent({want})")), "{text} should hold tangent({want})");
    assert_eq!(keys(&h.state().editor), [(0.0, 0.4), (12.0, 1.2), (24.0, 0.8)], "the keys did not move");

    // One undo takes the whole drag back: smooth again.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    assert!(!strength(&h.state().editor).to_string().contains("tangent"), "{}", strength(&h.state().editor));

    // A slope steep enough to carry the curve past 4 (the range's end) is refused.
    h.state_mut().editor.seal();
    let e = h.state_mut().editor.set_key_tangent("bloom", "strength", 1, 5.0).unwrap_err();
    assert!(e.contains("outside the range 0..=4"), "{e}");
}

#[test]
fn a_switch_is_keyed_in_steps_and_its_last_key_deleted_leaves_true_or_false() {
    let mut ed = editor();
    ed.auto_cook = false;
    let tint = |ed: &Editor| ed.doc().node("bloom").unwrap().params.get("tint").cloned();
    assert!(ed.toggle_key("bloom", "tint", 0.0).unwrap());
    assert_eq!(tint(&ed).unwrap().to_string().replace(' ', ""), "keys([(0,0,constant)])");
    assert!(ed.undo(), "one step");
    assert_eq!(tint(&ed), None);
    assert!(ed.redo());
    assert_eq!(ed.set_key("bloom", "tint", 12.0, 1.0).unwrap(), 1);
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    // Off until 12, on from 12: the constant interpolation steps.
    let port = ed.scalar_port("bloom", "tint").unwrap();
    assert_eq!((ed.scalar_at("bloom", &port, 11.0).unwrap(), ed.scalar_at("bloom", &port, 12.0).unwrap()), (0.0, 1.0));
    ed.delete_key("bloom", "tint", 0).unwrap();
    ed.delete_key("bloom", "tint", 0).unwrap();
    assert_eq!(tint(&ed), Some(ParamValue::Bool(true)), "the last key held true");
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
}
