//! Flow edits through the UI (issue 46): bypass with the B key and the node menu, the preview
//! of a bypassed node, and undo back to the document byte for byte.

use eframe::egui::{self, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
mod common;

use common::{preview_of, settle};
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue};

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app)
}

/// A small orange frame into a bloom.
fn bloom_graph() -> GraphDoc {
    let f = ParamValue::Float;
    let mut doc = GraphDoc::new();
    doc.add_node(
        "color",
        NodeDoc::new("imaging.constant_color")
            .param("width", ParamValue::Int(64))
            .param("height", ParamValue::Int(48))
            .param("color", ParamValue::List(vec![f(0.8), f(0.5), f(0.2), f(1.0)])),
    );
    doc.add_node("bloom", NodeDoc::new("imaging.bloom"));
    doc.connect("color.image", "bloom.image");
    doc
}

/// The pixels the preview shows now.
fn shown(h: &Harness<'_, EditorApp>) -> Option<Vec<u8>> {
    h.state().editor.preview().and_then(|p| p.image.as_ref()).map(|i| i.rgba.clone())
}

#[test]
fn bypassing_a_bloom_shows_its_input_and_undo_restores_the_document_byte_for_byte() {
    let mut ed = Editor::with_default_registry();
    ed.edit(None, |d| *d = bloom_graph());
    ed.seal();
    let original = ed.doc().to_ron();
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    let source = preview_of(&mut h, "color");
    let bloomed = preview_of(&mut h, "bloom");
    assert!(bloomed != source, "the bloom changes the frame, so the test can tell");

    // B with the bloom selected: bypassed, the preview is its input, the header says so.
    h.key_press(egui::Key::B);
    settle(&mut h);
    assert!(h.state().editor.is_bypassed("bloom"));
    assert!(h.state().editor.doc().to_ron().contains("bypass: true"));
    assert!(shown(&h) == Some(source.clone()), "the preview is the bloom's input");
    assert!(h.query_by_label("bypassed").is_some(), "the node's header shows it is bypassed");

    // Undo: the document is the original byte for byte, and the bloom is back.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    settle(&mut h);
    assert_eq!(h.state().editor.doc().to_ron(), original);
    assert!(shown(&h) == Some(bloomed), "the bloom is back");
    assert!(h.query_by_label("bypassed").is_none());
}

#[test]
fn a_node_that_cannot_be_bypassed_says_why_on_the_node() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut doc = GraphDoc::new();
    // A constant colour has no image input to pass through.
    doc.add_node("color", NodeDoc::new("imaging.constant_color"));
    ed.edit(None, |d| *d = doc);
    ed.toggle_bypass(&["color".to_string()]);
    let problems = ed.node_problems("color");
    assert!(problems.iter().any(|p| p.contains("cannot be bypassed") && p.contains("output 'image'")), "{problems:?}");
}

/// A primary drag from `from` to `to` in small steps, as a hand moves a mouse.
fn drag(h: &mut Harness<'_, EditorApp>, from: egui::Pos2, to: egui::Pos2) {
    use egui::{Event, PointerButton};
    h.event(Event::PointerMoved(from));
    h.run_steps(1);
    h.event(Event::PointerButton { pos: from, button: PointerButton::Primary, pressed: true, modifiers: Modifiers::NONE });
    h.run_steps(1);
    for k in 1..=10 {
        h.event(Event::PointerMoved(from + (to - from) * (k as f32 / 10.0)));
        h.run_steps(1);
    }
    h.event(Event::PointerButton { pos: to, button: PointerButton::Primary, pressed: false, modifiers: Modifiers::NONE });
    h.run_steps(3);
}

