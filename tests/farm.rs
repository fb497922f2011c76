//! Farm rendering: `pyrograph job` bundles validated and run by the Open Job Description CLI
//! give the same bytes as one `render`, and `--skip-existing` resumes an interrupted chunk.
//!
//! The `openjd` tests need the reference CLI (`pip install openjd-cli`); `.ci/run` installs it
//! and sets PYROGRAPH_OPENJD. Without it they are ignored, not faked.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pyrograph_testing::workspace;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pyrograph"))
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn ok(o: Output, what: &str) -> Output {
    assert!(o.status.success(), "{what} failed:\n{}", text(&o));
    o
}

fn openjd() -> Command {
    Command::new(std::env::var_os("PYROGRAPH_OPENJD").unwrap_or_else(|| "openjd".into()))
}

/// Every file under `dir`, relative, with its bytes, sorted.
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.file_name().is_some_and(|n| n == ".pyrograph-job") {
                continue;
            }
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push((p.strip_prefix(base).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn render(graph: &Path, out: &Path, frames: &str, extra: &[&str]) -> Output {
    bin().arg("render").arg(graph).arg("--out").arg(out).args(["--frames", frames]).args(extra).output().unwrap()
}

#[test]
#[ignore = "needs openjd: set PYROGRAPH_OPENJD or put openjd-cli on PATH (.ci/run installs it)"]
fn a_chunked_openjd_job_renders_the_same_bytes_as_one_process() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/burning-cube.ron");
    let (single, farm, job) = (dir.path().join("single"), dir.path().join("farm"), dir.path().join("job"));
    ok(render(&graph, &single, "0-47", &[]), "single render");
    let o = ok(
        bin()
            .arg("job")
            .arg(&graph)
            .arg("--out")
            .arg(&farm)
            .args(["--frames", "0-47", "--chunk", "8", "-o"])
            .arg(&job)
            .output()
            .unwrap(),
        "pyrograph job",
    );
    assert!(text(&o).contains("6 tasks of up to 8 frames"), "{}", text(&o));
    ok(openjd().arg("check").arg(job.join("template.yaml")).output().unwrap(), "openjd check");
    let params = format!("file://{}", job.join("job_params.yaml").display());
    let o = ok(
        openjd().arg("run").arg(job.join("template.yaml")).args(["--step", "Render", "-p", &params]).output().unwrap(),
        "openjd run",
    );
    assert!(text(&o).contains("Chunks run: 6"), "{}", text(&o));
    let (a, b) = (tree(&single), tree(&farm));
    assert_eq!(a.len(), 48, "48 frames from the single render");
    assert_eq!(a.iter().map(|f| &f.0).collect::<Vec<_>>(), b.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert!(a == b, "every farm frame is byte-identical to the single render");
    let o = ok(bin().args(["job", "collect"]).arg(&job).output().unwrap(), "job collect");
    assert!(text(&o).contains("6 tasks, 48 files"), "{}", text(&o));
}

#[test]
#[ignore = "needs openjd: set PYROGRAPH_OPENJD or put openjd-cli on PATH (.ci/run installs it)"]
fn a_job_without_task_chunking_lists_its_chunks_and_runs() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/burning-cube.ron");
    let (single, farm, job) = (dir.path().join("single"), dir.path().join("farm"), dir.path().join("job"));
    ok(render(&graph, &single, "0-30:3,31", &[]), "single render");
    let args = ["--frames", "0-30:3,31", "--chunk", "4", "--no-chunking", "-o"];
    ok(bin().arg("job").arg(&graph).arg("--out").arg(&farm).args(args).arg(&job).output().unwrap(), "pyrograph job");
    ok(openjd().arg("check").arg(job.join("template.yaml")).output().unwrap(), "openjd check");
    let params = format!("file://{}", job.join("job_params.yaml").display());
    ok(
        openjd().arg("run").arg(job.join("template.yaml")).args(["--step", "Render", "-p", &params]).output().unwrap(),
        "openjd run",
    );
    let (a, b) = (tree(&single), tree(&farm));
    assert_eq!(a.len(), 12);
    assert!(a == b, "the stepped, listed frames match a single render");
}

#[test]
fn skip_existing_completes_an_interrupted_chunk_identically() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/burning-cube.ron");
    let (clean, crashed) = (dir.path().join("clean"), dir.path().join("crashed"));
    ok(render(&graph, &clean, "8-15", &[]), "clean render");
    ok(render(&graph, &crashed, "8-15", &[]), "render that will be cut short");
    // Simulate a worker killed mid-chunk: the last three frames were never renamed into place,
    // one temporary file is left behind, and one finished frame must not be rewritten.
    let files = tree(&crashed);
    for (name, _) in &files[5..] {
        std::fs::remove_file(crashed.join(name)).unwrap();
    }
    let first = crashed.join(&files[0].0);
    let leftover = first.with_file_name(".frame_0013.png.4242.tmp");
    std::fs::write(&leftover, b"half a frame").unwrap();
    let kept = std::fs::metadata(&first).unwrap().modified().unwrap();

    // burning-cube's writer has overwrite on, so only --skip-existing keeps the finished frames.
    ok(render(&graph, &crashed, "8-15", &["--skip-existing"]), "resumed render");
    std::fs::remove_file(&leftover).unwrap();
    assert!(tree(&clean) == tree(&crashed), "the resumed sequence is complete and identical");
    assert_eq!(std::fs::metadata(&first).unwrap().modified().unwrap(), kept, "finished frames are left alone");
}

