//! The Eigenfires nodes through their descriptions: bad inputs give errors naming port and cause.

use std::sync::Arc;

use pyrograph_core::{Channels, Clip, CookCtx, Image, NodeError, PortType, Registry, Value};
use pyrograph_nodes_eigen::values::{Basis, FrameList, Weights};

fn registry() -> Registry {
    let mut r = Registry::new();
    pyrograph_nodes_eigen::register(&mut r);
    r
}

/// Cooks node `ty` with `set` overriding the port defaults.
fn cook(ty: &str, set: &[(&str, Value)]) -> Result<Vec<Value>, NodeError> {
    let r = registry();
    let node = r.get(ty).unwrap_or_else(|| panic!("{ty} registered"));
    pyrograph_core::testing::cook_node(&**node, set)
}

fn clip(w: u32, h: u32, m: usize, seed: u32) -> Value {
    let frames = (0..m)
        .map(|i| {
            Value::Image(Arc::new(Image::gray_from_fn(w, h, |x, y| {
                (((x * 7 + y * 13 + i as u32 * 31 + seed) % 17) as f32) / 17.0
            })))
        })
        .collect();
    Value::Clip(Clip::from_frames(PortType::Image, 30.0, frames))
}

fn message(e: NodeError) -> String {
    e.to_string()
}

fn trained() -> (Value, Value) {
    let out = cook("eigen.eigenfires", &[("clip1", clip(6, 5, 8, 0)), ("clip2", clip(6, 5, 4, 3))]).unwrap();
    (out[0].clone(), out[1].clone())
}

#[test]
fn two_clips_become_one_database_remembering_sources() {
    let (basis, weights) = trained();
    let (Some(b), Some(w)) = (basis.downcast::<Basis>(), weights.downcast::<Weights>()) else { panic!() };
    assert_eq!(b.sources.len(), 12);
    assert_eq!((b.sources[8].clip, b.sources[8].index), (1, 0));
    assert_eq!(w.frames, 12);
    assert!(b.components() <= 11);
}

#[test]
fn clips_of_different_sizes_name_the_port() {
    let e = message(cook("eigen.eigenfires", &[("clip1", clip(6, 5, 4, 0)), ("clip2", clip(5, 5, 4, 0))]).unwrap_err());
    assert!(e.contains("port 'clip2'") && e.contains("5x5") && e.contains("6x5"), "{e}");
    let rgba =
        Value::Clip(Clip::from_frames(PortType::Image, 30.0, vec![Value::Image(Arc::new(Image::new(6, 5, Channels::Rgba))); 3]));
    let e = message(cook("eigen.eigenfires", &[("clip1", rgba)]).unwrap_err());
    assert!(e.contains("RGBA"), "{e}");
    let empty = Value::Clip(Clip::from_frames(PortType::Image, 30.0, vec![]));
    assert!(message(cook("eigen.eigenfires", &[("clip1", empty)]).unwrap_err()).contains("no frames"));
}

#[test]
fn too_many_components_is_an_error_naming_the_port() {
    let (basis, weights) = trained();
    let e = message(
        cook("eigen.reconstruct", &[("basis", basis.clone()), ("weights", weights.clone()), ("components", Value::Int(500))])
            .unwrap_err(),
    );
    assert!(e.contains("port 'components'") && e.contains("500"), "{e}");
    let e = message(
        cook("eigen.project", &[("basis", basis.clone()), ("clip", clip(6, 5, 2, 0)), ("components", Value::Int(99))])
            .unwrap_err(),
    );
    assert!(e.contains("port 'components'"), "{e}");
    let e = message(cook("eigen.project", &[("basis", basis), ("clip", clip(4, 4, 2, 0))]).unwrap_err());
    assert!(e.contains("port 'clip'") && e.contains("4x4"), "{e}");
}

#[test]
fn empty_ranges_and_unreachable_theta_are_errors() {
    let (_, weights) = trained();
    let e = message(
        cook(
            "eigen.direct_bridging",
            &[
                ("weights", weights.clone()),
                ("t1_start", Value::Int(5)),
                ("t1_end", Value::Int(2)),
                ("t2_start", Value::Int(8)),
                ("t2_end", Value::Int(9)),
            ],
        )
        .unwrap_err(),
    );
    assert!(e.contains("port 't1_end'") && e.contains("empty"), "{e}");
    let e = message(
        cook(
            "eigen.motion_list",
            &[
                ("weights", weights.clone()),
                ("motions", Value::String("T1 = 0-3; T2 = 9-40".into())),
                ("method", Value::Enum("cut".into())),
            ],
        )
        .unwrap_err(),
    );
    assert!(e.contains("port 'motions'") && e.contains("past"), "{e}");
    let e = message(
        cook("eigen.recognize", &[("weights", weights.clone()), ("frame", Value::Int(0)), ("theta_min", Value::Float(1e8))])
            .unwrap_err(),
    );
    assert!(e.contains("port 'theta_min'"), "{e}");
    let ok = cook("eigen.recognize", &[("weights", weights), ("frame", Value::Int(0)), ("exclude", Value::Int(1))]).unwrap();
    let Some(l) = ok[0].downcast::<FrameList>() else { panic!() };
    assert_eq!(l.items.len(), 1);
}

