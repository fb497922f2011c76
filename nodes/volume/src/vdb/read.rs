//! Reading an OpenVDB file into a volume: every float, double, half and vec3 grid, whatever
//! compression OpenVDB wrote it with, active tiles expanded into bricks; the grids' bricks are
//! united into one set of bricks (a grid lacking a brick reads as its background there). Every
//! count is checked against the bytes left and the voxel budget before anything is allocated.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::IVec3;

use super::bytes::Reader;
use super::tree::{slot_xyz, vdb_index};
use super::write::{META_DIVERGENCE, META_ITERATIONS, META_SUBSTEPS, META_TIME};
use super::{COMPRESS_ACTIVE_MASK, COMPRESS_BLOSC, COMPRESS_ZIP, MAGIC, VdbError, codec};
use crate::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS, Volume, brick_of};

/// What a read may hold.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Most active voxels (over the union of the grids' bricks).
    pub max_voxels: u64,
}

/// One grid's values per brick (`components` floats per voxel, in brick order).
struct Grid {
    name: String,
    components: usize,
    transform: Transform,
    bricks: HashMap<IVec3, Vec<f32>>,
    background: [f32; 3],
}

/// A value type of a grid: components and bytes per component in the file.
#[derive(Clone, Copy)]
struct Kind {
    components: usize,
    /// 4 (float), 8 (double).
    width: usize,
    /// Values stored as 16-bit halves.
    half: bool,
}

impl Kind {
    fn parse(ty: &str) -> Option<Kind> {
        let (base, half) = match ty.strip_suffix("_HalfFloat") {
            Some(b) => (b, true),
            None => (ty, false),
        };
        let (components, width) = match base {
            "Tree_float_5_4_3" => (1, 4),
            "Tree_double_5_4_3" => (1, 8),
            "Tree_vec3s_5_4_3" => (3, 4),
            "Tree_vec3d_5_4_3" => (3, 8),
            _ => return None,
        };
        Some(Kind { components, width, half })
    }

    /// Bytes of one value at full precision (backgrounds, tiles, inactive values).
    fn full(&self) -> usize {
        self.components * self.width
    }

    /// Bytes of one value in a value array.
    fn stored(&self) -> usize {
        if self.half { self.components * 2 } else { self.full() }
    }

    fn value(&self, r: &mut Reader) -> Result<[f32; 3], VdbError> {
        let mut v = [0.0; 3];
        for c in v.iter_mut().take(self.components) {
            *c = if self.width == 8 { r.f64()? as f32 } else { r.f32()? };
        }
        Ok(v)
    }
}

/// The volume in OpenVDB file `data`. Grids of other value types (int, bool, points) are skipped
/// when the file lets them be (it has grid offsets) and named in `skipped`.
pub fn read_volume(data: &[u8], options: &ReadOptions, skipped: &mut Vec<String>) -> Result<Volume, VdbError> {
    let mut r = Reader::new(data);
    if r.bytes(8)? != MAGIC {
        return Err(VdbError::Invalid("not an OpenVDB file (its first bytes are not the OpenVDB magic number)".into()));
    }
    let version = r.u32()?;
    if !(222..=225).contains(&version) {
        return Err(VdbError::Unsupported(format!(
            "OpenVDB file format version {version}; pyrograph reads versions 222 to 225 (OpenVDB 3.1 and later)"
        )));
    }
    let (_major, _minor) = (r.u32()?, r.u32()?);
    let offsets = r.u8()? != 0;
    r.bytes(36)?;
    r.what = "the file metadata".into();
    let file_meta = metadata(&mut r)?;
    r.what = "the grid count".into();
    let count = r.count(36, "grids")?;
    let mut grids: Vec<Grid> = Vec::new();
    let mut seen = HashSet::new();
    for g in 0..count {
        r.what = format!("grid {g}'s descriptor");
        let unique = r.string(1 << 16)?;
        let ty = r.string(1 << 16)?;
        let parent = r.string(1 << 16)?;
        let (grid_pos, _block_pos, end_pos) = (r.i64()?, r.i64()?, r.i64()?);
        let name = unique.split('\u{1e}').next().unwrap_or_default().to_string();
        if offsets && (grid_pos as u64 != r.pos() as u64 || end_pos < grid_pos || end_pos as u64 > data.len() as u64) {
            return Err(VdbError::Invalid(format!(
                "grid '{name}' declares its data at bytes {grid_pos}–{end_pos}, outside the file"
            )));
        }
        let Some(kind) = Kind::parse(&ty) else {
            if offsets {
                skipped.push(format!("{name} ({ty})"));
                r.seek(end_pos as u64)?;
                continue;
            }
            return Err(VdbError::Unsupported(format!(
                "grid '{name}' is a {ty} grid; pyrograph reads float, double and vec3 grids"
            )));
        };
        r.what = format!("grid '{name}'");
        let grid = read_grid(&mut r, &name, kind, &parent, &grids, options, &mut seen)?;
        grids.push(grid);
        if offsets {
            r.seek(end_pos as u64)?;
        }
    }
    assemble(grids, &file_meta)
}

