//! Values of the learned flame model (Stich & Magnor, "Learning Flames"): parameter series x_t
//! (§3), the auto-regressive process that drives them (§4) and the generic flame model (§3–3.2).

use std::hash::Hash;

use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

fn hash_f64s(h: &mut Fingerprinter, values: &[f64]) {
    values.len().hash(h);
    values.iter().for_each(|v| v.to_bits().hash(h));
}

/// A time series of parameter vectors x_t (Stich & Magnor §3): `frames × dim` values, row-major,
/// one named column per parameter (path, width, eigenflame weights, height, …).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ParamSeries {
    /// Name of each column (`dim` of them).
    pub names: Vec<String>,
    /// Number of rows (time steps).
    pub frames: usize,
    /// Row-major `frames × names.len()`.
    pub data: Vec<f64>,
    /// Frames per second of the series.
    pub fps: f64,
}

impl ParamSeries {
    /// Wraps row-major data; `None` if its length is not `frames × names.len()`.
    pub fn new(names: Vec<String>, frames: usize, data: Vec<f64>, fps: f64) -> Option<Self> {
        (frames.checked_mul(names.len())? == data.len()).then_some(ParamSeries { names, frames, data, fps })
    }

    /// Number of parameters per row.
    pub fn dim(&self) -> usize {
        self.names.len()
    }

    /// Row `t`, `None` past the last.
    pub fn row(&self, t: usize) -> Option<&[f64]> {
        let d = self.dim();
        self.data.get(t * d..(t + 1) * d)
    }
}

impl ValueType for ParamSeries {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "ParamSeries",
        doc: "A time series of flame-model parameter vectors x_t (Stich & Magnor §3).",
        color: [230, 150, 200],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (&self.names, self.frames, self.fps.to_bits()).hash(h);
        hash_f64s(h, &self.data);
    }

    fn byte_size(&self) -> usize {
        self.data.len() * 8 + self.names.iter().map(|n| n.len() + 24).sum::<usize>()
    }

    fn summary(&self) -> String {
        format!("ParamSeries {} frames x {} parameters", self.frames, self.dim())
    }
}

/// A learned auto-regressive process (Stich & Magnor §4, eq. 2):
/// x_t = Σ_{k=1..K} A_k x_{t−k} + d + B w_t, fitted on unit-variance scaled data
/// (`scaled = (x − offset) / scale`), so sampling rescales with the same `offset` and `scale`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ArModel {
    /// Parameter names (`dim` of them), as in the training [`ParamSeries`].
    pub names: Vec<String>,
    /// Order K.
    pub order: usize,
    /// A_1..A_K, each `dim × dim` row-major, one after another.
    pub a: Vec<f64>,
    /// Constant term d (`dim`).
    pub d: Vec<f64>,
    /// Noise matrix B, `dim × dim` row-major (w_t is unit Gaussian).
    pub b: Vec<f64>,
    /// Observation noise variances (`dim`; the diagonal of the observation covariance), in the
    /// unit-variance space of the learning.
    pub observation_noise: Vec<f64>,
    /// Per-parameter offset subtracted before scaling (the training mean).
    pub offset: Vec<f64>,
    /// Per-parameter scale (the training standard deviation).
    pub scale: Vec<f64>,
    /// The last K training rows (unscaled, oldest first): a default initial state for sampling.
    pub initial: Vec<f64>,
    /// Log-likelihood after each EM iteration.
    pub log_likelihood: Vec<f64>,
    /// Frames per second of the training series.
    pub fps: f64,
}

impl ArModel {
    /// Number of parameters.
    pub fn dim(&self) -> usize {
        self.names.len()
    }
}

