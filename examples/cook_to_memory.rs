//! Cooks frames of a clip output into memory through the Rust API and prints the time: the
//! Rust side of the Python-binding benchmark (benches/python/run.sh), doing what
//! `Graph.cook(endpoint, frames=range(n))` does in Python, minus the conversion to numpy.
//!
//! `cargo run --release --example cook_to_memory -- GRAPH NODE.PORT FRAMES`

use std::path::PathBuf;

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, Value};
use rayon::prelude::*;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [graph, endpoint, frames] = args.as_slice() else {
        return Err("usage: cook_to_memory GRAPH NODE.PORT FRAMES".into());
    };
    let frames: usize = frames.parse().map_err(|e| format!("FRAMES: {e}"))?;
    let registry = pyrograph_frontend::registry();
    let started = std::time::Instant::now();
    let (_, graph) = Graph::load(&PathBuf::from(graph), &registry, &BuildOptions::default()).map_err(|d| d.to_string())?;
    let ctx = CookCtx::new();
    let value = Evaluator::new().output(&graph, endpoint, &ctx).map_err(|e| e.to_string())?;
    let Value::Clip(clip) = value else { return Err(format!("{endpoint} is not a clip")) };
    // In parallel and in order, as the Python binding pulls frames.
    let cooked: Vec<Value> =
        (0..frames).into_par_iter().map(|i| clip.get(i, &ctx)).collect::<Result<_, _>>().map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    let checksum: f64 = cooked
        .iter()
        .map(|v| match v {
            Value::Image(img) => img.data().iter().map(|&x| f64::from(x)).sum::<f64>(),
            _ => 0.0,
        })
        .sum();
    println!("{{\"seconds\": {seconds}, \"frames\": {}, \"checksum\": {checksum}}}", cooked.len());
    Ok(())
}
