//! EM for the auto-regressive process with noisy observations (Stich & Magnor §4, §4.1):
//! the hidden state is the stacked z_t = (x_t, x_{t−1}, …, x_{t−K+1}) (dimension K·D), moving by the
//! companion form of eq. 2, observed as y_t = x_t + v_t with v_t ~ N(0, diag r).
//!
//! Two E-steps give the same expected sufficient statistics ([`Stats`]): an exact Kalman filter
//! with Rauch–Tung–Striebel smoother ([`super::kalman`]), and the paper's condensation (particle)
//! approximation ([`super::condensation`]). The M-step here is the closed-form maximum-likelihood
//! estimate of λ = {A, d, B} and of r from them; the starting values λ_0 are here too.

use faer::prelude::Solve;
use faer::{Mat, Side};

/// ln 2π, of the Gaussian densities.
pub(super) const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// The parameters λ of the process in the scaled (unit-variance) space, plus the observation
/// noise and the prior of the first state.
#[derive(Clone, Debug)]
pub struct Lambda {
    /// D.
    pub dim: usize,
    /// K.
    pub order: usize,
    /// [A_1 … A_K], `D × K·D`.
    pub a: Mat<f64>,
    /// d.
    pub d: Vec<f64>,
    /// Q = B Bᵀ, `D × D`.
    pub q: Mat<f64>,
    /// Observation noise variances.
    pub r: Vec<f64>,
    /// Prior mean of z_1 (K·D).
    pub mu0: Vec<f64>,
    /// Prior variance of every component of z_1 (fixed; the data have unit variance).
    pub v0: f64,
}

impl Lambda {
    /// K·D.
    pub fn state_dim(&self) -> usize {
        self.dim * self.order
    }

    /// A z + d: the deterministic part of the next x given the stacked state z.
    pub(super) fn predict_x(&self, z: &[f64], out: &mut [f64]) {
        let n = self.state_dim();
        for (i, o) in out.iter_mut().enumerate().take(self.dim) {
            *o = self.d[i] + (0..n).zip(z).map(|(j, zj)| self.a[(i, j)] * zj).sum::<f64>();
        }
    }
}

/// Expected sufficient statistics of one E-step and the log-likelihood of the parameters it used.
pub struct Stats {
    /// log p(y_1..T | λ) (exact for Kalman, the particle estimate for condensation), scaled space.
    pub log_likelihood: f64,
    /// Σ_t E[x_t z_{t−1}ᵀ], `D × n`.
    pub sxz: Mat<f64>,
    /// Σ_t E[x_t].
    pub sx1: Vec<f64>,
    /// Σ_t E[z_{t−1} z_{t−1}ᵀ], `n × n`.
    pub szz: Mat<f64>,
    /// Σ_t E[z_{t−1}].
    pub sz1: Vec<f64>,
    /// Σ_t E[x_t x_tᵀ], `D × D`.
    pub sxx: Mat<f64>,
    /// Number of transitions summed (T − 1).
    pub transitions: usize,
    /// Σ_t E[(y_t − x_t)²] per parameter over all T frames.
    pub obs_sq: Vec<f64>,
    /// Number of frames T.
    pub frames: usize,
    /// E[z_1 | y].
    pub z1: Vec<f64>,
}

impl Stats {
    /// Sums still to accumulate for a state of `n` (observations of `dim`) over `frames` frames,
    /// with the E-step's log-likelihood `ll`; `z1` is left for the E-step that knows it.
    pub fn zeroed(dim: usize, n: usize, frames: usize, ll: f64) -> Stats {
        Stats {
            log_likelihood: ll,
            sxz: Mat::zeros(dim, n),
            sx1: vec![0.0; dim],
            szz: Mat::zeros(n, n),
            sz1: vec![0.0; n],
            sxx: Mat::zeros(dim, dim),
            transitions: frames.saturating_sub(1),
            obs_sq: vec![0.0; dim],
            frames,
            z1: Vec::new(),
        }
    }
}

