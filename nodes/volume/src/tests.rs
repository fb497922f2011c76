//! The volume nodes in graphs: a cache written and read back renders the same frames byte for
//! byte, frames cooked in chunks equal a whole cook, and hostile inputs (NaN from a parameter or an
//! emitter, corrupt and truncated files) are errors naming the node, port, frame or file.

use std::path::Path;

use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, Registry, Value};

fn registry() -> Registry {
    let mut r = Registry::with_builtins();
    pyrograph_nodes_particles::register(&mut r);
    pyrograph_nodes_imaging::register(&mut r);
    super::register(&mut r);
    r
}

fn graph(ron: &str, dir: &Path) -> Graph {
    let doc = GraphDoc::from_ron(ron).unwrap();
    let options = BuildOptions { output_dir: Some(dir.to_path_buf()), ..BuildOptions::default() };
    Graph::build(&doc, &registry(), dir, &options).unwrap_or_else(|d| panic!("{d}"))
}

fn error(g: &Graph, endpoint: &str, frame: usize) -> String {
    let ctx = CookCtx::new();
    let v = Evaluator::new().output(g, endpoint, &ctx);
    let e = match v {
        Ok(Value::Clip(c)) => c.get(frame, &ctx).err(),
        Ok(_) => None,
        Err(e) => Some(e),
    };
    e.map(|e| e.to_string()).unwrap_or_else(|| panic!("{endpoint} frame {frame} cooked"))
}

const SIM: &str = r#""source": (type: "volume.source", params: {"center": (0.0, 0.2, 0.0), "radius": 0.2}),
        "sim": (type: "volume.simulate", params: {"frames": 8, "voxel_size": 0.1}),"#;

#[test]
fn a_parameter_or_an_emitter_turning_nan_is_an_error_naming_the_port_and_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let g = graph(
        r#"(version: 3, nodes: {
            "source": (type: "volume.source", params: {"center": (0.0, 0.2, 0.0), "radius": 0.2}),
            "sim": (type: "volume.simulate", params: {"frames": 8, "voxel_size": 0.1, "buoyancy": expr("sqrt(2.5 - frame)")}),
        }, edges: [("source.source", "sim.source")])"#,
        dir.path(),
    );
    let e = error(&g, "sim.volume", 6);
    assert!(e.contains("sim") && e.contains("buoyancy") && e.contains("frame 3"), "{e}");
    let g = graph(
        r#"(version: 3, nodes: {
            "source": (type: "volume.source", params: {"center": (expr("ln(1.5 - frame)"), 0.2, 0.0), "radius": 0.2}),
            "sim": (type: "volume.simulate", params: {"frames": 8, "voxel_size": 0.1}),
        }, edges: [("source.source", "sim.source")])"#,
        dir.path(),
    );
    let e = error(&g, "sim.volume", 4);
    assert!(e.contains("sim") && e.contains("center") && e.contains("frame 2"), "{e}");
}

#[test]
fn a_cache_read_back_renders_the_frames_of_the_simulation_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let write = graph(
        &format!(
            r#"(version: 3, nodes: {{ {SIM}
                "cache": (type: "volume.write_vdb", params: {{"pattern": "cache/smoke_####.vdb"}}),
                "view": (type: "volume.preview", params: {{"width": 40, "height": 48, "center": (0.0, 0.6, 0.0), "size": 2.0}}),
            }}, edges: [("source.source", "sim.source"), ("sim.volume", "cache.volume"), ("sim.volume", "view.volume")])"#
        ),
        dir.path(),
    );
    let ctx = CookCtx::new();
    Evaluator::new().cook(&write, &["cache"], &ctx).unwrap().node("cache").unwrap().as_ref().unwrap();
    let direct = Evaluator::new().output(&write, "view.image", &ctx).unwrap();
    let read = graph(
        r#"(version: 3, nodes: {
            "cache": (type: "volume.load_vdb", params: {"path": "cache/smoke_####.vdb"}),
            "view": (type: "volume.preview", params: {"width": 40, "height": 48, "center": (0.0, 0.6, 0.0), "size": 2.0}),
        }, edges: [("cache.volume", "view.volume")])"#,
        dir.path(),
    );
    let Value::Clip(direct) = direct else { panic!("a clip") };
    let Value::Clip(cached) = Evaluator::new().output(&read, "view.image", &CookCtx::new()).unwrap() else { panic!("a clip") };
    assert_eq!(cached.len(), 8);
    for f in [7, 2, 5] {
        let (a, b) = (direct.image(f, &ctx).unwrap(), cached.image(f, &CookCtx::new()).unwrap());
        assert!(a.data().iter().any(|v| *v > 0.05), "frame {f} shows something");
        assert!(a.data() == b.data(), "frame {f} from the cache differs");
    }
    // The volumes themselves, every field and statistic.
    let Value::Clip(sim) = Evaluator::new().output(&write, "sim.volume", &ctx).unwrap() else { panic!("a clip") };
    let Value::Clip(loaded) = Evaluator::new().output(&read, "cache.volume", &ctx).unwrap() else { panic!("a clip") };
    assert!(sim.get(6, &ctx).unwrap().fingerprint() == loaded.get(6, &ctx).unwrap().fingerprint());
}

