//! Perry's long exposure drawn as one continuous swept shape per flame (Perry 1994 §3.2.2).
//!
//! A flame is the trajectory of one fuzzy particle photographed with the shutter open: the film
//! sums the particle's colour along its whole path. Drawing the trajectory's steps as separate
//! fuzzy N-gons samples that path at `steps` points, and where neighbouring particles overlap
//! unevenly the sum ripples once per step: horizontal bands, like a stack of coins. Here the path
//! is swept instead: a camera-facing strip through the steps whose cross-section is the
//! particle's (centre colour on the path, rim colour at the particle's extent across it), capped
//! at both ends by half of the end particle's N-gon, with the colour scaled by the exposure the
//! overlapping particles would have summed to on average (the particle's extent along the path
//! over the step length). The look then depends on the step count only through how finely the
//! path is sampled.
//!
//! Written here rather than taken from a library: this is a camera-dependent mesh built per
//! frame from the particles; the rasterizer (`pyrograph_render`) draws its body as a grid strip
//! (`DrawList::strip`: binned per band, not per triangle) and its caps as a small mesh.

use glam::{Vec2, Vec3, Vec4};
use pyrograph_render::{Blend, Camera, DrawList, Particle, Vertex, View};

pyrograph_core::choice! {
    /// How `particles.render_flames` draws a flame's trajectory.
    pub enum Exposure {
        /// One continuous swept shape along each flame's trajectory (the long exposure's limit).
        Continuous = "continuous",
        /// Every trajectory step as its own fuzzy N-gon (Perry's discrete particles; shows a band per step).
        Steps = "steps",
    }
}

/// Vertices across the swept shape at every step.
const ACROSS: u32 = 5;
/// Below this distance (pixels) from the path to the rim, the profile's inner vertices are left out.
const INNER_MIN_PIXELS: f32 = 12.0;
/// Most spline samples per trajectory step.
const MAX_SUBDIVISIONS: usize = 4;
/// Where the inner vertices sit, as a fraction of the half-width.
const INNER: f32 = 0.4;
/// The long exposure's profile across the path at [`INNER`]: a cone of half extents (X, Y)
/// swept along y sums, at x = ρX, to Y·g(ρ) with g(ρ) = √(1−ρ²) − ρ²·ln((1 + √(1−ρ²))/ρ), a
/// rounded top; g(0.4) = 0.666. With a vertex there the strip follows that profile instead of
/// a cone's crease along the path.
const INNER_WEIGHT: f32 = 0.666;

/// Reused buffers for [`swept_flame`].
#[derive(Default)]
pub struct SweptScratch {
    verts: Vec<Vertex>,
    tris: Vec<[u32; 3]>,
    frames: Vec<StepFrame>,
    /// The caps' vertices (copies of the end samples' path and rim vertices, then their rims).
    cap_verts: Vec<Vertex>,
}

/// One step of the path in the camera's billboard plane.
#[derive(Clone, Copy)]
struct StepFrame {
    /// The path: the particle's world position.
    at: Vec3,
    /// Colour of the path vertex (exposed).
    centre: Vec4,
    /// Colour of the rim vertices (exposed).
    rim: Vec4,
    /// World offset from the path to the rim, across the path.
    across: Vec3,
    /// World offset from the end particle's centre to its cap tip, along the path.
    along: Vec3,
    /// Whether the path moves on screen at this step (its tangent is its own).
    moved: bool,
}

/// The colours the path and rim vertices of one step carry so that one layer of the swept shape
/// adds what `exposure` overlapping layers of straight colours `centre` and `rim` would.
fn exposed(centre: [f32; 4], rim: [f32; 4], exposure: f32, blend: Blend) -> [[f32; 4]; 2] {
    match blend {
        Blend::Additive => {
            // Additive adds rgb·a (and a, clamped to 1). rgb·a·exposure is kept with a ≤ 1 by
            // scaling rgb up and a down by one factor shared across the step, so that rgb and a,
            // interpolated separately, still multiply to the particles' linear falloff.
            let k = |c: [f32; 4]| c[3].clamp(0.0, 1.0) * exposure;
            let s = k(centre).max(k(rim)).max(1.0);
            [centre, rim].map(|c| [c[0] * s, c[1] * s, c[2] * s, k(c) / s])
        }
        // `exposure` layers "over" each other let 1 − (1 − a)^exposure through.
        Blend::Over => [centre, rim].map(|c| [c[0], c[1], c[2], 1.0 - (1.0 - c[3].clamp(0.0, 1.0)).powf(exposure)]),
        Blend::Opaque => [centre, rim],
    }
}

