//! Bypassed nodes (Houdini's bypass flag, Nuke's disable): the node stays in the graph with its
//! ports and wires, but each output passes through the node's first input of the same type, so a
//! bloom can be compared with and without itself. A writer (no outputs) that is bypassed writes
//! nothing. A node with an output no input can stand in for is refused when the graph loads.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use crate::ctx::CookCtx;
use crate::error::NodeError;
use crate::node::{Inputs, Node, NodeDesc};
use crate::value::Value;

/// `node` with every output fed by the input that stands in for it; or, for the message, the
/// name and type of the first output no input can stand in for.
pub(super) fn bypassed(node: Arc<dyn Node>) -> Result<Arc<dyn Node>, String> {
    let desc = node.desc();
    let mut pass = Vec::with_capacity(desc.outputs.len());
    for out in &desc.outputs {
        match desc.inputs.iter().position(|i| i.ty == out.ty) {
            Some(i) => pass.push(i),
            None => {
                let inputs: Vec<String> = desc.inputs.iter().map(|p| format!("{} ({})", p.name, p.ty)).collect();
                return Err(format!(
                    "cannot be bypassed: its output '{}' is {} and none of its inputs is ({}); \
                     turn bypass off or remove the node",
                    out.name,
                    out.ty,
                    if inputs.is_empty() { "it has none".to_string() } else { inputs.join(", ") }
                ));
            }
        }
    }
    Ok(Arc::new(Bypassed { inner: node, pass }))
}

struct Bypassed {
    inner: Arc<dyn Node>,
    /// For each output, the input it passes through.
    pass: Vec<usize>,
}

impl Node for Bypassed {
    fn desc(&self) -> &NodeDesc {
        self.inner.desc()
    }

    fn cook(&self, inputs: &Inputs<'_>, _ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        self.pass
            .iter()
            .map(|&i| inputs.value(i).cloned().ok_or_else(|| NodeError::msg("a bypassed node lost its input")))
            .collect()
    }

    fn fingerprint_salt(&self) -> u64 {
        // Not the node's own result: a bypassed and an active node must never share a cache entry.
        let mut h = std::hash::DefaultHasher::new();
        ("bypass", self.inner.fingerprint_salt(), &self.pass).hash(&mut h);
        h.finish()
    }
}
