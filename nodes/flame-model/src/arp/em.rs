//! EM for the auto-regressive process with noisy observations (Stich & Magnor §4, §4.1):
//! the hidden state is the stacked z_t = (x_t, x_{t−1}, …, x_{t−K+1}) (dimension K·D), moving by the
//! companion form of eq. 2, observed as y_t = x_t + v_t with v_t ~ N(0, diag r).
//!
//! Two E-steps give the same expected sufficient statistics: an exact Kalman filter with
//! Rauch–Tung–Striebel smoother, and the paper's condensation (particle) approximation. The
//! M-step is the closed-form maximum-likelihood estimate of λ = {A, d, B} and of r from them.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::prelude::Solve;
use faer::{Accum, Mat, MatRef, Par, Side};

use super::rng::Rng;

const LN_2PI: f64 = 1.837_877_066_409_345_5;

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
    fn predict_x(&self, z: &[f64], out: &mut [f64]) {
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

fn symmetrize(m: &mut Mat<f64>) {
    let n = m.nrows();
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

/// F X for the companion matrix F (top rows A, then the shift).
fn f_left(a: MatRef<'_, f64>, x: MatRef<'_, f64>, dim: usize) -> Mat<f64> {
    let n = x.nrows();
    let mut out = Mat::<f64>::zeros(n, x.ncols());
    matmul(out.as_mut().subrows_mut(0, dim), Accum::Replace, a, x, 1.0, Par::Seq);
    out.as_mut().subrows_mut(dim, n - dim).copy_from(x.subrows(0, n - dim));
    out
}

/// X Fᵀ for the companion matrix F.
fn f_right(a: MatRef<'_, f64>, x: MatRef<'_, f64>, dim: usize) -> Mat<f64> {
    let n = x.ncols();
    let mut out = Mat::<f64>::zeros(x.nrows(), n);
    matmul(out.as_mut().subcols_mut(0, dim), Accum::Replace, x, a.transpose(), 1.0, Par::Seq);
    out.as_mut().subcols_mut(dim, n - dim).copy_from(x.subcols(0, n - dim));
    out
}

/// F z + c for a state vector.
fn f_vec(lam: &Lambda, z: &[f64]) -> Vec<f64> {
    let (dim, n) = (lam.dim, lam.state_dim());
    let mut out = vec![0.0; n];
    lam.predict_x(z, &mut out[..dim]);
    out[dim..].copy_from_slice(&z[..n - dim]);
    out
}

/// The converged covariances of the forward pass, from frame `from` on.
struct SteadyFilter {
    l: Mat<f64>,
    w: Mat<f64>,
    logdet: f64,
    pp: Mat<f64>,
    pf: Mat<f64>,
    fp: Mat<f64>,
    from: usize,
}

/// Whether two covariances agree to 1e-10 of their largest entry (converged).
fn same(a: &Mat<f64>, b: &Mat<f64>) -> bool {
    let (mut scale, mut diff) = (0.0f64, 0.0f64);
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            scale = scale.max(a[(i, j)].abs());
            diff = diff.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    diff <= 1e-10 * scale.max(1e-300)
}

/// The exact E-step: Kalman filter, RTS smoother and lag-one covariances on the stacked state.
/// `y` is `frames × D` row-major (scaled).
pub fn kalman_estep(y: &[f64], frames: usize, lam: &Lambda) -> Result<Stats, String> {
    let (dim, n) = (lam.dim, lam.state_dim());
    let a = lam.a.as_ref();
    let mut m_pred: Vec<Vec<f64>> = Vec::with_capacity(frames);
    let mut m_filt: Vec<Vec<f64>> = Vec::with_capacity(frames);
    let mut p_pred: Vec<Mat<f64>> = Vec::with_capacity(frames);
    let mut p_filt: Vec<Mat<f64>> = Vec::with_capacity(frames);
    let mut fp: Vec<Mat<f64>> = Vec::with_capacity(frames); // F P_filt[t]
    let mut ll = 0.0;
    // The system is time-invariant, so the covariances converge to steady values after a few
    // frames; from then on they (and the gain) are reused instead of recomputed — the same
    // numbers to the convergence test's tolerance, at the cost of the mean updates only.
    let mut steady: Option<SteadyFilter> = None;
    for t in 0..frames {
        let yt = &y[t * dim..(t + 1) * dim];
        if let Some(sf) = &steady {
            let mp = f_vec(lam, &m_filt[t - 1]);
            let mut v = Mat::<f64>::from_fn(dim, 1, |i, _| yt[i] - mp[i]);
            solve_lower_triangular_in_place(sf.l.as_ref(), v.as_mut(), Par::Seq);
            let quad: f64 = (0..dim).map(|i| v[(i, 0)] * v[(i, 0)]).sum();
            ll += -0.5 * (dim as f64 * LN_2PI + sf.logdet + quad);
            let mut mf = mp.clone();
            for (j, m) in mf.iter_mut().enumerate() {
                *m += (0..dim).map(|i| sf.w[(i, j)] * v[(i, 0)]).sum::<f64>();
            }
            fp.push(sf.fp.clone());
            m_pred.push(mp);
            p_pred.push(sf.pp.clone());
            m_filt.push(mf);
            p_filt.push(sf.pf.clone());
            continue;
        }
        let (mp, pp) = if t == 0 {
            (lam.mu0.clone(), Mat::<f64>::from_fn(n, n, |i, j| if i == j { lam.v0 } else { 0.0 }))
        } else {
            let mp = f_vec(lam, &m_filt[t - 1]);
            let g = f_left(a, p_filt[t - 1].as_ref(), dim);
            let mut pp = f_right(a, g.as_ref(), dim);
            for i in 0..dim {
                for j in 0..dim {
                    pp[(i, j)] += lam.q[(i, j)];
                }
            }
            symmetrize(&mut pp);
            fp.push(g);
            (mp, pp)
        };
        let mut s = pp.submatrix(0, 0, dim, dim).to_owned();
        for i in 0..dim {
            s[(i, i)] += lam.r[i];
        }
        let llt = s.llt(Side::Lower).map_err(|_| format!("innovation covariance at frame {t} is not positive definite"))?;
        let l = llt.L();
        let mut w = pp.subrows(0, dim).to_owned(); // becomes L⁻¹ P[x, :]
        solve_lower_triangular_in_place(l, w.as_mut(), Par::Seq);
        let mut v = Mat::<f64>::from_fn(dim, 1, |i, _| yt[i] - mp[i]);
        solve_lower_triangular_in_place(l, v.as_mut(), Par::Seq);
        let logdet: f64 = (0..dim).map(|i| l[(i, i)].ln()).sum::<f64>() * 2.0;
        let quad: f64 = (0..dim).map(|i| v[(i, 0)] * v[(i, 0)]).sum();
        ll += -0.5 * (dim as f64 * LN_2PI + logdet + quad);
        let mut mf = mp.clone();
        for (j, m) in mf.iter_mut().enumerate() {
            *m += (0..dim).map(|i| w[(i, j)] * v[(i, 0)]).sum::<f64>();
        }
        let mut pf = pp.clone();
        matmul(pf.as_mut(), Accum::Add, w.transpose(), w.as_ref(), -1.0, Par::Seq);
        symmetrize(&mut pf);
        if t >= 1 && same(&pp, &p_pred[t - 1]) && same(&pf, &p_filt[t - 1]) {
            let fpt = f_left(a, pf.as_ref(), dim);
            steady = Some(SteadyFilter { l: l.to_owned(), w, logdet, pp: pp.clone(), pf: pf.clone(), fp: fpt, from: t });
        }
        m_pred.push(mp);
        p_pred.push(pp);
        m_filt.push(mf);
        p_filt.push(pf);
    }
    if !ll.is_finite() {
        return Err("the log-likelihood is not finite".into());
    }

    // Backward pass (RTS), accumulating the statistics of transition t−1 → t as it goes.
    let mut st = Stats {
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
    };
    let mut ms = m_filt[frames - 1].clone();
    let mut ps = p_filt[frames - 1].clone();
    add_obs(&mut st, &y[(frames - 1) * dim..frames * dim], &ms, &ps);
    // In the steady zone (P_filt[t] and P_pred[t+1] both steady) Jᵀ is constant, and once the
    // smoothed covariance stops changing it stays put: both are then reused.
    let steady_from = steady.as_ref().map_or(usize::MAX, |s| s.from);
    let mut steady_jt: Option<Mat<f64>> = None;
    let mut settled: Option<(Mat<f64>, Mat<f64>)> = None; // (cross, P_s) once converged
    for t in (0..frames - 1).rev() {
        let in_steady = t >= steady_from;
        if !in_steady {
            settled = None;
        }
        // Jᵀ = P_pred[t+1]⁻¹ F P_filt[t]
        let jt = match (&steady_jt, in_steady) {
            (Some(j), true) => j.clone(),
            _ => {
                let llt = p_pred[t + 1]
                    .llt(Side::Lower)
                    .map_err(|_| format!("predicted covariance at frame {} is not positive definite", t + 1))?;
                let mut jt = fp[t].clone();
                llt.solve_in_place(jt.as_mut());
                if in_steady {
                    steady_jt = Some(jt.clone());
                }
                jt
            }
        };
        // Cov(z_{t+1}, z_t | y) = P_s[t+1] Jᵀ; only the x rows are needed.
        let cross = match &settled {
            Some((c, _)) => c.clone(),
            None => {
                let mut cross = Mat::<f64>::zeros(dim, n);
                matmul(cross.as_mut(), Accum::Replace, ps.as_ref().subrows(0, dim), jt.as_ref(), 1.0, Par::Seq);
                cross
            }
        };
        let mut ms_prev = m_filt[t].clone();
        let diff: Vec<f64> = (0..n).map(|i| ms[i] - m_pred[t + 1][i]).collect();
        for (i, m) in ms_prev.iter_mut().enumerate() {
            *m += (0..n).map(|k| jt[(k, i)] * diff[k]).sum::<f64>();
        }
        let ps_prev = match &settled {
            Some((_, p)) => p.clone(),
            None => {
                let mut delta = ps.clone();
                delta -= &p_pred[t + 1];
                let mut tmp = Mat::<f64>::zeros(n, n);
                matmul(tmp.as_mut(), Accum::Replace, delta.as_ref(), jt.as_ref(), 1.0, Par::Seq);
                let mut ps_prev = p_filt[t].clone();
                matmul(ps_prev.as_mut(), Accum::Add, jt.transpose(), tmp.as_ref(), 1.0, Par::Seq);
                symmetrize(&mut ps_prev);
                if in_steady && same(&ps_prev, &ps) {
                    settled = Some((cross.clone(), ps_prev.clone()));
                }
                ps_prev
            }
        };

        // Transition t → t+1: x = ms[..dim], z_prev = ms_prev.
        for i in 0..dim {
            st.sx1[i] += ms[i];
            for j in 0..n {
                st.sxz[(i, j)] += cross[(i, j)] + ms[i] * ms_prev[j];
            }
            for j in 0..dim {
                st.sxx[(i, j)] += ps[(i, j)] + ms[i] * ms[j];
            }
        }
        for i in 0..n {
            st.sz1[i] += ms_prev[i];
            for j in 0..n {
                st.szz[(i, j)] += ps_prev[(i, j)] + ms_prev[i] * ms_prev[j];
            }
        }
        add_obs(&mut st, &y[t * dim..(t + 1) * dim], &ms_prev, &ps_prev);
        ms = ms_prev;
        ps = ps_prev;
    }
    st.z1 = ms;
    Ok(st)
}

fn add_obs(st: &mut Stats, y: &[f64], m: &[f64], p: &Mat<f64>) {
    for (i, o) in st.obs_sq.iter_mut().enumerate() {
        let e = y[i] - m[i];
        *o += e * e + p[(i, i)];
    }
}

/// The condensation E-step (§4.1): `particles` weighted samples of the state, propagated by the
/// process and weighted by the observations, with systematic resampling; expectations are
/// averages over the particles' ancestral paths. Since both the process and the observation are
/// linear-Gaussian, each particle proposes x_t from p(x_t | z_{t−1}, y_t) and is weighted by
/// p(y_t | z_{t−1}) (the fully adapted filter), which keeps a few hundred particles useful in 26
/// dimensions. The log-likelihood is the particle estimate Σ_t log mean_i p(y_t | z_{t−1}^i).
pub fn condensation_estep(y: &[f64], frames: usize, lam: &Lambda, particles: usize, seed: u64) -> Result<Stats, String> {
    let (dim, n, np) = (lam.dim, lam.state_dim(), particles.max(1));
    let mut rng = Rng::new(seed);
    // Σ = Q + R, the predictive covariance of y given z_{t−1}; gain G = Q Σ⁻¹; posterior P = Q − G Q.
    let mut sigma = lam.q.clone();
    for i in 0..dim {
        sigma[(i, i)] += lam.r[i];
    }
    let sig_llt = sigma.llt(Side::Lower).map_err(|_| "Q + R is not positive definite".to_string())?;
    let sig_l = sig_llt.L().to_owned();
    let sig_logdet: f64 = (0..dim).map(|i| sig_l[(i, i)].ln()).sum::<f64>() * 2.0;
    let mut gain_t = lam.q.clone(); // Σ⁻¹ Q = Gᵀ
    sig_llt.solve_in_place(gain_t.as_mut());
    let mut post = lam.q.clone();
    matmul(post.as_mut(), Accum::Add, gain_t.transpose(), lam.q.as_ref(), -1.0, Par::Seq);
    symmetrize(&mut post);
    for i in 0..dim {
        post[(i, i)] += 1e-12;
    }
    let post_l = post
        .llt(Side::Lower)
        .map_err(|_| "the particle proposal covariance is not positive definite".to_string())?
        .L()
        .to_owned();
    // First frame: x_1 | y_1 from the prior N(mu0_x, v0) and R, per component.
    let lag = n - dim;
    let mut xs = vec![0.0; frames * np * dim]; // x_t of each particle
    let mut anc = vec![0usize; frames * np]; // ancestor at t−1 of particle i at t
    let mut pre = vec![0.0; np * lag]; // pre-sample lags of z_1
    let mut noise = vec![0.0; dim.max(lag)];
    let mut ll = 0.0;
    {
        let mut lw = 0.0;
        for (i, yi) in y.iter().enumerate().take(dim) {
            let (m0, s2, ri) = (lam.mu0[i], lam.v0, lam.r[i]);
            let e = yi - m0;
            lw += -0.5 * (LN_2PI + (s2 + ri).ln() + e * e / (s2 + ri));
        }
        ll += lw;
        for p in 0..np {
            rng.fill_normal(&mut noise[..dim]);
            for i in 0..dim {
                let (m0, s2, ri) = (lam.mu0[i], lam.v0, lam.r[i]);
                let pv = s2 * ri / (s2 + ri);
                let pm = m0 + s2 / (s2 + ri) * (y[i] - m0);
                xs[p * dim + i] = pm + pv.sqrt() * noise[i];
            }
            rng.fill_normal(&mut noise[..lag]);
            for j in 0..lag {
                pre[p * lag + j] = lam.mu0[dim + j] + lam.v0.sqrt() * noise[j];
            }
        }
    }
    // Current stacked state of each particle, z_t = (x_t, x_{t−1}, …).
    let mut z = vec![0.0; np * n];
    for p in 0..np {
        z[p * n..p * n + dim].copy_from_slice(&xs[p * dim..(p + 1) * dim]);
        z[p * n + dim..(p + 1) * n].copy_from_slice(&pre[p * lag..(p + 1) * lag]);
    }
    let mut mu = vec![0.0; np * dim];
    let mut logw = vec![0.0; np];
    let mut e = Mat::<f64>::zeros(dim, 1);
    let mut znew = vec![0.0; np * n];
    for t in 1..frames {
        let yt = &y[t * dim..(t + 1) * dim];
        for p in 0..np {
            lam.predict_x(&z[p * n..(p + 1) * n], &mut mu[p * dim..(p + 1) * dim]);
            for i in 0..dim {
                e[(i, 0)] = yt[i] - mu[p * dim + i];
            }
            solve_lower_triangular_in_place(sig_l.as_ref(), e.as_mut(), Par::Seq);
            let quad: f64 = (0..dim).map(|i| e[(i, 0)] * e[(i, 0)]).sum();
            logw[p] = -0.5 * (dim as f64 * LN_2PI + sig_logdet + quad);
        }
        let mx = logw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !mx.is_finite() {
            return Err(format!("every particle has zero weight at frame {t}"));
        }
        let w: Vec<f64> = logw.iter().map(|l| (l - mx).exp()).collect();
        let total: f64 = w.iter().sum();
        ll += mx + (total / np as f64).ln();
        // Systematic resampling.
        let step = total / np as f64;
        let mut u = rng.uniform() * step;
        let (mut cum, mut k) = (w[0], 0usize);
        for p in 0..np {
            while u > cum && k + 1 < np {
                k += 1;
                cum += w[k];
            }
            anc[t * np + p] = k;
            u += step;
        }
        // Propose x_t ~ N(μ + G (y − μ), P) for each resampled particle.
        for p in 0..np {
            let a = anc[t * np + p];
            rng.fill_normal(&mut noise[..dim]);
            for i in 0..dim {
                let mut v = mu[a * dim + i];
                for j in 0..dim {
                    v += gain_t[(j, i)] * (yt[j] - mu[a * dim + j]);
                }
                for j in 0..=i {
                    v += post_l[(i, j)] * noise[j];
                }
                xs[(t * np + p) * dim + i] = v;
                znew[p * n + i] = v;
            }
            znew[p * n + dim..(p + 1) * n].copy_from_slice(&z[a * n..a * n + lag]);
        }
        std::mem::swap(&mut z, &mut znew);
    }

    // Trace every final particle back to its full path and average the statistics over paths.
    let mut st = Stats {
        log_likelihood: ll,
        sxz: Mat::zeros(dim, n),
        sx1: vec![0.0; dim],
        szz: Mat::zeros(n, n),
        sz1: vec![0.0; n],
        sxx: Mat::zeros(dim, dim),
        transitions: frames.saturating_sub(1),
        obs_sq: vec![0.0; dim],
        frames,
        z1: vec![0.0; n],
    };
    if !ll.is_finite() {
        return Err("the log-likelihood is not finite".into());
    }
    let inv = 1.0 / np as f64;
    let rows = frames.saturating_sub(1) * np;
    // Regressors u = [z_{t−1}; 1] and targets x_t of every (path, t), stacked for two products.
    let mut big_z = Mat::<f64>::zeros(rows, n + 1);
    let mut big_x = Mat::<f64>::zeros(rows, dim);
    let mut path = vec![0usize; frames];
    for p in 0..np {
        path[frames - 1] = p;
        for t in (1..frames).rev() {
            path[t - 1] = anc[t * np + path[t]];
        }
        let x_at = |t: usize| &xs[(t * np + path[t]) * dim..(t * np + path[t] + 1) * dim];
        let root = path[0];
        // Lag j of z_t (block j = x_{t−j}) along this path.
        let lagged = |t: usize, j: usize, i: usize| -> f64 {
            if t >= j { x_at(t - j)[i] } else { pre[root * lag + (j - t - 1) * dim + i] }
        };
        for t in 0..frames {
            let xt = x_at(t);
            for ((o, yi), xi) in st.obs_sq.iter_mut().zip(yt_at(y, dim, t)).zip(xt) {
                let ev = yi - xi;
                *o += ev * ev * inv;
            }
            if t > 0 {
                let row = (t - 1) * np + p;
                for j in 0..lam.order {
                    for i in 0..dim {
                        big_z[(row, j * dim + i)] = lagged(t - 1, j, i);
                    }
                }
                big_z[(row, n)] = 1.0;
                for i in 0..dim {
                    big_x[(row, i)] = xt[i];
                }
            }
        }
        for j in 0..lam.order {
            for i in 0..dim {
                st.z1[j * dim + i] += lagged(0, j, i) * inv;
            }
        }
    }
    let mut suu = Mat::<f64>::zeros(n + 1, n + 1);
    matmul(suu.as_mut(), Accum::Replace, big_z.transpose(), big_z.as_ref(), inv, Par::Seq);
    let mut sxu = Mat::<f64>::zeros(dim, n + 1);
    matmul(sxu.as_mut(), Accum::Replace, big_x.transpose(), big_z.as_ref(), inv, Par::Seq);
    matmul(st.sxx.as_mut(), Accum::Replace, big_x.transpose(), big_x.as_ref(), inv, Par::Seq);
    st.szz.copy_from(suu.as_ref().submatrix(0, 0, n, n));
    st.sxz.copy_from(sxu.as_ref().submatrix(0, 0, dim, n));
    for i in 0..n {
        st.sz1[i] = suu[(i, n)];
    }
    for i in 0..dim {
        st.sx1[i] = sxu[(i, n)];
    }
    Ok(st)
}

fn yt_at(y: &[f64], dim: usize, t: usize) -> &[f64] {
    &y[t * dim..(t + 1) * dim]
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
