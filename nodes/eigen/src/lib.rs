//! pyrograph-nodes-eigen: Eigenfires (thesis ch. 4–5): PCA training, projection and
//! reconstruction, the database on disk, recognition, motion transitions (low-pass, Direct
//! Bridging, End Growing), motion lists, weight synthesis and plots.
//!
//! Pixel values are 0..1 (the thesis works in 0..255), so weights, distances and θ_min are 1/255
//! of the thesis' numbers (its θ_min = 500 is about 2 here).
#![deny(missing_docs)]

pub mod blas;
pub mod database;
pub mod frame_store;
pub mod motion;
pub mod pages;
pub mod pca;
pub mod transition;
pub mod values;
pub mod view;

use pyrograph_core::Registry;

/// Adds every Eigenfires node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<pca::Eigenfires>();
    registry.declare::<pca::Project>();
    registry.declare::<pca::Reconstruct>();
    registry.declare::<database::SaveDatabase>();
    registry.declare::<database::LoadDatabase>();
    registry.declare::<transition::nodes::Recognize>();
    registry.declare::<transition::nodes::LowpassTransition>();
    registry.declare::<transition::nodes::DirectBridgingTransition>();
    registry.declare::<transition::nodes::EndGrowingConnection>();
    registry.declare::<motion::MotionList>();
    registry.declare::<motion::FramesToClip>();
    registry.declare::<motion::WeightsEdit>();
    registry.declare::<view::EigenfireView>();
    registry.declare::<view::EigenfireGrid>();
    registry.declare::<view::PcaPlot>();
    registry.declare::<view::WeightBars>();
}
