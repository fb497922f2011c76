//! Cooking one node outside a graph, for the unit tests of the node crates: every input at its
//! declared default but those a test sets, cooked as the evaluator would. Here rather than in
//! `pyrograph-testing` because that crate has no dependencies (core itself takes it as a
//! dev-dependency), and this needs core's node types.

use crate::declare::Declared;
use crate::{Cook, CookCtx, Inputs, Node, NodeError, Value};

/// Cooks `node` with `set` (input name, value) and every other input at its default; an input
/// without a default that `set` leaves out, or a name the node does not have, is an error.
pub fn cook_node(node: &dyn Node, set: &[(&str, Value)]) -> Result<Vec<Value>, NodeError> {
    let desc = node.desc();
    if let Some((name, _)) = set.iter().find(|(n, _)| desc.input_index(n).is_none()) {
        return Err(NodeError::msg(format!("{} has no input '{name}'", desc.type_name)));
    }
    let mut values = Vec::with_capacity(desc.inputs.len());
    for port in &desc.inputs {
        let value = set.iter().find(|(n, _)| *n == port.name).map(|(_, v)| v.clone()).or_else(|| port.default.clone());
        values.push(value.ok_or_else(|| NodeError::msg(format!("{}.{} needs a value", desc.type_name, port.name)))?);
    }
    node.cook(&Inputs::new(desc, &values), &CookCtx::new())
}

/// [`cook_node`] for the declared node type `T`.
pub fn cook<T: Cook>(set: &[(&str, Value)]) -> Result<Vec<Value>, NodeError> {
    cook_node(&*T::node(), set)
}

/// Cooks node type `T` on `values`, one per input in port order.
pub fn cook_values<T: Cook>(values: &[Value]) -> Result<Vec<Value>, NodeError> {
    let node = T::node();
    node.cook(&Inputs::new(node.desc(), values), &CookCtx::new())
}

/// Reads node type `T`'s inputs from `values` (one per input, in port order), as a cook does first.
pub fn read<T: Declared>(values: &[Value]) -> Result<T, NodeError> {
    T::read(&Inputs::new(&T::desc(), values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::Registry;

    #[test]
    fn defaults_fill_what_a_test_leaves_out_and_unknown_names_are_refused() {
        let r = Registry::with_builtins();
        let add = r.get("math.add").expect("math.add");
        let out = cook_node(&**add, &[("a", Value::Float(2.0)), ("b", Value::Float(3.0))]).unwrap();
        assert!(matches!(out[0], Value::Float(v) if v == 5.0), "{out:?}");
        let out = cook_node(&**add, &[("a", Value::Float(2.0))]).unwrap();
        assert!(matches!(out[0], Value::Float(v) if v == 2.0), "b defaults to 0: {out:?}");
        let e = cook_node(&**add, &[("c", Value::Float(1.0))]).unwrap_err().to_string();
        assert!(e.contains("math.add has no input 'c'"), "{e}");
    }
}
