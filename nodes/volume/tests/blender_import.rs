//! pyrograph's OpenVDB caches in Blender (the `bpy` wheel from PyPI, `tests/blender_check.py`):
//! a frame written as float, as half, and a numbered sequence import through Blender's own
//! OpenVDB importer as a volume object with pyrograph's grids, their types, the voxel size and
//! origin as the index-to-object matrix, and world bounds around the active bricks.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use glam::IVec3;
use pyrograph_nodes_volume::grid::{Field, FieldData, SimStats, Topology, Transform, Volume};
use pyrograph_nodes_volume::vdb::{Compression, WriteOptions, write_volume};
use serde_json::Value as Json;

const MARKER: &str = "== blender_check json";

/// The Python with `bpy`: `PYROGRAPH_BPY_PYTHON`, else the venv `.ci/run` fills.
fn bpy_python() -> PathBuf {
    match std::env::var_os("PYROGRAPH_BPY_PYTHON") {
        Some(p) => PathBuf::from(p),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/bpy-venv/bin/python"),
    }
}

fn blender(files: &[PathBuf]) -> Json {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender_check.py");
    let python = bpy_python();
    let out = Command::new(&python)
        .arg(&script)
        .args(files)
        .output()
        .unwrap_or_else(|e| panic!("{} runs ({e}); .ci/run installs bpy into target/bpy-venv", python.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "blender_check.py failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let json = stdout.split(MARKER).nth(1).unwrap_or_else(|| panic!("no result from Blender:\n{stdout}"));
    serde_json::from_str(json.trim()).expect("the script prints JSON")
}

/// A cache frame like the simulation's: density, temperature and velocity over bricks on either
/// side of the origin, the whole frame shifted by `shift` bricks along x.
fn frame(shift: i32) -> Volume {
    let coords = [IVec3::new(0, 0, 0), IVec3::new(1, 0, 0), IVec3::new(-1, 2, 0), IVec3::new(0, 3, -2)];
    let top = Topology::new(coords.iter().map(|c| *c + IVec3::new(shift, 0, 0)).collect());
    let n = top.voxels();
    Volume {
        transform: Transform { voxel_size: 0.05, origin: [1.0, -2.5, 0.125] },
        topology: Arc::new(top),
        fields: vec![
            Field { name: "density".into(), data: FieldData::Scalar((0..n).map(|i| (i % 97) as f32 / 96.0).collect()) },
            Field { name: "temperature".into(), data: FieldData::Scalar((0..n).map(|i| (i % 13) as f32 * 0.1).collect()) },
            Field { name: "vel".into(), data: FieldData::Vector((0..n).map(|i| [0.0, 1.0 + (i % 5) as f32, 0.0]).collect()) },
        ],
        time: 0.0,
        stats: SimStats::default(),
    }
}

fn assert_frame(seen: &Json, v: &Volume, what: &str) {
    assert_eq!(seen["operator"], serde_json::json!(["FINISHED"]), "{what}");
    assert_eq!(seen["object_type"], "VOLUME", "{what}");
    assert_eq!((seen["loaded"].as_bool(), seen["error"].as_str()), (Some(true), Some("")), "{what}");
    let grids = seen["grids"].as_array().unwrap();
    let kinds: Vec<(&str, &str, u64)> = grids
        .iter()
        .map(|g| (g["name"].as_str().unwrap(), g["data_type"].as_str().unwrap(), g["channels"].as_u64().unwrap()))
        .collect();
    assert_eq!(kinds, [("density", "FLOAT", 1), ("temperature", "FLOAT", 1), ("vel", "VECTOR_FLOAT", 3)], "{what}");
    let (h, o) = (v.transform.voxel_size, v.transform.origin);
    for g in grids {
        let m: Vec<Vec<f64>> = serde_json::from_value(g["matrix"].clone()).unwrap();
        for r in 0..3 {
            for c in 0..3 {
                let want = if r == c { h } else { 0.0 };
                assert!((m[r][c] - want).abs() < 1e-7, "{what} {}: matrix {m:?}", g["name"]);
            }
            assert!((m[r][3] - o[r]).abs() < 1e-7, "{what} {}: translation {m:?}", g["name"]);
        }
    }
    // World bounds: around the active bricks' voxels, within a voxel (Blender pads by half a
    // voxel for the cells' extent).
    let coords = v.topology.coords();
    let lo = coords.iter().fold(IVec3::MAX, |a, c| a.min(*c * 8));
    let hi = coords.iter().fold(IVec3::MIN, |a, c| a.max(*c * 8 + 7));
    let bounds: [[f64; 3]; 2] = serde_json::from_value(seen["bounds"].clone()).unwrap();
    for a in 0..3 {
        let (want_lo, want_hi) = (o[a] + f64::from(lo[a]) * h, o[a] + f64::from(hi[a]) * h);
        assert!((bounds[0][a] - want_lo).abs() <= h + 1e-6, "{what} axis {a}: low {} vs {want_lo}", bounds[0][a]);
        assert!((bounds[1][a] - want_hi).abs() <= h + 1e-6, "{what} axis {a}: high {} vs {want_hi}", bounds[1][a]);
    }
}

#[test]
#[ignore = "needs Blender's bpy wheel (PYROGRAPH_BPY_PYTHON; .ci/run installs it into target/bpy-venv)"]
fn blender_imports_a_cache_frame_as_a_volume_object_with_its_grids() {
    let dir = tempfile::tempdir().unwrap();
    let v = frame(0);
    for (half, compression) in [(false, Compression::None), (true, Compression::Zip)] {
        let path = dir.path().join(format!("fire_sim_{half}.0001.vdb"));
        std::fs::write(&path, write_volume(&v, &WriteOptions { half, compression, ..WriteOptions::default() }).unwrap()).unwrap();
        let seen = blender(&[path]);
        assert_frame(&seen, &v, &format!("half {half}"));
        assert_eq!(seen["is_sequence"], false);
        println!("Blender {}: half {half}: {}", seen["blender"], seen["grids"]);
    }
    // A numbered cache, as `pyrograph simulate` writes it, imports as one animated volume.
    let seq: Vec<PathBuf> = (1..=3)
        .map(|f| {
            let path = dir.path().join(format!("fire_sim.{f:04}.vdb"));
            std::fs::write(&path, write_volume(&frame(f - 1), &WriteOptions::default()).unwrap()).unwrap();
            path
        })
        .collect();
    let seen = blender(&seq);
    assert_frame(&seen, &frame(0), "sequence");
    assert_eq!((seen["is_sequence"].as_bool(), seen["frame_duration"].as_u64()), (Some(true), Some(3)));
}
