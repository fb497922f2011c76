//! The exact E-step of the AR-process EM (Stich & Magnor §4.1): a Kalman filter with
//! Rauch–Tung–Striebel smoother and lag-one covariances on the stacked state, giving the
//! expected sufficient statistics exactly.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::prelude::Solve;
use faer::{Accum, Mat, MatRef, Par, Side};

use super::em::{LN_2PI, Lambda, Stats, symmetrize};

/// The exact E-step: Kalman filter, RTS smoother and lag-one covariances on the stacked state.
/// `y` is `frames × D` row-major (scaled).
pub fn kalman_estep(y: &[f64], frames: usize, lam: &Lambda) -> Result<Stats, String> {
    let fw = forward(y, frames, lam)?;
    if !fw.ll.is_finite() {
        return Err("the log-likelihood is not finite".into());
    }
    backward(y, frames, lam, &fw)
}

/// What the forward pass (the Kalman filter) leaves for the smoother.
struct Forward {
    /// Predicted means m_{t|t−1}.
    m_pred: Vec<Vec<f64>>,
    /// Filtered means m_{t|t}.
    m_filt: Vec<Vec<f64>>,
    /// Predicted covariances P_{t|t−1}.
    p_pred: Vec<Mat<f64>>,
    /// Filtered covariances P_{t|t}.
    p_filt: Vec<Mat<f64>>,
    /// F P_filt[t], for t from 0.
    fp: Vec<Mat<f64>>,
    /// log p(y_1..T | λ).
    ll: f64,
    /// The frame from which the covariances are steady (`usize::MAX` if they never settle).
    steady_from: usize,
}

/// The Kalman filter over all frames: predicted and filtered means and covariances and the
/// log-likelihood.
fn forward(y: &[f64], frames: usize, lam: &Lambda) -> Result<Forward, String> {
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
    let steady_from = steady.as_ref().map_or(usize::MAX, |s| s.from);
    Ok(Forward { m_pred, m_filt, p_pred, p_filt, fp, ll, steady_from })
}

/// The Rauch–Tung–Striebel smoother over the forward pass `fw`, accumulating the statistics of
/// every transition t−1 → t as it goes.
fn backward(y: &[f64], frames: usize, lam: &Lambda, fw: &Forward) -> Result<Stats, String> {
    let (dim, n) = (lam.dim, lam.state_dim());
    let Forward { m_pred, m_filt, p_pred, p_filt, fp, ll, steady_from } = fw;
    let (ll, steady_from) = (*ll, *steady_from);
    // Backward pass (RTS), accumulating the statistics of transition t−1 → t as it goes.
    let mut st = Stats::zeroed(dim, n, frames, ll);
    let mut ms = m_filt[frames - 1].clone();
    let mut ps = p_filt[frames - 1].clone();
    add_obs(&mut st, &y[(frames - 1) * dim..frames * dim], &ms, &ps);
    // In the steady zone (P_filt[t] and P_pred[t+1] both steady) Jᵀ is constant, and once the
    // smoothed covariance stops changing it stays put: both are then reused.
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

fn add_obs(st: &mut Stats, y: &[f64], m: &[f64], p: &Mat<f64>) {
    for (i, o) in st.obs_sq.iter_mut().enumerate() {
        let e = y[i] - m[i];
        *o += e * e + p[(i, i)];
    }
}
