//! Compares how rendered flames look with real footage (issue 28): per flame, the coefficient of
//! variation and lag-1/lag-2 autocorrelation of area, height, width and energy, and the banding
//! measure (see `pyrograph::look`).
//!
//! `cargo run --release --example look -- [FOOTAGE_FRAMES_DIR] [GRAPH NODE.PORT [node.param=value ...]]`
//!
//! Defaults: `../shared/footage/candle-black/frames` against `graphs/candles.ron render.image`
//! (without its lit table), at its own step count and at half of it, and drawn as discrete steps.
//! The learned candle beside them: `... FRAMES_DIR graphs/learning-flames-candle.ron render.color`
//! with `PYROGRAPH_FOOTAGE` set.

use std::path::{Path, PathBuf};

use pyrograph::look::{ClipLook, footage_look, graph_look};

/// Luminance above which a pixel is flame.
const THRESHOLD: f32 = 0.25;

fn print(name: &str, look: &ClipLook) {
    println!("{name:<34} {}", look.summary());
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let footage = args.first().map(PathBuf::from).unwrap_or_else(|| root.join("../shared/footage/candle-black/frames"));
    let graph = args.get(1).map(PathBuf::from).unwrap_or_else(|| root.join("graphs/candles.ron"));
    let endpoint = args.get(2).map(String::as_str).unwrap_or("render.image");
    // The default graph's flames alone, as in the footage: no lit table under them.
    let mut sets: Vec<&str> = if args.len() <= 1 { vec!["render.ground=false"] } else { Vec::new() };
    sets.extend(args.iter().skip(3).map(String::as_str));
    print(
        &format!("footage {}", footage.file_name().map(|f| f.to_string_lossy()).unwrap_or_default()),
        &footage_look(&footage, usize::MAX, THRESHOLD, 25)?,
    );
    print(&graph.display().to_string(), &graph_look(&graph, endpoint, &sets, THRESHOLD, 25)?);
    if args.len() <= 1 {
        let half: Vec<&str> = vec!["render.ground=false", "flames.steps=12"];
        print("  at half the steps (12)", &graph_look(&graph, endpoint, &half, THRESHOLD, 12)?);
        let mut steps = half.clone();
        steps.push("render.exposure=steps");
        print("  discrete steps (12)", &graph_look(&graph, endpoint, &steps, THRESHOLD, 12)?);
        print(
            "  discrete steps (25)",
            &graph_look(&graph, endpoint, &["render.ground=false", "render.exposure=steps"], THRESHOLD, 25)?,
        );
    }
    Ok(())
}
