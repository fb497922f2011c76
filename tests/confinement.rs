//! Writers stay inside the output folder: with `--out`, a writer path that is absolute or
//! climbs out with `..` is refused when the graph loads (naming node and port), by `check` as
//! by `render`, and nothing is written; `--allow-outside-out` lets it through. Without `--out`
//! the graph file's folder is the limit.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pyrograph")).args(args).output().expect("the binary runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A graph with one writer of `writer_type` whose `port` is `target`, fed what it needs.
fn graph(writer_type: &str, port: &str, target: &str) -> String {
    let target = target.replace('\\', "\\\\");
    let size = r#""width": 8, "height": 8"#;
    let (feed, params, edges) = match writer_type {
        "imaging.write_image" => ("imaging.constant_color", size, r#"("src.image", "w.image")"#),
        "eigen.save_database" => ("imaging.constant_color", size, ""),
        "imaging.write_exr_layers" => ("imaging.turbulence_flame", size, r#"("src.clip", "w.main")"#),
        "cloth.write_usd" => ("cloth.mass_spring_flame", r#""frames": 2"#, r#"("src.cloth", "w.cloth")"#),
        "particles.write_usd" => {
            ("particles.particle_flame", r#""frames": 2"#, r#"("roots.roots", "src.roots"), ("src.flames", "w.particles")"#)
        }
        _ => ("imaging.turbulence_flame", size, r#"("src.clip", "w.clip")"#),
    };
    format!(
        r#"(version: 1, nodes: {{"src": (type: "{feed}", params: {{{params}}}), "roots": (type: "particles.roots"),
            "w": (type: "{writer_type}", params: {{"{port}": "{target}"}})}}, edges: [{edges}])"#
    )
}

const WRITERS: &[(&str, &str, &str)] = &[
    ("imaging.write_image", "path", "x.png"),
    ("imaging.write_sequence", "pattern", "x_####.png"),
    ("imaging.write_flipbook", "path", "x.png"),
    ("imaging.write_exr_layers", "pattern", "x_####.exr"),
    ("particles.write_usd", "path", "x.usda"),
    ("cloth.write_usd", "path", "x.usda"),
    ("eigen.save_database", "path", "x.db"),
];

fn setup() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let graphs = dir.path().join("graphs");
    let out = dir.path().join("out");
    std::fs::create_dir_all(&graphs).unwrap();
    std::fs::create_dir_all(&out).unwrap();
    (dir, graphs, out)
}

fn files_under(dir: &Path) -> usize {
    walk(dir).len()
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() { v.extend(walk(&p)) } else { v.push(p) }
    }
    v
}

#[test]
fn every_writer_refuses_absolute_and_climbing_paths_under_out() {
    let (dir, graphs, out) = setup();
    let escape = dir.path().join("escaped");
    for (ty, port, name) in WRITERS {
        for target in [escape.join(name).to_string_lossy().into_owned(), format!("../../escaped/{name}")] {
            let file = graphs.join("g.ron");
            std::fs::write(&file, graph(ty, port, &target)).unwrap();
            let file = file.to_str().unwrap();
            let out_s = out.to_str().unwrap();
            for args in [vec!["check", file, "--out", out_s], vec!["render", file, "--out", out_s]] {
                let o = run(&args);
                let all = text(&o);
                assert_eq!(o.status.code(), Some(1), "{ty} {target} {args:?}:\n{all}");
                assert!(all.contains(&format!("node 'w', port '{port}'")), "{ty} {target}: names node and port:\n{all}");
                assert!(all.contains("outside the output folder (--out)") && all.contains("--allow-outside-out"), "{all}");
            }
        }
    }
    assert_eq!(files_under(dir.path()), 1, "only the graph file exists: nothing was written");
}

