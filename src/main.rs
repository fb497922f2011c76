//! `pyrograph`: cook node graphs headlessly (CI, render farms), check them, list nodes and presets.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};

use clap::{Parser, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use serde_json::json;

use pyrograph::{errln, outln};
use pyrograph_frontend::text::printable_json;

mod cli_farm;
mod cli_plugins;
mod cli_presets;
mod cli_sim;

use cli_farm::{JobAction, JobArgs, collect, job, write_manifest};
use cli_presets::{PresetQuery, presets, render_preset};
use pyrograph_frontend::core::{
    BuildOptions, CookCtx, CookResult, CookSettings, Diagnostics, Evaluator, FrameSet, Graph, GraphDoc, NodeError, ParamValue,
    Progress, Registry, TimeDep, Warning,
};

#[derive(Parser)]
#[command(
    name = "pyrograph",
    version,
    about = "Node-graph toolkit for procedural fire. With no command, cooks the built-in demo graph."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    limits: Limits,
    #[command(flatten)]
    plugins: cli_plugins::PluginArgs,
}

/// What the process may read and how big a graph or image it builds (for services that cook
/// graphs their users submit; every command obeys them).
#[derive(clap::Args)]
struct Limits {
    /// Read only inside this folder (repeat for several): includes, presets, footage, meshes
    /// and databases elsewhere are refused, symbolic links followed to where they lead. The
    /// graph file named on the command line is read wherever it is.
    #[arg(long = "read-root", value_name = "DIR", global = true)]
    read_roots: Vec<PathBuf>,
    /// Refuse a graph that has more nodes than this once its includes are flattened (default
    /// 1,000,000, or PYROGRAPH_MAX_NODES).
    #[arg(long, value_name = "N", global = true)]
    max_nodes: Option<u64>,
    /// Refuse an image or video whose header declares more pixels a frame than this (default
    /// 268,435,456 = 16384 × 16384, or PYROGRAPH_MAX_PIXELS).
    #[arg(long, value_name = "N", global = true)]
    max_pixels: Option<u64>,
    /// Refuse a volume (a simulation's active region, a VDB file's grids) of more active voxels
    /// than this (default 67,108,864 = 64 Mi, or PYROGRAPH_MAX_VOXELS).
    #[arg(long, value_name = "N", global = true)]
    max_voxels: Option<u64>,
}

impl Limits {
    /// The limits as arguments again (read roots made absolute), for a job's tasks.
    fn args(&self) -> Vec<String> {
        let mut out = Vec::new();
        for r in &self.read_roots {
            out.push("--read-root".to_string());
            out.push(std::path::absolute(r).unwrap_or_else(|_| r.clone()).display().to_string());
        }
        for (flag, n) in [("--max-nodes", self.max_nodes), ("--max-pixels", self.max_pixels), ("--max-voxels", self.max_voxels)] {
            if let Some(n) = n {
                out.extend([flag.to_string(), n.to_string()]);
            }
        }
        out
    }

    fn apply(&self) -> Result<(), Failure> {
        use pyrograph_frontend::core::limits;
        limits::set_max_nodes(self.max_nodes);
        limits::set_max_pixels(self.max_pixels);
        limits::set_max_voxels(self.max_voxels);
        limits::set_read_roots(&self.read_roots).map_err(|e| Failure(format!("error: --read-root {e}")))
    }
}

