//! pyrograph: a node-graph toolkit for procedural fire.
//!
//! This facade gathers every node family into one [`registry`], and holds what the CLI, the
//! examples and the benches share: the embedded demo graph, the node reference generator and the
//! evaluator benchmark graphs.
#![deny(missing_docs)]

pub mod bench;
pub mod check;
pub mod demo;
pub mod job;
pub mod look;
pub mod manifest;
pub mod preset_cook;
pub mod preset_docs;
pub mod presets;
pub mod reference;
pub mod wedge;

pub use pyrograph_core as core;
pub use pyrograph_nodes_cloth as cloth;
pub use pyrograph_nodes_eigen as eigen;
pub use pyrograph_nodes_flame_model as flame_model;
pub use pyrograph_nodes_imaging as imaging;
pub use pyrograph_nodes_particles as particles;
pub use pyrograph_render as render;

/// A registry with every node type pyrograph ships.
pub fn registry() -> core::Registry {
    let mut r = core::Registry::with_builtins();
    imaging::register(&mut r);
    eigen::register(&mut r);
    particles::register(&mut r);
    cloth::register(&mut r);
    flame_model::register(&mut r);
    r
}
