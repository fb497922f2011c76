//! Parameters between Python and graph documents: Python values become the `ParamValue`s a
//! graph file holds, and back.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};

use pyrograph_frontend::core::ParamValue;

/// How deeply tuples may nest in a parameter (a colour or vector is one level); deeper, or
/// self-containing, lists are refused instead of exhausting the stack.
const MAX_DEPTH: usize = 4;

/// A Python value as a graph parameter: bool, int, float, str, a path-like, or a tuple/list of
/// those (colours, vectors).
pub fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<ParamValue> {
    from_py_at(obj, 0)
}

fn from_py_at(obj: &Bound<'_, PyAny>, depth: usize) -> PyResult<ParamValue> {
    // bool first: Python's bool is an int. numpy's bool (what `arr.any()` returns) is no int
    // but has `__float__`, so it is recognised by name before the number fallbacks.
    if obj.is_instance_of::<PyBool>() || is_numpy_bool(obj)? {
        return Ok(ParamValue::Bool(obj.is_truthy()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return Ok(ParamValue::Int(obj.extract()?));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(ParamValue::Float(obj.extract()?));
    }
    if obj.is_instance_of::<PyString>() {
        let text: String = obj.extract()?;
        return Ok(form_text(&text).unwrap_or(ParamValue::String(text)));
    }
    if obj.is_instance_of::<PyTuple>() || obj.is_instance_of::<PyList>() {
        if depth >= MAX_DEPTH {
            return Err(PyTypeError::new_err(format!("a parameter's tuples may nest at most {MAX_DEPTH} deep")));
        }
        return obj.try_iter()?.map(|item| from_py_at(&item?, depth + 1)).collect::<PyResult<Vec<_>>>().map(ParamValue::List);
    }
    if obj.hasattr("__fspath__")? {
        let path: std::path::PathBuf = obj.extract()?;
        return Ok(ParamValue::String(path.to_string_lossy().into_owned()));
    }
    // numpy scalars and other number-likes.
    if obj.hasattr("__index__")? {
        return Ok(ParamValue::Int(obj.call_method0("__index__")?.extract()?));
    }
    if obj.hasattr("__float__")? {
        return Ok(ParamValue::Float(obj.call_method0("__float__")?.extract()?));
    }
    Err(PyTypeError::new_err(format!(
        "a parameter must be a bool, int, float, str, path or a tuple of those, not {}",
        obj.get_type().name()?
    )))
}

/// A string written as a form, as in a graph file and on the command line: an animated parameter,
/// `keys([...])` or `expr(...)`, or a place in a point list, `face(3)`.
fn form_text(text: &str) -> Option<ParamValue> {
    let t = text.trim();
    if !["keys(", "expr(", "face("].iter().any(|f| t.starts_with(f)) || !t.ends_with(')') {
        return None;
    }
    Some(ParamValue::parse_cli(t)).filter(|v| matches!(v, ParamValue::Call(..)))
}

fn is_numpy_bool(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    let ty = obj.get_type();
    let module: String = ty.module()?.extract()?;
    let name: String = ty.name()?.extract()?;
    Ok(module == "numpy" && (name == "bool_" || name == "bool"))
}

/// A graph parameter as a Python value (lists become tuples, as the file writes them).
pub fn to_py<'py>(py: Python<'py>, v: &ParamValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        ParamValue::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        ParamValue::Int(i) => i.into_pyobject(py)?.into_any(),
        ParamValue::Float(f) => f.into_pyobject(py)?.into_any(),
        ParamValue::String(s) => s.into_pyobject(py)?.into_any(),
        ParamValue::List(items) => {
            let items = items.iter().map(|i| to_py(py, i)).collect::<PyResult<Vec<_>>>()?;
            PyTuple::new(py, items)?.into_any()
        }
        // As written in the file, so `set(endpoint, get(endpoint))` keeps it.
        ParamValue::Call(..) => v.to_string().into_pyobject(py)?.into_any(),
    })
}