#[test]
fn without_out_the_graph_folder_is_the_limit() {
    let (dir, graphs, _) = setup();
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", "../escaped.png")).unwrap();
    let o = run(&["check", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("outside the graph's folder"), "{}", text(&o));
    // Inside it, `..` that stays in is fine.
    std::fs::write(&file, graph("imaging.write_image", "path", "sub/../inside.png")).unwrap();
    let o = run(&["render", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(graphs.join("inside.png").is_file());
    assert!(!dir.path().join("escaped.png").exists());
}

#[test]
fn allow_outside_out_lets_a_writer_out() {
    let (dir, graphs, out) = setup();
    let target = dir.path().join("elsewhere/x.png");
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", target.to_str().unwrap())).unwrap();
    let args = ["render", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--allow-outside-out"];
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(target.is_file());
    let o = run(&["check", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--allow-outside-out"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_inside_out_does_not_lead_writers_outside() {
    let (dir, graphs, out) = setup();
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::fs::create_dir_all(out.join("sub")).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("link")).unwrap();
    std::os::unix::fs::symlink(out.join("sub"), out.join("inner")).unwrap();
    let out_s = out.to_str().unwrap();
    for (ty, port, name) in WRITERS {
        let file = graphs.join("g.ron");
        std::fs::write(&file, graph(ty, port, &format!("link/deeper/{name}"))).unwrap();
        let file = file.to_str().unwrap();
        for args in [vec!["check", file, "--out", out_s], vec!["render", file, "--out", out_s]] {
            let o = run(&args);
            let all = text(&o);
            assert_eq!(o.status.code(), Some(1), "{ty} {args:?}:\n{all}");
            assert!(all.contains(&format!("node 'w', port '{port}'")) && all.contains("outside the output folder"), "{all}");
        }
    }
    assert_eq!(files_under(&elsewhere), 0, "nothing was written through the link");
    // A link that stays inside is a folder like any other.
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", "inner/x.png")).unwrap();
    let o = run(&["render", file.to_str().unwrap(), "--out", out_s]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("sub/x.png").is_file());
    // And --allow-outside-out lets a write through the outward link, as it lets any.
    std::fs::write(&file, graph("imaging.write_image", "path", "link/x.png")).unwrap();
    let o = run(&["render", file.to_str().unwrap(), "--out", out_s, "--allow-outside-out"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(elsewhere.join("x.png").is_file());
}

/// The manifest obeys the writers' rule: inside `--out` (links followed) unless
/// `--allow-outside-out`, checked before anything cooks; and it replaces only a manifest.
#[cfg(unix)]
#[test]
fn the_manifest_stays_inside_out_and_replaces_only_a_manifest() {
    let (dir, graphs, out) = setup();
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("link")).unwrap();
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", "x.png")).unwrap();
    let render = |manifest: &Path, extra: &[&str]| {
        let base = ["render", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--manifest", manifest.to_str().unwrap()];
        run(&[&base[..], extra].concat())
    };
    for outside in [elsewhere.join("m.json"), out.join("link/m.json"), out.join("../m.json")] {
        let o = render(&outside, &[]);
        assert_eq!(o.status.code(), Some(1), "{outside:?}: {}", text(&o));
        assert!(text(&o).contains("--manifest") && text(&o).contains("outside the output folder"), "{}", text(&o));
    }
    assert_eq!(files_under(&out) + files_under(&elsewhere), 0, "refused before cooking: nothing was written");
    // A user's file under the manifest's name is not replaced; a manifest is.
    let m = out.join("m.json");
    std::fs::write(&m, "my notes").unwrap();
    let o = render(&m, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("is not a pyrograph manifest"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&m).unwrap(), "my notes");
    std::fs::remove_file(&m).unwrap();
    for run in 0..2 {
        let _ = std::fs::remove_file(out.join("x.png"));
        let o = render(&m, &[]);
        assert!(o.status.success(), "run {run} (the second replaces its own manifest): {}", text(&o));
    }
    assert!(std::fs::read_to_string(&m).unwrap().contains("\"files\""));
    let o = render(&elsewhere.join("m.json"), &["--overwrite", "--allow-outside-out"]);
    assert!(o.status.success() && elsewhere.join("m.json").is_file(), "{}", text(&o));
}

/// Files are written through a fresh temporary and a rename: a symbolic link already standing
/// under an output's name is replaced, never written through, and a job bundle's files too.
#[cfg(unix)]
#[test]
fn a_link_under_an_outputs_name_is_replaced_not_followed() {
    let (dir, graphs, out) = setup();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    std::os::unix::fs::symlink(&victim, out.join("x.png")).unwrap();
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", "x.png")).unwrap();
    let o = run(&["render", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--overwrite"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(!out.join("x.png").is_symlink() && out.join("x.png").is_file());

    let job = dir.path().join("job");
    std::fs::create_dir_all(&job).unwrap();
    std::os::unix::fs::symlink(&victim, job.join("template.yaml")).unwrap();
    let args = ["job", file.to_str().unwrap(), "--out", out.to_str().unwrap(), "--frames", "0-3", "-o", job.to_str().unwrap()];
    let o = run(&args);
    assert_eq!(o.status.code(), Some(1), "an existing bundle file is not replaced unasked: {}", text(&o));
    let o = run(&[&args[..], &["--overwrite"]].concat());
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(std::fs::read_to_string(job.join("template.yaml")).unwrap().contains("specificationVersion"));
}

/// Files written through a temporary get the permissions any new file gets (0666 less the umask),
/// not the temporary's private 0600: a farm's frames are read by other users.
#[cfg(unix)]
#[test]
fn written_files_are_as_readable_as_any_new_file() {
    use std::os::unix::fs::PermissionsExt;
    let (_dir, graphs, out) = setup();
    let file = graphs.join("g.ron");
    std::fs::write(&file, graph("imaging.write_image", "path", "x.png")).unwrap();
    let o = run(&["render", file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let plain = out.join("plain");
    std::fs::File::create(&plain).unwrap();
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&out.join("x.png")), mode(&plain));
}
