//! The editor in a real X11 window: Xvfb for a screen, xdotool for a mouse and keyboard, and
//! the editor's `--state-dump` to read what the clicks did. This is the path a user's hand
//! takes (window system events through winit), which the headless tests cannot cover: selecting
//! nodes on the canvas, and setting a key with the inspector's key toggle (then Ctrl+Z).
//!
//! Uses the binary in `PYROGRAPH_EDITOR_BIN` when set (a release build, say), else
//! the one cargo built for this test.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use pyrograph_testing::workspace;
use serde_json::Value;

/// Kills the child processes however the test ends, removes the display's lock and socket (a
/// killed Xvfb leaves them), then lets the next test have the screen.
struct Kill(Vec<Child>, u32, #[allow(dead_code)] MutexGuard<'static, ()>);

/// One editor at a time: tests running in parallel would pick the same free display.
static SCREEN: Mutex<()> = Mutex::new(());

impl Drop for Kill {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
        clear_display(self.1);
    }
}

/// The lock file and socket of X display `n`.
fn display_files(n: u32) -> [PathBuf; 2] {
    [PathBuf::from(format!("/tmp/.X{n}-lock")), PathBuf::from(format!("/tmp/.X11-unix/X{n}"))]
}

/// Whether no X server holds display `n`: no lock file, or one naming a process that is gone
/// (an Xvfb killed by an earlier run leaves its lock and socket behind; they fill the range).
fn display_free(n: u32) -> bool {
    let [lock, socket] = display_files(n);
    match std::fs::read_to_string(&lock) {
        Ok(text) => text.trim().parse::<u32>().is_ok_and(|pid| !Path::new(&format!("/proc/{pid}")).exists()),
        Err(_) => !socket.exists() || std::fs::metadata(&lock).is_err(),
    }
}

/// Removes the lock file and socket of display `n` (a free one's are stale).
fn clear_display(n: u32) {
    for f in display_files(n) {
        let _ = std::fs::remove_file(f);
    }
}

fn xdotool(display: &str, args: &[&str]) {
    let st = Command::new("xdotool").args(args).env("DISPLAY", display).status().expect("xdotool runs");
    assert!(st.success(), "xdotool {args:?} failed");
}

