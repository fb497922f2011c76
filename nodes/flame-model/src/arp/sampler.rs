//! Sampling a learned ARP (Stich & Magnor §4.3): eq. 2 evaluated repeatedly, then rescaled, with
//! the §5.1 controls (an offset on the path parameters bends the flame, as wind does; height,
//! width and overall scale) applied per frame.

use std::sync::Arc;

use pyrograph_core::declare::{Anim, AnimError, Cook};
use pyrograph_core::{CookCtx, NodeError, port};

use super::rng::Rng;
use super::{ModelError, spectral_radius};
use crate::values::{ArModel, ParamSeries};

/// Steps eq. 2 with flat, preallocated arrays: one step is a `D × K·D` mat-vec, a triangular
/// `D × D` mat-vec and D normal deviates, with no allocation.
pub struct ArSampler {
    dim: usize,
    n: usize,
    /// [A_1 … A_K] row-major `D × K·D` (row i: A_1 row i, A_2 row i, …).
    a: Vec<f64>,
    d: Vec<f64>,
    /// B row-major; `b_len[i]` is the number of leading entries of row i that can be non-zero.
    b: Vec<f64>,
    b_len: Vec<usize>,
    /// Scaled history z = (x_{t−1}, …, x_{t−K}).
    z: Vec<f64>,
    w: Vec<f64>,
    x: Vec<f64>,
    offset: Vec<f64>,
    scale: Vec<f64>,
    /// Observation noise standard deviations (scaled space).
    obs_sd: Vec<f64>,
    rng: Rng,
}

impl ArSampler {
    /// A sampler starting from the model's initial state (the last K training rows), seeded by
    /// `seed`. Unstable or malformed models are errors.
    pub fn new(model: &ArModel, seed: u64) -> Result<Self, ModelError> {
        let rho = spectral_radius(model)?;
        if rho >= 1.0 {
            return Err(ModelError::Unstable(rho));
        }
        let (dim, k) = (model.dim(), model.order);
        let n = dim * k;
        let mut a = vec![0.0; dim * n];
        for blk in 0..k {
            for i in 0..dim {
                for j in 0..dim {
                    a[i * n + blk * dim + j] = model.a[blk * dim * dim + i * dim + j];
                }
            }
        }
        let b_len = (0..dim).map(|i| (0..dim).rev().find(|&j| model.b[i * dim + j] != 0.0).map_or(0, |j| j + 1)).collect();
        let mut s = ArSampler {
            dim,
            n,
            a,
            d: model.d.clone(),
            b: model.b.clone(),
            b_len,
            z: vec![0.0; n],
            w: vec![0.0; dim],
            x: vec![0.0; dim],
            offset: model.offset.clone(),
            scale: model.scale.clone(),
            obs_sd: model.observation_noise.iter().map(|r| r.max(0.0).sqrt()).collect(),
            rng: Rng::new(seed),
        };
        s.set_history(&model.initial)?;
        Ok(s)
    }

    /// Restarts from K unscaled rows (oldest first, `K × D` values).
    pub fn set_history(&mut self, rows: &[f64]) -> Result<(), ModelError> {
        let (dim, k) = (self.dim, self.n / self.dim);
        if rows.len() != self.n || rows.iter().any(|v| !v.is_finite()) {
            return Err(ModelError::History { order: k, dim });
        }
        for lag in 0..k {
            let row = &rows[(k - 1 - lag) * dim..(k - lag) * dim];
            let block = &mut self.z[lag * dim..(lag + 1) * dim];
            for (i, (z, r)) in block.iter_mut().zip(row).enumerate() {
                *z = (r - self.offset[i]) / self.scale[i];
            }
        }
        Ok(())
    }

    /// Number of parameters D.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// One step of eq. 2 in the scaled space; returns the new scaled x_t.
    #[inline]
    pub fn step_scaled(&mut self) -> &[f64] {
        let (dim, n) = (self.dim, self.n);
        self.rng.fill_normal(&mut self.w);
        for i in 0..dim {
            let row = &self.a[i * n..(i + 1) * n];
            let brow = &self.b[i * dim..i * dim + self.b_len[i]];
            self.x[i] = self.d[i] + dot(row, &self.z) + dot(brow, &self.w);
        }
        self.z.copy_within(0..n - dim, dim);
        self.z[..dim].copy_from_slice(&self.x);
        &self.x
    }

