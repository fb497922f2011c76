//! Cooked values handed to Python: images and masks as read-only numpy views of the cooked
//! memory (no copy), scalars as Python numbers, contours and crate-declared types as wrappers.

use std::sync::Arc;

use numpy::ndarray::{ArrayView2, ArrayView3};
use numpy::{PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use pyrograph_frontend::core::{Contours as RustContours, Image, Mask, Value as RustValue};
use pyrograph_frontend::render::particles::Particles;

/// Keeps cooked pixels alive while numpy arrays view them: the arrays' `base`.
#[pyclass(frozen, module = "pyrograph")]
pub struct FrameMemory {
    _held: Held,
}

enum Held {
    Image(#[allow(dead_code)] Arc<Image>),
    Mask(#[allow(dead_code)] Arc<Mask>),
}

fn read_only(arr: &Bound<'_, PyAny>) -> PyResult<()> {
    let kwargs = PyDict::new(arr.py());
    kwargs.set_item("write", false)?;
    arr.call_method("setflags", (), Some(&kwargs))?;
    Ok(())
}

/// An image as an H×W×C float32 array (C = 1 for gray, 4 for RGBA) viewing the cooked samples.
/// Read-only: the frame may be shared with the evaluator's and the frame cache's copies.
pub fn image_array<'py>(py: Python<'py>, img: &Arc<Image>) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let shape = (h, w, img.channels().count());
    let view = ArrayView3::from_shape(shape, img.data())
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("image of {w}×{h}: {e}")))?;
    let owner = Bound::new(py, FrameMemory { _held: Held::Image(img.clone()) })?.into_any();
    // SAFETY: `view` points into the samples of the `Arc<Image>` that `owner` holds, and numpy
    // keeps `owner` alive as the array's base for as long as the array exists. Images behind an
    // `Arc` are never mutated, and the array is made read-only below, so nothing writes to it.
    let arr = unsafe { PyArray3::<f32>::borrow_from_array(&view, owner) }.into_any();
    read_only(&arr)?;
    Ok(arr)
}

/// A mask as an H×W uint8 array (0 outside, 255 inside), viewing the cooked bytes read-only.
pub fn mask_array<'py>(py: Python<'py>, mask: &Arc<Mask>) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let view = ArrayView2::from_shape((h, w), mask.data())
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("mask of {w}×{h}: {e}")))?;
    let owner = Bound::new(py, FrameMemory { _held: Held::Mask(mask.clone()) })?.into_any();
    // SAFETY: as for images: the view borrows the bytes of the `Arc<Mask>` held by `owner`, the
    // array's base, and the array is read-only.
    let arr = unsafe { PyArray2::<u8>::borrow_from_array(&view, owner) }.into_any();
    read_only(&arr)?;
    Ok(arr)
}

/// Contours traced from a mask: `len()`, indexing and iteration give one dict per polygon with
/// `points` (N×2 float32, x then y), `depth`, `parent`, `area` and `hole`.
#[pyclass(frozen, module = "pyrograph")]
pub struct Contours {
    inner: Arc<RustContours>,
}

#[pymethods]
impl Contours {
    /// Width of the traced mask.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }
    /// Height of the traced mask.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }
    fn __len__(&self) -> usize {
        self.inner.contours.len()
    }
    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyDict>> {
        let n = self.inner.contours.len() as isize;
        let i = if index < 0 { index + n } else { index };
        if !(0..n).contains(&i) {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!("contour {index} of {n}")));
        }
        let c = &self.inner.contours[i as usize];
        let flat: Vec<f32> = c.points.iter().flat_map(|p| [p[0], p[1]]).collect();
        let points = numpy::PyArray1::from_vec(py, flat).reshape([c.points.len(), 2])?;
        let d = PyDict::new(py);
        d.set_item("points", points)?;
        d.set_item("depth", c.depth)?;
        d.set_item("parent", c.parent)?;
        d.set_item("area", c.area)?;
        d.set_item("hole", c.is_hole())?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        format!("Contours({} polygons, {}×{})", self.inner.contours.len(), self.inner.width, self.inner.height)
    }
}

/// A cooked value of a type a node crate declares (a mesh, an Eigenfires database, a learned
/// flame model, a wind field…): its type name and summary. Such values stay inside pyrograph;
/// connect nodes to use them.
#[pyclass(frozen, name = "Value", module = "pyrograph")]
pub struct Opaque {
    value: RustValue,
}

