//! The state of a fire and smoke simulation between sub-steps: the active bricks, the four
//! scalar fields, the staggered (MAC) velocity and the last pressure (the next solve's first
//! guess), and the `Volume` a frame shows of it.

use std::sync::Arc;

use pyrograph_core::stepping::Checkpoint;
use rayon::prelude::*;

use crate::grid::{Field, FieldData, NONE, SimStats, Topology, Transform, VOXELS, Volume, remap, slot};

/// Index of the smoke density in [`SimState::scalars`].
pub const DENSITY: usize = 0;
/// Index of the temperature (above ambient).
pub const TEMPERATURE: usize = 1;
/// Index of the unburnt fuel.
pub const FUEL: usize = 2;
/// Index of the flame (the visible reaction, fading after the fuel burns).
pub const FLAME: usize = 3;
/// The scalar fields' names, as OpenVDB files and DCCs expect them.
pub const NAMES: [&str; 4] = ["density", "temperature", "fuel", "flame"];

/// A fire and smoke simulation between sub-steps.
#[derive(Clone, Debug, PartialEq)]
pub struct SimState {
    /// The active bricks.
    pub top: Arc<Topology>,
    /// Density, temperature, fuel and flame, one value per voxel centre.
    pub scalars: [Vec<f32>; 4],
    /// Velocity on the staggered grid: `vel[a][v]` is component `a` on voxel `v`'s lower face
    /// across axis `a` (world units per second).
    pub vel: [Vec<f32>; 3],
    /// The pressure of the last projection, in the solver's units.
    pub pressure: Vec<f32>,
    /// Voxel edge in world units.
    pub voxel_size: f32,
    /// Simulation time in seconds.
    pub time: f64,
    /// What the frame that reached this state reported.
    pub stats: SimStats,
}

impl SimState {
    /// An empty simulation (no active brick) at time 0.
    pub fn new(voxel_size: f32) -> SimState {
        SimState {
            top: Arc::new(Topology::default()),
            scalars: Default::default(),
            vel: Default::default(),
            pressure: Vec::new(),
            voxel_size,
            time: 0.0,
            stats: SimStats::default(),
        }
    }

    /// Lays every field out on `top`: bricks kept keep their values, new bricks start empty
    /// and at rest, retired bricks are dropped.
    pub fn retopologize(&mut self, top: Topology) {
        if top == *self.top {
            return;
        }
        let old = &self.top;
        for f in self.scalars.iter_mut().chain(self.vel.iter_mut()) {
            *f = remap(old, &top, f, 0.0);
        }
        self.pressure = remap(old, &top, &self.pressure, 0.0);
        self.top = Arc::new(top);
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.top.voxels() * 4 * 8 + self.top.len() * 128
    }

    /// The velocity at every voxel centre: the mean of each component's two faces (the upper
    /// face is the next voxel's lower face; at the edge of the active bricks the lower face
    /// stands for both).
    pub fn centred_velocity(&self) -> Vec<[f32; 3]> {
        let top = &self.top;
        let mut out = vec![[0.0f32; 3]; top.voxels()];
        out.par_chunks_mut(VOXELS).enumerate().for_each(|(b, o)| {
            for (i, v) in o.iter_mut().enumerate() {
                for (a, c) in v.iter_mut().enumerate() {
                    let lower = self.vel[a][b * VOXELS + i];
                    let upper = upper_face(top, &self.vel[a], b, i, a).unwrap_or(lower);
                    *c = 0.5 * (lower + upper);
                }
            }
        });
        out
    }

    /// The volume this state shows: the four scalar fields and the centred velocity `vel`.
    pub fn snapshot(&self) -> Volume {
        let mut fields: Vec<Field> = NAMES
            .iter()
            .zip(&self.scalars)
            .map(|(n, d)| Field { name: n.to_string(), data: FieldData::Scalar(d.clone()) })
            .collect();
        fields.push(Field { name: "vel".into(), data: FieldData::Vector(self.centred_velocity()) });
        Volume {
            transform: Transform { voxel_size: f64::from(self.voxel_size), origin: [0.0; 3] },
            topology: self.top.clone(),
            fields,
            time: self.time,
            stats: self.stats,
        }
    }
}

/// Component `a` on the upper face of brick `b`'s voxel `i` (the next voxel's lower face), if
/// that voxel is active.
#[inline(always)]
pub fn upper_face(top: &Topology, field: &[f32], b: usize, i: usize, a: usize) -> Option<f32> {
    let shift = 3 * a;
    let local = (i >> shift) & 7;
    if local < 7 {
        return Some(field[b * VOXELS + i + (1 << shift)]);
    }
    let d = [(a == 0) as i32, (a == 1) as i32, (a == 2) as i32];
    let nb = top.neighbors(b)[slot(d[0], d[1], d[2])];
    (nb != NONE).then(|| field[nb as usize * VOXELS + (i - (7 << shift))])
}

impl Checkpoint for SimState {
    fn bytes(&self) -> usize {
        SimState::bytes(self)
    }
}
