//! `imaging.stabilize`: a handheld clip held still, so cues that compare pixels over time (the
//! flicker of `imaging.fire_cues`) see the scene, not the camera, and the crop box fits the fire.
//!
//! The camera's motion between consecutive frames is a rotation and a shift found by direct image
//! alignment: Gauss–Newton on the brightness difference (Lucas & Kanade 1981, in the form of
//! Baker & Matthews, "Lucas-Kanade 20 Years On", IJCV 2004), coarse to fine on an image pyramid,
//! with Huber weights so the flame (which moves on its own) does not pull the estimate. The
//! motions are chained into the camera's path; each frame is turned and shifted back onto the
//! first frame's (lock), or onto that path smoothed over time (smoothing > 0), which keeps a pan and
//! removes the shake (the smooth-path idea of video stabilizers since Matsushita et al. 2006).
//!
//! Written here rather than taken from a library: imageproc has no image registration, and
//! OpenCV's (its ECC or feature tracker) would bring a C++ toolchain to every build.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, ClipOf, Cook, CookCtx, FrameSource, Image, NodeError, Value, port};

use crate::filters::Plane;

/// Longest side of the plane motion is measured on (frames are box-averaged down by halves).
const WORK_SIDE: usize = 640;

/// Share of the frames' brightest level from which a pixel is left out of the alignment: the fire
/// and what it lights move on their own, and a flame on black would otherwise be "stabilized"
/// onto itself.
const BRIGHT: f32 = 0.75;

/// Mean squared gradient (brightness per pixel, squared) the still pixels must have for the
/// motion to be measured; below it (a flame on black) the camera is taken as still.
const MIN_TEXTURE: f64 = 2e-5;

pyrograph_core::node! {
    /// Holds a handheld clip still before the cues that compare pixels over time (extends Eigenfires thesis §3.1, whose footage is shot from a tripod; direct alignment after Lucas & Kanade 1981 and Baker & Matthews 2004, smoothed camera path after Matsushita et al. 2006).
    ///
    /// The rotation and shift between consecutive frames are found by aligning their brightness, coarse to fine, leaving out the brightest pixels (the fire moves on its own) and weighing down pixels that disagree (Huber); the motions are chained into the camera's path. With smoothing 0 every frame is turned and shifted onto the first frame; above 0 onto the path smoothed over that many frames (Gaussian σ), which keeps a pan and removes the shake. Pixels brought in from outside the frame are transparent black. A clip without still texture (a flame on black) is taken as shot from a tripod and passes unchanged. Outputs the held clip and the largest correction applied, in pixels.
    #[node("imaging.stabilize", "Pre-processing", WholeClip)]
    pub struct Stabilize {
        /// The clip to hold still.
        clip: ClipOf<Arc<Image>>,
        /// 0 locks every frame to the first; above 0, the camera path's smoothing in frames (σ).
        #[range(0.0, 1000.0)]
        smoothing: f64 = 0.0,
    }
    pub struct StabilizeOut {
        /// The stabilized clip.
        clip: ClipOf<Arc<Image>>,
        /// The largest shift applied to a frame (at its corners, from the turn and the shift), in pixels.
        correction: f64,
    }
}

/// A rotation by `angle` radians about the frame's centre followed by a shift, in full-size pixels:
/// `x ↦ R(angle)(x − c) + c + shift`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rigid {
    /// Rotation, radians (positive turns +x towards +y: clockwise on screen).
    pub angle: f64,
    /// Shift, pixels.
    pub shift: [f64; 2],
}

impl Rigid {
    /// `self` then `next`.
    pub fn then(self, next: Rigid) -> Rigid {
        let (s, c) = next.angle.sin_cos();
        let [x, y] = self.shift;
        Rigid { angle: self.angle + next.angle, shift: [c * x - s * y + next.shift[0], s * x + c * y + next.shift[1]] }
    }

    /// The motion that undoes `self`.
    pub fn inverse(self) -> Rigid {
        let (s, c) = (-self.angle).sin_cos();
        let [x, y] = self.shift;
        Rigid { angle: -self.angle, shift: [-(c * x - s * y), -(s * x + c * y)] }
    }

