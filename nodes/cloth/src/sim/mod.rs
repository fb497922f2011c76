//! Mass-spring flames (mass-spring flame project 2019 §Integration, §Internal Forces,
//! §External Forces; shear and bend springs after Provot 1995): the grid topology and the
//! per-flame state in structure-of-arrays form with the semi-implicit Euler stepper ([`model`]),
//! the parameters and their checks ([`cloth_params`]), the whole simulation with its check of the
//! stability limit ([`simulation`]), the stepping cache behind the clip ([`cache`]) and the
//! `cloth.mass_spring_flame` node ([`node`]).

pub mod cache;
pub mod cloth_params;
pub mod error;
pub mod model;
pub mod node;
pub mod simulation;

pub use cache::{CHECKPOINT_BUDGET, CHECKPOINT_EVERY, ClothSource, SNAPSHOT_BUDGET};
pub use cloth_params::ClothParams;
pub use error::ClothError;
pub use model::{FlameState, Topology, unit_random, wind_active};
pub use node::MassSpringFlame;
pub use simulation::{Simulation, check_step, grid_roots};

#[cfg(test)]
mod tests;
