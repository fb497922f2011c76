//! Done-when tests of the editor: logic through `Editor`, UI through egui_kittest (headless).

use std::sync::Arc;
use std::time::{Duration, Instant};

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
mod common;

use common::settle;
use pyrograph_editor::action::Action;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{Cook, CookCtx, GraphDoc, NodeDoc, NodeError, ParamValue, Registry};
use pyrograph_testing::workspace;

const WAIT: Duration = Duration::from_secs(20);

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app)
}

#[test]
fn palette_search_adds_a_node_through_the_ui() {
    let mut h = harness(EditorApp::new(Editor::with_default_registry()));
    h.key_press(egui::Key::Tab);
    h.run_steps(2);
    assert!(h.state().palette_is_open(), "Tab opens the palette");
    h.event(egui::Event::Text("constant color".into()));
    h.run_steps(2);
    // The search matched by name; the best match is listed and Enter adds it.
    assert!(h.query_by_label("imaging.constant_color").is_some(), "palette lists the match");
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let doc = h.state().editor.doc().clone();
    assert_eq!(doc.nodes.0.len(), 1);
    assert_eq!(doc.nodes.0[0].1.type_name, "imaging.constant_color");
    assert!(!h.state().palette_is_open());
    // The canvas shows it, and the search works on doc text and categories too.
    assert_eq!(h.state().canvas.node_ids(), vec!["constant_color".to_string()]);
    let ed = &h.state().editor;
    assert!(ed.palette("filled with one colour").iter().any(|i| i.type_name == "imaging.constant_color"));
    assert!(ed.palette("math").iter().any(|i| i.type_name == "math.add"));
    assert!(ed.palette("flame card").iter().any(|i| i.preset.is_some()), "presets are in the palette");
}

#[test]
fn connections_go_through_the_type_checker() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let a = ed.add_node("value.float", (0.0, 0.0)).unwrap();
    let add = ed.add_node("math.add", (200.0, 0.0)).unwrap();
    let img = ed.add_node("imaging.constant_color", (0.0, 200.0)).unwrap();
    ed.connect(&a, "value", &add, "a").expect("Float -> Float connects");
    assert!(ed.doc().edges.contains(&("float.value".into(), "add.a".into())));
    let err = ed.connect(&img, "image", &add, "b").expect_err("Image -> Float is refused");
    assert!(err.contains("needs Float, got Image"), "{err}");
    assert_eq!(ed.doc().edges.len(), 1, "a refused connection is not made");
    // A cycle is refused too.
    let err = ed.connect(&add, "value", &add, "b").expect_err("self loop");
    assert!(err.contains("itself"), "{err}");

    // Through the UI: the canvas gesture goes through the same check and the reason is shown.
    let mut h = harness(EditorApp::new(ed));
    h.run_steps(2);
    assert_eq!(h.state().canvas.wire_count(), 1);
    h.state_mut()
        .apply(vec![Action::Connect { from: ("constant_color".into(), "image".into()), to: ("add".into(), "b".into()) }]);
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("type mismatch: needs Float, got Image").count() >= 1, "reason shown in the UI");
    assert_eq!(h.state().canvas.wire_count(), 1);
    h.state_mut().apply(vec![Action::Connect { from: ("float".into(), "value".into()), to: ("add".into(), "b".into()) }]);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().edges.len(), 2);
    assert_eq!(h.state().canvas.wire_count(), 2, "the canvas follows the document");
}

fn chain_editor() -> Editor {
    // a ─┐
    //    add ── mul          (the previewed cone)
    // b ─┘
    // other ── other_mul     (not in the cone)
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = true;
    let mut doc = GraphDoc::new();
    doc.add_node("a", NodeDoc::new("value.float").param("value", ParamValue::Float(1.0)));
    doc.add_node("b", NodeDoc::new("value.float").param("value", ParamValue::Float(2.0)));
    doc.add_node("add", NodeDoc::new("math.add"));
    doc.add_node("mul", NodeDoc::new("math.multiply").param("b", ParamValue::Float(10.0)));
    doc.add_node("other", NodeDoc::new("value.float"));
    doc.add_node("other_mul", NodeDoc::new("math.multiply"));
    doc.connect("a.value", "add.a").connect("b.value", "add.b").connect("add.value", "mul.a");
    doc.connect("other.value", "other_mul.a");
    ed.edit(None, |d| *d = doc);
    ed
}

