//! Writing a volume as an OpenVDB file: one grid per chosen field, every brick a leaf with all
//! its voxels active, masks and values laid out as OpenVDB 10 writes them.

use glam::IVec3;
use rayon::prelude::*;

use super::bytes::Writer;
use super::tree::{layout, vdb_index};
use super::{COMPRESS_ACTIVE_MASK, COMPRESS_ZIP, FILE_VERSION, MAGIC, VdbError, codec};
use crate::grid::{Field, FieldData, VOXELS, Volume};

/// How value arrays are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// As they are.
    None,
    /// zlib, each leaf's values on their own (any OpenVDB build reads it).
    Zip,
}

/// What to write.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteOptions {
    /// The fields, by name, in file order; every field of the volume when empty.
    pub fields: Vec<String>,
    /// Scalar and vector values as 16-bit halves (`…_HalfFloat` grids).
    pub half: bool,
    /// How value arrays are stored.
    pub compression: Compression,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions { fields: Vec::new(), half: false, compression: Compression::None }
    }
}

/// File metadata keys holding what a `Volume` knows beyond its grids (so a cache read back is the
/// same value).
pub const META_TIME: &str = "pyrograph_time";
/// The frame's sub-steps.
pub const META_SUBSTEPS: &str = "pyrograph_substeps";
/// The frame's largest divergence.
pub const META_DIVERGENCE: &str = "pyrograph_max_divergence";
/// The frame's conjugate-gradient iterations.
pub const META_ITERATIONS: &str = "pyrograph_pressure_iterations";

/// The file's bytes. Errors name a field that is not in the volume.
pub fn write_volume(volume: &Volume, options: &WriteOptions) -> Result<Vec<u8>, VdbError> {
    let fields: Vec<&Field> = if options.fields.is_empty() {
        volume.fields.iter().collect()
    } else {
        options
            .fields
            .iter()
            .map(|n| {
                volume.field(n).ok_or_else(|| {
                    let have: Vec<&str> = volume.fields.iter().map(|f| f.name.as_str()).collect();
                    VdbError::Invalid(format!("the volume has no field '{n}' (it has {})", have.join(", ")))
                })
            })
            .collect::<Result<_, _>>()?
    };
    let mut w = Writer::default();
    w.bytes(&MAGIC);
    w.u32(FILE_VERSION);
    w.u32(10);
    w.u32(0);
    w.u8(1); // grid offsets
    w.bytes(b"00000000-0000-4000-8000-000000000000");
    // File metadata, sorted by name as OpenVDB writes it.
    w.u32(4);
    meta(&mut w, META_DIVERGENCE, "double", &f64::from(volume.stats.max_divergence).to_le_bytes());
    meta(&mut w, META_ITERATIONS, "int32", &(volume.stats.pressure_iterations as i32).to_le_bytes());
    meta(&mut w, META_SUBSTEPS, "int32", &(volume.stats.substeps as i32).to_le_bytes());
    meta(&mut w, META_TIME, "double", &volume.time.to_le_bytes());
    w.i32(fields.len() as i32);
    for f in fields {
        grid(&mut w, volume, f, options);
    }
    Ok(w.buf)
}

fn meta(w: &mut Writer, name: &str, ty: &str, payload: &[u8]) {
    w.string(name);
    w.string(ty);
    w.u32(payload.len() as u32);
    w.bytes(payload);
}

fn grid(w: &mut Writer, volume: &Volume, field: &Field, options: &WriteOptions) {
    let vector = matches!(field.data, FieldData::Vector(_));
    let base = if vector { "Tree_vec3s_5_4_3" } else { "Tree_float_5_4_3" };
    w.string(&field.name);
    w.string(&if options.half { format!("{base}_HalfFloat") } else { base.to_string() });
    w.string("");
    let positions = w.buf.len();
    w.i64(0);
    w.i64(0);
    w.i64(0);
    w.patch_i64(positions, w.buf.len() as i64);
    let flags = COMPRESS_ACTIVE_MASK | if options.compression == Compression::Zip { COMPRESS_ZIP } else { 0 };
    w.u32(flags);
    grid_metadata(w, volume, field, options, vector);
    transform(w, volume);
    let top = &volume.topology;
    let origins: Vec<IVec3> = top.coords().iter().map(|c| *c * 8).collect();
    let tree = layout(&origins);
    let comps = if vector { 3 } else { 1 };
    // Topology: the root (background 0, no tiles), then each 5-node and 4-node's masks and their
    // empty value arrays, then each leaf's mask.
    w.u32(1);
    (0..comps).for_each(|_| w.f32(0.0));
    w.u32(0);
    w.u32(tree.len() as u32);
    let empty_values = |w: &mut Writer| {
        w.u8(0);
        if options.compression == Compression::Zip && !options.half {
            w.i64(0);
        }
    };
    for (o5, n4s) in &tree {
        w.i32(o5.0);
        w.i32(o5.1);
        w.i32(o5.2);
        mask(w, 32768, n4s.keys().copied());
        w.bytes(&[0; 4096]);
        empty_values(w);
        for leaves in n4s.values() {
            mask(w, 4096, leaves.keys().copied());
            w.bytes(&[0; 512]);
            empty_values(w);
            (0..leaves.len()).for_each(|_| w.bytes(&[0xff; 64]));
        }
    }
    w.patch_i64(positions + 8, w.buf.len() as i64);
    // Buffers: each leaf's mask again, "no inactive values", and its 512 values in OpenVDB order.
    let order: Vec<usize> = tree.values().flat_map(|n4| n4.values().flat_map(|l| l.values().copied())).collect();
    let leaves: Vec<Vec<u8>> = order.par_iter().map(|b| leaf_values(field, *b, options)).collect();
    for l in leaves {
        w.bytes(&[0xff; 64]);
        w.u8(0);
        w.bytes(&l);
    }
    w.patch_i64(positions + 16, w.buf.len() as i64);
}

