//! The farm side of the CLI: `job` bundles, `job collect`, and render manifests.

use std::path::{Path, PathBuf};

use clap::Subcommand;
use pyrograph::wedge::{Variant, Wedges, cell_image};
use pyrograph::{errln, outln};
use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, FrameSet, Graph, GraphDoc, Registry};
use pyrograph_frontend::text::printable_json;
use rayon::prelude::*;

use crate::{Failure, RenderOpts, apply_sets, explain, load, memory_kib};
use pyrograph::job::simulations;

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
    pyrograph_frontend::core::document::write_atomic(&merged, text.as_bytes(), true)
        .map_err(|e| Failure(format!("error: writing {}: {e}", merged.display())))?;
    if json_out {
        // The merged file keeps the tasks' own strings; what reaches the terminal is printable.
        let shown = serde_json::to_value(&report).map(printable_json).map_err(|e| Failure(format!("error: {e}")))?;
        println!("{}", serde_json::to_string_pretty(&shown).map_err(|e| Failure(format!("error: {e}")))?);
    } else {
        let bytes: u64 = report.files.iter().map(|f| f.bytes).sum();
        outln!(
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
        errln!("error: {} of {} have no finished task", report.missing, report.frames);
    }
    for d in &report.damaged {
        errln!("error: {d}");
    }
    if report.is_complete() { Ok(()) } else { Err(Failure(String::new())) }
}

pub struct JobArgs {
    pub graph: PathBuf,
    pub out: PathBuf,
    pub frames: FrameSet,
    pub chunk: usize,
    pub sets: Vec<String>,
    pub wedge: Vec<String>,
    pub wedge_zip: Vec<String>,
    pub task_chunking: bool,
    /// The limits given to `job` (as command-line arguments), for every task.
    pub limits: Vec<String>,
}

/// Checks the graph as the tasks will load it, then writes the bundle.
pub fn job(registry: &Registry, a: &JobArgs, job_dir: &Path, overwrite: bool) -> Result<(), Failure> {
    let abs = |p: &Path| std::path::absolute(p).map_err(|e| Failure(format!("error: {}: {e}", p.display())));
    let options = BuildOptions { output_dir: Some(a.out.clone()), ..BuildOptions::default() };
    let wedges = Wedges::parse(&a.wedge, &a.wedge_zip).map_err(|e| Failure(format!("error: {e}")))?;
    let variants = wedges.variants();
    let mut simulate = false;
    if variants.is_empty() {
        simulate = !simulations(&load(registry, &a.graph, &a.sets, &options)?.1).is_empty();
    }
    // Every variant is checked here, so no task fails on a bad wedge value.
    for v in &variants {
        simulate |= !simulations(&build_variant(registry, &a.graph, &a.sets, a.out.as_path(), false, v)?.0).is_empty();
    }
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
        wedge: a.wedge.clone(),
        wedge_zip: a.wedge_zip.clone(),
        variants: variants.len(),
        task_chunking: a.task_chunking,
        limits: a.limits.clone(),
        simulate,
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
        pyrograph_frontend::core::document::write_atomic(&job_dir.join(f), text.as_bytes(), overwrite)
            .map_err(|e| Failure(format!("error: writing {}: {e}", job_dir.join(f).display())))?;
    }
    let tasks = a.frames.chunks(a.chunk).len() * variants.len().max(1);
    outln!("job bundle {}: {tasks} tasks of up to {} frames ({})", job_dir.display(), a.chunk, a.frames);
    let deps = if simulate {
        outln!("a Simulate step caches the simulations once ({}) before the chunks render", simulations_note(variants.len()));
        " --run-dependencies"
    } else {
        ""
    };
    outln!(
        "run it here:  openjd run {0}/template.yaml --step Render{deps} -p file://{0}/job_params.yaml",
        abs(job_dir)?.display()
    );
    outln!("submit it:    deadline bundle submit {} (AWS Deadline Cloud)", job_dir.display());
    Ok(())
}