    /// Where `p` goes, about the centre `c`.
    pub fn apply(self, p: [f64; 2], c: [f64; 2]) -> [f64; 2] {
        let (s, co) = self.angle.sin_cos();
        let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
        [co * dx - s * dy + c[0] + self.shift[0], s * dx + co * dy + c[1] + self.shift[1]]
    }
}

/// Frames of a clip moved by one motion each.
struct HeldSource {
    clip: Clip,
    /// Per frame: where a pixel of the output is found in the input.
    lookups: Vec<Rigid>,
}

impl FrameSource for HeldSource {
    fn len(&self) -> usize {
        self.clip.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let Value::Image(img) = self.clip.get(index, ctx)? else {
            return Err(NodeError::port(port!(Stabilize, clip), format!("frame {index} is not an image")));
        };
        let m = self.lookups.get(index).copied().unwrap_or_default();
        // A copy, never the input's own frame: the frame cache keeps a frame that is held outside
        // it, so one frame cached by both clips would pin itself in both.
        if is_identity(m) {
            return Ok(Value::Image(Arc::new((*img).clone())));
        }
        Ok(Value::Image(Arc::new(warp(&img, m))))
    }
}

impl Cook for Stabilize {
    fn cook(self, ctx: &CookCtx) -> Result<StabilizeOut, NodeError> {
        use rayon::prelude::*;
        let clip: &Clip = &self.clip;
        let n = clip.len();
        let read = |i: usize| -> Result<Arc<Image>, NodeError> {
            ctx.check_cancel()?;
            match clip.get(i, ctx)? {
                Value::Image(img) => Ok(img),
                _ => Err(NodeError::port(port!(Stabilize, clip), format!("frame {i} is not an image"))),
            }
        };
        // Each consecutive pair is measured on its own, in parallel, each thread along long runs
        // of frames (a video decodes forward); only the motions are kept.
        let steps = (1..n)
            .into_par_iter()
            .with_min_len(crate::media::long_runs(n))
            .map(|i| {
                let (a, b) = (read(i - 1)?, read(i)?);
                if a.size() != b.size() {
                    return Err(NodeError::port(
                        port!(Stabilize, clip),
                        format!(
                            "frame {i} is {}x{} but frame {} is {}x{}: every frame must be the same size",
                            b.width(),
                            b.height(),
                            i - 1,
                            a.width(),
                            a.height()
                        ),
                    ));
                }
                Ok(frame_motion(&a, &b))
            })
            .collect::<Result<Vec<Option<Rigid>>, NodeError>>()?;
        let still = steps.iter().filter(|s| s.is_none()).count();
        // A clip with no still texture at all is stock fire on black, shot from a tripod: nothing
        // to say. Some steps unmeasured in a clip that has texture may hide shake.
        if still > 0 && still < steps.len() {
            ctx.warn(format!(
                "{still} of {} frame steps have too little still texture to measure the camera by: taken as still",
                steps.len()
            ));
        }
        let path = camera_path(&steps);
        let target = smooth_path(&path, self.smoothing);
        // Output pixel x shows the scene point the target path puts there: found in frame i at
        // path_i(target_i⁻¹(x)).
        let lookups: Vec<Rigid> = path.iter().zip(&target).map(|(p, t)| t.inverse().then(*p)).collect();
        let size = if n > 0 { read(0)?.size() } else { (0, 0) };
        if lookups.iter().all(|m| is_identity(*m)) {
            // Nothing to move (a tripod, a flame on black): the clip itself, no copies.
            return Ok(StabilizeOut { clip: self.clip, correction: 0.0 });
        }
        let correction = lookups.iter().map(|m| corner_shift(*m, size)).fold(0.0, f64::max);
        let mut h = Fingerprinter::new();
        let bits: Vec<[u64; 3]> =
            lookups.iter().map(|m| [m.angle.to_bits(), m.shift[0].to_bits(), m.shift[1].to_bits()]).collect();
        ("imaging.stabilize", clip.fingerprint(), bits).hash(&mut h);
        let held =
            Clip::new(clip.element().clone(), clip.fps(), h.finish(), Arc::new(HeldSource { clip: clip.clone(), lookups }));
        Ok(StabilizeOut { clip: ClipOf::new(held), correction })
    }
}