#[test]
fn rendered_frames_cooked_alone_and_out_of_order_equal_a_whole_cook_and_the_fire_glows() {
    let dir = tempfile::tempdir().unwrap();
    let ron = format!(
        r#"(version: 3, nodes: {{ {SIM}
            "render": (type: "volume.render", params: {{"width": 48, "height": 40, "camera_position": (0.0, 0.6, 4.0),
                "camera_target": (0.0, 0.6, 0.0)}}),
        }}, edges: [("source.source", "sim.source"), ("sim.volume", "render.volume")])"#
    );
    let g = graph(&ron, dir.path());
    let ctx = CookCtx::new();
    let Value::Clip(whole) = Evaluator::new().output(&g, "render.image", &ctx).unwrap() else { panic!("a clip") };
    let whole: Vec<_> = (0..8).map(|f| whole.image(f, &ctx).unwrap()).collect();
    for f in [6, 1, 4] {
        // A fresh graph and evaluator per frame, as a farm chunk cooks it.
        let g = graph(&ron, dir.path());
        let Value::Clip(alone) = Evaluator::new().output(&g, "render.image", &CookCtx::new()).unwrap() else { panic!("a clip") };
        assert!(alone.image(f, &CookCtx::new()).unwrap().data() == whole[f].data(), "frame {f} cooked alone differs");
    }
    // The burning source glows: red above blue somewhere, as a blackbody below 3,000 K.
    let last = &whole[7];
    assert!(last.data().chunks(4).any(|p| p[0] > 0.2 && p[0] > 2.0 * p[2]), "no fire glow in the last frame");
}

#[test]
fn corrupt_truncated_and_missing_files_are_errors_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("junk_0000.vdb"), b"this is not a volume").unwrap();
    let v = crate::vdb::write_volume(&crate::vdb::tests::sample_volume(), &Default::default()).unwrap();
    std::fs::write(dir.path().join("cut_0000.vdb"), &v[..v.len() * 2 / 3]).unwrap();
    std::fs::write(dir.path().join("gap_0000.vdb"), &v).unwrap();
    std::fs::write(dir.path().join("gap_0002.vdb"), &v).unwrap();
    let g = graph(
        r#"(version: 3, nodes: {
            "junk": (type: "volume.load_vdb", params: {"path": "junk_####.vdb"}),
            "cut": (type: "volume.load_vdb", params: {"path": "cut_####.vdb"}),
            "gap": (type: "volume.load_vdb", params: {"path": "gap_####.vdb"}),
            "none": (type: "volume.load_vdb", params: {"path": "nothing_####.vdb"}),
        }, edges: [])"#,
        dir.path(),
    );
    let e = error(&g, "junk.volume", 0);
    assert!(e.contains("junk_0000.vdb") && e.contains("not an OpenVDB file"), "{e}");
    let e = error(&g, "cut.volume", 0);
    assert!(e.contains("cut_0000.vdb") && (e.contains("truncated") || e.contains("outside the file")), "{e}");
    let e = error(&g, "gap.volume", 0);
    assert!(e.contains("frame 1 is missing"), "{e}");
    let e = error(&g, "none.volume", 0);
    assert!(e.contains("no files match") && e.contains("nothing_####.vdb"), "{e}");
}