#[pymethods]
impl Opaque {
    /// The value's type name (`Mesh`, `Basis`, `FlameModel`…).
    #[getter]
    fn r#type(&self) -> String {
        self.value.type_name()
    }
    /// A one-line summary (what the CLI prints).
    #[getter]
    fn summary(&self) -> String {
        self.value.summary()
    }
    /// Bytes the value holds.
    #[getter]
    fn nbytes(&self) -> usize {
        self.value.byte_size()
    }
    /// A hash of the content: equal values have equal fingerprints.
    #[getter]
    fn fingerprint(&self) -> u64 {
        self.value.fingerprint()
    }
    fn __repr__(&self) -> String {
        format!("<pyrograph.Value {}: {}>", self.value.type_name(), self.value.summary())
    }
}

/// A cooked per-frame value as a Python object (a clip is handled by the caller).
pub fn to_py<'py>(py: Python<'py>, v: &RustValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        RustValue::Float(f) => f.into_pyobject(py)?.into_any(),
        RustValue::Int(i) => i.into_pyobject(py)?.into_any(),
        RustValue::Bool(b) => pyo3::types::PyBool::new(py, *b).to_owned().into_any(),
        RustValue::Color(c) => PyTuple::new(py, c)?.into_any(),
        RustValue::Vec2(c) => PyTuple::new(py, c)?.into_any(),
        RustValue::Vec3(c) => PyTuple::new(py, c)?.into_any(),
        RustValue::String(s) | RustValue::Enum(s) => s.into_pyobject(py)?.into_any(),
        RustValue::Path(p) => p.into_pyobject(py)?.into_any(),
        RustValue::Image(img) => image_array(py, img)?,
        RustValue::Mask(m) => mask_array(py, m)?,
        RustValue::Contours(c) => Bound::new(py, Contours { inner: c.clone() })?.into_any(),
        RustValue::Custom(_) => match v.downcast::<Particles>() {
            Some(p) => particles_dict(py, &p)?,
            None => Bound::new(py, Opaque { value: v.clone() })?.into_any(),
        },
        RustValue::Clip(_) => Bound::new(py, Opaque { value: v.clone() })?.into_any(),
        // An animated default (a preset's keyed parameter) reads as it is written in the file.
        RustValue::Anim(a) => a.summary().into_pyobject(py)?.into_any(),
        // A ramp as the list of (position, value) keys a graph file holds.
        RustValue::Ramp(r) => crate::param_values::to_py(py, &r.to_param())?,
        // Points as the list a graph file holds (a face place reads as the text "face(F)").
        RustValue::Points(p) => crate::param_values::to_py(py, &p.to_param())?,
    })
}

/// Particles (flame trajectories, embers, roots, lights) as a dict of numpy arrays, one row per
/// particle: `position`, `velocity` (N×3), `size` (N×2), `center`, `edge` (N×4, straight RGBA),
/// `weight` (N), `group` (N, uint32), and the set's `time`, `sides` and `trails`. Copies: a
/// frame's particles are small next to its pixels.
fn particles_dict<'py>(py: Python<'py>, p: &Particles) -> PyResult<Bound<'py, PyAny>> {
    let n = p.particles.len();
    let d = PyDict::new(py);
    let rows =
        |k: usize, f: &dyn Fn(&pyrograph_frontend::render::particles::Particle) -> Vec<f32>| -> PyResult<Bound<'py, PyAny>> {
            let flat: Vec<f32> = p.particles.iter().flat_map(f).collect();
            Ok(numpy::PyArray1::from_vec(py, flat).reshape([n, k])?.into_any())
        };
    d.set_item("position", rows(3, &|q| q.position.to_vec())?)?;
    d.set_item("velocity", rows(3, &|q| q.velocity.to_vec())?)?;
    d.set_item("size", rows(2, &|q| q.size.to_vec())?)?;
    d.set_item("center", rows(4, &|q| q.center.to_vec())?)?;
    d.set_item("edge", rows(4, &|q| q.edge.to_vec())?)?;
    d.set_item("weight", numpy::PyArray1::from_vec(py, p.particles.iter().map(|q| q.weight).collect()))?;
    d.set_item("group", numpy::PyArray1::from_vec(py, p.particles.iter().map(|q| q.group).collect()))?;
    d.set_item("time", p.time)?;
    d.set_item("sides", p.sides)?;
    d.set_item("trails", p.trails)?;
    Ok(d.into_any())
}
