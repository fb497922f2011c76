//! `imaging.to_gray`: colour to one gray channel, by Rec. 601 or Rec. 709 weights, the average or
//! the maximum of R, G, B.

use std::sync::Arc;

use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError};

pyrograph_core::choice! {
    /// How colour is reduced to one intensity.
    pub enum GrayMode {
        /// 0.299 R + 0.587 G + 0.114 B (OpenCV's `COLOR_RGB2GRAY`, used by the Eigenfires thesis).
        Rec601 = "rec601",
        /// 0.2126 R + 0.7152 G + 0.0722 B (sRGB / HDTV primaries).
        Rec709 = "rec709",
        /// (R + G + B) / 3.
        Average = "average",
        /// max(R, G, B).
        Max = "max",
    }
}

impl GrayMode {
    fn apply(self, r: f32, g: f32, b: f32) -> f32 {
        match self {
            GrayMode::Rec601 => 0.299 * r + 0.587 * g + 0.114 * b,
            GrayMode::Rec709 => 0.2126 * r + 0.7152 * g + 0.0722 * b,
            GrayMode::Average => (r + g + b) / 3.0,
            GrayMode::Max => r.max(g).max(b),
        }
    }
}

pyrograph_core::node! {
    /// Converts an image to one gray channel.
    ///
    /// Alpha is dropped; a gray input passes through unchanged.
    #[node("imaging.to_gray", "Imaging", PerFrame)]
    pub struct ToGray {
        /// The image to convert.
        image: Arc<Image>,
        /// Weights: rec601 (OpenCV), rec709, average or max of R, G, B.
        mode: GrayMode = GrayMode::Rec601,
    }
    /// The gray image.
    -> image: Arc<Image>
}

/// The gray version of `img` (alpha ignored).
pub fn to_gray(img: &Image, mode: GrayMode) -> Image {
    match img.channels() {
        Channels::Gray => img.clone(),
        Channels::Rgba => {
            let data = img.data().chunks_exact(4).map(|p| mode.apply(p[0], p[1], p[2])).collect();
            Image::from_vec(img.width(), img.height(), Channels::Gray, data)
                .unwrap_or_else(|| Image::new(img.width(), img.height(), Channels::Gray))
        }
    }
}

impl Cook for ToGray {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(to_gray(&self.image, self.mode)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{gray, image_value, read, rgba};
    use pyrograph_core::Value;

    #[test]
    fn gray_modes_give_their_weights() {
        let img = rgba(1, 1, &[1.0, 0.5, 0.25, 0.3]);
        let g = |m| to_gray(&img, m).data()[0];
        assert!((g(GrayMode::Rec601) - (0.299 + 0.587 * 0.5 + 0.114 * 0.25)).abs() < 1e-6);
        assert!((g(GrayMode::Rec709) - (0.2126 + 0.7152 * 0.5 + 0.0722 * 0.25)).abs() < 1e-6);
        assert!((g(GrayMode::Average) - 1.75 / 3.0).abs() < 1e-6);
        assert_eq!(g(GrayMode::Max), 1.0);
        assert_eq!(to_gray(&img, GrayMode::Max).channels(), Channels::Gray);
        let already = gray(2, 1, &[0.1, 0.2]);
        assert_eq!(to_gray(&already, GrayMode::Rec709), already);
        let err = read::<ToGray>(&[image_value(already), Value::Enum("luma".into())]).unwrap_err().to_string();
        assert!(err.contains("mode"), "{err}");
    }
}