impl ValueType for ArModel {
    const INFO: &'static TypeInfo =
        &TypeInfo { name: "ArModel", doc: "A learned auto-regressive process (Stich & Magnor §4).", color: [230, 150, 200] };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (&self.names, self.order, self.fps.to_bits()).hash(h);
        for v in
            [&self.a, &self.d, &self.b, &self.observation_noise, &self.offset, &self.scale, &self.initial, &self.log_likelihood]
        {
            hash_f64s(h, v);
        }
    }

    fn byte_size(&self) -> usize {
        (self.a.len() + self.b.len() + self.d.len() + self.initial.len() + 4 * self.dim() + self.log_likelihood.len()) * 8
    }

    fn summary(&self) -> String {
        format!("ArModel K={} over {} parameters, {} EM iterations", self.order, self.dim(), self.log_likelihood.len())
    }
}

/// The generic flame model (Stich & Magnor §3): the sizes of the parameter vector, the
/// normalization frame fixed for the whole fitted clip, and the eigenflames of the normalized
/// images — enough to turn a parameter row back into an image.
///
/// A parameter row is `[path_0..N_p, width_0..N_w, eig_0..N_e, height]` (pixels for path, width
/// and height). A frame point is `anchor + v·height·axis + (path(v) + u·width(v))·across`, where
/// `across` is `axis` turned by +90° (x right, y down), `path(v)`/`width(v)` are the natural cubic
/// splines through the samples at equidistant heights v = 0..1, and `(u, v)` is a point of the
/// normalized image (columns u ∈ −u_extent..u_extent, rows v from `v_range[1]` at the top down to
/// `v_range[0]`).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FlameModel {
    /// Path samples N_p.
    pub path_samples: usize,
    /// Width samples N_w.
    pub width_samples: usize,
    /// Eigenflames N_e.
    pub eigenflames: usize,
    /// Width of the normalized images.
    pub width: u32,
    /// Height of the normalized images.
    pub height: u32,
    /// Mean normalized image (`width × height`, row-major).
    pub mean: Vec<f32>,
    /// Eigenflames, `eigenflames × width·height`, component-major.
    pub basis: Vec<f32>,
    /// Their eigenvalues, largest first.
    pub eigenvalues: Vec<f64>,
    /// Output frame size of the fitted footage (width, height).
    pub frame_size: (u32, u32),
    /// Flame base point in frame pixels (x right, y down).
    pub anchor: [f64; 2],
    /// Unit main axis, base → tip, in frame pixels.
    pub axis: [f64; 2],
    /// Heights (fractions of the flame height) covered by the normalized image's bottom and top rows.
    pub v_range: [f64; 2],
    /// Half-width of the normalized image in local flame widths.
    pub u_extent: f64,
    /// The average intensity every normalized image was scaled to (0 when not normalized).
    pub mean_intensity: f64,
    /// Mean parameter row of the training frames.
    pub mean_params: Vec<f64>,
}

impl FlameModel {
    /// Length of the parameter vector: N_p + N_w + N_e + 1.
    pub fn dim(&self) -> usize {
        self.path_samples + self.width_samples + self.eigenflames + 1
    }
}

impl ValueType for FlameModel {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "FlameModel",
        doc: "The generic flame model: parameter sizes and eigenflames (Stich & Magnor §3).",
        color: [230, 150, 200],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.path_samples, self.width_samples, self.eigenflames, self.width, self.height, self.frame_size).hash(h);
        hash_f32s(h, &self.mean);
        hash_f32s(h, &self.basis);
        hash_f64s(h, &self.eigenvalues);
        let fixed = [self.anchor[0], self.anchor[1], self.axis[0], self.axis[1], self.v_range[0], self.v_range[1]];
        hash_f64s(h, &fixed);
        hash_f64s(h, &[self.u_extent, self.mean_intensity]);
        hash_f64s(h, &self.mean_params);
    }

    fn byte_size(&self) -> usize {
        (self.mean.len() + self.basis.len()) * 4 + (self.eigenvalues.len() + self.mean_params.len() + 10) * 8
    }

    fn summary(&self) -> String {
        format!(
            "FlameModel Np={} Nw={} Ne={} on {}x{} normalized images",
            self.path_samples, self.width_samples, self.eigenflames, self.width, self.height
        )
    }
}
