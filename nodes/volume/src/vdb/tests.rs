//! Round trips through the writer and reader, and hostile files: truncated at every length,
//! bytes flipped, and sizes that would allocate far more than the file holds.

use std::sync::Arc;

use glam::IVec3;

use super::VdbError;
use super::read::{ReadOptions, read_volume};
use super::write::{Compression, WriteOptions, write_volume};
use crate::grid::{Field, FieldData, SimStats, Topology, Transform, Volume};

/// A volume over bricks on both sides of 0 and in two 5-nodes, with a float and a vector field.
pub(crate) fn sample_volume() -> Volume {
    let top = Topology::new(vec![IVec3::new(0, 0, 0), IVec3::new(-1, 0, 2), IVec3::new(1, -3, 0), IVec3::new(600, 1, -1)]);
    let n = top.voxels();
    let density: Vec<f32> = (0..n).map(|i| ((i * 37) % 101) as f32 / 100.0).collect();
    let temperature: Vec<f32> = (0..n).map(|i| -(i as f32) * 0.5 + 3.25).collect();
    let vel: Vec<[f32; 3]> = (0..n).map(|i| [i as f32 * 0.01, -1.5, (i % 7) as f32]).collect();
    Volume {
        transform: Transform { voxel_size: 0.05, origin: [1.0, -2.5, 0.125] },
        topology: Arc::new(top),
        fields: vec![
            Field { name: "density".into(), data: FieldData::Scalar(density) },
            Field { name: "temperature".into(), data: FieldData::Scalar(temperature) },
            Field { name: "vel".into(), data: FieldData::Vector(vel) },
        ],
        time: 1.25,
        stats: SimStats { substeps: 3, max_divergence: 0.0042, pressure_iterations: 11 },
    }
}

fn read(bytes: &[u8]) -> Result<Volume, VdbError> {
    read_volume(bytes, &ReadOptions { max_voxels: 1 << 24 }, &mut Vec::new())
}

#[test]
fn a_volume_written_as_float_reads_back_as_the_same_value() {
    let v = sample_volume();
    for compression in [Compression::None, Compression::Zip] {
        let bytes = write_volume(&v, &WriteOptions { compression, ..WriteOptions::default() }).unwrap();
        assert!(read(&bytes).unwrap() == v, "{compression:?}");
    }
}

#[test]
fn half_grids_read_back_within_half_precision_and_chosen_fields_only() {
    let v = sample_volume();
    let options = WriteOptions { fields: vec!["vel".into(), "density".into()], half: true, ..WriteOptions::default() };
    let back = read(&write_volume(&v, &options).unwrap()).unwrap();
    let names: Vec<&str> = back.fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["vel", "density"]);
    let (a, b) = (v.scalar("density").unwrap(), back.scalar("density").unwrap());
    assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() <= x.abs() / 1024.0 + 1e-7));
    let (a, b) = (v.vector("vel").unwrap(), back.vector("vel").unwrap());
    assert!(a.iter().zip(b).all(|(x, y)| (0..3).all(|k| (x[k] - y[k]).abs() <= x[k].abs() / 1024.0 + 1e-7)));
    let e = write_volume(&v, &WriteOptions { fields: vec!["smoke".into()], ..WriteOptions::default() }).unwrap_err();
    assert!(e.to_string().contains("no field 'smoke'") && e.to_string().contains("density"), "{e}");
}

#[test]
fn an_empty_volume_round_trips() {
    let v = Volume { fields: vec![Field { name: "density".into(), data: FieldData::Scalar(Vec::new()) }], ..Volume::empty(0.1) };
    assert!(read(&write_volume(&v, &WriteOptions::default()).unwrap()).unwrap() == v);
}

#[test]
fn every_truncation_is_an_error_and_never_a_panic() {
    let v = sample_volume();
    let bytes = write_volume(&v, &WriteOptions { compression: Compression::Zip, ..WriteOptions::default() }).unwrap();
    // Every length near the start, then a stride through the rest.
    let lengths = (0..bytes.len().min(400)).chain((400..bytes.len()).step_by(97));
    for n in lengths {
        assert!(read(&bytes[..n]).is_err(), "{n} of {} bytes read as a whole file", bytes.len());
    }
    let e = read(&bytes[..bytes.len() / 2]).unwrap_err();
    assert!(matches!(e, VdbError::Truncated { .. } | VdbError::Invalid(_)), "{e}");
}

#[test]
fn flipped_bytes_give_errors_or_values_never_panics() {
    let v = sample_volume();
    let bytes = write_volume(&v, &WriteOptions { compression: Compression::Zip, ..WriteOptions::default() }).unwrap();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..400 {
        let mut b = bytes.clone();
        for _ in 0..4 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let at = (state % b.len() as u64) as usize;
            b[at] ^= (state >> 40) as u8 | 1;
        }
        let _ = read(&b);
    }
}

