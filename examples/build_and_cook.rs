//! Builds a small graph in Rust through the library API, cooks it, and saves it as RON.
//!
//! `cargo run --release --example build_and_cook` writes `build_and_cook/` (frames + graph).

use std::path::Path;

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new("build_and_cook");
    std::fs::create_dir_all(out)?;

    let mut doc = GraphDoc::new();
    doc.description = Some("Two procedural flames added together, written as PNG frames.".into());
    doc.add_node(
        "left",
        NodeDoc::new("imaging.turbulence_flame").param("seed", ParamValue::Int(1)).param("frames", ParamValue::Int(12)),
    );
    doc.add_node(
        "right",
        NodeDoc::new("imaging.turbulence_flame").param("seed", ParamValue::Int(2)).param("frames", ParamValue::Int(12)),
    );
    doc.add_node("add", NodeDoc::new("imaging.composite").param("mode", ParamValue::String("screen".into())));
    doc.add_node("gray", NodeDoc::new("imaging.to_gray"));
    doc.add_node(
        "write",
        NodeDoc::new("imaging.write_sequence")
            .param("pattern", ParamValue::String("frames/flame_####.png".into()))
            .param("overwrite", ParamValue::Bool(true)),
    );
    doc.connect("left.clip", "add.a")
        .connect("right.clip", "add.b")
        .connect("add.image", "gray.image")
        .connect("gray.image", "write.clip");

    let graph = Graph::build(&doc, &pyrograph_frontend::registry(), out, &BuildOptions::default())?;
    let result = Evaluator::new().cook(&graph, &["write"], &CookCtx::new())?;
    let frames = result.output(&graph, "write", "frames")?;
    println!("wrote {} frames to {}", frames.summary(), out.join("frames").display());

    let saved = out.join("build_and_cook.ron");
    doc.save(&saved, true)?;
    println!("saved the graph as {}", saved.display());
    Ok(())
}