/// Appends one flame — `path`, the particles of one trajectory in step order — to `list` as a
/// swept shape (see the module docs). A path that does not move on screen (every step at one
/// point) is drawn as its particles, which is what a long exposure of a still particle is.
pub fn swept_flame(list: &mut DrawList, path: &[Particle], sides: u32, blend: Blend, scratch: &mut SweptScratch) {
    let n = path.len();
    if n < 2 || path.iter().any(|q| !Vec3::from_array(q.position).is_finite() || !Vec2::from_array(q.size).is_finite()) {
        draw_steps(list, path, sides, blend);
        return;
    }
    let camera = *list.view().camera();
    let frames = &mut scratch.frames;
    let moved = step_frames(&camera, path, blend, frames);
    if !moved {
        draw_steps(list, path, sides, blend);
        return;
    }
    // Steps before the path first moves (particles stacked at its start) take its first
    // direction, not the default.
    if let Some(first) = frames.iter().position(|f| f.moved) {
        let (across, along) = (frames[first].across.normalize_or_zero(), frames[first].along.normalize_or_zero());
        for f in &mut frames[..first] {
            let (w, r) = (f.across.length(), f.along.length());
            (f.across, f.along) = (across * w, along * r);
        }
    }
    let (verts, tris) = (&mut scratch.verts, &mut scratch.tris);
    verts.clear();
    tris.clear();
    // Between steps the strip follows a Catmull-Rom spline through them (position, width and
    // colours): straight segments would put a kink, and so a faint band, at every step.
    let detail = Detail::of(list.view(), frames, sides);
    let mut samples = 0u32;
    for k in 0..n {
        let parts = if k + 1 == n { 1 } else { detail.subdivisions };
        for j in 0..parts {
            let f = if j == 0 { frames[k] } else { spline(frames, k, j as f32 / parts as f32) };
            let [centre, rim] = [f.centre, f.rim].map(|c| c.max(Vec4::ZERO).min(Vec4::new(f32::MAX, f32::MAX, f32::MAX, 1.0)));
            let inner = (rim + (centre - rim) * INNER_WEIGHT).to_array();
            let [centre, rim] = [centre.to_array(), rim.to_array()];
            verts.push(Vertex::new(f.at + f.across, rim));
            if detail.across == 5 {
                verts.push(Vertex::new(f.at + f.across * INNER, inner));
            }
            verts.push(Vertex::new(f.at, centre));
            if detail.across == 5 {
                verts.push(Vertex::new(f.at - f.across * INNER, inner));
            }
            verts.push(Vertex::new(f.at - f.across, rim));
            samples += 1;
        }
    }
    // `across` vertices per sample across the path: rim, (inner,) path, (inner,) rim.
    let across = detail.across;
    list.strip(verts, across, blend);
    // Caps: half of the end particle's N-gon, facing away from the path, around copies of the
    // end sample's path and rim vertices.
    let (body, caps) = (samples, &mut scratch.cap_verts);
    caps.clear();
    for (k, sample, outward) in [(0usize, 0u32, -1.0f32), (n - 1, body - 1, 1.0)] {
        let f = frames[k];
        if f.along.length_squared() <= 0.0 {
            continue;
        }
        let rim = f.rim.max(Vec4::ZERO).min(Vec4::new(f32::MAX, f32::MAX, f32::MAX, 1.0)).to_array();
        let row = &verts[(across * sample) as usize..(across * (sample + 1)) as usize];
        let centre = caps.len() as u32;
        caps.extend([row[(across / 2) as usize], row[0]]);
        for j in 1..detail.cap_sides {
            let theta = std::f32::consts::PI * j as f32 / detail.cap_sides as f32;
            let p = f.at + f.across * theta.cos() + f.along * (outward * theta.sin());
            caps.push(Vertex::new(p, rim));
            let v = caps.len() as u32 - 1;
            tris.push([centre, v - 1, v]);
        }
        caps.push(row[(across - 1) as usize]);
        let v = caps.len() as u32 - 1;
        tris.push([centre, v - 1, v]);
    }
    list.mesh(caps, tris, None, blend);
}