#[test]
fn absurd_sizes_are_refused_before_allocating() {
    let v = sample_volume();
    let bytes = write_volume(&v, &WriteOptions::default()).unwrap();
    // The root's child count of the first grid, declared as 4 billion.
    let root = find(&bytes, b"UniformScaleTranslateMap") + 24 + 18 * 8 + 4 + 4 + 4;
    let mut b = bytes.clone();
    b[root..root + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = read(&b).unwrap_err().to_string();
    assert!(e.contains("root children") && e.contains("bytes left"), "{e}");
    // An active root tile: 4096³ voxels, over any budget (in a file without grid offsets, read
    // straight through).
    let mut b = bytes[..root - 4].to_vec();
    b[20] = 0;
    b.extend(1u32.to_le_bytes());
    b.extend(0u32.to_le_bytes());
    b.extend([0u8; 12]);
    b.extend(1.0f32.to_le_bytes());
    b.push(1);
    b.extend([0u8; 64]);
    let e = read(&b).unwrap_err();
    assert!(matches!(&e, VdbError::TooBig(m) if m.contains("over the limit") && m.contains("--max-voxels")), "{e}");
    // A grid count no file could hold.
    let mut b = bytes.clone();
    let count = 8 + 4 + 4 + 4 + 1 + 36;
    let meta_end = count + 4 + file_meta_len(&bytes[count + 4..]);
    b[meta_end..meta_end + 4].copy_from_slice(&i32::MAX.to_le_bytes());
    let e = read(&b).unwrap_err().to_string();
    assert!(e.contains("grids") && e.contains("bytes left"), "{e}");
    assert!(read(b"not a vdb file at all").unwrap_err().to_string().contains("not an OpenVDB file"));
}

fn find(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len()).position(|w| w == needle).expect("the writer wrote it")
}

/// Bytes of the file metadata entries after their count.
fn file_meta_len(b: &[u8]) -> usize {
    let mut at = 0;
    let word = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize;
    for _ in 0..4 {
        at += 4 + word(at);
        at += 4 + word(at);
        at += 4 + word(at);
    }
    at
}

#[test]
fn blosc_compressed_grids_with_inactive_values_read_like_openvdb() {
    // A hand-built file in the layout OpenVDB 10 writes by default (Blosc + active mask), one leaf
    // with two active voxels whose inactive values are the background: the spec's example.
    let mut f = Vec::new();
    f.extend(super::MAGIC);
    f.extend(224u32.to_le_bytes());
    f.extend(10u32.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    f.push(0);
    f.extend(b"00000000-0000-4000-8000-000000000000");
    f.extend(0u32.to_le_bytes());
    f.extend(1i32.to_le_bytes());
    let s = |f: &mut Vec<u8>, t: &str| {
        f.extend((t.len() as u32).to_le_bytes());
        f.extend(t.as_bytes());
    };
    s(&mut f, "density");
    s(&mut f, "Tree_float_5_4_3");
    s(&mut f, "");
    f.extend([0u8; 24]);
    f.extend(6u32.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    s(&mut f, "UniformScaleMap");
    for v in [0.5f64, 0.5, 0.5, 0.5, 0.5, 0.5, 2.0, 2.0, 2.0, 4.0, 4.0, 4.0, 1.0, 1.0, 1.0] {
        f.extend(v.to_le_bytes());
    }
    f.extend(1u32.to_le_bytes());
    f.extend(0.0f32.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    f.extend(1u32.to_le_bytes());
    f.extend([0u8; 12]);
    let empty_blosc = [2u8, 1, 0x33, 4, 0, 0, 0, 0, 1, 0, 0, 0, 16, 0, 0, 0];
    for bits in [32768usize, 4096] {
        let mut child = vec![0u8; bits / 8];
        child[0] = 1;
        f.extend(child);
        f.extend(vec![0u8; bits / 8]);
        f.push(0);
        f.extend(16i64.to_le_bytes());
        f.extend(empty_blosc);
    }
    let mut leaf = [0u8; 64];
    leaf[0] = 1;
    leaf[10] = 8;
    f.extend(leaf);
    f.extend(leaf);
    f.push(0);
    let data: Vec<u8> = [1.0f32, 0.5].iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut frame = vec![2u8, 1, 0x33, 4];
    frame.extend(8u32.to_le_bytes());
    frame.extend(8u32.to_le_bytes());
    frame.extend(24u32.to_le_bytes());
    frame.extend(&data);
    f.extend((frame.len() as i64).to_le_bytes());
    f.extend(frame);
    let v = read(&f).unwrap();
    assert_eq!(v.transform, Transform { voxel_size: 0.5, origin: [0.0; 3] });
    assert_eq!(v.topology.coords(), &[IVec3::ZERO]);
    let d = v.scalar("density").unwrap();
    assert_eq!((d[0], d[1 | (2 << 3) | (3 << 6)]), (1.0, 0.5));
    assert_eq!(d.iter().filter(|x| **x != 0.0).count(), 2);
    assert_eq!(v.scalar_at(d, IVec3::new(1, 2, 3)), 0.5);
}
