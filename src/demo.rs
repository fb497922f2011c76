//! The demo graph embedded in the binary: `pyrograph` with no arguments cooks it.

/// The demo graph's RON text (also shipped as `graphs/demo.ron`).
pub const DEMO_RON: &str = include_str!("../graphs/demo.ron");

/// Folder the demo writes into, relative to the current directory.
pub const DEMO_OUT: &str = "pyrograph-out";
