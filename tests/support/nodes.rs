//! Inputs for any node type, shared by `every_node.rs` (every node cooks) and `node_pictures.rs`
//! (every node's picture in the reference): files the loaders read, made by the nodes that write
//! them, and the smallest producers of every port type.
#![allow(dead_code)] // Each test file uses its own part.

use std::path::{Path, PathBuf};

use pyrograph_frontend::core::{
    BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDesc, NodeDoc, ParamValue, PortType, Registry,
};
use pyrograph_testing::workspace;

/// Frames of the shared test flame: the transition nodes' default motions reach frame 149.
const FLAME_FRAMES: i64 = 150;

pub fn int(v: i64) -> ParamValue {
    ParamValue::Int(v)
}

pub fn text(v: &str) -> ParamValue {
    ParamValue::String(v.to_string())
}

pub fn path(p: &Path) -> ParamValue {
    text(&p.to_string_lossy())
}

/// Adds a producer node `id` unless the graph has it; true when it was added (connect it then).
pub fn add(doc: &mut GraphDoc, id: &str, node: NodeDoc) -> bool {
    let new = doc.node(id).is_none();
    if new {
        doc.add_node(id, node);
    }
    new
}

/// Adds the nodes that make a value of type `ty` for a port of node type `consumer` (once each)
/// and returns their endpoint. Every producer is a registered node with the smallest parameters
/// that still give data its consumers accept: one RGBA flame frame read from a file for images,
/// masks and contours of it, the 150-frame flame clip (gray for the Eigenfires nodes), a database
/// trained on it.
pub fn supply(doc: &mut GraphDoc, ty: &PortType, consumer: &str, files: &Files) -> Option<String> {
    let still = |doc: &mut GraphDoc| {
        add(doc, "s_still", NodeDoc::new("imaging.load_image").param("path", path(&files.image)));
        "s_still.image".to_string()
    };
    let flame = NodeDoc::new("imaging.turbulence_flame")
        .param("width", int(files.flame.0))
        .param("height", int(files.flame.1))
        .param("frames", int(FLAME_FRAMES));
    let endpoint = match ty.to_string().as_str() {
        "Image" => still(doc),
        "Clip<Image>" => {
            add(doc, "s_flame", flame);
            if !consumer.starts_with("eigen.") {
                return Some("s_flame.clip".to_string());
            }
            if add(doc, "s_gray", NodeDoc::new("imaging.to_gray")) {
                doc.connect("s_flame.clip", "s_gray.image");
            }
            "s_gray.image".to_string()
        }
        "Mask" => {
            let image = still(doc);
            let mask = NodeDoc::new("imaging.hsv_mask")
                .param("layer1_enabled", ParamValue::Bool(false))
                .param("layer2_enabled", ParamValue::Bool(true))
                .param("layer3_enabled", ParamValue::Bool(true));
            if add(doc, "s_mask", mask) {
                doc.connect(&image, "s_mask.image");
            }
            "s_mask.mask".to_string()
        }
        "Clip<Mask>" => {
            add(doc, "s_flame", flame);
            let mask = NodeDoc::new("imaging.hsv_mask")
                .param("layer1_enabled", ParamValue::Bool(false))
                .param("layer2_enabled", ParamValue::Bool(true))
                .param("layer3_enabled", ParamValue::Bool(true));
            if add(doc, "s_clip_mask", mask) {
                doc.connect("s_flame.clip", "s_clip_mask.image");
            }
            "s_clip_mask.mask".to_string()
        }
        "Clip<Float>" => {
            // A per-frame lean: pose normalization over the flame clip.
            let masks = supply(doc, &PortType::clip_of(PortType::Mask), consumer, files)?;
            if add(doc, "s_clip_contours", NodeDoc::new("imaging.contours")) {
                doc.connect(&masks, "s_clip_contours.mask");
            }
            if add(doc, "s_pose", NodeDoc::new("imaging.pose_normalize")) {
                doc.connect("s_flame.clip", "s_pose.image");
                doc.connect("s_clip_contours.contours", "s_pose.contours");
            }
            "s_pose.angle".to_string()
        }
        "Contours" => {
            let mask = supply(doc, &PortType::Mask, consumer, files)?;
            if add(doc, "s_contours", NodeDoc::new("imaging.contours")) {
                doc.connect(&mask, "s_contours.mask");
            }
            "s_contours.contours".to_string()
        }
        "Basis" | "Weights" => {
            add(doc, "s_db", NodeDoc::new("eigen.load_database").param("path", path(&files.database)));
            format!("s_db.{}", if ty.to_string() == "Basis" { "basis" } else { "weights" })
        }
        "FrameList" => {
            add(doc, "s_db", NodeDoc::new("eigen.load_database").param("path", path(&files.database)));
            if add(doc, "s_motion", NodeDoc::new("eigen.motion_list").param("method", text("direct_bridging"))) {
                doc.connect("s_db.weights", "s_motion.weights");
            }
            "s_motion.frames".to_string()
        }
        "FlameModel" | "ParamSeries" | "ArModel" => {
            add(doc, "s_flame", flame);
            if add(doc, "s_fit", NodeDoc::new("flame_model.fit")) {
                doc.connect("s_flame.clip", "s_fit.clip");
            }
            match ty.to_string().as_str() {
                "FlameModel" => "s_fit.model".to_string(),
                "ParamSeries" => "s_fit.params".to_string(),
                _ => {
                    if add(doc, "s_learn", NodeDoc::new("flame_model.arp_learn")) {
                        doc.connect("s_fit.params", "s_learn.params");
                    }
                    "s_learn.model".to_string()
                }
            }
        }
        other => return supply_simulated(doc, other),
    };
    Some(endpoint)
}

