//! Mask nodes: combining masks with the blend modes of the HSV mask layers (thesis §3.2, Figure
//! 17), so masks made by different nodes (a colour range, a dilated flame region) can be joined or
//! cut, and showing a mask as a gray image.

use std::sync::Arc;

use pyrograph_core::{Cook, CookCtx, Image, Mask, NodeError, port};

use crate::convert;

pyrograph_core::choice! {
    /// How two masks combine.
    pub enum MaskOp {
        /// Inside either (union).
        Add = "add",
        /// Inside a but not b.
        Subtract = "subtract",
        /// Inside exactly one (symmetric difference).
        Difference = "difference",
        /// Inside both.
        Intersect = "intersect",
    }
}

impl MaskOp {
    fn apply(self, a: bool, b: bool) -> bool {
        match self {
            MaskOp::Add => a || b,
            MaskOp::Subtract => a && !b,
            MaskOp::Difference => a != b,
            MaskOp::Intersect => a && b,
        }
    }
}

/// Combines two masks of the same size pixel by pixel.
pub fn combine_masks(a: &Mask, b: &Mask, op: MaskOp) -> Result<Mask, String> {
    if (a.width(), a.height()) != (b.width(), b.height()) {
        return Err(format!("masks differ in size: {}x{} and {}x{}", a.width(), a.height(), b.width(), b.height()));
    }
    let data = a.data().iter().zip(b.data()).map(|(&x, &y)| if op.apply(x != 0, y != 0) { 255 } else { 0 }).collect();
    Mask::from_vec(a.width(), a.height(), data).ok_or_else(|| "mask size overflow".to_string())
}

pyrograph_core::node! {
    /// Combines two masks with the blend modes of the HSV mask layers (Eigenfires thesis §3.2, Figure 17): add = union,
    /// subtract = a without b, difference = in exactly one, intersect = in both.
    #[node("imaging.mask_combine", "Pre-processing", PerFrame)]
    pub struct MaskCombine {
        /// First mask.
        a: Arc<Mask>,
        /// Second mask, same size.
        b: Arc<Mask>,
        /// How b combines with a.
        mode: MaskOp = MaskOp::Add,
    }
    /// The combined mask.
    -> mask: Arc<Mask>
}

impl Cook for MaskCombine {
    fn cook(self, _: &CookCtx) -> Result<Arc<Mask>, NodeError> {
        let out = combine_masks(&self.a, &self.b, self.mode).map_err(|m| NodeError::port(port!(MaskCombine, b), m))?;
        Ok(Arc::new(out))
    }
}

pyrograph_core::node! {
    /// Turns a mask into a gray image (0 outside, 1 inside), so masks can be viewed, composited and written.
    #[node("imaging.mask_to_image", "Imaging", PerFrame)]
    pub struct MaskToImage {
        /// The mask.
        mask: Arc<Mask>,
    }
    /// The gray image.
    -> image: Arc<Image>
}

impl Cook for MaskToImage {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(convert::mask_to_image(&self.mask)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::cook_node;
    use pyrograph_core::{Channels, Value};

    fn mask(bits: &[u8]) -> Mask {
        Mask::from_vec(bits.len() as u32, 1, bits.to_vec()).unwrap()
    }

    #[test]
    fn each_mode_has_its_truth_table() {
        let (a, b) = (mask(&[0, 0, 1, 1]), mask(&[0, 1, 0, 1]));
        let run = |op| combine_masks(&a, &b, op).unwrap().data().to_vec();
        assert_eq!(run(MaskOp::Add), vec![0, 255, 255, 255]);
        assert_eq!(run(MaskOp::Subtract), vec![0, 0, 255, 0]);
        assert_eq!(run(MaskOp::Difference), vec![0, 255, 255, 0]);
        assert_eq!(run(MaskOp::Intersect), vec![0, 0, 0, 255]);
    }

    #[test]
    fn sizes_must_match() {
        assert!(combine_masks(&mask(&[1]), &mask(&[1, 0]), MaskOp::Add).unwrap_err().contains("differ in size"));
    }

    #[test]
    fn mask_to_image_cook_reads_its_port() {
        let values = [Value::Mask(Arc::new(Mask::from_vec(2, 1, vec![0, 255]).unwrap()))];
        let out = cook_node::<MaskToImage>(&values).unwrap();
        assert!(matches!(&out[0], Value::Image(img) if img.data() == [0.0, 1.0] && img.channels() == Channels::Gray));
    }
}
