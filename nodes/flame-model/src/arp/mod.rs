//! The auto-regressive process of Stich & Magnor §4: learning it from a parameter series by EM
//! (§4, §4.1, initialization §4.2), sampling new controllable parameter series from it (§4.3,
//! §5.1), and the node types `flame_model.arp_learn` and `flame_model.arp_sample`.

pub mod condensation;
pub mod em;
pub mod kalman;
pub mod rng;
pub mod sampler;

use std::sync::Arc;

use faer::Mat;
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, NodeError, port};

pub use sampler::{ArSampler, ArpSample, BendShape, ControlPorts, Controls, Ramp, SampleError, sample};

use crate::values::{ArModel, ParamSeries};
use em::Lambda;

/// How the E-step computes the expected statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EStep {
    /// Exact Kalman filter + Rauch–Tung–Striebel smoother on the stacked state.
    Kalman,
    /// The paper's condensation (particle) approximation (§4.1) with this many particles N_c.
    Condensation {
        /// N_c.
        particles: usize,
        /// Seed of the particle filter (each iteration uses seed + iteration).
        seed: u64,
    },
}

/// Settings of [`learn`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearnOptions {
    /// Order K of the process.
    pub order: usize,
    /// E-steps at most (each is one evaluation of the likelihood).
    pub max_iterations: usize,
    /// Stop after this many consecutive iterations without an increase of the likelihood (§5: 3).
    pub patience: usize,
    /// An iteration counts as an increase only if it gains more than `tolerance · max(1, |ℓ|)`.
    pub tolerance: f64,
    /// The E-step.
    pub e_step: EStep,
    /// Initial observation-noise variance in the unit-variance space (§4.2: small, the
    /// observations are first taken as almost exact).
    pub initial_observation_noise: f64,
    /// Lower bound of the observation-noise variances in the unit-variance space.
    pub min_observation_noise: f64,
    /// Where EM starts.
    pub init: Init,
    /// Learn the constant d (§4). Off holds d = 0 on the centred data, so the process mean is
    /// the training mean exactly: with 150 frames of a slowly drifting flame (lag-1
    /// autocorrelation 0.95) the learned d leaves the process mean a third of a standard
    /// deviation off the training mean, which a 600-frame sample then shows.
    pub learn_constant: bool,
}

pyrograph_core::choice! {
    /// The starting parameters λ_0 of EM.
    pub enum Init {
        /// §4.2: diagonal A_k from each parameter's own AR fit, d = 0, B = diag(sd).
        Diagonal = "diagonal",
        /// The full VAR(K) by conditional least squares on the observations (the no-noise limit).
        LeastSquares = "least_squares",
    }
}

impl Default for LearnOptions {
    fn default() -> Self {
        LearnOptions {
            order: 2,
            max_iterations: 200,
            patience: 3,
            tolerance: 1e-7,
            e_step: EStep::Kalman,
            initial_observation_noise: 0.01,
            min_observation_noise: 1e-6,
            init: Init::Diagonal,
            learn_constant: false,
        }
    }
}

/// Why [`learn`] could not learn a process: each variant blames one input (the series, the
/// order) or says where EM failed, so `flame_model.arp_learn` can name the right port.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LearnError {
    /// The training series is unusable (empty, too short, not finite, a constant column).
    #[error("{0}")]
    Series(String),
    /// The order K is 0.
    #[error("the order K must be at least 1")]
    Order,
    /// The least-squares start ([`Init::LeastSquares`]) failed.
    #[error("least-squares start: {0}")]
    LeastSquares(String),
    /// An E- or M-step failed (1-based iteration).
    #[error("EM iteration {iteration}: {message}")]
    Iteration {
        /// The iteration, counted from 1.
        iteration: usize,
        /// What failed.
        message: String,
    },
    /// EM ran no iteration, so there is no model.
    #[error("EM ran no iteration")]
    NoIteration,
    /// The learned noise covariance has no Cholesky factor, even with jitter.
    #[error("the learned noise covariance B Bᵀ is not positive semi-definite")]
    NoiseCovariance,
    /// The learned process is unstable: the spectral radius of its companion matrix.
    #[error(
        "the learned process is unstable: the spectral radius of its companion matrix is {0:.4} ≥ 1, so samples would \
         diverge; use more frames, fewer parameters or a lower order K"
    )]
    Unstable(f64),
    /// The learned model failed its own checks.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The cook was cancelled.
    #[error("cancelled")]
    Cancelled,
}

