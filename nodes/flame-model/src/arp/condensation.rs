//! The condensation (particle) E-step of the AR-process EM (Stich & Magnor §4.1): the paper's
//! approximation of the expected sufficient statistics by weighted samples of the state.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::prelude::Solve;
use faer::{Accum, Mat, Par, Side};

use super::em::{LN_2PI, Lambda, Stats, symmetrize};
use super::rng::Rng;

/// The condensation E-step (§4.1): `particles` weighted samples of the state, propagated by the
/// process and weighted by the observations, with systematic resampling; expectations are
/// averages over the particles' ancestral paths. Since both the process and the observation are
/// linear-Gaussian, each particle proposes x_t from p(x_t | z_{t−1}, y_t) and is weighted by
/// p(y_t | z_{t−1}) (the fully adapted filter), which keeps a few hundred particles useful in 26
/// dimensions. The log-likelihood is the particle estimate Σ_t log mean_i p(y_t | z_{t−1}^i).
pub fn condensation_estep(y: &[f64], frames: usize, lam: &Lambda, particles: usize, seed: u64) -> Result<Stats, String> {
    let np = particles.max(1);
    let mut rng = Rng::new(seed);
    let prop = Proposal::new(lam)?;
    let mut swarm = Swarm::new(lam, frames, np);
    let mut ll = 0.0;
    ll += swarm.first_frame(y, lam, &mut rng);
    swarm.filter(y, lam, &prop, &mut rng, &mut ll)?;
    swarm.statistics(y, lam, ll)
}

/// The fully adapted proposal: the factor of Σ = Q + R, the predictive covariance of y given
/// z_{t−1}, the gain and the factor of the posterior covariance.
struct Proposal {
    /// Lower Cholesky factor of Σ.
    sig_l: Mat<f64>,
    /// log det Σ.
    sig_logdet: f64,
    /// Σ⁻¹ Q = Gᵀ.
    gain_t: Mat<f64>,
    /// Lower Cholesky factor of the posterior P = Q − G Q.
    post_l: Mat<f64>,
}

impl Proposal {
    fn new(lam: &Lambda) -> Result<Proposal, String> {
        let dim = lam.dim;
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
        Ok(Proposal { sig_l, sig_logdet, gain_t, post_l })
    }
}

/// The particles: every particle's x_t over all frames, its ancestors, and its pre-sample lags.
struct Swarm {
    /// Number of frames T.
    frames: usize,
    /// Number of particles.
    np: usize,
    /// D.
    dim: usize,
    /// K·D.
    n: usize,
    /// (K − 1)·D, the lags of z_1 before the first frame.
    lag: usize,
    /// x_t of each particle.
    xs: Vec<f64>,
    /// Ancestor at t−1 of particle i at t.
    anc: Vec<usize>,
    /// Pre-sample lags of z_1.
    pre: Vec<f64>,
    /// Normal draws of one particle.
    noise: Vec<f64>,
}

impl Swarm {
    fn new(lam: &Lambda, frames: usize, np: usize) -> Swarm {
        let (dim, n) = (lam.dim, lam.state_dim());
        let lag = n - dim;
        let xs = vec![0.0; frames * np * dim];
        let anc = vec![0usize; frames * np];
        let pre = vec![0.0; np * lag];
        let noise = vec![0.0; dim.max(lag)];
        Swarm { frames, np, dim, n, lag, xs, anc, pre, noise }
    }

    /// First frame: x_1 | y_1 from the prior N(mu0_x, v0) and R, per component. Returns the
    /// frame's log-likelihood.
    fn first_frame(&mut self, y: &[f64], lam: &Lambda, rng: &mut Rng) -> f64 {
        let (dim, np, lag) = (self.dim, self.np, self.lag);
        let Swarm { xs, pre, noise, .. } = self;
        let mut lw = 0.0;
        for (i, yi) in y.iter().enumerate().take(dim) {
            let (m0, s2, ri) = (lam.mu0[i], lam.v0, lam.r[i]);
            let e = yi - m0;
            lw += -0.5 * (LN_2PI + (s2 + ri).ln() + e * e / (s2 + ri));
        }
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
        lw
    }

    /// Frames 2..T: weights by p(y_t | z_{t−1}), systematic resampling and the proposal of x_t;
    /// adds each frame's log-likelihood to `ll`.
    fn filter(&mut self, y: &[f64], lam: &Lambda, prop: &Proposal, rng: &mut Rng, ll: &mut f64) -> Result<(), String> {
        let (dim, n, np, lag, frames) = (self.dim, self.n, self.np, self.lag, self.frames);
        let Proposal { sig_l, sig_logdet, gain_t, post_l } = prop;
        let sig_logdet = *sig_logdet;
        let Swarm { xs, anc, pre, noise, .. } = self;
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
            *ll += mx + (total / np as f64).ln();
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
        Ok(())
    }

    /// Traces every final particle back to its full path and averages the statistics over paths.
    fn statistics(&self, y: &[f64], lam: &Lambda, ll: f64) -> Result<Stats, String> {
        let (dim, n, np, lag, frames) = (self.dim, self.n, self.np, self.lag, self.frames);
        let Swarm { xs, anc, pre, .. } = self;
        let mut st = Stats { z1: vec![0.0; n], ..Stats::zeroed(dim, n, frames, ll) };
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
}

fn yt_at(y: &[f64], dim: usize, t: usize) -> &[f64] {
    &y[t * dim..(t + 1) * dim]
}