/// Reads one grid from its compression word to the end of its buffers.
fn read_grid(
    r: &mut Reader,
    name: &str,
    kind: Kind,
    parent: &str,
    grids: &[Grid],
    options: &ReadOptions,
    seen: &mut HashSet<IVec3>,
) -> Result<Grid, VdbError> {
    let flags = r.u32()?;
    if flags & !7 != 0 {
        return Err(VdbError::Invalid(format!("grid '{name}' has unknown compression flags {flags:#x}")));
    }
    let meta = metadata(r)?;
    let half = match meta.get("is_saved_as_half_float") {
        Some(Meta::Bool(b)) => *b,
        _ => kind.half,
    };
    let kind = Kind { half, ..kind };
    let transform = read_transform(r, name)?;
    if !parent.is_empty() {
        let p = grids.iter().find(|g| g.name == parent.split('\u{1e}').next().unwrap_or_default());
        let p = p.ok_or_else(|| {
            VdbError::Invalid(format!("grid '{name}' shares the tree of '{parent}', which comes before it nowhere"))
        })?;
        return Ok(Grid {
            name: name.into(),
            components: p.components,
            transform,
            bricks: p.bricks.clone(),
            background: p.background,
        });
    }
    let mut grid =
        Grid { name: name.into(), components: kind.components, transform, bricks: HashMap::new(), background: [0.0; 3] };
    let tree = TreeReader { kind, flags, name, max_voxels: options.max_voxels };
    tree.read(r, &mut grid, seen)?;
    Ok(grid)
}

/// A metadata value pyrograph reads (others are skipped by their size).
#[derive(Debug, PartialEq)]
enum Meta {
    Bool(bool),
    Int(i64),
    Float(f64),
    Other,
}

fn metadata(r: &mut Reader) -> Result<HashMap<String, Meta>, VdbError> {
    let n = r.count(12, "metadata entries")?;
    let mut out = HashMap::new();
    for _ in 0..n {
        let name = r.string(1 << 16)?;
        let ty = r.string(1 << 16)?;
        let size = r.u32()? as usize;
        let payload = r.bytes(size)?;
        let fixed = |want: usize| {
            if size == want {
                Ok(())
            } else {
                Err(VdbError::Invalid(format!("metadata '{name}' of type {ty} is {size} bytes, not {want}")))
            }
        };
        let value = match ty.as_str() {
            "bool" => {
                fixed(1)?;
                Meta::Bool(payload[0] != 0)
            }
            "int32" => {
                fixed(4)?;
                Meta::Int(i64::from(i32::from_le_bytes([payload[0], payload[1], payload[2], payload[3]])))
            }
            "int64" => {
                fixed(8)?;
                Meta::Int(i64::from_le_bytes(payload.try_into().unwrap_or_default()))
            }
            "float" => {
                fixed(4)?;
                Meta::Float(f64::from(f32::from_le_bytes([payload[0], payload[1], payload[2], payload[3]])))
            }
            "double" => {
                fixed(8)?;
                Meta::Float(f64::from_le_bytes(payload.try_into().unwrap_or_default()))
            }
            _ => Meta::Other,
        };
        out.insert(name, value);
    }
    Ok(out)
}