    /// One step of eq. 2, written to `out` in the original units (`D` values).
    #[inline]
    pub fn step(&mut self, out: &mut [f64]) {
        self.step_scaled();
        for (((o, x), m), s) in out.iter_mut().zip(&self.x).zip(&self.offset).zip(&self.scale) {
            *o = m + s * x;
        }
    }
}

impl ArSampler {
    /// One step of eq. 2 seen through the learned observation noise (y_t = x_t + v_t): what a
    /// camera filming the synthesized flame would measure, with the footage's frame-to-frame
    /// flicker. The noise does not feed back into the process.
    #[inline]
    pub fn observe(&mut self, out: &mut [f64]) {
        self.step_scaled();
        let dim = self.dim;
        self.rng.fill_normal(&mut self.w[..dim]);
        for (i, o) in out.iter_mut().enumerate().take(dim) {
            *o = self.offset[i] + self.scale[i] * (self.x[i] + self.obs_sd[i] * self.w[i]);
        }
    }
}

/// Σ a_i b_i over the shorter length, with eight independent partial sums: a single running
/// sum is one long chain of dependent adds (the compiler may not reorder float adds), which made
/// the sampler latency-bound.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// A control value that moves linearly from `start` (first frame) to `end` (last frame), or,
/// when `keyed`, follows keys or an expression over the output frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Ramp {
    /// Value at the first frame.
    pub start: f64,
    /// Value at the last frame.
    pub end: f64,
    /// An animated control and the frame rate its `time` counts in: it replaces the ramp.
    pub keyed: Option<(Anim<f64>, f64)>,
}

impl Ramp {
    /// The same value on every frame.
    pub fn constant(v: f64) -> Self {
        Ramp { start: v, end: v, keyed: None }
    }

    /// A linear ramp from `start` to `end`.
    pub fn linear(start: f64, end: f64) -> Self {
        Ramp { start, end, keyed: None }
    }

    /// The value at frame `f` of `frames`; a keyed control's errors name its port and the frame.
    pub fn at(&self, f: usize, frames: usize) -> Result<f64, AnimError> {
        if let Some((anim, fps)) = &self.keyed {
            return anim.at(f as f64, *fps);
        }
        Ok(if frames <= 1 { self.start } else { self.start + (self.end - self.start) * f as f64 / (frames - 1) as f64 })
    }
}

pyrograph_core::choice! {
    /// How the bend offset is spread over the path samples path_0 … path_{N_p−1} (path_0 at the base).
    pub enum BendShape {
        /// The same offset on every path sample (§5.1 taken literally: the flame shifts sideways).
        Uniform = "uniform",
        /// Offset growing linearly with height: the flame leans.
        Linear = "linear",
        /// Offset growing with the square of height: the flame bends like a plume in a cross wind.
        Quadratic = "quadratic",
    }
}

impl BendShape {
    fn weight(self, j: usize, count: usize) -> f64 {
        let h = if count <= 1 { 1.0 } else { j as f64 / (count - 1) as f64 };
        match self {
            BendShape::Uniform => 1.0,
            BendShape::Linear => h,
            BendShape::Quadratic => h * h,
        }
    }
}

/// The §5.1 controls, each a per-frame ramp: `bend` is added to the path parameters, `height`
/// multiplies the height, `width` the width parameters and `scale` all three (path, width and
/// height: the whole flame grows about its base).
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    /// Offset on the path parameters.
    pub bend: Ramp,
    /// How the offset spreads over height.
    pub bend_shape: BendShape,
    /// Height factor.
    pub height: Ramp,
    /// Width factor.
    pub width: Ramp,
    /// Overall scale factor.
    pub scale: Ramp,
    /// Add the learned observation noise to each output row ([`ArSampler::observe`]), so the
    /// synthesized series has the training footage's statistics, flicker included; off gives
    /// the noise-free process x_t.
    pub observation_noise: bool,
}

impl Default for Controls {
    fn default() -> Self {
        Controls {
            bend: Ramp::constant(0.0),
            bend_shape: BendShape::Quadratic,
            height: Ramp::constant(1.0),
            width: Ramp::constant(1.0),
            scale: Ramp::constant(1.0),
            observation_noise: true,
        }
    }
}