/// What is wrong with an [`ArModel`] for sampling: malformed, unstable, or a bad history.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// Shapes or numbers of the model are wrong (which ones).
    #[error("malformed ARP: {0}")]
    Malformed(&'static str),
    /// The eigenvalues of the companion matrix could not be computed.
    #[error("eigenvalues of the companion matrix: {0}")]
    Eigenvalues(String),
    /// The companion matrix has spectral radius ≥ 1 (its value).
    #[error("the process is unstable (companion spectral radius {0:.4} ≥ 1); its samples would diverge")]
    Unstable(f64),
    /// A history that is not `order` finite rows of `dim` parameters.
    #[error("the initial state must be {order} finite rows of {dim} parameters")]
    History {
        /// K rows expected.
        order: usize,
        /// D parameters per row.
        dim: usize,
    },
}

/// Minimum number of frames to learn an order-`order` process over `dim` parameters: each row of
/// [A_1 … A_K d] has K·D + 1 unknowns and needs as many transitions.
pub fn min_frames(dim: usize, order: usize) -> usize {
    order * dim + order + 1
}

/// Checks a training series: at least [`min_frames`] rows, every value finite, no parameter of
/// zero variance. Errors name the parameter (and frame).
pub fn validate_series(series: &ParamSeries, order: usize) -> Result<(), LearnError> {
    let dim = series.dim();
    if dim == 0 {
        return Err(LearnError::Series("the parameter series has no columns".into()));
    }
    if series.data.len() != series.frames * dim {
        return Err(LearnError::Series(format!(
            "the series holds {} values, not frames × parameters = {} × {dim}",
            series.data.len(),
            series.frames
        )));
    }
    if order == 0 {
        return Err(LearnError::Order);
    }
    let need = min_frames(dim, order);
    if series.frames < need {
        return Err(LearnError::Series(format!(
            "too few frames for K = {order}: {} frames of {dim} parameters, an order-{order} process needs at least \
             K·D + K + 1 = {need}",
            series.frames
        )));
    }
    if let Some(k) = series.data.iter().position(|v| !v.is_finite()) {
        return Err(LearnError::Series(format!(
            "parameter '{}' is {} at frame {}",
            series.names[k % dim],
            series.data[k],
            k / dim
        )));
    }
    let (mean, sd) = column_moments(series);
    for i in 0..dim {
        if sd[i] <= 1e-12 * mean[i].abs().max(1e-300) || sd[i] == 0.0 {
            return Err(LearnError::Series(format!(
                "parameter '{}' does not vary (constant {}); a zero-variance parameter cannot be scaled to unit variance \
                 (§4.2) — drop it from the series",
                series.names[i], mean[i]
            )));
        }
    }
    Ok(())
}

/// Mean and (population) standard deviation of every column.
pub fn column_moments(series: &ParamSeries) -> (Vec<f64>, Vec<f64>) {
    let (dim, t) = (series.dim(), series.frames.max(1) as f64);
    let mut mean = vec![0.0; dim];
    for row in series.data.chunks_exact(dim) {
        mean.iter_mut().zip(row).for_each(|(m, v)| *m += v / t);
    }
    let mut var = vec![0.0; dim];
    for row in series.data.chunks_exact(dim) {
        for i in 0..dim {
            var[i] += (row[i] - mean[i]).powi(2) / t;
        }
    }
    (mean, var.into_iter().map(f64::sqrt).collect())
}

