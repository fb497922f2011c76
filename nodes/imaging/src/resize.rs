//! `imaging.resize`: an image scaled to a new size by a choice of resampling filter, keeping HDR
//! values.

use std::sync::Arc;

use image::imageops::{self, FilterType};
use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError, port};

use crate::convert;
use crate::size::{MAX_SIZE, image_size_text};

pyrograph_core::choice! {
    /// A resampling filter of `imaging.resize`.
    pub enum ResizeFilter {
        /// The nearest pixel.
        Nearest = "nearest",
        /// Linear interpolation (a triangle filter).
        Bilinear = "bilinear",
        /// The Catmull–Rom cubic.
        CatmullRom = "catmull_rom",
        /// Lanczos with a window of 3.
        Lanczos3 = "lanczos3",
    }
}

impl ResizeFilter {
    /// The `image` crate's filter.
    pub fn filter_type(self) -> FilterType {
        match self {
            ResizeFilter::Nearest => FilterType::Nearest,
            ResizeFilter::Bilinear => FilterType::Triangle,
            ResizeFilter::CatmullRom => FilterType::CatmullRom,
            ResizeFilter::Lanczos3 => FilterType::Lanczos3,
        }
    }
}

pyrograph_core::node! {
    /// Scales an image to a new size.
    ///
    /// A width or height of 0 keeps the aspect ratio from the other one.
    #[node("imaging.resize", "Imaging", PerFrame)]
    pub struct Resize {
        /// The image to scale.
        image: Arc<Image>,
        /// New width; 0 = from height, keeping the aspect ratio.
        #[range(0, MAX_SIZE)]
        width: u32 = 0,
        /// New height; 0 = from width, keeping the aspect ratio.
        #[range(0, MAX_SIZE)]
        height: u32 = 0,
        /// Resampling filter.
        filter: ResizeFilter = ResizeFilter::Bilinear,
    }
    /// The scaled image.
    -> image: Arc<Image>
}

/// Why an image cannot be resized, by the setting it concerns (`Resize`'s cook names the port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ResizeError {
    /// The image is empty.
    #[error("{0}")]
    Image(String),
    /// No size was asked for (width and height both 0).
    #[error("{0}")]
    Size(String),
}

/// A resize's error on the port of `imaging.resize` it concerns.
impl From<ResizeError> for NodeError {
    fn from(e: ResizeError) -> NodeError {
        match e {
            ResizeError::Image(m) => NodeError::port(port!(Resize, image), m),
            ResizeError::Size(m) => NodeError::port(port!(Resize, width), m),
        }
    }
}

/// The output size, filling a 0 side from the other one to keep the aspect ratio.
pub fn resize_target(img: &Image, width: u32, height: u32) -> Result<(u32, u32), ResizeError> {
    let (w0, h0) = (f64::from(img.width()), f64::from(img.height()));
    if img.width() == 0 || img.height() == 0 {
        return Err(ResizeError::Image(format!("cannot resize an empty {} image", image_size_text(img))));
    }
    let scaled = |v: f64| (v.round() as u32).max(1);
    match (width, height) {
        (0, 0) => Err(ResizeError::Size("width and height are both 0; set at least one of them".into())),
        (0, h) => Ok((scaled(w0 * f64::from(h) / h0), h)),
        (w, 0) => Ok((w, scaled(h0 * f64::from(w) / w0))),
        (w, h) => Ok((w, h)),
    }
}

/// `img` scaled to `width × height` (0 keeps the aspect ratio) with `filter`.
pub fn resize(img: &Image, width: u32, height: u32, filter: FilterType) -> Result<Image, ResizeError> {
    let (w, h) = resize_target(img, width, height)?;
    // imageops clamps float samples to 0..1; scaling into that range first keeps HDR values.
    let peak = img.data().iter().fold(1.0_f32, |m, &v| m.max(v));
    let scale = |img: Image, k: f32| -> Image {
        let mut img = img;
        if k != 1.0 {
            img.data_mut().iter_mut().for_each(|v| *v *= k);
        }
        img
    };
    let normalised = scale(img.clone(), 1.0 / peak);
    let resized = match img.channels() {
        Channels::Gray => convert::from_gray32f(imageops::resize(&convert::to_gray32f(&normalised), w, h, filter)),
        Channels::Rgba => convert::from_rgba32f(imageops::resize(&convert::to_rgba32f(&normalised), w, h, filter)),
    };
    Ok(scale(resized, peak))
}

impl Cook for Resize {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(resize(&self.image, self.width, self.height, self.filter.filter_type())?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{assert_close, gray, image_value, read, rgba};
    use pyrograph_core::Value;

    #[test]
    fn resize_keeps_aspect_and_values() {
        let img = Image::gray_from_fn(4, 2, |_, _| 0.5);
        assert_eq!(resize_target(&img, 2, 0).unwrap(), (2, 1));
        assert_eq!(resize_target(&img, 0, 4).unwrap(), (8, 4));
        assert!(resize_target(&img, 0, 0).unwrap_err().to_string().contains("both 0"));
        let r = resize(&img, 2, 0, FilterType::Triangle).unwrap();
        assert_eq!((r.size(), r.channels()), ((2, 1), Channels::Gray));
        assert_close(r.data(), &[0.5, 0.5]);
        let px = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let r = resize(&px, 2, 2, FilterType::Nearest).unwrap();
        assert_close(r.data(), &[0.2, 0.4, 0.6, 1.0].repeat(4));
    }

    #[test]
    fn resize_nearest_picks_pixels_and_hdr_survives() {
        let img = gray(2, 1, &[0.0, 1.0]);
        let r = resize(&img, 4, 1, FilterType::Nearest).unwrap();
        assert_close(r.data(), &[0.0, 0.0, 1.0, 1.0]);
        let hdr = gray(2, 2, &[4.0; 4]);
        let r = resize(&hdr, 1, 1, FilterType::Triangle).unwrap();
        assert_close(r.data(), &[4.0]);
        assert_eq!(ResizeFilter::parse("bilinear").unwrap().filter_type(), FilterType::Triangle);
        let values = [image_value(img), Value::Int(1), Value::Int(1), Value::Enum("cubic".into())];
        assert!(read::<Resize>(&values).unwrap_err().to_string().contains("filter"));
    }
}
