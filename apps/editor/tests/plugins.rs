//! A Python plugin node in the editor: it is in the palette, it is added and wired, its preview
//! shows its frame, and editing its file then choosing File ▸ Reload plugins re-cooks it alone
//! (what feeds it is served from the cache), by the recompute log.

use std::path::Path;

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
mod common;

use common::{preview_of, settle};
use pyrograph_editor::{Editor, EditorApp};
use pyrograph_frontend::plugins::PluginFlags;
use pyrograph_testing::{python_with_numpy, workspace};

fn harness(app: EditorApp) -> Harness<'static, EditorApp> {
    Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app)
}

/// The heat-haze example (graph and plugins/ folder) copied to `dir`, so the test can edit it.
fn copy_example(dir: &Path) -> std::path::PathBuf {
    let example = workspace().join("examples/plugins/heat_haze");
    std::fs::create_dir(dir.join("plugins")).unwrap();
    std::fs::copy(example.join("plugins/heat_haze.py"), dir.join("plugins/heat_haze.py")).unwrap();
    std::fs::copy(example.join("heat-haze.ron"), dir.join("heat-haze.ron")).unwrap();
    dir.join("heat-haze.ron")
}

fn cooked(h: &mut Harness<'_, EditorApp>) -> Vec<String> {
    h.state_mut().editor.take_outcomes().into_iter().flat_map(|o| o.log).collect()
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_plugin_node_is_in_the_palette_wires_previews_and_recooks_alone_after_a_reload() {
    let dir = tempfile::tempdir().unwrap();
    let graph = copy_example(dir.path());
    let flags = PluginFlags { python: Some(python_with_numpy()), ..PluginFlags::default() };
    let mut ed = Editor::with_plugins(flags);
    ed.open(&graph).unwrap();
    assert!(ed.validation().diagnostics.is_empty(), "{:?}", ed.validation().diagnostics);
    let mut h = harness(EditorApp::new(ed));
    settle(&mut h);

    // The palette lists it with its doc, and Enter adds one.
    h.key_press(egui::Key::Tab);
    h.run_steps(2);
    h.event(egui::Event::Text("heat haze".into()));
    h.run_steps(2);
    assert!(h.query_by_label("studio.heat_haze").is_some(), "the palette lists the plugin node");
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let added = h.state().editor.doc().nodes.0.iter().find(|(id, n)| id != "haze" && n.type_name == "studio.heat_haze");
    let added = added.map(|(id, _)| id.clone()).expect("a second heat haze node");
    // Wired like any node: the flame into its image input.
    h.state_mut().editor.connect("flame", "clip", &added, "image").expect("Clip<Image> into the plugin's image input");

    // Previewed: its frame arrives from Python.
    let _ = cooked(&mut h);
    let before = preview_of(&mut h, "haze");
    let first = cooked(&mut h);
    assert!(first.contains(&"haze".to_string()), "{first:?}");

    // Edit the plugin (half the displacement) and reload through the File menu.
    let plugin = dir.path().join("plugins/heat_haze.py");
    let text = std::fs::read_to_string(&plugin).unwrap();
    assert!(text.contains("return amount * np.sin"), "the example's wave line moved: update this test");
    std::fs::write(&plugin, text.replace("return amount * np.sin", "return 0.5 * amount * np.sin")).unwrap();
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Reload plugins").click();
    h.run_steps(2);
    let after = preview_of(&mut h, "haze");
    let log = cooked(&mut h);
    assert!(log.contains(&"haze".to_string()), "the edited plugin's node re-cooks: {log:?}");
    assert!(!log.contains(&"flame".to_string()), "what feeds it comes from the cache: {log:?}");
    assert_ne!(before, after, "the preview shows the edited plugin's frame");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn the_whole_clip_and_emitter_examples_preview_in_the_editor() {
    for (graph, node) in [("temporal_median/temporal-median.ron", "median"), ("csv_emitter/csv-emitter.ron", "view")] {
        let flags = PluginFlags { python: Some(python_with_numpy()), ..PluginFlags::default() };
        let mut ed = Editor::with_plugins(flags);
        ed.open(&workspace().join("examples/plugins").join(graph)).unwrap();
        assert!(ed.validation().diagnostics.is_empty(), "{graph}: {:?}", ed.validation().diagnostics);
        let mut h = harness(EditorApp::new(ed));
        settle(&mut h);
        let pixels = preview_of(&mut h, node);
        assert!(pixels.chunks(4).any(|p| p[0] > 60), "{graph}: the preview of '{node}' shows fire");
    }
}