/// Whether `m` moves no pixel by a measurable amount.
fn is_identity(m: Rigid) -> bool {
    m.angle.abs() < 1e-6 && m.shift[0].abs() < 1e-3 && m.shift[1].abs() < 1e-3
}

/// The camera's path: frame 0's motion is none, each next one the last chained with its step (a
/// step not measured counts as none).
pub fn camera_path(steps: &[Option<Rigid>]) -> Vec<Rigid> {
    let mut path = vec![Rigid::default()];
    for s in steps {
        let last = path[path.len() - 1];
        path.push(last.then(s.unwrap_or_default()));
    }
    path
}

/// `path` smoothed by a Gaussian of `sigma` frames (angle and shift apart; the ends renormalized);
/// `sigma` 0 is no motion at all: every frame held on the first.
pub fn smooth_path(path: &[Rigid], sigma: f64) -> Vec<Rigid> {
    if sigma <= 0.0 {
        return vec![Rigid::default(); path.len()];
    }
    let r = (3.0 * sigma).ceil() as i64;
    (0..path.len() as i64)
        .map(|i| {
            let (mut sum, mut weight) = (Rigid::default(), 0.0);
            for j in (i - r).max(0)..=(i + r).min(path.len() as i64 - 1) {
                let w = (-((j - i) as f64).powi(2) / (2.0 * sigma * sigma)).exp();
                let p = path[j as usize];
                sum.angle += w * p.angle;
                sum.shift[0] += w * p.shift[0];
                sum.shift[1] += w * p.shift[1];
                weight += w;
            }
            Rigid { angle: sum.angle / weight, shift: [sum.shift[0] / weight, sum.shift[1] / weight] }
        })
        .collect()
}

/// How far `m` moves the farthest corner of a `size` frame, in pixels.
fn corner_shift(m: Rigid, size: (u32, u32)) -> f64 {
    let (w, h) = (f64::from(size.0), f64::from(size.1));
    let c = [w / 2.0, h / 2.0];
    [[0.0, 0.0], [w, 0.0], [0.0, h], [w, h]]
        .iter()
        .map(|p| {
            let q = m.apply(*p, c);
            (q[0] - p[0]).hypot(q[1] - p[1])
        })
        .fold(0.0, f64::max)
}

/// `img` resampled so output pixel `x` shows input pixel `lookup(x)`, about the frame's centre;
/// pixels from outside the frame are transparent black. Catmull-Rom (bicubic), each sample kept
/// within its four nearest input pixels: a held frame is resampled once more than the footage,
/// and bilinear would soften every edge (a flame's outline, which the mask follows) once more;
/// the clamp keeps the cubic's overshoot from ringing around a bright flame.
pub fn warp(img: &Image, lookup: Rigid) -> Image {
    use rayon::prelude::*;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let ch = img.channels().count();
    let c = [w as f64 / 2.0, h as f64 / 2.0];
    let src = img.data();
    let mut out = vec![0.0f32; w * h * ch];
    out.par_chunks_mut((w * ch).max(1)).enumerate().for_each(|(y, row)| {
        for x in 0..w {
            // Pixel centres: the frame's centre is between pixels for even sizes.
            let [sx, sy] = lookup.apply([x as f64 + 0.5, y as f64 + 0.5], c);
            let (fx, fy) = (sx - 0.5, sy - 0.5);
            if fx < -0.5 || fy < -0.5 || fx > w as f64 - 0.5 || fy > h as f64 - 0.5 {
                continue;
            }
            let (x0, y0) = (fx.floor(), fy.floor());
            let (wx, wy) = (catmull_rom((fx - x0) as f32), catmull_rom((fy - y0) as f32));
            let clampi = |v: f64, most: usize| (v.max(0.0) as usize).min(most - 1);
            let xs = [-1.0, 0.0, 1.0, 2.0].map(|d| clampi(x0 + d, w));
            let ys = [-1.0, 0.0, 1.0, 2.0].map(|d| clampi(y0 + d, h));
            for k in 0..ch {
                let at = |x: usize, y: usize| src[(y * w + x) * ch + k];
                let mut v = 0.0;
                for (j, &yy) in ys.iter().enumerate() {
                    let line: f32 = xs.iter().zip(&wx).map(|(&xx, wt)| wt * at(xx, yy)).sum();
                    v += wy[j] * line;
                }
                let near = [at(xs[1], ys[1]), at(xs[2], ys[1]), at(xs[1], ys[2]), at(xs[2], ys[2])];
                let (lo, hi) = near.iter().fold((f32::MAX, f32::MIN), |(l, u), &n| (l.min(n), u.max(n)));
                // Four NaN neighbours (a float file's holes) leave nothing to clamp to.
                row[x * ch + k] = if lo <= hi { v.clamp(lo, hi) } else { v };
            }
        }
    });
    let channels = if ch == 1 { Channels::Gray } else { Channels::Rgba };
    Image::from_vec(img.width(), img.height(), channels, out).unwrap_or_else(|| img.clone())
}

