//! Six-way lighting flipbooks as the engines read them (issue 62): a simulated puff of smoke
//! rendered by volume.render_sixway, both maps laid out by imaging.write_flipbook as PNG sheets
//! with their side-cars, read back with the `image` crate (what the engine flipbook tests use),
//! and relit by Unity's six-way decode from six light directions between the axes: each must
//! reproduce volume.render's frame lit by a sun from that direction.

use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

use glam::Vec3;
use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, Image, Value};
use pyrograph_frontend::render::ports::CameraPorts;
use pyrograph_frontend::volume::render::sixway::{camera_frame, relight};

const SIZE: u32 = 48;
const CAMERA: &str = r#""width": 48, "height": 48, "camera_position": (0.0, 0.5, 2.6), "camera_target": (0.0, 0.45, 0.0)"#;
const LOOK: &str = r#""extinction": 8.0, "anisotropy": 0.0, "step_size": 0.5"#;

/// Four frames of a rising puff, and volume.render of it lit by a sun along `sun` (world, toward
/// the light), smoke only (no ambient, no fire light, black background).
fn graph(sun: Vec3) -> String {
    format!(
        r#"(
    version: 3,
    nodes: {{
        "source": (type: "volume.source", params: {{"smoke_rate": 6.0, "fuel_rate": 0.0, "radius": 0.3, "velocity": (0.0, 1.5, 0.0)}}),
        "sim": (type: "volume.simulate", params: {{"frames": 4, "voxel_size": 0.1}}),
        "six": (type: "volume.render_sixway", params: {{{CAMERA}, {LOOK}, "albedo": 0.9}}),
        "lit": (type: "volume.render", params: {{{CAMERA}, {LOOK}, "albedo": (0.9, 0.9, 0.9), "ambient": (0.0, 0.0, 0.0),
            "sun_direction": ({}, {}, {}), "sun_color": (1.0, 1.0, 1.0), "fire_light": 0.0, "exposure": 0.0, "glow": 0.0,
            "background": (0.0, 0.0, 0.0, 0.0)}}),
    }},
    edges: [("source.source", "sim.source"), ("sim.volume", "six.volume"), ("sim.volume", "lit.volume")],
)"#,
        sun.x, sun.y, sun.z
    )
}

fn frames(doc: &str, output: &str) -> Vec<Arc<Image>> {
    let doc = GraphDoc::from_ron(doc).unwrap();
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), Path::new("."), &BuildOptions::default()).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&g, output, &ctx).unwrap() else { panic!("{output}") };
    (0..clip.len()).map(|i| clip.image(i, &ctx).unwrap()).collect()
}

