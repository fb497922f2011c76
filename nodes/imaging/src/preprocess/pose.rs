//! `imaging.pose_normalize`: direction removal by a weighted least-squares line through the
//! flame contour (thesis §3.4, eq. 7–11, remedies 1–3), or per-clip style centring and scaling.

use std::sync::Arc;

use image::{Luma, Rgba};
use imageproc::geometric_transformations::{Border, Interpolation, Projection, warp};
use pyrograph_core::{Channels, Contour, Contours, Cook, CookCtx, Image, NodeError, port};

use super::contours::simplify_closed;
use super::pose_smooth::outline_elongation;
use crate::auto_crop::fill_warning;
use crate::convert::{from_gray32f, from_rgba32f, to_gray32f, to_rgba32f};

/// How contour points are weighted in the line fit (eq. 7–8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Weighting {
    /// Every stretch of outline counts the same (vertices weighted by their share of the perimeter).
    Uniform,
    /// Remedy 3: weight grows towards the bottom of the flame (its root), `0.1 + t²` with
    /// `t` 0 at the top of the contour and 1 at its bottom (times the perimeter share).
    Root,
    /// Remedy 1: simplify the contour with Douglas–Peucker at this tolerance first, then fit the
    /// low-poly outline uniformly.
    LowPoly(f64),
}

/// A fitted flame axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlameAxis {
    /// Lower end point of the trimmed line (the rotation pivot), in pixels.
    pub root: [f64; 2],
    /// Upper end point.
    pub tip: [f64; 2],
    /// Lean of the axis from vertical in degrees, positive when the tip leans right (x grows).
    pub angle_deg: f64,
}

/// Weighted least-squares line through `points` minimizing `Σ wᵢ rᵢ²` with perpendicular
/// residuals (eq. 7). Returns the weighted centroid and a unit direction, or `None` with fewer
/// than two distinct points or no positive weight.
///
/// Hand-written because neither imageproc nor image fits weighted lines. Using the principal axis
/// of the weighted covariance instead of `y = mx + b` keeps vertical flames (infinite slope,
/// the common case) well-defined.
pub fn fit_line(points: &[[f64; 2]], weights: &[f64]) -> Option<([f64; 2], [f64; 2])> {
    let total: f64 = weights.iter().sum();
    if points.len() < 2 || total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (mut cx, mut cy) = (0.0, 0.0);
    for (p, w) in points.iter().zip(weights) {
        cx += w * p[0];
        cy += w * p[1];
    }
    let (cx, cy) = (cx / total, cy / total);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (p, w) in points.iter().zip(weights) {
        let (dx, dy) = (p[0] - cx, p[1] - cy);
        sxx += w * dx * dx;
        sxy += w * dx * dy;
        syy += w * dy * dy;
    }
    if sxx + syy <= f64::EPSILON * total {
        return None;
    }
    // Major axis of the symmetric 2×2 covariance: the direction minimizing perpendicular residuals.
    let phi = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    Some(([cx, cy], [phi.cos(), phi.sin()]))
}

/// Projects every point on the line (eq. 9–11 in direction-vector form) and returns the two
/// extreme projections, lower one (larger y) first.
pub fn trim_line(points: &[[f64; 2]], centre: [f64; 2], dir: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let t = |p: &[f64; 2]| (p[0] - centre[0]) * dir[0] + (p[1] - centre[1]) * dir[1];
    let (lo, hi) = points.iter().map(t).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let at = |s: f64| [centre[0] + s * dir[0], centre[1] + s * dir[1]];
    let (a, b) = (at(lo), at(hi));
    // Image y grows downwards, so the root is the end with the larger y; ties go to the left end.
    if a[1] > b[1] || (a[1] == b[1] && a[0] <= b[0]) { (a, b) } else { (b, a) }
}

/// The contour the pose is taken from: the largest outermost one (as the OpenCV peer picks).
pub fn main_contour(contours: &Contours) -> Option<&Contour> {
    contours.contours.iter().filter(|c| c.depth == 0).max_by(|a, b| a.area.total_cmp(&b.area))
}

fn to_f64(points: &[[f32; 2]]) -> Vec<[f64; 2]> {
    points.iter().map(|&[x, y]| [f64::from(x), f64::from(y)]).collect()
}

/// Each vertex's share of the closed polygon's perimeter (half of its two edges).
///
/// Traced borders sample diagonal runs at √2 px and straight runs at 1 px, and simplified
/// polygons sample anything; weighting by arc length makes the fit follow the outline, not the
/// sampling density (without it a 25° ellipse reads as 26°).
fn arc_weights(points: &[[f64; 2]]) -> Vec<f64> {
    let n = points.len();
    let dist = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    (0..n)
        .map(|i| match (points.get((i + n - 1) % n), points.get(i), points.get((i + 1) % n)) {
            (Some(prev), Some(p), Some(next)) => 0.5 * (dist(prev, p) + dist(p, next)),
            _ => 0.0,
        })
        .collect()
}

