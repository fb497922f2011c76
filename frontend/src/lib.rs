//! What every pyrograph front end (the CLI, the editor, the Python module) needs: the registry
//! of every node type, graph checks that probe inputs without cooking, the node reference, preset
//! libraries and preset cooking. Nothing here parses arguments, draws, or writes job bundles: those
//! belong to the front end that needs them.
#![deny(missing_docs)]

pub mod check;
pub mod plugins;
pub mod preset_cook;
pub mod preset_docs;
pub mod presets;
pub mod reference;
pub mod text;

pub use pyrograph_core as core;
pub use pyrograph_nodes_cloth as cloth;
pub use pyrograph_nodes_eigen as eigen;
pub use pyrograph_nodes_flame_model as flame_model;
pub use pyrograph_nodes_imaging as imaging;
pub use pyrograph_nodes_particles as particles;
pub use pyrograph_nodes_volume as volume;
pub use pyrograph_plugin as plugin;
pub use pyrograph_render as render;

/// A registry with every node type pyrograph ships.
pub fn registry() -> core::Registry {
    let mut r = core::Registry::with_builtins();
    imaging::register(&mut r);
    eigen::register(&mut r);
    particles::register(&mut r);
    cloth::register(&mut r);
    flame_model::register(&mut r);
    volume::register(&mut r);
    r
}
