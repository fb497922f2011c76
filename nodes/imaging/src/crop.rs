//! `imaging.crop`: a rectangle cut out of an image.

use std::sync::Arc;

use pyrograph_core::{Cook, CookCtx, Image, NodeError, port};

use crate::size::image_size_text;

/// Largest pixel offset accepted by `crop`.
const MAX_OFFSET: i64 = 1 << 20;

pyrograph_core::node! {
    /// Cuts a rectangle out of an image.
    #[node("imaging.crop", "Imaging", PerFrame)]
    pub struct Crop {
        /// The image to crop.
        image: Arc<Image>,
        /// Left edge of the rectangle, in pixels from the left.
        #[range(0, MAX_OFFSET)]
        x: u32 = 0,
        /// Top edge of the rectangle, in pixels from the top.
        #[range(0, MAX_OFFSET)]
        y: u32 = 0,
        /// Width of the rectangle; 0 = up to the right edge.
        #[range(0, MAX_OFFSET)]
        width: u32 = 0,
        /// Height of the rectangle; 0 = up to the bottom edge.
        #[range(0, MAX_OFFSET)]
        height: u32 = 0,
    }
    /// The cropped image.
    -> image: Arc<Image>
}

/// Why a crop failed, by the setting it concerns (`Crop`'s cook names the matching port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CropError {
    /// The left edge lies outside the image.
    #[error("{0}")]
    X(String),
    /// The top edge lies outside the image.
    #[error("{0}")]
    Y(String),
    /// The width reaches past the right edge.
    #[error("{0}")]
    Width(String),
    /// The height reaches past the bottom edge.
    #[error("{0}")]
    Height(String),
    /// The image's data does not match its size.
    #[error("{0}")]
    Image(String),
}

/// Resolves one axis of a crop: `(start, length)` within `size`, or the message for the start
/// (`Err(Ok(..))`) or for the length (`Err(Err(..))`).
fn crop_span(start: u32, len: u32, size: u32, img: &Image) -> Result<(u32, u32), Result<String, String>> {
    if start >= size {
        return Err(Ok(format!("{start} is outside the {} image", image_size_text(img))));
    }
    let len = if len == 0 { size - start } else { len };
    if u64::from(start) + u64::from(len) > u64::from(size) {
        return Err(Err(format!("{} + {len} reaches past the edge of the {} image", start, image_size_text(img))));
    }
    Ok((start, len))
}

/// The `width × height` rectangle at `(x, y)`; 0 sizes reach the right / bottom edge.
pub fn crop(img: &Image, x: u32, y: u32, width: u32, height: u32) -> Result<Image, CropError> {
    let (x, w) = crop_span(x, width, img.width(), img).map_err(|e| e.map_or_else(CropError::Width, CropError::X))?;
    let (y, h) = crop_span(y, height, img.height(), img).map_err(|e| e.map_or_else(CropError::Height, CropError::Y))?;
    let n = img.channels().count();
    let row_len = img.width() as usize * n;
    let data: Vec<f32> = img
        .data()
        .chunks_exact(row_len)
        .skip(y as usize)
        .take(h as usize)
        .flat_map(|row| row.iter().skip(x as usize * n).take(w as usize * n).copied())
        .collect();
    Image::from_vec(w, h, img.channels(), data).ok_or_else(|| CropError::Image("image data does not match its size".into()))
}

/// A crop's error on the port of `imaging.crop` it concerns.
impl From<CropError> for NodeError {
    fn from(e: CropError) -> NodeError {
        match e {
            CropError::X(m) => NodeError::port(port!(Crop, x), m),
            CropError::Y(m) => NodeError::port(port!(Crop, y), m),
            CropError::Width(m) => NodeError::port(port!(Crop, width), m),
            CropError::Height(m) => NodeError::port(port!(Crop, height), m),
            CropError::Image(m) => NodeError::port(port!(Crop, image), m),
        }
    }
}

impl Cook for Crop {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(crop(&self.image, self.x, self.y, self.width, self.height)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{cook_node, gray, image_value, rgba};
    use pyrograph_core::Value;

    #[test]
    fn crop_cuts_the_rectangle_and_zero_reaches_the_edge() {
        let img = Image::gray_from_fn(4, 3, |x, y| (y * 4 + x) as f32);
        let c = crop(&img, 1, 1, 2, 2).unwrap();
        assert_eq!((c.size(), c.data()), ((2, 2), &[5.0, 6.0, 9.0, 10.0][..]));
        let c = crop(&img, 2, 1, 0, 0).unwrap();
        assert_eq!((c.size(), c.data()), ((2, 2), &[6.0, 7.0, 10.0, 11.0][..]));
        let c = crop(&rgba(2, 1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]), 1, 0, 1, 1).unwrap();
        assert_eq!(c.data(), &[5.0, 6.0, 7.0, 8.0]);
    }

    #[test]
    fn crop_outside_the_image_names_port_and_size() {
        let img = Image::gray_from_fn(4, 3, |_, _| 0.0);
        let err = NodeError::from(crop(&img, 4, 0, 0, 0).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, message } if port == "x" && message.contains("4x3")), "{err}");
        let err = NodeError::from(crop(&img, 1, 0, 4, 0).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, message } if port == "width" && message.contains("4x3")), "{err}");
        let err = NodeError::from(crop(&img, 0, 1, 0, 3).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, .. } if port == "height"), "{err}");
    }

    #[test]
    fn crop_cook_reads_its_ports() {
        let values = [image_value(gray(2, 2, &[0.0; 4])), Value::Int(0), Value::Int(0), Value::Int(3), Value::Int(0)];
        let err = cook_node::<Crop>(&values).unwrap_err().to_string();
        assert!(err.contains("width") && err.contains("2x2"), "{err}");
    }
}