/// [`supply`] for the types Perry's particles, the volume solver and the cloth make.
fn supply_simulated(doc: &mut GraphDoc, ty: &str) -> Option<String> {
    let endpoint = match ty {
        "Particles" => {
            add(doc, "s_roots", NodeDoc::new("particles.roots"));
            "s_roots.roots".to_string()
        }
        "Clip<Particles>" => {
            add(doc, "s_roots", NodeDoc::new("particles.roots"));
            if add(doc, "s_flames", NodeDoc::new("particles.particle_flame").param("frames", int(3))) {
                doc.connect("s_roots.roots", "s_flames.roots");
            }
            "s_flames.flames".to_string()
        }
        "Mesh" => {
            add(doc, "s_mesh", NodeDoc::new("particles.mesh_load"));
            "s_mesh.mesh".to_string()
        }
        "SpreadState" => {
            add(doc, "s_mesh", NodeDoc::new("particles.mesh_load"));
            if add(doc, "s_spread", NodeDoc::new("particles.fire_spread").param("frames", int(12))) {
                doc.connect("s_mesh.mesh", "s_spread.mesh");
            }
            "s_spread.spread".to_string()
        }
        "VolumeSource" => {
            add(doc, "s_vsource", NodeDoc::new("volume.source"));
            "s_vsource.source".to_string()
        }
        "Volume" | "Clip<Volume>" => {
            add(doc, "s_vsource", NodeDoc::new("volume.source"));
            let sim = NodeDoc::new("volume.simulate").param("frames", int(2)).param("voxel_size", ParamValue::Float(0.1));
            if add(doc, "s_sim", sim) {
                doc.connect("s_vsource.source", "s_sim.source");
            }
            "s_sim.volume".to_string()
        }
        "ClothState" | "Clip<ClothState>" => {
            add(doc, "s_cloth", NodeDoc::new("cloth.mass_spring_flame").param("frames", int(6)).param("count", int(2)));
            "s_cloth.cloth".to_string()
        }
        _ => return None,
    };
    Some(endpoint)
}

/// Parameters some nodes need beyond their defaults to have anything to do with the test data.
pub fn needs(name: &str) -> &'static [(&'static str, i64)] {
    match name {
        // rows × cols must equal the clip's frames.
        "imaging.flipbook" | "imaging.write_flipbook" => &[("rows", 10), ("cols", 15)],
        // Without a query, recognition needs a database frame to look up.
        "eigen.recognize" => &[("frame", 0)],
        // Both sizes default to 0 ("keep the aspect"), and one of them must be set.
        "imaging.resize" => &[("width", 24)],
        _ => &[],
    }
}

/// Refusals that depend on the data, not on the node's ports: End Growing (the default method of
/// eigen.motion_list) stops when no database frame brings the two ends closer, which a 150-frame
/// procedural flame allows for nine steps; the footage tests run it on real candles.
pub fn data_refusal(name: &str, error: &str) -> bool {
    matches!(name, "eigen.end_growing" | "eigen.motion_list") && error.contains("no pair of frames brings the two ends")
}