/// The grid's transform as a voxel size and origin; maps that rotate, shear or scale unevenly are
/// refused (a volume's voxels are cubes on the world axes).
fn read_transform(r: &mut Reader, name: &str) -> Result<Transform, VdbError> {
    let map = r.string(256)?;
    let mut doubles = |n: usize| (0..n).map(|_| r.f64()).collect::<Result<Vec<f64>, _>>();
    let (scale, origin) = match map.as_str() {
        "TranslationMap" => ([1.0; 3], doubles(3)?),
        "ScaleMap" | "UniformScaleMap" => {
            let v = doubles(15)?;
            ([v[0], v[1], v[2]], vec![0.0; 3])
        }
        "ScaleTranslateMap" | "UniformScaleTranslateMap" => {
            let v = doubles(18)?;
            ([v[3], v[4], v[5]], v[0..3].to_vec())
        }
        "AffineMap" => {
            let m = doubles(16)?;
            let off = [m[1], m[2], m[4], m[6], m[8], m[9]];
            if off.iter().any(|v| *v != 0.0) || m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 {
                return Err(VdbError::Unsupported(format!(
                    "grid '{name}' is rotated or sheared; pyrograph reads axis-aligned grids"
                )));
            }
            ([m[0], m[5], m[10]], vec![m[12], m[13], m[14]])
        }
        other => {
            return Err(VdbError::Unsupported(format!(
                "grid '{name}' has a {other} transform; pyrograph reads linear, axis-aligned ones"
            )));
        }
    };
    let s = scale[0];
    if !(s.is_finite() && s > 0.0)
        || scale.iter().any(|v| (v - s).abs() > 1e-9 * s.abs())
        || origin.iter().any(|v| !v.is_finite())
    {
        return Err(VdbError::Unsupported(format!(
            "grid '{name}' has voxels of size {scale:?} at {origin:?}; pyrograph reads cubic, positive voxels"
        )));
    }
    Ok(Transform { voxel_size: s, origin: [origin[0], origin[1], origin[2]] })
}

/// Reads a grid's tree.
struct TreeReader<'a> {
    kind: Kind,
    flags: u32,
    name: &'a str,
    max_voxels: u64,
}

/// A node mask as words.
fn read_mask(r: &mut Reader, bits: usize) -> Result<Vec<u64>, VdbError> {
    let b = r.bytes(bits / 8)?;
    Ok(b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default())).collect())
}

fn bit(mask: &[u64], i: usize) -> bool {
    mask[i >> 6] >> (i & 63) & 1 == 1
}

fn ones(mask: &[u64]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, word)| (0..64).filter(move |b| word >> b & 1 == 1).map(move |b| w * 64 + b))
}