/// Learns the ARP of eq. 2 from `series` by EM (§4–4.2).
///
/// The data are scaled to zero mean and unit variance, λ_0 is the §4.2 heuristic, and EM runs
/// until the likelihood has not increased for `patience` consecutive iterations (or
/// `max_iterations`). The returned model is the one of the best likelihood (with the exact
/// E-step that is the last one: EM never decreases it); its `log_likelihood` lists the
/// likelihood of the original (unscaled) data at every iteration. A fit whose companion matrix
/// has spectral radius ≥ 1 is an error: its samples would diverge.
pub fn learn(series: &ParamSeries, opts: &LearnOptions, ctx: &CookCtx) -> Result<ArModel, LearnError> {
    validate_series(series, opts.order)?;
    let (dim, frames, k) = (series.dim(), series.frames, opts.order);
    let (offset, scale) = column_moments(series);
    let mut y = series.data.clone();
    for row in y.chunks_exact_mut(dim) {
        for i in 0..dim {
            row[i] = (row[i] - offset[i]) / scale[i];
        }
    }
    // log p(x) = log p(y) − T Σ ln σ_i (change of variables back to the original units).
    let jacobian = -(frames as f64) * scale.iter().map(|s| s.ln()).sum::<f64>();
    let mut lam = match opts.init {
        Init::Diagonal => em::initial_lambda(&y, frames, dim, k, opts.initial_observation_noise),
        Init::LeastSquares => em::least_squares_lambda(&y, frames, dim, k, opts.initial_observation_noise, opts.learn_constant)
            .map_err(LearnError::LeastSquares)?,
    };
    let mut history = Vec::new();
    let mut best: Option<(f64, Lambda)> = None;
    let mut stall = 0;
    for it in 0..opts.max_iterations.max(1) {
        ctx.check_cancel().map_err(|_| LearnError::Cancelled)?;
        let stats = match opts.e_step {
            EStep::Kalman => kalman::kalman_estep(&y, frames, &lam),
            EStep::Condensation { particles, seed } => {
                condensation::condensation_estep(&y, frames, &lam, particles, seed.wrapping_add(it as u64))
            }
        }
        .map_err(|message| LearnError::Iteration { iteration: it + 1, message })?;
        let ll = stats.log_likelihood + jacobian;
        history.push(ll);
        ctx.frame_progress(it + 1, opts.max_iterations);
        match &best {
            Some((b, _)) if ll <= b + opts.tolerance * b.abs().max(1.0) => {
                stall += 1;
                if ll > *b {
                    best = Some((ll, lam.clone()));
                }
            }
            _ => {
                stall = 0;
                best = Some((ll, lam.clone()));
            }
        }
        if stall >= opts.patience.max(1) || it + 1 >= opts.max_iterations {
            break;
        }
        lam = em::m_step(&stats, &lam, opts.min_observation_noise, opts.learn_constant)
            .map_err(|message| LearnError::Iteration { iteration: it + 1, message })?;
    }
    let Some((_, lam)) = best else {
        return Err(LearnError::NoIteration);
    };
    let model = to_model(series, &lam, offset, scale, history)?;
    let rho = spectral_radius(&model)?;
    if rho >= 1.0 {
        return Err(LearnError::Unstable(rho));
    }
    Ok(model)
}

fn to_model(
    series: &ParamSeries,
    lam: &Lambda,
    offset: Vec<f64>,
    scale: Vec<f64>,
    history: Vec<f64>,
) -> Result<ArModel, LearnError> {
    let (dim, k) = (lam.dim, lam.order);
    let mut a = Vec::with_capacity(k * dim * dim);
    for blk in 0..k {
        for i in 0..dim {
            for j in 0..dim {
                a.push(lam.a[(i, blk * dim + j)]);
            }
        }
    }
    let b = cholesky_lower(&lam.q)?;
    let initial = series.data[(series.frames - k) * dim..].to_vec();
    Ok(ArModel {
        names: series.names.clone(),
        order: k,
        a,
        d: lam.d.clone(),
        b,
        observation_noise: lam.r.clone(),
        offset,
        scale,
        initial,
        log_likelihood: history,
        fps: series.fps,
    })
}

