//! Python plugin nodes through the `pyrograph` binary: a graph of built-in nodes never starts
//! Python (even with plugins beside it), `--no-plugins` and a missing interpreter are clear
//! errors, and (with a Python that has numpy) the shipped example lists, renders and matches its
//! golden frame, and a plugin that raises fails its node with the traceback while the other
//! branches of the graph still cook.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pyrograph_testing::workspace;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pyrograph"));
    c.env_remove("PYROGRAPH_PLUGIN_PATH");
    c
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn example() -> PathBuf {
    workspace().join("examples/plugins/heat_haze/heat-haze.ron")
}

/// A Python that has numpy: PYROGRAPH_PYTHON, /usr/bin/python3, then python3.
fn python() -> OsString {
    let candidates = std::env::var_os("PYROGRAPH_PYTHON").into_iter().chain(["/usr/bin/python3".into(), "python3".into()]);
    for p in candidates {
        if Command::new(&p).args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success()) {
            return p;
        }
    }
    panic!("needs python3 with numpy: none of PYROGRAPH_PYTHON, /usr/bin/python3, python3 has it");
}

/// A graph of built-in nodes in a folder whose `plugins/` holds a plugin.
fn builtin_graph_beside_a_plugin(dir: &Path) -> PathBuf {
    std::fs::create_dir(dir.join("plugins")).unwrap();
    std::fs::copy(workspace().join("examples/plugins/heat_haze/plugins/heat_haze.py"), dir.join("plugins/heat_haze.py")).unwrap();
    let graph = dir.join("flame.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "flame": (type: "imaging.turbulence_flame", params: {"width": 32, "height": 48, "frames": 2}),
            "out": (type: "imaging.write_sequence", params: {"pattern": "flame_####.png"}),
        }, edges: [("flame.clip", "out.clip")])"#,
    )
    .unwrap();
    graph
}

#[test]
fn a_graph_of_builtin_nodes_never_starts_python() {
    let dir = tempfile::tempdir().unwrap();
    let graph = builtin_graph_beside_a_plugin(dir.path());
    let out = dir.path().join("out");
    let o =
        bin().env("PYROGRAPH_PYTHON", "/nonexistent/python").arg("render").arg(&graph).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("flame_0001.png").is_file());
}

