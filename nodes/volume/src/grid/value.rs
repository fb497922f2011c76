//! The `Volume` value: named scalar and vector fields over one sparse set of bricks, with the
//! transform from voxel index to world space. It is what `volume.simulate` gives per frame, what
//! `volume.load_vdb` reads and what the writers and renderers take.

use std::hash::Hash;
use std::sync::Arc;

use glam::{DVec3, IVec3, Vec3};
use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

use super::topology::{Topology, VOXELS};

/// Where voxels are in the world: voxel `i` has its centre at `origin + i · voxel_size` (OpenVDB's
/// convention: voxel centres at integer index coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Edge of a voxel in world units.
    pub voxel_size: f64,
    /// World position of the centre of voxel (0, 0, 0).
    pub origin: [f64; 3],
}

impl Transform {
    /// World position of index-space point `p`.
    pub fn to_world(&self, p: Vec3) -> Vec3 {
        (DVec3::from_array(self.origin) + p.as_dvec3() * self.voxel_size).as_vec3()
    }

    /// Index-space position of world point `w`.
    pub fn to_index(&self, w: Vec3) -> Vec3 {
        ((w.as_dvec3() - DVec3::from_array(self.origin)) / self.voxel_size).as_vec3()
    }

    /// The voxel containing world point `w`.
    pub fn voxel_at(&self, w: Vec3) -> IVec3 {
        self.to_index(w).round().as_ivec3()
    }
}

/// One named field's values, `VOXELS` per active brick in brick order.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldData {
    /// One float per voxel (density, temperature, fuel, flame).
    Scalar(Vec<f32>),
    /// Three floats per voxel (velocity, at voxel centres).
    Vector(Vec<[f32; 3]>),
}

impl FieldData {
    /// Floats per voxel.
    pub fn components(&self) -> usize {
        match self {
            FieldData::Scalar(_) => 1,
            FieldData::Vector(_) => 3,
        }
    }

    /// Voxels held.
    pub fn len(&self) -> usize {
        match self {
            FieldData::Scalar(v) => v.len(),
            FieldData::Vector(v) => v.len(),
        }
    }

    /// Holds nothing.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A named field.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// The name DCCs expect (`density`, `temperature`, `fuel`, `flame`, `vel`).
    pub name: String,
    /// The values.
    pub data: FieldData,
}

/// What a simulation reported for the frame it made (none for a volume read from a file).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SimStats {
    /// Sub-steps taken to reach this frame from the one before.
    pub substeps: u32,
    /// The largest |∇·u| (1/s) over the fluid voxels after the last sub-step's projection.
    pub max_divergence: f32,
    /// Conjugate-gradient iterations of the last sub-step's pressure solve.
    pub pressure_iterations: u32,
}

/// Fire and smoke at one moment on a sparse grid of 8³ bricks (the volume family's value).
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Index to world.
    pub transform: Transform,
    /// The active bricks every field is laid out on.
    pub topology: Arc<Topology>,
    /// The fields, in a fixed order.
    pub fields: Vec<Field>,
    /// Time in seconds.
    pub time: f64,
    /// What the simulation reported for this frame.
    pub stats: SimStats,
}

impl Volume {
    /// A volume with no active brick and no field.
    pub fn empty(voxel_size: f64) -> Volume {
        Volume {
            transform: Transform { voxel_size, origin: [0.0; 3] },
            topology: Arc::new(Topology::default()),
            fields: Vec::new(),
            time: 0.0,
            stats: SimStats::default(),
        }
    }

    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// The scalar field called `name`.
    pub fn scalar(&self, name: &str) -> Option<&[f32]> {
        match &self.field(name)?.data {
            FieldData::Scalar(v) => Some(v),
            FieldData::Vector(_) => None,
        }
    }

    /// The vector field called `name`.
    pub fn vector(&self, name: &str) -> Option<&[[f32; 3]]> {
        match &self.field(name)?.data {
            FieldData::Vector(v) => Some(v),
            FieldData::Scalar(_) => None,
        }
    }

    /// The value of scalar field `data` at voxel `v` (0 outside the active bricks).
    pub fn scalar_at(&self, data: &[f32], v: IVec3) -> f32 {
        let Some(b) = self.topology.find(super::topology::brick_of(v)) else { return 0.0 };
        let l = v & IVec3::splat(7);
        data[b as usize * VOXELS + super::topology::voxel(l.x as usize, l.y as usize, l.z as usize)]
    }