/// Catmull-Rom weights of the four taps around a sample `t` (0..1) past the second.
fn catmull_rom(t: f32) -> [f32; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

/// The camera's motion from frame `a` to frame `b` (where a still point of `a` is in `b`), or
/// `None` when the frames have too little still texture to tell.
pub fn frame_motion(a: &Image, b: &Image) -> Option<Rigid> {
    let (mut pa, mut pb) = (vec![Plane::luminance(a)], vec![Plane::luminance(b)]);
    let mut scale = 1.0;
    while pa[0].width.max(pa[0].height) > WORK_SIDE {
        pa[0] = pa[0].half();
        pb[0] = pb[0].half();
        scale *= 2.0;
    }
    let mut pk = vec![still_pixels(&pa[0], &pb[0])];
    while pa[pa.len() - 1].width.min(pa[pa.len() - 1].height) >= 48 && pa.len() < 6 {
        let (na, nb, nk) = (pa[pa.len() - 1].half(), pb[pb.len() - 1].half(), pk[pk.len() - 1].half());
        pa.push(na);
        pb.push(nb);
        pk.push(nk);
    }
    let mut m = Rigid::default();
    for level in (0..pa.len()).rev() {
        let f = (1u32 << level) as f64;
        // The motion in this level's pixels.
        let mut lm = Rigid { angle: m.angle, shift: [m.shift[0] / f, m.shift[1] / f] };
        let grads = Gradients::of(&pb[level]);
        for _ in 0..12 {
            // Noise averages out on the coarsest level, where a frame without still texture is
            // told apart; a finer level that cannot add to the estimate leaves it as it is.
            let Some(step) = gauss_newton_step(&pa[level], &pb[level], &pk[level], &grads, lm) else {
                if level == pa.len() - 1 {
                    return None;
                }
                break;
            };
            lm.angle += step[0];
            lm.shift[0] += step[1];
            lm.shift[1] += step[2];
            if step[0].abs() < 1e-5 && step[1].abs() < 1e-3 && step[2].abs() < 1e-3 {
                break;
            }
        }
        m = Rigid { angle: lm.angle, shift: [lm.shift[0] * f, lm.shift[1] * f] };
    }
    // A camera's motion brings the still pixels into register; a flame, a hand or smoke moving on
    // its own does not. Unless the motion makes clearly more pixels agree than no motion does,
    // the camera is taken as still (a tripod's noise is not shake either).
    let moved = still_residuals(&pa[0], &pb[0], &pk[0], m);
    let within = agree_level(&moved);
    let (moved, unmoved) =
        (agreeing(&moved, within), agreeing(&still_residuals(&pa[0], &pb[0], &pk[0], Rigid::default()), within));
    if moved < 0.5 || moved < unmoved + 0.05 {
        return Some(Rigid::default());
    }
    Some(Rigid { angle: m.angle, shift: [m.shift[0] * scale, m.shift[1] * scale] })
}

/// Brightness difference under which a pixel agrees in two frames, at most: footage with less
/// noise and contrast is judged by its own residual (see [`agree_level`]).
const AGREE: f32 = 0.03;

/// The least difference a pixel may differ by and still disagree: three 8-bit steps.
const AGREE_FLOOR: f32 = 3.0 / 255.0;

/// The frame's centre in the plane's index coordinates: index `i` is the pixel whose centre is at
/// `i + 0.5`, as [`warp`] counts, so both turn about the same point at every scale.
fn index_centre(w: usize, h: usize) -> [f64; 2] {
    [w as f64 / 2.0 - 0.5, h as f64 / 2.0 - 0.5]
}

/// The difference under which a still pixel agrees, from the still pixels' `residuals` under the
/// motion found (what noise and resampling leave): 2.5 × their median, between [`AGREE_FLOOR`] and
/// [`AGREE`]. Dim or flat footage moves its pixels by less than a bright textured one for the same
/// shake, and a fixed level would take its shake for noise. The floor keeps 8-bit noise from
/// agreeing better under a half-pixel motion than under none (bilinear sampling averages four noisy
/// pixels, a quarter less noise, which a level of about 2σ would count as agreement).
fn agree_level(residuals: &[f32]) -> f32 {
    if residuals.is_empty() {
        return AGREE;
    }
    let mut sorted = residuals.to_vec();
    let mid = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(mid, f32::total_cmp).1;
    (2.5 * median).clamp(AGREE_FLOOR, AGREE)
}

/// Share of `residuals` under `within`: of the still pixels, those that agree (0 with none).
fn agreeing(residuals: &[f32], within: f32) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    residuals.iter().filter(|r| **r < within).count() as f64 / residuals.len() as f64
}

