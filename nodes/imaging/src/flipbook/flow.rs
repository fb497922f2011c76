//! Dense optical flow between two frames (pyramidal Lucas–Kanade) for the flipbook's motion sheet.

use pyrograph_core::Image;

use crate::filters::{Plane, convolve_separable, gaussian_kernel};

/// Smallest eigenvalue of the windowed structure tensor (luminance 0..1, per pixel²) for which
/// Lucas–Kanade trusts a window; below it (dark noise, flat areas) the flow is left at zero.
pub const MIN_EIGENVALUE: f32 = 1e-4;

/// Luminance (locally averaged over the window) below which a pixel counts as empty background
/// and gets zero motion.
pub const MIN_CONTENT: f32 = 0.02;

/// Dense optical flow from `a` to `b` in pixels (x right, y down): a pyramidal Lucas–Kanade with a
/// Gaussian window (σ 2), five levels at most and five iterations per level. A pixel at `p` in `a`
/// is at `p + (u, v)` in `b`. Textureless regions (a black background) get zero motion; images of
/// different sizes (or empty ones) give zero flow.
pub fn optical_flow(a: &Image, b: &Image) -> (Plane, Plane) {
    if a.size() != b.size() || a.width() == 0 || a.height() == 0 {
        let (w, h) = (a.width() as usize, a.height() as usize);
        return (Plane::new(w, h), Plane::new(w, h));
    }
    let (mut pa, mut pb) = (vec![Plane::luminance(a)], vec![Plane::luminance(b)]);
    while pa.len() < 5 && pa[pa.len() - 1].width.min(pa[pa.len() - 1].height) >= 32 {
        let (na, nb) = (pa[pa.len() - 1].half(), pb[pb.len() - 1].half());
        pa.push(na);
        pb.push(nb);
    }
    let window = gaussian_kernel(2.0);
    let mut flow: Option<(Plane, Plane)> = None;
    for level in (0..pa.len()).rev() {
        let (i1, i2) = (&pa[level], &pb[level]);
        let (w, h) = (i1.width, i1.height);
        // Initial flow: the coarser level's, doubled.
        let (mut u, mut v) = match flow.take() {
            None => (Plane::new(w, h), Plane::new(w, h)),
            Some((cu, cv)) => {
                let up = |c: &Plane| Plane {
                    width: w,
                    height: h,
                    data: (0..w * h)
                        .map(|k| 2.0 * c.sample(((k % w) as f32 - 0.5) / 2.0, ((k / w) as f32 - 0.5) / 2.0))
                        .collect(),
                };
                (up(&cu), up(&cv))
            }
        };
        let at = |p: &Plane, x: usize, y: usize| p.data[y * p.width + x];
        let grad = |x: usize, y: usize| {
            let gx = 0.5 * (at(i1, (x + 1).min(w - 1), y) - at(i1, x.saturating_sub(1), y));
            let gy = 0.5 * (at(i1, x, (y + 1).min(h - 1)) - at(i1, x, y.saturating_sub(1)));
            (gx, gy)
        };
        let (gx, gy): (Vec<f32>, Vec<f32>) = (0..w * h).map(|k| grad(k % w, k / w)).unzip();
        let prod = |f: &dyn Fn(usize) -> f32| {
            convolve_separable(&Plane { width: w, height: h, data: (0..w * h).map(f).collect() }, &window)
        };
        let sxx = prod(&|k| gx[k] * gx[k]);
        let sxy = prod(&|k| gx[k] * gy[k]);
        let syy = prod(&|k| gy[k] * gy[k]);
        for _ in 0..5 {
            let it: Vec<f32> =
                (0..w * h).map(|k| i2.sample((k % w) as f32 + u.data[k], (k / w) as f32 + v.data[k]) - i1.data[k]).collect();
            let bx = prod(&|k| gx[k] * it[k]);
            let by = prod(&|k| gy[k] * it[k]);
            for k in 0..w * h {
                let (a, b, c) = (sxx.data[k], sxy.data[k], syy.data[k]);
                let det = a * c - b * b;
                let trace = a + c;
                // Skip ill-conditioned windows: flat or noisy-dark regions (small eigenvalue) and pure edges.
                let lambda_min = 0.5 * (trace - (trace * trace - 4.0 * det).max(0.0).sqrt());
                if lambda_min < MIN_EIGENVALUE || det < 1e-3 * trace * trace {
                    continue;
                }
                let du = -(c * bx.data[k] - b * by.data[k]) / det;
                let dv = -(a * by.data[k] - b * bx.data[k]) / det;
                u.data[k] += du.clamp(-2.0, 2.0);
                v.data[k] += dv.clamp(-2.0, 2.0);
            }
        }
        flow = Some((u, v));
    }
    let (w, h) = (a.width() as usize, a.height() as usize);
    let (mut u, mut v) = flow.unwrap_or_else(|| (Plane::new(w, h), Plane::new(w, h)));
    // Coarse levels spread motion into the empty background around a flame; nothing moves where
    // neither frame has content nearby.
    let content = Plane { width: w, height: h, data: pa[0].data.iter().zip(&pb[0].data).map(|(x, y)| x.max(*y)).collect() };
    let near = convolve_separable(&content, &window);
    for (k, &c) in near.data.iter().enumerate() {
        if c < MIN_CONTENT {
            u.data[k] = 0.0;
            v.data[k] = 0.0;
        }
    }
    (u, v)
}
