//! `imaging.hermite_background` and `imaging.hermite_background_masked`: Hermite background
//! removal of thesis §3.3.1 (eq. 5–6, Fig. 20).
//!
//! The protect mask is a separate node type rather than an optional input because every input
//! port must have a default or be connected and a Mask has no meaningful constant default.

use std::sync::Arc;

use pyrograph_core::{Cook, CookCtx, Image, Mask, NodeError, port};
use rayon::prelude::*;

use crate::convert::{from_gray32f, to_gray32f};

/// The second Hermite basis function `-2S³ + 3S²` (eq. 5), with `s` clamped to `[0, 1]`.
#[inline]
pub fn hermite_intensity(s: f32) -> f32 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// Darkens one gray sample `p` (0..1) with thresholds on the 0–255 scale (eq. 6): above `i_max`
/// unchanged, below `i_min` black, between multiplied by the Hermite curve.
#[inline]
pub fn hermite_pixel(p: f32, i_min: f32, i_max: f32) -> f32 {
    let v = p * 255.0;
    if v > i_max {
        p
    } else if v < i_min {
        0.0
    } else {
        p * hermite_intensity((v - i_min) / (i_max - i_min))
    }
}

/// Hermite background removal of `image` (RGBA is first converted to gray with Rec.601 weights).
///
/// Pixels inside `protect` keep their gray value (thesis Fig. 20d). `i_min >= i_max` is an error
/// naming `i_min`; a protect mask of another size is an error naming `protect`.
pub fn hermite_background(image: &Image, i_min: f32, i_max: f32, protect: Option<&Mask>) -> Result<Image, HermiteError> {
    if i_min.is_nan() || i_max.is_nan() || i_min >= i_max {
        return Err(HermiteError::IMin(format!("must be below i_max, got i_min {i_min} and i_max {i_max}")));
    }
    let mut gray = to_gray32f(image);
    let w = gray.width().max(1) as usize;
    if let Some(m) = protect
        && (m.width(), m.height()) != gray.dimensions()
    {
        return Err(HermiteError::Protect(format!(
            "mask is {}×{} but the image is {}×{}",
            m.width(),
            m.height(),
            gray.width(),
            gray.height()
        )));
    }
    // A per-pixel curve: one rayon task per row is all the parallelism it needs.
    let rows = gray.par_chunks_mut(w);
    match protect {
        Some(m) => rows.zip(m.data().par_chunks(w)).for_each(|(row, keep)| {
            for (p, &k) in row.iter_mut().zip(keep) {
                if k == 0 {
                    *p = hermite_pixel(*p, i_min, i_max);
                }
            }
        }),
        None => rows.for_each(|row| row.iter_mut().for_each(|p| *p = hermite_pixel(*p, i_min, i_max))),
    }
    Ok(from_gray32f(gray))
}

/// Why the background cannot be removed, by the setting it concerns (the Hermite nodes name the
/// port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HermiteError {
    /// `i_min` is not below `i_max`.
    #[error("{0}")]
    IMin(String),
    /// The protect mask's size is not the image's.
    #[error("{0}")]
    Protect(String),
}

/// A Hermite error on the port of the Hermite nodes it concerns.
impl From<HermiteError> for NodeError {
    fn from(e: HermiteError) -> NodeError {
        match e {
            HermiteError::IMin(m) => NodeError::port(port!(HermiteInputs, i_min), m),
            HermiteError::Protect(m) => NodeError::port(port!(HermiteBackgroundMasked, protect), m),
        }
    }
}

pyrograph_core::ports! {
    /// The frame and thresholds of both Hermite nodes.
    pub struct HermiteInputs {
        /// Frame, gray or RGBA
        image: Arc<Image>,
        /// Below this intensity (0–255) pixels become black
        #[range(0.0, 255.0)]
        i_min: f32 = 110.0,
        /// Above this intensity (0–255) pixels are unchanged
        #[range(0.0, 255.0)]
        i_max: f32 = 220.0,
    }
}

