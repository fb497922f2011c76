//! The farm side of the CLI: `job` bundles, `job collect`, and render manifests.

use std::path::{Path, PathBuf};

use clap::Subcommand;
use pyrograph::core::{BuildOptions, CookCtx, CookResult, FrameSet, Registry};

use crate::{Failure, RenderOpts, load, memory_kib};

#[derive(Subcommand)]
pub enum JobAction {
    /// Merge the task manifests of a job into JOB_DIR/manifest.json; exit 1 when a frame has no
    /// finished task or a file changed after its task wrote it.
    Collect {
        /// The job bundle folder.
        job_dir: PathBuf,
        /// Print the merged report as JSON.
        #[arg(long)]
        json: bool,
    },
}

pub fn collect(job_dir: &Path, json_out: bool) -> Result<(), Failure> {
    let report = pyrograph::manifest::collect(job_dir).map_err(|e| Failure(format!("error: {e}")))?;
    let text = serde_json::to_string_pretty(&report).map_err(|e| Failure(format!("error: {e}")))?;
    let merged = job_dir.join("manifest.json");
    pyrograph::core::document::write_atomic(&merged, text.as_bytes(), true)
        .map_err(|e| Failure(format!("error: writing {}: {e}", merged.display())))?;
    if json_out {
        println!("{text}");
    } else {
        let bytes: u64 = report.files.iter().map(|f| f.bytes).sum();
        println!(
            "{} tasks, {} files ({:.1} MiB), {:.1} task-seconds, peak {} MiB; merged into {}",
            report.tasks,
            report.files.len(),
            bytes as f64 / (1u64 << 20) as f64,
            report.task_seconds,
            report.peak_rss_mib.map_or_else(|| "?".into(), |m| m.to_string()),
            merged.display()
        );
    }
    if !report.missing.is_empty() {
        eprintln!("error: frames {} of {} have no finished task", report.missing, report.frames);
    }
    for d in &report.damaged {
        eprintln!("error: {d}");
    }
    if report.is_complete() { Ok(()) } else { Err(Failure(String::new())) }
}

pub struct JobArgs {
    pub graph: PathBuf,
    pub out: PathBuf,
    pub frames: FrameSet,
    pub chunk: usize,
    pub sets: Vec<String>,
    pub task_chunking: bool,
}

/// Checks the graph as the tasks will load it, then writes the bundle.
pub fn job(registry: &Registry, a: &JobArgs, job_dir: &Path, overwrite: bool) -> Result<(), Failure> {
    let abs = |p: &Path| std::path::absolute(p).map_err(|e| Failure(format!("error: {}: {e}", p.display())));
    let options = BuildOptions { output_dir: Some(a.out.clone()), ..BuildOptions::default() };
    load(registry, &a.graph, &a.sets, &options)?;
    if a.chunk == 0 {
        return Err(Failure("error: --chunk must be at least 1 frame".into()));
    }
    let exe = std::env::current_exe().map_err(|e| Failure(format!("error: cannot find the pyrograph binary: {e}")))?;
    let name = a.graph.file_stem().map_or_else(|| "graph".into(), |s| s.to_string_lossy().into_owned());
    let spec = pyrograph::job::JobSpec {
        name: format!("pyrograph {name} {}", a.frames),
        pyrograph: exe,
        graph: abs(&a.graph)?,
        out: abs(&a.out)?,
        frames: a.frames.clone(),
        chunk: a.chunk,
        sets: a.sets.clone(),
        task_chunking: a.task_chunking,
    };
    std::fs::create_dir_all(job_dir).map_err(|e| Failure(format!("error: cannot create {}: {e}", job_dir.display())))?;
    let bundle = spec.bundle();
    if !overwrite && let Some((f, _)) = bundle.files.iter().find(|(f, _)| job_dir.join(f).exists()) {
        return Err(Failure(format!(
            "error: {} exists; nothing was written (--overwrite replaces it)",
            job_dir.join(f).display()
        )));
    }
    for (f, text) in &bundle.files {
        pyrograph::core::document::write_atomic(&job_dir.join(f), text.as_bytes(), overwrite)
            .map_err(|e| Failure(format!("error: writing {}: {e}", job_dir.join(f).display())))?;
    }
    let tasks = a.frames.chunks(a.chunk).len();
    println!("job bundle {}: {tasks} tasks of up to {} frames ({})", job_dir.display(), a.chunk, a.frames);
    println!("run it here:  openjd run {0}/template.yaml --step Render -p file://{0}/job_params.yaml", abs(job_dir)?.display());
    println!("submit it:    deadline bundle submit {} (AWS Deadline Cloud)", job_dir.display());
    Ok(())
}

pub fn write_manifest(
    file: &Path,
    graph: &Path,
    out: &Path,
    o: &RenderOpts,
    ctx: &CookCtx,
    result: &CookResult,
    elapsed: std::time::Duration,
) -> Result<(), Failure> {
    let fail = |e: std::io::Error| Failure(format!("error: manifest {}: {e}", file.display()));
    let manifest = pyrograph::manifest::Manifest {
        graph: graph.display().to_string(),
        frames: o.frames.as_ref().map(ToString::to_string),
        ok: result.root_errors().is_empty(),
        seconds: elapsed.as_secs_f64(),
        peak_rss_mib: memory_kib("VmHWM").map(|k| k >> 10),
        files: pyrograph::manifest::records(&ctx.written(), out).map_err(fail)?,
    };
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(fail)?;
    }
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| Failure(format!("error: manifest: {e}")))?;
    pyrograph::core::document::write_atomic(file, text.as_bytes(), true).map_err(fail)
}
