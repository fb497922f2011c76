//! A picture for every node type in the node reference (issue 64): each node cooked on the
//! standard inputs (a procedural flame, masks, contours and an Eigenfires database made from it,
//! Perry's roots and wind, a sphere of smoke) and its output shown the way an artist would look at
//! it: images and clips as they are, masks as gray, contours over the frame, particles, meshes,
//! spreads, cloths and volumes through their renderers, Eigenfires data through its plots, numbers
//! as a labelled card, writers as what they write. The pictures live in `docs/images/nodes/`;
//! `REGENERATE=1` renews them, and otherwise a node without one, or whose picture no longer
//! matches what it cooks, fails.

#[path = "support/nodes.rs"]
mod nodes;

use std::path::{Path, PathBuf};

use nodes::{Files, add, graph_for, int, make_files, supply};
use pyrograph_frontend::core::value::{Channels, Image};
use pyrograph_frontend::core::{
    BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDesc, NodeDoc, ParamValue, PortType, Value,
};
use pyrograph_frontend::preset_cook::{THUMB_BACKGROUND, fit, picture_output};
use pyrograph_testing::workspace;

/// A node's picture: the thumbnail size of the preset catalogue, halved.
const SIZE: (u32, u32) = (192, 108);
/// The standard flame's size: a tall frame, as flames are.
const FLAME: (i64, i64) = (72, 96);

fn pictures_dir() -> PathBuf {
    workspace().join("docs/images/nodes")
}

/// Where a node type's picture lives, relative to `docs/` (what the node reference links).
pub fn picture_file(type_name: &str) -> PathBuf {
    pictures_dir().join(format!("{type_name}.png"))
}

/// What to show of a node: an endpoint whose value is an image, a clip of images or a clip of
/// numbers, or a card of labels.
enum Shown {
    Endpoint(String),
    Card(Vec<String>),
}

/// Connects `from` into a new node `id` of `type_name` at `port`, with parameters; returns `id`.
fn view(doc: &mut GraphDoc, id: &str, node: NodeDoc, wires: &[(&str, &str)]) -> String {
    add(doc, id, node);
    for (from, port) in wires {
        doc.connect(from, &format!("{id}.{port}"));
    }
    id.to_string()
}

