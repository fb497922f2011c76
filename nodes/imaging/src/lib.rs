//! pyrograph-nodes-imaging: image I/O, colour conversion, compositing and the Eigenfires
//! pre-processing chain (thesis ch. 3).
#![deny(missing_docs)]

pub mod auto_crop;
pub mod bloom;
pub mod color;
pub mod composite;
pub mod constant_color;
pub mod convert;
pub mod crop;
pub mod filters;
pub mod flipbook;
pub mod gray;
pub mod io;
pub mod levels;
pub mod masks;
pub mod preprocess;
pub mod procedural;
pub mod resize;
pub mod sheet;
pub mod size;
pub mod smoke;
pub mod time_range;
pub mod video;

#[cfg(test)]
mod testing;

use pyrograph_core::Registry;

/// Adds every imaging node type.
pub fn register(registry: &mut Registry) {
    io::register(registry);
    registry.declare::<gray::ToGray>();
    registry.declare::<crop::Crop>();
    registry.declare::<resize::Resize>();
    registry.declare::<time_range::TimeRange>();
    registry.declare::<composite::Composite>();
    registry.declare::<constant_color::ConstantColor>();
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