/// Files the loader nodes read, made by the nodes that write them.
pub struct Files {
    _dir: tempfile::TempDir,
    /// Width and height of the procedural flame every picture input is made from.
    pub flame: (i64, i64),
    pub image: PathBuf,
    pub sequence: PathBuf,
    pub database: PathBuf,
    pub include: PathBuf,
    pub vdb: PathBuf,
}

pub fn cook(registry: &Registry, doc: &GraphDoc, out: &Path, target: &str) -> Result<(), String> {
    let options = BuildOptions { output_dir: Some(out.to_path_buf()), ..BuildOptions::default() };
    let graph = Graph::build(doc, registry, out, &options).map_err(|d| format!("does not build: {d}"))?;
    let result = Evaluator::new().cook(&graph, &[target], &CookCtx::new()).map_err(|e| e.to_string())?;
    match result.node(target) {
        Some(Ok(_)) => Ok(()),
        Some(Err(e)) => Err(e.to_string()),
        None => Err("was not cooked".to_string()),
    }
}

/// The files, made from a `width` × `height` procedural flame.
pub fn make_files(registry: &Registry, (width, height): (i64, i64)) -> Files {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let mut doc = GraphDoc::new();
    doc.add_node(
        "flame",
        NodeDoc::new("imaging.turbulence_flame")
            .param("width", int(width))
            .param("height", int(height))
            .param("frames", int(FLAME_FRAMES)),
    );
    doc.add_node("gray", NodeDoc::new("imaging.to_gray"));
    doc.add_node("write", NodeDoc::new("imaging.write_sequence").param("pattern", path(&frames.join("f_####.png"))));
    doc.add_node("train", NodeDoc::new("eigen.eigenfires"));
    doc.add_node("save", NodeDoc::new("eigen.save_database").param("path", path(&dir.path().join("db"))));
    doc.connect("flame.clip", "gray.image").connect("flame.clip", "write.clip");
    doc.connect("gray.image", "train.clip1");
    doc.connect("train.basis", "save.basis").connect("train.weights", "save.weights");
    doc.add_node("smoke", NodeDoc::new("volume.source"));
    doc.add_node("sim", NodeDoc::new("volume.simulate").param("frames", int(2)).param("voxel_size", ParamValue::Float(0.1)));
    doc.add_node("cache", NodeDoc::new("volume.write_vdb").param("pattern", path(&dir.path().join("vdb/smoke_####.vdb"))));
    doc.connect("smoke.source", "sim.source").connect("sim.volume", "cache.volume");
    for target in ["write", "save", "cache"] {
        cook(registry, &doc, dir.path(), target).unwrap_or_else(|e| panic!("making the test files: {target}: {e}"));
    }
    let root = workspace();
    Files {
        image: frames.join("f_0000.png"),
        sequence: frames,
        database: dir.path().join("db"),
        include: root.join("graphs/candles.ron"),
        vdb: dir.path().join("vdb/smoke_####.vdb"),
        flame: (width, height),
        _dir: dir,
    }
}

/// A graph of the node type `desc` as node `n`, its required inputs fed by [`supply`] (paths from
/// `files`) and the parameters [`needs`] lists.
pub fn graph_for(desc: &NodeDesc, files: &Files) -> GraphDoc {
    let name = desc.type_name.as_str();
    let mut doc = GraphDoc::new();
    doc.add_node("n", NodeDoc::new(name));
    for port in desc.inputs.iter().filter(|p| p.is_required()) {
        let element = port.ty.clip_element().unwrap_or(&port.ty).clone();
        if element == PortType::Path {
            let file = match name {
                "imaging.load_image" => &files.image,
                "imaging.load_sequence" => &files.sequence,
                "eigen.load_database" => &files.database,
                "graph.include" => &files.include,
                "volume.load_vdb" => &files.vdb,
                _ => panic!("{name}.{}: no test file for this required path; add one to make_files", port.name),
            };
            doc.node_mut("n").unwrap().params.insert(port.name.clone(), path(file));
            continue;
        }
        let Some(from) = supply(&mut doc, &port.ty, name, files) else {
            panic!("{name}.{}: no producer of {} in supply(); add one", port.name, port.ty);
        };
        doc.connect(&from, &format!("n.{}", port.name));
    }
    for (param, value) in needs(name) {
        doc.node_mut("n").unwrap().params.insert(param.to_string(), int(*value));
    }
    doc
}