fn root_weights(points: &[[f64; 2]]) -> Vec<f64> {
    let (top, bottom) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    let span = (bottom - top).max(f64::EPSILON);
    points.iter().map(|p| 0.1 + ((p[1] - top) / span).powi(2)).collect()
}

/// Fits the flame axis of `contour` with `weighting`; `None` when the contour is degenerate.
pub fn flame_axis(contour: &Contour, weighting: Weighting) -> Option<FlameAxis> {
    let all = to_f64(&contour.points);
    let (fit_points, weights) = match weighting {
        Weighting::Uniform => (all.clone(), arc_weights(&all)),
        Weighting::Root => {
            let w = arc_weights(&all).iter().zip(root_weights(&all)).map(|(a, r)| a * r).collect();
            (all.clone(), w)
        }
        Weighting::LowPoly(tol) => {
            let low = to_f64(&simplify_closed(&contour.points, tol));
            let w = arc_weights(&low);
            (low, w)
        }
    };
    let (centre, dir) = fit_line(&fit_points, &weights)?;
    let (root, tip) = trim_line(&all, centre, dir);
    let angle_deg = (tip[0] - root[0]).atan2(root[1] - tip[1]).to_degrees();
    Some(FlameAxis { root, tip, angle_deg })
}

/// Below this lean (degrees) rotation is skipped, so an upright flame passes through bit-exact.
pub const UPRIGHT_EPSILON_DEG: f64 = 1e-3;

/// Applies `projection` (input → output pixel coordinates) with bilinear sampling; uncovered
/// pixels become black (transparent for RGBA).
pub fn warp_image(image: &Image, projection: Projection) -> Image {
    match image.channels() {
        Channels::Gray => {
            from_gray32f(warp(&to_gray32f(image), projection, Interpolation::Bilinear, Border::Constant(Luma([0.0]))))
        }
        Channels::Rgba => {
            from_rgba32f(warp(&to_rgba32f(image), projection, Interpolation::Bilinear, Border::Constant(Rgba([0.0; 4]))))
        }
    }
}

/// Rotates `image` about the axis root so the flame stands vertical.
pub fn rotate_upright(image: &Image, axis: &FlameAxis) -> Image {
    if axis.angle_deg.abs() < UPRIGHT_EPSILON_DEG {
        return image.clone();
    }
    let (px, py) = (axis.root[0] as f32, axis.root[1] as f32);
    // imageproc's rotation turns clockwise on screen for positive angles; a right-leaning tip
    // needs the opposite turn.
    let theta = (-axis.angle_deg.to_radians()) as f32;
    warp_image(image, Projection::translate(px, py) * Projection::rotate(theta) * Projection::translate(-px, -py))
}

/// Where the flame's outline lands after `rotate_upright` turns it by `turn_deg` about `root`, as
/// a bounding box `[x_min, y_min, x_max, y_max]` (the same rotation as the warp: positive turns
/// a right-leaning tip up).
pub fn turned_bounds(points: &[[f32; 2]], root: [f64; 2], turn_deg: f64) -> Option<[f64; 4]> {
    let (s, c) = (-turn_deg.to_radians()).sin_cos();
    let turned = points.iter().map(|&[x, y]| {
        let (dx, dy) = (f64::from(x) - root[0], f64::from(y) - root[1]);
        [root[0] + c * dx - s * dy, root[1] + s * dx + c * dy]
    });
    let b = turned.fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, [x, y]| {
        [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]
    });
    (b[0] <= b[2]).then_some(b)
}

/// The scale (≤ 1, about the root) and shift that bring the turned outline `bounds` inside a
/// `w` × `h` frame with `margin` pixels to spare; `(1, [0, 0])` when it is inside already.
pub fn keep_inside(bounds: [f64; 4], root: [f64; 2], w: f64, h: f64, margin: f64) -> (f64, [f64; 2]) {
    let (bw, bh) = (bounds[2] - bounds[0], bounds[3] - bounds[1]);
    let scale = ((w - 1.0 - 2.0 * margin) / bw.max(1e-9)).min((h - 1.0 - 2.0 * margin) / bh.max(1e-9)).clamp(1e-3, 1.0);
    // The scaled box, about the root.
    let at = |v: f64, r: f64| r + scale * (v - r);
    let (x0, y0, x1, y1) = (at(bounds[0], root[0]), at(bounds[1], root[1]), at(bounds[2], root[0]), at(bounds[3], root[1]));
    let shift_axis = |lo: f64, hi: f64, size: f64| {
        if lo < margin {
            margin - lo
        } else if hi > size - 1.0 - margin {
            (size - 1.0 - margin - hi).max(margin - lo)
        } else {
            0.0
        }
    };
    (scale, [shift_axis(x0, x1, w), shift_axis(y0, y1, h)])
}

