//! `graph.include`, for callers that knew it here: the type lives in [`crate::builtin`] and
//! the loader that flattens includes in [`crate::graph`]. Nothing in the core imports this module.

pub use crate::builtin::{INCLUDE_TYPE, include_desc};
pub use crate::graph::preset_desc;