#[test]
fn a_scenario_renders_to_a_clip_both_ways() {
    let (basis, weights) = trained();
    let out = cook(
        "eigen.motion_list",
        &[
            ("weights", weights.clone()),
            ("motions", Value::String("T1 = 0-3; T2 = 8-11".into())),
            ("scenario", Value::String("T1 + T2".into())),
            ("loop", Value::Bool(true)),
            ("method", Value::Enum("lowpass".into())),
            ("lowpass_components", Value::Int(3)),
            ("span", Value::Int(1)),
        ],
    )
    .unwrap();
    let frames = out[0].clone();
    let rec = cook("eigen.frames_to_clip", &[("frames", frames.clone()), ("basis", basis.clone()), ("weights", weights.clone())])
        .unwrap();
    let Value::Clip(c) = &rec[0] else { panic!() };
    assert_eq!(c.len(), 8);
    // Source mode needs the training clips; without them the error names the missing port.
    let e = message(
        cook(
            "eigen.frames_to_clip",
            &[
                ("frames", frames.clone()),
                ("basis", basis.clone()),
                ("weights", weights.clone()),
                ("mode", Value::Enum("source".into())),
            ],
        )
        .unwrap_err(),
    );
    assert!(e.contains("clip1"), "{e}");
    let src = cook(
        "eigen.frames_to_clip",
        &[
            ("frames", frames),
            ("basis", basis),
            ("weights", weights),
            ("mode", Value::Enum("source".into())),
            ("clip1", clip(6, 5, 8, 0)),
            ("clip2", clip(6, 5, 4, 3)),
        ],
    )
    .unwrap();
    let Value::Clip(c) = &src[0] else { panic!() };
    assert_eq!(c.len(), 8);
}

#[test]
fn weights_edit_from_zeros_reconstructs_the_mean() {
    let (basis, weights) = trained();
    let w = cook("eigen.weights_edit", &[("basis", basis.clone()), ("weights", weights.clone())]).unwrap();
    let out =
        cook("eigen.reconstruct", &[("basis", basis.clone()), ("weights", w[0].clone()), ("clamp", Value::Bool(false))]).unwrap();
    let (Value::Clip(c), Some(b)) = (&out[0], basis.downcast::<Basis>()) else { panic!() };
    let img = c.image(0, &CookCtx::new()).unwrap();
    assert!(img.data().iter().zip(&b.mean).all(|(a, m)| (a - m).abs() < 1e-6));
    let e = message(
        cook("eigen.weights_edit", &[("basis", basis), ("weights", weights), ("edits", Value::String("99=1".into()))])
            .unwrap_err(),
    );
    assert!(e.contains("port 'edits'") && e.contains("component 99"), "{e}");
    let _ = Weights::default();
}

#[test]
fn database_nodes_round_trip_and_reject_a_truncated_pack() {
    let (basis, weights) = trained();
    let dir = tempfile::tempdir().unwrap();
    let path = Value::Path(dir.path().join("db"));
    cook(
        "eigen.save_database",
        &[("basis", basis.clone()), ("weights", weights.clone()), ("path", path.clone()), ("pack_size", Value::Int(3))],
    )
    .unwrap();
    let out = cook("eigen.load_database", &[("path", path.clone())]).unwrap();
    assert_eq!(out[1].fingerprint(), weights.fingerprint());
    assert_eq!(out[0].fingerprint(), basis.fingerprint());
    let pack = dir.path().join("db/pack_002.bin");
    let bytes = std::fs::read(&pack).unwrap();
    std::fs::write(&pack, &bytes[..bytes.len() / 2]).unwrap();
    let e = message(cook("eigen.load_database", &[("path", path)]).unwrap_err());
    assert!(e.contains("port 'path'") && e.contains("pack_002.bin") && e.contains("truncated"), "{e}");
}

#[test]
fn end_growing_adaptive_theta_needs_the_basis_and_reports_the_thresholds() {
    let (basis, weights) = trained();
    let ports = |mode: &str| -> Vec<(&str, Value)> {
        vec![
            ("weights", weights.clone()),
            ("t1_start", Value::Int(0)),
            ("t1_end", Value::Int(1)),
            ("t2_start", Value::Int(9)),
            ("t2_end", Value::Int(11)),
            ("exclude", Value::Int(0)),
            ("theta_mode", Value::Enum(mode.into())),
        ]
    };
    let e = message(cook("eigen.end_growing", &ports("measured")).unwrap_err());
    assert!(e.contains("port 'basis'") && e.contains("theta_mode measured"), "{e}");
    let mut bad = ports("per_clip");
    bad.push(("basis", basis.clone()));
    bad.push(("theta_per_clip", Value::String("0.01".into())));
    let e = message(cook("eigen.end_growing", &bad).unwrap_err());
    assert!(e.contains("port 'theta_per_clip'") && e.contains("clip 2"), "{e}");
    // Measured with scale 0: both clips get θ_min = 0, the same as the fixed default.
    let mut measured = ports("measured");
    measured.push(("basis", basis));
    measured.push(("theta_scale", Value::Float(0.0)));
    let out = cook("eigen.end_growing", &measured).unwrap();
    let fixed = cook("eigen.end_growing", &ports("fixed")).unwrap();
    let (Value::String(t), Value::String(tf)) = (&out[2], &fixed[2]) else { panic!() };
    assert_eq!((t.as_str(), tf.as_str()), ("0, 0", "0"));
    let (Some(a), Some(b)) = (out[0].downcast::<FrameList>(), fixed[0].downcast::<FrameList>()) else { panic!() };
    assert_eq!(a.items.len(), b.items.len());
}