/// Rotates `image` about `root` by `turn_deg` (as [`rotate_upright`]), then scales it by `scale`
/// about the root and shifts it by `shift`.
pub fn turn_scale_shift(image: &Image, root: [f64; 2], turn_deg: f64, scale: f64, shift: [f64; 2]) -> Image {
    let (px, py) = (root[0] as f32, root[1] as f32);
    let theta = (-turn_deg.to_radians()) as f32;
    let (s, sx, sy) = (scale as f32, shift[0] as f32, shift[1] as f32);
    warp_image(
        image,
        Projection::translate(px + sx, py + sy)
            * Projection::scale(s, s)
            * Projection::rotate(theta)
            * Projection::translate(-px, -py),
    )
}

/// Bounding box `[x_min, y_min, x_max, y_max]` of every outermost contour's points.
pub fn flame_bounds(contours: &Contours) -> Option<[f64; 4]> {
    let pts = contours.contours.iter().filter(|c| c.depth == 0).flat_map(|c| c.points.iter());
    let b = pts.fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, &[x, y]| {
        [b[0].min(f64::from(x)), b[1].min(f64::from(y)), b[2].max(f64::from(x)), b[3].max(f64::from(y))]
    });
    (b[0] <= b[2]).then_some(b)
}

/// Translates the flame's bounding box to the image centre and scales it to `height_fraction`
/// of the image height (the thesis does this once per clip via its UI, §3.4).
pub fn center_scale(image: &Image, bounds: [f64; 4], height_fraction: f64) -> Image {
    let (w, h) = (f64::from(image.width()), f64::from(image.height()));
    let box_h = (bounds[3] - bounds[1]).max(1.0);
    let s = (height_fraction * h / box_h) as f32;
    let (bx, by) = (((bounds[0] + bounds[2]) / 2.0) as f32, ((bounds[1] + bounds[3]) / 2.0) as f32);
    // Pixel centres sit at integer coordinates, so the image centre is at (w-1)/2, (h-1)/2.
    let (cx, cy) = (((w - 1.0) / 2.0) as f32, ((h - 1.0) / 2.0) as f32);
    warp_image(image, Projection::translate(cx, cy) * Projection::scale(s, s) * Projection::translate(-bx, -by))
}

/// Pose normalization mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PoseMode {
    /// Rotate about the axis root so the flame stands vertical.
    Rotate,
    /// Centre the flame's bounding box and scale it to this fraction of the image height.
    CenterScale(f64),
}

/// Result of [`pose_normalize`].
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// The normalized image.
    pub image: Image,
    /// The fitted axis; `None` when there were no usable contours (the image passes through).
    pub axis: Option<FlameAxis>,
}

/// Normalizes the pose of the flame described by `contours` in `image`.
///
/// Without contours (or with a degenerate main contour) the image passes through unchanged and
/// no axis is reported — an empty frame is normal in a clip, not an error.
pub fn pose_normalize(image: &Image, contours: &Contours, mode: PoseMode, weighting: Weighting) -> Pose {
    let axis = main_contour(contours).and_then(|c| flame_axis(c, weighting));
    let image = match (mode, axis) {
        (PoseMode::Rotate, Some(a)) => rotate_upright(image, &a),
        (PoseMode::CenterScale(f), Some(_)) => {
            flame_bounds(contours).map_or_else(|| image.clone(), |b| center_scale(image, b, f))
        }
        (_, None) => image.clone(),
    };
    Pose { image, axis }
}

pyrograph_core::choice! {
    /// The `mode` option of `imaging.pose_normalize` (a [`PoseMode`] without its target height).
    pub enum PoseModeOption {
        /// [`PoseMode::Rotate`].
        Rotate = "rotate",
        /// [`PoseMode::CenterScale`].
        CenterScale = "center_scale",
        /// Only measure the lean (for imaging.smooth_angle): the frame passes through, no guard acts or warns.
        Measure = "measure",
    }
}

pyrograph_core::choice! {
    /// The `weights` option of `imaging.pose_normalize` (a [`Weighting`] without its tolerance).
    pub enum WeightingOption {
        /// [`Weighting::Uniform`].
        Uniform = "uniform",
        /// [`Weighting::Root`].
        Root = "root",
        /// [`Weighting::LowPoly`].
        LowPoly = "lowpoly",
    }
}

