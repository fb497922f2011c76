//! The canvas driven as a user drives it: pointer presses, drags and keys at node positions
//! (egui_kittest events, never `Editor::select`), copy/paste between two editors, groups and
//! comments through save and reload, and navigation.

use eframe::egui::{self, Event, Modifiers, PointerButton, Pos2, Rect, accesskit::Role};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use pyrograph_editor::annotate::Annotation;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue};

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    let mut h = Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    // "Frame all" settles over the first frames, as node sizes become known.
    h.run_steps(8);
    h
}

/// Three unconnected value nodes and a chain: a and b side by side, c further right, add fed by a.
fn three_node_editor() -> Editor {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut doc = GraphDoc::new();
    let node = |ty: &str, x: f32, y: f32| {
        let mut n = NodeDoc::new(ty);
        n.pos = Some((x, y));
        n
    };
    doc.add_node("a", node("value.float", 0.0, 0.0).param("value", ParamValue::Float(1.0)));
    doc.add_node("b", node("value.float", 0.0, 160.0));
    doc.add_node("add", node("math.add", 320.0, 0.0));
    doc.add_node("c", node("value.float", 640.0, 160.0));
    doc.connect("a.value", "add.a");
    ed.edit(None, |d| *d = doc);
    ed.seal();
    ed
}

fn rect(h: &Harness<'_, EditorApp>, id: &str) -> Rect {
    h.state().canvas.node_screen_rect(id).unwrap_or_else(|| panic!("node {id} is not on screen"))
}

fn selection(h: &Harness<'_, EditorApp>) -> Vec<String> {
    h.state().editor.selection().to_vec()
}

/// A press and release at `pos` with `mods` held, `hold` frames apart.
fn click(h: &mut Harness<'_, EditorApp>, pos: Pos2, mods: Modifiers, hold: usize) {
    h.event(Event::PointerMoved(pos));
    h.event(Event::ModifiersChanged(mods));
    h.event(Event::PointerButton { pos, button: PointerButton::Primary, pressed: true, modifiers: mods });
    h.run_steps(1);
    h.run_steps(hold);
    h.event(Event::PointerButton { pos, button: PointerButton::Primary, pressed: false, modifiers: mods });
    h.event(Event::ModifiersChanged(Modifiers::NONE));
    h.run_steps(2);
}

/// A primary drag from `from` to `to` in small steps, as a hand moves a mouse.
fn drag(h: &mut Harness<'_, EditorApp>, from: Pos2, to: Pos2, mods: Modifiers) {
    h.event(Event::PointerMoved(from));
    h.event(Event::ModifiersChanged(mods));
    h.event(Event::PointerButton { pos: from, button: PointerButton::Primary, pressed: true, modifiers: mods });
    for k in 1..=10 {
        h.event(Event::PointerMoved(from + (to - from) * (k as f32 / 10.0)));
    }
    h.event(Event::PointerButton { pos: to, button: PointerButton::Primary, pressed: false, modifiers: mods });
    h.event(Event::ModifiersChanged(Modifiers::NONE));
    h.run_steps(3);
}

/// A point of empty canvas just above and left of every node.
fn empty_spot(h: &Harness<'_, EditorApp>) -> Pos2 {
    let all = ["a", "b", "add", "c"].iter().fold(Rect::NOTHING, |acc, id| acc.union(rect(h, id)));
    all.min - egui::vec2(30.0, 30.0)
}