fn read_dump(path: &Path) -> Option<Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Waits until the dump satisfies `ok`; returns the last dump read.
fn wait_for(path: &Path, what: &str, ok: impl Fn(&Value) -> bool) -> Value {
    let start = Instant::now();
    loop {
        if let Some(v) = read_dump(path)
            && ok(&v)
        {
            return v;
        }
        if start.elapsed() > Duration::from_secs(60) {
            panic!("timed out waiting for {what}; last state: {:?}", read_dump(path));
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn center(dump: &Value, id: &str) -> (i64, i64) {
    let n = &dump["nodes"][id];
    let f = |k: &str| n[k].as_f64().unwrap_or_else(|| panic!("node {id} has no {k} in {dump}"));
    ((f("x") + f("w") / 2.0) as i64, (f("y") + f("h") / 2.0) as i64)
}

fn selection(dump: &Value) -> Vec<String> {
    dump["selection"].as_array().map(|a| a.iter().filter_map(|v| v.as_str().map(String::from)).collect()).unwrap_or_default()
}

/// Xvfb on a free display and the editor on `graph` in it (with `args`), writing its state to
/// the returned dump file. Everything started is killed when the returned guard drops.
fn start_editor(graph: &Path, args: &[&str], dir: &Path) -> (Kill, String, PathBuf) {
    let serial = SCREEN.lock().unwrap_or_else(|e| e.into_inner());
    let display_num = (90..140).find(|&n| display_free(n)).expect("a free display");
    // Stale files of a killed server: Xvfb would refuse the lock, and the wait below would take
    // the old socket for the new server's.
    clear_display(display_num);
    let display = format!(":{display_num}");
    let xvfb = Command::new("Xvfb")
        .args([display.as_str(), "-screen", "0", "1600x1000x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("Xvfb starts (apt-get install xvfb)");
    let mut procs = Kill(vec![xvfb], display_num, serial);
    let socket = PathBuf::from(format!("/tmp/.X11-unix/X{display_num}"));
    let start = Instant::now();
    while !socket.exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "Xvfb did not come up on {display}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let dump = dir.join("state.json");
    let bin = std::env::var_os("PYROGRAPH_EDITOR_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_pyrograph-editor")));
    let editor = Command::new(&bin)
        .arg(graph)
        .args(args)
        .arg("--state-dump")
        .arg(&dump)
        .env("DISPLAY", &display)
        .env("XDG_CONFIG_HOME", dir)
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {}: {e}", bin.display()));
    procs.0.push(editor);
    (procs, display, dump)
}

/// Keys go to the focused window: with no window manager on the Xvfb screen, focus it by hand.
fn focus_editor(display: &str) {
    let out = Command::new("xdotool").args(["search", "--name", "pyrograph"]).env("DISPLAY", display).output().unwrap();
    let window = String::from_utf8_lossy(&out.stdout).lines().next().map(str::to_string).expect("the editor's window");
    xdotool(display, &["windowfocus", "--sync", &window]);
    std::thread::sleep(Duration::from_millis(500));
}

#[test]
#[ignore = "needs Xvfb and xdotool: .ci/run installs them and runs it"]
fn a_click_in_a_real_window_selects_the_node() {
    let dir = tempfile::tempdir().unwrap();
    let (_procs, display, dump) = start_editor(&workspace().join("graphs/burning-cube.ron"), &[], dir.path());
    let first = settled(&dump, 6);
    assert!(selection(&first).is_empty());

    // A slow press and release on a node's body selects it.
    let (x, y) = center(&first, "spread");
    let (xs, ys) = (x.to_string(), y.to_string());
    xdotool(&display, &["mousemove", &xs, &ys]);
    xdotool(&display, &["mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(300));
    xdotool(&display, &["mouseup", "1"]);
    let v = wait_for(&dump, "spread selected", |v| selection(v) == ["spread"]);

    // Shift-click adds a second node (a key held down: the window needs the focus).
    focus_editor(&display);
    let (x, y) = center(&v, "render");
    xdotool(&display, &["mousemove", &x.to_string(), &y.to_string()]);
    for step in [&["keydown", "shift"][..], &["click", "1"], &["keyup", "shift"]] {
        std::thread::sleep(Duration::from_millis(300));
        xdotool(&display, step);
    }
    let v = wait_for(&dump, "render added", |v| selection(v) == ["spread", "render"]);

    // A rectangle dragged on empty canvas around `cube` and `wind` selects exactly those.
    let n = |id: &str, k: &str| v["nodes"][id][k].as_f64().unwrap();
    let (x0, y0) = (n("cube", "x") - 20.0, n("cube", "y") - 20.0);
    let (x1, y1) = (n("wind", "x") + n("wind", "w") + 10.0, n("wind", "y") + n("wind", "h") + 10.0);
    xdotool(&display, &["mousemove", &(x0 as i64).to_string(), &(y0 as i64).to_string()]);
    xdotool(&display, &["mousedown", "1"]);
    for k in 1..=8 {
        let t = k as f64 / 8.0;
        let (x, y) = (x0 + (x1 - x0) * t, y0 + (y1 - y0) * t);
        xdotool(&display, &["mousemove", &(x as i64).to_string(), &(y as i64).to_string()]);
        std::thread::sleep(Duration::from_millis(30));
    }
    xdotool(&display, &["mouseup", "1"]);
    let v = wait_for(&dump, "the rectangle's nodes selected", |v| {
        let mut s = selection(v);
        s.sort();
        s == ["cube", "wind"]
    });
    // The nodes did not move: it was a rectangle, not a drag of the view or of a node.
    assert_eq!(
        (&v["nodes"]["cube"]["x"], &v["nodes"]["cube"]["y"]),
        (&first["nodes"]["cube"]["x"], &first["nodes"]["cube"]["y"])
    );
}

#[test]
#[ignore = "needs Xvfb and xdotool: .ci/run installs them and runs it"]
fn a_click_on_the_key_toggle_in_a_real_window_sets_a_key_and_ctrl_z_takes_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("bloom.ron");
    std::fs::write(
        &graph,
        r#"(
    version: 1,
    nodes: {
        "flame": (type: "imaging.turbulence_flame", params: {"width": 48, "height": 64, "frames": 24, "octaves": 2}, pos: (0, 0)),
        "bloom": (type: "imaging.bloom", params: {"strength": 0.4, "sigma": 4.0, "passes": 2}, pos: (320, 0)),
    },
    edges: [("flame.clip", "bloom.image")],
)"#,
    )
    .unwrap();
    let (_procs, display, dump) = start_editor(&graph, &["--select", "bloom"], dir.path());
    let v = wait_for(&dump, "the key toggle of strength", |v| v["key_toggles"]["strength"].is_object());
    assert_eq!(v["params"]["strength"], "0.4");
    // Let the layout settle, then press and release on the diamond.
    std::thread::sleep(Duration::from_millis(700));
    let v = wait_for(&dump, "the key toggle of strength", |v| v["key_toggles"]["strength"].is_object());
    let t = &v["key_toggles"]["strength"];
    let f = |k: &str| t[k].as_f64().unwrap();
    let (x, y) = ((f("x") + f("w") / 2.0) as i64, (f("y") + f("h") / 2.0) as i64);
    xdotool(&display, &["mousemove", &x.to_string(), &y.to_string()]);
    xdotool(&display, &["mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(150));
    xdotool(&display, &["mouseup", "1"]);
    let v = wait_for(&dump, "a key on strength", |v| v["params"]["strength"] != "0.4");
    assert_eq!(v["params"]["strength"].as_str().map(|s| s.replace(' ', "")), Some("keys([(0,0.4)])".into()), "{v}");
    // Ctrl+Z takes it back.
    focus_editor(&display);
    xdotool(&display, &["mousemove", "500", "500"]);
    xdotool(&display, &["key", "ctrl+z"]);
    wait_for(&dump, "the key undone", |v| v["params"]["strength"] == "0.4");
}

/// A chain of 100,000 nodes given on the command line: the window comes up and keeps drawing
/// while a loader thread reads and validates the file (the frame count in the state dump goes on
/// rising while it says "opening"), then it shows a bounded part of the chain. The slowest frame
/// is printed (TESTING.md records it for a release build).
#[test]
#[ignore = "needs Xvfb and xdotool: .ci/run installs them and runs it"]
fn a_100000_node_chain_opens_in_a_real_window_without_freezing_it() {
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("chain.ron");
    std::fs::write(&graph, pyrograph_testing::chain_ron(100_000)).unwrap();
    let (_procs, _display, dump) = start_editor(&graph, &[], dir.path());
    let opening = wait_for(&dump, "the window while opening", |v| v["frames"].as_u64().is_some());
    let frames_then = opening["frames"].as_u64().unwrap_or(0);
    let opened = wait_for(&dump, "the chain opened", |v| {
        v["opening"] == false && v["status"].as_str().is_some_and(|s| s.starts_with("opened"))
    });
    let status = opened["status"].as_str().unwrap_or_default();
    assert!(!status.contains("problem"), "{status}");
    let culled = &opened["culled"];
    assert_eq!(culled[1].as_u64(), Some(100_000), "{opened}");
    assert!(culled[0].as_u64().is_some_and(|held| held > 0 && held <= 600), "{culled}");
    if opening["opening"] == true {
        assert!(opened["frames"].as_u64().unwrap_or(0) > frames_then + 1, "the window kept drawing while it opened");
    }
    eprintln!(
        "100,000-node chain in a real window: {} frames, slowest {:.1} ms, {} of 100000 nodes held",
        opened["frames"],
        opened["slowest_frame_ms"].as_f64().unwrap_or(-1.0),
        culled[0]
    );
}

/// The first frames lay the graph out and frame it: waits until all `count` nodes have a place
/// on screen that holds still, and returns that dump.
fn settled(dump: &Path, count: usize) -> Value {
    let start = Instant::now();
    let mut first = wait_for(dump, "the nodes on screen", |v| v["nodes"].as_object().is_some_and(|n| n.len() == count));
    loop {
        std::thread::sleep(Duration::from_millis(700));
        let again = wait_for(dump, "the nodes on screen", |_| true);
        if again["nodes"] == first["nodes"] {
            return first;
        }
        assert!(start.elapsed() < Duration::from_secs(90), "the layout never settled");
        first = again;
    }
}

fn scope(dump: &Value) -> Vec<String> {
    dump["scope"].as_array().map(|a| a.iter().filter_map(|v| v.as_str().map(String::from)).collect()).unwrap_or_default()
}

/// A double-click on an include's header in a real window steps inside it (the include's
/// nodes are on screen, the breadcrumb says where), and a click on the breadcrumb's first
/// button steps back out.
#[test]
#[ignore = "needs Xvfb and xdotool: .ci/run installs them and runs it"]
fn a_double_click_in_a_real_window_steps_into_an_include_and_the_breadcrumb_steps_out() {
    let dir = tempfile::tempdir().unwrap();
    let (_procs, display, dump) = start_editor(&workspace().join("graphs/flame-cards.ron"), &[], dir.path());
    let first = settled(&dump, 4);
    // The header: a little inside the node's top-left corner.
    let n = |k: &str| first["nodes"]["calm"][k].as_f64().unwrap();
    let (x, y) = ((n("x") + 30.0) as i64, (n("y") + 20.0) as i64);
    xdotool(&display, &["mousemove", &x.to_string(), &y.to_string()]);
    std::thread::sleep(Duration::from_millis(200));
    xdotool(&display, &["click", "--repeat", "2", "--delay", "80", "1"]);
    // The scope can change a frame before the include's nodes are laid out: wait for both.
    let inside = wait_for(&dump, "inside calm with its nodes", |v| scope(v) == ["calm"] && v["nodes"]["flame"].is_object());
    let nodes = inside["nodes"].as_object().map(|m| m.keys().cloned().collect::<Vec<_>>()).unwrap_or_default();
    assert!(nodes.iter().any(|k| k == "flame") && !nodes.iter().any(|k| k == "calm"), "the preset's nodes: {nodes:?}");
    let crumbs = inside["crumbs"].as_array().cloned().unwrap_or_default();
    assert_eq!(crumbs.len(), 2, "the file, then calm: {inside}");

    let c = |k: &str| crumbs[0][k].as_f64().unwrap();
    let (x, y) = ((c("x") + c("w") / 2.0) as i64, (c("y") + c("h") / 2.0) as i64);
    xdotool(&display, &["mousemove", &x.to_string(), &y.to_string()]);
    xdotool(&display, &["mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(120));
    xdotool(&display, &["mouseup", "1"]);
    let out = wait_for(&dump, "back at the top level", |v| scope(v).is_empty() && v["nodes"]["calm"].is_object());
    assert_eq!(selection(&out), ["calm"], "the include stepped out of is selected");
}