pyrograph_core::node! {
    /// Removes the flame's direction with a weighted least-squares line through its contour (Eigenfires thesis §3.4, eq. 7–11).
    ///
    /// The line is fitted to the largest outermost contour (weights: uniform; root = remedy 3, more weight near the
    /// bottom; lowpoly = remedy 1, Douglas–Peucker first), trimmed at the extreme projections of the contour points,
    /// and the image is rotated about the lower end so the flame stands vertical. Mode center_scale instead moves the
    /// flame's bounding box to the centre and scales it to target_height of the frame (angle and end points are
    /// still reported). With no contours the image passes through and angle is 0. Guards for footage the thesis did
    /// not film: a lean beyond max_angle is turned only max_angle, and a fire filling the picture (which has no
    /// single axis) is neither turned nor scaled — every frame of the clip when fills is connected to
    /// imaging.auto_crop's fills (its box over the clip spans max_fill of the frame's width or height), else each
    /// frame whose outline spans max_width of the frame's width; both warn, and turned reports the rotation
    /// applied. Mode measure only reports the lean, for imaging.smooth_angle.
    #[node("imaging.pose_normalize", "Pre-processing", PerFrame)]
    pub struct PoseNormalize {
        /// Frame to normalize (gray or RGBA)
        image: Arc<Image>,
        /// Flame contours traced from this frame
        contours: Arc<Contours>,
        /// rotate: stand the flame upright; center_scale: centre and scale it; measure: only report the lean
        mode: PoseModeOption = PoseModeOption::Rotate,
        /// Point weighting of the line fit (remedies 3 and 1)
        weights: WeightingOption = WeightingOption::Uniform,
        /// Douglas–Peucker tolerance in pixels for weights = lowpoly
        #[range(0.1, 1000.0)]
        lowpoly_tolerance: f64 = 8.0,
        /// Flame height as a fraction of the frame height in center_scale mode
        #[range(0.01, 4.0)]
        target_height: f64 = 0.8,
        /// Largest rotation in degrees; a flame leaning further is turned this far only (rotate mode)
        #[range(0.0, 180.0)]
        max_angle: f64 = 45.0,
        /// Outline width, as a fraction of the frame's, from which a frame fills the picture and is not turned (rotate mode)
        #[range(0.05, 1.0)]
        max_width: f64 = 0.9,
        /// The fire fills the picture over the clip (connect imaging.auto_crop's fills): no frame is turned or scaled, and the auto crop has said so (rotate mode)
        fills: bool = false,
        /// Keep the turned flame inside the frame: where the turn would push part of it out, move it back in and, if it is taller or wider than the frame, scale it down about its root (rotate mode; off keeps every frame's scale, as the thesis does)
        keep_inside: bool = false,
        /// Straighten by lean instead of the fitted angle (connect imaging.smooth_angle's angle so the turn does not jitter); the guards still apply (rotate mode)
        use_lean: bool = false,
        /// The lean to straighten, in degrees, positive to the right (with use_lean)
        #[range(-180.0, 180.0)]
        lean: f64 = 0.0,
    }
    pub struct PoseNormalizeOut {
        /// Normalized frame
        image: Arc<Image>,
        /// Lean of the flame from vertical in degrees, positive to the right; 0 without contours
        angle: f64,
        /// Lower end of the fitted line (the pivot), in input pixels
        root: [f64; 2],
        /// Upper end of the fitted line, in input pixels
        tip: [f64; 2],
        /// Rotation applied in degrees (the lean, limited by the guards); 0 in center_scale mode
        turned: f64,
        /// How much longer than wide the outline is (its principal axes' ratio; 0 without contours): for imaging.smooth_angle's judgement of fires with no single axis
        elongation: f64,
        /// Separate fires in the frame (outermost contours)
        fires: i64,
    }
}

/// The rotation `imaging.pose_normalize` applies for a measured lean: the lean itself, at most
/// `max_angle` either way, and none when the outline spans `max_width` of the frame's width (a
/// frame on its own: only width counts there, so a flame lying across a short frame is still
/// straightened; over a clip, the auto crop's [`crate::auto_crop::fills_picture`] decides). Returns
/// the turn and, when a guard acted, the warning to give.
pub fn guarded_turn(lean_deg: f64, span: (f64, f64), frame: (f64, f64), max_angle: f64, max_width: f64) -> (f64, Option<String>) {
    // One wording for every frame (no per-frame numbers), so a clip reports each guard once
    // (see CookCtx::warn) instead of once per frame.
    if span.0 >= max_width * frame.0 {
        return (0.0, Some(fill_warning(None, max_width)));
    }
    if lean_deg.abs() > max_angle {
        let turn = max_angle.copysign(lean_deg);
        let msg = format!(
            "the flame leans more than max_angle ({max_angle}°): frames like this are turned {max_angle}° only; raise \
             max_angle if flames this tilted should stand upright"
        );
        return (turn, Some(msg));
    }
    (lean_deg, None)
}

