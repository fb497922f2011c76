//! The `pyrograph` binary over bad inputs (one fixture per validation class, plus bad image files)
//! and over the shipped graphs: exit codes, specific messages, and never a panic.

use std::path::PathBuf;
use std::process::{Command, Output};

use pyrograph_testing::workspace;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pyrograph"))
}

fn fixture(name: &str) -> PathBuf {
    workspace().join("tests/fixtures/bad").join(name)
}

fn run(args: &[&str]) -> Output {
    bin().args(args).env_remove("PYROGRAPH_TEST_UNSET_VARIABLE").output().expect("the binary runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Each bad fixture with the words its error must contain (node id, port, cause).
const BAD: &[(&str, &[&str])] = &[
    ("malformed.ron", &["malformed.ron", "line 5, column", "malformed graph"]),
    ("unknown_type.ron", &["node 'gray'", "unknown node type 'imaging.to_grey'", "did you mean 'imaging.to_gray'"]),
    ("unknown_port.ron", &["node 'gray', port 'img'", "has no input 'img'"]),
    ("unknown_param.ron", &["node 'card', port 'colour'", "has no parameter 'colour'"]),
    ("type_mismatch.ron", &["node 'out', port 'clip'", "type mismatch: needs Clip<Image>, got Image from 'card.image'"]),
    ("cycle.ron", &["cycle through nodes 'a', 'b'"]),
    ("missing_input.ron", &["node 'gray', port 'image'", "required input 'image' (Image) is not set"]),
    ("wrong_kind.ron", &["node 'card', port 'width'", "needs an integer, got \"wide\""]),
    ("out_of_range.ron", &["node 'card', port 'width'", "0 is outside the range 1..=16384"]),
    ("duplicate_id.ron", &["node 'card'", "duplicate node id"]),
    ("missing_node.ron", &["loader.clip -> gray.image", "node 'loader', which is not in the graph"]),
    ("missing_image.ron", &["node 'load'", "no-such-image.png"]),
    ("corrupt_png.ron", &["node 'load'", "corrupt.png"]),
    ("empty_file.ron", &["node 'load'", "empty.png"]),
    ("empty_graph_file.ron", &["empty_graph_file.ron", "malformed graph"]),
    ("newer_version.ron", &["graph version 9 is newer"]),
    ("bypass_nothing_to_pass.ron", &["node 'card'", "cannot be bypassed: its output 'image' is Image"]),
    ("unset_variable.ron", &["node 'frames', port 'path'", "environment variable PYROGRAPH_TEST_UNSET_VARIABLE is not set"]),
    ("outside_out.ron", &["node 'out', port 'path'", "card.png\" writes to", "outside the", "--allow-outside-out"]),
];

#[test]
fn check_and_render_fail_with_the_specific_message_on_every_bad_fixture() {
    let out_dir = tempfile::tempdir().unwrap();
    for (file, needles) in BAD {
        let path = fixture(file);
        let path = path.to_str().unwrap();
        for args in [vec!["check", path], vec!["render", path, "--out", out_dir.path().to_str().unwrap()]] {
            let o = run(&args);
            let all = text(&o);
            assert!(!all.contains("panicked"), "{args:?} panicked:\n{all}");
            assert_eq!(o.status.code(), Some(1), "{args:?} must exit 1:\n{all}");
            for n in *needles {
                assert!(all.contains(n), "{args:?}: expected {n:?} in:\n{all}");
            }
        }
    }
    assert_eq!(std::fs::read_dir(out_dir.path()).unwrap().count(), 0, "a failed render writes nothing");
}

#[test]
fn a_rejected_required_parameter_is_one_problem_not_two() {
    let o = run(&["check", "--json", fixture("unset_variable.ron").to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    assert_eq!(v["problems"].as_array().unwrap().len(), 1, "{v}");
}

#[test]
fn check_json_lists_every_problem_with_its_location() {
    let o = run(&["check", "--json", fixture("unknown_port.ron").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    assert_eq!(v["ok"], false);
    assert_eq!(v["problems"][0]["location"], "node 'gray', port 'img'");
    assert_eq!(v["problems"][0]["kind"], "UnknownPort");
}

#[test]
fn no_bad_fixture_is_left_untested() {
    let mut listed: Vec<&str> = BAD.iter().map(|(f, _)| *f).collect();
    listed.sort_unstable();
    let mut on_disk: Vec<String> = std::fs::read_dir(workspace().join("tests/fixtures/bad"))
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".ron"))
        .collect();
    on_disk.sort();
    assert_eq!(listed, on_disk);
}

#[test]
fn check_accepts_every_shipped_graph_that_needs_no_footage() {
    for entry in std::fs::read_dir(workspace().join("graphs")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        if path.extension().is_none_or(|e| e != "ron") || text.contains("${PYROGRAPH_FOOTAGE}") {
            continue;
        }
        let o = run(&["check", path.to_str().unwrap()]);
        assert!(o.status.success(), "{}:\n{}", path.display(), self::text(&o));
    }
}

#[test]
fn render_writes_with_set_and_frames_and_refuses_to_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let graph = workspace().join("graphs/flame-cards.ron");
    let graph = graph.to_str().unwrap();
    let o = run(&["render", graph, "--out", out, "--frames", "2-4", "--set", "calm.width=32"]);
    assert!(o.status.success(), "{}", text(&o));
    let calm: Vec<_> = std::fs::read_dir(dir.path().join("flame-cards")).unwrap().filter_map(|e| e.ok()).collect();
    assert_eq!(calm.len(), 6, "3 frames from each of the two writers");
    let img = image::open(dir.path().join("flame-cards/calm_0002.png")).unwrap();
    assert_eq!(img.width(), 32, "--set reached the preset's exposed width");

    let again = run(&["render", graph, "--out", out, "--frames", "2-4"]);
    assert_eq!(again.status.code(), Some(1));
    assert!(text(&again).contains("exists"), "{}", text(&again));
    let forced = run(&["render", graph, "--out", out, "--frames", "2-4", "--overwrite"]);
    assert!(forced.status.success(), "{}", text(&forced));
}

#[test]
fn a_cache_dir_that_is_not_a_folder_is_an_error_before_anything_cooks() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/flame-cards.ron");
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    for cache in [dir.path().join("missing"), file] {
        let o = run(&[
            "render",
            graph.to_str().unwrap(),
            "--out",
            dir.path().to_str().unwrap(),
            "--cache-dir",
            cache.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains("--cache-dir") && text(&o).contains("not a folder"), "{}", text(&o));
    }
    assert!(!dir.path().join("flame-cards").exists(), "nothing was written");
}

#[test]
fn bad_set_arguments_are_errors_not_panics() {
    let graph = workspace().join("graphs/demo.ron");
    let graph = graph.to_str().unwrap();
    for set in ["nobody.width=3", "render.width=huge", "no-equals-sign"] {
        let o = run(&["check", graph]);
        assert!(o.status.success());
        let o = run(&["render", graph, "--set", set, "--out", "/nonexistent-dir-never-written"]);
        assert_eq!(o.status.code(), Some(1), "--set {set}: {}", text(&o));
        assert!(!text(&o).contains("panicked"));
    }
}

#[test]
fn nodes_json_and_presets_list_what_is_there() {
    let o = run(&["nodes", "--json"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v.as_array().unwrap().iter().any(|n| n["type"] == "imaging.load_sequence"));

    let o = bin().args(["presets", "--json"]).current_dir(workspace()).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let card = v
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["file"].as_str().unwrap().ends_with("flame-card.ron"))
        .expect("flame-card listed");
    let params: Vec<&str> = card["params"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert!(params.contains(&"seed") && params.contains(&"turbulence"), "{params:?}");
}

#[test]
fn demo_writes_frames_and_says_where() {
    let dir = tempfile::tempdir().unwrap();
    let o = bin().current_dir(dir.path()).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("demo frames are in"), "{stdout}");
    let frames = std::fs::read_dir(dir.path().join("pyrograph-out")).unwrap().count();
    assert_eq!(frames, 120);
    // A second run replaces the demo's own frames rather than failing.
    assert!(bin().current_dir(dir.path()).output().unwrap().status.success());
}

#[test]
fn info_describes_a_graph() {
    let o = run(&["info", workspace().join("graphs/demo.ron").to_str().unwrap()]);
    assert!(o.status.success());
    let t = text(&o);
    assert!(t.contains("particles.render_fire") && t.contains("Clip<Image>") && t.contains("per frame over a clip"), "{t}");
}

#[test]
fn save_migrates_applies_set_and_refuses_to_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cards.ron");
    let out_s = out.to_str().unwrap();
    let graph = workspace().join("graphs/flame-cards.ron");
    let graph = graph.to_str().unwrap();
    let o = run(&["save", graph, "-o", out_s, "--set", "calm.turbulence=0.8"]);
    assert!(o.status.success(), "{}", text(&o));
    let saved = pyrograph_frontend::core::GraphDoc::load(&out).expect("the saved file loads");
    let mut expected = pyrograph_frontend::core::GraphDoc::load(std::path::Path::new(graph)).unwrap();
    expected.set_param("calm", "turbulence", pyrograph_frontend::core::ParamValue::Float(0.8)).unwrap();
    assert_eq!(saved, expected);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), expected.to_ron(), "what the editor and Python write");

    std::fs::write(&out, "mine").unwrap();
    let again = run(&["save", graph, "-o", out_s]);
    assert_eq!(again.status.code(), Some(1));
    assert!(text(&again).contains(out_s), "{}", text(&again));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine", "nothing was overwritten");
    assert!(run(&["save", graph, "-o", out_s, "--overwrite"]).status.success());

    // A pre-release (unversioned) file comes out in the current format.
    let old = workspace().join("tests/fixtures/migrate/v0.ron");
    let migrated = dir.path().join("migrated.ron");
    assert!(run(&["save", old.to_str().unwrap(), "-o", migrated.to_str().unwrap()]).status.success());
    let text = std::fs::read_to_string(&migrated).unwrap();
    assert!(text.contains("version: 1") && text.contains("type: \"imaging.constant_color\""), "{text}");
    assert!(!text.contains("kind:") && !text.contains("settings:"), "the old field names are gone: {text}");
}

