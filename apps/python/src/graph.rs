//! `pyrograph.Graph`: a graph document with a persistent evaluator. Loading, saving and editing
//! work on the same RON document the CLI and the editor use; cooking re-uses every result whose
//! inputs did not change since the last cook, so a `set` followed by a cook re-cooks only what
//! is downstream of the edit (`graph.last_cooked` lists what actually ran).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::{
    BuildOptions, CookSettings, Diagnostics, Evaluator, Graph as RustGraph, GraphDoc, NodeDoc, NodeError, ParamValue, Registry,
    Value,
};

use crate::clip::{Clip, frame_selection, frames_to_py, pull_frames};
use crate::errors::{from_diagnostics, from_node_error, graph_error};
use crate::registry;

/// A pyrograph graph: load or build it, edit it, cook outputs into numpy, render its writers.
///
/// Every method takes `&self`: a graph shared by Python threads serializes their calls on its
/// locks (they take turns, each completes) instead of failing with a borrow error. Python values
/// are converted before a lock is taken (a conversion can run Python code, which can switch
/// threads), and no lock on the document is held while the GIL is released.
#[pyclass(module = "pyrograph")]
pub struct Graph {
    state: Mutex<Doc>,
    /// The graph built from `doc` for cooking, until the next edit or a change of the plugin
    /// files (a new registry), with the registry it was built with.
    built: Mutex<Option<(Arc<Registry>, Arc<RustGraph>)>>,
    eval: Mutex<Evaluator>,
    last_cooked: Mutex<Vec<String>>,
    /// `(node, message)` of every warning of the last cook or render.
    last_warnings: Mutex<Vec<(String, String)>>,
}

/// The document and where it belongs.
struct Doc {
    doc: GraphDoc,
    /// The file the document belongs to (relative paths resolve against its folder).
    file: Option<PathBuf>,
    /// The folder relative paths resolve against.
    dir: PathBuf,
    /// Where each node id is in `doc.nodes` (the first of a duplicated id, as the document's own
    /// lookup finds it): a script building a big graph calls add_node, connect and set once per
    /// node, and a scan of the list each time made that quadratic.
    index: HashMap<String, usize>,
}

impl Doc {
    fn build(&self, options: &BuildOptions) -> Result<RustGraph, Diagnostics> {
        self.build_on(&self.registry(), options)
    }

    fn build_on(&self, registry: &Registry, options: &BuildOptions) -> Result<RustGraph, Diagnostics> {
        match &self.file {
            Some(f) => RustGraph::build_file(&self.doc, f, registry, options),
            None => RustGraph::build(&self.doc, registry, &self.dir, options),
        }
    }

    /// The node types this graph can use: the built-ins and the plugins beside it.
    fn registry(&self) -> Arc<Registry> {
        registry(Some(&self.dir))
    }

    fn new(doc: GraphDoc, file: Option<PathBuf>, dir: PathBuf) -> Doc {
        let mut d = Doc { doc, file, dir, index: HashMap::new() };
        d.reindex();
        d
    }

    fn reindex(&mut self) {
        self.index.clear();
        for (i, (id, _)) in self.doc.nodes.0.iter().enumerate() {
            self.index.entry(id.clone()).or_insert(i);
        }
    }

    /// Where node `id` is in the document's list.
    fn position(&self, id: &str) -> Option<usize> {
        self.index.get(id).copied().filter(|&i| self.doc.nodes.0.get(i).is_some_and(|(k, _)| k == id))
    }

    fn node(&self, id: &str) -> Option<&NodeDoc> {
        self.position(id).map(|i| &self.doc.nodes.0[i].1)
    }

    fn node_mut(&mut self, py: Python<'_>, id: &str) -> PyResult<&mut NodeDoc> {
        match self.position(id) {
            Some(i) => Ok(&mut self.doc.nodes.0[i].1),
            None => Err(graph_error(py, Some(id), None, &format!("no node '{id}' in the graph"))),
        }
    }

    /// Appends node `id`, which must be new.
    fn push_node(&mut self, id: &str, node: NodeDoc) {
        self.index.insert(id.to_string(), self.doc.nodes.0.len());
        self.doc.nodes.0.push((id.to_string(), node));
    }
}