/// Columns and rows the outline covers: a traced outline runs through pixel centres, so one from
/// the first column to the last spans the whole width.
fn outline_span(contour: &Contour) -> (f64, f64) {
    let b = contour.points.iter().fold([f32::INFINITY, f32::INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY], |b, &[x, y]| {
        [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]
    });
    if b[0] > b[2] { (0.0, 0.0) } else { (f64::from(b[2] - b[0]) + 1.0, f64::from(b[3] - b[1]) + 1.0) }
}

impl Cook for PoseNormalize {
    fn cook(self, ctx: &CookCtx) -> Result<PoseNormalizeOut, NodeError> {
        let (image, contours) = (&self.image, &self.contours);
        if (contours.width, contours.height) != image.size() && !contours.contours.is_empty() {
            return Err(NodeError::port(
                port!(PoseNormalize, contours),
                format!(
                    "traced in a {}×{} image but the image is {}×{}",
                    contours.width,
                    contours.height,
                    image.width(),
                    image.height()
                ),
            ));
        }
        let mode = match self.mode {
            PoseModeOption::Rotate | PoseModeOption::Measure => PoseMode::Rotate,
            PoseModeOption::CenterScale => PoseMode::CenterScale(self.target_height),
        };
        let weighting = match self.weights {
            WeightingOption::Uniform => Weighting::Uniform,
            WeightingOption::Root => Weighting::Root,
            WeightingOption::LowPoly => Weighting::LowPoly(self.lowpoly_tolerance),
        };
        let axis = main_contour(contours).and_then(|c| flame_axis(c, weighting));
        let (angle, root, tip) = axis.map_or((0.0, [0.0; 2], [0.0; 2]), |a| (a.angle_deg, a.root, a.tip));
        let elongation = main_contour(contours).map_or(0.0, outline_elongation);
        let fires = contours.contours.iter().filter(|c| c.depth == 0).count() as i64;
        if self.mode == PoseModeOption::Measure {
            let image = Arc::clone(&self.image);
            return Ok(PoseNormalizeOut { image, angle, root, tip, turned: 0.0, elongation, fires });
        }
        let (image, turned) = match (mode, axis) {
            (PoseMode::Rotate, Some(a)) => {
                let (iw, ih) = (f64::from(image.width()), f64::from(image.height()));
                let span = main_contour(contours).map_or((0.0, 0.0), outline_span);
                let lean = if self.use_lean { self.lean } else { a.angle_deg };
                // A clip the auto crop found filling the picture: every frame stays as it is, and
                // the auto crop has given the one warning.
                let (turn, warning) =
                    if self.fills { (0.0, None) } else { guarded_turn(lean, span, (iw, ih), self.max_angle, self.max_width) };
                if let Some(w) = warning {
                    ctx.warn(w);
                }
                let fit = main_contour(contours)
                    .and_then(|c| turned_bounds(&c.points, a.root, turn))
                    .map_or((1.0, [0.0; 2]), |b| keep_inside(b, a.root, iw, ih, 1.0));
                if self.keep_inside && fit != (1.0, [0.0; 2]) && turn.abs() >= UPRIGHT_EPSILON_DEG {
                    // One wording for every frame, so a clip reports it once (see CookCtx::warn).
                    ctx.warn(if fit.0 < 1.0 {
                        "turned upright the flame would not fit the frame: it was scaled down about its root to keep it \
                         whole; crop with more room above and beside the flame to avoid this"
                    } else {
                        "turned upright the flame would leave the frame: it was moved back in to keep it whole; crop with \
                         more room above and beside the flame to avoid this"
                    });
                    (turn_scale_shift(image, a.root, turn, fit.0, fit.1), turn)
                } else {
                    (rotate_upright(image, &FlameAxis { angle_deg: turn, ..a }), turn)
                }
            }
            _ => (pose_normalize(image, contours, mode, weighting).image, 0.0),
        };
        Ok(PoseNormalizeOut { image: Arc::new(image), angle, root, tip, turned, elongation, fires })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::preprocess::contours::trace_contours;
    use pyrograph_core::Mask;

    /// A filled ellipse with semi-axes `rx`, `ry` centred at `(cx, cy)`, its long axis leaning
    /// `lean_deg` from vertical (positive: top to the right).
    pub(crate) fn ellipse_mask(w: u32, h: u32, (cx, cy): (f64, f64), (rx, ry): (f64, f64), lean_deg: f64) -> Mask {
        let (s, c) = lean_deg.to_radians().sin_cos();
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (f64::from(x) - cx, f64::from(y) - cy)))
            .map(|(dx, dy)| {
                // Coordinates along the leaning axes: u across, v along the flame (up = -y).
                let u = dx * c + dy * s;
                let v = dx * s - dy * c;
                if (u / rx).powi(2) + (v / ry).powi(2) <= 1.0 { 255 } else { 0 }
            })
            .collect();
        Mask::from_vec(w, h, data).unwrap()
    }

    fn mask_image(m: &Mask) -> Image {
        crate::convert::mask_to_image(m)
    }

    #[test]
    fn recovers_the_angle_of_a_tilted_flame() {
        for lean in [-35.0, -10.0, 0.0, 20.0, 40.0] {
            let m = ellipse_mask(120, 120, (60.0, 60.0), (12.0, 40.0), lean);
            let c = trace_contours(&m);
            for weighting in [Weighting::Uniform, Weighting::LowPoly(2.0)] {
                let axis = flame_axis(&c.contours[0], weighting).unwrap();
                assert!((axis.angle_deg - lean).abs() < 1.0, "{weighting:?}: {} vs {lean}", axis.angle_deg);
                assert!(axis.root[1] > axis.tip[1]);
            }
        }
    }

    #[test]
    fn guards_limit_the_turn_and_say_so() {
        let frame = (200.0, 100.0);
        assert_eq!(guarded_turn(10.0, (30.0, 60.0), frame, 45.0, 0.9), (10.0, None));
        let (turn, w) = guarded_turn(-60.0, (30.0, 60.0), frame, 45.0, 0.9);
        assert_eq!(turn, -45.0);
        assert!(w.is_some_and(|w| w.contains("leans more than max_angle (45°)") && w.contains("turned 45° only")));
        // Every frame over the limit words it alike, so a clip reports it once.
        assert_eq!(guarded_turn(-60.0, (30.0, 60.0), frame, 45.0, 0.9).1, guarded_turn(70.0, (30.0, 60.0), frame, 45.0, 0.9).1);
        let (turn, w) = guarded_turn(20.0, (190.0, 60.0), frame, 45.0, 0.9);
        assert_eq!(turn, 0.0);
        assert!(w.is_some_and(|w| w.contains("fills the picture") && w.contains("neither turned nor scaled")));
        // In the auto crop's words; a frame on its own fills by its width only (a flame lying
        // across a short frame is straightened).
        assert_eq!(guarded_turn(20.0, (190.0, 60.0), frame, 45.0, 0.9).1, Some(fill_warning(None, 0.9)));
        assert_eq!(guarded_turn(-5.0, (40.0, 95.0), frame, 45.0, 0.9), (-5.0, None));
    }

    /// Cooks the node with its defaults on `m` (the mask as the frame), returning the output and
    /// the warnings.
    fn cook_node(m: &Mask) -> (PoseNormalizeOut, Vec<String>) {
        cook_node_with(m, false)
    }

    /// [`cook_node`] with `fills` set as given.
    fn cook_node_with(m: &Mask, fills: bool) -> (PoseNormalizeOut, Vec<String>) {
        let node = PoseNormalize {
            image: Arc::new(mask_image(m)),
            contours: Arc::new(trace_contours(m)),
            mode: PoseModeOption::Rotate,
            weights: WeightingOption::Uniform,
            lowpoly_tolerance: 8.0,
            target_height: 0.8,
            max_angle: 45.0,
            max_width: 0.9,
            fills,
            keep_inside: true,
            use_lean: false,
            lean: 0.0,
        };
        let ctx = CookCtx::new();
        let out = node.cook(&ctx).unwrap();
        (out, ctx.warnings().into_iter().map(|w| w.message).collect())
    }

    #[test]
    fn a_steep_lean_is_turned_max_angle_only() {
        let m = ellipse_mask(160, 160, (80.0, 80.0), (12.0, 45.0), 60.0);
        let (out, warnings) = cook_node(&m);
        assert!((out.angle - 60.0).abs() < 1.0, "measured {}", out.angle);
        assert_eq!(out.turned, 45.0);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        // What is left of the lean after the turn: about 15°.
        let turned =
            Mask::from_vec(160, 160, out.image.data().iter().map(|&v| if v >= 0.5 { 255 } else { 0 }).collect()).unwrap();
        let rest = flame_axis(main_contour(&trace_contours(&turned)).unwrap(), Weighting::Uniform).unwrap();
        assert!((rest.angle_deg - 15.0).abs() < 1.5, "left leaning {}", rest.angle_deg);
    }

    #[test]
    fn a_frame_filling_fire_is_not_turned() {
        // Wider than 90 % of the frame and tilted 20°: passed through untouched, with a warning.
        let m = ellipse_mask(100, 100, (50.0, 50.0), (20.0, 60.0), 70.0);
        let (out, warnings) = cook_node(&m);
        assert_eq!(out.turned, 0.0);
        assert_eq!(out.image.data(), mask_image(&m).data());
        assert!(warnings.iter().any(|w| w.contains("no single axis")), "{warnings:?}");
        // A flame in the middle of the same frame is turned as before, without a warning.
        let (out, warnings) = cook_node(&ellipse_mask(100, 100, (50.0, 50.0), (8.0, 30.0), 20.0));
        assert!((out.turned - 20.0).abs() < 1.0 && warnings.is_empty(), "{} {warnings:?}", out.turned);
        // In a clip the auto crop found filling the picture, that frame too stays as it is, and
        // the auto crop's warning is the only one.
        let m = ellipse_mask(100, 100, (50.0, 50.0), (8.0, 30.0), 20.0);
        let (out, warnings) = cook_node_with(&m, true);
        assert_eq!((out.turned, warnings.len()), (0.0, 0));
        assert!((out.angle - 20.0).abs() < 1.0, "the lean is still measured: {}", out.angle);
        assert_eq!(out.image.data(), mask_image(&m).data());
    }

    #[test]
    fn a_turned_flame_is_kept_whole_inside_the_frame() {
        // A long flame lying 40° across a wide, short frame: upright it is taller than the frame.
        let m = ellipse_mask(200, 90, (100.0, 50.0), (8.0, 52.0), 40.0);
        let (out, warnings) = cook_node(&m);
        assert!((out.turned - 40.0).abs() < 1.0, "{}", out.turned);
        assert!(warnings.iter().any(|w| w.contains("would not fit the frame") && w.contains("scaled")), "{warnings:?}");
        let lit = |img: &Image| -> Vec<(u32, u32)> {
            (0..img.height())
                .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
                .filter(|&(x, y)| img.pixel(x, y)[0] > 0.5)
                .collect()
        };
        let after = lit(&out.image);
        // Nothing touches the border, and (almost) all of the flame is still there: scaled
        // to fit, its area shrinks by the scale squared, never by a cut.
        assert!(after.iter().all(|&(x, y)| x > 0 && y > 0 && x < 199 && y < 89), "the flame touches the frame's edge");
        let upright =
            Mask::from_vec(200, 90, out.image.data().iter().map(|&v| if v >= 0.5 { 255 } else { 0 }).collect()).unwrap();
        let axis = flame_axis(main_contour(&trace_contours(&upright)).unwrap(), Weighting::Uniform).unwrap();
        assert!(axis.angle_deg.abs() < 2.0, "still upright: {}", axis.angle_deg);
        let height = axis.root[1] - axis.tip[1];
        assert!(height > 80.0, "scaled to the frame's height, not cut: {height}");
        // Without the guard the same turn cuts the flame at the top of the frame.
        let a = flame_axis(main_contour(&trace_contours(&m)).unwrap(), Weighting::Uniform).unwrap();
        let cut = rotate_upright(&mask_image(&m), &a);
        assert!(lit(&cut).iter().any(|&(_, y)| y == 0), "the plain turn reaches the top edge");
    }

    #[test]
    fn turned_bounds_predict_where_the_warp_puts_the_flame() {
        let m = ellipse_mask(160, 160, (80.0, 90.0), (10.0, 40.0), -30.0);
        let c = trace_contours(&m);
        let a = flame_axis(main_contour(&c).unwrap(), Weighting::Uniform).unwrap();
        let b = turned_bounds(&main_contour(&c).unwrap().points, a.root, a.angle_deg).unwrap();
        let img = rotate_upright(&mask_image(&m), &a);
        for y in 0..160 {
            for x in 0..160 {
                if img.pixel(x, y)[0] > 0.5 {
                    let (x, y) = (f64::from(x), f64::from(y));
                    assert!(x >= b[0] - 1.5 && x <= b[2] + 1.5 && y >= b[1] - 1.5 && y <= b[3] + 1.5, "({x}, {y}) outside {b:?}");
                }
            }
        }
        assert_eq!(keep_inside(b, a.root, 160.0, 160.0, 1.0), (1.0, [0.0, 0.0]), "inside already: untouched");
    }

    #[test]
    fn rotating_stands_the_flame_upright() {
        let m = ellipse_mask(120, 120, (60.0, 60.0), (12.0, 40.0), 25.0);
        let pose = pose_normalize(&mask_image(&m), &trace_contours(&m), PoseMode::Rotate, Weighting::Uniform);
        let axis = pose.axis.unwrap();
        assert!((axis.angle_deg - 25.0).abs() < 1.0, "{axis:?}");
        let upright =
            Mask::from_vec(120, 120, pose.image.data().iter().map(|&v| if v >= 0.5 { 255 } else { 0 }).collect()).unwrap();
        let again = flame_axis(&trace_contours(&upright).contours[0], Weighting::Uniform).unwrap();
        assert!(again.angle_deg.abs() < 1.0, "{}", again.angle_deg);
        // The pivot stays where it was.
        let (rx, ry) = (axis.root[0].round() as u32, axis.root[1].round() as u32 - 3);
        assert!(pose.image.pixel(rx, ry)[0] > 0.5);
    }

    #[test]
    fn vertical_line_fit_has_no_division_by_zero() {
        let pts = [[5.0, 0.0], [5.0, 10.0], [5.0, 20.0]];
        let (c, d) = fit_line(&pts, &[1.0; 3]).unwrap();
        assert_eq!(c, [5.0, 10.0]);
        assert!(d[0].abs() < 1e-12 && (d[1].abs() - 1.0).abs() < 1e-12);
        let (root, tip) = trim_line(&pts, c, d);
        let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9;
        assert!(close(root, [5.0, 20.0]) && close(tip, [5.0, 0.0]), "{root:?} {tip:?}");
        assert!(fit_line(&[[1.0, 1.0]; 3], &[1.0; 3]).is_none());
    }

    #[test]
    fn root_weights_favour_the_bottom() {
        let w = root_weights(&[[0.0, 0.0], [0.0, 10.0]]);
        assert!((w[0] - 0.1).abs() < 1e-12 && (w[1] - 1.1).abs() < 1e-12);
        let m = ellipse_mask(100, 100, (50.0, 50.0), (10.0, 35.0), -15.0);
        let axis = flame_axis(&trace_contours(&m).contours[0], Weighting::Root).unwrap();
        assert!((axis.angle_deg + 15.0).abs() < 3.0, "{}", axis.angle_deg);
    }

    #[test]
    fn no_contours_pass_through_with_no_axis() {
        let img = Image::gray_from_fn(6, 4, |x, y| (x + y) as f32 / 10.0);
        let empty = Contours { width: 6, height: 4, contours: Vec::new() };
        for mode in [PoseMode::Rotate, PoseMode::CenterScale(0.8)] {
            let pose = pose_normalize(&img, &empty, mode, Weighting::Uniform);
            assert_eq!(pose, Pose { image: img.clone(), axis: None });
        }
    }

    #[test]
    fn center_scale_moves_the_flame_to_the_middle() {
        let m = ellipse_mask(100, 100, (25.0, 30.0), (6.0, 12.0), 0.0);
        let c = trace_contours(&m);
        let pose = pose_normalize(&mask_image(&m), &c, PoseMode::CenterScale(0.5), Weighting::Uniform);
        let out = Mask::from_vec(100, 100, pose.image.data().iter().map(|&v| if v >= 0.5 { 255 } else { 0 }).collect()).unwrap();
        let b = flame_bounds(&trace_contours(&out)).unwrap();
        assert!(((b[0] + b[2]) / 2.0 - 49.5).abs() <= 1.0 && ((b[1] + b[3]) / 2.0 - 49.5).abs() <= 1.0, "{b:?}");
        assert!(((b[3] - b[1]) - 50.0).abs() <= 2.0, "{b:?}");
    }

    #[test]
    fn gray_and_rgba_both_warp() {
        let m = ellipse_mask(40, 40, (20.0, 20.0), (4.0, 12.0), 30.0);
        let c = trace_contours(&m);
        let rgba = mask_image(&m).to_rgba();
        let pose = pose_normalize(&rgba, &c, PoseMode::Rotate, Weighting::Uniform);
        assert_eq!(pose.image.channels(), Channels::Rgba);
    }
}

#[cfg(test)]
mod proptests {
    use super::tests::ellipse_mask;
    use super::*;
    use crate::preprocess::contours::trace_contours;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn an_upright_flame_is_left_unchanged(cx in 20u32..44, cy in 25u32..39, rx in 3u32..10, extra in 3u32..14, root in proptest::bool::ANY) {
            let m = ellipse_mask(64, 64, (f64::from(cx), f64::from(cy)), (f64::from(rx), f64::from(rx + extra)), 0.0);
            let img = crate::convert::mask_to_image(&m);
            let weighting = if root { Weighting::Root } else { Weighting::Uniform };
            let pose = pose_normalize(&img, &trace_contours(&m), PoseMode::Rotate, weighting);
            let axis = pose.axis.unwrap();
            prop_assert!(axis.angle_deg.abs() < 1e-6, "angle {}", axis.angle_deg);
            let diff = pose.image.data().iter().zip(img.data()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            prop_assert!(diff < 1e-6, "max difference {diff}");
        }
    }
}