/// The brightness differences between the still pixels of `a` and where the motion `m` puts them
/// in `b`, for those it keeps inside `b`.
fn still_residuals(a: &Plane, b: &Plane, still: &Plane, m: Rigid) -> Vec<f32> {
    let (w, h) = (a.width, a.height);
    let c = index_centre(w, h);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if still.data[y * w + x] < 1.0 {
                continue;
            }
            let [bx, by] = m.apply([x as f64, y as f64], c);
            if bx < 0.0 || by < 0.0 || bx > (w - 1) as f64 || by > (h - 1) as f64 {
                continue;
            }
            out.push((b.sample(bx as f32, by as f32) - a.data[y * w + x]).abs());
        }
    }
    out
}

/// 1 where a pixel is far enough from the fire to count as still scene in both frames, 0 near it:
/// pixels within a 24th of the frame's larger side of one at [`BRIGHT`] of the brightest level or
/// above (the fire, its glow and what it lights move with it).
fn still_pixels(a: &Plane, b: &Plane) -> Plane {
    let (w, h) = (a.width, a.height);
    let r = (w.max(h) / 24).max(1);
    // Relative to the frames' brightest (their 99.9th percentile), so a darker exposure's fire
    // is left out as well.
    let mut sorted: Vec<f32> = a.data.iter().zip(&b.data).map(|(x, y)| x.max(*y)).collect();
    let top = if sorted.is_empty() {
        1.0
    } else {
        let k = (sorted.len() - 1) * 999 / 1000;
        *sorted.select_nth_unstable_by(k, f32::total_cmp).1
    };
    // A light source stands out from the scene: in a scene with none (a textured wall, a sky as
    // bright as the fire) nothing is left out and the Huber weights and the check in
    // `frame_motion` keep the fire from counting.
    let k = (sorted.len().max(1) - 1) / 2;
    let median = if sorted.is_empty() { 0.0 } else { *sorted.select_nth_unstable_by(k, f32::total_cmp).1 };
    let level = (BRIGHT * top.max(0.05)).max(2.5 * median);
    let hot: Vec<bool> = a.data.iter().zip(&b.data).map(|(x, y)| x.max(*y) >= level).collect();
    // Distance to the nearest hot pixel along rows, then the box of it along columns: a square
    // dilation by r in two passes.
    let mut near_row = vec![false; w * h];
    for y in 0..h {
        let mut last: Option<usize> = None;
        for x in 0..w {
            if hot[y * w + x] {
                last = Some(x);
            }
            near_row[y * w + x] = last.is_some_and(|l| x - l <= r);
        }
        let mut next: Option<usize> = None;
        for x in (0..w).rev() {
            if hot[y * w + x] {
                next = Some(x);
            }
            near_row[y * w + x] |= next.is_some_and(|n| n - x <= r);
        }
    }
    let mut still = Plane::new(w, h);
    for x in 0..w {
        let mut last: Option<usize> = None;
        for y in 0..h {
            if near_row[y * w + x] {
                last = Some(y);
            }
            still.data[y * w + x] = f32::from(last.is_none_or(|l| y - l > r));
        }
        let mut next: Option<usize> = None;
        for y in (0..h).rev() {
            if near_row[y * w + x] {
                next = Some(y);
            }
            if next.is_some_and(|n| n - y <= r) {
                still.data[y * w + x] = 0.0;
            }
        }
    }
    still
}