#[test]
fn job_refuses_bad_arguments_and_existing_bundles() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/burning-cube.ron");
    let job = dir.path().join("job");
    let run = |extra: &[&str]| {
        bin().arg("job").arg(&graph).arg("--out").arg(dir.path().join("o")).arg("-o").arg(&job).args(extra).output().unwrap()
    };
    let o = run(&["--frames", "9-3"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("the first frame is after the last"), "{}", text(&o));
    assert!(text(&run(&["--frames", "0-9", "--chunk", "0"])).contains("--chunk must be at least 1"));
    let o = run(&["--frames", "0-9", "--set", "nosuch.x=1"]);
    assert_eq!(o.status.code(), Some(1), "a bad --set is caught before any task runs:\n{}", text(&o));
    ok(run(&["--frames", "0-9"]), "first bundle");
    let o = run(&["--frames", "0-9"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("exists; nothing was written"), "{}", text(&o));
    ok(run(&["--frames", "0-9", "--overwrite"]), "replacing the bundle");
}

/// Runs the tasks of a job bundle's chunks the way a worker does, without openjd.
fn run_tasks(graph: &Path, out: &Path, chunks: &[&str]) {
    for c in chunks {
        let manifest = out.join(format!(".pyrograph-job/task-{c}.json"));
        let extra = ["--skip-existing", "--manifest", manifest.to_str().unwrap()];
        ok(render(graph, out, c, &extra), "task");
    }
}

#[test]
fn job_collect_merges_manifests_and_reports_missing_frames_and_changed_files() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/burning-cube.ron");
    let (out, job) = (dir.path().join("out"), dir.path().join("job"));
    let args = ["--frames", "0-23", "--chunk", "8", "-o"];
    ok(bin().arg("job").arg(&graph).arg("--out").arg(&out).args(args).arg(&job).output().unwrap(), "pyrograph job");
    let template = std::fs::read_to_string(job.join("template.yaml")).unwrap();
    assert!(template.contains(r#""--manifest", "{{Param.Out}}/.pyrograph-job/task-{{Task.Param.Frame}}.json""#), "{template}");
    // Two of the three tasks finished.
    run_tasks(&graph, &out, &["0-7", "16-23"]);
    let collect = || bin().args(["job", "collect"]).arg(&job).output().unwrap();
    let o = collect();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("error: frames 8-15 of 0-23 have no finished task"), "{}", text(&o));
    // The third task runs; now the job is whole.
    run_tasks(&graph, &out, &["8-15"]);
    let o = ok(collect(), "collect");
    assert!(text(&o).contains("3 tasks, 24 files"), "{}", text(&o));
    let merged: serde_json::Value = serde_json::from_slice(&std::fs::read(job.join("manifest.json")).unwrap()).unwrap();
    let files = merged["files"].as_array().unwrap();
    assert_eq!(files.len(), 24);
    let first = out.join(files[0]["path"].as_str().unwrap());
    assert_eq!(files[0]["bytes"].as_u64().unwrap(), std::fs::metadata(&first).unwrap().len());
    assert_eq!(files[0]["sha256"].as_str().unwrap().len(), 64);
    // A file changed after its task wrote it is reported.
    std::fs::write(&first, b"not the frame").unwrap();
    let o = collect();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("changed after its task wrote it"), "{}", text(&o));
}