/// Fills `frames` with the path in the billboard plane of each step (tangent, across and along
/// offsets, exposed colours); returns whether the path moves on screen at all.
fn step_frames(camera: &Camera, path: &[Particle], blend: Blend, frames: &mut Vec<StepFrame>) -> bool {
    let n = path.len();
    let pos = |k: usize| Vec3::from_array(path[k].position);
    frames.clear();
    let mut last_tangent = Vec2::Y;
    let mut moved = false;
    for (k, q) in path.iter().enumerate() {
        let (r, u) = camera.billboard_axes(pos(k));
        let plane = |d: Vec3| Vec2::new(d.dot(r), d.dot(u));
        let before = if k > 0 { plane(pos(k) - pos(k - 1)) } else { Vec2::ZERO };
        let after = if k + 1 < n { plane(pos(k + 1) - pos(k)) } else { Vec2::ZERO };
        let size = Vec2::from_array(q.size).abs();
        let scale = size.max_element().max(1e-12);
        let chord = before + after;
        let step_moved = chord.length() > 1e-6 * scale;
        let tangent = if step_moved { chord.normalize() } else { last_tangent };
        moved |= step_moved;
        last_tangent = tangent;
        let normal = Vec2::new(-tangent.y, tangent.x);
        // The particle's ellipse measured across and along the path.
        let width = (size * normal).length();
        let reach = (size * tangent).length();
        let step = match (k > 0, k + 1 < n) {
            (true, true) => 0.5 * (before.length() + after.length()),
            (true, false) => before.length(),
            _ => after.length(),
        };
        // A cone of half-extent `reach` integrates to `reach` along the path; particles every
        // `step` sum to `reach / step` on average, never more than all of them at once.
        let mut exposure = if step > 0.0 { (reach / step).min(n as f32) } else { coincident(path, k) as f32 };
        if k == 0 || k + 1 == n {
            // At an end of the path only the particles on one side overlap: about half as many,
            // plus the end particle itself.
            exposure = (0.5 * (exposure + 1.0)).min(exposure);
        }
        let world = |v: Vec2| r * v.x + u * v.y;
        let [centre, rim] = exposed(q.center, q.edge, exposure, blend).map(Vec4::from_array);
        frames.push(StepFrame {
            at: pos(k),
            centre,
            rim,
            across: world(normal) * width,
            along: world(tangent) * reach,
            moved: step_moved,
        });
    }
    moved
}

/// How finely a flame is drawn, from its size on screen: a far flame a few pixels wide needs
/// neither spline samples between its steps, nor the inner vertices of the profile, nor round
/// caps of many sides (level of detail, as the fans of discrete particles never needed).
struct Detail {
    /// Spline samples per step: a sample at most ~3 pixels from the next, at most [`MAX_SUBDIVISIONS`].
    subdivisions: usize,
    /// Vertices across: 5 when the rim lies more than [`INNER_MIN_PIXELS`] from the path, else 3.
    across: u32,
    /// Triangles of a half N-gon cap: the particle's `sides / 2`, fewer for caps a few pixels across.
    cap_sides: u32,
}

impl Detail {
    fn of(view: &View, frames: &[StepFrame], sides: u32) -> Detail {
        let fine = Detail { subdivisions: MAX_SUBDIVISIONS, across: ACROSS, cap_sides: (sides / 2).max(1) };
        let (mut step_px, mut rim_px) = (0.0f32, 0.0f32);
        let mut prev: Option<Vec2> = None;
        for f in frames {
            let (Some(p), Some(r)) = (view.project(f.at), view.project(f.at + f.across)) else { return fine };
            let p = p.truncate();
            if let Some(q) = prev {
                step_px = step_px.max((p - q).length());
            }
            rim_px = rim_px.max((r.truncate() - p).length());
            prev = Some(p);
        }
        Detail {
            subdivisions: ((step_px / 3.0).ceil() as usize).clamp(1, MAX_SUBDIVISIONS),
            across: if rim_px > INNER_MIN_PIXELS { ACROSS } else { 3 },
            // Rim segments of about 4 pixels along a half circle of radius `rim_px`.
            cap_sides: ((std::f32::consts::PI * rim_px / 4.0).ceil() as u32).clamp(2, fine.cap_sides.max(2)),
        }
    }
}

/// The Catmull-Rom spline through `frames` between step `k` and `k + 1`, at `t` in 0..1.
fn spline(frames: &[StepFrame], k: usize, t: f32) -> StepFrame {
    let last = frames.len() - 1;
    let [p0, p1, p2, p3] = [k.saturating_sub(1), k, (k + 1).min(last), (k + 2).min(last)].map(|i| &frames[i]);
    let (t2, t3) = (t * t, t * t * t);
    let w = [-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0, -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2];
    StepFrame {
        at: p0.at * w[0] + p1.at * w[1] + p2.at * w[2] + p3.at * w[3],
        centre: p0.centre * w[0] + p1.centre * w[1] + p2.centre * w[2] + p3.centre * w[3],
        rim: p0.rim * w[0] + p1.rim * w[1] + p2.rim * w[2] + p3.rim * w[3],
        across: p0.across * w[0] + p1.across * w[1] + p2.across * w[2] + p3.across * w[3],
        along: p1.along,
        moved: true,
    }
}

/// How many particles of `path` sit exactly where particle `k` does (itself included).
fn coincident(path: &[Particle], k: usize) -> usize {
    path.iter().filter(|q| q.position == path[k].position).count()
}

