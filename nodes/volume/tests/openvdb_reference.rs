//! pyrograph's OpenVDB files against the reference library (OpenVDB 10 through Debian's
//! python3-openvdb, `tests/openvdb_check.py`): what pyrograph writes opens there with the same
//! grid names, types, voxel size, transform, active voxel count and every value, for float, half
//! and vec3 grids, stored plain or zlib-compressed; and what the library writes from numpy (Blosc
//! compressed, half, vec3, negative coordinates) reads here with the values it holds.

use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use glam::IVec3;
use pyrograph_nodes_volume::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS, Volume};
use pyrograph_nodes_volume::vdb::{Compression, ReadOptions, WriteOptions, read_volume, write_volume};
use serde_json::Value as Json;

const PYTHON: &str = "/usr/bin/python3";

fn check(args: &[&str]) -> Json {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/openvdb_check.py");
    let out = Command::new(PYTHON).arg(&script).args(args).output().expect("Debian's /usr/bin/python3 runs");
    assert!(out.status.success(), "openvdb_check.py {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("the script prints JSON")
}

fn volume() -> Volume {
    let top = Topology::new(vec![IVec3::new(0, 0, 0), IVec3::new(-1, 0, 2), IVec3::new(3, -3, 0), IVec3::new(600, 1, -1)]);
    let n = top.voxels();
    Volume {
        transform: Transform { voxel_size: 0.05, origin: [1.0, -2.5, 0.125] },
        topology: Arc::new(top),
        fields: vec![
            Field { name: "density".into(), data: FieldData::Scalar((0..n).map(|i| ((i * 37) % 101) as f32 / 100.0).collect()) },
            Field { name: "temperature".into(), data: FieldData::Scalar((0..n).map(|i| 3.25 - i as f32 * 0.5).collect()) },
            Field {
                name: "vel".into(),
                data: FieldData::Vector((0..n).map(|i| [i as f32 * 0.01, -1.5, (i % 7) as f32]).collect()),
            },
        ],
        time: 1.25,
        stats: SimStats::default(),
    }
}

/// Every voxel of `v`'s field `name` as (index, components).
fn voxels(v: &Volume, name: &str) -> Vec<(IVec3, Vec<f32>)> {
    let mut out = Vec::new();
    for (b, c) in v.topology.coords().iter().enumerate() {
        for i in 0..VOXELS {
            let ijk = *c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
            let value = match &v.field(name).unwrap().data {
                FieldData::Scalar(d) => vec![d[b * VOXELS + i]],
                FieldData::Vector(d) => d[b * VOXELS + i].to_vec(),
            };
            out.push((ijk, value));
        }
    }
    out.sort_by_key(|(p, _)| (p.x, p.y, p.z));
    out
}

fn json_voxels(grid: &Json) -> Vec<(IVec3, Vec<f32>)> {
    let mut out: Vec<(IVec3, Vec<f32>)> = grid["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            let r: Vec<f64> = row.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            (IVec3::new(r[0] as i32, r[1] as i32, r[2] as i32), r[3..].iter().map(|x| *x as f32).collect())
        })
        .collect();
    out.sort_by_key(|(p, _)| (p.x, p.y, p.z));
    out
}

#[test]
#[ignore = "needs Debian's python3-openvdb under /usr/bin/python3 (.ci/run installs it)"]
fn files_pyrograph_writes_open_in_openvdb_with_every_value() {
    let dir = tempfile::tempdir().unwrap();
    let v = volume();
    let cases = [(false, Compression::None), (true, Compression::None), (false, Compression::Zip), (true, Compression::Zip)];
    for (half, compression) in cases {
        let path = dir.path().join(format!("v_{half}_{compression:?}.vdb"));
        std::fs::write(&path, write_volume(&v, &WriteOptions { half, compression, ..WriteOptions::default() }).unwrap()).unwrap();
        let seen = check(&["dump", path.to_str().unwrap()]);
        let grids = seen["grids"].as_array().unwrap();
        let names: Vec<&str> = grids.iter().map(|g| g["name"].as_str().unwrap()).collect();
        assert_eq!(names, ["density", "temperature", "vel"], "half {half} {compression:?}");
        for g in grids {
            let name = g["name"].as_str().unwrap();
            let want_type = if name == "vel" { "vec3s" } else { "float" };
            assert_eq!((g["type"].as_str().unwrap(), g["half"].as_bool().unwrap()), (want_type, half), "{name}");
            assert_eq!(g["voxel_size"], serde_json::json!([0.05, 0.05, 0.05]), "{name}");
            assert_eq!(g["origin"], serde_json::json!([1.0, -2.5, 0.125]), "{name}");
            let w = g["world_111"].as_array().unwrap();
            assert!(
                (w[0].as_f64().unwrap() - 1.05).abs() < 1e-12 && (w[1].as_f64().unwrap() + 2.45).abs() < 1e-12,
                "{name}: {w:?}"
            );
            assert_eq!(g["active"].as_u64().unwrap(), v.topology.voxels() as u64, "{name}");
            let (theirs, ours) = (json_voxels(g), voxels(&v, name));
            assert_eq!(theirs.len(), ours.len(), "{name}");
            for ((p, a), (q, b)) in theirs.iter().zip(&ours) {
                assert_eq!(p, q, "{name}");
                let b: Vec<f32> = if half { b.iter().map(|x| half::f16::from_f32(*x).to_f32()).collect() } else { b.clone() };
                assert_eq!(a, &b, "{name} at {p}, half {half} {compression:?}");
            }
        }
        assert_eq!(grids[0]["class"].as_str().unwrap(), "fog volume");
    }
}

#[test]
#[ignore = "needs Debian's python3-openvdb under /usr/bin/python3 (.ci/run installs it)"]
fn files_openvdb_writes_from_numpy_read_in_pyrograph_with_every_value() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("numpy.vdb");
    let made = check(&["make", path.to_str().unwrap()]);
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 224, "the library's own file version");
    let v = read_volume(&bytes, &ReadOptions { max_voxels: 1 << 24 }, &mut Vec::new()).unwrap();
    assert_eq!(v.transform, Transform { voxel_size: 0.25, origin: [1.0, 2.0, 3.0] });
    for g in made["grids"].as_array().unwrap() {
        let name = g["name"].as_str().unwrap();
        let theirs = json_voxels(g);
        assert!(!theirs.is_empty(), "{name}");
        let ours: std::collections::HashMap<IVec3, Vec<f32>> = voxels(&v, name).into_iter().collect();
        for (p, a) in &theirs {
            assert_eq!(ours.get(p), Some(a), "{name} at {p}");
        }
        // Voxels the library does not hold as active read as its background, 0.
        let active: std::collections::HashSet<IVec3> = theirs.iter().map(|(p, _)| *p).collect();
        assert!(ours.iter().filter(|(p, _)| !active.contains(p)).all(|(_, v)| v.iter().all(|x| *x == 0.0)), "{name}");
        println!("{name}: {} active voxels from OpenVDB, all equal", theirs.len());
    }
    assert_eq!(v.fields.iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["density", "vel", "temperature"]);
}
