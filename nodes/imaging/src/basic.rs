//! (being written)

use pyrograph_core::Registry;

/// Adds this module's node types.
pub fn register(_registry: &mut Registry) {}
