//! pyrograph-nodes-volume: fire and smoke as volumes. A sparse grid of 8³ bricks holds named
//! fields ([`grid`]); `volume.source` turns the graph's geometry into emitters ([`source`]);
//! `volume.simulate` runs a combustion solver on the active bricks ([`sim`], after Fedkiw, Stam
//! & Jensen 2001 and Nguyen, Fedkiw & Jensen 2002); `volume.write_vdb` and `volume.load_vdb`
//! cache and deliver volumes as OpenVDB files ([`vdb`]); `volume.render` lights and ray-marches
//! them ([`render`]); the algorithms are plain functions on these types, below the node
//! declarations that call them.
#![deny(missing_docs)]

pub mod grid;
pub mod preview;
pub mod render;
pub mod sim;
pub mod source;
pub mod vdb;

use pyrograph_core::Registry;

#[cfg(test)]
mod tests;

/// Adds every volume node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<source::Source>();
    registry.declare::<sim::Simulate>();
    registry.declare::<vdb::nodes::WriteVdb>();
    registry.declare::<vdb::nodes::LoadVdb>();
    registry.declare::<preview::Preview>();
    registry.declare::<render::Render>();
    registry.declare::<render::sixway::RenderSixway>();
}
