//! The value types the particle nodes own: wind fields (Perry 1994 §3.2.3), meshes and
//! spreading fires (§3.3–3.4). Particles themselves live in `pyrograph-render`, which draws them.

mod mesh;
mod wind;

pub use mesh::{CharMark, FlameRoot, Mesh, NO_NEIGHBOR, SpreadState};
pub use wind::{LargeWind, WindAnimation, WindField};
