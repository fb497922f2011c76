//! Volume sources: the `VolumeSource` value ([`value`]) and the `volume.source` node that
//! builds one from the graph's geometry ([`node`]).

pub mod node;
pub mod value;

pub use node::{Shape, Source};
pub use value::{Emitter, Geometry, Rates, SourceError, Splat, TimedPoint, VolumeSource};
