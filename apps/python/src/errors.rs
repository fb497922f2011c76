//! Python exceptions: `GraphError` with the node, port and message of what went wrong, and the
//! `Problem` objects `Graph.check()` returns.

use pyo3::exceptions::PyException;
use pyo3::prelude::*;

use pyrograph_frontend::check::Problem as RustProblem;
use pyrograph_frontend::core::{Diagnostics, NodeError};
use pyrograph_frontend::text::printable;

pyo3::create_exception!(
    pyrograph,
    GraphError,
    PyException,
    "A graph that does not load, type-check or cook. `.node` and `.port` say where (or None), `.message` what."
);

/// A `GraphError` carrying `node`, `port` and `message` attributes. The message (and `.message`)
/// has its control characters escaped and overlong runs cut, as the CLI prints it: a traceback
/// printed to a terminal cannot be made to drive it. `.node` and `.port` keep the exact ids, for
/// code that looks the node up.
pub fn graph_error(py: Python<'_>, node: Option<&str>, port: Option<&str>, message: &str) -> PyErr {
    let shown = printable(message);
    let message: &str = &shown;
    let err = GraphError::new_err(message.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail short of memory exhaustion;
    // the exception still carries its message if it does.
    let _ = value.setattr("node", node);
    let _ = value.setattr("port", port);
    let _ = value.setattr("message", message);
    err
}

/// Load-time diagnostics as one `GraphError` located at the first problem; the message lists
/// them all.
pub fn from_diagnostics(py: Python<'_>, d: &Diagnostics) -> PyErr {
    let problems = pyrograph_frontend::check::diagnostics(d);
    let first = problems.first();
    graph_error(py, first.and_then(|p| p.node.as_deref()), first.and_then(|p| p.port.as_deref()), &d.to_string())
}

/// A cook error of node `node` (the node the caller asked for, when the error does not name
/// another) as a `GraphError`.
pub fn from_node_error(py: Python<'_>, node: &str, e: &NodeError) -> PyErr {
    let at = match e {
        NodeError::InNode { node, .. } => node.as_str(),
        _ => node,
    };
    graph_error(py, Some(at), pyrograph_frontend::check::error_port(e), &pyrograph_frontend::check::explain(at, e))
}

/// One problem `Graph.check()` found.
#[pyclass(frozen, get_all, module = "pyrograph")]
pub struct Problem {
    /// The graph file, when the graph came from one.
    pub file: Option<String>,
    /// The node at fault, or None.
    pub node: Option<String>,
    /// The port or parameter at fault, or None.
    pub port: Option<String>,
    /// Where, as text.
    pub location: String,
    /// The kind: `Syntax`, `UnknownType`, `TypeMismatch`, … or `Cook` for a source that failed.
    pub kind: String,
    /// What is wrong.
    pub message: String,
}

impl From<RustProblem> for Problem {
    fn from(p: RustProblem) -> Self {
        Problem {
            file: p.file.as_ref().map(|f| f.display().to_string()),
            node: p.node.clone(),
            port: p.port.clone(),
            location: printable(&p.location).into_owned(),
            kind: p.kind.clone(),
            message: printable(&p.to_string()).into_owned(),
        }
    }
}

#[pymethods]
impl Problem {
    /// As Python writes the values: `Problem(kind='Cycle', node='p', port=None, message='…')`.
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let r = |v: Bound<'_, PyAny>| -> PyResult<String> { Ok(v.repr()?.to_string()) };
        Ok(format!(
            "Problem(kind={}, node={}, port={}, message={})",
            r(self.kind.clone().into_pyobject(py)?.into_any())?,
            r(self.node.clone().into_pyobject(py)?.into_any())?,
            r(self.port.clone().into_pyobject(py)?.into_any())?,
            r(self.message.clone().into_pyobject(py)?.into_any())?,
        ))
    }
    fn __str__(&self) -> String {
        self.message.clone()
    }
}
