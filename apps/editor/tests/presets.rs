//! The preset browser and "Save selection as preset" (issue 30), driven through the UI with
//! egui_kittest: search the browser, insert a preset, save selected nodes as a preset that loads
//! and cooks to the same frames as the nodes it was made from.

use std::path::Path;

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Value};
use pyrograph_testing::workspace;

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app)
}

fn menu(h: &mut Harness<'_, EditorApp>, top: &str, item: &str) {
    h.get_by_label(top).click();
    h.run_steps(2);
    h.get_by_label(item).click();
    h.run_steps(3);
}

/// Frame `frame` of `endpoint` in the graph `doc` (built in `dir`), as RGBA floats.
fn frame(doc: &GraphDoc, dir: &Path, endpoint: &str, frame: usize) -> Vec<f32> {
    let g = Graph::build(doc, &pyrograph_frontend::registry(), dir, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let ctx = CookCtx::new();
    match Evaluator::new().output(&g, endpoint, &ctx).unwrap() {
        Value::Clip(c) => c.image(frame, &ctx).unwrap().data().to_vec(),
        other => panic!("{endpoint}: {}", other.summary()),
    }
}

#[test]
fn the_browser_searches_and_inserts_a_preset() {
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    let mut h = harness(EditorApp::new(ed));
    h.run_steps(2);
    menu(&mut h, "Presets", "Preset browser…");
    assert!(h.state().preset_browser_is_open());
    assert!(h.query_by_label("campfire").is_some(), "the shipped presets are listed");
    // The search field has the focus: typing filters the list.
    h.event(egui::Event::Text("gas ring".into()));
    h.run_steps(3);
    assert!(h.query_by_label("gas ring").is_some(), "the match is listed");
    assert!(h.query_by_label("campfire").is_none(), "and nothing else");
    h.get_by_label("gas ring").click();
    h.run_steps(3);
    let doc = h.state().editor.doc().clone();
    assert_eq!(doc.nodes.0.len(), 1, "one click inserts one node");
    let (id, nd) = &doc.nodes.0[0];
    assert_eq!(nd.type_name, "graph.include");
    assert!(matches!(nd.params.get("path"), Some(ParamValue::String(p)) if p.ends_with("gas-ring.ron")), "{:?}", nd.params);
    let ed = &h.state().editor;
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    let desc = ed.desc(id).unwrap();
    assert!(desc.outputs.iter().any(|p| p.name == "clip") && desc.inputs.iter().any(|p| p.name == "width"), "the preset's ports");
    let _ = ed;
    // Dragging a preset onto the canvas drops it where the pointer lets go.
    let from = h.get_by_label("gas ring").rect().center();
    let to = egui::pos2(640.0, 720.0);
    h.event(egui::Event::PointerMoved(from));
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Default::default(),
    });
    h.run_steps(2);
    for k in 1..=8 {
        h.event(egui::Event::PointerMoved(from + (to - from) * (k as f32 / 8.0)));
        h.run_steps(1);
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Default::default(),
    });
    h.run_steps(3);
    let doc = h.state().editor.doc().clone();
    assert_eq!(doc.nodes.0.len(), 2, "the drop inserts a second gas ring");
    let dropped = doc.nodes.0[1].1.pos.expect("placed");
    let want = h.state().canvas.to_graph(to);
    assert!((dropped.0 - want.x).abs() < 1.0 && (dropped.1 - want.y).abs() < 1.0, "dropped at {dropped:?}, pointer at {want:?}");
    let ed = &h.state().editor;
    // Tags filter too: a tag no gas ring carries empties the list.
    assert!(ed.browse_presets("", &["footage".into()]).iter().all(|p| p.meta.tags.contains(&"footage".into())));
    assert!(ed.browse_presets("gas ring", &["footage".into()]).is_empty());
}