pyrograph_core::node! {
    /// Hermite background and smoke removal (Eigenfires thesis §3.3.1, eq. 5–6, Fig. 20b–c).
    ///
    /// Converts to gray (Rec.601), leaves pixels brighter than i_max unchanged, blacks out pixels darker than
    /// i_min and multiplies those between by -2S³+3S² with S = (p − i_min)/(i_max − i_min), all on the 0–255 scale.
    #[node("imaging.hermite_background", "Pre-processing", PerFrame)]
    pub struct HermiteBackground {
        /// The frame and thresholds.
        inputs: HermiteInputs,
    }
    /// Gray image with the background darkened
    -> image: Arc<Image>
}

impl Cook for HermiteBackground {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let HermiteInputs { image, i_min, i_max } = self.inputs;
        Ok(Arc::new(hermite_background(&image, i_min, i_max, None)?))
    }
}

pyrograph_core::node! {
    /// Hermite background removal that leaves the flame's interior untouched (Eigenfires thesis §3.3.1, eq. 5–6, Fig. 20d–e).
    ///
    /// Converts to gray (Rec.601), leaves pixels brighter than i_max unchanged, blacks out pixels darker than
    /// i_min and multiplies those between by -2S³+3S² with S = (p − i_min)/(i_max − i_min), all on the 0–255 scale.
    #[node("imaging.hermite_background_masked", "Pre-processing", PerFrame)]
    pub struct HermiteBackgroundMasked {
        /// The frame and thresholds.
        inputs: HermiteInputs,
        /// Pixels inside this mask (the filled flame contour) keep their gray value
        protect: Arc<Mask>,
    }
    /// Gray image with the background darkened
    -> image: Arc<Image>
}

impl Cook for HermiteBackgroundMasked {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let HermiteInputs { image, i_min, i_max } = self.inputs;
        Ok(Arc::new(hermite_background(&image, i_min, i_max, Some(&self.protect))?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::Channels;

    #[test]
    fn hermite_curve_at_known_points() {
        assert_eq!(hermite_intensity(0.0), 0.0);
        assert_eq!(hermite_intensity(0.5), 0.5);
        assert_eq!(hermite_intensity(1.0), 1.0);
        assert!((hermite_intensity(0.25) - 0.15625).abs() < 1e-7);
    }

    #[test]
    fn thresholds_black_out_scale_and_keep() {
        let px = |v: f32| v / 255.0;
        // 100 < i_min → 0; 110 → S 0; 165 → S 0.5; 220 → S 1; 240 > i_max → unchanged.
        let img = Image::from_vec(5, 1, Channels::Gray, vec![px(100.0), px(110.0), px(165.0), px(220.0), px(240.0)]).unwrap();
        let out = hermite_background(&img, 110.0, 220.0, None).unwrap();
        let want = [0.0, 0.0, px(165.0) * 0.5, px(220.0), px(240.0)];
        for (got, want) in out.data().iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
    }

    #[test]
    fn protect_region_is_untouched() {
        let img = Image::gray_from_fn(4, 1, |_, _| 0.3);
        let protect = Mask::from_vec(4, 1, vec![0, 255, 255, 0]).unwrap();
        let out = hermite_background(&img, 110.0, 220.0, Some(&protect)).unwrap();
        assert_eq!(out.data(), [0.0, 0.3, 0.3, 0.0]);
    }

    #[test]
    fn rgba_is_converted_to_gray() {
        let img = Image::from_vec(1, 1, Channels::Rgba, vec![1.0, 1.0, 1.0, 1.0]).unwrap();
        let out = hermite_background(&img, 110.0, 220.0, None).unwrap();
        assert_eq!(out.channels(), Channels::Gray);
        assert!((out.data()[0] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_thresholds_and_mask_size_name_their_ports() {
        let img = Image::new(2, 2, Channels::Gray);
        let err = NodeError::from(hermite_background(&img, 200.0, 200.0, None).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "i_min"), "{err}");
        let err = NodeError::from(hermite_background(&img, 1.0, 2.0, Some(&Mask::new(3, 2))).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "protect"), "{err}");
    }
}
