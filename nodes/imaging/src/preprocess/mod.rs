//! Eigenfires pre-processing (thesis ch. 3) (being written)

use pyrograph_core::Registry;

/// Adds this module's node types.
pub fn register(_registry: &mut Registry) {}
