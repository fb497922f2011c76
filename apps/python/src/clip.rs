//! Clips handed to Python: lazy (`len()`, indexing and slicing cook the frames asked for) so a
//! long plate never has to fit in memory, and the frame selections `cook(frames=…)` accepts.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyList, PyRange, PySlice, PyString};
use rayon::prelude::*;

use pyrograph_frontend::core::{Clip as RustClip, CookCtx, CookSettings, FrameSet, NodeError, Value};

use crate::errors::from_node_error;

/// A time-varying output, cooked lazily: `len(clip)`, `clip[i]` (a frame), `clip[a:b]` and
/// `clip.frames(sel)` (lists of frames). Frames are cached by pyrograph's frame cache, within
/// its memory budget.
#[pyclass(frozen, module = "pyrograph")]
pub struct Clip {
    clip: RustClip,
    node: Arc<str>,
    port: String,
}

impl Clip {
    /// Wraps output `port` of node `node`.
    pub fn new(clip: RustClip, node: &str, port: &str) -> Clip {
        Clip { clip, node: node.into(), port: port.into() }
    }
}

#[pymethods]
impl Clip {
    fn __len__(&self) -> usize {
        self.clip.len()
    }
    /// Frames per second.
    #[getter]
    fn fps(&self) -> f64 {
        self.clip.fps()
    }
    /// The type of each frame (`Image`, `Mask`, `Float`…).
    #[getter]
    fn element(&self) -> String {
        self.clip.element().to_string()
    }
    fn __getitem__<'py>(&self, py: Python<'py>, index: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(slice) = index.cast::<PySlice>() {
            let ind = slice.indices(self.clip.len() as isize)?;
            let list: Vec<usize> = (0..ind.slicelength).map(|k| (ind.start + k as isize * ind.step) as usize).collect();
            return self.pull(py, list, None);
        }
        let i: isize = index.extract()?;
        let n = self.clip.len() as isize;
        let at = if i < 0 { i + n } else { i };
        if !(0..n).contains(&at) {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!("frame {i} of a {n}-frame clip")));
        }
        let frames = self.pull(py, vec![at as usize], None)?;
        frames.cast_into::<PyList>()?.get_item(0)
    }
    /// The frames of `selection` (a range, a list of indices or a string such as `"0-99:2"`),
    /// cooked in parallel, as a list; `progress` receives a dict per finished frame.
    #[pyo3(signature = (selection, progress=None))]
    fn frames<'py>(
        &self,
        py: Python<'py>,
        selection: &Bound<'py, PyAny>,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let list = frame_selection(selection)?.resolve(self.clip.len()).map_err(|e| from_node_error(py, &self.node, &e))?;
        self.pull(py, list, progress)
    }
    fn __repr__(&self) -> String {
        format!(
            "<pyrograph.Clip {}.{}: {} frames of {} at {} fps>",
            self.node,
            self.port,
            self.clip.len(),
            self.clip.element(),
            self.clip.fps()
        )
    }
}

impl Clip {
    fn pull<'py>(&self, py: Python<'py>, list: Vec<usize>, progress: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyAny>> {
        let clip = &self.clip;
        let node = &self.node;
        let values = crate::run::run(py, CookSettings::default(), progress, |ctx| pull_frames(clip, &list, &ctx.for_node(node)))?;
        let values = values.map_err(|e| from_node_error(py, &self.node, &e))?;
        frames_to_py(py, &values)
    }
}

/// Frames `list` of `clip`, cooked in parallel, in the order asked.
pub fn pull_frames(clip: &RustClip, list: &[usize], ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let total = list.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    list.par_iter()
        .map(|&i| {
            let v = clip.get(i, ctx)?;
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            ctx.frame_progress(n, total);
            Ok(v)
        })
        .collect()
}

/// Cooked frames as a Python list.
pub fn frames_to_py<'py>(py: Python<'py>, values: &[Value]) -> PyResult<Bound<'py, PyAny>> {
    let items = values.iter().map(|v| crate::values::to_py(py, v)).collect::<PyResult<Vec<_>>>()?;
    Ok(PyList::new(py, items)?.into_any())
}

/// A frame selection as Python gives it: an int, a `range` or a string in the CLI's `--frames`
/// grammar (`"0-99"`, `"0-99:2"`, `"1,5,9-12"`) stay a compact [`FrameSet`] until the clip's
/// length is known, so a mistyped `"0-4000000000"` is an error, not a 30 GB list; any other
/// iterable of ints is taken as the list it already is.
pub enum Selection {
    /// A set of frame ranges, expanded only once checked against a length.
    Set(FrameSet),
    /// Frames in the order asked (repeats allowed).
    List(Vec<usize>),
}

impl Selection {
    /// The frames, checked against a clip of `len` frames.
    pub fn resolve(&self, len: usize) -> Result<Vec<usize>, NodeError> {
        let last = match self {
            Selection::Set(set) => set.last(),
            Selection::List(list) => list.iter().copied().max().unwrap_or(0),
        };
        if last >= len && !self.is_empty() {
            return Err(NodeError::msg(format!("frame {last} is past the end of a {len}-frame clip")));
        }
        Ok(match self {
            Selection::Set(set) => set.frames(),
            Selection::List(list) => list.clone(),
        })
    }

    fn is_empty(&self) -> bool {
        match self {
            // The grammar has no empty set.
            Selection::Set(_) => false,
            Selection::List(list) => list.is_empty(),
        }
    }

    /// The frames as a set, for writers.
    pub fn to_frame_set(&self) -> Option<FrameSet> {
        match self {
            Selection::Set(set) => Some(set.clone()),
            Selection::List(list) => FrameSet::from_list(list),
        }
    }
}

fn negative(f: i64) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(format!("frame {f} is negative"))
}

/// Reads a frame selection (see [`Selection`]).
pub fn frame_selection(sel: &Bound<'_, PyAny>) -> PyResult<Selection> {
    let parse = |text: &str| -> PyResult<Selection> {
        text.parse::<FrameSet>().map(Selection::Set).map_err(pyo3::exceptions::PyValueError::new_err)
    };
    if sel.is_instance_of::<PyString>() {
        return parse(&sel.extract::<String>()?);
    }
    if let Ok(one) = sel.extract::<i64>() {
        return usize::try_from(one).map(|f| Selection::List(vec![f])).map_err(|_| negative(one));
    }
    if sel.is_instance_of::<PyRange>() {
        let (start, stop, step): (i64, i64, i64) =
            (sel.getattr("start")?.extract()?, sel.getattr("stop")?.extract()?, sel.getattr("step")?.extract()?);
        if step > 0 && start >= 0 {
            if stop <= start {
                return Ok(Selection::List(Vec::new()));
            }
            // The last frame the range reaches, in the grammar's inclusive form.
            let last = start + (stop - 1 - start) / step * step;
            return parse(&format!("{start}-{last}:{step}"));
        }
    }
    let mut out = Vec::new();
    for item in sel.try_iter()? {
        let f: i64 = item?.extract()?;
        out.push(usize::try_from(f).map_err(|_| negative(f))?);
    }
    Ok(Selection::List(out))
}