#[test]
fn editing_a_parameter_recooks_only_the_downstream() {
    let mut ed = chain_editor();
    ed.select("mul");
    assert!(ed.wait_idle(WAIT));
    let first = ed.take_outcomes();
    let cold: Vec<String> = first.iter().flat_map(|o| o.log.clone()).collect();
    let mut sorted = cold.clone();
    sorted.sort();
    assert_eq!(sorted, ["a", "add", "b", "mul"], "cold cook covers exactly the cone");
    assert_eq!(ed.preview().unwrap().summary, "30");

    ed.set_param("b", "value", ParamValue::Float(5.0)).unwrap();
    assert!(ed.wait_idle(WAIT));
    let log: Vec<String> = ed.take_outcomes().iter().flat_map(|o| o.log.clone()).collect();
    assert_eq!(log, ["b", "add", "mul"], "only the edited node and its downstream re-cook");
    assert_eq!(ed.preview().unwrap().summary, "60");

    // Through the UI: the preview panel shows the re-cooked value.
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    assert!(h.query_by_label("60").is_some(), "preview shows the scalar");
    h.state_mut().editor.set_param("a", "value", ParamValue::Float(0.0)).unwrap();
    settle(&mut h);
    assert!(h.query_by_label("50").is_some(), "preview re-cooked after the edit");
    let log: Vec<String> = h.state_mut().editor.take_outcomes().iter().flat_map(|o| o.log.clone()).collect();
    assert!(log.ends_with(&["a".to_string(), "add".into(), "mul".into()]), "{log:?}");
    assert!(!log.contains(&"b".to_string()) && !log.contains(&"other".to_string()), "{log:?}");
}

#[test]
fn every_edit_undoes_and_redoes() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut states = vec![ed.doc().clone()];
    let a = ed.add_node("value.float", (0.0, 0.0)).unwrap();
    states.push(ed.doc().clone());
    let m = ed.add_node("math.multiply", (200.0, 0.0)).unwrap();
    states.push(ed.doc().clone());
    ed.connect(&a, "value", &m, "a").unwrap();
    states.push(ed.doc().clone());
    // A slider drag: many changes of one parameter are one step.
    for v in [0.1, 0.2, 0.3, 0.4] {
        ed.set_param(&m, "b", ParamValue::Float(v)).unwrap();
    }
    ed.seal();
    states.push(ed.doc().clone());
    ed.move_node(&a, (10.0, 20.0));
    ed.seal();
    states.push(ed.doc().clone());
    let dups = ed.duplicate(std::slice::from_ref(&m));
    assert_eq!(dups.len(), 1);
    states.push(ed.doc().clone());
    ed.reset_param(&m, "b");
    states.push(ed.doc().clone());
    ed.remove_nodes(std::slice::from_ref(&a));
    assert!(ed.doc().edges.is_empty(), "edges of a deleted node go with it");
    states.push(ed.doc().clone());

    for expected in states.iter().rev().skip(1) {
        assert!(ed.undo());
        assert_eq!(ed.doc(), expected);
    }
    assert!(!ed.undo(), "nothing left to undo");
    for expected in states.iter().skip(1) {
        assert!(ed.redo());
        assert_eq!(ed.doc(), expected);
    }
    assert!(!ed.redo());

    // Keyboard shortcuts in the UI.
    let mut h = harness(EditorApp::new(ed));
    let last = h.state().editor.doc().clone();
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc(), &states[states.len() - 2]);
    h.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc(), &last);
}

#[test]
fn save_and_reload_give_an_identical_document() {
    let dir = tempfile::tempdir().unwrap();
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&workspace().join("graphs/candles.ron")).unwrap();
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    assert!(!ed.is_dirty());
    ed.set_param("roots", "count", ParamValue::Int(7)).unwrap();
    assert!(ed.is_dirty() && ed.title().starts_with("* "));
    let out = dir.path().join("candles-edited.ron");
    ed.save_as(&out).unwrap();
    assert!(!ed.is_dirty() && !ed.title().starts_with("* "));
    let mut fresh = Editor::with_default_registry();
    fresh.auto_cook = false;
    fresh.open(&out).unwrap();
    assert_eq!(fresh.doc(), ed.doc());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), ed.doc().to_ron());
    assert!(fresh.recent().iter().any(|p| p.ends_with("candles-edited.ron")));
    // Save again in place, with no temp files left behind.
    fresh.set_param("roots", "count", ParamValue::Int(3)).unwrap();
    fresh.save().unwrap();
    assert_eq!(GraphDoc::load(&out).unwrap(), *fresh.doc());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().filter_map(|e| e.ok()).collect();
    assert_eq!(leftovers.len(), 1);
}

