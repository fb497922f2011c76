//! The core's own node types: `graph.include` and small value/math utilities for driving
//! parameters from other nodes.

use crate::error::NodeError;
use crate::eval::CookCtx;
use crate::include::{IncludePlaceholder, include_desc};
use crate::node::{FnNode, Inputs, NodeDesc, PortDesc, TimeDep};
use crate::registry::Registry;
use crate::value::{PortType, Value};

/// Adds the built-in node types.
pub fn register(r: &mut Registry) {
    r.add(std::sync::Arc::new(IncludePlaceholder(include_desc())));
    r.add(FnNode::new(float_desc(), cook_float));
    r.add(FnNode::new(int_desc(), cook_int));
    r.add(FnNode::new(binary_desc("math.add", "Adds two floats (a + b)."), cook_add));
    r.add(FnNode::new(binary_desc("math.multiply", "Multiplies two floats (a × b)."), cook_multiply));
}

const BIG: f64 = 1e12;

fn float_desc() -> NodeDesc {
    NodeDesc::new("value.float", "Value", TimeDep::Source, "A float constant that can drive any Float parameter.")
        .input(PortDesc::float("value", 0.0, (-BIG, BIG), "The value."))
        .output("value", PortType::Float, "The value.")
}

fn cook_float(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Float(i.float("value")?)])
}

fn int_desc() -> NodeDesc {
    NodeDesc::new("value.int", "Value", TimeDep::Source, "An integer constant that can drive any Int parameter.")
        .input(PortDesc::int("value", 0, (-(1 << 40), 1 << 40), "The value."))
        .output("value", PortType::Int, "The value.")
}

fn cook_int(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Int(i.int("value")?)])
}

fn binary_desc(name: &str, doc: &str) -> NodeDesc {
    NodeDesc::new(name, "Math", TimeDep::PerFrame, doc)
        .input(PortDesc::float("a", 0.0, (-BIG, BIG), "First operand."))
        .input(PortDesc::float("b", 0.0, (-BIG, BIG), "Second operand."))
        .output("value", PortType::Float, "The result.")
}

fn cook_add(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Float(i.float("a")? + i.float("b")?)])
}

fn cook_multiply(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::Float(i.float("a")? * i.float("b")?)])
}