/// Nodes that turn a value of type `ty` at `from` into a picture; `None` for numbers and text.
fn viewer(doc: &mut GraphDoc, ty: &PortType, from: &str, files: &Files, name: &str) -> Option<String> {
    let element = ty.clip_element().unwrap_or(ty).to_string();
    let mut need = |t: PortType| supply(doc, &t, name, files).unwrap_or_else(|| panic!("supply() makes no {t}"));
    let endpoint = match element.as_str() {
        "Image" => return Some(from.to_string()),
        "Mask" => view(doc, "v_mask", NodeDoc::new("imaging.mask_to_image"), &[(from, "mask")]) + ".image",
        "Contours" => {
            let frame = need(PortType::Image);
            view(doc, "v_contours", NodeDoc::new("imaging.contour_overlay"), &[(&frame, "image"), (from, "contours")]) + ".image"
        }
        "Particles" => {
            let render = |doc: &mut GraphDoc, wires: &[(&str, &str)]| view(doc, "v_render", render_flames(), wires) + ".image";
            match name {
                // Roots: flames grown from them.
                "particles.roots" => {
                    let flames = NodeDoc::new("particles.particle_flame").param("frames", int(24));
                    let flames = view(doc, "v_flames", flames, &[(from, "roots")]);
                    render(doc, &[(&format!("{flames}.flames"), "flames")])
                }
                // Roots on a mesh: small flames on it lighting it, seen as particles.render_fire
                // frames a mesh.
                "particles.mesh_roots" => {
                    let mesh = need(port_type("Mesh"));
                    let flames =
                        NodeDoc::new("particles.particle_flame").param("frames", int(24)).param("size", ParamValue::Float(0.1));
                    let flames = view(doc, "v_flames", flames, &[(from, "roots")]) + ".flames";
                    let lights = view(
                        doc,
                        "v_lights",
                        NodeDoc::new("particles.flame_lights").param("intensity", ParamValue::Float(0.2)),
                        &[(&flames, "flames")],
                    );
                    // From above, so the top faces the roots stand on are in view.
                    let close = render_flames()
                        .param("camera_position", floats(&[1.8, 2.4, 2.2]))
                        .param("camera_target", floats(&[0.0, 0.5, 0.0]))
                        .param("ambient", ParamValue::Float(0.3));
                    let wires =
                        [(flames.as_str(), "flames"), (&format!("{lights}.lights") as &str, "lights"), (mesh.as_str(), "mesh")];
                    view(doc, "v_render", close, &wires) + ".image"
                }
                // Sparks and lights: drawn with the flames they belong to.
                "particles.embers" | "particles.flame_lights" => {
                    let flames = need(PortType::clip_of(port_type("Particles")));
                    let port = if name == "particles.embers" { "sparks" } else { "lights" };
                    render(doc, &[(&flames, "flames"), (from, port)])
                }
                // Char: on the burning mesh.
                "particles.char" => {
                    let (spread, mesh) = (need(port_type("SpreadState")), need(port_type("Mesh")));
                    let wires = [(spread.as_str(), "spread"), (mesh.as_str(), "mesh"), (from, "char")];
                    view(doc, "v_fire", NodeDoc::new("particles.render_fire"), &wires) + ".image"
                }
                _ => render(doc, &[(from, "flames")]),
            }
        }
        // A mesh: fire spreading over it, as particles.render_fire draws it.
        "Mesh" => {
            let spread = view(doc, "v_spread", NodeDoc::new("particles.fire_spread").param("frames", int(24)), &[(from, "mesh")]);
            let wires = [(format!("{spread}.spread"), "spread"), (from.to_string(), "mesh")];
            view(
                doc,
                "v_fire",
                NodeDoc::new("particles.render_fire"),
                &wires.iter().map(|(a, b)| (a.as_str(), *b)).collect::<Vec<_>>(),
            ) + ".image"
        }
        "SpreadState" => {
            let mesh = need(port_type("Mesh"));
            view(doc, "v_fire", NodeDoc::new("particles.render_fire"), &[(from, "spread"), (&mesh, "mesh")]) + ".image"
        }
        "WindField" => {
            let roots = need(port_type("Particles"));
            let flames = NodeDoc::new("particles.particle_flame").param("frames", int(24));
            let flames = view(doc, "v_flames", flames, &[(&roots, "roots"), (from, "wind")]);
            view(doc, "v_render", render_flames(), &[(&format!("{flames}.flames"), "flames")]) + ".image"
        }
        "VolumeSource" => {
            let sim = NodeDoc::new("volume.simulate").param("frames", int(12)).param("voxel_size", ParamValue::Float(0.06));
            let sim = view(doc, "v_sim", sim, &[(from, "source")]);
            view(doc, "v_volume", volume_render(), &[(&format!("{sim}.volume"), "volume")]) + ".image"
        }
        "Volume" => view(doc, "v_volume", volume_render(), &[(from, "volume")]) + ".image",
        "ClothState" => view(doc, "v_cloth", NodeDoc::new("cloth.cloth_render"), &[(from, "cloth")]) + ".image",
        "Basis" => view(doc, "v_grid", NodeDoc::new("eigen.eigenfire_grid"), &[(from, "basis")]) + ".image",
        // Hand-set weights: the flame they make (one row is a single point in the weight plot).
        "Weights" if name == "eigen.weights_edit" => {
            let basis = need(port_type("Basis"));
            view(doc, "v_flame", NodeDoc::new("eigen.reconstruct"), &[(&basis, "basis"), (from, "weights")]) + ".clip"
        }
        "Weights" => {
            let basis = need(port_type("Basis"));
            view(doc, "v_pca", NodeDoc::new("eigen.pca_plot"), &[(&basis, "basis"), (from, "weights")]) + ".image"
        }
        "FrameList" => {
            let (basis, weights) = (need(port_type("Basis")), need(port_type("Weights")));
            let wires = [(from, "frames"), (basis.as_str(), "basis"), (weights.as_str(), "weights")];
            view(doc, "v_frames", NodeDoc::new("eigen.frames_to_clip"), &wires) + ".clip"
        }
        "FlameModel" => {
            let params = need(port_type("ParamSeries"));
            view(doc, "v_model", NodeDoc::new("flame_model.render"), &[(from, "model"), (&params, "params")]) + ".color"
        }
        "ParamSeries" => view(doc, "v_plot", NodeDoc::new("flame_model.param_plot"), &[(from, "real")]) + ".image",
        "ArModel" => {
            let real = need(port_type("ParamSeries"));
            let sample =
                view(doc, "v_sample", NodeDoc::new("flame_model.arp_sample").param("frames", int(150)), &[(from, "model")]);
            let wires = [(real.as_str(), "real"), (&format!("{sample}.params") as &str, "synth")];
            view(doc, "v_plot", NodeDoc::new("flame_model.param_plot"), &wires) + ".image"
        }
        _ => return None,
    };
    Some(endpoint)
}