#[derive(Subcommand)]
enum Command {
    /// Cook a graph: every writer node (or the nodes given with --node).
    Render {
        /// The graph file (RON).
        graph: PathBuf,
        #[command(flatten)]
        opts: RenderOpts,
        /// Memory for cached frames, in MiB, shared by every clip of the graph (least recently
        /// used frames are dropped and recomputed when needed again).
        #[arg(long, value_name = "MIB", default_value_t = pyrograph_frontend::core::value::frame_cache::DEFAULT_BUDGET >> 20)]
        cache_mb: usize,
        /// Hold cached frames of 8-bit content at one byte a sample (four times as many in the
        /// budget, for graphs that revisit frames; costs a pass over each frame cached).
        #[arg(long)]
        compact_cache: bool,
    },
    /// Write an Open Job Description job bundle that renders the graph on a render farm (AWS
    /// Deadline Cloud) or locally with `openjd run`: one task per chunk of frames.
    /// `job collect JOB_DIR` merges the tasks' manifests and reports missing frames.
    #[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
    Job {
        #[command(subcommand)]
        action: Option<JobAction>,
        /// The graph file (RON).
        #[arg(required = true)]
        graph: Option<PathBuf>,
        /// Where the tasks write (relative output paths resolve against it).
        #[arg(long, required = true)]
        out: Option<PathBuf>,
        /// Frames to render: 0-239, 0-99:2, 1,5,9-12.
        #[arg(long, value_parser = parse_frames, required = true)]
        frames: Option<FrameSet>,
        /// Frames per task.
        #[arg(long, default_value_t = 24)]
        chunk: usize,
        /// Override a parameter in every task: node.param=value.
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        set: Vec<String>,
        /// List the chunks as a STRING task parameter instead of using the TASK_CHUNKING
        /// extension, for schedulers without it.
        #[arg(long)]
        no_chunking: bool,
        /// A wedge axis, as `render --wedge`: each variant becomes its own tasks.
        #[arg(long = "wedge", value_name = "NODE.PARAM=V1,V2,…")]
        wedge: Vec<String>,
        /// Parameters that vary together, as `render --wedge-zip`.
        #[arg(long = "wedge-zip", value_name = "NODE.PARAM=V1,V2,…")]
        wedge_zip: Vec<String>,
        /// The bundle folder to write.
        #[arg(short = 'o', long = "output", value_name = "JOB_DIR", required = true)]
        job_dir: Option<PathBuf>,
        /// Replace bundle files that already exist.
        #[arg(long)]
        overwrite: bool,
    },
    /// Step every volume simulation of a graph once and cache its frames as VDB files, for
    /// `render --sim-cache` (a farm job's Simulate step, before its chunked Render step).
    Simulate(cli_sim::SimulateArgs),
    /// Validate a graph and probe its sources (files exist and decode) without rendering.
    Check {
        /// The graph file (RON).
        graph: PathBuf,
        /// The output folder the render will use: writer paths must stay inside it (without
        /// it, inside the graph file's folder).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Let writer paths leave the output folder, as `render --allow-outside-out`.
        #[arg(long)]
        allow_outside_out: bool,
        /// Print a JSON report instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Write a graph back out in the current format (older versions migrated), after --set:
    /// byte for byte what the editor and Python's `Graph.save` write.
    Save {
        /// The graph file (RON).
        graph: PathBuf,
        /// Where to write.
        #[arg(short = 'o', long = "output", value_name = "FILE")]
        output: PathBuf,
        /// Override a parameter: node.param=value.
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        set: Vec<String>,
        /// Replace the output file if it exists.
        #[arg(long)]
        overwrite: bool,
    },
    /// The node reference.
    Nodes {
        /// As Markdown (what docs/nodes.md holds).
        #[arg(long, conflicts_with = "json")]
        markdown: bool,
        /// As JSON.
        #[arg(long)]
        json: bool,
    },
    /// Nodes, edges, types and interface of a graph.
    Info {
        /// The graph file (RON).
        graph: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// List presets with their metadata and exposed ports: those next to --graph (its `presets/`
    /// folder), in every folder of PYROGRAPH_PRESET_PATH, then pyrograph's own; an earlier folder
    /// wins a name, and the listing says what it hides.
    Presets {
        /// List only this folder instead of the search path.
        #[arg(long)]
        dir: Option<PathBuf>,
        /// Search the `presets/` folder next to this graph first.
        #[arg(long)]
        graph: Option<PathBuf>,
        /// Only presets with this tag (repeat for several; all must match).
        #[arg(long)]
        tag: Vec<String>,
        /// Only presets whose name, description or tags contain this text (any case).
        #[arg(long)]
        search: Option<String>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Cook each listed preset at 256×144 (its middle frame or thumbnail_frame; inputs from its samples) and
        /// write the thumbnail its metadata names (default thumbs/<file>.png beside it).
        #[arg(long)]
        thumbnails: bool,
        /// With --thumbnails: write them into this folder instead.
        #[arg(long, requires = "thumbnails")]
        out: Option<PathBuf>,
        /// With --thumbnails: replace thumbnails that exist.
        #[arg(long, requires = "thumbnails")]
        overwrite: bool,
    },
    /// Render one preset by name (or file) into frames: --set PARAM=VALUE sets its exposed
    /// parameters, --input NAME=FILE feeds its inputs (a graph file, an image, a video or a
    /// folder of frames); frames go to --out (default pyrograph-out) as <preset>/<preset>_####.png.
    Preset {
        /// The preset's name (see `pyrograph presets`) or a preset file.
        name: String,
        /// Search the `presets/` folder next to this graph first.
        #[arg(long)]
        graph: Option<PathBuf>,
        /// Feed an input: NAME=FILE (default: the preset's sample, where it has one).
        #[arg(long = "input", value_name = "NAME=FILE")]
        input: Vec<String>,
        #[command(flatten)]
        opts: RenderOpts,
    },
    /// Time the evaluator: cold, warm and one-parameter re-cook of 200-node chains and fans.
    Bench {
        /// Iterations per measurement.
        #[arg(long, default_value_t = 200)]
        iters: usize,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Cook the built-in demo graph (what `pyrograph` alone does).
    Demo {
        /// Output folder.
        #[arg(long, default_value = pyrograph::demo::DEMO_OUT)]
        out: PathBuf,
    },
}

fn parse_frames(s: &str) -> Result<FrameSet, String> {
    s.parse()
}

/// A failure that ends the command with exit code 1 after printing its message.
struct Failure(String);

impl From<Diagnostics> for Failure {
    fn from(d: Diagnostics) -> Self {
        Failure(d.to_string())
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let mut registry = pyrograph_frontend::registry();
    if let Err(Failure(msg)) = cli.limits.apply().and_then(|()| cli.plugins.attach(&mut registry, cli.command.as_ref())) {
        errln!("{msg}");
        return ExitCode::FAILURE;
    }
    let result = match cli.command {
        None => demo(&registry, Path::new(pyrograph::demo::DEMO_OUT)),
        Some(Command::Demo { out }) => demo(&registry, &out),
        Some(Command::Render { graph, opts, cache_mb, compact_cache }) => {
            pyrograph_frontend::core::FrameCache::global().set_budget(cache_mb << 20);
            pyrograph_frontend::core::FrameCache::global().set_compact(compact_cache);
            render(&registry, &graph, &opts)
        }
        Some(Command::Job { action: Some(JobAction::Collect { job_dir, json }), .. }) => collect(&job_dir, json),
        Some(Command::Job {
            action: None,
            graph,
            out,
            frames,
            chunk,
            set,
            no_chunking,
            wedge,
            wedge_zip,
            job_dir,
            overwrite,
        }) => match (graph, out, frames, job_dir) {
            (Some(graph), Some(out), Some(frames), Some(job_dir)) => {
                let mut limits = cli.limits.args();
                match cli.plugins.args() {
                    Ok(plugins) => limits.extend(plugins),
                    Err(Failure(msg)) => {
                        errln!("{msg}");
                        return ExitCode::FAILURE;
                    }
                }
                let spec =
                    JobArgs { graph, out, frames, chunk, sets: set, wedge, wedge_zip, task_chunking: !no_chunking, limits };
                job(&registry, &spec, &job_dir, overwrite)
            }
            _ => Err(Failure("error: job needs GRAPH, --out, --frames and -o JOB_DIR".into())),
        },
        Some(Command::Simulate(args)) => cli_sim::simulate(&registry, &args),
        Some(Command::Check { graph, out, allow_outside_out, json }) => {
            check(&registry, &graph, &BuildOptions { output_dir: out, allow_outside_out, ..BuildOptions::default() }, json)
        }
        Some(Command::Save { graph, output, set, overwrite }) => save(&graph, &output, &set, overwrite),
        Some(Command::Nodes { markdown, json }) => cli_plugins::nodes(&registry, markdown, json),
        Some(Command::Info { graph, json }) => info(&registry, &graph, json),
        Some(Command::Presets { dir, graph, tag, search, json, thumbnails, out, overwrite }) => {
            let thumbnails = thumbnails.then_some(out);
            presets(&registry, &PresetQuery { dir, graph, tags: tag, search, thumbnails, overwrite }, json)
        }
        Some(Command::Preset { name, graph, input, opts }) => render_preset(&registry, &name, graph.as_deref(), &input, &opts),
        Some(Command::Bench { iters, json }) => {
            bench(&registry, iters, json);
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure(msg)) => {
            if !msg.is_empty() {
                errln!("{msg}");
            }
            ExitCode::FAILURE
        }
    }
}

/// A wedge: its axes and the variant a farm task takes (`render` and `simulate`).
#[derive(clap::Args)]
struct WedgeArgs {
    /// Once per value: node.param=v1,v2,… (repeat: every combination). Writer paths may use
    /// {wedge} and {wedge.PARAM}; otherwise each variant writes into OUT/<variant>/.
    #[arg(long = "wedge", value_name = "NODE.PARAM=V1,V2,…")]
    wedge: Vec<String>,
    /// Parameters that vary together, as one wedge axis (equal value counts).
    #[arg(long = "wedge-zip", value_name = "NODE.PARAM=V1,V2,…")]
    wedge_zip: Vec<String>,
    /// Only this variant of the wedge (0-based; what a farm task does).
    #[arg(long, value_name = "K")]
    wedge_index: Option<usize>,
}

/// What `render` does beyond which graph: frames, outputs, overrides, wedges, reports.
#[derive(clap::Args)]
struct RenderOpts {
    /// Frames to write: 12, 0-99, 0-99:2 (or 0-99x2, every second), lists like 1,5,9-12.
    #[arg(long, value_parser = parse_frames)]
    frames: Option<FrameSet>,
    /// Leave frames whose files already exist (a re-run after a crash writes only what is
    /// missing; files are written atomically, so an existing file is a whole one).
    #[arg(long)]
    skip_existing: bool,
    /// Let writer paths leave --out (or the graph's folder): absolute paths and `..`.
    #[arg(long)]
    allow_outside_out: bool,
    /// Write a JSON manifest of the files written (size, SHA-256), the time and peak memory.
    #[arg(long, value_name = "FILE")]
    manifest: Option<PathBuf>,
    #[command(flatten)]
    wedges: WedgeArgs,
    /// Also write OUT/wedges.png: a labelled contact sheet, one cell per variant.
    #[arg(long)]
    sheet: bool,
    /// Folder that relative output paths resolve against (default: the graph file's folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a parameter: node.param=value (value in RON: 0.5, "text", (1, 0, 0)).
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    set: Vec<String>,
    /// Cook only these nodes (and what they need).
    #[arg(long = "node", value_name = "ID")]
    nodes: Vec<String>,
    /// Replace existing output files.
    #[arg(long)]
    overwrite: bool,
    /// Folder for scratch files of out-of-core work (Eigenfires training on databases larger
    /// than its memory_mb); the system's temp folder (TMPDIR) when not given.
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Read each volume simulation's frames from this cache folder instead of stepping it
    /// (written by `pyrograph simulate`; a farm job's Render step).
    #[arg(long, value_name = "DIR")]
    sim_cache: Option<PathBuf>,
    /// Print a JSON report instead of text.
    #[arg(long)]
    json: bool,
}

impl RenderOpts {
    /// The settings writers obey.
    fn settings(&self) -> CookSettings {
        CookSettings {
            frames: self.frames.clone(),
            skip_existing: self.skip_existing,
            overwrite: self.overwrite,
            cache_dir: self.cache_dir.clone(),
            sim_cache: self.sim_cache.clone(),
        }
    }
}

fn apply_sets(doc: &mut GraphDoc, sets: &[String]) -> Result<(), Failure> {
    for s in sets {
        let (lhs, value) = s.split_once('=').ok_or_else(|| Failure(format!("error: --set {s}: expected node.param=value")))?;
        let (node, param) = pyrograph_frontend::core::document::split_endpoint(lhs)
            .ok_or_else(|| Failure(format!("error: --set {s}: expected node.param=value")))?;
        doc.set_param(node, param, ParamValue::parse_cli(value)).map_err(|e| Failure(format!("error: --set {s}: {e}")))?;
    }
    Ok(())
}

fn load(registry: &Registry, path: &Path, sets: &[String], options: &BuildOptions) -> Result<(GraphDoc, Graph), Failure> {
    let mut doc = GraphDoc::load(path)?;
    apply_sets(&mut doc, sets)?;
    let graph = Graph::build_file(&doc, path, registry, options)?;
    Ok((doc, graph))
}

/// Progress bars per node, drawn on stderr (hidden when it is not a terminal).
fn progress_bars(enabled: bool) -> Option<pyrograph_frontend::core::ProgressFn> {
    if !enabled {
        return None;
    }
    let multi = MultiProgress::new();
    let bars: Mutex<HashMap<Arc<str>, ProgressBar>> = Mutex::new(HashMap::new());
    let style = ProgressStyle::with_template("{prefix:>16} [{bar:32}] {pos}/{len} frames {per_sec} eta {eta} {msg}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    Some(Arc::new(move |p: &Progress| {
        let Progress::Frame { node, done, total } = p else { return };
        let Ok(mut bars) = bars.lock() else { return };
        let bar = bars.entry(node.clone()).or_insert_with(|| {
            let b = multi.add(ProgressBar::new(*total as u64));
            b.set_style(style.clone());
            b.set_prefix(pyrograph_frontend::core::text::printable(node).into_owned());
            b
        });
        bar.set_position((*done as u64).max(bar.position()));
        if let Some(rss) = memory_kib("VmRSS") {
            bar.set_message(format!("{} MiB", rss >> 10));
        }
        if done == total {
            bar.finish();
        }
    }))
}

fn render(registry: &Registry, path: &Path, o: &RenderOpts) -> Result<(), Failure> {
    let wedges =
        pyrograph::wedge::Wedges::parse(&o.wedges.wedge, &o.wedges.wedge_zip).map_err(|e| Failure(format!("error: {e}")))?;
    if !wedges.is_empty() {
        return cli_farm::render_wedges(registry, path, o, &wedges);
    }
    if o.wedges.wedge_index.is_some() || o.sheet {
        return Err(Failure("error: --wedge-index and --sheet need --wedge or --wedge-zip".into()));
    }
    let options = BuildOptions { output_dir: o.out.clone(), allow_outside_out: o.allow_outside_out, ..BuildOptions::default() };
    let (doc, graph) = load(registry, path, &o.set, &options)?;
    let mut targets: Vec<String> = if o.nodes.is_empty() {
        let sinks = graph.sinks();
        if sinks.is_empty() { graph.leaves() } else { sinks }.iter().map(|s| s.to_string()).collect()
    } else {
        o.nodes.clone()
    };
    // A bypassed writer writes nothing: say so rather than list the file it would have written.
    targets.retain(|t| {
        let bypassed = doc.node(t).is_some_and(|n| n.bypass) && graph.desc(t).is_some_and(|d| d.time == TimeDep::Sink);
        if bypassed {
            outln!("{t}: bypassed, writes nothing");
        }
        !bypassed
    });
    cook_graph(&graph, path, o, &targets)
}

/// Cooks `targets` of `graph` (built from `path`) with the settings of `o`: progress, the
/// manifest and the report.
fn cook_graph(graph: &Graph, path: &Path, o: &RenderOpts, targets: &[String]) -> Result<(), Failure> {
    let target_refs: Vec<&str> = targets.iter().map(String::as_str).collect();
    if let Some(dir) = &o.cache_dir
        && !dir.is_dir()
    {
        return Err(Failure(format!("error: --cache-dir {}: not a folder", dir.display())));
    }
    if let Some(dir) = &o.sim_cache
        && !dir.is_dir()
    {
        return Err(Failure(format!(
            "error: --sim-cache {}: not a folder; write the cache first with `pyrograph simulate {} --sim-cache {0}`",
            dir.display(),
            path.display()
        )));
    }
    if let Some(file) = &o.manifest {
        cli_farm::check_manifest_target(file, o.out.as_deref().unwrap_or(&graph.dir), o)?;
    }
    let mut ctx = CookCtx::new().with_settings(o.settings());
    if let Some(p) = progress_bars(!o.json) {
        ctx = ctx.with_progress(p);
    }
    let started = std::time::Instant::now();
    let result = Evaluator::new().cook(graph, &target_refs, &ctx).map_err(|e| Failure(format!("error: {e}")))?;
    if let Some(file) = &o.manifest {
        let out = o.out.clone().unwrap_or_else(|| graph.dir.clone());
        let ok = result.root_errors().is_empty();
        write_manifest(file, path, &out, o, None, ok, &ctx.written(), started.elapsed())?;
    }
    report(graph, path, targets, &result, &ctx.warnings(), started.elapsed(), o.json)
}

/// What a render cooked, its warnings and errors, each naming the graph file and node.
fn report(
    graph: &Graph,
    path: &Path,
    targets: &[String],
    result: &CookResult,
    warnings: &[Warning],
    elapsed: std::time::Duration,
    json: bool,
) -> Result<(), Failure> {
    let errors = result.root_errors();
    let warning_node = |w: &Warning| w.node.as_deref().unwrap_or("").to_string();
    if json {
        let nodes: serde_json::Map<String, serde_json::Value> = targets
            .iter()
            .map(|t| {
                let v = match result.node(t) {
                    Some(Ok(values)) => json!({"ok": true, "outputs": output_map(graph, t, values)}),
                    Some(Err(e)) => json!({"ok": false, "error": e.to_string()}),
                    None => json!({"ok": false, "error": "not cooked"}),
                };
                (t.clone(), v)
            })
            .collect();
        let errs: Vec<_> = errors.iter().map(|(n, e)| json!({"node": n, "error": e.to_string()})).collect();
        let cache = pyrograph_frontend::core::FrameCache::global().stats();
        println!(
            "{}",
            printable_json(json!({
                "ok": errors.is_empty(),
                "graph": path.display().to_string(),
                "seconds": elapsed.as_secs_f64(),
                "peak_rss_mib": memory_kib("VmHWM").map(|k| k >> 10),
                "frame_cache": cache,
                "targets": nodes,
                "errors": errs,
                "warnings": warnings.iter().map(|w| json!({"node": warning_node(w), "message": w.message})).collect::<Vec<_>>(),
            }))
        );
    } else {
        for t in targets {
            if let Some(Ok(values)) = result.node(t) {
                outln!("{t}: {}", describe_outputs(graph, t, values));
            }
        }
        let file = path.display();
        for w in warnings {
            errln!("warning: {file}: node '{}': {}", warning_node(w), w.message);
        }
        for (node, e) in &errors {
            errln!("error: {file}: {}", explain(node, e));
        }
        if errors.is_empty() {
            let peak = memory_kib("VmHWM").map(|k| format!(", peak memory {} MiB", k >> 10)).unwrap_or_default();
            outln!("cooked in {:.2} s{peak}", elapsed.as_secs_f64());
        }
    }
    if errors.is_empty() { Ok(()) } else { Err(Failure(String::new())) }
}

/// A memory figure of this process from /proc/self/status (`VmRSS` now, `VmHWM` its peak), in
/// KiB; `None` where there is no procfs.
fn memory_kib(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status.lines().find_map(|l| l.strip_prefix(field)?.strip_prefix(':')?.trim().strip_suffix("kB")?.trim().parse().ok())
}

fn explain(node: &str, e: &NodeError) -> String {
    pyrograph_frontend::check::explain(node, e)
}

fn output_map(graph: &Graph, id: &str, values: &[pyrograph_frontend::core::Value]) -> serde_json::Value {
    let Some(desc) = graph.desc(id) else { return json!({}) };
    desc.outputs.iter().zip(values).map(|(p, v)| (p.name.clone(), json!(v.summary()))).collect::<serde_json::Map<_, _>>().into()
}

fn describe_outputs(graph: &Graph, id: &str, values: &[pyrograph_frontend::core::Value]) -> String {
    let Some(desc) = graph.desc(id) else { return String::new() };
    desc.outputs.iter().zip(values).map(|(p, v)| format!("{} = {}", p.name, v.summary())).collect::<Vec<_>>().join(", ")
}

fn demo(registry: &Registry, out: &Path) -> Result<(), Failure> {
    let doc = GraphDoc::from_ron(pyrograph::demo::DEMO_RON)?;
    let options = BuildOptions { output_dir: Some(out.to_path_buf()), ..BuildOptions::default() };
    let graph = Graph::build(&doc, registry, Path::new("."), &options)?;
    let sinks: Vec<String> = graph.sinks().iter().map(|s| s.to_string()).collect();
    let targets: Vec<&str> = sinks.iter().map(String::as_str).collect();
    let mut ctx = CookCtx::new();
    if let Some(p) = progress_bars(true) {
        ctx = ctx.with_progress(p);
    }
    let started = std::time::Instant::now();
    let result = Evaluator::new().cook(&graph, &targets, &ctx).map_err(|e| Failure(format!("error: {e}")))?;
    let errors = result.root_errors();
    if !errors.is_empty() {
        let msgs: Vec<String> = errors.iter().map(|(n, e)| format!("error: {}", explain(n, e))).collect();
        return Err(Failure(msgs.join("\n")));
    }
    let abs = std::fs::canonicalize(out).unwrap_or_else(|_| out.to_path_buf());
    for s in &sinks {
        let frames = result.output(&graph, s, "frames").map(|v| v.summary()).unwrap_or_default();
        let first = result.output(&graph, s, "first").map(|v| v.summary()).unwrap_or_default();
        outln!("demo: {s} wrote {frames} frames, first {first}");
    }
    outln!("demo frames are in {} (cooked in {:.2} s)", abs.display(), started.elapsed().as_secs_f64());
    Ok(())
}

fn problem_json(p: &pyrograph_frontend::check::Problem) -> serde_json::Value {
    json!({
        "file": p.file.as_ref().map(|f| f.display().to_string()),
        "location": p.location,
        "node": p.node,
        "port": p.port,
        "kind": p.kind,
        "message": p.message,
    })
}

fn check(registry: &Registry, path: &Path, options: &BuildOptions, json_out: bool) -> Result<(), Failure> {
    let built = Graph::load(path, registry, options).map(|(_, g)| g);
    let (problems, warnings) = pyrograph_frontend::check::problems_and_warnings(built.as_ref());
    if json_out {
        let list: Vec<_> = problems.iter().map(problem_json).collect();
        let warned: Vec<_> = warnings.iter().map(problem_json).collect();
        let counts = built.as_ref().ok().map(|g| json!({"nodes": g.node_count(), "edges": g.edge_count()}));
        println!(
            "{}",
            printable_json(
                json!({"ok": problems.is_empty(), "file": path.display().to_string(), "graph": counts, "problems": list, "warnings": warned})
            )
        );
        return if problems.is_empty() { Ok(()) } else { Err(Failure(String::new())) };
    }
    // Warnings do not fail a check: the graph cooks, its result may be wrong.
    for w in &warnings {
        errln!("warning: {w}");
    }
    if let (Ok(g), true) = (&built, problems.is_empty()) {
        outln!("ok: {}: {} nodes, {} edges", path.display(), g.node_count(), g.edge_count());
    } else {
        for p in &problems {
            errln!("error: {p}");
        }
        errln!("{}: {} problem(s)", path.display(), problems.len());
    }
    if problems.is_empty() { Ok(()) } else { Err(Failure(String::new())) }
}

/// `pyrograph save`: the document as the current writer writes it (what the editor and Python's
/// `Graph.save` write), after `--set`; migrates files of older versions.
fn save(path: &Path, output: &Path, sets: &[String], overwrite: bool) -> Result<(), Failure> {
    let mut doc = GraphDoc::load(path)?;
    apply_sets(&mut doc, sets)?;
    doc.save(output, overwrite).map_err(|e| Failure(format!("error: cannot write {}: {e}", output.display())))?;
    outln!("saved {}", output.display());
    Ok(())
}

fn info(registry: &Registry, path: &Path, json_out: bool) -> Result<(), Failure> {
    let (doc, graph) = Graph::load(path, registry, &BuildOptions::default())?;
    let rows: Vec<_> = graph
        .topo_order()
        .iter()
        .map(|i| {
            let n = graph.node(*i);
            let outs: Vec<String> =
                n.node.desc().outputs.iter().zip(&n.out_types).map(|(p, t)| format!("{}: {t}", p.name)).collect();
            (n.id.to_string(), n.node.desc().type_name.clone(), n.lifted, outs)
        })
        .collect();
    let animated = animated_params(&graph);
    if json_out {
        let nodes: Vec<_> = rows
            .iter()
            .map(|(id, ty, lifted, outs)| {
                let anim: serde_json::Map<String, serde_json::Value> =
                    animated.iter().filter(|(n, _, _)| n == id).map(|(_, p, v)| (p.clone(), json!(v))).collect();
                json!({"id": id, "type": ty, "lifted": lifted, "outputs": outs, "animated": anim})
            })
            .collect();
        println!(
            "{}",
            printable_json(json!({"file": path.display().to_string(), "description": doc.description, "nodes": nodes,
                   "edges": doc.edges, "interface": doc.interface.as_ref().map(|i| json!({"inputs": i.inputs, "outputs": i.outputs, "params": i.params})),
                   "sinks": graph.sinks().iter().map(|s| s.to_string()).collect::<Vec<_>>()}))
        );
        return Ok(());
    }
    outln!("{}: {} nodes, {} edges", path.display(), graph.node_count(), graph.edge_count());
    if let Some(d) = &doc.description {
        outln!("  {d}");
    }
    for (id, ty, lifted, outs) in rows {
        outln!("  {id:<16} {ty:<30} {}{}", outs.join(", "), if lifted { "  (per frame over a clip)" } else { "" });
    }
    for (a, b) in &doc.edges {
        outln!("  {a} -> {b}");
    }
    if !animated.is_empty() {
        outln!("  animated parameters:");
        for (node, port, value) in &animated {
            outln!("    {node}.{port} = {value}");
        }
    }
    Ok(())
}

/// Every parameter that changes over time, as `(node, port, value as written)`, in cook order.
fn animated_params(graph: &Graph) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
    for &i in graph.topo_order() {
        let n = graph.node(i);
        for (src, port) in n.inputs.iter().zip(&n.node.desc().inputs) {
            if let pyrograph_frontend::core::graph::InputSource::Const(pyrograph_frontend::core::Value::Anim(a)) = src {
                out.push((n.id.to_string(), port.name.clone(), a.summary()));
            }
        }
    }
    out
}

fn bench(registry: &Registry, iters: usize, json_out: bool) {
    use pyrograph::bench::{Shape, Workload, time};
    let mut rows = Vec::new();
    for shape in [Shape::Chain, Shape::Fan] {
        for workload in [Workload::Cold, Workload::Warm, Workload::Recook] {
            let (median, min, cooked) = time(registry, shape, 200, workload, iters);
            rows.push((format!("{shape:?}").to_lowercase(), format!("{workload:?}").to_lowercase(), median, min, cooked));
        }
    }
    if json_out {
        let list: Vec<_> = rows
            .iter()
            .map(|(s, w, med, min, c)| json!({"graph": s, "nodes": 200, "workload": w, "median_s": med.as_secs_f64(), "min_s": min.as_secs_f64(), "cooked_nodes": c, "iters": iters}))
            .collect();
        println!("{}", printable_json(serde_json::Value::Array(list)));
        return;
    }
    outln!("{:<8} {:<8} {:>12} {:>12} {:>8}", "graph", "workload", "median", "min", "cooked");
    for (s, w, med, min, c) in rows {
        outln!("{s:<8} {w:<8} {:>9.1} µs {:>9.1} µs {c:>8}", med.as_secs_f64() * 1e6, min.as_secs_f64() * 1e6);
    }
}
