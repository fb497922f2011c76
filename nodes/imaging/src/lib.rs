//! pyrograph-nodes-imaging: image I/O, colour conversion, compositing and the Eigenfires
//! pre-processing chain (thesis ch. 3).
#![deny(missing_docs)]

pub mod basic;
pub mod convert;
pub mod io;
pub mod preprocess;
pub mod procedural;
pub mod sheet;

use pyrograph_core::Registry;

/// Adds every imaging node type.
pub fn register(registry: &mut Registry) {
    io::register(registry);
    basic::register(registry);
    preprocess::register(registry);
    procedural::register(registry);
    sheet::register(registry);
}
