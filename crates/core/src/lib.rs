//! pyrograph-core: value and port types, the node trait and registry, versioned RON graph
//! documents with validation, and the lazy, memoizing evaluator. No node algorithms live here
//! beyond `graph.include` and small value/math utilities.
#![deny(missing_docs)]

pub mod anim;
pub mod builtin;
pub mod builtin_time;
pub mod ctx;
pub mod declare;
pub mod document;
pub mod error;
pub mod eval;
pub mod fingerprint;
pub mod frames;
pub mod graph;
pub mod limits;
pub mod node;
pub mod registry;
pub mod stepping;
pub mod testing;
pub mod text;
pub mod timeline;
mod typos;
pub mod value;

pub use anim::Animated;
pub use ctx::{CancelToken, CookCtx, CookSettings, Progress, ProgressFn, Warning};
pub use declare::{ClipOf, Cook, InputPath, OutputPath};
pub use document::{CommentDoc, GraphDoc, GroupDoc, NodeDoc, ParamValue};
pub use error::{AtPort, Diagnostic, DiagnosticKind, Diagnostics, Location, NodeError};
pub use eval::{CookResult, Evaluator};
pub use frames::FrameSet;
pub use graph::{BuildOptions, Graph};
pub use node::{Inputs, Node, NodeDesc, PathRole, PortDesc, TimeDep};
pub use registry::Registry;
pub use timeline::Timeline;
pub use value::frame_cache::{CacheStats, FrameCache};
pub use value::{Channels, Clip, Contour, Contours, FrameSource, Image, Mask, PortType, TypeInfo, Value, ValueType};