#[test]
fn presets_insert_as_include_nodes() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let preset = workspace().join("graphs/presets/flame-card.ron");
    let id = ed.add_preset(&preset, (0.0, 0.0)).unwrap();
    let nd = ed.doc().node(&id).unwrap();
    assert_eq!(nd.type_name, "graph.include");
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    let desc = ed.desc(&id).unwrap();
    assert!(desc.outputs.iter().any(|p| p.name == "clip"), "include exposes the preset's outputs");
    assert!(desc.inputs.iter().any(|p| p.name == "seed"), "and its parameters");
}

#[test]
fn a_broken_graph_opens_with_errors_on_its_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        r#"(
    version: 1,
    nodes: {
        "color": (type: "imaging.constant_color", params: {"width": -4}),
        "mystery": (type: "imaging.no_such_node"),
        "add": (type: "math.add"),
        "gray": (type: "imaging.to_gray"),
    },
    edges: [("color.image", "add.a"), ("ghost.value", "add.b")],
)"#,
    )
    .unwrap();
    let mut ed = Editor::with_default_registry();
    ed.open(&bad).expect("a file that parses opens");
    let v = ed.validation();
    assert!(v.graph.is_none());
    for node in ["color", "mystery", "add", "gray"] {
        assert!(v.by_node.contains_key(node), "problem mapped to node {node}: {:?}", v.by_node);
    }
    let mut h = harness(EditorApp::new(ed));
    h.run_steps(3);
    assert!(h.query_all_by_label_contains("unknown node type 'imaging.no_such_node'").count() >= 1);
    assert!(h.query_all_by_label_contains("outside the range").count() >= 1);
    assert!(h.query_all_by_label_contains("type mismatch").count() >= 1);
    // Selecting a node shows its problems in the inspector too.
    h.state_mut().editor.select("gray");
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("required input 'image'").count() >= 2);

    // A file that does not even parse: reported, empty document, never adopted for saving.
    let garbage = dir.path().join("garbage.ron");
    std::fs::write(&garbage, "(version: 1, nodes: { \"a\": (type: ").unwrap();
    let r = h.state_mut().editor.open(&garbage);
    assert!(r.is_err());
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("malformed graph").count() >= 1);
    assert!(h.state().editor.path().is_none());
    // Missing file.
    assert!(h.state_mut().editor.open(&dir.path().join("nope.ron")).is_err());
    h.run_steps(2);
}

pyrograph_frontend::core::node! {
    /// Takes a while.
    #[node("test.slow", "Test", Source)]
    pub struct Slow {
        /// How long.
        #[range(0.0, 100.0)]
        seconds: f64 = 1.0,
    }
    /// The duration.
    -> value: f64
}

impl Cook for Slow {
    fn cook(self, ctx: &CookCtx) -> Result<f64, NodeError> {
        let secs = self.seconds;
        let start = Instant::now();
        let mut n = 0;
        while start.elapsed().as_secs_f64() < secs {
            ctx.check_cancel()?;
            std::thread::sleep(Duration::from_millis(2));
            n += 1;
            ctx.frame_progress(n, (secs * 500.0) as usize);
        }
        Ok(secs)
    }
}

fn slow_registry() -> Arc<Registry> {
    let mut r = pyrograph_frontend::registry();
    r.declare::<Slow>();
    Arc::new(r)
}

#[test]
fn a_long_cook_keeps_the_ui_responsive_and_cancel_stops_it() {
    let mut ed = Editor::new(slow_registry());
    let id = ed.add_node("test.slow", (0.0, 0.0)).unwrap();
    ed.set_param(&id, "seconds", ParamValue::Float(30.0)).unwrap();
    let mut h = harness(EditorApp::new(ed));
    h.state_mut().editor.select(&id);
    let mut times = Vec::new();
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(800) {
        let t = Instant::now();
        h.step();
        times.push(t.elapsed().as_secs_f64() * 1000.0);
    }
    assert!(h.state().editor.is_cooking(), "the cook is still running");
    let worst = times.iter().cloned().fold(0.0, f64::max);
    assert!(times.len() >= 10, "frames kept coming: {}", times.len());
    assert!(worst < 50.0, "frame times stay under 50 ms while cooking, worst {worst:.1} ms");
    assert!(h.query_by_label("Cancel").is_some(), "progress with a cancel button");
    h.get_by_label("Cancel").click();
    let t = Instant::now();
    settle(&mut h);
    assert!(t.elapsed() < Duration::from_secs(5), "cancel stops the cook promptly");
    assert!(!h.state().editor.is_cooking());
    let outcome = h.state().editor.last_outcome().unwrap();
    assert!(outcome.cancelled);
}

