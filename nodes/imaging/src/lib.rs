//! pyrograph-nodes-imaging: image I/O, colour conversion, compositing and the Eigenfires
//! pre-processing chain (thesis ch. 3).
#![deny(missing_docs)]

pub mod auto_crop;
pub mod blobs;
pub mod bloom;
pub mod color;
pub mod composite;
pub mod constant_color;
pub mod convert;
pub mod crop;
pub mod filters;
pub mod flipbook;
pub mod gray;
pub mod io;
pub mod levels;
pub mod masks;
pub mod media;
pub mod preprocess;
pub mod procedural;
pub mod resize;
pub mod sheet;
pub mod size;
pub mod smoke;
pub mod time_range;
pub mod video;

#[cfg(test)]
mod testing;

use pyrograph_core::Registry;

/// Adds every imaging node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<io::nodes::LoadSequence>();
    registry.declare::<io::nodes::LoadImage>();
    registry.declare::<io::nodes::WriteSequence>();
    registry.declare::<io::nodes::WriteImage>();
    registry.declare::<io::write_layers::WriteExrLayers>();
    registry.declare::<gray::ToGray>();
    registry.declare::<crop::Crop>();
    registry.declare::<resize::Resize>();
    registry.declare::<time_range::TimeRange>();
    registry.declare::<composite::Composite>();
    registry.declare::<constant_color::ConstantColor>();
    registry.declare::<auto_crop::AutoCrop>();
    registry.declare::<masks::MaskCombine>();
    registry.declare::<masks::MaskToImage>();
    registry.declare::<preprocess::hsv::HsvMask>();
    registry.declare::<preprocess::hsv_auto::HsvAutoMask>();
    registry.declare::<preprocess::morphology::Morphology>();
    registry.declare::<preprocess::morphology::GaussianBlur>();
    registry.declare::<preprocess::contours::TraceContours>();
    registry.declare::<preprocess::contours::HoleRemoval>();
    registry.declare::<preprocess::contours::SimplifyContours>();
    registry.declare::<preprocess::contours::ContourMask>();
    registry.declare::<preprocess::contours::ContourOverlay>();
    registry.declare::<preprocess::hermite::HermiteBackground>();
    registry.declare::<preprocess::hermite::HermiteBackgroundMasked>();
    registry.declare::<preprocess::pose::PoseNormalize>();
    registry.declare::<preprocess::pose_smooth::SmoothAngle>();
    registry.declare::<preprocess::regions::FireRegionsNode>();
    registry.declare::<preprocess::fire_cues::FireCues>();
    registry.declare::<preprocess::stabilize::Stabilize>();
    registry.declare::<procedural::TurbulenceFlame>();
    registry.declare::<sheet::ContactSheet>();
    registry.declare::<sheet::Stack>();
    registry.declare::<color::OriginalColoring>();
    registry.declare::<color::OriginalColoringLayered>();
    registry.declare::<color::OriginalColoringMasked>();
    registry.declare::<color::SyntheticColoring>();
    registry.declare::<color::SyntheticColoringTexture>();
    registry.declare::<color::Premultiply>();
    registry.declare::<color::SetAlpha>();
    registry.declare::<bloom::BloomNode>();
    registry.declare::<smoke::Smoke>();
    registry.declare::<flipbook::FlipbookNode>();
    registry.declare::<flipbook::WriteFlipbook>();
    registry.declare::<levels::Levels>();
}