/// Makes `m` exactly symmetric: each pair of mirrored entries becomes their mean.
pub(super) fn symmetrize(m: &mut Mat<f64>) {
    let n = m.nrows();
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

/// The M-step: [A d] = S_xu S_uu⁻¹, Q = (S_xx − [A d] S_xuᵀ) / (T − 1), r_i = mean E[(y − x)²]
/// (not below `min_r`), μ_0 = E[z_1 | y]. Every block maximizes its own term of the expected
/// complete-data log-likelihood, so the likelihood cannot decrease (exact E-step).
pub fn m_step(st: &Stats, lam: &Lambda, min_r: f64, learn_d: bool) -> Result<Lambda, String> {
    let (dim, n) = (lam.dim, lam.state_dim());
    let tn = st.transitions as f64;
    // Regressors u = [z_{t−1}, 1], or z_{t−1} alone when d is held at 0.
    let nu = if learn_d { n + 1 } else { n };
    let mut suu = Mat::<f64>::zeros(nu, nu);
    suu.as_mut().submatrix_mut(0, 0, n, n).copy_from(st.szz.as_ref());
    if learn_d {
        for i in 0..n {
            suu[(i, n)] = st.sz1[i];
            suu[(n, i)] = st.sz1[i];
        }
        suu[(n, n)] = tn;
    }
    symmetrize(&mut suu);
    let llt = suu
        .llt(Side::Lower)
        .map_err(|_| "the state statistics are singular: too few frames or linearly dependent parameters".to_string())?;
    // Θᵀ = S_uu⁻¹ S_xuᵀ
    let mut theta_t = Mat::<f64>::from_fn(nu, dim, |j, i| if j < n { st.sxz[(i, j)] } else { st.sx1[i] });
    llt.solve_in_place(theta_t.as_mut());
    let a = Mat::<f64>::from_fn(dim, n, |i, j| theta_t[(j, i)]);
    let d: Vec<f64> = (0..dim).map(|i| if learn_d { theta_t[(n, i)] } else { 0.0 }).collect();
    // Q = (S_xx − Θ S_xuᵀ) / (T − 1)
    let mut q = st.sxx.clone();
    for i in 0..dim {
        for k in 0..dim {
            let mut s = 0.0;
            for j in 0..n {
                s += theta_t[(j, i)] * st.sxz[(k, j)];
            }
            if learn_d {
                s += theta_t[(n, i)] * st.sx1[k];
            }
            q[(i, k)] -= s;
        }
    }
    q *= faer::Scale(1.0 / tn);
    symmetrize(&mut q);
    let r: Vec<f64> = st.obs_sq.iter().map(|s| (s / st.frames as f64).max(min_r)).collect();
    Ok(Lambda { dim, order: lam.order, a, d, q, r, mu0: st.z1.clone(), v0: lam.v0 })
}

/// Initial λ_0 (§4.2): diagonal A_k^0 from each parameter's own Yule–Walker AR(K) fit, d^0 = 0,
/// B^0 = diag(standard deviations) (= I on the unit-variance data), small observation noise
/// `r0`, μ_0 from the first frame.
pub fn initial_lambda(y: &[f64], frames: usize, dim: usize, order: usize, r0: f64) -> Lambda {
    let n = dim * order;
    let mut a = Mat::<f64>::zeros(dim, n);
    for i in 0..dim {
        let col: Vec<f64> = (0..frames).map(|t| y[t * dim + i]).collect();
        let phi = yule_walker(&col, order);
        for (k, p) in phi.iter().enumerate() {
            a[(i, k * dim + i)] = *p;
        }
    }
    let mut mu0 = vec![0.0; n];
    for k in 0..order {
        mu0[k * dim..(k + 1) * dim].copy_from_slice(&y[..dim]);
    }
    Lambda {
        dim,
        order,
        a,
        d: vec![0.0; dim],
        q: Mat::<f64>::from_fn(dim, dim, |i, j| if i == j { 1.0 } else { 0.0 }),
        r: vec![r0; dim],
        mu0,
        v0: 1.0,
    }
}

/// λ_0 from conditional least squares: the M-step applied to the observations taken as exact
/// states (x_t = y_t, no covariance), i.e. the ordinary VAR(K) regression of y_t on
/// [y_{t−1} … y_{t−K}, 1] — the maximum of the likelihood in the limit of no observation noise.
/// EM then only has to find the observation noise and the small corrections it brings.
pub fn least_squares_lambda(
    y: &[f64],
    frames: usize,
    dim: usize,
    order: usize,
    r0: f64,
    learn_d: bool,
) -> Result<Lambda, String> {
    let n = dim * order;
    let stacked = |t: usize| -> Vec<f64> {
        // z_t = [x_t, x_{t−1}, …, x_{t−K+1}]
        (0..order).flat_map(|k| y[(t - k) * dim..(t - k + 1) * dim].iter().copied()).collect()
    };
    let mut st = Stats {
        log_likelihood: 0.0,
        sxz: Mat::zeros(dim, n),
        sx1: vec![0.0; dim],
        szz: Mat::zeros(n, n),
        sz1: vec![0.0; n],
        sxx: Mat::zeros(dim, dim),
        transitions: frames - order,
        obs_sq: vec![0.0; dim],
        frames,
        z1: stacked(order - 1),
    };
    for t in order..frames {
        let (x, z) = (&y[t * dim..(t + 1) * dim], stacked(t - 1));
        for i in 0..dim {
            st.sx1[i] += x[i];
            for (j, zj) in z.iter().enumerate() {
                st.sxz[(i, j)] += x[i] * zj;
            }
            for (j, xj) in x.iter().enumerate() {
                st.sxx[(i, j)] += x[i] * xj;
            }
        }
        for i in 0..n {
            st.sz1[i] += z[i];
            for j in 0..n {
                st.szz[(i, j)] += z[i] * z[j];
            }
        }
    }
    let mut lam = m_step(&st, &initial_lambda(y, frames, dim, order, r0), r0, learn_d)?;
    lam.r = vec![r0; dim];
    // μ_0 is the first stacked state of the frames (z_1 = [y_1, y_1, …] as in the diagonal start).
    lam.mu0 = initial_lambda(y, frames, dim, order, r0).mu0;
    Ok(lam)
}

/// AR(K) coefficients of a zero-mean series by the Yule–Walker equations (Levinson–Durbin),
/// which always give a stable filter.
pub fn yule_walker(x: &[f64], order: usize) -> Vec<f64> {
    let t = x.len();
    let acov: Vec<f64> = (0..=order).map(|k| (k..t).map(|i| x[i] * x[i - k]).sum::<f64>() / t as f64).collect();
    let mut phi = vec![0.0; order];
    if acov[0] <= 0.0 {
        return phi;
    }
    let mut err = acov[0];
    for m in 0..order {
        let mut k = acov[m + 1];
        for j in 0..m {
            k -= phi[j] * acov[m - j];
        }
        k /= err;
        let prev = phi.clone();
        phi[m] = k;
        for j in 0..m {
            phi[j] = prev[j] - k * prev[m - 1 - j];
        }
        err *= 1.0 - k * k;
        if err <= 0.0 {
            break;
        }
    }
    phi
}
