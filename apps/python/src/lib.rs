//! The `pyrograph` Python module (built with maturin as `pyrograph._native`): load, edit and
//! cook pyrograph graphs from Python, with frames handed over as numpy arrays.
//!
//! Everything goes through the same documents, registry and evaluator as the CLI and the
//! editor; this crate only converts between Python and Rust and keeps the GIL released while
//! a cook runs (see `run`).

use std::sync::{Arc, OnceLock};

use pyo3::prelude::*;

mod clip;
mod errors;
mod graph;
mod param_values;
mod run;
mod values;

/// Every node type pyrograph ships, and the Python plugin nodes of `PYROGRAPH_PLUGIN_PATH` and of
/// the `plugins/` folder in `graph_dir` (found again when a plugin file changes).
fn registry(graph_dir: Option<&std::path::Path>) -> Arc<pyrograph_frontend::core::Registry> {
    use pyrograph_frontend::plugins::{PluginFlags, PluginRegistries};
    static REGISTRIES: OnceLock<PluginRegistries> = OnceLock::new();
    REGISTRIES.get_or_init(|| PluginRegistries::new(pyrograph_frontend::registry(), PluginFlags::default())).for_graph(graph_dir)
}

/// Every node type with its category, doc (citing its paper section) and ports (name, type,
/// default, range, options, doc): the same list as `pyrograph nodes --json`.
#[pyfunction]
fn nodes(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let text = pyrograph_frontend::reference::json(&registry(None)).to_string();
    py.import("json")?.call_method1("loads", (text,))
}

/// The reference of node type `type` as Markdown (its doc citing the paper section, then
/// its inputs and outputs with types, defaults and ranges): its section of docs/nodes.md.
#[pyfunction]
fn describe(py: Python<'_>, r#type: &str) -> PyResult<String> {
    let type_name = r#type;
    let reg = registry(None);
    match reg.desc(type_name) {
        Some(d) => Ok(pyrograph_frontend::reference::node_markdown(d)),
        None => {
            let hint = reg.suggest(type_name).map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default();
            Err(errors::graph_error(
                py,
                None,
                None,
                &format!("unknown node type '{}'{hint}", pyrograph_frontend::core::error::shortened(type_name)),
            ))
        }
    }
}

/// Confines and bounds what this process reads and builds, as the command line's
/// `--read-root`, `--max-nodes`, `--max-pixels` and `--max-voxels` do (for a service cooking graphs its users
/// submit). `read_roots`: folders every include, preset, footage, mesh or database must lie
/// in, symbolic links followed (an empty list lifts the confinement; the graph file given to
/// `Graph.load` is read wherever it is). `max_nodes`, `max_pixels`, `max_voxels`: the limits (0 restores the
/// default or the environment's). Arguments left out keep their setting. Process-wide: every
/// `Graph` and thread obeys them from the next build or read.
#[pyfunction]
#[pyo3(signature = (*, read_roots=None, max_nodes=None, max_pixels=None, max_voxels=None))]
fn set_limits(
    read_roots: Option<Vec<std::path::PathBuf>>,
    max_nodes: Option<u64>,
    max_pixels: Option<u64>,
    max_voxels: Option<u64>,
) -> PyResult<()> {
    use pyrograph_frontend::core::limits;
    if let Some(roots) = read_roots {
        limits::set_read_roots(&roots).map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("read_roots: {e}")))?;
    }
    if let Some(n) = max_nodes {
        limits::set_max_nodes((n > 0).then_some(n));
    }
    if let Some(n) = max_pixels {
        limits::set_max_pixels((n > 0).then_some(n));
    }
    if let Some(n) = max_voxels {
        limits::set_max_voxels((n > 0).then_some(n));
    }
    Ok(())
}

/// The limits in force: `{"read_roots": [...], "max_nodes": N, "max_pixels": N, "max_voxels": N}`.
#[pyfunction]
fn limits(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    use pyrograph_frontend::core::limits as l;
    let d = pyo3::types::PyDict::new(py);
    let roots: Vec<String> = l::read_roots().iter().map(|p| p.display().to_string()).collect();
    d.set_item("read_roots", roots)?;
    d.set_item("max_nodes", l::max_nodes())?;
    d.set_item("max_pixels", l::max_pixels())?;
    d.set_item("max_voxels", l::max_voxels())?;
    Ok(d)
}

/// The Python module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // Load numpy's C API now: loaded lazily, it would run Python code at the first frame handed
    // over, where a Ctrl-C arriving at that moment cannot be reported as a KeyboardInterrupt.
    numpy::PyArray1::<f32>::zeros(m.py(), [0], false);
    m.add("GraphError", m.py().get_type::<errors::GraphError>())?;
    m.add_class::<graph::Graph>()?;
    m.add_class::<clip::Clip>()?;
    m.add_class::<errors::Problem>()?;
    m.add_class::<values::Contours>()?;
    m.add_class::<values::Opaque>()?;
    m.add_class::<values::FrameMemory>()?;
    m.add_function(wrap_pyfunction!(nodes, m)?)?;
    m.add_function(wrap_pyfunction!(describe, m)?)?;
    m.add_function(wrap_pyfunction!(set_limits, m)?)?;
    m.add_function(wrap_pyfunction!(limits, m)?)?;
    Ok(())
}
