//! Alpha: straight and premultiplied alpha, and replacing an image's alpha with a matte.

use std::sync::Arc;

use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError};

use super::{ColoringError, check_size, intensity};

pyrograph_core::choice! {
    /// How colour relates to alpha in an output file.
    pub enum AlphaMode {
        /// Colour independent of alpha (the in-memory convention).
        Straight = "straight",
        /// Colour multiplied by alpha (what game engines and compositors blend fastest).
        Premultiplied = "premultiplied",
    }
}

impl AlphaMode {
    /// The image converted from straight alpha to this mode (gray images have no alpha and pass).
    pub fn apply(self, img: &Image) -> Image {
        match self {
            AlphaMode::Straight => img.clone(),
            AlphaMode::Premultiplied => premultiply(img),
        }
    }
}

/// Straight → premultiplied alpha (RGB × A); gray images are returned unchanged.
pub fn premultiply(img: &Image) -> Image {
    let mut out = img.clone();
    if img.channels() == Channels::Rgba {
        for p in out.data_mut().chunks_exact_mut(4) {
            let a = p[3];
            p[0] *= a;
            p[1] *= a;
            p[2] *= a;
        }
    }
    out
}

/// Premultiplied → straight alpha (RGB ÷ A; colour 0 where A is 0); gray images are returned unchanged.
pub fn unpremultiply(img: &Image) -> Image {
    let mut out = img.clone();
    if img.channels() == Channels::Rgba {
        for p in out.data_mut().chunks_exact_mut(4) {
            let a = p[3];
            for c in &mut p[..3] {
                *c = if a > 0.0 { *c / a } else { 0.0 };
            }
        }
    }
    out
}

pyrograph_core::choice! {
    /// Which way `imaging.premultiply` converts.
    pub enum AlphaDirection {
        /// Straight → premultiplied, [`premultiply`].
        Premultiply = "premultiply",
        /// Premultiplied → straight, [`unpremultiply`].
        Unpremultiply = "unpremultiply",
    }
}

pyrograph_core::node! {
    /// Converts between straight and premultiplied alpha (RGB × A, or RGB ÷ A with 0 where A = 0).
    #[node("imaging.premultiply", "Color & Post", PerFrame)]
    pub struct Premultiply {
        /// RGBA image (gray passes through)
        image: Arc<Image>,
        /// Which way to convert
        direction: AlphaDirection = AlphaDirection::Premultiply,
    }
    /// Converted image
    -> image: Arc<Image>
}

impl Cook for Premultiply {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let out = match self.direction {
            AlphaDirection::Premultiply => premultiply(&self.image),
            AlphaDirection::Unpremultiply => unpremultiply(&self.image),
        };
        Ok(Arc::new(out))
    }
}

/// `image` as RGBA with its alpha replaced by the intensity of `matte` (clamped to 0..1).
pub fn set_alpha(image: &Image, matte: &Image) -> Result<Image, ColoringError> {
    check_size(image, matte).map_err(ColoringError::Matte)?;
    let mut out = image.to_rgba();
    let n = out.data().len() / 4;
    for i in 0..n {
        let a = intensity(matte, i).clamp(0.0, 1.0);
        out.data_mut()[4 * i + 3] = a;
    }
    Ok(out)
}

pyrograph_core::node! {
    /// Replaces an image's alpha with a matte, e.g. the bloom matte (bloom + source) of Eigenfires thesis §6.2.
    ///
    /// Colours stay as they are (straight alpha); an RGBA matte gives its luma.
    #[node("imaging.set_alpha", "Color & Post", PerFrame)]
    pub struct SetAlpha {
        /// Colour image (gray is promoted to RGBA)
        image: Arc<Image>,
        /// Alpha matte, same size
        matte: Arc<Image>,
    }
    /// RGBA image with the matte as alpha
    -> image: Arc<Image>
}

impl Cook for SetAlpha {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(set_alpha(&self.image, &self.matte)?))
    }
}