/// Which column plays which role, from the names `path_*`, `width_*` and `height`.
struct Roles {
    path: Vec<usize>,
    width: Vec<usize>,
    height: Option<usize>,
}

fn roles(names: &[String]) -> Roles {
    let index = |prefix: &str| -> Vec<usize> {
        let mut v: Vec<(usize, usize)> = names
            .iter()
            .enumerate()
            .filter_map(|(c, n)| n.strip_prefix(prefix).and_then(|s| s.parse::<usize>().ok()).map(|j| (j, c)))
            .collect();
        v.sort_unstable();
        v.into_iter().map(|(_, c)| c).collect()
    };
    Roles { path: index("path_"), width: index("width_"), height: names.iter().position(|n| n == "height") }
}

/// Why [`sample`] failed: the model cannot be sampled, or a keyed control could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// The model is malformed or unstable.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A keyed control failed at a frame (it names the port it was set on).
    #[error(transparent)]
    Control(#[from] AnimError),
}

/// Samples `frames` rows from `model` (§4.3) after discarding `warmup` steps, starting from the
/// model's initial state, with the §5.1 `controls`. The output has the training series' columns.
pub fn sample(model: &ArModel, frames: usize, warmup: usize, seed: u64, controls: &Controls) -> Result<ParamSeries, SampleError> {
    let mut s = ArSampler::new(model, seed)?;
    let dim = s.dim();
    let mut data = vec![0.0; frames * dim];
    let mut scratch = vec![0.0; dim];
    for _ in 0..warmup {
        s.step(&mut scratch);
    }
    let r = roles(&model.names);
    let bend_w: Vec<f64> = (0..r.path.len()).map(|j| controls.bend_shape.weight(j, r.path.len())).collect();
    for (f, row) in data.chunks_exact_mut(dim).enumerate() {
        if controls.observation_noise {
            s.observe(row);
        } else {
            s.step(row);
        }
        let (bend, hf, wf, sf) = (
            controls.bend.at(f, frames)?,
            controls.height.at(f, frames)?,
            controls.width.at(f, frames)?,
            controls.scale.at(f, frames)?,
        );
        for (j, &c) in r.path.iter().enumerate() {
            row[c] = (row[c] + bend * bend_w[j]) * sf;
        }
        for &c in &r.width {
            row[c] *= wf * sf;
        }
        if let Some(c) = r.height {
            row[c] *= hf * sf;
        }
    }
    Ok(ParamSeries { names: model.names.clone(), frames, data, fps: model.fps })
}

pyrograph_core::ports! {
    /// The §5.1 controls of `flame_model.arp_sample` as ports: each control's value, and its
    /// `_end` value on the last frame when `ramp` is on. [`ControlPorts::controls`] gives the
    /// [`Controls`] of a cook.
    pub struct ControlPorts {
        /// Offset added to the path parameters (§5.1: a bent flame, e.g. wind); keys or an expression are sampled at every output frame.
        #[range(-1.0e6, 1.0e6)]
        bend: Anim<f64> = Anim::constant(0.0),
        /// How the bend offset grows from path_0 (base) to the last path sample: same everywhere, linearly or quadratically.
        bend_shape: BendShape = BendShape::Quadratic,
        /// Factor on the flame height (§5.1).
        #[range(0.0, 100.0)]
        height: Anim<f64> = Anim::constant(1.0),
        /// Factor on the width parameters (§5.1).
        #[range(0.0, 100.0)]
        width: Anim<f64> = Anim::constant(1.0),
        /// Factor on the whole flame: path, width and height (§5.1).
        #[range(0.0, 100.0)]
        scale: Anim<f64> = Anim::constant(1.0),
        /// Add the learned observation noise to each frame (the footage's flicker, and its statistics); off: the smooth process x_t.
        observation_noise: bool = true,
        /// Ramp every control linearly from its value to its `_end` value over the frames.
        ramp: bool = false,
        /// Bend offset on the last frame when `ramp` is on (linear in between).
        #[range(-1.0e6, 1.0e6)]
        bend_end: f64 = 0.0,
        /// Height factor on the last frame when `ramp` is on (linear in between).
        #[range(0.0, 100.0)]
        height_end: f64 = 1.0,
        /// Width factor on the last frame when `ramp` is on (linear in between).
        #[range(0.0, 100.0)]
        width_end: f64 = 1.0,
        /// Scale factor on the last frame when `ramp` is on (linear in between).
        #[range(0.0, 100.0)]
        scale_end: f64 = 1.0,
    }
}

