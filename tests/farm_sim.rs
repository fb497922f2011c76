//! A graph that simulates, on a farm: `pyrograph simulate` steps each volume simulation once into
//! a VDB cache, renders read it with `--sim-cache` and give the bytes a render that simulates
//! gives, and a job bundle runs the two as dependent steps under `openjd`.
//!
//! The `openjd` test needs the reference CLI (`pip install openjd-cli`); `.ci/run` installs it
//! and sets PYROGRAPH_OPENJD. Without it it is ignored, not faked.

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

fn failed(o: Output, what: &str) -> String {
    assert_eq!(o.status.code(), Some(1), "{what} should fail:\n{}", text(&o));
    text(&o)
}

/// Small and quick: 12 frames at a coarse voxel.
const SETS: [&str; 4] = ["--set", "fire.frames=12", "--set", "fire.voxel_size=0.12"];

fn graph() -> PathBuf {
    workspace().join("graphs/campfire-smoke.ron")
}

/// Every file under `dir` but the job's own folder, relative, with its bytes, sorted.
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out: Vec<(PathBuf, Vec<u8>)> = walkdir(dir)
        .into_iter()
        .filter(|p| !p.components().any(|c| c.as_os_str() == ".pyrograph-job"))
        .map(|p| (p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

fn walkdir(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            if e.path().is_dir() { stack.push(e.path()) } else { files.push(e.path()) }
        }
    }
    files
}

fn render(out: &Path, frames: &str, extra: &[&str]) -> Output {
    bin().arg("render").arg(graph()).arg("--out").arg(out).args(["--frames", frames]).args(SETS).args(extra).output().unwrap()
}

fn simulate(cache: &Path, frames: &str, extra: &[&str]) -> Output {
    bin()
        .arg("simulate")
        .arg(graph())
        .arg("--sim-cache")
        .arg(cache)
        .args(["--frames", frames])
        .args(SETS)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn a_render_from_the_simulation_cache_equals_one_that_simulates_and_a_missing_frame_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, cached, cache) = (dir.path().join("plain"), dir.path().join("cached"), dir.path().join("cache"));
    let cache_arg = cache.to_str().unwrap();
    let e = failed(render(&cached, "0-5", &["--sim-cache", cache_arg]), "a render from a cache not written");
    assert!(e.contains("not a folder") && e.contains("pyrograph simulate"), "{e}");

    let o = ok(simulate(&cache, "0-5", &[]), "simulate");
    assert!(text(&o).contains("fire/sim: 6 frames cached"), "{}", text(&o));
    assert!(cache.join("fire_sim/fire_sim.0005.vdb").is_file() && !cache.join("fire_sim/fire_sim.0006.vdb").exists());
    ok(render(&plain, "0-5", &[]), "plain render");
    ok(render(&cached, "0-5", &["--sim-cache", cache_arg]), "render from the cache");
    let (a, b) = (tree(&plain), tree(&cached));
    assert_eq!(a.len(), 13, "6 PNGs, 6 VDBs and the USD stage: {:?}", a.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert!(a == b, "the frames rendered from the cache are the bytes of a render that simulates");

    let e = failed(render(&dir.path().join("more"), "4-7", &["--sim-cache", cache_arg]), "frames past the cache");
    assert!(e.contains("fire/sim") && e.contains("fire_sim.0006.vdb") && e.contains("pyrograph simulate"), "{e}");

    let e = failed(simulate(&cache, "0-5", &[]), "simulating over a cache");
    assert!(e.contains("fire_sim.0000.vdb exists; nothing was simulated") && e.contains("--overwrite"), "{e}");
    let o = ok(simulate(&cache, "0-5", &["--skip-existing"]), "a whole cache left alone");
    assert!(text(&o).contains("6 frames already cached"), "{}", text(&o));
    let o = ok(simulate(&cache, "0-7", &["--skip-existing", "--overwrite"]), "a cache completed");
    assert!(text(&o).contains("fire/sim: 8 frames cached"), "{}", text(&o));

    let cube = workspace().join("graphs/burning-cube.ron");
    let o = ok(bin().arg("simulate").arg(&cube).arg("--sim-cache").arg(&cache).output().unwrap(), "a graph without simulations");
    assert!(text(&o).contains("nothing to cache"), "{}", text(&o));
    let e = failed(
        bin().arg("render").arg(graph()).args(["--wedge", "fire.seed=1,2", "--sim-cache", cache_arg]).output().unwrap(),
        "a wedge sharing one cache",
    );
    assert!(e.contains("--wedge-index"), "{e}");
}

#[test]
fn a_cache_that_cannot_be_written_stops_the_simulation_with_the_file_named() {
    // The cache is written on its own thread while the next frames step: its failure must end the
    // run with an error, not be lost.
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    std::fs::create_dir_all(&cache).unwrap();
    std::fs::write(cache.join("fire_sim"), b"a file where the folder goes").unwrap();
    let e = failed(simulate(&cache, "0-5", &[]), "a cache folder that is a file");
    assert!(e.contains("simulation 'fire/sim'") && e.contains("cannot create") && e.contains("fire_sim"), "{e}");
    assert!(!e.contains("writer stopped"), "the cause, not the symptom: {e}");
}

#[test]
#[ignore = "needs openjd: set PYROGRAPH_OPENJD or put openjd-cli on PATH (.ci/run installs it)"]
fn a_simulation_job_on_openjd_simulates_once_then_renders_chunks_identical_to_one_render() {
    let dir = tempfile::tempdir().unwrap();
    let (single, farm, job) = (dir.path().join("single"), dir.path().join("farm"), dir.path().join("job"));
    ok(render(&single, "0-11", &[]), "single render");
    let o = ok(
        bin()
            .arg("job")
            .arg(graph())
            .arg("--out")
            .arg(&farm)
            .args(["--frames", "0-11", "--chunk", "4", "-o"])
            .arg(&job)
            .args(SETS)
            .output()
            .unwrap(),
        "pyrograph job",
    );
    assert!(text(&o).contains("a Simulate step") && text(&o).contains("--run-dependencies"), "{}", text(&o));
    let template = std::fs::read_to_string(job.join("template.yaml")).unwrap();
    assert!(
        template.contains("- name: Simulate\n") && template.contains("  dependencies:\n  - dependsOn: Simulate\n"),
        "{template}"
    );
    let openjd = || Command::new(std::env::var_os("PYROGRAPH_OPENJD").unwrap_or_else(|| "openjd".into()));
    ok(openjd().arg("check").arg(job.join("template.yaml")).output().unwrap(), "openjd check");
    let params = format!("file://{}", job.join("job_params.yaml").display());
    let run = ["--step", "Render", "--run-dependencies", "-p", &params];
    let o = ok(openjd().arg("run").arg(job.join("template.yaml")).args(run).output().unwrap(), "openjd run");
    assert!(text(&o).contains("fire/sim: 12 frames cached"), "the Simulate step ran first:\n{}", text(&o));
    assert!(farm.join(".pyrograph-job/sim/fire_sim/fire_sim.0011.vdb").is_file());
    let (a, b) = (tree(&single), tree(&farm));
    assert_eq!(a.len(), 25, "12 PNGs, 12 VDBs and the USD stage");
    assert_eq!(a.iter().map(|f| &f.0).collect::<Vec<_>>(), b.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert!(a == b, "every farm file is byte-identical to the single render");
}