/// Frames of an orange flame on black whose base is cut by the bottom edge in every frame,
/// masked by `imaging.hsv_auto_mask` and framed by `imaging.auto_crop`: the render succeeds and
/// says why its result may be wrong, in text and in `--json`.
#[test]
fn render_reports_a_flame_cut_by_the_bottom_edge_as_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    for f in 0..6u32 {
        let img = image::RgbaImage::from_fn(64, 48, |x, y| {
            let inside = (24 + f % 3..40).contains(&x) && y >= 10 + f;
            if inside { image::Rgba([255, 140, 25, 255]) } else { image::Rgba([6, 3, 2, 255]) }
        });
        img.save(dir.path().join(format!("cut_{f:04}.png"))).unwrap();
    }
    let graph = dir.path().join("cut.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "shots": (type: "imaging.load_sequence", params: {"path": "cut_####.png"}),
            "mask": (type: "imaging.hsv_auto_mask", params: {"stride": 1}),
            "crop": (type: "imaging.auto_crop"),
            "write": (type: "imaging.write_sequence", params: {"pattern": "out/crop_####.png"}),
        }, edges: [
            ("shots.clip", "mask.clip"), ("shots.clip", "crop.clip"), ("mask.mask", "crop.mask"), ("crop.clip", "write.clip"),
        ])"#,
    )
    .unwrap();
    let o = run(&["render", graph.to_str().unwrap(), "--out", dir.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(&format!(
            "warning: {}: node 'crop': the flame touches the bottom edge in 100 % of frames: its base is outside the picture",
            graph.display()
        )),
        "{stderr}"
    );
    let written = image::open(dir.path().join("out/crop_0000.png")).unwrap();
    assert_eq!((written.width() % 8, written.height() % 8), (0, 0), "cropped to multiples of 8");
    let o = run(&["render", graph.to_str().unwrap(), "--out", dir.path().to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let warnings = v["warnings"].as_array().unwrap();
    assert!(warnings.iter().any(|w| w["node"] == "crop" && w["message"].as_str().unwrap().contains("bottom edge")), "{v}");
}

/// `check` warns, without cooking, about a flame-model fit fed straight from a loader (it would fit
/// the whole frame), names the node and the fix, and still passes: warnings do not fail a check.
/// The learning-flames graph, which frames the flame first, gets no such warning.
#[test]
fn check_warns_about_a_flame_model_fit_of_whole_frames() {
    let dir = tempfile::tempdir().unwrap();
    for f in 0..3u32 {
        image::RgbaImage::from_pixel(32, 24, image::Rgba([200, 120, 20, 255]))
            .save(dir.path().join(format!("f_{f:04}.png")))
            .unwrap();
    }
    let graph = dir.path().join("fit.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "plate": (type: "imaging.load_sequence", params: {"path": "f_####.png"}),
            "fit": (type: "flame_model.fit"),
        }, edges: [("plate.clip", "fit.clip")])"#,
    )
    .unwrap();
    let o = run(&["check", graph.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("warning:") && stderr.contains("node 'fit'") && stderr.contains("fits the whole frame of 'plate'"),
        "{stderr}"
    );
    let o = run(&["check", "--json", graph.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["ok"], true, "{v}");
    let warnings = v["warnings"].as_array().unwrap();
    assert!(warnings.iter().any(|w| w["node"] == "fit" && w["kind"] == "Warning"), "{v}");
    let learning = workspace().join("graphs/learning-flames-candle.ron");
    let o = bin().args(["check", "--json", learning.to_str().unwrap()]).env("PYROGRAPH_FOOTAGE", dir.path()).output().unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["warnings"].as_array().unwrap().iter().all(|w| w["node"] != "fit"), "{v}");
}

#[test]
fn a_bypassed_writer_writes_nothing_and_the_same_writer_active_writes() {
    let dir = tempfile::tempdir().unwrap();
    let graph = |bypass: bool| {
        format!(
            r#"(version: 5, nodes: {{
                "card": (type: "imaging.constant_color", params: {{"width": 8, "height": 8}}),
                "write": (type: "imaging.write_image", params: {{"path": "card.png"}}, bypass: {bypass}),
            }}, edges: [("card.image", "write.image")])"#
        )
    };
    let file = dir.path().join("g.ron");
    let out = dir.path().join("out");
    for bypass in [true, false] {
        std::fs::write(&file, graph(bypass)).unwrap();
        let o = run(&["render", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(out.join("card.png").exists(), !bypass, "bypass {bypass}: {}", text(&o));
        assert_eq!(text(&o).contains("write: bypassed, writes nothing"), bypass, "{}", text(&o));
    }
}

/// A graph whose node id and path hold terminal controls (OSC retitle, BEL, CR, NUL, clear
/// screen): every message shows them escaped, in text and in `--json`, and a 100 kB id is cut.
#[test]
fn control_characters_in_ids_and_values_never_reach_the_terminal_raw() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 3, nodes: {"a\u{1b}]0;PWNED\u{7}b\r\u{0}": (type: "imaging.load_image", params: {"path": "x\u{1b}[2J.png"})}, edges: [])"#,
    )
    .unwrap();
    let raw = |o: &Output| [&o.stdout, &o.stderr].iter().any(|s| s.iter().any(|b| matches!(b, 0 | 7 | 0x0d | 0x1b)));
    let g = graph.to_str().unwrap();
    let out = dir.path().join("out");
    for args in [vec!["render", g, "--out", out.to_str().unwrap()], vec!["check", g], vec!["info", g]] {
        let o = run(&args);
        assert!(!raw(&o), "{args:?}: {:?}", text(&o));
        for json in [false, true] {
            if !json && args[0] == "info" {
                continue;
            }
            let mut a = args.clone();
            if json {
                a.push("--json");
            }
            let o = run(&a);
            assert!(!raw(&o), "{a:?}: {:?}", text(&o));
            let t = text(&o);
            let escaped = if json { r"a\\u{1b}]0;PWNED\\u{7}b\\u{d}\\u{0}" } else { r"a\u{1b}]0;PWNED\u{7}b\u{d}\u{0}" };
            assert!(t.contains(escaped), "{a:?}: {t}");
            if args[0] == "render" {
                let path = if json { r"x\\u{1b}[2J.png" } else { r"x\u{1b}[2J.png" };
                assert!(t.contains(path) && t.contains("no such file"), "{a:?}: {t}");
                assert_eq!(o.status.code(), Some(1));
            }
        }
    }
    let long = dir.path().join("long.ron");
    std::fs::write(&long, format!(r#"(version: 3, nodes: {{"{}": (type: "nope")}}, edges: [])"#, "x".repeat(100_000))).unwrap();
    let o = run(&["check", long.to_str().unwrap()]);
    let t = text(&o);
    assert!(t.len() < 2_000, "{} bytes", t.len());
    assert!(t.contains("more characters]") && t.contains("unknown node type 'nope'"), "{t}");
}