impl TreeReader<'_> {
    /// Admits the bricks of a `span`³ region at `origin` (a leaf: 8) into the union of every
    /// grid's bricks, refusing before anything is allocated when the union would outgrow the budget.
    fn admit(&self, seen: &mut HashSet<IVec3>, origin: IVec3, span: i32) -> Result<(), VdbError> {
        let per = span / 8;
        let region = (per as u64).pow(3);
        let over = |n: u64| n.saturating_mul(VOXELS as u64) > self.max_voxels;
        if over(seen.len() as u64 + region) {
            let new = if region <= 4096 {
                (0..region as i32)
                    .filter(|k| !seen.contains(&(brick_of(origin) + IVec3::new(k % per, (k / per) % per, k / (per * per)))))
                    .count() as u64
            } else {
                region
            };
            let needed = (seen.len() as u64 + new).saturating_mul(VOXELS as u64);
            if over(seen.len() as u64 + new) {
                return Err(VdbError::TooBig(format!(
                    "grid '{}' makes the volume hold {needed} active voxels, over the limit of {}; {}",
                    self.name,
                    self.max_voxels,
                    pyrograph_core::limits::raise_hint("--max-voxels", "PYROGRAPH_MAX_VOXELS", needed.max(self.max_voxels * 2))
                )));
            }
        }
        for k in 0..region as i32 {
            seen.insert(brick_of(origin) + IVec3::new(k % per, (k / per) % per, k / (per * per)));
        }
        Ok(())
    }

    fn read(&self, r: &mut Reader, grid: &mut Grid, seen: &mut HashSet<IVec3>) -> Result<(), VdbError> {
        if r.u32()? != 1 {
            return Err(VdbError::Invalid(format!("grid '{}' does not have one value buffer", self.name)));
        }
        let bg = self.kind.value(r)?;
        grid.background = bg;
        let full = self.kind.full();
        let tiles = r.count(12 + full + 1, "root tiles")?;
        let children = r.count(12 + 8192 + 1, "root children")?;
        for _ in 0..tiles {
            let o = IVec3::new(r.i32()?, r.i32()?, r.i32()?);
            let v = self.kind.value(r)?;
            if r.u8()? != 0 {
                self.tile(grid, o, 4096, v, seen)?;
            }
        }
        let mut leaves = Vec::new();
        for _ in 0..children {
            let o5 = IVec3::new(r.i32()?, r.i32()?, r.i32()?);
            if o5 & IVec3::splat(4095) != IVec3::ZERO {
                return Err(VdbError::Invalid(format!("grid '{}' has a root child at {o5}, not a multiple of 4096", self.name)));
            }
            r.what = format!("the upper internal node at {o5} of grid '{}'", self.name);
            let (c5, v5) = (read_mask(r, 32768)?, read_mask(r, 32768)?);
            let vals = self.values(r, 32768, &v5, bg)?;
            for t in ones(&v5).filter(|t| !bit(&c5, *t)) {
                self.tile(grid, o5 + (slot_xyz(t, 5) * 128), 128, vals[t], seen)?;
            }
            for s5 in ones(&c5) {
                let o4 = o5 + (slot_xyz(s5, 5) * 128);
                r.what = format!("the lower internal node at {o4} of grid '{}'", self.name);
                let (c4, v4) = (read_mask(r, 4096)?, read_mask(r, 4096)?);
                let vals = self.values(r, 4096, &v4, bg)?;
                for t in ones(&v4).filter(|t| !bit(&c4, *t)) {
                    self.tile(grid, o4 + (slot_xyz(t, 4) * 8), 8, vals[t], seen)?;
                }
                for s4 in ones(&c4) {
                    r.what = format!("a leaf's mask in grid '{}'", self.name);
                    let mask = read_mask(r, 512)?;
                    let origin = o4 + (slot_xyz(s4, 4) * 8);
                    self.admit(seen, origin, 8)?;
                    leaves.push((origin, mask));
                }
            }
        }
        for (origin, mask) in leaves {
            r.what = format!("the leaf at {origin} of grid '{}'", self.name);
            if read_mask(r, 512)? != mask {
                return Err(VdbError::Invalid(format!("grid '{}': the leaf at {origin} has two different masks", self.name)));
            }
            let vals = self.values(r, 512, &mask, bg)?;
            let c = self.kind.components;
            let brick = grid.bricks.entry(brick_of(origin)).or_insert_with(|| vec![0.0; VOXELS * c]);
            for (n, v) in vals.iter().enumerate() {
                let i = vdb_index(n);
                brick[i * c..(i + 1) * c].copy_from_slice(&v[..c]);
            }
        }
        Ok(())
    }

    /// An active tile of `span`³ voxels at `origin`, as bricks.
    fn tile(&self, grid: &mut Grid, origin: IVec3, span: i32, v: [f32; 3], seen: &mut HashSet<IVec3>) -> Result<(), VdbError> {
        self.admit(seen, origin, span)?;
        let c = self.kind.components;
        let per = span / 8;
        for z in 0..per {
            for y in 0..per {
                for x in 0..per {
                    let b = brick_of(origin) + IVec3::new(x, y, z);
                    let brick = grid.bricks.entry(b).or_insert_with(|| vec![0.0; VOXELS * c]);
                    brick.chunks_exact_mut(c).for_each(|d| d.copy_from_slice(&v[..c]));
                }
            }
        }
        Ok(())
    }

    /// One value array (OpenVDB's `readCompressedValues`): `num` values with the active ones
    /// (`active`) read and the inactive ones rebuilt from the metadata byte.
    fn values(&self, r: &mut Reader, num: usize, active: &[u64], bg: [f32; 3]) -> Result<Vec<[f32; 3]>, VdbError> {
        let meta = r.u8()?;
        if meta > 6 {
            return Err(VdbError::Invalid(format!("{} has an unknown value layout {meta}", r.what)));
        }
        let neg = bg.map(|v| -v);
        let mut inact = [if meta == 0 { bg } else { neg }, bg];
        if matches!(meta, 2 | 4 | 5) {
            inact[0] = self.kind.value(r)?;
        }
        if meta == 5 {
            inact[1] = self.kind.value(r)?;
        }
        let select = if matches!(meta, 3..=5) { Some(read_mask(r, num)?) } else { None };
        let masked = self.flags & COMPRESS_ACTIVE_MASK != 0 && meta != 6;
        let k = if masked { active.iter().map(|w| w.count_ones() as usize).sum() } else { num };
        let data = self.data(r, k)?;
        let mut out = Vec::with_capacity(num);
        let mut next = 0;
        for i in 0..num {
            if !masked || bit(active, i) {
                out.push(data[next]);
                next += 1;
            } else {
                out.push(inact[usize::from(select.as_ref().is_some_and(|s| bit(s, i)))]);
            }
        }
        Ok(out)
    }

    /// `k` stored values, decompressed as the grid's flags say.
    fn data(&self, r: &mut Reader, k: usize) -> Result<Vec<[f32; 3]>, VdbError> {
        let bytes = k * self.kind.stored();
        if k == 0 && self.kind.half {
            return Ok(Vec::new());
        }
        let raw: Vec<u8> = if self.flags & (COMPRESS_BLOSC | COMPRESS_ZIP) != 0 {
            let n = r.i64()?;
            if n <= 0 {
                if n.unsigned_abs() != bytes as u64 {
                    return Err(VdbError::Invalid(format!(
                        "{} stores {} raw bytes where {bytes} are due",
                        r.what,
                        n.unsigned_abs()
                    )));
                }
                r.bytes(bytes)?.to_vec()
            } else {
                if n as u64 > r.left() as u64 {
                    return Err(VdbError::Truncated { at: r.pos(), what: r.what.clone() });
                }
                let chunk = r.bytes(n as usize)?;
                if self.flags & COMPRESS_BLOSC != 0 { codec::unblosc(chunk, bytes)? } else { codec::unzip(chunk, bytes)? }
            }
        } else {
            r.bytes(bytes)?.to_vec()
        };
        let c = self.kind.components;
        let step = self.kind.stored() / c;
        Ok(raw
            .chunks_exact(self.kind.stored())
            .map(|v| {
                let mut out = [0.0; 3];
                for (j, o) in out.iter_mut().enumerate().take(c) {
                    let b = &v[j * step..(j + 1) * step];
                    *o = match step {
                        2 => half::f16::from_le_bytes([b[0], b[1]]).to_f32(),
                        4 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                        _ => f64::from_le_bytes(b.try_into().unwrap_or_default()) as f32,
                    };
                }
                out
            })
            .collect())
    }
}