/// Perry's flames as the candles preset frames them, at the picture's size.
fn render_flames() -> NodeDoc {
    NodeDoc::new("particles.render_flames")
        .param("width", int(SIZE.0.into()))
        .param("height", int(SIZE.1.into()))
        .param("camera_position", floats(&[0.0, 2.5, 9.0]))
        .param("camera_target", floats(&[0.0, 1.5, 0.0]))
        .param("background", floats(&[0.01, 0.01, 0.015, 1.0]))
}

/// A vector or colour parameter.
fn floats(v: &[f64]) -> ParamValue {
    ParamValue::List(v.iter().map(|&f| ParamValue::Float(f)).collect())
}

/// The port type named `name` (a node crate's own type, such as `Basis`), as some node outputs it.
fn port_type(name: &str) -> PortType {
    let registry = pyrograph_frontend::registry();
    let found = registry
        .descs()
        .flat_map(|d| d.outputs.iter())
        .map(|p| p.ty.clip_element().unwrap_or(&p.ty).clone())
        .find(|t| t.to_string() == name);
    found.unwrap_or_else(|| panic!("no node outputs a {name}"))
}

/// Parameters that make the standard inputs show what a node does.
fn tweak(doc: &mut GraphDoc, name: &str) {
    let mut set = |id: &str, param: &str, value: ParamValue| {
        if let Some(node) = doc.node_mut(id) {
            node.params.insert(param.into(), value);
        }
    };
    match name {
        // End Growing cannot join the default motions of the procedural flame (frames 0-49 and
        // 100-149: every_node.rs lets it refuse); the picture joins 0-49 to 51-100, which it can.
        "eigen.end_growing" => {
            set("n", "t2_start", int(51));
            set("n", "t2_end", int(100));
        }
        "eigen.motion_list" => set("n", "motions", ParamValue::String("T1 = 0-49; T2 = 51-100".into())),
        // The defaults are all zeros, the mean image: start from a frame and push the first
        // eigenfire two standard deviations, as the thesis's Fig. 44 edits do.
        "eigen.weights_edit" => {
            set("n", "frame", int(10));
            set("n", "edits", ParamValue::String("1=2, 2=-1".into()));
        }
        // The mask layers that catch the procedural flame (as supply()'s masks do).
        "imaging.hsv_mask" => {
            set("n", "layer1_enabled", ParamValue::Bool(false));
            set("n", "layer2_enabled", ParamValue::Bool(true));
            set("n", "layer3_enabled", ParamValue::Bool(true));
        }
        // The default factor is 0: a flat line.
        "math.multiply" => set("n", "b", ParamValue::Float(2.0)),
        "time.channel" => {
            set("n", "value", ParamValue::Call("expr".into(), Box::new(ParamValue::String("sin(frame / 6)".into()))))
        }
        _ => {}
    }
    // Flames that have grown for a second (the standard three frames are for cooking quickly).
    set("s_flames", "frames", int(24));
    // A puff that has risen for a second, framed close (the defaults frame a campfire's column).
    set("s_sim", "frames", int(24));
    set("s_sim", "voxel_size", ParamValue::Float(0.06));
    if name == "particles.render_flames" {
        // supply() gives a per-frame node's `flames` the roots (a Particles value); the picture
        // draws flames grown from them.
        doc.edges.retain(|(from, to)| !(from == "s_roots.roots" && to == "n.flames"));
        add(doc, "s_grown", NodeDoc::new("particles.particle_flame").param("frames", int(24)));
        doc.connect("s_roots.roots", "s_grown.roots").connect("s_grown.flames", "n.flames");
    }
    let framed = match name {
        "particles.render_flames" => render_flames(),
        "volume.render" | "volume.render_sixway" => volume_render(),
        _ => return,
    };
    doc.node_mut("n").expect("the node").params.extend(framed.params);
}