    /// Sum of a scalar field over every voxel (its mass, in field units × voxels).
    pub fn total(&self, name: &str) -> f64 {
        self.scalar(name).map_or(0.0, |v| v.iter().map(|x| f64::from(*x)).sum())
    }

    /// The density-weighted centre of a scalar field, in world space (`None` when it is all 0).
    pub fn centroid(&self, name: &str) -> Option<Vec3> {
        let data = self.scalar(name)?;
        let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0f64);
        for (b, c) in self.topology.coords().iter().enumerate() {
            let base = (*c * 8).as_dvec3();
            for (i, v) in data[b * VOXELS..(b + 1) * VOXELS].iter().enumerate() {
                if *v > 0.0 {
                    let l = glam::DVec3::new((i & 7) as f64, ((i >> 3) & 7) as f64, (i >> 6) as f64);
                    sum += (base + l) * f64::from(*v);
                    weight += f64::from(*v);
                }
            }
        }
        (weight > 0.0).then(|| self.transform.to_world((sum / weight).as_vec3()))
    }

    /// The index box (inclusive) of the voxels whose scalar field `name` exceeds `threshold`:
    /// how tall a smoke column is, in voxels.
    pub fn field_bounds(&self, name: &str, threshold: f32) -> Option<(IVec3, IVec3)> {
        let data = self.scalar(name)?;
        let mut bounds: Option<(IVec3, IVec3)> = None;
        for (b, c) in self.topology.coords().iter().enumerate() {
            for (i, v) in data[b * VOXELS..(b + 1) * VOXELS].iter().enumerate() {
                if *v > threshold {
                    let p = *c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
                    bounds = Some(bounds.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
                }
            }
        }
        bounds
    }
}

impl ValueType for Volume {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "Volume",
        doc: "Fire and smoke on a sparse grid of 8³ bricks: density, temperature, fuel, flame and velocity (Fedkiw, Stam & Jensen 2001).",
        color: [170, 130, 230],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.transform.voxel_size.to_bits(), self.transform.origin.map(f64::to_bits), self.time.to_bits()).hash(h);
        self.topology.coords().iter().for_each(|c| c.to_array().hash(h));
        for f in &self.fields {
            f.name.hash(h);
            match &f.data {
                FieldData::Scalar(v) => hash_f32s(h, v),
                FieldData::Vector(v) => v.iter().for_each(|x| hash_f32s(h, x)),
            }
        }
    }

    fn byte_size(&self) -> usize {
        self.fields.iter().map(|f| f.data.len() * f.data.components() * 4).sum::<usize>() + self.topology.len() * 128
    }

    fn summary(&self) -> String {
        let names: Vec<&str> = self.fields.iter().map(|f| f.name.as_str()).collect();
        format!(
            "Volume {} active voxels in {} bricks, voxel size {}, fields {}",
            self.topology.voxels(),
            self.topology.len(),
            self.transform.voxel_size,
            names.join(" ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::topology::voxel;

    #[test]
    fn field_bounds_cover_the_voxels_over_the_threshold_across_bricks() {
        let top = Topology::new(vec![IVec3::new(0, 0, 0), IVec3::new(0, 2, -1)]);
        let mut data = vec![0.0f32; top.voxels()];
        let (a, b) = (top.find(IVec3::new(0, 0, 0)).unwrap() as usize, top.find(IVec3::new(0, 2, -1)).unwrap() as usize);
        data[a * VOXELS + voxel(3, 1, 2)] = 0.5;
        data[b * VOXELS + voxel(5, 6, 7)] = 0.2;
        data[b * VOXELS + voxel(0, 7, 0)] = 0.01;
        let v = Volume {
            topology: Arc::new(top),
            fields: vec![Field { name: "density".into(), data: FieldData::Scalar(data) }],
            ..Volume::empty(0.1)
        };
        assert_eq!(v.field_bounds("density", 0.05), Some((IVec3::new(3, 1, -1), IVec3::new(5, 22, 2))));
        assert_eq!(v.field_bounds("density", 0.6), None);
        assert_eq!(v.field_bounds("fuel", 0.0), None);
    }
}