#[test]
fn no_plugins_refuses_a_graph_that_needs_one() {
    let o = bin().args(["check", "--no-plugins"]).arg(example()).output().unwrap();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    for needle in ["node 'haze'", "unknown node type 'studio.heat_haze'", "plugin nodes are off (--no-plugins)"] {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
}

#[test]
fn a_missing_interpreter_or_plugin_folder_is_a_clear_error() {
    let o = bin().env("PYROGRAPH_PYTHON", "/nonexistent/python").arg("check").arg(example()).output().unwrap();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    for needle in ["unknown node type 'studio.heat_haze'", "could not start Python ('/nonexistent/python')", "PYROGRAPH_PYTHON"] {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
    let o = bin().args(["nodes", "--plugins", "/nonexistent/pyrograph-plugins"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("plugin folder /nonexistent/pyrograph-plugins (from --plugins) does not exist"), "{}", text(&o));
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn nodes_lists_a_plugin_node_with_its_file_and_line() {
    let dir = workspace().join("examples/plugins/heat_haze/plugins");
    let o = bin().env("PYROGRAPH_PYTHON", python()).arg("nodes").arg("--plugins").arg(&dir).output().unwrap();
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    let line = all.lines().find(|l| l.starts_with("studio.heat_haze")).unwrap_or_else(|| panic!("not listed:\n{all}"));
    assert!(line.contains("Studio") && line.contains(&format!("({}:", dir.join("heat_haze.py").display())), "{line}");
    assert!(all.lines().any(|l| l.starts_with("imaging.crop")), "built-ins are still listed");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn the_example_plugin_graph_renders_its_golden_frame() {
    let out = tempfile::tempdir().unwrap();
    let o = bin().env("PYROGRAPH_PYTHON", python()).arg("render").arg(example()).arg("--out").arg(out.path()).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let frames = std::fs::read_dir(out.path().join("heat-haze")).unwrap().count();
    assert_eq!(frames, 24);
    let made = out.path().join("heat-haze/haze_0012.png");
    let want = workspace().join("tests/golden/heat_haze_0012.png");
    if std::env::var("REGENERATE").as_deref() == Ok("1") {
        std::fs::copy(&made, &want).unwrap();
    }
    let a = image::open(&made).unwrap().to_rgba8();
    let b = image::open(&want).unwrap_or_else(|e| panic!("{}: {e} (REGENERATE=1 creates it)", want.display())).to_rgba8();
    pyrograph_testing::pictures_match(a.as_raw(), a.dimensions(), b.as_raw(), b.dimensions()).unwrap();
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_raising_plugin_fails_its_node_with_the_traceback_and_other_branches_cook() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("plugins")).unwrap();
    std::fs::write(
        dir.path().join("plugins/raises.py"),
        "from pyrograph_plugin import node, Image\n\n@node(\"studio.raises\")\ndef raises(image: Image) -> Image:\n    \"\"\"Fails on purpose.\"\"\"\n    return image / 0.0 if False else 1 // 0\n",
    )
    .unwrap();
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "flame": (type: "imaging.turbulence_flame", params: {"width": 32, "height": 48, "frames": 3}),
            "bad": (type: "studio.raises"),
            "bad_out": (type: "imaging.write_sequence", params: {"pattern": "bad_####.png"}),
            "good_out": (type: "imaging.write_sequence", params: {"pattern": "good_####.png"}),
        }, edges: [("flame.clip", "bad.image"), ("bad.image", "bad_out.clip"), ("flame.clip", "good_out.clip")])"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = bin().env("PYROGRAPH_PYTHON", python()).arg("render").arg(&graph).arg("--out").arg(&out).output().unwrap();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    let place = format!("{}:6 in raises", dir.path().join("plugins/raises.py").display());
    for needle in
        ["node 'bad' (studio.raises)", "frame ", "ZeroDivisionError: integer division or modulo by zero", place.as_str()]
    {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
    assert!(out.join("good_0002.png").is_file(), "the branch without the plugin still cooks:\n{all}");
    assert!(!out.join("bad_0000.png").exists());
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn ctrl_c_stops_a_hanging_plugin_within_a_second() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("plugins")).unwrap();
    let pid_file = dir.path().join("pid");
    let plugin = format!(
        "import os\nfrom pyrograph_plugin import node, Image\n\n@node(\"studio.hang\")\ndef hang(image: Image) -> Image:\n    \"\"\"Never returns.\"\"\"\n    open({:?}, \"w\").write(str(os.getpid()))\n    while True:\n        pass\n",
        pid_file.display().to_string()
    );
    std::fs::write(dir.path().join("plugins/hang.py"), plugin).unwrap();
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "flame": (type: "imaging.turbulence_flame", params: {"width": 16, "height": 16, "frames": 1}),
            "h": (type: "studio.hang"),
            "out": (type: "imaging.write_sequence", params: {"pattern": "h_####.png"}),
        }, edges: [("flame.clip", "h.image"), ("h.image", "out.clip")])"#,
    )
    .unwrap();
    let mut child = bin()
        .env("PYROGRAPH_PYTHON", python())
        .arg("render")
        .arg(&graph)
        .arg("--out")
        .arg(dir.path().join("out"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while std::fs::read_to_string(&pid_file).map_or(true, |s| s.is_empty()) {
        assert!(started.elapsed().as_secs() < 60, "the plugin never started");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let worker = std::fs::read_to_string(&pid_file).unwrap();
    let interrupted = std::time::Instant::now();
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    while child.try_wait().unwrap().is_none() || runs(&worker) {
        let state = std::fs::read_to_string(format!("/proc/{worker}/stat")).unwrap_or_default();
        assert!(interrupted.elapsed().as_millis() < 1000, "pyrograph or its worker still runs 1 s after Ctrl-C: {state}");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    assert!(!dir.path().join("out/h_0000.png").exists());
}

/// Whether process `pid` runs (a zombie waiting for a parent to reap it does not).
fn runs(pid: &str) -> bool {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // The state follows the command name in parentheses: "1234 (python3) R …".
    stat.rsplit_once(") ").is_some_and(|(_, rest)| !rest.starts_with('Z') && !rest.starts_with('X'))
}
