//! `imaging.constant_color`: an RGBA image filled with one colour.

use std::sync::Arc;

use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError, port};

use crate::size::MAX_SIZE;

pyrograph_core::node! {
    /// An RGBA image filled with one colour.
    #[node("imaging.constant_color", "Imaging", Source)]
    pub struct ConstantColor {
        /// Width in pixels.
        #[range(1, MAX_SIZE)]
        width: u32 = 512,
        /// Height in pixels.
        #[range(1, MAX_SIZE)]
        height: u32 = 512,
        /// The fill colour (linear RGBA, straight alpha).
        color: [f32; 4] = [0.0, 0.0, 0.0, 1.0],
    }
    /// The filled image.
    -> image: Arc<Image>
}

/// A `width × height` RGBA image of `color`.
pub fn constant_color(width: u32, height: u32, color: [f32; 4]) -> Image {
    let data = std::iter::repeat_n(color, width as usize * height as usize).flatten().collect();
    Image::from_vec(width, height, Channels::Rgba, data).unwrap_or_else(|| Image::new(width, height, Channels::Rgba))
}

impl Cook for ConstantColor {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let width = ConstantColor::check_size(self.width, port!(ConstantColor, width))?;
        let height = ConstantColor::check_size(self.height, port!(ConstantColor, height))?;
        Ok(Arc::new(constant_color(width, height, self.color)))
    }
}

impl ConstantColor {
    /// `v` when it is a size the nodes here create (1..=[`MAX_SIZE`]), else an error on `port`: the
    /// port's range is only a hint to editors, and a 0 or huge image would fail later and less
    /// clearly.
    fn check_size(v: u32, port: &str) -> Result<u32, NodeError> {
        if v >= 1 && i64::from(v) <= MAX_SIZE {
            Ok(v)
        } else {
            Err(NodeError::port(port, format!("{v} is outside 1..={MAX_SIZE}")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::cook_node;
    use pyrograph_core::Value;
    use pyrograph_core::declare::Declared;

    #[test]
    fn constant_color_fills_every_pixel() {
        let img = constant_color(2, 1, [0.1, 0.2, 0.3, 0.4]);
        assert_eq!((img.size(), img.channels()), ((2, 1), Channels::Rgba));
        assert_eq!(img.data(), &[0.1, 0.2, 0.3, 0.4, 0.1, 0.2, 0.3, 0.4]);
    }

    #[test]
    fn constant_color_cook_reads_its_ports() {
        let values: Vec<Value> = ConstantColor::desc().inputs.iter().map(|p| p.default.clone().unwrap()).collect();
        let out = cook_node::<ConstantColor>(&values).unwrap();
        assert!(matches!(&out[0], Value::Image(img) if img.size() == (512, 512) && img.pixel(3, 3) == [0.0, 0.0, 0.0, 1.0]));
    }
}