/// Every particle of `path` as its own fuzzy N-gon.
pub fn draw_steps(list: &mut DrawList, path: &[Particle], sides: u32, blend: Blend) {
    for q in path {
        list.particle(Vec3::from_array(q.position), Vec2::from_array(q.size), sides, q.center, q.edge, blend);
    }
}

/// The index ranges of `particles` that are one trajectory each (runs of one group).
pub fn trails(particles: &[Particle]) -> Vec<std::ops::Range<usize>> {
    let mut runs = Vec::new();
    let mut start = 0;
    for k in 1..=particles.len() {
        if k == particles.len() || particles[k].group != particles[start].group {
            if k > start {
                runs.push(start..k);
            }
            start = k;
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flame::{FlameParams, Root, simulate_frame};
    use crate::render::render_particles;
    use crate::types::WindField;
    use pyrograph_render::{Camera, Particles};

    fn view() -> View {
        let cam = Camera::new(Vec3::new(0.0, 1.5, 6.0), Vec3::new(0.0, 1.5, 0.0), Vec3::Y, 40.0, 0.1, 100.0).unwrap();
        View::new(cam, 160, 240).unwrap()
    }

    fn candle() -> Particles {
        let roots = [Root { position: Vec3::ZERO, direction: Vec3::Y }];
        simulate_frame(&roots, &WindField::default(), &FlameParams::default(), 0).unwrap()
    }

    /// Luminance of the flame's centre column, top to bottom, and the image's total.
    fn profile(exposure: Exposure, flame: &Particles) -> (Vec<f32>, f32) {
        let img = render_particles(&view(), flame, exposure, Blend::Additive, [0.0, 0.0, 0.0, 1.0], None, &Particles::default());
        let lum = |p: &[f32]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        let column = (0..240).map(|y| lum(img.pixel(80, y))).collect();
        let total = img.data().chunks_exact(4).map(lum).sum();
        (column, total)
    }

    /// The largest second difference of the lit part of `p`: a ripple per step shows up here.
    fn roughness(p: &[f32]) -> f32 {
        p.windows(3)
            .filter(|w| w.iter().all(|&v| v > 0.05 && v < 0.95))
            .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
            .fold(0.0, f32::max)
    }

    #[test]
    fn the_swept_flame_is_smooth_where_the_steps_ripple_and_keeps_their_light() {
        let flame = candle();
        let (swept, swept_total) = profile(Exposure::Continuous, &flame);
        let (steps, steps_total) = profile(Exposure::Steps, &flame);
        let (rs, rd) = (roughness(&swept), roughness(&steps));
        assert!(rs < 0.25 * rd, "swept roughness {rs} against the steps' {rd}");
        let ratio = swept_total / steps_total;
        assert!((0.75..1.33).contains(&ratio), "total light {swept_total} against the steps' {steps_total}");
    }

    #[test]
    fn far_flames_and_over_blending_keep_the_steps_light() {
        // Far away the strip has 3 vertices across and few-sided caps; "over" uses its own exposure.
        let far = View::new(
            Camera::new(Vec3::new(0.0, 1.5, 60.0), Vec3::new(0.0, 1.5, 0.0), Vec3::Y, 40.0, 0.1, 100.0).unwrap(),
            160,
            240,
        )
        .unwrap();
        let flame = candle();
        for (view, blend) in [(&far, Blend::Additive), (&view(), Blend::Over), (&far, Blend::Over)] {
            let total = |exposure| {
                let img = render_particles(view, &flame, exposure, blend, [0.0, 0.0, 0.0, 1.0], None, &Particles::default());
                assert!(img.data().iter().all(|v| v.is_finite()));
                img.data().chunks_exact(4).map(|p| p[0] + p[1] + p[2]).sum::<f32>()
            };
            let (swept, steps) = (total(Exposure::Continuous), total(Exposure::Steps));
            assert!(steps > 0.0 && (0.6..1.5).contains(&(swept / steps)), "{blend:?}: {swept} against {steps}");
        }
    }

    #[test]
    fn a_still_particle_is_drawn_as_its_steps() {
        let mut flame = candle();
        let first = flame.particles[0].position;
        flame.particles.iter_mut().for_each(|q| q.position = first);
        let (a, _) = profile(Exposure::Continuous, &flame);
        let (b, _) = profile(Exposure::Steps, &flame);
        assert_eq!(a, b);
    }

    #[test]
    fn trails_split_at_group_changes() {
        let q = |group| Particle { group, ..Particle::default() };
        assert_eq!(trails(&[q(0), q(0), q(1), q(2), q(2), q(2)]), vec![0..2, 2..3, 3..6]);
        assert!(trails(&[]).is_empty());
    }
}