/// B with B Bᵀ = Q (lower Cholesky factor, row-major); a tiny jitter is added if Q is only
/// semi-definite.
fn cholesky_lower(q: &Mat<f64>) -> Result<Vec<f64>, LearnError> {
    let dim = q.nrows();
    let mut jitter = 0.0;
    for _ in 0..8 {
        let mut m = q.clone();
        for i in 0..dim {
            m[(i, i)] += jitter;
        }
        if let Ok(llt) = m.llt(faer::Side::Lower) {
            let l = llt.L();
            return Ok((0..dim * dim).map(|k| if k % dim <= k / dim { l[(k / dim, k % dim)] } else { 0.0 }).collect());
        }
        jitter = if jitter == 0.0 { 1e-12 } else { jitter * 100.0 };
    }
    Err(LearnError::NoiseCovariance)
}

/// Checks the shapes and numbers of an [`ArModel`].
pub fn validate_model(m: &ArModel) -> Result<(), ModelError> {
    let (dim, k) = (m.dim(), m.order);
    let bad = |what: &'static str| Err(ModelError::Malformed(what));
    if dim == 0 || k == 0 {
        return bad("no parameters or order 0");
    }
    if m.a.len() != k * dim * dim {
        return bad("A has the wrong size");
    }
    if m.d.len() != dim || m.b.len() != dim * dim || m.offset.len() != dim || m.scale.len() != dim {
        return bad("d, B, offset or scale has the wrong size");
    }
    if m.initial.len() != k * dim {
        return bad("the initial state is not K rows");
    }
    let all = m.a.iter().chain(&m.d).chain(&m.b).chain(&m.offset).chain(&m.scale).chain(&m.initial);
    if all.clone().any(|v| !v.is_finite()) {
        return bad("it holds a NaN or infinite number");
    }
    Ok(())
}

/// Spectral radius of the companion matrix [[A_1 … A_K], [I 0]]: the process is stable (its
/// samples stay bounded in distribution) iff this is < 1.
pub fn spectral_radius(m: &ArModel) -> Result<f64, ModelError> {
    validate_model(m)?;
    let (dim, k) = (m.dim(), m.order);
    let n = dim * k;
    let f = Mat::<f64>::from_fn(n, n, |i, j| {
        if i < dim {
            let (blk, jj) = (j / dim, j % dim);
            m.a[blk * dim * dim + i * dim + jj]
        } else if j + dim == i {
            1.0
        } else {
            0.0
        }
    });
    let ev = f.eigenvalues().map_err(|e| ModelError::Eigenvalues(format!("{e:?}")))?;
    Ok(ev.iter().map(|c| c.re.hypot(c.im)).fold(0.0, f64::max))
}

pyrograph_core::choice! {
    /// The E-step of `flame_model.arp_learn`: the kinds of [`EStep`].
    pub enum EStepKind {
        /// [`EStep::Kalman`].
        Kalman = "kalman",
        /// [`EStep::Condensation`].
        Condensation = "condensation",
    }
}

