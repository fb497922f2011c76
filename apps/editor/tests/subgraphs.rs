//! Subgraphs through the UI (issue 46): step into an included preset with a double-click,
//! change an inner node, step out with the breadcrumb, save, reload and cook (the change is
//! there, the shipped preset file keeps its bytes); collapse a selection into a subgraph
//! (the same frames); each with undo back to the original document byte for byte.

use eframe::egui::{self, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
mod common;

use common::{preview_of, settle};
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Value};

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    // Steps of 1/60 s, so that two clicks a few steps apart are a double-click (kittest's default
    // step is a quarter of a second, longer than egui's double-click delay).
    Harness::builder()
        .with_size(egui::vec2(1400.0, 900.0))
        .with_step_dt(1.0 / 60.0)
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app)
}

/// Every frame of `endpoint` (a clip of images) of graph file `file`, as raw samples.
fn frames_of(file: &std::path::Path, endpoint: &str) -> Vec<Vec<f32>> {
    let registry = pyrograph_frontend::registry();
    let (_, g) = Graph::load(file, &registry, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let ctx = CookCtx::new();
    let Ok(Value::Clip(clip)) = Evaluator::new().output(&g, endpoint, &ctx) else { panic!("{endpoint} is not a clip") };
    (0..clip.len())
        .map(|i| match clip.get(i, &ctx) {
            Ok(Value::Image(img)) => img.data().to_vec(),
            other => panic!("frame {i} of {endpoint}: {other:?}"),
        })
        .collect()
}

fn double_click(h: &mut Harness<'_, EditorApp>, at: egui::Pos2) {
    h.event(egui::Event::PointerMoved(at));
    for _ in 0..2 {
        for pressed in [true, false] {
            h.event(egui::Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Modifiers::NONE,
            });
            h.step();
        }
    }
    h.run_steps(3);
}

#[test]
fn step_into_the_campfire_preset_change_an_inner_node_step_out_save_reload_and_cook() {
    let preset = pyrograph_testing::workspace().join("graphs/presets/campfire.ron");
    let shipped = std::fs::read(&preset).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let main = dir.path().join("fire.ron");
    let text = format!(
        "(\n    version: 1,\n    nodes: {{\n        \"fire\": (type: \"graph.include\", params: {{\"path\": {:?}, \"frames\": 2, \"width\": 96, \"height\": 54}}, pos: (40, 40)),\n    }},\n)\n",
        preset.display().to_string()
    );
    std::fs::write(&main, &text).unwrap();
    let before = frames_of(&main, "fire.clip");

    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&main).unwrap();
    let original = ed.doc().to_ron();
    let mut app = EditorApp::new(ed);
    app.canvas.frame_all();
    let mut h = harness(app);
    h.run_steps(6);

    // A double-click on the include's header steps inside: the preset's nodes on the canvas.
    let header = h.state().canvas.node_screen_rect("fire").expect("on screen").min + egui::vec2(30.0, 20.0);
    double_click(&mut h, header);
    assert_eq!(h.state().editor.scope_prefix(), "fire/", "{:?} {header:?}", h.state().editor.status());
    assert!(h.state().editor.doc().node("flames").is_some(), "inside: {}", h.state().editor.doc().to_ron());
    assert!(
        h.query_by_label_contains("edits here make a local copy").is_some()
            || h.query_by_label_contains("an edit here makes a local copy").is_some()
    );

    // A parameter the include sets through the preset's exposed ones shows what cooks and where
    // it comes from, not an editor that would change nothing: the render's width is fire's 96.
    h.state_mut().editor.select("render");
    h.run_steps(3);
    assert!(h.query_by_label_contains("96 (set by fire's width)").is_some(), "the inspector marks render.width");
    assert!(h.query_by_label_contains("(set by fire's frames)").is_none(), "render has no `frames`");

    // Change an inner node (one the preset does not expose): the flames' size.
    h.state_mut().editor.select("flames");
    h.state_mut().editor.set_param("flames", "size", ParamValue::Float(0.3)).unwrap();
    h.state_mut().editor.seal();
    h.run_steps(3);
    assert!(h.query_by_label_contains("local copy of campfire.ron").is_some(), "the breadcrumb says it is a local copy now");

    // The breadcrumb's first button goes back to the top level.
    h.get_by_label("⬆ fire.ron").click();
    h.run_steps(3);
    assert!(h.state().editor.scope().is_empty());
    assert!(h.state().editor.is_local("fire"));
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::S);
    h.run_steps(2);
    assert!(!h.state().editor.is_dirty(), "{:?}", h.state().editor.status());
    assert_eq!(std::fs::read(&preset).unwrap(), shipped, "the shipped preset file is byte-identical");

    // Reloaded, the change is there and cooks.
    let mut again = Editor::with_default_registry();
    again.auto_cook = false;
    again.open(&main).unwrap();
    let local = &again.doc().subgraphs["fire"];
    assert_eq!(local.node("flames").unwrap().params["size"], ParamValue::Float(0.3));
    let after = frames_of(&main, "fire.clip");
    assert_eq!(after.len(), before.len());
    assert!(after != before, "bigger flames cook other frames");

    // Undo walks back to the document as opened, byte for byte.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().to_ron(), original);
    assert!(h.state().editor.doc().subgraphs.is_empty());
}

