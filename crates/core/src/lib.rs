//! pyrograph-core: value and port types, the node trait and registry, versioned RON graph
//! documents with validation, and the lazy, memoizing evaluator. No node algorithms live here
//! beyond `graph.include` and small value/math utilities.
#![deny(missing_docs)]

pub mod builtin;
pub mod document;
pub mod error;
pub mod eval;
pub mod fingerprint;
pub mod graph;
pub mod include;
pub mod node;
pub mod registry;
pub mod value;

pub use document::{GraphDoc, NodeDoc, ParamValue};
pub use error::{Diagnostic, DiagnosticKind, Diagnostics, Location, NodeError};
pub use eval::{CancelToken, CookCtx, CookResult, CookSettings, Evaluator, Progress, ProgressFn};
pub use graph::{BuildOptions, Graph};
pub use node::{FnNode, Inputs, Node, NodeDesc, PathRole, PortDesc, TimeDep};
pub use registry::Registry;
pub use value::{
    Basis, Channels, Clip, ClothState, Contour, Contours, FrameItem, FrameList, FrameRef, FrameSource, Image, LargeWind, Mask,
    Particle, Particles, PortType, Value, Weights, WindField,
};