#[test]
fn a_selection_saved_as_a_preset_cooks_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("candles.ron");
    let text = std::fs::read_to_string(workspace().join("graphs/candles.ron")).unwrap();
    std::fs::write(&graph, text.replace("\"frames\": 48", "\"frames\": 6")).unwrap();
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&graph).unwrap();
    let mut h = harness(EditorApp::new(ed));
    h.run_steps(2);
    let picked: Vec<String> = ["roots", "wind", "flames", "lights", "render"].iter().map(|s| s.to_string()).collect();
    h.state_mut().editor.set_selection(picked);
    h.run_steps(2);
    menu(&mut h, "Presets", "Save selection as preset…");
    // The name field has the focus; the file defaults to <graph folder>/presets/<name>.ron.
    h.event(egui::Event::Text("My candles".into()));
    h.run_steps(2);
    h.get_by_label("roots.count").click();
    h.run_steps(2);
    h.get_by_label("Save preset").click();
    h.run_steps(3);
    let file = dir.path().join("presets/my-candles.ron");
    assert!(file.exists(), "status: {:?}", h.state().editor.status().map(|s| s.text.clone()));
    assert!(h.state().save_preset.is_none(), "the dialog closes on success");

    let preset = GraphDoc::load(&file).unwrap();
    let meta = preset.preset.as_ref().unwrap();
    assert_eq!(meta.name, "My candles");
    let iface = preset.interface.as_ref().unwrap();
    assert_eq!(iface.params.get("count").map(String::as_str), Some("roots.count"));
    assert_eq!(iface.outputs.get("image").map(String::as_str), Some("render.image"), "the edge to the writer became the output");
    assert_eq!(preset.nodes.0.len(), 5, "the writer was not selected");
    // The browser finds it (the graph's presets/ folder is on the search path).
    assert_eq!(h.state().editor.browse_presets("my candles", &[]).len(), 1);

    // Included with its default count, it cooks the frames the original nodes cook.
    let mut wrapper = GraphDoc::new();
    wrapper.add_node("p", NodeDoc::new("graph.include").param("path", ParamValue::String(file.display().to_string())));
    let original = GraphDoc::load(&graph).unwrap();
    let a = frame(&original, dir.path(), "render.image", 3);
    let b = frame(&wrapper, dir.path(), "p.image", 3);
    assert_eq!(a.len(), b.len());
    assert!(a == b, "the preset cooks other pixels than the nodes it was made from");
    assert!(a.iter().any(|&v| v > 0.1), "and those frames are not empty");
    // The exposed parameter works: fewer candles, another frame.
    if let Some((_, n)) = wrapper.nodes.0.first_mut() {
        n.params.insert("count".into(), ParamValue::Int(2));
    }
    assert!(frame(&wrapper, dir.path(), "p.image", 3) != a, "count reaches the inner roots node");

    // Saving again under the same name refuses to overwrite unless ticked.
    menu(&mut h, "Presets", "Save selection as preset…");
    h.event(egui::Event::Text("My candles".into()));
    h.run_steps(2);
    h.get_by_label("Save preset").click();
    h.run_steps(3);
    let err = h.state().save_preset.as_ref().and_then(|d| d.error.clone()).unwrap_or_default();
    assert!(err.contains("exists"), "{err}");
}

#[test]
fn a_saved_preset_finds_its_files_and_keeps_the_include_path_free() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("footage")).unwrap();
    std::fs::copy(workspace().join("tests/golden/candles_0012.png"), dir.path().join("footage/frame.png")).unwrap();
    let graph = dir.path().join("shot.ron");
    let preset = workspace().join("graphs/presets/flame-card.ron");
    std::fs::write(
        &graph,
        format!(
            r#"(version: 1, nodes: {{
                "load": (type: "imaging.load_image", params: {{"path": "footage/frame.png"}}),
                "blur": (type: "imaging.gaussian_blur", params: {{"sigma": 2.0}}),
                "card": (type: "graph.include", params: {{"path": "{}"}}),
            }}, edges: [("load.image", "blur.image")])"#,
            preset.display()
        ),
    )
    .unwrap();
    let mut ed = Editor::with_default_registry();
    ed.auto_cook = false;
    ed.open(&graph).unwrap();
    ed.set_selection(vec!["load".into(), "blur".into()]);
    let spec = pyrograph_editor::state::SelectionPreset {
        name: "soft frame".into(),
        params: vec![("load".into(), "path".into()), ("blur".into(), "sigma".into())],
        ..Default::default()
    };
    let file = ed.save_selection_as_preset(&dir.path().join("presets/soft-frame.ron"), &spec).unwrap();
    let doc = GraphDoc::load(&file).unwrap();
    // The footage path now climbs out of presets/ to where the file is.
    assert!(
        matches!(doc.node("load").unwrap().params.get("path"), Some(ParamValue::String(p)) if p == "../footage/frame.png"),
        "{:?}",
        doc.node("load").unwrap().params
    );
    // `path` is the include node's own parameter: the exposed one is renamed.
    let iface = doc.interface.unwrap();
    assert_eq!(iface.params.get("load_path").map(String::as_str), Some("load.path"), "{:?}", iface.params);
    assert!(!iface.params.contains_key("path"));
    // Included from the graph's folder, it cooks the footage frame blurred.
    let mut wrapper = GraphDoc::new();
    wrapper.add_node("p", NodeDoc::new("graph.include").param("path", ParamValue::String("presets/soft-frame.ron".into())));
    let g = Graph::build(&wrapper, &pyrograph_frontend::registry(), dir.path(), &BuildOptions::default())
        .unwrap_or_else(|d| panic!("{d}"));
    let v = Evaluator::new().output(&g, "p.image", &CookCtx::new()).unwrap();
    assert!(matches!(v, Value::Image(ref i) if i.size() == (640, 360)), "{}", v.summary());
}
