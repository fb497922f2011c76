//! Reads confined with `--read-root` (a studio service cooking graphs its users submit), and the
//! size limits raised or lowered with `--max-nodes` and `--max-pixels`: through the binary, one
//! process per case, since the limits are process-wide.
//!
//! Each case builds its own folders: `root/` (where reads are allowed) and `secret/` (where they
//! are not), with symbolic links from one into the other.

use std::path::{Path, PathBuf};
use std::process::Command;

const SECRET: &str = "hunter2-top-secret";

fn run(args: &[&str], paths: &[&Path]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_pyrograph")).args(args).args(paths).output().expect("the binary runs");
    (o.status.code(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

struct Setup {
    _dir: tempfile::TempDir,
    root: PathBuf,
    secret: PathBuf,
}

fn setup() -> Setup {
    let dir = tempfile::tempdir().unwrap();
    let (root, secret) = (dir.path().join("root"), dir.path().join("secret"));
    std::fs::create_dir_all(root.join("frames")).unwrap();
    std::fs::create_dir_all(&secret).unwrap();
    std::fs::write(secret.join("passwd"), format!("{SECRET}:x:0:0\n")).unwrap();
    let png = image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 100, 50, 255]));
    for name in ["frame_0001.png", "frame_0002.png"] {
        png.save(root.join("frames").join(name)).unwrap();
    }
    png.save(secret.join("plate.png")).unwrap();
    Setup { _dir: dir, root, secret }
}

fn write_graph(path: &Path, nodes: &str) {
    std::fs::write(path, format!("(version: 4, nodes: {{{nodes}}}, edges: [])")).unwrap();
}