/// The volume renderer framing the standard puff.
fn volume_render() -> NodeDoc {
    NodeDoc::new("volume.render")
        .param("camera_position", floats(&[0.0, 0.5, 1.8]))
        .param("camera_target", floats(&[0.0, 0.45, 0.0]))
}

/// The graph that shows node type `desc`, and what to show of it.
fn picture_graph(desc: &NodeDesc, files: &Files) -> (GraphDoc, Shown) {
    let name = desc.type_name.as_str();
    let mut doc = graph_for(desc, files);
    tweak(&mut doc, name);
    if name == "graph.include" {
        // The included graph (graphs/candles.ron) exposes its frames as `clip`.
        return (doc, Shown::Endpoint("n.clip".into()));
    }
    if let Some(out) = desc.outputs.iter().find(|p| p.ty == PortType::clip_of(PortType::Float)) {
        return (doc, Shown::Endpoint(format!("n.{}", out.name)));
    }
    if name.starts_with("math.") {
        // Fed the timeline's seconds, a math node's value becomes a curve over the frames.
        let first = desc.inputs.iter().find(|p| p.ty == PortType::Float).expect("a math node takes a number");
        add(&mut doc, "t", NodeDoc::new("time.frame"));
        doc.connect("t.time", &format!("n.{}", first.name));
        return (doc, Shown::Endpoint("n.value".into()));
    }
    if let Some((port, _)) = picture_output(desc) {
        return (doc, Shown::Endpoint(format!("n.{port}")));
    }
    // A writer shows what it writes: its first required input as that input's viewer shows it.
    let shown_port = desc.outputs.iter().find(|p| viewable(&p.ty)).map(|p| (format!("n.{}", p.name), p.ty.clone()));
    let written = || desc.inputs.iter().find(|p| p.is_required() && viewable(&p.ty));
    let (from, ty) = match (shown_port, desc.time == pyrograph_frontend::core::TimeDep::Sink) {
        (Some(out), false) => out,
        (_, true) if written().is_some() => {
            let port = written().expect("checked");
            let from = doc
                .edges
                .iter()
                .find(|(_, to)| *to == format!("n.{}", port.name))
                .map(|(from, _)| from.clone())
                .expect("supplied");
            (from, port.ty.clone())
        }
        _ => return (doc, Shown::Card(desc.outputs.iter().map(|p| format!("{}: {}", p.name, p.ty)).collect())),
    };
    match viewer(&mut doc, &ty, &from, files, name) {
        Some(endpoint) => (doc, Shown::Endpoint(endpoint)),
        None => (doc, Shown::Card(vec![format!("{from}: {ty}")])),
    }
}

fn viewable(ty: &PortType) -> bool {
    let element = ty.clip_element().unwrap_or(ty);
    !matches!(element, PortType::Float | PortType::Int | PortType::Bool | PortType::String | PortType::Path)
        && !matches!(element.to_string().as_str(), "Vec2" | "Vec3" | "Color")
}

/// Cooks the picture of node type `desc`.
fn picture(desc: &NodeDesc, files: &Files) -> Result<Image, String> {
    let registry = pyrograph_frontend::registry();
    let (doc, shown) = picture_graph(desc, files);
    let out = tempfile::tempdir().map_err(|e| e.to_string())?;
    let options = BuildOptions { output_dir: Some(out.path().to_path_buf()), ..BuildOptions::default() };
    let graph = Graph::build(&doc, &registry, out.path(), &options).map_err(|d| format!("does not build: {d}"))?;
    let ctx = CookCtx::new();
    let mut eval = Evaluator::new();
    let image = match shown {
        Shown::Endpoint(endpoint) => {
            let value = eval.output(&graph, &endpoint, &ctx).map_err(|e| format!("{endpoint}: {e}"))?;
            picture_of(value, &ctx).map_err(|e| format!("{endpoint}: {e}"))?
        }
        Shown::Card(lines) => card(&desc.type_name, &lines, &mut eval, &graph, &ctx)?,
    };
    fit(&image, SIZE.0, SIZE.1, THUMB_BACKGROUND)
}

