//! The core's own node types: `graph.include` and small value/math utilities for driving
//! parameters from other nodes.

use crate::ctx::CookCtx;
use crate::declare::Cook;
use crate::error::NodeError;
use crate::node::{Node, NodeDesc, PathRole, PortDesc, TimeDep};

/// The built-in node types, for [`crate::Registry::with_builtins`] (a list rather than a
/// `register(&mut Registry)`, so this module does not depend on the registry that depends on it).
pub fn nodes() -> Vec<std::sync::Arc<dyn Node>> {
    let mut nodes = vec![FloatValue::node(), IntValue::node(), Add::node(), Multiply::node()];
    nodes.extend(crate::builtin_time::nodes());
    nodes
}

/// The type name of include nodes.
pub const INCLUDE_TYPE: &str = "graph.include";

/// The input of `graph.include` naming the file; the loader reads it, so it is declared here.
pub const INCLUDE_PATH: &str = "path";

/// The description of `graph.include` as listed (the loader adds the ports of the file it names
/// and flattens the file's nodes into the including graph, so it has no cook of its own).
pub fn include_desc() -> NodeDesc {
    NodeDesc::new(
        INCLUDE_TYPE,
        "Graph",
        TimeDep::WholeClip,
        "Uses another graph file as one node: its declared interface inputs, outputs and exposed \
         parameters become this node's ports. The path resolves against the including file's folder.",
    )
    .input(PortDesc::path(INCLUDE_PATH, PathRole::Input, None, "Graph file to include (RON with an `interface`)."))
}

/// Bound of the value and math nodes' numbers: wide, but finite so sliders have ends.
const BIG: f64 = 1e12;

crate::node! {
    /// A float constant that can drive any Float parameter.
    #[node("value.float", "Value", Source)]
    pub struct FloatValue {
        /// The value.
        #[range(-BIG, BIG)]
        value: f64 = 0.0,
    }
    /// The value.
    -> value: f64
}

impl Cook for FloatValue {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.value)
    }
}

crate::node! {
    /// An integer constant that can drive any Int parameter.
    #[node("value.int", "Value", Source)]
    pub struct IntValue {
        /// The value.
        #[range(-(1i64 << 40), 1i64 << 40)]
        value: i64 = 0,
    }
    /// The value.
    -> value: i64
}

impl Cook for IntValue {
    fn cook(self, _: &CookCtx) -> Result<i64, NodeError> {
        Ok(self.value)
    }
}

crate::ports! {
    /// The two operands of a binary math node.
    pub struct Operands {
        /// First operand.
        #[range(-BIG, BIG)]
        a: f64 = 0.0,
        /// Second operand.
        #[range(-BIG, BIG)]
        b: f64 = 0.0,
    }
}

crate::node! {
    /// Adds two floats (a + b).
    #[node("math.add", "Math", PerFrame)]
    pub struct Add {
        /// The operands.
        operands: Operands,
    }
    /// The result.
    -> value: f64
}

impl Cook for Add {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.operands.a + self.operands.b)
    }
}

crate::node! {
    /// Multiplies two floats (a × b).
    #[node("math.multiply", "Math", PerFrame)]
    pub struct Multiply {
        /// The operands.
        operands: Operands,
    }
    /// The result.
    -> value: f64
}

impl Cook for Multiply {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.operands.a * self.operands.b)
    }
}