#[test]
fn clicking_selects_plain_shift_and_rectangle() {
    let mut h = harness(EditorApp::new(three_node_editor()));
    assert!(h.query_by_label("Click a node to edit its parameters.").is_some());

    // A plain click on a node's body selects it and the inspector shows its parameters.
    let a = rect(&h, "a");
    click(&mut h, a.center(), Modifiers::NONE, 0);
    assert_eq!(selection(&h), ["a"]);
    assert!(h.query_by_label("Click a node to edit its parameters.").is_none(), "the inspector follows the click");
    assert!(h.query_by_label("value.float").is_some(), "the inspector names the node's type");

    // Shift-click on another node's title adds it; the inspector follows the last clicked.
    let b = rect(&h, "b");
    click(&mut h, b.min + egui::vec2(24.0, 10.0), Modifiers::SHIFT, 0);
    assert_eq!(selection(&h), ["a", "b"]);
    assert_eq!(h.state().editor.current(), Some("b"));
    // Shift-click again removes it.
    click(&mut h, b.center(), Modifiers::SHIFT, 0);
    assert_eq!(selection(&h), ["a"]);
    // Ctrl-click toggles the same way.
    click(&mut h, b.center(), Modifiers::COMMAND, 0);
    assert_eq!(selection(&h), ["a", "b"]);
    click(&mut h, b.center(), Modifiers::COMMAND, 0);
    assert_eq!(selection(&h), ["a"]);

    // A slow press and release still selects.
    let c = rect(&h, "c");
    click(&mut h, c.center(), Modifiers::NONE, 40);
    assert_eq!(selection(&h), ["c"]);

    // A click on empty canvas clears the selection.
    let empty = empty_spot(&h);
    click(&mut h, empty, Modifiers::NONE, 0);
    assert!(selection(&h).is_empty());

    // A drag from empty canvas draws a rectangle over a and b (not add or c), and the view stays.
    let before = h.state().canvas.transform();
    let (a, b) = (rect(&h, "a"), rect(&h, "b"));
    drag(&mut h, empty, a.union(b).max + egui::vec2(10.0, 10.0), Modifiers::NONE);
    assert_eq!(selection(&h), ["a", "b"]);
    assert_eq!(h.state().canvas.transform(), before, "drawing a rectangle does not pan");

    // Shift-rectangle over c adds it; Ctrl-rectangle over a removes it.
    let c = rect(&h, "c");
    drag(&mut h, c.min - egui::vec2(8.0, 8.0), c.max + egui::vec2(8.0, 8.0), Modifiers::SHIFT);
    assert_eq!(selection(&h), ["a", "b", "c"]);
    let a = rect(&h, "a");
    drag(&mut h, a.min - egui::vec2(8.0, 8.0), a.center(), Modifiers::COMMAND);
    assert_eq!(selection(&h), ["b", "c"]);

    // Alt-drag on empty canvas pans instead.
    let empty = empty_spot(&h);
    drag(&mut h, empty, empty + egui::vec2(-60.0, 0.0), Modifiers::ALT);
    assert_ne!(h.state().canvas.transform(), before, "Alt-drag pans");
    assert_eq!(selection(&h), ["b", "c"], "panning leaves the selection");

    // Ctrl+A selects every node.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    h.run_steps(2);
    assert_eq!(selection(&h), ["a", "b", "add", "c"]);

    // Ctrl+D duplicates the selection with its internal wire and selects the copies.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::D);
    h.run_steps(2);
    let doc = h.state().editor.doc().clone();
    assert_eq!(doc.nodes.0.len(), 8);
    let copies = selection(&h);
    assert_eq!(copies.len(), 4);
    assert!(copies.iter().all(|id| !["a", "b", "add", "c"].contains(&id.as_str())), "{copies:?}");
    assert_eq!(doc.edges.len(), 2, "the copy of a keeps its wire to the copy of add: {:?}", doc.edges);
}

#[test]
fn dragging_a_selected_node_moves_the_whole_selection_as_one_undo_step() {
    let mut h = harness(EditorApp::new(three_node_editor()));
    let (a, b) = (rect(&h, "a"), rect(&h, "b"));
    let empty = empty_spot(&h);
    drag(&mut h, empty, a.union(b).max + egui::vec2(10.0, 10.0), Modifiers::NONE);
    assert_eq!(selection(&h), ["a", "b"]);
    let pos = |h: &Harness<'_, EditorApp>, id: &str| h.state().editor.doc().node(id).unwrap().pos.unwrap();
    let (a0, b0, c0) = (pos(&h, "a"), pos(&h, "b"), pos(&h, "c"));
    let a = rect(&h, "a");
    drag(&mut h, a.min + egui::vec2(20.0, 8.0), a.min + egui::vec2(120.0, 68.0), Modifiers::NONE);
    let (a1, b1) = (pos(&h, "a"), pos(&h, "b"));
    let da = (a1.0 - a0.0, a1.1 - a0.1);
    assert!(da.0 > 20.0 && da.1 > 10.0, "a moved: {da:?}");
    assert_eq!((b1.0 - b0.0, b1.1 - b0.1), da, "b moved with it");
    assert_eq!(pos(&h, "c"), c0, "c is not selected and stays");
    assert_eq!(selection(&h), ["a", "b"]);
    // Dragging an unselected node selects it alone.
    let c = rect(&h, "c");
    drag(&mut h, c.min + egui::vec2(20.0, 8.0), c.min + egui::vec2(60.0, 8.0), Modifiers::NONE);
    assert_eq!(selection(&h), ["c"]);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!((pos(&h, "a"), pos(&h, "b"), pos(&h, "c")), (a0, b0, c0), "each drag is one undo step");
}

