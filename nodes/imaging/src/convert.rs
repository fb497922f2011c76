//! Conversions between pyrograph's [`Image`]/[`Mask`] and `image` crate buffers, so imageproc
//! and the codecs can work on our values without copies beyond the one format change.

use image::{DynamicImage, GrayImage, ImageBuffer, Luma, Rgba, Rgba32FImage};
use pyrograph_core::{Channels, Image, Mask};

/// A single-channel f32 buffer.
pub type Gray32FImage = ImageBuffer<Luma<f32>, Vec<f32>>;

/// An RGBA f32 buffer of the image (gray is replicated, alpha 1).
pub fn to_rgba32f(img: &Image) -> Rgba32FImage {
    let rgba = img.to_rgba();
    let (w, h) = rgba.size();
    // The length always matches: `to_rgba` yields w·h·4 samples.
    ImageBuffer::from_raw(w, h, rgba.into_vec()).unwrap_or_else(|| ImageBuffer::new(w, h))
}

/// Wraps an RGBA f32 buffer.
pub fn from_rgba32f(buf: Rgba32FImage) -> Image {
    let (w, h) = buf.dimensions();
    Image::from_vec(w, h, Channels::Rgba, buf.into_raw()).unwrap_or_else(|| Image::new(w, h, Channels::Rgba))
}

/// Luma of the image as an f32 buffer: gray as is, RGBA by Rec.601 weights (as OpenCV's
/// `cvtColor(..., COLOR_RGB2GRAY)`, which the Eigenfires thesis used).
pub fn to_gray32f(img: &Image) -> Gray32FImage {
    let (w, h) = img.size();
    let data = match img.channels() {
        Channels::Gray => img.data().to_vec(),
        Channels::Rgba => img.data().chunks_exact(4).map(|p| 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]).collect(),
    };
    ImageBuffer::from_raw(w, h, data).unwrap_or_else(|| ImageBuffer::new(w, h))
}

/// Wraps a single-channel f32 buffer as a gray image.
pub fn from_gray32f(buf: Gray32FImage) -> Image {
    let (w, h) = buf.dimensions();
    Image::from_vec(w, h, Channels::Gray, buf.into_raw()).unwrap_or_else(|| Image::new(w, h, Channels::Gray))
}

/// 8-bit gray (0..1 → 0..255, clamped and rounded).
pub fn to_gray8(img: &Image) -> GrayImage {
    let (w, h) = img.size();
    // The same luma as `to_gray32f`, without the intermediate f32 buffer.
    let data = match img.channels() {
        Channels::Gray => img.data().iter().map(|&v| unit_to_u8(v)).collect(),
        Channels::Rgba => img.data().chunks_exact(4).map(|p| unit_to_u8(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2])).collect(),
    };
    GrayImage::from_raw(w, h, data).unwrap_or_else(|| GrayImage::new(w, h))
}

/// A mask as an imageproc-style gray image (0 / 255).
pub fn mask_to_gray8(mask: &Mask) -> GrayImage {
    GrayImage::from_raw(mask.width(), mask.height(), mask.data().to_vec())
        .unwrap_or_else(|| GrayImage::new(mask.width(), mask.height()))
}

/// A gray image as a mask: every non-zero pixel is inside.
pub fn gray8_to_mask(buf: GrayImage) -> Mask {
    let (w, h) = buf.dimensions();
    Mask::from_vec(w, h, buf.into_raw()).unwrap_or_else(|| Mask::new(w, h))
}

/// A mask as a gray image (0.0 / 1.0).
pub fn mask_to_image(mask: &Mask) -> Image {
    let data = mask.data().iter().map(|&v| if v == 0 { 0.0 } else { 1.0 }).collect();
    Image::from_vec(mask.width(), mask.height(), Channels::Gray, data)
        .unwrap_or_else(|| Image::new(mask.width(), mask.height(), Channels::Gray))
}

/// A decoded image: colour sources become RGBA, gray sources stay gray.
pub fn from_dynamic(img: DynamicImage) -> Image {
    if img.color().has_color() {
        from_rgba32f(img.into_rgba32f())
    } else {
        let (w, h) = (img.width(), img.height());
        let luma = img.to_luma32f();
        Image::from_vec(w, h, Channels::Gray, luma.into_raw()).unwrap_or_else(|| Image::new(w, h, Channels::Gray))
    }
}

/// RGBA 8-bit (for PNG writing and previews), values clamped to 0..1.
pub fn to_rgba8(img: &Image) -> image::RgbaImage {
    let rgba = img.to_rgba();
    let (w, h) = rgba.size();
    let data = rgba.data().iter().map(|&v| unit_to_u8(v)).collect();
    image::RgbaImage::from_raw(w, h, data).unwrap_or_else(|| image::RgbaImage::new(w, h))
}

/// RGBA 16-bit, values clamped to 0..1.
pub fn to_rgba16(img: &Image) -> ImageBuffer<Rgba<u16>, Vec<u16>> {
    let rgba = img.to_rgba();
    let (w, h) = rgba.size();
    let data = rgba.data().iter().map(|&v| (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16).collect();
    ImageBuffer::from_raw(w, h, data).unwrap_or_else(|| ImageBuffer::new(w, h))
}

/// 0..1 float to a byte, clamped and rounded.
pub fn unit_to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgba_round_trips_through_image_buffers() {
        let img = Image::from_vec(1, 2, Channels::Rgba, vec![0.1, 0.2, 0.3, 1.0, 0.5, 0.6, 0.7, 0.5]).unwrap();
        assert_eq!(from_rgba32f(to_rgba32f(&img)), img);
    }

    #[test]
    fn gray_uses_rec601_weights() {
        let img = Image::from_vec(1, 1, Channels::Rgba, vec![1.0, 0.0, 0.0, 1.0]).unwrap();
        assert!((to_gray32f(&img).get_pixel(0, 0)[0] - 0.299).abs() < 1e-6);
    }

    #[test]
    fn masks_round_trip_and_convert_to_unit_images() {
        let m = Mask::from_vec(3, 1, vec![0, 255, 9]).unwrap();
        assert_eq!(gray8_to_mask(mask_to_gray8(&m)), m);
        assert_eq!(mask_to_image(&m).data(), &[0.0, 1.0, 1.0]);
    }

    #[test]
    fn bytes_round_and_clamp() {
        assert_eq!(unit_to_u8(-1.0), 0);
        assert_eq!(unit_to_u8(0.5), 128);
        assert_eq!(unit_to_u8(7.0), 255);
    }
}