fn grid_metadata(w: &mut Writer, volume: &Volume, field: &Field, options: &WriteOptions, vector: bool) {
    let (lo, hi) = volume.topology.voxel_bounds().unwrap_or((IVec3::splat(i32::MAX), IVec3::splat(i32::MIN)));
    let class = if field.name == "density" { "fog volume" } else { "unknown" };
    let compression = if options.compression == Compression::Zip { "zip + active values" } else { "active values" };
    let mut entries: Vec<(&str, &str, Vec<u8>)> = vec![
        ("class", "string", class.as_bytes().to_vec()),
        ("file_bbox_max", "vec3i", hi.to_array().iter().flat_map(|v| v.to_le_bytes()).collect()),
        ("file_bbox_min", "vec3i", lo.to_array().iter().flat_map(|v| v.to_le_bytes()).collect()),
        ("file_compression", "string", compression.as_bytes().to_vec()),
        ("file_voxel_count", "int64", (volume.topology.voxels() as i64).to_le_bytes().to_vec()),
        ("name", "string", field.name.as_bytes().to_vec()),
    ];
    if options.half {
        entries.push(("is_saved_as_half_float", "bool", vec![1]));
    }
    if vector {
        entries.push(("vector_type", "string", b"contravariant relative".to_vec()));
    }
    entries.sort_by(|a, b| a.0.cmp(b.0));
    w.u32(entries.len() as u32);
    for (name, ty, payload) in entries {
        meta(w, name, ty, &payload);
    }
}

/// `UniformScaleTranslateMap`: translation, scale, voxel size, 1/scale, 1/scale², 1/(2 scale).
fn transform(w: &mut Writer, volume: &Volume) {
    let (t, s) = (volume.transform.origin, volume.transform.voxel_size);
    w.string("UniformScaleTranslateMap");
    t.iter().for_each(|v| w.f64(*v));
    for v in [s, s.abs(), 1.0 / s, 1.0 / (s * s), 0.5 / s] {
        (0..3).for_each(|_| w.f64(v));
    }
}

/// A node mask of `bits` bits with `set` on.
fn mask(w: &mut Writer, bits: usize, set: impl Iterator<Item = usize>) {
    let mut words = vec![0u64; bits / 64];
    for s in set {
        words[s >> 6] |= 1 << (s & 63);
    }
    words.iter().for_each(|x| w.bytes(&x.to_le_bytes()));
}

/// Brick `b`'s values in OpenVDB order, as floats or halves, zlib-compressed if asked (with the
/// size prefix, negative when stored raw because compression did not help).
fn leaf_values(field: &Field, b: usize, options: &WriteOptions) -> Vec<u8> {
    let mut raw = Vec::with_capacity(VOXELS * 12);
    let mut push = |v: f32| {
        if options.half {
            raw.extend(half::f16::from_f32(v).to_le_bytes());
        } else {
            raw.extend(v.to_le_bytes());
        }
    };
    for n in 0..VOXELS {
        let i = b * VOXELS + vdb_index(n);
        match &field.data {
            FieldData::Scalar(v) => push(v[i]),
            FieldData::Vector(v) => v[i].iter().for_each(|c| push(*c)),
        }
    }
    if options.compression == Compression::None {
        return raw;
    }
    let z = codec::zip(&raw);
    let mut out = Vec::with_capacity(z.len().min(raw.len()) + 8);
    if z.len() < raw.len() {
        out.extend((z.len() as i64).to_le_bytes());
        out.extend(z);
    } else {
        out.extend((-(raw.len() as i64)).to_le_bytes());
        out.extend(raw);
    }
    out
}