fn copied_text(h: &Harness<'_, EditorApp>) -> Option<String> {
    h.output().platform_output.commands.iter().find_map(|c| match c {
        egui::OutputCommand::CopyText(t) => Some(t.clone()),
        _ => None,
    })
}

#[test]
fn copy_and_paste_carry_connections_between_two_documents() {
    let mut h1 = harness(EditorApp::new(three_node_editor()));
    let p = rect(&h1, "a").center();
    click(&mut h1, p, Modifiers::NONE, 0);
    let p = rect(&h1, "add").center();
    click(&mut h1, p, Modifiers::SHIFT, 0);
    assert_eq!(selection(&h1), ["a", "add"]);
    h1.event(Event::Copy);
    h1.run_steps(1);
    let text = copied_text(&h1).expect("Ctrl+C puts the nodes on the clipboard");
    assert!(text.contains("math.add") && text.contains("(\"a.value\", \"add.a\")"), "{text}");

    // A second editor with a document of its own: the pasted ids that clash are renamed.
    let mut other = Editor::with_default_registry();
    other.auto_cook = false;
    other.add_node("value.float", (0.0, 0.0)).unwrap();
    other.edit(None, |d| d.nodes.0[0].0 = "a".into());
    let mut h2 = harness(EditorApp::new(other));
    h2.event(Event::PointerMoved(Pos2::new(300.0, 400.0)));
    h2.event(Event::Paste(text));
    h2.run_steps(3);
    let doc = h2.state().editor.doc().clone();
    let ids: Vec<&str> = doc.nodes.0.iter().map(|(id, _)| id.as_str()).collect();
    assert_eq!(ids, ["a", "a2", "add"]);
    assert_eq!(doc.edges, vec![("a2.value".to_string(), "add.a".to_string())], "the internal connection is kept");
    assert_eq!(doc.node("a2").unwrap().params["value"], ParamValue::Float(1.0), "parameters travel too");
    assert_eq!(selection(&h2), ["a2", "add"], "the pasted nodes are selected");
    // They land under the pointer.
    let p = rect(&h2, "a2").min;
    assert!(p.distance(Pos2::new(300.0, 400.0)) < 40.0, "pasted at {p:?}");

    // Cut removes them from the first document; pasting other text reports and changes nothing.
    h1.event(Event::Cut);
    h1.run_steps(2);
    assert_eq!(h1.state().editor.doc().nodes.0.len(), 2);
    let before = h2.state().editor.doc().clone();
    h2.event(Event::Paste("just some words".into()));
    h2.run_steps(2);
    assert_eq!(h2.state().editor.doc(), &before);
    assert!(h2.state().editor.status().is_some_and(|s| s.error && s.text.contains("no pyrograph nodes")));
}

