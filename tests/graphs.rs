//! Every shipped graph round-trips through RON; old shapes migrate; the node reference is current;
//! example graphs match their golden frames (regenerate on purpose with REGENERATE=1).

use std::path::{Path, PathBuf};

use pyrograph_frontend::core::{BuildOptions, CookCtx, CookSettings, Evaluator, FrameSet, Graph, GraphDoc, Value};
use pyrograph_testing::workspace;

fn ron_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(ron_files(&path));
        } else if path.extension().is_some_and(|e| e == "ron") {
            out.push(path);
        }
    }
    out.sort();
    out
}

#[test]
fn every_graph_round_trips_load_save_load() {
    let files = ron_files(&workspace().join("graphs"));
    assert!(files.len() >= 3, "graphs/ holds the demo, candle-gray and presets");
    let dir = tempfile::tempdir().unwrap();
    for file in files {
        let doc = GraphDoc::load(&file).unwrap_or_else(|d| panic!("{d}"));
        let saved = dir.path().join(file.file_name().unwrap());
        doc.save(&saved, true).unwrap();
        let again = GraphDoc::load(&saved).unwrap_or_else(|d| panic!("{}: {d}", saved.display()));
        assert_eq!(doc, again, "{} changed in a round trip", file.display());
    }
}

#[test]
fn the_unversioned_shape_migrates_and_cooks() {
    let path = workspace().join("tests/fixtures/migrate/v0.ron");
    let (doc, graph) =
        Graph::load(&path, &pyrograph_frontend::registry(), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(doc.version, pyrograph_frontend::core::document::CURRENT_VERSION, "migrated to the newest version in memory");
    assert_eq!(doc.node("card").unwrap().pos, Some((10.0, 20.0)));
    let gray = Evaluator::new().output(&graph, "gray.image", &CookCtx::new()).unwrap();
    let Value::Image(img) = gray else { panic!("expected an image") };
    assert_eq!(img.size(), (16, 8));
    assert!((img.data()[0] - 0.5).abs() < 1e-6, "average of (1, 0.5, 0) is 0.5");
    // Without groups or comments it saves as version 1 (what older readers know), which loads as is.
    let text = doc.to_ron();
    assert!(text.contains("version: 1"));
    assert_eq!(GraphDoc::from_ron(&text).unwrap(), doc);
}

/// Whether the goldens (and docs/nodes.md) are to be rewritten: only for `REGENERATE=1`, so a
/// stray `REGENERATE=0` or empty value cannot turn the comparisons into copies.
fn regenerate() -> bool {
    regenerate_from(std::env::var("REGENERATE").ok().as_deref())
}

fn regenerate_from(value: Option<&str>) -> bool {
    value == Some("1")
}

#[test]
fn only_regenerate_1_regenerates() {
    assert!(regenerate_from(Some("1")));
    for v in [None, Some("0"), Some(""), Some("true"), Some("yes")] {
        assert!(!regenerate_from(v), "{v:?}");
    }
}

#[test]
fn docs_nodes_md_is_current() {
    let expected = pyrograph_frontend::reference::markdown(&pyrograph_frontend::registry());
    let path = workspace().join("docs/nodes.md");
    if regenerate() {
        std::fs::write(&path, &expected).unwrap();
    }
    let actual = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(actual == expected, "docs/nodes.md is stale: run `cargo run --release -- nodes --markdown > docs/nodes.md`");
}

#[test]
fn every_registered_node_has_a_doc_and_documented_ports() {
    for d in pyrograph_frontend::registry().descs() {
        assert!(!d.doc.trim().is_empty(), "{} has no doc", d.type_name);
        for p in d.inputs.iter().chain(&d.outputs) {
            assert!(!p.doc.trim().is_empty(), "{}.{} has no doc", d.type_name, p.name);
        }
    }
}

/// Renders `graph` into a temp folder and compares chosen frames with tests/golden/.
fn golden(graph: &str, frames: (usize, usize), files: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    let path = workspace().join("graphs").join(graph);
    let options = BuildOptions { output_dir: Some(out.path().to_path_buf()), ..BuildOptions::default() };
    let (_, g) = Graph::load(&path, &pyrograph_frontend::registry(), &options).unwrap_or_else(|d| panic!("{d}"));
    let sinks: Vec<String> = g.sinks().iter().map(|s| s.to_string()).collect();
    let targets: Vec<&str> = sinks.iter().map(String::as_str).collect();
    let ctx = CookCtx::new()
        .with_settings(CookSettings { frames: Some(FrameSet::range(frames.0, frames.1)), ..CookSettings::default() });
    let res = Evaluator::new().cook(&g, &targets, &ctx).unwrap();
    assert!(res.is_ok(), "{:?}", res.root_errors());
    let golden_dir = workspace().join("tests/golden");
    for f in files {
        let made = out.path().join(f);
        let want = golden_dir.join(Path::new(f).file_name().unwrap());
        if regenerate() {
            std::fs::create_dir_all(&golden_dir).unwrap();
            std::fs::copy(&made, &want).unwrap();
        }
        let a = image::open(&made).unwrap().to_rgba8();
        let b = image::open(&want).unwrap_or_else(|e| panic!("{}: {e} (REGENERATE=1 creates it)", want.display())).to_rgba8();
        assert_eq!(a.dimensions(), b.dimensions(), "{f}");
        let worst = a.as_raw().iter().zip(b.as_raw()).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        assert!(worst <= 2, "{f} differs from its golden frame by up to {worst}/255");
    }
}

#[test]
fn demo_graph_matches_its_golden_frames() {
    // The burning cube in full flame: fire spread, char, lit mesh and particle flames.
    golden("demo.ron", (60, 60), &["demo_0060.png"]);
}

#[test]
fn candles_match_their_golden_frame() {
    golden("candles.ron", (12, 12), &["candles/candles_0012.png"]);
}

#[test]
fn campfire_matches_its_golden_frame() {
    // Flames on logs, sparks, lit logs and ground, bloom: every part of the campfire preset.
    golden("campfire.ron", (24, 24), &["campfire/campfire_0024.png"]);
}

#[test]
fn mass_spring_flames_match_their_golden_frame() {
    golden("mass-spring-9.ron", (30, 30), &["mass-spring-9/mass_spring_9_0030.png"]);
}

#[test]
fn flame_cards_match_their_golden_frames() {
    golden("flame-cards.ron", (5, 5), &["flame-cards/calm_0005.png", "flame-cards/wild_0005.png"]);
}

#[test]
fn ramps_and_points_in_the_old_text_forms_load_as_the_typed_values_they_spell() {
    let registry = pyrograph_frontend::registry();
    let path = workspace().join("tests/fixtures/migrate/v3-text-forms.ron");
    let (doc, old) = Graph::load(&path, &registry, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let mut typed = doc.clone();
    let set = |doc: &mut GraphDoc, node: &str, port: &str, ron: &str| {
        doc.set_param(node, port, pyrograph_frontend::core::ParamValue::parse_cli(ron)).unwrap();
    };
    // The text form sorted its keys; the typed form is written in order.
    set(
        &mut typed,
        "flames",
        "center_ramp",
        "[(0, (0.3, 0.4, 1, 0.12)), (0.15, (1, 0.8, 0.45, 0.16)), (1, (0.9, 0.2, 0.02, 0))]",
    );
    set(&mut typed, "flames", "width_ramp", "[(0, 0.67), (0.5, 1.07), (1, 0.67)]");
    set(&mut typed, "tint", "ramp", "[(0, (0, 0, 0)), (0.3, (0.6, 0.05, 0)), (1, (1, 0.95, 0.75))]");
    set(&mut typed, "spread", "ignite", "[(0.5, 0.2, -0.15), (1.5, face(3, (0.2, 0.3, 0.5))), (2, face(1))]");
    let new = Graph::build_file(&typed, &path, &registry, &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    for (node, port) in [("flames", "center_ramp"), ("flames", "width_ramp"), ("tint", "ramp"), ("spread", "ignite")] {
        let constant = |g: &Graph| {
            let n = g.node(g.index(node).unwrap());
            let i = n.node.desc().input_index(port).unwrap();
            match &n.inputs[i] {
                pyrograph_frontend::core::graph::InputSource::Const(v @ (Value::Ramp(_) | Value::Points(_))) => v.fingerprint(),
                other => panic!("{node}.{port} is {other:?}"),
            }
        };
        assert_eq!(constant(&old), constant(&new), "{node}.{port}");
    }
    // A typed key out of order is an error naming the key.
    set(&mut typed, "flames", "width_ramp", "[(0.5, 1.07), (0, 0.67)]");
    let e = Graph::build_file(&typed, &path, &registry, &BuildOptions::default()).err().unwrap().to_string();
    assert!(e.contains("width_ramp") && e.contains("key 2 at 0 comes before key 1"), "{e}");
    // So is a point that is no place.
    set(&mut typed, "flames", "width_ramp", "[(0, 0.67), (0.5, 1.07)]");
    set(&mut typed, "spread", "ignite", "[(0.5, 0.2, -0.15), (1.5, (0.2, 0.3))]");
    let e = Graph::build_file(&typed, &path, &registry, &BuildOptions::default()).err().unwrap().to_string();
    assert!(e.contains("'ignite'") && e.contains("point 2: a point is (x, y, z)"), "{e}");
}
