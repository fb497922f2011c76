//! Combining masks with the blend modes of the HSV mask layers (thesis §3.2, Figure 17), so masks
//! made by different nodes (a colour range, a dilated flame region) can be joined or cut.

use std::sync::Arc;

use pyrograph_core::{CookCtx, FnNode, Inputs, Mask, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep, Value};

/// Adds this module's node types.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(mask_combine_desc(), cook_mask_combine));
}

/// How two masks combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskOp {
    /// Inside either (union).
    Add,
    /// Inside a but not b.
    Subtract,
    /// Inside exactly one (symmetric difference).
    Difference,
    /// Inside both.
    Intersect,
}

impl MaskOp {
    /// The op named `name` (the node's option names).
    pub fn from_name(name: &str) -> Option<MaskOp> {
        Some(match name {
            "add" => MaskOp::Add,
            "subtract" => MaskOp::Subtract,
            "difference" => MaskOp::Difference,
            "intersect" => MaskOp::Intersect,
            _ => return None,
        })
    }

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

fn mask_combine_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.mask_combine",
        "Pre-processing",
        TimeDep::PerFrame,
        "Combines two masks with the blend modes of the HSV mask layers (Eigenfires thesis §3.2, Figure 17): \
         add = union, subtract = a without b, difference = in exactly one, intersect = in both.",
    )
    .input(PortDesc::new("a", PortType::Mask, "First mask."))
    .input(PortDesc::new("b", PortType::Mask, "Second mask, same size."))
    .input(PortDesc::choice("mode", &["add", "subtract", "difference", "intersect"], "add", "How b combines with a."))
    .output("mask", PortType::Mask, "The combined mask.")
}

fn cook_mask_combine(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let mode = i.choice("mode")?;
    let op = MaskOp::from_name(mode).ok_or_else(|| NodeError::port("mode", format!("unknown mode '{mode}'")))?;
    let out = combine_masks(i.mask("a")?, i.mask("b")?, op).map_err(|m| NodeError::port("b", m))?;
    Ok(vec![Value::Mask(Arc::new(out))])
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
