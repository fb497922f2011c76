//! pyrograph-nodes-flame-model: T. Stich and M. Magnor, "Learning Flames". A generic flame model
//! fitted to video (§3: moments, normalization, height slices, eigenflames), rendered back
//! through cubic-spline inverse deformation (§3.1–3.2), and an auto-regressive process learned
//! by EM (§4) that synthesizes endless controllable flames (§4.3, §5.1).
#![deny(missing_docs)]

pub mod arp;
pub mod model;
pub mod plot;
pub mod values;

use pyrograph_core::Registry;

/// Adds every flame-model node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<model::FitModel>();
    registry.declare::<model::RenderModel>();
    registry.declare::<arp::ArpLearn>();
    registry.declare::<arp::ArpSample>();
    registry.declare::<plot::ParamPlot>();
}