/// What a cook produced before it is handed to Python.
enum Cooked {
    One(Value),
    Frames(Vec<Value>),
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panic inside a cook is reported as an error; the evaluator's cache stays usable.
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

fn endpoint<'a>(py: Python<'_>, text: &'a str) -> PyResult<(&'a str, &'a str)> {
    split_endpoint(text).ok_or_else(|| graph_error(py, None, None, &format!("'{text}' is not of the form node.port")))
}

impl Graph {
    fn with_doc(doc: GraphDoc, file: Option<PathBuf>, dir: PathBuf) -> Graph {
        Graph {
            state: Mutex::new(Doc::new(doc, file, dir)),
            built: Mutex::new(None),
            eval: Mutex::new(Evaluator::new()),
            last_cooked: Mutex::new(Vec::new()),
            last_warnings: Mutex::new(Vec::new()),
        }
    }

    /// The document, locked. Locks are always taken in the order state, built.
    fn state(&self) -> std::sync::MutexGuard<'_, Doc> {
        lock(&self.state)
    }

    fn build_with(&self, options: &BuildOptions) -> Result<RustGraph, Diagnostics> {
        self.state().build(options)
    }

    /// The graph for cooking outputs, built once per edit (and again when a plugin file
    /// changed: the registry is then a new one, whose changed nodes have new fingerprints).
    fn cooking_graph(&self, py: Python<'_>) -> PyResult<Arc<RustGraph>> {
        let st = self.state();
        let registry = st.registry();
        let mut slot = lock(&self.built);
        if let Some((r, g)) = &*slot
            && Arc::ptr_eq(r, &registry)
        {
            return Ok(g.clone());
        }
        let g = Arc::new(st.build_on(&registry, &BuildOptions::default()).map_err(|d| from_diagnostics(py, &d))?);
        *slot = Some((registry, g.clone()));
        Ok(g)
    }

    /// Forgets the built graph after an edit (called with the state locked).
    fn edited(&self) {
        *lock(&self.built) = None;
    }
}

#[pymethods]
impl Graph {
    /// An empty graph; relative paths resolve against the current folder until it is saved.
    #[new]
    #[pyo3(signature = (description=None))]
    fn py_new(description: Option<String>) -> PyResult<Graph> {
        let mut doc = GraphDoc::new();
        doc.description = description;
        Ok(Graph::with_doc(doc, None, std::env::current_dir()?))
    }

