//! Original colouring (Eigenfires thesis §6.1.1, Algorithm 2): the colour of the source video
//! copied above a threshold and faded into the destination (bloom) and smoke layers below it.

use std::sync::Arc;

use pyrograph_core::{Channels, Cook, CookCtx, Image, Mask, NodeError};

use super::{ColoringError, check_size, intensity, rgb, size_text};

/// The optional inputs of Algorithm 2.
#[derive(Clone, Copy, Debug, Default)]
pub struct ColoringLayers<'a> {
    /// The destination's initial content (the bloom image, §6.2); black when `None`.
    pub destination: Option<&'a Image>,
    /// The smoke image (§6.3); smoke disabled when `None`.
    pub smoke: Option<&'a Image>,
    /// A custom mask (§6.4): inside it the original is taken as if the source were above the threshold.
    pub custom_mask: Option<&'a Mask>,
}

/// Checks a threshold given on the thesis's 0–255 scale.
pub fn check_threshold(threshold: f64) -> Result<f32, String> {
    if !(0.0..=255.0).contains(&threshold) {
        return Err(format!("{threshold} is outside 0–255 (the thesis uses about 30)"));
    }
    Ok(threshold as f32)
}

/// Algorithm 2 of the thesis (§6.1.1) on all three channels.
///
/// `source` is the gray flame (gray or RGBA, whose luma is used), `original` the colour frame;
/// `threshold` is on the 0–255 scale. Where `source·255 > threshold` (or inside the custom mask)
/// the original colour is copied; below it the original fades linearly into the destination plus
/// smoke: `min(1, s·original + (1 − s)·(destination + smoke))` with `s = source·255 / threshold`.
/// The output is opaque RGBA.
pub fn original_coloring(
    source: &Image,
    original: &Image,
    threshold: f64,
    layers: ColoringLayers<'_>,
) -> Result<Image, ColoringError> {
    let t = check_threshold(threshold).map_err(ColoringError::Threshold)? / 255.0;
    check_size(source, original).map_err(ColoringError::Original)?;
    if let Some(d) = layers.destination {
        check_size(source, d).map_err(ColoringError::Destination)?;
    }
    if let Some(s) = layers.smoke {
        check_size(source, s).map_err(ColoringError::SmokeLayer)?;
    }
    if let Some(m) = layers.custom_mask
        && (m.width(), m.height()) != source.size()
    {
        return Err(ColoringError::CustomMask(format!(
            "is {}x{} but the source is {}; both must have the same size",
            m.width(),
            m.height(),
            size_text(source)
        )));
    }
    let (w, h) = source.size();
    let n = w as usize * h as usize;
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let src = intensity(source, i);
        let orig = rgb(original, i);
        let in_mask = layers.custom_mask.is_some_and(|m| m.data()[i] != 0);
        let px = if src > t || in_mask {
            orig
        } else {
            // Linearly diminish colours below the threshold (t = 0 only reaches here for src = 0).
            let scale_src = if t > 0.0 { (src / t).max(0.0) } else { 0.0 };
            let scale_dest = 1.0 - scale_src;
            let dest = layers.destination.map_or([0.0; 3], |d| rgb(d, i));
            let smoke = layers.smoke.map_or([0.0; 3], |s| rgb(s, i));
            std::array::from_fn(|c| (scale_src * orig[c] + scale_dest * dest[c] + smoke[c] * scale_dest).min(1.0))
        };
        out.extend_from_slice(&[px[0], px[1], px[2], 1.0]);
    }
    Image::from_vec(w, h, Channels::Rgba, out).ok_or_else(|| ColoringError::Message("image data does not match its size".into()))
}

pyrograph_core::ports! {
    /// The gray flame and the original frame of every original-colouring node.
    pub struct ColoringFrames {
        /// Gray flame (a reconstruction or a pre-processed frame)
        source: Arc<Image>,
        /// Original colour frame, same size and pose as the source
        original: Arc<Image>,
    }
}

