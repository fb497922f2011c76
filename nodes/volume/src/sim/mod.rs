//! Fire and smoke on sparse bricks (Fedkiw, Stam & Jensen 2001; Nguyen, Fedkiw & Jensen 2002):
//! the state ([`state`]), the parameters ([`params`]), each phase of a sub-step as a plain
//! function ([`emit`], [`advect`], [`combust`], [`forces`], [`pressure`] with [`multigrid`],
//! [`collide`]), the sub-step and frame ([`step`]), the stepping cache ([`cache`]) and the
//! `volume.simulate` node ([`node`]).

pub mod advect;
pub mod cache;
pub mod collide;
pub mod combust;
pub mod emit;
pub mod forces;
pub mod multigrid;
pub mod node;
pub mod params;
pub mod pressure;
pub mod state;
pub mod step;

pub use node::Simulate;
pub use params::{SimParams, StepParams};
pub use state::SimState;
pub use step::{Setup, SimError};

#[cfg(test)]
mod tests;