pyrograph_frontend::core::node! {
    /// Warns above 0.5.
    #[node("test.warn", "Test", Source)]
    pub struct Warn {
        /// How much.
        #[range(0.0, 1.0)]
        level: f64 = 0.9,
    }
    /// The level.
    -> value: f64
}

impl Cook for Warn {
    fn cook(self, ctx: &CookCtx) -> Result<f64, NodeError> {
        if self.level > 0.5 {
            ctx.warn(format!("level {} is above 0.5", self.level));
        }
        Ok(self.level)
    }
}

#[test]
fn warnings_show_on_their_node_until_it_cooks_again() {
    let mut r = pyrograph_frontend::registry();
    r.declare::<Warn>();
    let mut ed = Editor::new(Arc::new(r));
    let w = ed.add_node("test.warn", (0.0, 0.0)).unwrap();
    let add = ed.add_node("math.add", (200.0, 0.0)).unwrap();
    ed.connect(&w, "value", &add, "a").unwrap();
    let mut h = harness(EditorApp::new(ed));
    h.state_mut().editor.select(&w);
    settle(&mut h);
    assert_eq!(h.state().editor.node_warnings(&w), vec!["level 0.9 is above 0.5".to_string()]);
    assert!(h.query_by_label("⚠ warning: level 0.9 is above 0.5").is_some(), "the inspector shows it");
    // Another node re-cooks while the cache serves this one: its warning stays.
    h.state_mut().editor.take_outcomes();
    h.state_mut().editor.set_param(&add, "b", ParamValue::Float(2.0)).unwrap();
    h.state_mut().editor.select(&add);
    settle(&mut h);
    let cooked: Vec<String> = h.state_mut().editor.take_outcomes().into_iter().flat_map(|o| o.log).collect();
    assert!(cooked.contains(&add) && !cooked.contains(&w), "served from the cache: {cooked:?}");
    assert_eq!(h.state().editor.node_warnings(&w).len(), 1);
    // Fixed, it cooks again and the warning goes.
    h.state_mut().editor.set_param(&w, "level", ParamValue::Float(0.2)).unwrap();
    settle(&mut h);
    assert!(h.state().editor.node_warnings(&w).is_empty());
}

#[test]
fn control_characters_in_a_graph_show_escaped_in_the_status_and_on_the_node() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ron");
    let id = "a\u{1b}]0;PWNED\u{7}b\r\u{0}";
    std::fs::write(
        &bad,
        r#"(version: 3, nodes: {"a\u{1b}]0;PWNED\u{7}b\r\u{0}": (type: "imaging.no_such\u{1b}[2J")}, edges: [])"#,
    )
    .unwrap();
    let mut ed = Editor::with_default_registry();
    ed.open(&bad).expect("a file that parses opens");
    let status = ed.status().expect("a status").text.clone();
    let raw = |t: &str| t.chars().any(|c| matches!(c, '\u{0}' | '\u{7}' | '\r' | '\u{1b}'));
    assert!(!raw(&status), "{status:?}");
    assert!(status.contains(r"a\u{1b}]0;PWNED\u{7}b\u{d}\u{0}") && status.contains(r"imaging.no_such\u{1b}[2J"), "{status}");
    let problems = ed.node_problems(id);
    assert!(!problems.is_empty() && problems.iter().all(|p| !raw(p)), "{problems:?}");
    // A 100 kB id is cut in the status line.
    let long = dir.path().join("long.ron");
    std::fs::write(&long, format!(r#"(version: 3, nodes: {{"{}": (type: "nope")}}, edges: [])"#, "x".repeat(100_000))).unwrap();
    ed.open(&long).expect("a file that parses opens");
    let status = &ed.status().expect("a status").text;
    assert!(status.len() < 2_000 && status.contains("more characters]"), "{} bytes", status.len());
}