/// An image, or a clip's middle frame; a clip of numbers is plotted.
fn picture_of(value: Value, ctx: &CookCtx) -> Result<Image, String> {
    match value {
        Value::Image(img) => Ok((*img).clone()),
        Value::Clip(clip) if clip.element() == &PortType::Image && !clip.is_empty() => {
            clip.image(clip.len() / 2, ctx).map(|i| (*i).clone()).map_err(|e| e.to_string())
        }
        Value::Clip(clip) if clip.element() == &PortType::Float => {
            let values: Vec<f64> = clip
                .materialize(ctx)
                .map_err(|e| e.to_string())?
                .into_iter()
                .map(|v| if let Value::Float(f) = v { f } else { f64::NAN })
                .collect();
            Ok(plot(&values))
        }
        other => Err(format!("nothing to show in {}", other.summary())),
    }
}

/// A line plot of `values` (one point per frame) on the picture's background: the curve a clip of
/// numbers draws. Drawn here because no node plots a clip of numbers, and the picture needs no
/// axes or labels.
fn plot(values: &[f64]) -> Image {
    let (w, h) = SIZE;
    let mut data: Vec<f32> = std::iter::repeat_n(THUMB_BACKGROUND, (w * h) as usize).flatten().collect();
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let y_of = |v: f64| (f64::from(h) - 12.0) * (1.0 - (v - lo) / span) + 6.0;
    let n = values.len().max(2) - 1;
    for x in 0..w {
        let t = f64::from(x) / f64::from(w - 1) * n as f64;
        let (i, f) = (t.floor() as usize, t.fract());
        let (a, b) =
            (values.get(i).copied().unwrap_or(lo), values.get(i + 1).copied().unwrap_or(values.get(i).copied().unwrap_or(lo)));
        let y = y_of(a + (b - a) * f).round().clamp(0.0, f64::from(h - 2)) as u32;
        for dy in 0..2 {
            let at = (((y + dy) * w + x) * 4) as usize;
            data[at..at + 4].copy_from_slice(&[1.0, 0.55, 0.15, 1.0]);
        }
    }
    Image::from_vec(w, h, Channels::Rgba, data).expect("the picture's size")
}

/// A card for a node whose outputs are numbers or text: each output's value, cooked, as a label.
fn card(name: &str, ports: &[String], eval: &mut Evaluator, graph: &Graph, ctx: &CookCtx) -> Result<Image, String> {
    let mut lines = Vec::new();
    for port in ports {
        let (id, _) = port.split_once(':').unwrap_or((port, ""));
        let endpoint = if id.contains('.') { id.to_string() } else { format!("n.{id}") };
        let value = eval.output(graph, &endpoint, ctx).map_err(|e| format!("{endpoint}: {e}"))?;
        let shown = match &value {
            Value::Float(v) => format!("{v:.4}").trim_end_matches('0').trim_end_matches('.').to_string(),
            Value::Clip(c) => format!("{} frames", c.len()),
            other => other.summary(),
        };
        lines.push(format!("{} = {shown}", endpoint.trim_start_matches("n.")));
    }
    let blank = Image::from_vec(
        SIZE.0,
        SIZE.1 / 2,
        Channels::Rgba,
        std::iter::repeat_n(THUMB_BACKGROUND, (SIZE.0 * SIZE.1 / 2) as usize).flatten().collect(),
    )
    .expect("the card's size");
    let mut labels = vec![name.to_string()];
    labels.extend(lines);
    pyrograph::wedge::sheet(&[(blank, labels)], 1, SIZE.0)
}

/// Node pictures that show one realization of a random process: `flame_model.arp_learn` fits its
/// model with a particle filter whose resampling flips on the last bit of a float, and the flame
/// fit's numbers before it differ in that bit between builds and machines (the same commit drew one
/// realization in a local debug build, another in the clean-clone CI on the same machine, and a third
/// on the machine that made the pictures; not tracked down further), so each draws its own. They are compared by
/// their 12×12-pixel block means (the curves' envelopes): two realizations differ there by 0.7–1.0/255
/// on average and at most 8.3/255, a plot shifted 6 pixels or flattened by 4–6/255 and up to 47/255.
const REALIZATIONS: [&str; 2] = ["flame_model.arp_learn", "flame_model.arp_sample"];

