//! pyrograph-nodes-imaging: image I/O, colour conversion, compositing and the Eigenfires
//! pre-processing chain (thesis ch. 3).
#![deny(missing_docs)]

pub mod auto_crop;
pub mod basic;
pub mod bloom;
pub mod color;
pub mod convert;
pub mod flipbook;
pub mod io;
pub mod levels;
pub mod masks;
pub mod preprocess;
pub mod procedural;
pub mod sheet;
pub mod smoke;
pub mod video;

use pyrograph_core::Registry;

/// Adds every imaging node type.
pub fn register(registry: &mut Registry) {
    io::register(registry);
    basic::register(registry);
    auto_crop::register(registry);
    masks::register(registry);
    preprocess::register(registry);
    procedural::register(registry);
    sheet::register(registry);
    color::register(registry);
    bloom::register(registry);
    smoke::register(registry);
    flipbook::register(registry);
    registry.declare::<levels::Levels>();
}