pyrograph_core::ports! {
    /// The destination and smoke layers of the layered original-colouring nodes.
    pub struct ColoringLayerInputs {
        /// Initial destination: the bloom image (§6.2), or black (imaging.constant_color) for none
        destination: Arc<Image>,
        /// Smoke image (§6.3, imaging.smoke), or black for none
        smoke: Arc<Image>,
    }
}

pyrograph_core::ports! {
    /// The threshold of every original-colouring node.
    pub struct ColoringThreshold {
        /// Source intensity (0–255) above which the original colour is copied
        #[range(0.0, 255.0)]
        threshold: f64 = 30.0,
    }
}

pyrograph_core::node! {
    /// Colours a gray flame with the original video frame (Eigenfires thesis §6.1.1, Algorithm 2), empty destination, no smoke.
    ///
    /// Pixels whose source intensity is above the threshold take the original colour; below it the colour fades
    /// linearly to black. Output is opaque RGBA. For bloom and smoke layers use imaging.original_coloring_layered.
    #[node("imaging.original_coloring", "Color & Post", PerFrame)]
    pub struct OriginalColoring {
        /// The flame and the original frame.
        frames: ColoringFrames,
        /// The threshold.
        threshold: ColoringThreshold,
    }
    /// Coloured flame (RGBA)
    -> image: Arc<Image>
}

impl Cook for OriginalColoring {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let (frames, threshold) = (&self.frames, self.threshold.threshold);
        let img = original_coloring(&frames.source, &frames.original, threshold, ColoringLayers::default())?;
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Algorithm 2 of the Eigenfires thesis (§6.1.1) with a bloom destination (§6.2) and smoke (§6.3).
    ///
    /// Above the threshold the original colour is copied; below it the result is
    /// min(1, s·original + (1 − s)·(destination + smoke)), s = source / threshold. A black layer is the same as
    /// disabling it.
    #[node("imaging.original_coloring_layered", "Color & Post", PerFrame)]
    pub struct OriginalColoringLayered {
        /// The flame and the original frame.
        frames: ColoringFrames,
        /// The destination and smoke layers.
        layers: ColoringLayerInputs,
        /// The threshold.
        threshold: ColoringThreshold,
    }
    /// Coloured flame (RGBA)
    -> image: Arc<Image>
}

impl Cook for OriginalColoringLayered {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let (frames, threshold) = (&self.frames, self.threshold.threshold);
        let layers =
            ColoringLayers { destination: Some(&self.layers.destination), smoke: Some(&self.layers.smoke), custom_mask: None };
        let img = original_coloring(&frames.source, &frames.original, threshold, layers)?;
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Algorithm 2 (Eigenfires thesis §6.1.1) with bloom, smoke and a custom mask (§6.4).
    ///
    /// The custom mask is an extra layer that admits more pixels of the original: inside it the original colour
    /// is copied as if the source were above the threshold (smoke or glow removed before training comes back).
    #[node("imaging.original_coloring_masked", "Color & Post", PerFrame)]
    pub struct OriginalColoringMasked {
        /// The flame and the original frame.
        frames: ColoringFrames,
        /// The destination and smoke layers.
        layers: ColoringLayerInputs,
        /// Extra regions where the original colour is taken (§6.4)
        custom_mask: Arc<Mask>,
        /// The threshold.
        threshold: ColoringThreshold,
    }
    /// Coloured flame (RGBA)
    -> image: Arc<Image>
}

impl Cook for OriginalColoringMasked {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let (frames, threshold) = (&self.frames, self.threshold.threshold);
        let layers = ColoringLayers {
            destination: Some(&self.layers.destination),
            smoke: Some(&self.layers.smoke),
            custom_mask: Some(&self.custom_mask),
        };
        let img = original_coloring(&frames.source, &frames.original, threshold, layers)?;
        Ok(Arc::new(img))
    }
}