#[test]
fn a_wire_dragged_from_a_pin_into_empty_space_offers_the_nodes_that_take_it_and_wires_the_pick() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut doc = GraphDoc::new();
    let mut color = NodeDoc::new("imaging.constant_color");
    color.pos = Some((0.0, 0.0));
    doc.add_node("color", color);
    ed.edit(None, |d| *d = doc);
    ed.seal();
    let original = ed.doc().to_ron();
    let mut app = EditorApp::new(ed);
    app.canvas.frame_all();
    let mut h = harness(app);
    h.run_steps(4);
    // The output pin sits right of its label, inside the node's frame.
    let node = h.state().canvas.node_screen_rect("color").expect("the node is on screen");
    // Widgets on the canvas report their rectangles in canvas units: take them to the screen.
    let to_screen = h.state().canvas.transform();
    let label = h
        .query_all_by_label("image")
        .map(|n| to_screen.mul_rect(n.rect()))
        .find(|r| node.contains_rect(*r))
        .expect("the output's label, in the node");
    let pin = egui::pos2((label.right() + node.right()) / 2.0, label.center().y);
    let empty = pin + egui::vec2(220.0, 40.0);
    drag(&mut h, pin, empty);
    assert!(
        h.query_by_label_contains("Add a node taking color.image").is_some(),
        "dropping the wire on empty canvas opens the filtered palette"
    );
    assert!(h.query_by_label("imaging.bloom").is_some(), "bloom takes an image");
    assert!(h.query_by_label("math.add").is_none(), "math.add cannot take an image");
    h.event(egui::Event::Text("bloom".into()));
    h.run_steps(2);
    assert!(h.query_by_label("imaging.to_gray").is_none(), "typing narrows the list");
    h.get_by_label("imaging.bloom").click();
    h.run_steps(3);
    let doc = h.state().editor.doc().clone();
    assert_eq!(doc.node("bloom").map(|n| n.type_name.as_str()), Some("imaging.bloom"), "{}", doc.to_ron());
    assert!(doc.edges.contains(&("color.image".to_string(), "bloom.image".to_string())), "{:?}", doc.edges);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().to_ron(), original, "one undo takes the node and its wire back");
}

#[test]
fn a_writer_outside_the_graph_folder_is_refused_until_the_preference_allows_it() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut doc = GraphDoc::new();
    doc.add_node("card", NodeDoc::new("imaging.constant_color"));
    doc.add_node("write", NodeDoc::new("imaging.write_image").param("path", ParamValue::String("../elsewhere/card.png".into())));
    doc.connect("card.image", "write.image");
    ed.edit(None, |d| *d = doc);
    let refused = |ed: &Editor| ed.node_problems("write").iter().any(|p| p.contains("outside"));
    assert!(!pyrograph_editor::state::allow_outside_out(), "off by default");
    assert!(refused(&ed), "{:?}", ed.node_problems("write"));
    ed.set_allow_outside_out(true);
    assert!(!refused(&ed) && ed.validation().graph.is_some(), "{:?}", ed.node_problems("write"));
    ed.set_allow_outside_out(false);
    assert!(refused(&ed));
}

#[test]
fn a_node_dropped_onto_a_wire_is_spliced_into_it_in_one_undo_step() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut doc = GraphDoc::new();
    let at = |ty: &str, x: f32, y: f32| {
        let mut n = NodeDoc::new(ty);
        n.pos = Some((x, y));
        n
    };
    doc.add_node("color", at("imaging.constant_color", 0.0, 0.0));
    doc.add_node("gray", at("imaging.to_gray", 900.0, 0.0));
    doc.add_node("bloom", at("imaging.bloom", 400.0, 500.0));
    doc.connect("color.image", "gray.image");
    ed.edit(None, |d| *d = doc);
    ed.seal();
    let original = ed.doc().to_ron();
    let mut app = EditorApp::new(ed);
    app.canvas.frame_all();
    let mut h = harness(app);
    h.run_steps(6);
    let rect = |h: &Harness<'_, EditorApp>, id: &str| h.state().canvas.node_screen_rect(id).expect("on screen");
    let (color, gray, bloom) = (rect(&h, "color"), rect(&h, "gray"), rect(&h, "bloom"));
    // The wire runs from color's right edge to gray's left edge at the rows of their "image" pins.
    let to_screen = h.state().canvas.transform();
    let row = |h: &Harness<'_, EditorApp>, node: egui::Rect| {
        h.query_all_by_label("image").map(|n| to_screen.mul_rect(n.rect())).find(|r| node.contains_rect(*r)).expect("a pin label")
    };
    let (ya, yb) = (row(&h, color).center().y, row(&h, gray).center().y);
    let middle = egui::pos2((color.right() + gray.left()) / 2.0, (ya + yb) / 2.0);
    // Grab bloom by its header and drop it with its centre on the wire's middle.
    let grab = bloom.min + egui::vec2(20.0, 8.0);
    drag(&mut h, grab, grab + (middle - bloom.center()));
    h.run_steps(2);
    let edges = h.state().editor.doc().edges.clone();
    assert!(
        edges.contains(&("color.image".into(), "bloom.image".into()))
            && edges.contains(&("bloom.image".into(), "gray.image".into())),
        "spliced: {edges:?}"
    );
    assert!(!edges.contains(&("color.image".into(), "gray.image".into())), "the old wire is gone: {edges:?}");
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().to_ron(), original, "one undo takes back the drag and the splice");
    // Dropped away from any wire, a node only moves.
    let bloom = rect(&h, "bloom");
    let grab = bloom.min + egui::vec2(20.0, 8.0);
    drag(&mut h, grab, grab + egui::vec2(40.0, 30.0));
    assert_eq!(h.state().editor.doc().edges.len(), 1);
}

