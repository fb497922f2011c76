//! The sparse grid: active 8³ bricks ([`topology`]), the `Volume` value of named fields on them
//! ([`value`]), and reading fields between voxels ([`sample`]) and around a brick ([`halo`]).

pub mod halo;
pub mod sample;
pub mod topology;
pub mod value;

pub use topology::{DIM, NONE, Topology, VOXELS, brick_of, remap, slot, voxel};
pub use value::{Field, FieldData, SimStats, Transform, Volume};