#[test]
fn a_group_and_a_comment_survive_save_and_reload() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(EditorApp::new(three_node_editor()));
    let (a, b) = (rect(&h, "a"), rect(&h, "b"));
    let empty = empty_spot(&h);
    drag(&mut h, empty, a.union(b).max + egui::vec2(10.0, 10.0), Modifiers::NONE);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::G);
    h.run_steps(3);
    assert_eq!(h.state().editor.doc().groups.len(), 1);
    assert_eq!(h.state().editor.doc().groups[0].nodes, ["a", "b"]);
    assert_eq!(h.state().canvas.annotation, Some(Annotation::Group(0)), "the new group is selected for naming");

    // Keyboard-first: focus the title, type, Escape reverts; type again, Enter commits.
    h.get_by_role(Role::TextInput).focus();
    h.run_steps(1);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    h.get_by_role(Role::TextInput).type_text("zzz");
    h.key_press(egui::Key::Escape);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().groups[0].title, "Group", "Escape reverts");
    h.get_by_role(Role::TextInput).focus();
    h.run_steps(1);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    h.get_by_role(Role::TextInput).type_text("Inputs");
    h.key_press(egui::Key::Enter);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().groups[0].title, "Inputs", "Enter commits");

    // Shift+C adds a comment under the pointer.
    let spot = rect(&h, "c").max + egui::vec2(40.0, 40.0);
    h.event(Event::PointerMoved(spot));
    h.key_press_modifiers(Modifiers::SHIFT, egui::Key::C);
    h.run_steps(3);
    assert_eq!(h.state().editor.doc().comments.len(), 1);
    assert_eq!(h.state().canvas.annotation, Some(Annotation::Comment(0)));

    // Clicking the group's title bar selects the group; dragging it moves its nodes only.
    click(&mut h, empty, Modifiers::NONE, 0);
    let bar = h.state().canvas.annotation_screen_rect(Annotation::Group(0)).expect("group drawn");
    click(&mut h, bar.center(), Modifiers::NONE, 0);
    assert_eq!(h.state().canvas.annotation, Some(Annotation::Group(0)));
    let pos = |h: &Harness<'_, EditorApp>, id: &str| h.state().editor.doc().node(id).unwrap().pos.unwrap();
    let (a0, b0, c0) = (pos(&h, "a"), pos(&h, "b"), pos(&h, "c"));
    let bar = h.state().canvas.annotation_screen_rect(Annotation::Group(0)).unwrap();
    drag(&mut h, bar.center(), bar.center() + egui::vec2(80.0, 40.0), Modifiers::NONE);
    let (a1, b1) = (pos(&h, "a"), pos(&h, "b"));
    assert!(a1.0 > a0.0 && a1.1 > a0.1, "{a0:?} -> {a1:?}");
    assert_eq!((b1.0 - b0.0, b1.1 - b0.1), (a1.0 - a0.0, a1.1 - a0.1));
    assert_eq!(pos(&h, "c"), c0);
    // Dragging the comment moves it.
    let note = h.state().canvas.annotation_screen_rect(Annotation::Comment(0)).unwrap();
    let p0 = h.state().editor.doc().comments[0].pos;
    drag(&mut h, note.center(), note.center() + egui::vec2(-50.0, 30.0), Modifiers::NONE);
    let p1 = h.state().editor.doc().comments[0].pos;
    assert!(p1.0 < p0.0 && p1.1 > p0.1, "{p0:?} -> {p1:?}");

    // Save, reload in a fresh editor, compare.
    let file = dir.path().join("grouped.ron");
    h.state_mut().editor.save_as(&file).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("version: 2") && text.contains("Inputs") && text.contains("comments"), "{text}");
    let mut fresh = Editor::with_default_registry();
    fresh.auto_cook = false;
    fresh.open(&file).unwrap();
    assert_eq!(fresh.doc(), h.state().editor.doc());
    assert!(fresh.validation().diagnostics.is_empty(), "{:?}", fresh.validation().diagnostics);

    // Deleting a grouped node takes it out of its group.
    let p = rect(&h, "a").center();
    click(&mut h, p, Modifiers::NONE, 0);
    h.key_press(egui::Key::Delete);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().groups[0].nodes, ["b"]);
}

#[test]
fn navigation_frames_the_selection_limits_zoom_and_the_minimap_moves_the_view() {
    let mut h = harness(EditorApp::new(three_node_editor()));
    let p = rect(&h, "c").center();
    click(&mut h, p, Modifiers::NONE, 0);
    h.key_press(egui::Key::F);
    h.run_steps(3);
    // Framing one node zooms in on it: it is now in the middle of the canvas and larger.
    let c = rect(&h, "c");
    let all_framed = h.state().canvas.transform().scaling;
    h.key_press(egui::Key::Home);
    h.run_steps(3);
    assert!(h.state().canvas.transform().scaling < all_framed, "Home frames everything, further out");
    assert!(c.width() > rect(&h, "c").width());

    // Zoom stays within its limits however far the wheel goes.
    for _ in 0..40 {
        h.event(Event::PointerMoved(empty_spot(&h)));
        h.event(Event::Zoom(0.5));
    }
    h.run_steps(2);
    let s = h.state().canvas.transform().scaling;
    assert!((s - pyrograph_editor::viewer::MIN_SCALE).abs() < 1e-3, "zoomed out to the limit: {s}");
    for _ in 0..40 {
        h.event(Event::Zoom(2.0));
    }
    h.run_steps(2);
    let s = h.state().canvas.transform().scaling;
    assert!((s - pyrograph_editor::viewer::MAX_SCALE).abs() < 1e-3, "zoomed in to the limit: {s}");

    // A click in the minimap centres the view there; M hides it.
    let map = h.state().canvas.minimap_rect().expect("the minimap is shown");
    let before = h.state().canvas.transform();
    click(&mut h, map.left_top() + egui::vec2(20.0, 20.0), Modifiers::NONE, 0);
    assert_ne!(h.state().canvas.transform().translation, before.translation, "the minimap moved the view");
    assert!(h.state().canvas.show_minimap);
    h.key_press(egui::Key::M);
    h.run_steps(2);
    assert!(!h.state().canvas.show_minimap);
}