    /// Reads a graph file (RON, any version; older versions are migrated).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Graph> {
        let doc = GraphDoc::load(&path).map_err(|d| from_diagnostics(py, &d))?;
        // Absolute, so a later os.chdir() (DCC hosts change folders) does not move the graph.
        let path = std::path::absolute(&path)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(Graph::with_doc(doc, Some(path), dir))
    }

    /// Parses a graph from RON text; relative paths resolve against `base_dir` (default: the
    /// current folder).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None))]
    fn from_ron(py: Python<'_>, text: &str, base_dir: Option<PathBuf>) -> PyResult<Graph> {
        let doc = GraphDoc::from_ron(text).map_err(|d| from_diagnostics(py, &d))?;
        let dir = match base_dir {
            Some(d) => std::path::absolute(d)?,
            None => std::env::current_dir()?,
        };
        Ok(Graph::with_doc(doc, None, dir))
    }

    /// The document as RON text, exactly what `save` writes.
    fn to_ron(&self) -> String {
        self.state().doc.to_ron()
    }

    /// Writes the graph atomically (the same bytes as `pyrograph save` and the editor). An
    /// existing file is replaced only with `overwrite=True` (else `FileExistsError`). The graph
    /// then belongs to `path`: its relative paths resolve against that folder.
    #[pyo3(signature = (path, overwrite=false))]
    fn save(&self, path: PathBuf, overwrite: bool) -> PyResult<()> {
        let mut st = self.state();
        st.doc.save(&path, overwrite)?;
        let path = std::path::absolute(&path)?;
        st.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        st.file = Some(path);
        self.edited();
        Ok(())
    }

    /// Validates the graph and probes its sources (input files exist and decode), like
    /// `pyrograph check`: a list of `Problem`s, empty when the graph is fine.
    #[pyo3(signature = (out=None, allow_outside_out=false))]
    fn check(&self, py: Python<'_>, out: Option<PathBuf>, allow_outside_out: bool) -> Vec<crate::errors::Problem> {
        let options = BuildOptions { output_dir: out, allow_outside_out, ..BuildOptions::default() };
        let built = self.build_with(&options);
        let problems = py.detach(|| pyrograph_frontend::check::problems(built.as_ref()));
        problems.into_iter().map(Into::into).collect()
    }

    /// The file the graph was loaded from or last saved to.
    #[getter]
    fn file(&self) -> Option<PathBuf> {
        self.state().file.clone()
    }

    /// The one-line description.
    #[getter]
    fn get_description(&self) -> Option<String> {
        self.state().doc.description.clone()
    }

    #[setter]
    fn set_description(&self, text: Option<String>) {
        self.state().doc.description = text;
    }

    /// A snapshot of the nodes: id → {"type", "params", "pos"}. Edit with `set`, `add_node`
    /// and `remove_node`.
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        let st = self.state();
        for (id, n) in &st.doc.nodes.0 {
            let d = PyDict::new(py);
            d.set_item("type", &n.type_name)?;
            let params = PyDict::new(py);
            for (k, v) in &n.params {
                params.set_item(k, crate::param_values::to_py(py, v)?)?;
            }
            d.set_item("params", params)?;
            d.set_item("pos", n.pos)?;
            out.set_item(id, d)?;
        }
        Ok(out)
    }

    /// The edges as `("from.output", "to.input")` tuples.
    #[getter]
    fn edges(&self) -> Vec<(String, String)> {
        self.state().doc.edges.clone()
    }

    /// What the graph exposes as a preset: {"inputs", "outputs", "params"} (name → inner
    /// port), or None.
    #[getter]
    fn interface<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let st = self.state();
        let Some(i) = &st.doc.interface else { return Ok(None) };
        let d = PyDict::new(py);
        d.set_item("inputs", i.inputs.clone())?;
        d.set_item("outputs", i.outputs.clone())?;
        d.set_item("params", i.params.clone())?;
        Ok(Some(d))
    }

    /// Node ids that actually cooked (were not served from the cache) in the last `cook` or
    /// `render`, in cook order.
    #[getter]
    fn last_cooked(&self) -> Vec<String> {
        lock(&self.last_cooked).clone()
    }

    /// `(node, message)` of every warning nodes reported in the last `cook` or `render` — what
    /// a node noticed that did not stop it ("the flame touches the bottom edge in 90 % of
    /// frames: …"). Nodes served from the cache do not report theirs again.
    #[getter]
    fn last_warnings(&self) -> Vec<(String, String)> {
        lock(&self.last_warnings).clone()
    }

    /// Adds node `id` of type `type` (see `pyrograph.nodes()`; `graph.include` for a preset)
    /// with parameters given as keywords.
    #[pyo3(signature = (id, r#type, **params))]
    fn add_node(&self, py: Python<'_>, id: &str, r#type: &str, params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        if id.is_empty() || id.contains(['.', '/']) {
            return Err(graph_error(py, Some(id), None, &format!("node id '{id}' must be non-empty, without '.' or '/'")));
        }
        let reg = self.state().registry();
        if reg.desc(r#type).is_none() {
            let hint = reg.suggest(r#type).map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default();
            return Err(graph_error(
                py,
                Some(id),
                None,
                &format!("unknown node type '{}'{hint}", pyrograph_frontend::core::error::shortened(r#type)),
            ));
        }
        let mut node = NodeDoc::new(r#type);
        if let Some(params) = params {
            for (k, v) in params.iter() {
                let name: String = k.extract()?;
                check_param(py, &reg, id, r#type, &name)?;
                node.params.insert(name, crate::param_values::from_py(&v)?);
            }
        }
        let mut st = self.state();
        if st.node(id).is_some() {
            return Err(graph_error(py, Some(id), None, &format!("a node '{id}' already exists")));
        }
        st.push_node(id, node);
        self.edited();
        Ok(())
    }

    /// Removes node `id` and every edge touching it.
    fn remove_node(&self, py: Python<'_>, id: &str) -> PyResult<()> {
        let mut st = self.state();
        let before = st.doc.nodes.0.len();
        st.doc.nodes.0.retain(|(k, _)| k != id);
        st.reindex();
        if st.doc.nodes.0.len() == before {
            return Err(graph_error(py, Some(id), None, &format!("no node '{id}' in the graph")));
        }
        let touches = |e: &str| split_endpoint(e).is_some_and(|(n, _)| n == id);
        st.doc.edges.retain(|(a, b)| !touches(a) && !touches(b));
        st.doc.ungroup_node(id);
        self.edited();
        Ok(())
    }

    /// Connects output `src` ("node.output") to input `dst` ("node.input"). Types are checked
    /// when the graph is checked or cooked.
    fn connect(&self, py: Python<'_>, src: &str, dst: &str) -> PyResult<()> {
        let mut st = self.state();
        for e in [src, dst] {
            let (n, _) = endpoint(py, e)?;
            st.node_mut(py, n)?;
        }
        st.doc.connect(src, dst);
        self.edited();
        Ok(())
    }

    /// Removes the edge `src` → `dst`.
    fn disconnect(&self, py: Python<'_>, src: &str, dst: &str) -> PyResult<()> {
        let mut st = self.state();
        let before = st.doc.edges.len();
        st.doc.edges.retain(|(a, b)| !(a == src && b == dst));
        if st.doc.edges.len() == before {
            return Err(graph_error(py, None, None, &format!("no edge {src} -> {dst}")));
        }
        self.edited();
        Ok(())
    }

    /// Sets parameter `endpoint` ("node.param") to `value` (bool, int, float, str, path or a
    /// tuple for colours and vectors; `"keys([(0, 1.0), (40, 2.0)])"` or `"expr(sin(time))"` to
    /// animate it); the next cook re-cooks only what depends on it.
    fn set(&self, py: Python<'_>, endpoint: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = crate::param_values::from_py(value)?;
        self.set_param(py, endpoint, v)
    }

    /// Keys parameter `endpoint`: `keys` is a list of `(frame, value)` or
    /// `(frame, value, interpolation)` ("smooth", "linear", "constant", "ease"); `extrapolation`
    /// is "hold", "cycle" or "linear" on both sides, or a `(before, after)` pair.
    #[pyo3(signature = (endpoint, keys, extrapolation=None))]
    fn set_keys(
        &self,
        py: Python<'_>,
        endpoint: &str,
        keys: &Bound<'_, PyAny>,
        extrapolation: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let list = crate::param_values::from_py(keys)?;
        let arg = match extrapolation.map(crate::param_values::from_py).transpose()? {
            None => list,
            Some(ParamValue::List(sides)) => ParamValue::List(std::iter::once(list).chain(sides).collect()),
            Some(both) => ParamValue::List(vec![list, both]),
        };
        self.set_param(py, endpoint, ParamValue::Call("keys".into(), Box::new(arg)))
    }

    /// Sets parameter `endpoint` to an expression of `frame`, `time` and `fps`, e.g.
    /// `"0.5 + 0.2 * sin(time * 3)"`.
    fn set_expr(&self, py: Python<'_>, endpoint: &str, expression: &str) -> PyResult<()> {
        let form = ParamValue::Call("expr".into(), Box::new(ParamValue::String(expression.to_string())));
        self.set_param(py, endpoint, form)
    }

    /// Parameter `endpoint` ("node.param") as written in the graph, else its default (None for
    /// a preset's parameter that is not written).
    fn get<'py>(&self, py: Python<'py>, endpoint: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let (id, param) = self::endpoint(py, endpoint)?;
        let st = self.state();
        let node = st.node(id).ok_or_else(|| graph_error(py, Some(id), None, &format!("no node '{id}' in the graph")))?;
        if let Some(v) = node.params.get(param) {
            return crate::param_values::to_py(py, v).map(Some);
        }
        let ty = node.type_name.clone();
        let reg = st.registry();
        check_param(py, &reg, id, &ty, param)?;
        let default = reg.desc(&ty).and_then(|d| d.inputs.iter().find(|p| p.name == param)).and_then(|p| p.default.clone());
        default.map(|v| crate::values::to_py(py, &v)).transpose()
    }

    /// Cooks output `endpoint` ("node.port") and returns it: an image as an H×W×C float32
    /// array, a mask as H×W uint8, a number, a string, `Contours`, a `pyrograph.Value` for
    /// crate-declared types, or for a clip a lazy `Clip`, or with `frames` (range, list or
    /// "0-99:2") a list of those frames. `progress` receives a dict per event. Ctrl-C cancels.
    #[pyo3(signature = (endpoint, frames=None, progress=None))]
    fn cook<'py>(
        &self,
        py: Python<'py>,
        endpoint: &str,
        frames: Option<&Bound<'py, PyAny>>,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (id, port) = self::endpoint(py, endpoint)?;
        let graph = self.cooking_graph(py)?;
        let desc = graph.desc(id).ok_or_else(|| graph_error(py, Some(id), None, &format!("no node '{id}' in the graph")))?;
        if desc.output_index(port).is_none() {
            let names: Vec<&str> = desc.outputs.iter().map(|p| p.name.as_str()).collect();
            let msg = format!("node '{id}' has no output '{port}' (outputs: {})", names.join(", "));
            return Err(graph_error(py, Some(id), Some(port), &msg));
        }
        let wanted = frames.map(frame_selection).transpose()?;
        let (eval, last_cooked, last_warnings) = (&self.eval, &self.last_cooked, &self.last_warnings);
        let cooked = crate::run::run(py, CookSettings::default(), progress, |ctx| {
            let mut ev = lock(eval);
            let result = ev.cook(&graph, &[id], ctx);
            // Kept even when the caller raises (Ctrl-C): what did cook is cached from now on.
            *lock(last_cooked) = ev.take_log();
            *lock(last_warnings) = warning_pairs(ctx);
            drop(ev);
            let value = result.and_then(|r| r.output(&graph, id, port));
            value.and_then(|v| match (&wanted, v) {
                (None, v) => Ok(Cooked::One(v)),
                (Some(sel), Value::Clip(clip)) => {
                    let list = sel.resolve(clip.len())?;
                    pull_frames(&clip, &list, &ctx.for_node(&Arc::from(id))).map(Cooked::Frames)
                }
                (Some(_), other) => {
                    Err(NodeError::port(port, format!("is a {}, not a clip: frames= applies to clip outputs", other.type_name())))
                }
            })
        })?;
        match cooked.map_err(|e| from_node_error(py, id, &e))? {
            Cooked::One(Value::Clip(clip)) => Ok(Bound::new(py, Clip::new(clip, id, port))?.into_any()),
            Cooked::One(v) => crate::values::to_py(py, &v),
            Cooked::Frames(list) => frames_to_py(py, &list),
        }
    }

    /// Runs the graph's writers (or `nodes`) as `pyrograph render` does and returns the files
    /// of the render (written, or kept by `skip_existing`), as the CLI's manifest lists them. `out` is the folder relative output paths resolve against (default: the graph's
    /// folder); writers may not leave it unless `allow_outside_out`. `frames` limits the frames
    /// written; existing files are kept unless `overwrite`, or skipped with `skip_existing`.
    #[pyo3(signature = (out=None, frames=None, overwrite=false, skip_existing=false, nodes=None, allow_outside_out=false, progress=None))]
    #[allow(clippy::too_many_arguments)] // Python keywords, each optional.
    fn render<'py>(
        &self,
        py: Python<'py>,
        out: Option<PathBuf>,
        frames: Option<&Bound<'py, PyAny>>,
        overwrite: bool,
        skip_existing: bool,
        nodes: Option<Vec<String>>,
        allow_outside_out: bool,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Vec<PathBuf>> {
        let options = BuildOptions { output_dir: out, allow_outside_out, ..BuildOptions::default() };
        let graph = self.build_with(&options).map_err(|d| from_diagnostics(py, &d))?;
        let frames = match frames {
            Some(sel) => Some(
                frame_selection(sel)?
                    .to_frame_set()
                    .ok_or_else(|| pyo3::exceptions::PyValueError::new_err("frames= selects no frame"))?,
            ),
            None => None,
        };
        let targets: Vec<String> = match nodes {
            Some(n) => n,
            None => {
                let sinks = graph.sinks();
                if sinks.is_empty() { graph.leaves() } else { sinks }.iter().map(|s| s.to_string()).collect()
            }
        };
        let settings = CookSettings { frames, skip_existing, overwrite, cache_dir: None, sim_cache: None };
        let (eval, last_cooked, last_warnings) = (&self.eval, &self.last_cooked, &self.last_warnings);
        let (result, written) = crate::run::run(py, settings, progress, |ctx| {
            let refs: Vec<&str> = targets.iter().map(String::as_str).collect();
            let mut ev = lock(eval);
            let result = ev.cook(&graph, &refs, ctx);
            *lock(last_cooked) = ev.take_log();
            *lock(last_warnings) = warning_pairs(ctx);
            (result, ctx.written())
        })?;
        let result = result.map_err(|e| graph_error(py, None, None, &e.to_string()))?;
        let errors = result.root_errors();
        if let Some((node, e)) = errors.first() {
            let all: Vec<String> = errors.iter().map(|(n, e)| pyrograph_frontend::check::explain(n, e)).collect();
            return Err(graph_error(py, Some(node), pyrograph_frontend::check::error_port(e), &all.join("\n")));
        }
        Ok(written)
    }

    fn __eq__(&self, other: PyRef<'_, Graph>) -> bool {
        if std::ptr::eq(self, &*other) {
            return true;
        }
        // One lock at a time: `a == b` and `b == a` in two threads must not wait on each other.
        let mine = self.state().doc.clone();
        mine == other.state().doc
    }

    fn __repr__(&self) -> String {
        let st = self.state();
        let from = st.file.as_ref().map(|f| format!(" from {}", f.display())).unwrap_or_default();
        format!("<pyrograph.Graph{from}: {} nodes, {} edges>", st.doc.nodes.0.len(), st.doc.edges.len())
    }

    /// Pickles as its RON text and folder (for multiprocessing); the cache is not carried.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let from_ron = py.get_type::<Graph>().getattr("from_ron")?;
        let (text, dir) = {
            let st = self.state();
            (st.doc.to_ron(), st.dir.clone())
        };
        let args = PyTuple::new(py, [text.into_pyobject(py)?.into_any(), dir.into_pyobject(py)?.into_any()])?;
        PyTuple::new(py, [from_ron, args.into_any()])
    }
}