fn simulations_note(variants: usize) -> String {
    if variants > 0 { format!("one task per wedge variant, {variants}") } else { "one task".to_string() }
}

/// Refuses a manifest path before anything is cooked: outside `out` (names or symbolic links)
/// unless `--allow-outside-out`, or naming a file that is not a manifest unless `--overwrite`
/// (a re-run replaces its own manifest, never a graph or a frame given by mistake).
pub fn check_manifest_target(file: &Path, out: &Path, o: &RenderOpts) -> Result<(), Failure> {
    if !o.allow_outside_out && !pyrograph_frontend::core::limits::inside(file, out) {
        return Err(Failure(format!(
            "error: --manifest {}: outside the output folder {}; write it inside, or render with --allow-outside-out",
            file.display(),
            out.display()
        )));
    }
    if file.is_dir() {
        return Err(Failure(format!("error: --manifest {}: is a folder; name a file", file.display())));
    }
    if file.exists() && !o.overwrite && !pyrograph::manifest::is_manifest(file) {
        return Err(Failure(format!(
            "error: --manifest {}: exists and is not a pyrograph manifest; refusing to replace it (add --overwrite to)",
            file.display()
        )));
    }
    Ok(())
}

/// Writes a render's manifest: `files` hashed, relative to `out`.
#[allow(clippy::too_many_arguments)]
pub fn write_manifest(
    file: &Path,
    graph: &Path,
    out: &Path,
    o: &RenderOpts,
    wedge: Option<usize>,
    ok: bool,
    files: &[PathBuf],
    elapsed: std::time::Duration,
) -> Result<(), Failure> {
    let fail = |e: std::io::Error| Failure(format!("error: manifest {}: {e}", file.display()));
    let manifest = pyrograph::manifest::Manifest {
        graph: graph.display().to_string(),
        frames: o.frames.as_ref().map(ToString::to_string),
        wedge,
        ok,
        seconds: elapsed.as_secs_f64(),
        peak_rss_mib: memory_kib("VmHWM").map(|k| k >> 10),
        files: pyrograph::manifest::records(files, out).map_err(fail)?,
    };
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(fail)?;
    }
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| Failure(format!("error: manifest: {e}")))?;
    pyrograph_frontend::core::document::write_atomic(file, text.as_bytes(), true).map_err(fail)
}

/// What one wedge variant's cook left.
struct VariantRun {
    variant: Variant,
    out: PathBuf,
    written: Vec<PathBuf>,
    errors: Vec<String>,
}

/// Builds variant `v`'s graph (every variant is built before any cooks, so a bad value stops
/// the wedge before it writes anything).
pub(crate) fn build_variant(
    registry: &Registry,
    path: &Path,
    sets: &[String],
    out_root: &Path,
    allow_outside_out: bool,
    v: &Variant,
) -> Result<(Graph, PathBuf), Failure> {
    let mut doc = GraphDoc::load(path)?;
    apply_sets(&mut doc, sets)?;
    let used_tokens = v.apply(&mut doc).map_err(|e| Failure(format!("error: {e}")))?;
    let out = if used_tokens { out_root.to_path_buf() } else { out_root.join(&v.name) };
    let options = BuildOptions { output_dir: Some(out.clone()), allow_outside_out, ..BuildOptions::default() };
    let graph = Graph::build_file(&doc, path, registry, &options)?;
    Ok((graph, out))
}

fn run_variant(graph: &Graph, path: &Path, out: PathBuf, o: &RenderOpts, v: &Variant) -> Result<VariantRun, Failure> {
    let sinks: Vec<String> = graph.sinks().iter().map(|s| s.to_string()).collect();
    let targets: Vec<&str> = sinks.iter().map(String::as_str).collect();
    let ctx = CookCtx::new().with_settings(o.settings());
    let result = Evaluator::new().cook(graph, &targets, &ctx).map_err(|e| Failure(format!("error: {e}")))?;
    let errors = result
        .root_errors()
        .iter()
        .map(|(n, e)| format!("error: {}: wedge {}: {}", path.display(), v.name, explain(n, e)))
        .collect();
    Ok(VariantRun { variant: v.clone(), out, written: ctx.written(), errors })
}