/// A small orange frame, a bloom, then a gray conversion.
fn chain() -> GraphDoc {
    let f = ParamValue::Float;
    let mut doc = GraphDoc::new();
    let color = NodeDoc::new("imaging.constant_color")
        .param("width", ParamValue::Int(64))
        .param("height", ParamValue::Int(48))
        .param("color", ParamValue::List(vec![f(0.8), f(0.5), f(0.2), f(1.0)]));
    doc.add_node("color", NodeDoc { pos: Some((0.0, 0.0)), ..color });
    doc.add_node("bloom", NodeDoc { pos: Some((300.0, 0.0)), ..NodeDoc::new("imaging.bloom") });
    doc.add_node("gray", NodeDoc { pos: Some((600.0, 0.0)), ..NodeDoc::new("imaging.to_gray") });
    doc.connect("color.image", "bloom.image").connect("bloom.image", "gray.image");
    doc
}

#[test]
fn collapse_a_selection_into_a_subgraph_cooks_the_same_frame_and_undoes_byte_for_byte() {
    let mut ed = Editor::with_default_registry();
    ed.edit(None, |d| *d = chain());
    ed.seal();
    let original = ed.doc().to_ron();
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);
    let gray = preview_of(&mut h, "gray");
    let bloomed = preview_of(&mut h, "bloom");

    // Select the bloom and the gray node, then Ctrl+Shift+G.
    h.state_mut().editor.set_selection(vec!["bloom".into(), "gray".into()]);
    h.run_steps(2);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, egui::Key::G);
    settle(&mut h);
    let doc = h.state().editor.doc().clone();
    assert!(doc.node("bloom").is_none() && doc.node("subgraph").is_some(), "{}", doc.to_ron());
    assert_eq!(doc.edges, [("color.image".to_string(), "subgraph.bloom_image".to_string())]);
    assert!(h.state().editor.validation().graph.is_some(), "{:?}", h.state().editor.validation().diagnostics);

    // Inside, the bloom shows what it showed before; the subgraph's output is the gray frame.
    h.state_mut().editor.step_into("subgraph").unwrap();
    assert_eq!(preview_of(&mut h, "bloom"), bloomed);
    h.state_mut().editor.step_out();
    assert_eq!(preview_of(&mut h, "subgraph"), gray, "the collapsed graph's output: gray's frame");

    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().editor.doc().to_ron(), original, "one undo step");
}

#[test]
fn save_into_preset_asks_first_naming_the_graphs_that_use_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("presets")).unwrap();
    let preset = dir.path().join("presets/p.ron");
    let text = "(\n    version: 1,\n    interface: Some((outputs: {\"y\": \"v.value\"})),\n    nodes: {\"v\": (type: \"value.float\", params: {\"value\": 1.0})},\n)\n";
    std::fs::write(&preset, text).unwrap();
    let include = |name: &str| {
        format!("(version: 1, nodes: {{\"{name}\": (type: \"graph.include\", params: {{\"path\": \"presets/p.ron\"}})}})")
    };
    std::fs::write(dir.path().join("main.ron"), include("p")).unwrap();
    std::fs::write(dir.path().join("other.ron"), include("o")).unwrap();
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&dir.path().join("main.ron")).unwrap();
    ed.step_into("p").unwrap();
    ed.set_param("v", "value", ParamValue::Float(5.0)).unwrap();
    ed.seal();
    let mut h = harness(EditorApp::new(ed));
    h.run_steps(3);
    h.get_by_label("Save into preset…").click();
    h.run_steps(3);
    assert!(h.query_by_label_contains("1 other graph(s) use this preset").is_some());
    assert!(h.query_by_label_contains("other.ron").is_some(), "the other graph is named");
    assert_eq!(std::fs::read_to_string(&preset).unwrap(), text, "nothing written before the confirmation");
    h.get_by_label("Write the preset file").click();
    h.run_steps(3);
    let written = GraphDoc::load(&preset).unwrap();
    assert_eq!(written.node("v").unwrap().params["value"], ParamValue::Float(5.0));
    assert!(!h.state().editor.is_local("p") && h.state().editor.scope().is_empty());
}