/// Refuses a parameter the node type does not have (includes are checked when built).
impl Graph {
    fn set_param(&self, py: Python<'_>, endpoint: &str, v: ParamValue) -> PyResult<()> {
        let (id, param) = self::endpoint(py, endpoint)?;
        let mut st = self.state();
        let reg = st.registry();
        let node = st.node_mut(py, id)?;
        check_param(py, &reg, id, &node.type_name.clone(), param)?;
        node.params.insert(param.to_string(), v);
        self.edited();
        Ok(())
    }
}

fn check_param(py: Python<'_>, reg: &Registry, id: &str, ty: &str, name: &str) -> PyResult<()> {
    let Some(desc) = reg.desc(ty) else { return Ok(()) };
    if ty == pyrograph_frontend::core::builtin::INCLUDE_TYPE || desc.input_index(name).is_some() {
        return Ok(());
    }
    let names: Vec<&str> = desc.inputs.iter().map(|p| p.name.as_str()).collect();
    let msg = format!("node '{id}' ({ty}) has no parameter '{name}' (it has: {})", names.join(", "));
    Err(graph_error(py, Some(id), Some(name), &msg))
}

/// `(node, message)` of the warnings reported so far in the cook with `ctx`.
fn warning_pairs(ctx: &pyrograph_frontend::core::CookCtx) -> Vec<(String, String)> {
    // The message shown as the CLI prints it (control characters escaped); the node id exact.
    ctx.warnings()
        .into_iter()
        .map(|w| (w.node.as_deref().unwrap_or("").to_string(), pyrograph_frontend::text::printable(&w.message).into_owned()))
        .collect()
}