pyrograph_core::node! {
    /// Learns the auto-regressive process x_t = Σ_k A_k x_{t−k} + d + B w_t of a parameter series by EM (Stich & Magnor §4, §4.1).
    ///
    /// The state is observed through noise; the E-step is an exact Kalman smoother on the stacked state (K·D) or the
    /// paper's condensation with N_c particles. λ_0 follows §4.2: diagonal A_k from each parameter's own AR fit, d = 0,
    /// B = diag(standard deviations), the data scaled to unit variance and the result rescaled. EM stops when the
    /// likelihood has not increased for 3 consecutive iterations (§5). An unstable fit (companion spectral radius ≥ 1)
    /// is an error.
    #[node("flame_model.arp_learn", "Flame model", WholeClip)]
    pub struct ArpLearn {
        /// Training parameter series x_t (e.g. flame_model.fit's params).
        params: Arc<ParamSeries>,
        /// Order K of the process (§5: 2).
        #[range(1, 16)]
        order: usize = 2,
        /// E-step: exact Kalman smoother, or the paper's condensation particle filter (§4.1).
        e_step: EStepKind = EStepKind::Kalman,
        /// Particles N_c of the condensation E-step (§4.1: 50–300; §5: 200).
        #[range(10, 100_000)]
        particles: usize = 200,
        /// Most EM iterations.
        #[range(1, 100_000)]
        max_iterations: usize = 200,
        /// Stop after this many iterations without a likelihood increase (§5: 3).
        #[range(1, 1000)]
        patience: usize = 3,
        /// Relative likelihood gain below which an iteration does not count as an increase.
        #[range(0.0, 1.0)]
        tolerance: f64 = 1e-7,
        /// Seed of the condensation particle filter.
        #[range(0, u32::MAX)]
        seed: u64 = 0,
        /// λ_0: the paper's diagonal start (§4.2), or the full VAR(K) by least squares on the observations.
        init: Init = Init::Diagonal,
        /// Learn d (§4). Off holds d = 0 on the centred data so the process mean is the training mean exactly; a short,
        /// slowly drifting clip otherwise leaves the synthesized mean visibly off.
        learn_constant: bool = false,
    }
    pub struct ArpLearnOut {
        /// The learned process λ = {A, d, B} with scaling and initial state.
        model: Arc<ArModel>,
        /// Log-likelihood of the training data after each EM iteration (one column; plot it with flame_model.param_plot).
        log_likelihood: Arc<ParamSeries>,
        /// Spectral radius of the learned companion matrix (< 1: stable).
        spectral_radius: f64,
    }
}

impl Cook for ArpLearn {
    fn cook(self, ctx: &CookCtx) -> Result<ArpLearnOut, NodeError> {
        let e_step = match self.e_step {
            EStepKind::Kalman => EStep::Kalman,
            EStepKind::Condensation => EStep::Condensation { particles: self.particles, seed: self.seed },
        };
        let tolerance = self.tolerance;
        if !tolerance.is_finite() || tolerance < 0.0 {
            return Err(NodeError::port(port!(ArpLearn, tolerance), format!("must be a finite number ≥ 0, got {tolerance}")));
        }
        let opts = LearnOptions {
            order: self.order,
            max_iterations: self.max_iterations,
            patience: self.patience,
            tolerance,
            e_step,
            init: self.init,
            learn_constant: self.learn_constant,
            ..LearnOptions::default()
        };
        let model = learn(&self.params, &opts, ctx).map_err(ArpLearn::learn_error)?;
        let rho = spectral_radius(&model).map_err(ArpSample::model_error)?;
        let ll = ParamSeries {
            names: vec!["log_likelihood".into()],
            frames: model.log_likelihood.len(),
            data: model.log_likelihood.clone(),
            fps: 1.0,
        };
        Ok(ArpLearnOut { model: Arc::new(model), log_likelihood: Arc::new(ll), spectral_radius: rho })
    }
}

impl ArpLearn {
    /// The node's error for a failed [`learn`]: a bad series names `params`, a zero order names
    /// `order`; a malformed model reads as it does for `flame_model.arp_sample`.
    pub(crate) fn learn_error(e: LearnError) -> NodeError {
        match e {
            LearnError::Series(m) => NodeError::port(port!(ArpLearn, params), m),
            LearnError::Order => NodeError::port(port!(ArpLearn, order), e.to_string()),
            LearnError::Model(e) => ArpSample::model_error(e),
            LearnError::Cancelled => NodeError::Cancelled,
            LearnError::LeastSquares(_)
            | LearnError::Iteration { .. }
            | LearnError::NoIteration
            | LearnError::NoiseCovariance
            | LearnError::Unstable(_) => NodeError::msg(e.to_string()),
        }
    }
}

#[cfg(test)]
mod tests;