fn include(path: &Path) -> String {
    format!(r#""inc": (type: "graph.include", params: {{"path": {:?}}})"#, path.display().to_string())
}

fn load_image(path: &Path) -> String {
    format!(r#""img": (type: "imaging.load_image", params: {{"path": {:?}}})"#, path.display().to_string())
}

/// Refused with exit 1, naming the path and the root, never echoing the file.
fn assert_refused((code, text): (Option<i32>, String), path: &str) {
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains(path) && text.contains("outside the folders pyrograph may read"), "{text}");
    assert!(!text.contains(SECRET), "the error echoes the file: {text}");
    assert!(!text.contains("panicked"), "{text}");
}

#[test]
fn includes_and_inputs_outside_the_read_roots_are_refused_by_name() {
    let s = setup();
    let graph = s.root.join("g.ron");
    let roots = ["--read-root", s.root.to_str().unwrap()];
    let passwd = s.secret.join("passwd");
    write_graph(&graph, &include(&passwd));
    assert_refused(run(&[&["check"][..], &roots].concat(), &[&graph]), &passwd.display().to_string());
    // Without confinement the include is read, and still not echoed: it is not a graph.
    let (code, text) = run(&["check"], &[&graph]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("is not a graph file") && !text.contains(SECRET), "{text}");

    let plate = s.secret.join("plate.png");
    write_graph(&graph, &load_image(&plate));
    assert_refused(run(&[&["check"][..], &roots].concat(), &[&graph]), &plate.display().to_string());
    assert_refused(run(&[&["render", "--node", "img"][..], &roots].concat(), &[&graph]), &plate.display().to_string());
    // `..` out of the root is the same file.
    write_graph(&graph, &load_image(Path::new("../secret/plate.png")));
    assert_refused(run(&[&["check"][..], &roots].concat(), &[&graph]), "plate.png");
    // Inside, the same graph checks; a second root admits the other folder.
    let inside = s.root.join("frames/frame_0001.png");
    write_graph(&graph, &load_image(&inside));
    let (code, text) = run(&[&["check"][..], &roots].concat(), &[&graph]);
    assert_eq!(code, Some(0), "{text}");
    write_graph(&graph, &load_image(&plate));
    let (code, text) = run(&[&["check"][..], &roots, &["--read-root", s.secret.to_str().unwrap()]].concat(), &[&graph]);
    assert_eq!(code, Some(0), "{text}");
}

#[cfg(unix)]
#[test]
fn symbolic_links_inside_a_root_are_followed_to_where_they_lead() {
    let s = setup();
    let roots = ["--read-root", s.root.to_str().unwrap()];
    let graph = s.root.join("g.ron");
    // A link to a file, a link to a folder, and a frame of a sequence that is a link.
    std::os::unix::fs::symlink(s.secret.join("passwd"), s.root.join("innocent.ron")).unwrap();
    std::os::unix::fs::symlink(&s.secret, s.root.join("assets")).unwrap();
    write_graph(&graph, &include(Path::new("innocent.ron")));
    assert_refused(run(&[&["check"][..], &roots].concat(), &[&graph]), "innocent.ron");
    write_graph(&graph, &load_image(Path::new("assets/plate.png")));
    assert_refused(run(&[&["check"][..], &roots].concat(), &[&graph]), "plate.png");
    std::fs::remove_file(s.root.join("frames/frame_0002.png")).unwrap();
    std::os::unix::fs::symlink(s.secret.join("plate.png"), s.root.join("frames/frame_0002.png")).unwrap();
    write_graph(&graph, r#""seq": (type: "imaging.load_sequence", params: {"path": "frames"})"#);
    let (code, text) = run(&[&["render", "--node", "seq"][..], &roots].concat(), &[&graph]);
    assert_eq!(code, Some(1), "a frame linked out of the root: {text}");
    assert!(text.contains("frame_0002.png") && text.contains("outside the folders pyrograph may read"), "{text}");
    // A link that stays inside is an ordinary path.
    std::os::unix::fs::symlink(s.root.join("frames"), s.root.join("alias")).unwrap();
    write_graph(&graph, &load_image(Path::new("alias/frame_0001.png")));
    let (code, text) = run(&[&["render", "--node", "img"][..], &roots].concat(), &[&graph]);
    assert_eq!(code, Some(0), "{text}");
}

#[test]
fn a_preset_folder_outside_the_roots_is_not_listed() {
    let s = setup();
    let lib = s.secret.join("presets");
    std::fs::create_dir_all(&lib).unwrap();
    std::fs::write(
        lib.join("hidden.ron"),
        r#"(version: 4, nodes: {"c": (type: "imaging.constant_color")}, edges: [], interface: (outputs: {"image": "c.image"}))"#,
    )
    .unwrap();
    let (code, text) = run(&["presets", "--json", "--dir"], &[&lib]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("hidden"), "unconfined, the preset is listed: {text}");
    let (_, text) = run(&["presets", "--json", "--read-root", s.root.to_str().unwrap(), "--dir"], &[&lib]);
    assert!(!text.contains("\"hidden\"") && text.contains("outside the folders pyrograph may read"), "{text}");
}

#[test]
fn a_read_root_that_is_not_a_folder_is_an_error_before_anything_runs() {
    let s = setup();
    let (code, text) = run(&["check", "--read-root"], &[&s.secret.join("passwd"), &s.root.join("g.ron")]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("--read-root") && text.contains("passwd: not a folder"), "{text}");
}

#[test]
fn the_node_and_pixel_limits_follow_their_flags() {
    let s = setup();
    let graph = s.root.join("chain.ron");
    let nodes: Vec<String> = (0..50).map(|i| format!(r#""n{i}": (type: "math.add", params: {{"b": 1.0}})"#)).collect();
    write_graph(&graph, &nodes.join(", "));
    let (code, text) = run(&["check", "--max-nodes", "10"], &[&graph]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("the graph has 50 nodes, more than the 10 pyrograph builds") && text.contains("--max-nodes 50"),
        "{text}"
    );
    assert_eq!(run(&["check", "--max-nodes", "50"], &[&graph]).0, Some(0));

    write_graph(&graph, &load_image(&s.root.join("frames/frame_0001.png")));
    let (code, text) = run(&["check", "--max-pixels", "15"], &[&graph]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("declares 4 × 4 pixels (16 pixels), more than the 15 pixels") && text.contains("--max-pixels 16"),
        "{text}"
    );
    assert_eq!(run(&["check", "--max-pixels", "16"], &[&graph]).0, Some(0));
}