/// imaging.write_flipbook on `frames`, 2 × 2 cells, to `path`; returns the side-car.
fn write_sheet(frames: &[Arc<Image>], path: &Path) -> serde_json::Value {
    super::cook_writer(frames, &[("rows", Value::Int(2)), ("cols", Value::Int(2)), ("path", Value::Path(path.to_path_buf()))]);
    let json = path.with_file_name(format!("{}_2x2.json", path.file_stem().unwrap().to_str().unwrap()));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// Cell `k`'s pixels of a 2 × 2 sheet, as floats.
fn cell(sheet: &image::Rgba32FImage, k: u32) -> Vec<[f32; 4]> {
    let (x0, y0) = ((k % 2) * SIZE, (k / 2) * SIZE);
    (0..SIZE).flat_map(|y| (0..SIZE).map(move |x| sheet.get_pixel(x0 + x, y0 + y).0)).collect()
}

#[test]
fn six_way_sheets_relit_by_unitys_decode_match_direct_renders() {
    let dir = tempfile::tempdir().unwrap();
    let doc = graph(Vec3::Y);
    let (pos, neg) = (frames(&doc, "six.positive"), frames(&doc, "six.negative"));
    let mut sheets = Vec::new();
    for (name, clip) in [("smoke_pos.png", &pos), ("smoke_neg.png", &neg)] {
        let side = write_sheet(clip, &dir.path().join(name));
        assert_eq!(
            (side["rows"].as_u64(), side["cols"].as_u64(), side["frames"].as_u64()),
            (Some(2), Some(2), Some(4)),
            "{side}"
        );
        let file = dir.path().join(name.replace(".png", "_2x2.png"));
        let sheet = image::open(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display())).into_rgba32f();
        assert_eq!(sheet.dimensions(), (2 * SIZE, 2 * SIZE));
        // The sheet holds the maps' linear values, 8 bits each.
        for (k, frame) in clip.iter().enumerate() {
            for (a, b) in cell(&sheet, k as u32).iter().zip(frame.data().chunks(4)) {
                for c in 0..4 {
                    assert!((a[c] - b[c].clamp(0.0, 1.0)).abs() <= 0.5 / 255.0 + 1e-6, "cell {k}: {a:?} vs {b:?}");
                }
            }
        }
        sheets.push(sheet);
    }
    let view = CameraPorts::looking(SIZE, SIZE, [0.0, 0.5, 2.6], [0.0, 0.45, 0.0]).view().unwrap();
    let frame = camera_frame(&view);
    let last = 3;
    let (p, n) = (cell(&sheets[0], last), cell(&sheets[1], last));
    let covered: Vec<usize> = (0..p.len()).filter(|&k| p[k][3] > 0.05).collect();
    assert!(covered.len() > 150, "the puff covers {} pixels", covered.len());
    println!("| light (camera frame) | relative error per pixel | total light |");
    for l in [
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(-1.0, -0.5, -1.0),
        Vec3::new(0.6, 0.7, -0.4),
        Vec3::new(-0.3, 0.4, 0.87),
    ] {
        let l = l.normalize();
        let world = frame[0] * l.x + frame[1] * l.y + frame[2] * l.z;
        let direct = frames(&graph(world), "lit.image");
        let truth = &direct[last as usize];
        let (mut err, mut total, mut sum) = (0.0f64, 0.0f64, 0.0f64);
        for &k in &covered {
            let px = &truth.data()[k * 4..k * 4 + 4];
            // volume.render's straight RGBA over transparent black: premultiplied, times π (the maps' units).
            let want = PI * px[0] * px[3];
            let rgb = |c: [f32; 4]| Vec3::new(c[0], c[1], c[2]);
            let got = relight(rgb(p[k]), rgb(n[k]), l);
            err += f64::from((got - want).abs());
            total += f64::from(want);
            sum += f64::from(got);
        }
        let (relative, light) = (err / total, sum / total - 1.0);
        println!("| {l} | {:.1} % | {:+.1} % |", 100.0 * relative, 100.0 * light);
        // The tolerance of the volume crate's relighting test (dense puff), plus 8-bit sheets.
        assert!(relative <= 0.32 && light.abs() <= 0.15, "light {l}: {relative} per pixel, {light} in total");
    }
}

/// Bad input to the volume renderers is an error naming the node, the port and the frame.
#[test]
fn bad_volume_render_parameters_are_errors_naming_node_port_and_frame() {
    let graph = |params: &str| {
        format!(
            r#"(
    version: 3,
    nodes: {{
        "source": (type: "volume.source", params: {{"smoke_rate": 6.0, "radius": 0.3}}),
        "sim": (type: "volume.simulate", params: {{"frames": 2, "voxel_size": 0.1}}),
        "look": (type: "volume.render", params: {{"width": 8, "height": 8, {params}}}),
    }},
    edges: [("source.source", "sim.source"), ("sim.volume", "look.volume")],
)"#
        )
    };
    for (params, want) in [
        (r#""exposure": -1.0"#, "exposure"),
        (r#""sun_direction": (0.0, 0.0, 0.0)"#, "sun_direction"),
        (r#""albedo": (0.5, 0.5, 1.5)"#, "albedo"),
        (r#""ambient": (0.1, -1.0, 0.1)"#, "ambient"),
        (r#""camera_position": (0.0, 0.0, 0.0), "camera_target": (0.0, 0.0, 0.0)"#, "camera"),
    ] {
        let doc = GraphDoc::from_ron(&graph(params)).unwrap();
        let message = match Graph::build(&doc, &pyrograph_frontend::registry(), Path::new("."), &BuildOptions::default()) {
            Err(e) => e.to_string(),
            Ok(g) => {
                let ctx = CookCtx::new();
                let Value::Clip(clip) = Evaluator::new().output(&g, "look.image", &ctx).unwrap() else { panic!("a clip") };
                clip.image(1, &ctx).err().map(|e| e.to_string()).unwrap_or_default()
            }
        };
        println!("{params}: {message}");
        assert!(message.contains("look") && message.contains(want), "{params}: {message}");
        // Parameters checked per frame name the frame; a constant out of its range is refused
        // before any frame cooks.
        assert!(message.contains("frame 1") || message.contains("outside the range"), "{params}: {message}");
    }
}