#[test]
#[ignore = "needs openjd: set PYROGRAPH_OPENJD or put openjd-cli on PATH (.ci/run installs it)"]
fn a_wedge_job_on_openjd_matches_a_local_wedge_render() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/candles.ron");
    let (single, farm, job) = (dir.path().join("single"), dir.path().join("farm"), dir.path().join("job"));
    let wedge = ["--wedge", "wind.noise_c=0.01,0.04", "--wedge", "wind.seed=1,2,3"];
    let o = ok(
        bin().arg("render").arg(&graph).arg("--out").arg(&single).args(["--frames", "0-47"]).args(wedge).output().unwrap(),
        "local wedge",
    );
    assert!(text(&o).contains("cooked 6 variants"), "{}", text(&o));
    let args = ["--frames", "0-47", "--chunk", "24", "-o"];
    let o = ok(
        bin().arg("job").arg(&graph).arg("--out").arg(&farm).args(wedge).args(args).arg(&job).output().unwrap(),
        "pyrograph job",
    );
    assert!(text(&o).contains("12 tasks of up to 24 frames"), "{}", text(&o));
    ok(openjd().arg("check").arg(job.join("template.yaml")).output().unwrap(), "openjd check");
    let params = format!("file://{}", job.join("job_params.yaml").display());
    let o = ok(
        openjd().arg("run").arg(job.join("template.yaml")).args(["--step", "Render", "-p", &params]).output().unwrap(),
        "openjd run",
    );
    assert!(text(&o).contains("Chunks run: 12"), "{}", text(&o));
    let (a, b) = (tree(&single), tree(&farm));
    assert_eq!(a.len(), 6 * 48, "six variants of 48 frames, each in its own folder");
    assert!(a == b, "every wedge frame from the farm is byte-identical to the local wedge render");
    let o = ok(bin().args(["job", "collect"]).arg(&job).output().unwrap(), "job collect");
    assert!(text(&o).contains("12 tasks, 288 files"), "{}", text(&o));
    std::fs::remove_file(farm.join(".pyrograph-job/task-w4-24-47.json")).unwrap();
    let o = bin().args(["job", "collect"]).arg(&job).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("wedge 4 frames 24-47 of 0-47 have no finished task"), "{}", text(&o));
}

#[test]
fn a_local_wedge_writes_variants_apart_and_a_labelled_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let graph = workspace().join("graphs/candles.ron");
    let out = dir.path().join("out");
    let wedge = ["--wedge-zip", "wind.seed=1,2", "--wedge-zip", "flames.steps=10,30"];
    let o = ok(
        bin().arg("render").arg(&graph).arg("--out").arg(&out).args(["--frames", "0-3", "--sheet"]).args(wedge).output().unwrap(),
        "wedge",
    );
    assert!(text(&o).contains("cooked 2 variants"), "{}", text(&o));
    for name in ["wind.seed-1_flames.steps-10", "wind.seed-2_flames.steps-30"] {
        assert_eq!(tree(&out.join(name)).len(), 4, "{name}");
    }
    let sheet = pyrograph_frontend::imaging::io::load_image(&out.join("wedges.png")).unwrap();
    assert_eq!(sheet.width(), 2 * (320 + 8) + 8, "two cells across (the zipped axis)");
    // A bad value stops the wedge before anything is written.
    let bad = dir.path().join("bad");
    let o = bin().arg("render").arg(&graph).arg("--out").arg(&bad).args(["--wedge", "wind.noise_c=0.01,9"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("node 'wind', port 'noise_c': 9 is outside the range"), "{}", text(&o));
    assert!(!bad.exists(), "nothing was written");
}