/// `render --wedge …`: every variant (or `--wedge-index`'s one), in parallel (the shared frame
/// cache keeps them within one memory budget), then the manifest and the sheet.
pub fn render_wedges(registry: &Registry, path: &Path, o: &RenderOpts, wedges: &Wedges) -> Result<(), Failure> {
    let all = wedges.variants();
    let chosen: Vec<Variant> = match o.wedges.wedge_index {
        Some(k) if k < all.len() => vec![all[k].clone()],
        Some(k) => {
            return Err(Failure(format!("error: --wedge-index {k}: the wedge has {} variants (0-{})", all.len(), all.len() - 1)));
        }
        None if o.sim_cache.is_some() => {
            return Err(Failure(
                "error: --sim-cache with a wedge: each variant simulates differently, so render one variant \
                 (--wedge-index K) with the cache `pyrograph simulate --wedge-index K` wrote"
                    .into(),
            ));
        }
        None => all.clone(),
    };
    let out_root = o.out.clone().unwrap_or_else(|| path.parent().map(Path::to_path_buf).unwrap_or_default());
    if let Some(file) = &o.manifest {
        check_manifest_target(file, &out_root, o)?;
    }
    let started = std::time::Instant::now();
    let built: Vec<(Graph, PathBuf)> = chosen
        .iter()
        .map(|v| build_variant(registry, path, &o.set, &out_root, o.allow_outside_out, v))
        .collect::<Result<_, _>>()?;
    let runs: Vec<VariantRun> =
        chosen.par_iter().zip(built).map(|(v, (graph, out))| run_variant(&graph, path, out, o, v)).collect::<Result<_, _>>()?;
    let mut failed = false;
    for r in &runs {
        outln!(
            "wedge {}/{} {}: {} files in {}",
            r.variant.index + 1,
            all.len(),
            r.variant.name,
            r.written.len(),
            r.out.display()
        );
        for e in &r.errors {
            errln!("{e}");
            failed = true;
        }
    }
    if let Some(file) = &o.manifest {
        let files: Vec<PathBuf> = runs.iter().flat_map(|r| r.written.clone()).collect();
        write_manifest(file, path, &out_root, o, o.wedges.wedge_index, !failed, &files, started.elapsed())?;
    }
    if o.sheet && !failed {
        let sheet_path = out_root.join("wedges.png");
        write_sheet(&runs, wedges, &sheet_path, o.overwrite)?;
        outln!("wedge sheet: {}", sheet_path.display());
    }
    outln!("cooked {} variants in {:.2} s", runs.len(), started.elapsed().as_secs_f64());
    if failed { Err(Failure(String::new())) } else { Ok(()) }
}

fn write_sheet(runs: &[VariantRun], wedges: &Wedges, path: &Path, overwrite: bool) -> Result<(), Failure> {
    let mut cells = Vec::new();
    for r in runs {
        let file = cell_image(&r.written)
            .ok_or_else(|| Failure(format!("error: --sheet: wedge {} wrote no PNG or EXR image", r.variant.name)))?;
        let img = pyrograph_frontend::imaging::io::load_image(file).map_err(|e| Failure(format!("error: --sheet: {e}")))?;
        let mut label = vec![format!("#{}", r.variant.index)];
        label.extend(r.variant.label());
        cells.push((img, label));
    }
    let columns = wedges.shape().last().copied().unwrap_or(1);
    let sheet = pyrograph::wedge::sheet(&cells, columns, 320).map_err(|e| Failure(format!("error: --sheet: {e}")))?;
    let format = pyrograph_frontend::imaging::io::OutputFormat::Png { sixteen_bit: false };
    pyrograph_frontend::imaging::io::write_image(&sheet, path, format, overwrite)
        .map_err(|e| Failure(format!("error: --sheet: {e}")))
}