/// [`REALIZATIONS`]' comparison: the mean of 12×12-pixel block means' differences at most 2/255,
/// none over 16/255.
fn envelopes_match(made: &image::RgbaImage, want: &image::RgbaImage) -> Result<(), String> {
    const BLOCK: u32 = 12;
    if made.dimensions() != want.dimensions() {
        return Err(format!("size {:?}, committed {:?}", made.dimensions(), want.dimensions()));
    }
    let (w, h) = (made.width() / BLOCK, made.height() / BLOCK);
    let mean = |img: &image::RgbaImage, bx: u32, by: u32, c: usize| {
        let pixels = (0..BLOCK * BLOCK).map(|k| img.get_pixel(bx * BLOCK + k % BLOCK, by * BLOCK + k / BLOCK).0[c]);
        pixels.map(f64::from).sum::<f64>() / f64::from(BLOCK * BLOCK)
    };
    let diffs: Vec<f64> = (0..w * h)
        .flat_map(|b| (0..4).map(move |c| (b, c)))
        .map(|(b, c)| (mean(made, b % w, b / w, c) - mean(want, b % w, b / w, c)).abs())
        .collect();
    let average = diffs.iter().sum::<f64>() / diffs.len().max(1) as f64;
    let largest = diffs.iter().copied().fold(0.0, f64::max);
    if average > 2.0 || largest > 16.0 {
        return Err(format!("block means differ by {average:.2}/255 on average, up to {largest:.1}/255"));
    }
    Ok(())
}

fn regenerate() -> bool {
    std::env::var("REGENERATE").is_ok_and(|v| v == "1")
}

/// Makes node type `desc`'s picture and compares it with the committed one (`REGENERATE=1`
/// writes it first); the failure, if any.
fn check_picture(desc: &NodeDesc, files: &Files) -> Option<String> {
    let name = &desc.type_name;
    let made = match picture(desc, files) {
        Ok(img) => img,
        Err(e) => return Some(format!("{name}: {e}")),
    };
    let file = picture_file(name);
    if regenerate() {
        let bytes = pyrograph_frontend::imaging::io::encode_image(
            &made,
            pyrograph_frontend::imaging::io::OutputFormat::Png { sixteen_bit: false },
        )
        .expect("encode");
        std::fs::create_dir_all(pictures_dir()).expect("mkdir");
        pyrograph_frontend::core::document::write_atomic(&file, &bytes, true).expect("write the picture");
    }
    let made = pyrograph_frontend::imaging::convert::to_rgba8(&made);
    match image::open(&file) {
        Ok(want) => {
            let want = want.to_rgba8();
            let matched = if REALIZATIONS.contains(&name.as_str()) {
                envelopes_match(&made, &want)
            } else {
                pyrograph_testing::pictures_match(made.as_raw(), made.dimensions(), want.as_raw(), want.dimensions())
            };
            matched.err().map(|e| format!("{name}: {} is stale ({e}); REGENERATE=1 renews it", file.display()))
        }
        Err(e) => Some(format!("{name}: {}: {e} (REGENERATE=1 makes it)", file.display())),
    }
}

#[test]
fn every_node_has_a_current_picture_in_the_reference() {
    let registry = pyrograph_frontend::registry();
    let files = make_files(&registry, FLAME);
    let descs: Vec<NodeDesc> = registry.descs().cloned().collect();
    let names: Vec<String> = descs.iter().map(|d| format!("{}.png", d.type_name)).collect();
    // Two threads (the machine's cores): each picture is its own graph and evaluator.
    let half = descs.len().div_ceil(2);
    let failures: Vec<String> = std::thread::scope(|s| {
        let jobs: Vec<_> = descs
            .chunks(half)
            .map(|chunk| s.spawn(|| chunk.iter().filter_map(|d| check_picture(d, &files)).collect::<Vec<_>>()))
            .collect();
        jobs.into_iter().flat_map(|j| j.join().expect("a picture thread")).collect()
    });
    assert!(failures.is_empty(), "{} node picture(s) failed:\n{}", failures.len(), failures.join("\n"));
    // No picture of a node that is gone.
    let mut stale: Vec<String> = std::fs::read_dir(pictures_dir())
        .expect("docs/images/nodes")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| !names.contains(f))
        .collect();
    stale.sort();
    assert!(stale.is_empty(), "pictures of nodes that are not registered: {stale:?}");
}

#[test]
fn the_reference_shows_each_nodes_picture() {
    let reference = std::fs::read_to_string(workspace().join("docs/nodes.md")).expect("docs/nodes.md");
    for desc in pyrograph_frontend::registry().descs() {
        let link = format!("](images/nodes/{}.png)", desc.type_name);
        assert!(reference.contains(&link), "docs/nodes.md does not show {}'s picture", desc.type_name);
        assert!(Path::new(&picture_file(&desc.type_name)).exists(), "{} has no picture", desc.type_name);
    }
}
