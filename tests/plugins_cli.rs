//! Python plugin nodes through the `pyrograph` binary: a graph of built-in nodes never starts
//! Python (even with plugins beside it), `--no-plugins` and a missing interpreter are clear
//! errors, and (with a Python that has numpy) the shipped example lists, renders and matches its
//! golden frame, and a plugin that raises fails its node with the traceback while the other
//! branches of the graph still cook.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pyrograph_testing::{python_with_numpy, workspace};

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

/// `pyrograph render GRAPH --out OUT` with a Python that has numpy.
fn render_with_python(graph: &Path, out: &Path) -> Output {
    bin().env("PYROGRAPH_PYTHON", python_with_numpy()).arg("render").arg(graph).arg("--out").arg(out).output().unwrap()
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
    let by_flag = bin().args(["check", "--no-plugins"]).arg(example()).output().unwrap();
    let by_env = bin().arg("check").arg(example()).env("PYROGRAPH_NO_PLUGINS", "1").output().unwrap();
    for o in [by_flag, by_env] {
        let all = text(&o);
        assert_eq!(o.status.code(), Some(1), "{all}");
        for needle in
            ["node 'haze'", "unknown node type 'studio.heat_haze'", "plugin nodes are off (--no-plugins or PYROGRAPH_NO_PLUGINS)"]
        {
            assert!(all.contains(needle), "{needle:?} in:\n{all}");
        }
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
    let o = bin().env("PYROGRAPH_PYTHON", python_with_numpy()).arg("nodes").arg("--plugins").arg(&dir).output().unwrap();
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    let line = all.lines().find(|l| l.starts_with("studio.heat_haze")).unwrap_or_else(|| panic!("not listed:\n{all}"));
    assert!(line.contains("Studio") && line.contains(&format!("({}:", dir.join("heat_haze.py").display())), "{line}");
    assert!(all.lines().any(|l| l.starts_with("imaging.crop")), "built-ins are still listed");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn each_example_plugin_graph_renders_its_golden_frame() {
    // (graph, frames written, the frame compared, its golden copy)
    let examples = [
        ("heat_haze/heat-haze.ron", 24, "heat-haze/haze_0012.png", "heat_haze_0012.png"),
        ("temporal_median/temporal-median.ron", 24, "temporal-median/median_0012.png", "temporal_median_0012.png"),
        ("csv_emitter/csv-emitter.ron", 36, "csv-emitter/csv_0030.png", "csv_emitter_0030.png"),
    ];
    for (graph, count, frame, golden) in examples {
        let out = tempfile::tempdir().unwrap();
        let graph = workspace().join("examples/plugins").join(graph);
        let o = render_with_python(&graph, out.path());
        assert!(o.status.success(), "{}", text(&o));
        let made = out.path().join(frame);
        let written = std::fs::read_dir(made.parent().unwrap()).unwrap().count();
        assert_eq!(written, count, "{}", graph.display());
        let want = workspace().join("tests/golden").join(golden);
        if std::env::var("REGENERATE").as_deref() == Ok("1") {
            std::fs::copy(&made, &want).unwrap();
        }
        let a = image::open(&made).unwrap().to_rgba8();
        let b = image::open(&want).unwrap_or_else(|e| panic!("{}: {e} (REGENERATE=1 creates it)", want.display())).to_rgba8();
        pyrograph_testing::pictures_match(a.as_raw(), a.dimensions(), b.as_raw(), b.dimensions())
            .unwrap_or_else(|e| panic!("{frame}: {e}"));
    }
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
    let o = render_with_python(&graph, &out);
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
        .env("PYROGRAPH_PYTHON", python_with_numpy())
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

#[test]
fn a_preset_names_the_plugin_it_needs_when_it_is_missing() {
    // The example preset and a graph including it, in a folder without the plugin.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("presets")).unwrap();
    let example = workspace().join("examples/plugins/heat_haze");
    std::fs::copy(example.join("presets/hazy-flame.ron"), dir.path().join("presets/hazy-flame.ron")).unwrap();
    std::fs::copy(example.join("hazy-flame.ron"), dir.path().join("hazy-flame.ron")).unwrap();
    let o = bin()
        .env("PYROGRAPH_PYTHON", "/nonexistent/python")
        .arg("check")
        .arg(dir.path().join("hazy-flame.ron"))
        .output()
        .unwrap();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    for needle in ["node 'hazy'", "hazy-flame.ron needs the Python plugin node type 'studio.heat_haze'", "PYROGRAPH_PLUGIN_PATH"]
    {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
    assert!(!all.contains("could not start Python"), "no plugin files: no Python was asked:\n{all}");
    // A plain graph whose plugin is missing: the node and the type are named.
    std::fs::copy(example.join("heat-haze.ron"), dir.path().join("heat-haze.ron")).unwrap();
    let o = bin().arg("check").arg(dir.path().join("heat-haze.ron")).output().unwrap();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    assert!(all.contains("node 'haze': unknown node type 'studio.heat_haze'"), "{all}");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_preset_with_a_plugin_node_renders_where_the_plugin_is() {
    let out = tempfile::tempdir().unwrap();
    let graph = workspace().join("examples/plugins/heat_haze/hazy-flame.ron");
    let o = render_with_python(&graph, out.path());
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read_dir(out.path().join("hazy-flame")).unwrap().count(), 12);
}

#[test]
#[ignore = "needs python3 with numpy and openjd (PYROGRAPH_OPENJD): .ci/run installs both and runs the ignored tests"]
fn a_farm_job_with_a_plugin_node_renders_what_a_plain_render_does() {
    let dir = tempfile::tempdir().unwrap();
    // The plugin in a studio folder named on the command line, not beside the graph: the bundle
    // must pass it on to every task.
    let (studio, shot) = (dir.path().join("studio-plugins"), dir.path().join("shot"));
    std::fs::create_dir_all(&studio).unwrap();
    std::fs::create_dir_all(&shot).unwrap();
    let example = workspace().join("examples/plugins/heat_haze");
    std::fs::copy(example.join("plugins/heat_haze.py"), studio.join("heat_haze.py")).unwrap();
    std::fs::copy(example.join("heat-haze.ron"), shot.join("heat-haze.ron")).unwrap();
    let graph = shot.join("heat-haze.ron");
    let python = python_with_numpy();
    let (single, farm, job) = (dir.path().join("single"), dir.path().join("farm"), dir.path().join("job"));
    let run = |c: &mut Command| {
        let o = c.env("PYROGRAPH_PYTHON", &python).output().unwrap();
        assert!(o.status.success(), "{c:?}:\n{}", text(&o));
        o
    };
    run(bin().arg("render").arg(&graph).arg("--out").arg(&single).args(["--frames", "0-5", "--plugins"]).arg(&studio));
    run(bin()
        .arg("job")
        .arg(&graph)
        .arg("--out")
        .arg(&farm)
        .args(["--frames", "0-5", "--chunk", "3", "--plugins"])
        .arg(&studio)
        .arg("-o")
        .arg(&job));
    let template = std::fs::read_to_string(job.join("template.yaml")).unwrap();
    assert!(template.contains(&format!("\"--plugins\", \"{}\"", studio.display())), "{template}");
    let openjd = || Command::new(std::env::var_os("PYROGRAPH_OPENJD").unwrap_or_else(|| "openjd".into()));
    run(openjd().arg("check").arg(job.join("template.yaml")));
    let params = format!("file://{}", job.join("job_params.yaml").display());
    run(openjd().arg("run").arg(job.join("template.yaml")).args(["--step", "Render", "-p", &params]));
    for i in 0..6 {
        let name = format!("heat-haze/haze_{i:04}.png");
        let (a, b) = (std::fs::read(single.join(&name)).unwrap(), std::fs::read(farm.join(&name)).unwrap());
        assert!(a == b, "{name}: the farm frame differs from the plain render's");
    }
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_plugin_that_crashes_its_interpreter_fails_its_node_and_leaves_files_whole() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("plugins")).unwrap();
    let plugin = dir.path().join("plugins/crash.py");
    let write_plugin = |body: &str| {
        let text = format!(
            "import os, signal\nfrom pyrograph_plugin import node, Image\n\n@node(\"studio.crash\")\ndef crash(image: Image) -> Image:\n    \"\"\"Crashes its interpreter.\"\"\"\n    {body}\n"
        );
        std::fs::write(&plugin, text).unwrap();
    };
    let graph = dir.path().join("g.ron");
    std::fs::write(
        &graph,
        r#"(version: 1, nodes: {
            "flame": (type: "imaging.turbulence_flame", params: {"width": 32, "height": 48, "frames": 4}),
            "c": (type: "studio.crash"),
            "out": (type: "imaging.write_sequence", params: {"pattern": "c_####.png", "overwrite": true}),
        }, edges: [("flame.clip", "c.image"), ("c.image", "out.clip")])"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let render = || render_with_python(&graph, &out);
    // A first render that works leaves four frames; the same render with a crashing plugin must
    // leave them as they were, with nothing half-written beside them.
    write_plugin("return image");
    let o = render();
    assert!(o.status.success(), "{}", text(&o));
    let before: Vec<_> = (0..4).map(|i| std::fs::read(out.join(format!("c_{i:04}.png"))).unwrap()).collect();
    write_plugin("os.kill(os.getpid(), signal.SIGSEGV)");
    let o = render();
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    for needle in ["node 'c' (studio.crash)", "killed by signal 11 (SIGSEGV)", "crash.py"] {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
    let after: Vec<_> = (0..4).map(|i| std::fs::read(out.join(format!("c_{i:04}.png"))).unwrap()).collect();
    assert!(before == after, "the frames written before are untouched");
    let names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names.len(), 4, "no partial or temporary file: {names:?}");
}