#[test]
fn pin_as_b_then_select_another_node_shows_both_side_by_side_and_as_a_wipe() {
    use pyrograph_editor::state::viewers::CompareMode;
    let mut ed = Editor::with_default_registry();
    ed.edit(None, |d| *d = bloom_graph());
    ed.seal();
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    let source = preview_of(&mut h, "color");
    let bloomed = preview_of(&mut h, "bloom");
    h.get_by_label("Pin as B").click();
    settle(&mut h);
    let _ = preview_of(&mut h, "color");
    let ed = &h.state().editor;
    assert_eq!(ed.compare_request().map(|b| b.node.as_str()), Some("bloom"));
    let b = ed.compare_preview().0.and_then(|p| p.image.as_ref()).map(|i| i.rgba.clone());
    assert!(b == Some(bloomed), "B still shows the bloom");
    assert!(shown(&h) == Some(source), "A shows the selected node");
    assert!(h.query_by_label("B: bloom @ 0").is_some() && h.query_by_label("side by side").is_some());
    // Wipe: one picture split at the middle.
    h.get_by_label("wipe").click();
    h.run_steps(2);
    assert_eq!(h.state_mut().editor.compare_mut().mode, CompareMode::Wipe);
    assert_eq!(h.state_mut().editor.compare_mut().wipe, 0.5);
    // Closing B returns to the single preview.
    h.get_by_label("×").click();
    h.run_steps(2);
    assert!(h.state().editor.compare_request().is_none());
    assert!(h.query_by_label("Pin as B").is_some());
}

/// Every frame of output `endpoint` (`node.port`, a clip of images) of `doc`, read from `file`'s
/// folder, as raw samples.
fn cooked_frames(doc: &GraphDoc, file: &std::path::Path, endpoint: &str) -> Vec<Vec<f32>> {
    use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, Value};
    let registry = pyrograph_frontend::registry();
    let g = Graph::build_file(doc, file, &registry, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let ctx = CookCtx::new();
    let Ok(Value::Clip(clip)) = Evaluator::new().output(&g, endpoint, &ctx) else { panic!("{endpoint} is not a clip") };
    (0..clip.len())
        .map(|i| match clip.get(i, &ctx) {
            Ok(Value::Image(img)) => img.data().to_vec(),
            other => panic!("frame {i} of {endpoint}: {other:?}"),
        })
        .collect()
}

#[test]
fn unpacking_an_include_from_its_menu_cooks_the_same_frames_and_undoes_byte_for_byte() {
    let file = pyrograph_testing::workspace().join("graphs/flame-cards.ron");
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&file).unwrap();
    let original = ed.doc().to_ron();
    let before = cooked_frames(ed.doc(), &file, "calm.clip");
    let mut app = EditorApp::new(ed);
    app.canvas.frame_all();
    let mut h = harness(app);
    h.run_steps(6);
    let calm = h.state().canvas.node_screen_rect("calm").expect("on screen");
    let at = calm.min + egui::vec2(20.0, 8.0);
    h.event(egui::Event::PointerMoved(at));
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Secondary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Secondary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    h.run_steps(3);
    h.get_by_label("Unpack").click();
    h.run_steps(3);
    let doc = h.state().editor.doc().clone();
    assert!(doc.node("calm").is_none(), "the include is gone");
    assert!(doc.nodes.0.iter().any(|(id, _)| id.starts_with("calm_")), "its nodes are in: {}", doc.to_ron());
    let (source, _) = doc.edges.iter().find(|(_, b)| b == "write_calm.clip").expect("the writer is still fed");
    assert!(source.starts_with("calm_"), "fed by an unpacked node: {source}");
    let after = cooked_frames(&doc, &file, source);
    assert_eq!(after.len(), before.len());
    assert!(after == before, "the unpacked nodes cook the include's frames, sample for sample");
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().to_ron(), original, "one undo step");
}