/// Central-difference brightness gradients of a plane.
struct Gradients {
    x: Plane,
    y: Plane,
}

impl Gradients {
    fn of(p: &Plane) -> Gradients {
        let (w, h) = (p.width, p.height);
        let at = |x: usize, y: usize| p.data[y * w + x];
        let mut gx = Plane::new(w, h);
        let mut gy = Plane::new(w, h);
        for y in 0..h {
            for x in 0..w {
                gx.data[y * w + x] = 0.5 * (at((x + 1).min(w - 1), y) - at(x.saturating_sub(1), y));
                gy.data[y * w + x] = 0.5 * (at(x, (y + 1).min(h - 1)) - at(x, y.saturating_sub(1)));
            }
        }
        Gradients { x: gx, y: gy }
    }
}

/// One Huber-weighted Gauss–Newton step `[angle, shift x, shift y]` for the motion `m` taking `a`
/// onto `b` (residual `b(m(x)) − a(x)` over `a`'s still pixels), or `None` when those pixels have
/// too little texture to fix the motion.
fn gauss_newton_step(a: &Plane, b: &Plane, still: &Plane, g: &Gradients, m: Rigid) -> Option<[f64; 3]> {
    let (w, h) = (a.width, a.height);
    let c = index_centre(w, h);
    let (s, co) = m.angle.sin_cos();
    // Residuals and Jacobians of the pixels used; the Huber scale is their median residual's.
    let mut rows: Vec<(f64, [f64; 3])> = Vec::with_capacity(w * h);
    let mut texture = 0.0;
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let va = a.data[y * w + x];
            if still.data[y * w + x] < 1.0 {
                continue;
            }
            let [bx, by] = m.apply([x as f64, y as f64], c);
            if bx < 1.0 || by < 1.0 || bx > (w - 2) as f64 || by > (h - 2) as f64 {
                continue;
            }
            let (fx, fy) = (bx as f32, by as f32);
            let vb = b.sample(fx, fy);
            let (gx, gy) = (f64::from(g.x.sample(fx, fy)), f64::from(g.y.sample(fx, fy)));
            let (dx, dy) = (x as f64 - c[0], y as f64 - c[1]);
            let d_angle = gx * (-s * dx - co * dy) + gy * (co * dx - s * dy);
            texture += gx * gx + gy * gy;
            rows.push((f64::from(vb - va), [d_angle, gx, gy]));
        }
    }
    if rows.len() < 64 || texture / (rows.len() as f64) < MIN_TEXTURE {
        return None;
    }
    let mut abs: Vec<f64> = rows.iter().map(|(r, _)| r.abs()).collect();
    let mid = abs.len() / 2;
    let median = *abs.select_nth_unstable_by(mid, f64::total_cmp).1;
    let k = (1.345 * 1.4826 * median).max(1e-3);
    let (mut hm, mut gv) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
    for (r, j) in &rows {
        let wgt = if r.abs() <= k { 1.0 } else { k / r.abs() };
        for i in 0..3 {
            gv[i] += wgt * j[i] * r;
            for l in 0..3 {
                hm[i][l] += wgt * j[i] * j[l];
            }
        }
    }
    solve3(hm, gv.map(|v| -v))
}

/// `x` with `m x = v` (Cramer's rule), `None` when `m` is singular.
fn solve3(m: [[f64; 3]; 3], v: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if !d.is_finite() || d.abs() < 1e-18 {
        return None;
    }
    let mut out = [0.0; 3];
    for (col, o) in out.iter_mut().enumerate() {
        let mut mc = m;
        for row in 0..3 {
            mc[row][col] = v[row];
        }
        *o = det(&mc) / d;
    }
    Some(out)
}

#[cfg(test)]
mod tests;