impl ControlPorts {
    /// The [`Controls`] these ports describe, for a series at `fps`; a value that is not finite is
    /// an error naming its port, and so is a keyed control with `ramp` on (the keys are the ramp).
    pub fn controls(&self, fps: f64) -> Result<Controls, NodeError> {
        let finite = |v: f64, port: &str| {
            if v.is_finite() { Ok(v) } else { Err(NodeError::port(port, format!("must be finite, got {v}"))) }
        };
        // The `_end` value is read only when ramping: otherwise the control is constant.
        let pair = |start: (&Anim<f64>, &str), end: (f64, &str)| -> Result<Ramp, NodeError> {
            if start.0.is_animated() {
                if self.ramp {
                    return Err(NodeError::port(
                        start.1,
                        format!("is keyed, and ramp is on: the keys already move it; turn ramp off or remove {}", end.1),
                    ));
                }
                return Ok(Ramp { keyed: Some((start.0.clone(), fps)), ..Ramp::constant(*start.0.value()) });
            }
            let start = finite(*start.0.value(), start.1)?;
            let end = if self.ramp { finite(end.0, end.1)? } else { start };
            Ok(Ramp::linear(start, end))
        };
        Ok(Controls {
            bend: pair((&self.bend, port!(ControlPorts, bend)), (self.bend_end, port!(ControlPorts, bend_end)))?,
            bend_shape: self.bend_shape,
            height: pair((&self.height, port!(ControlPorts, height)), (self.height_end, port!(ControlPorts, height_end)))?,
            width: pair((&self.width, port!(ControlPorts, width)), (self.width_end, port!(ControlPorts, width_end)))?,
            scale: pair((&self.scale, port!(ControlPorts, scale)), (self.scale_end, port!(ControlPorts, scale_end)))?,
            observation_noise: self.observation_noise,
        })
    }
}

pyrograph_core::node! {
    /// Synthesizes a new parameter series of any length by evaluating the learned ARP repeatedly (Stich & Magnor §4.3), with the §5.1 controls.
    ///
    /// Starts from the last K training rows, deterministic for a seed. An offset on the path parameters bends the flame
    /// (wind); height, width and scale multiply the height, the width parameters and the whole flame. With `ramp` on,
    /// every control moves linearly from its value on the first frame to its `_end` value on the last.
    #[node("flame_model.arp_sample", "Flame model", Simulation)]
    pub struct ArpSample {
        /// The learned process (flame_model.arp_learn).
        model: Arc<ArModel>,
        /// Number of frames to synthesize.
        #[range(1, 100_000_000)]
        frames: usize = 400,
        /// Seed of the process noise w_t.
        #[range(0, u32::MAX)]
        seed: u64 = 0,
        /// Steps run and discarded before the first output frame.
        #[range(0, 1_000_000)]
        warmup: usize = 0,
        /// The §5.1 controls.
        controls: ControlPorts,
    }
    /// The synthesized series, in the training series' columns.
    -> params: Arc<ParamSeries>
}

impl Cook for ArpSample {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<ParamSeries>, NodeError> {
        let controls = self.controls.controls(self.model.fps)?;
        ctx.check_cancel()?;
        let out = sample(&self.model, self.frames, self.warmup, self.seed, &controls).map_err(ArpSample::sample_error)?;
        Ok(Arc::new(out))
    }
}

impl ArpSample {
    /// The node's error for a model that cannot be sampled: it names the `model` port, except
    /// when the eigenvalue solver fails, which is no fault of the model.
    pub(crate) fn model_error(e: ModelError) -> NodeError {
        match e {
            ModelError::Eigenvalues(_) => NodeError::msg(e.to_string()),
            ModelError::Malformed(_) | ModelError::Unstable(_) | ModelError::History { .. } => {
                NodeError::port(port!(ArpSample, model), e.to_string())
            }
        }
    }

    /// The node's error for a failed [`sample`]: a keyed control's error names its own port.
    pub(crate) fn sample_error(e: SampleError) -> NodeError {
        match e {
            SampleError::Model(e) => ArpSample::model_error(e),
            SampleError::Control(e) => e.into(),
        }
    }
}
