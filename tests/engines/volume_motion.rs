//! Volume flipbooks whose motion comes from the simulation (issue 62): a puff of smoke carried by
//! the wind, rendered by volume.render at twice the sheet's rate with its motion pass (the velocity
//! field projected to pixels per sheet frame); the even frames and their motion pass make a 4×4
//! Unity flipbook (imaging.write_flipbook with `motion_vectors`), the odd frames are the true
//! in-betweens. Unity's motion blend along the simulation's vectors must come closer to them than a
//! cross-fade and than the same blend along the optical flow, and the sheet must decode to the
//! motion pass's vectors.

use std::path::Path;
use std::sync::Arc;

use pyrograph_frontend::core::{BuildOptions, Clip, CookCtx, Evaluator, Graph, GraphDoc, Image, PortType, Value};

use super::{H, SIDE, Texture, W, cook_writer, rebuild, unity};

/// A puff blown right by a steady wind (a burst of smoke, then none), 32 frames at 24 fps; the
/// motion pass in pixels per sheet frame (12 fps). The frame is W × H.
const SCENE: &str = r#"(
    version: 3,
    nodes: {
        "source": (type: "volume.source", params: {"smoke_rate": keys([(0, 60.0, constant), (3, 0.0, constant)]), "fuel_rate": 0.0, "hold_temperature": 0.0, "radius": 0.25, "center": (-0.6, 1.4, 0.0), "velocity": (2.0, 0.0, 0.0)}),
        "wind": (type: "particles.wind_field", params: {"large_scale": "constant", "wind": (2.0, 0.0, 0.0), "noise_c": 0.0, "k_g": 0.0}),
        "sim": (type: "volume.simulate", params: {"frames": 32, "voxel_size": 0.1, "wind_drag": 8.0, "buoyancy": 0.0, "turbulence": 0.0, "vorticity": 0.0}),
        "beauty": (type: "volume.render", params: {"width": 96, "height": 128, "camera_position": (0.3, 1.4, 4.0), "camera_target": (0.3, 1.4, 0.0), "extinction": 8.0, "ambient": (0.25, 0.25, 0.25), "sun_color": (3.0, 3.0, 3.0), "fire_light": 0.0, "background": (0.0, 0.0, 0.0, 0.0)}),
        "motion": (type: "volume.render", params: {"width": 96, "height": 128, "camera_position": (0.3, 1.4, 4.0), "camera_target": (0.3, 1.4, 0.0), "extinction": 8.0, "pass": "motion", "frame_rate": 12.0}),
    },
    edges: [("source.source", "sim.source"), ("wind.wind", "sim.wind"), ("sim.volume", "beauty.volume"), ("sim.volume", "motion.volume")],
)"#;

#[test]
fn unitys_motion_blend_along_the_simulations_velocity_beats_a_cross_fade_and_the_optical_flow() {
    let doc = GraphDoc::from_ron(SCENE).unwrap();
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), Path::new("."), &BuildOptions::default()).unwrap();
    let ctx = CookCtx::new();
    let clip = |output: &str| -> Vec<Arc<Image>> {
        let Value::Clip(clip) = Evaluator::new().output(&g, output, &ctx).unwrap() else { panic!("{output}") };
        (0..clip.len()).map(|i| clip.image(i, &ctx).unwrap()).collect()
    };
    let (beauty, motion) = (clip("beauty.image"), clip("motion.image"));
    assert_eq!((beauty.len(), motion.len(), (beauty[0].width(), beauty[0].height())), (32, 32, (W, H)));
    let sheet: Vec<Arc<Image>> = beauty.iter().step_by(2).cloned().collect();
    let vectors: Vec<Arc<Image>> = motion.iter().step_by(2).cloned().collect();
    let truth: Vec<Arc<Image>> = beauty.iter().skip(1).step_by(2).take(SIDE * SIDE - 1).cloned().collect();
    let fastest = vectors.iter().flat_map(|v| v.data().chunks(4).map(|p| p[0].hypot(p[1]))).fold(0.0f32, f32::max);
    assert!(fastest > 2.0, "the puff moves {fastest} px per sheet frame at most");
    let dir = tempfile::tempdir().unwrap();
    let side = Value::Int(SIDE as i64);
    let as_clip = |frames: &[Arc<Image>]| {
        Value::Clip(Clip::from_frames(PortType::Image, 12.0, frames.iter().cloned().map(Value::Image).collect()))
    };
    let mut results = Vec::new();
    for (name, given) in [("velocity", Some(as_clip(&vectors))), ("flow", None)] {
        let base = dir.path().join(format!("{name}.png"));
        let mut params = vec![
            ("rows", side.clone()),
            ("cols", side.clone()),
            ("alpha", Value::Enum("premultiplied".into())),
            ("convention", Value::Enum("unity".into())),
            ("path", Value::Path(base.clone())),
        ];
        params.extend(given.map(|v| ("motion_vectors", v)));
        cook_writer(&sheet, &params);
        let file = |suffix: &str, ext: &str| dir.path().join(format!("{name}_{SIDE}x{SIDE}{suffix}.{ext}"));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(file("", "json")).unwrap()).unwrap();
        let scale = json["engine_value"].as_f64().unwrap() as f32;
        let (tex, mv) = (Texture::load(&file("", "png"), false), Texture::load(&file("_mv", "png"), false));
        let (with, without) = rebuild(unity, &tex, &mv, scale, &truth);
        if name == "velocity" {
            same_vectors(&mv, scale, &vectors);
        }
        println!("{name}: Motion Vector Scale {scale}; in-betweens {with:.2} dB with motion, {without:.2} dB cross-faded");
        results.push((with, without));
    }
    let ((velocity, fade), (flow, _)) = (results[0], results[1]);
    println!("in-betweens: the simulation's velocity {velocity:.2} dB, optical flow {flow:.2} dB, cross-fade {fade:.2} dB");
    assert!(velocity > fade + 3.0, "the simulation's vectors: {velocity:.2} dB vs {fade:.2} dB cross-faded");
    assert!(velocity > flow, "the simulation's vectors: {velocity:.2} dB vs {flow:.2} dB along the optical flow");
}

/// The 16-bit Unity sheet's vectors, decoded with Unity's formula (cell UVs, v up) and turned back
/// into frame pixels, are the motion pass's within 1/4 pixel.
fn same_vectors(mv: &Texture, scale: f32, vectors: &[Arc<Image>]) {
    let (w, h) = (W as usize, H as usize);
    let mut worst = 0.0f32;
    for (k, v) in vectors.iter().enumerate() {
        let (cx, cy) = ((k % SIDE) * w, (k / SIDE) * h);
        for (i, p) in v.data().chunks(4).enumerate() {
            let m = mv.px[(cy + i / w) * mv.w + cx + i % w];
            let (dx, dy) = ((m[0] * 2.0 - 1.0) * scale * w as f32, -(m[1] * 2.0 - 1.0) * scale * h as f32);
            worst = worst.max((dx - p[0]).abs()).max((dy - p[1]).abs());
        }
    }
    println!("decoded vectors against the motion pass: largest difference {worst:.4} px");
    assert!(worst <= 0.25, "the sheet's vectors differ from the motion pass by {worst} px");
}
