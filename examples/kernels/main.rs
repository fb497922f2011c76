//! The pyrograph side of the peer harness (`benches/peers/run.py`): each subcommand reads its
//! input from `.npy` files the harness made (the peer reads the same files), runs one kernel
//! `--warmup` times untimed and `--reps` times timed, writes its output for the harness to compare
//! with the peer's, and prints one JSON line `{"op", "times_s", "median_s", "threads", …}`.
//! Threads: rayon's pool, set by `RAYON_NUM_THREADS`.
//!
//!     cargo run --release --example kernels -- bloom --input frame.npy --output out.npy

mod eigen;
mod flames;
mod npy;
mod render;
mod smoke;
mod solo;

use std::time::Instant;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(about = "pyrograph kernels for the peer harness (benches/peers/run.py)")]
struct Cli {
    /// Untimed runs before the timed ones.
    #[arg(long, default_value_t = 1, global = true)]
    warmup: usize,
    /// Timed runs.
    #[arg(long, default_value_t = 5, global = true)]
    reps: usize,
    #[command(subcommand)]
    op: Op,
}

#[derive(Subcommand)]
enum Op {
    /// imaging.bloom (thesis §6.2) with its defaults (σ 32/16/8/4, strength 0.4) on an H×W×3 f32 frame.
    Bloom(flames::BloomArgs),
    /// End Growing (thesis §5.1.2.2, Algorithm 1) on an M×E f32 weight matrix.
    Endgrow(eigen::EndGrowArgs),
    /// Batch reconstruction (eq. 22): B×E weights through an E×P basis and a P mean.
    Reconstruct(eigen::ReconstructArgs),
    /// Eigenfires training (§4.2, PCA + weights of every frame) on M×H×W f32 frames.
    Train(eigen::TrainArgs),
    /// Mass-spring cloth flames, structural springs, constant wind: sub-steps of every flame.
    Cloth(flames::ClothArgs),
    /// Learning flames §4: fit + EM learning on footage frames (untimed), then ARP sampling.
    Arp(flames::ArpArgs),
    /// `volume.simulate`'s sub-step on a dense N³ box of warm smoke (the Warp peer's step).
    Smoke(smoke::SmokeArgs),
    /// `volume.render`'s march on a dense N³ box of smoke lit by the sun (the Warp peer's march).
    Render(render::RenderArgs),
    /// No peer: 1,000 particle flames, simulate + render 1280×720, per frame.
    Particles(solo::FramesArgs),
    /// No peer: 144 cloth flames (node defaults), a frame's sub-steps + render 1280×720, per frame.
    ClothFrame(solo::FramesArgs),
    /// No peer: the burning cube (graphs/burning-cube.ron), mean frame over frames 48–95.
    Cube(solo::CubeArgs),
    /// No peer: fire spread over a plane of a given number of faces, per step (scaling sweep).
    Spread(solo::SpreadArgs),
    /// Which library does the Eigenfires products: the system's OpenBLAS (its configuration) or faer.
    Products,
}

fn main() {
    let cli = Cli::parse();
    let t = Timing { warmup: cli.warmup, reps: cli.reps.max(1) };
    let result = match cli.op {
        Op::Bloom(a) => flames::bloom(&a, t),
        Op::Endgrow(a) => eigen::end_grow(&a, t),
        Op::Reconstruct(a) => eigen::reconstruct(&a, t),
        Op::Train(a) => eigen::train(&a, t),
        Op::Cloth(a) => flames::cloth(&a, t),
        Op::Arp(a) => flames::arp(&a, t),
        Op::Smoke(a) => smoke::smoke(&a, t),
        Op::Render(a) => render::render_box(&a, t),
        Op::Particles(a) => solo::particles(&a, t),
        Op::ClothFrame(a) => solo::cloth_frame(&a, t),
        Op::Cube(a) => solo::cube(&a, t),
        Op::Spread(a) => solo::spread(&a, t),
        Op::Products => Ok(eigen::products()),
    };
    match result {
        Ok(line) => println!("{line}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// How often to run a kernel.
#[derive(Clone, Copy)]
pub struct Timing {
    warmup: usize,
    reps: usize,
}

impl Timing {
    /// Runs `f` `warmup` times, then `reps` times timed; the seconds of each timed run.
    pub fn run<T>(self, mut f: impl FnMut() -> Result<T, String>) -> Result<(Vec<f64>, T), String> {
        for _ in 0..self.warmup {
            f()?;
        }
        let mut times = Vec::with_capacity(self.reps);
        let mut last = None;
        for _ in 0..self.reps {
            let start = Instant::now();
            let out = f()?;
            times.push(start.elapsed().as_secs_f64());
            last = Some(out);
        }
        last.map(|o| (times, o)).ok_or_else(|| "no timed run".to_string())
    }

    /// [`Timing::run`] with a fresh input from `setup` for every run, untimed (for kernels that
    /// consume their input).
    pub fn run_with<I, T>(
        self,
        mut setup: impl FnMut() -> I,
        mut f: impl FnMut(I) -> Result<T, String>,
    ) -> Result<(Vec<f64>, T), String> {
        for _ in 0..self.warmup {
            f(setup())?;
        }
        let mut times = Vec::with_capacity(self.reps);
        let mut last = None;
        for _ in 0..self.reps {
            let input = setup();
            let start = Instant::now();
            let out = f(input)?;
            times.push(start.elapsed().as_secs_f64());
            last = Some(out);
        }
        last.map(|o| (times, o)).ok_or_else(|| "no timed run".to_string())
    }
}

/// The JSON line of one op: its times, their median and the thread count, plus `extra` fields.
pub fn report(op: &str, times: &[f64], extra: serde_json::Value) -> String {
    let mut sorted = times.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = if sorted.is_empty() {
        f64::NAN
    } else if sorted.len() % 2 == 1 {
        sorted[sorted.len() / 2]
    } else {
        0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
    };
    let mut v = serde_json::json!({
        "op": op,
        "tool": "pyrograph",
        "times_s": times,
        "median_s": median,
        "threads": rayon::current_num_threads(),
    });
    if let (Some(map), serde_json::Value::Object(more)) = (v.as_object_mut(), extra) {
        map.extend(more);
    }
    v.to_string()
}
