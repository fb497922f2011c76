//! `pyrograph simulate`: steps every volume simulation of a graph once and caches its frames as
//! VDB files, which `render --sim-cache` then reads instead of stepping. A farm job whose graph
//! simulates runs this as its Simulate step, before the chunks of its Render step.

use std::path::{Path, PathBuf};

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, FrameSet, Graph, Registry, Value};
use pyrograph_frontend::volume::grid::Volume;
use pyrograph_frontend::volume::vdb::sim_cache::{cache_file, cache_name, write_cache_frame};

use crate::Failure;
use crate::cli_farm::build_variant;
use pyrograph::job::{SIMULATION_TYPE, simulations};
use pyrograph::outln;

/// What `simulate` steps and where it caches it.
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// The graph file (RON).
    graph: PathBuf,
    /// Folder of the cache: frame i of simulation SIM goes to DIR/SIM/SIM.<i:04>.vdb.
    #[arg(long, value_name = "DIR")]
    sim_cache: PathBuf,
    /// The render's output folder (writer paths are checked against it, as `render --out`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The frames the render will need: each simulation steps to the last of them (default:
    /// its whole clip).
    #[arg(long, value_parser = crate::parse_frames)]
    frames: Option<FrameSet>,
    /// Override a parameter: node.param=value.
    #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
    set: Vec<String>,
    // The wedge, as `render --wedge`: --wedge-index picks the variant to simulate.
    #[command(flatten)]
    wedges: crate::WedgeArgs,
    /// Leave a simulation alone whose every frame is already cached (a re-queued task).
    #[arg(long)]
    skip_existing: bool,
    /// Replace cached frames that exist (a simulation re-steps from its first frame).
    #[arg(long)]
    overwrite: bool,
}

impl SimulateArgs {
    /// The graph file.
    pub fn graph(&self) -> &std::path::Path {
        &self.graph
    }
}

fn build(registry: &Registry, a: &SimulateArgs) -> Result<Graph, Failure> {
    let wedges =
        pyrograph::wedge::Wedges::parse(&a.wedges.wedge, &a.wedges.wedge_zip).map_err(|e| Failure(format!("error: {e}")))?;
    let out = a.out.clone().unwrap_or_else(|| a.graph.parent().map(Path::to_path_buf).unwrap_or_default());
    if wedges.is_empty() {
        if a.wedges.wedge_index.is_some() {
            return Err(Failure("error: --wedge-index needs --wedge or --wedge-zip".into()));
        }
        let options = BuildOptions { output_dir: Some(out), ..BuildOptions::default() };
        return Ok(crate::load(registry, &a.graph, &a.set, &options)?.1);
    }
    let all = wedges.variants();
    let Some(v) = a.wedges.wedge_index.and_then(|k| all.get(k)) else {
        return Err(Failure(format!(
            "error: a wedge has one cache per variant: pick one with --wedge-index 0-{} (and a --sim-cache of its own)",
            all.len() - 1
        )));
    };
    Ok(build_variant(registry, &a.graph, &a.set, &out, false, v)?.0)
}

/// Steps each simulation of the graph to the last frame needed and writes every frame.
pub fn simulate(registry: &Registry, a: &SimulateArgs) -> Result<(), Failure> {
    let graph = build(registry, a)?;
    let sims = simulations(&graph);
    if sims.is_empty() {
        outln!("{}: no {SIMULATION_TYPE} node, nothing to cache", a.graph.display());
        return Ok(());
    }
    let mut names: Vec<String> = sims.iter().map(|s| cache_name(s)).collect();
    names.dedup();
    if names.len() != sims.len() {
        return Err(Failure(format!(
            "error: two simulations share a cache folder name ({}): give them ids that differ in letters or digits",
            sims.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", ")
        )));
    }
    let ctx = CookCtx::new();
    for id in &sims {
        ctx.check_cancel().map_err(|e| Failure(format!("error: {e}")))?;
        let started = std::time::Instant::now();
        let value = Evaluator::new()
            .output(&graph, &format!("{id}.volume"), &ctx)
            .map_err(|e| Failure(format!("error: {}: {}", a.graph.display(), crate::explain(id, &e))))?;
        let Value::Clip(clip) = value else {
            return Err(Failure(format!("error: simulation '{id}' made no clip")));
        };
        let last = a.frames.as_ref().map_or(clip.len(), |f| (f.last() + 1).min(clip.len()));
        let files: Vec<PathBuf> = (0..last).map(|i| cache_file(&a.sim_cache, id, i)).collect();
        if a.skip_existing && files.iter().all(|f| f.is_file()) {
            outln!("{id}: {last} frames already cached in {}", a.sim_cache.join(cache_name(id)).display());
            continue;
        }
        if !a.overwrite
            && let Some(f) = files.iter().find(|f| f.exists())
        {
            return Err(Failure(format!(
                "error: {} exists; nothing was simulated (--overwrite re-simulates and replaces the cache)",
                f.display()
            )));
        }
        let node_ctx = ctx.for_node(id);
        let mut stats = Stats::default();
        // Frames are written on a second thread while the next ones are stepped (encoding and
        // writing a frame of half a million voxels takes about as long as a sub-step), in
        // order, at most three frames behind (two queued, one being written), so memory stays bounded and an interrupted run
        // leaves every frame before the one it stopped at complete.
        std::thread::scope(|scope| -> Result<(), Failure> {
            let (to_writer, frames) = std::sync::mpsc::sync_channel::<(usize, std::sync::Arc<Volume>)>(2);
            let writer = scope.spawn(move || -> Result<(), Failure> {
                for (i, volume) in frames {
                    write_cache_frame(&a.sim_cache, id, i, &volume)
                        .map_err(|e| Failure(format!("error: simulation '{id}': {e}")))?;
                }
                Ok(())
            });
            let stepped = (0..last).try_for_each(|i| {
                let frame = clip
                    .get(i, &node_ctx)
                    .map_err(|e| Failure(format!("error: {}: {}", a.graph.display(), crate::explain(id, &e))))?;
                let volume = frame
                    .downcast::<Volume>()
                    .ok_or_else(|| Failure(format!("error: simulation '{id}' frame {i}: not a volume")))?;
                stats.add(&volume);
                // A closed channel means the writer stopped on an error: stop stepping; the
                // writer's error is the one reported.
                to_writer.send((i, volume)).map_err(|_| Failure(format!("error: simulation '{id}': the cache writer stopped")))
            });
            drop(to_writer);
            let written =
                writer.join().unwrap_or_else(|_| Err(Failure(format!("error: simulation '{id}': the cache writer failed"))));
            written.and(stepped)
        })?;
        let dir = a.sim_cache.join(cache_name(id));
        let secs = started.elapsed().as_secs_f64();
        outln!(
            "{id}: {last} frames cached in {} ({secs:.1} s; {} sub-steps, {:.1} a second; up to {} active voxels; smoke {} voxels tall)",
            dir.display(),
            stats.substeps,
            stats.substeps as f64 / secs,
            stats.voxels,
            stats.height
        );
    }
    Ok(())
}

/// What a simulation did over its frames, for the line `simulate` prints.
#[derive(Default)]
struct Stats {
    substeps: u64,
    voxels: usize,
    /// The tallest extent of smoke (density over 1 %), in voxels.
    height: i32,
}

impl Stats {
    fn add(&mut self, v: &Volume) {
        self.substeps += u64::from(v.stats.substeps);
        self.voxels = self.voxels.max(v.topology.voxels());
        if let Some((lo, hi)) = v.field_bounds("density", 0.01) {
            self.height = self.height.max(hi.y - lo.y + 1);
        }
    }
}