/// One volume of the grids: the union of their bricks, each grid a field (its background where it
/// lacks a brick); their transforms must agree.
fn assemble(grids: Vec<Grid>, meta: &HashMap<String, Meta>) -> Result<Volume, VdbError> {
    let Some(first) = grids.first() else {
        return Err(VdbError::Unsupported("the file holds no float, double or vec3 grid".into()));
    };
    let transform = first.transform;
    if let Some(g) = grids.iter().find(|g| g.transform != transform) {
        return Err(VdbError::Unsupported(format!(
            "grids '{}' and '{}' have different voxel sizes or origins ({:?} and {:?}); pyrograph holds a volume's fields on one grid",
            first.name, g.name, transform, g.transform
        )));
    }
    let top = Arc::new(Topology::new(grids.iter().flat_map(|g| g.bricks.keys().copied()).collect()));
    let mut fields: Vec<Field> = Vec::with_capacity(grids.len());
    for g in grids {
        let mut name = g.name.clone();
        let mut k = 1;
        while fields.iter().any(|f| f.name == name) {
            name = format!("{}[{k}]", g.name);
            k += 1;
        }
        let mut flat = vec![0.0f32; top.voxels() * g.components];
        for (b, c) in top.coords().iter().enumerate() {
            let dst = &mut flat[b * VOXELS * g.components..(b + 1) * VOXELS * g.components];
            match g.bricks.get(c) {
                Some(v) => dst.copy_from_slice(v),
                None => dst.chunks_exact_mut(g.components).for_each(|d| d.copy_from_slice(&g.background[..g.components])),
            }
        }
        let data = if g.components == 1 {
            FieldData::Scalar(flat)
        } else {
            FieldData::Vector(flat.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect())
        };
        fields.push(Field { name, data });
    }
    let float = |k: &str| match meta.get(k) {
        Some(Meta::Float(v)) => *v,
        _ => 0.0,
    };
    let int = |k: &str| match meta.get(k) {
        Some(Meta::Int(v)) => u32::try_from(*v).unwrap_or(0),
        _ => 0,
    };
    let stats = SimStats {
        substeps: int(META_SUBSTEPS),
        max_divergence: float(META_DIVERGENCE) as f32,
        pressure_iterations: int(META_ITERATIONS),
    };
    Ok(Volume { transform, topology: top, fields, time: float(META_TIME), stats })
}
