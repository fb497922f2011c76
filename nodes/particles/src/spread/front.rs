//! The fire front (Perry 1994 §3.3–3.4): rings of control points moving over a [`Surface`] at the
//! speed of eq. 3.4, the double-burn test of Figure 3-9 over a grid of boundary segments, point
//! insertion and thinning, and the flame roots and char marks the front leaves behind.

use std::sync::Arc;

use glam::{Quat, Vec3};
use pyrograph_core::declare::AnimError;
use pyrograph_core::port;
use rayon::prelude::*;

use super::spread_params::SpreadParams;
use super::surface::{Chord, Surface, segment_distance};
use crate::flame::unit_random;
use crate::types::{CharMark, FlameRoot, SpreadState, WindField};
use crate::wind::WindSampler;

/// Where and when a fire starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ignition {
    /// Face (triangle) index.
    pub face: u32,
    /// Barycentric coordinates in the face (normalized on use).
    pub bary: [f32; 3],
    /// Simulation time (seconds) at which it ignites.
    pub time: f32,
}

/// The external wind the spread sees, `u∞(p) = −k_g g + w_L(p)` (§3.3.1: gravity-induced
/// convection plus the large-scale wind; the small-scale noise only shapes flames).
pub fn spread_wind(field: &WindField) -> impl Fn(Vec3) -> Vec3 + Sync + Send + use<> {
    let sampler = WindSampler::new(field);
    let convection = -Vec3::from_array(field.gravity) * field.k_g;
    move |p| convection + sampler.large(p)
}

/// A point's proposed move: where it would be, whether it hit a boundary edge, and how far it
/// moved; `None` for an extinguished point.
type Move = Option<(ControlPoint, bool, f32)>;

/// One spread control point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlPoint {
    /// World position (on the surface).
    pub position: Vec3,
    /// Face it lies on.
    pub face: u32,
    /// Unit heading in the face plane.
    pub heading: Vec3,
    /// Distance travelled since the last flame drop.
    pub since_drop: f32,
    /// Still moving.
    pub alive: bool,
}

/// A spread simulation: boundary loops, live flame roots, char marks.
#[derive(Clone, Debug)]
pub struct Spread {
    surface: Arc<Surface>,
    params: SpreadParams,
    /// The curvature distance in use: `d_t`, or 0 with `curvature` off.
    d_t: f32,
    /// The flame lifetime l_f in seconds.
    lifetime: f32,
    /// The global time scale K in use: the constant, or the animated K at the current step.
    k: f32,
    pending: Vec<Ignition>,
    loops: Vec<Vec<ControlPoint>>,
    roots: Vec<FlameRoot>,
    chars: Vec<CharMark>,
    extinguished: Vec<[f32; 3]>,
    time: f32,
    dropped: u64,
}

/// Why a spread cannot start. The node maps each to the port it is about.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpreadError {
    /// A parameter of [`SpreadParams`] outside what the spread can run with.
    #[error("{param}: {message}")]
    Param {
        /// The parameter's name (its port).
        param: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// An ignition that is not a point of the surface.
    #[error("{0}")]
    Ignition(String),
}

/// A [`SpreadError::Param`] about `param`.
fn param_error(param: &'static str, message: impl Into<String>) -> SpreadError {
    SpreadError::Param { param, message: message.into() }
}

impl SpreadParams {
    /// Checks spread parameters no port range can (`fps` converts the lifetime from frames to
    /// seconds); errors name the parameter. Gives the curvature distance in use (0 with `curvature`
    /// off) and the lifetime in seconds.
    pub(crate) fn validate(&self, fps: f32) -> Result<(f32, f32), SpreadError> {
        let p = self;
        let d_t = if p.curvature { p.d_t } else { 0.0 };
        let lifetime = p.lifetime as f32 / fps;
        let port_k = port!(SpreadParams, K);
        let (port_s, port_d) = (port!(SpreadParams, d_s), port!(SpreadParams, d_d));
        for (name, v) in [
            (port!(SpreadParams, q_o), p.q_o),
            (port!(SpreadParams, q_c), p.q_c),
            (port_k, *p.K.value()),
            (port!(SpreadParams, d_t), d_t),
            (port_s, p.d_s),
            (port_d, p.d_d),
            (port!(SpreadParams, lifetime), lifetime),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(param_error(name, format!("must be a finite number ≥ 0, got {v}")));
            }
        }
        if *p.K.value() <= 0.0 {
            return Err(param_error(port_k, "the global time scale K must be positive"));
        }
        for (name, v) in [(port_s, p.d_s), (port_d, p.d_d)] {
            if v <= 0.0 {
                return Err(param_error(name, "must be positive"));
            }
        }
        if p.points < 3 {
            return Err(param_error(
                port!(SpreadParams, points),
                format!("an ignition ring needs at least 3 points (Perry used ≥ 8), got {}", p.points),
            ));
        }
        Ok((d_t, lifetime))
    }
}

impl Spread {
    /// A spread over `surface` that will ignite at each of `ignitions` (at its time); `fps`
    /// converts the flame lifetime l_f from frames to seconds.
    pub fn new(surface: Arc<Surface>, ignitions: Vec<Ignition>, params: SpreadParams, fps: f32) -> Result<Spread, SpreadError> {
        let (d_t, lifetime) = params.validate(fps)?;
        for (k, ig) in ignitions.iter().enumerate() {
            if ig.face as usize >= surface.len() {
                return Err(SpreadError::Ignition(format!(
                    "ignition {}: face {} is past the mesh's {} faces",
                    k + 1,
                    ig.face,
                    surface.len()
                )));
            }
            if ig.bary.iter().any(|b| !b.is_finite() || *b < 0.0) || ig.bary.iter().sum::<f32>() <= 0.0 {
                return Err(SpreadError::Ignition(format!(
                    "ignition {}: barycentric coordinates {:?} are not a point of the face (need ≥ 0, not all 0)",
                    k + 1,
                    ig.bary
                )));
            }
        }
        let mut pending = ignitions;
        pending.sort_by(|a, b| b.time.total_cmp(&a.time));
        let k = *params.K.value();
        let mut s = Spread {
            surface,
            params,
            d_t,
            lifetime,
            k,
            pending,
            loops: Vec::new(),
            roots: Vec::new(),
            chars: Vec::new(),
            extinguished: Vec::new(),
            time: 0.0,
            dropped: 0,
        };
        s.ignite_due();
        Ok(s)
    }

    fn ignite_due(&mut self) {
        while self.pending.last().is_some_and(|ig| ig.time <= self.time + 1e-6) {
            let Some(ig) = self.pending.pop() else { break };
            let p = self.surface.point(ig.face, ig.bary);
            let f = &self.surface.faces[ig.face as usize];
            let u = (f.v[1] - f.v[0]).normalize_or_zero();
            let v = f.n.cross(u);
            let n = self.params.points;
            let ring = (0..n)
                .map(|k| {
                    let th = std::f32::consts::TAU * k as f32 / n as f32;
                    ControlPoint {
                        position: p,
                        face: ig.face,
                        heading: u * th.cos() + v * th.sin(),
                        since_drop: 0.0,
                        alive: true,
                    }
                })
                .collect();
            self.loops.push(ring);
        }
    }

    /// Simulation time in seconds.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// The boundary loops (counter-clockwise seen from outside, burnt region on the left).
    pub fn loops(&self) -> &[Vec<ControlPoint>] {
        &self.loops
    }

    /// Control points in all loops.
    pub fn point_count(&self) -> usize {
        self.loops.iter().map(Vec::len).sum()
    }

    /// Flame roots dropped so far (live or dead).
    pub fn flames_dropped(&self) -> u64 {
        self.dropped
    }

    /// Approximate memory held.
    pub fn bytes(&self) -> usize {
        self.point_count() * std::mem::size_of::<ControlPoint>()
            + self.roots.len() * std::mem::size_of::<FlameRoot>()
            + self.chars.len() * std::mem::size_of::<CharMark>()
            + self.extinguished.len() * 12
    }

    /// Spread speed at a point heading `h` on `face` at `p` (eq. 3.4).
    fn speed(&self, face: u32, p: Vec3, h: Vec3, wind: Vec3) -> f32 {
        let n = self.surface.faces[face as usize].n;
        let tangential = (wind - n * wind.dot(n)).normalize_or_zero();
        let a_c = h.dot(tangential).max(0.0);
        let q = self.params.q_o + a_c * self.params.q_c;
        self.surface.curvature(face, p, self.d_t) * q / self.k
    }

    /// Samples the animated parameters (K) at `frame` (fractional for a sub-step) of a clip at
    /// `fps`, for the steps that follow. Errors name the port and the frame.
    pub fn follow(&mut self, frame: f64, fps: f64) -> Result<(), AnimError> {
        if self.params.K.is_animated() {
            self.k = self.params.K.at(frame, fps)?;
        }
        Ok(())
    }

    /// Advances the spread by `dt` seconds in the wind `wind(p)` (the external wind u∞).
    pub fn step(&mut self, dt: f32, wind: &(dyn Fn(Vec3) -> Vec3 + Sync)) {
        let dt = dt.max(0.0);
        self.age_roots(dt);
        let moves = self.propose_moves(dt, wind);
        let blocked = if self.params.double_burn { self.blocked_moves(&moves) } else { Vec::new() };
        self.apply_moves(&moves, &blocked);
        self.thin_dead_runs();
        self.insert_points();
        self.time += dt;
        self.ignite_due();
    }

    /// Flame roots age; the dead leave char (§3.4.1).
    fn age_roots(&mut self, dt: f32) {
        for c in &mut self.chars {
            c.age += dt;
        }
        let mut live = Vec::with_capacity(self.roots.len());
        for mut r in std::mem::take(&mut self.roots) {
            r.age += dt;
            if r.age >= r.lifetime {
                self.chars.push(CharMark { position: r.position, normal: r.direction, age: r.age - r.lifetime });
            } else {
                live.push(r);
            }
        }
        self.roots = live;
    }

    /// Proposed moves, in parallel (each point moves without knowledge of the others, §3.4.2):
    /// per loop and point, `None` for an extinguished point.
    fn propose_moves(&self, dt: f32, wind: &(dyn Fn(Vec3) -> Vec3 + Sync)) -> Vec<Vec<Move>> {
        self.loops
            .par_iter()
            .map(|ring| {
                ring.par_iter()
                    .map(|cp| {
                        if !cp.alive {
                            return None;
                        }
                        let dist = self.speed(cp.face, cp.position, cp.heading, wind(cp.position)) * dt;
                        if dist <= 0.0 {
                            return Some((*cp, false, 0.0));
                        }
                        let (face, position, heading, hit) = self.surface.advance(cp.face, cp.position, cp.heading, dist);
                        let moved = (position - cp.position).length();
                        Some((ControlPoint { position, face, heading, ..*cp }, hit, moved))
                    })
                    .collect()
            })
            .collect()
    }

    /// Double-burn prevention against the boundary at t − 1 (Figure 3-9): per loop and point,
    /// whether its move is blocked.
    fn blocked_moves(&self, moves: &[Vec<Move>]) -> Vec<Vec<bool>> {
        // Points move at once, so the test also runs against the proposed boundary at t:
        // two fronts closing in by less than two steps would otherwise pass through each other.
        let proposed: Vec<Vec<ControlPoint>> = self
            .loops
            .iter()
            .zip(moves)
            .map(|(ring, m)| ring.iter().zip(m).map(|(cp, mv)| mv.map_or(*cp, |(np, _, _)| np)).collect())
            .collect();
        let cell = self.params.d_s.max(1e-6) * 2.0;
        let surface = &*self.surface;
        let (old_grid, new_grid) =
            rayon::join(|| SegmentGrid::new(surface, &self.loops, cell), || SegmentGrid::new(surface, &proposed, cell));
        let tol = 0.02 * self.params.d_s;
        self.loops
            .par_iter()
            .enumerate()
            .map(|(li, ring)| {
                (0..ring.len())
                    .into_par_iter()
                    .map(|j| match &moves[li][j] {
                        Some((np, _, moved)) if *moved > 0.0 => {
                            let n = ring.len();
                            let path = surface.chord(ring[j].face, ring[j].position, np.face, np.position);
                            // The segment test skips the point's own two segments: check them here.
                            [(j + n - 1) % n, (j + 1) % n]
                                .into_iter()
                                .any(|k| met_neighbour(surface, (&ring[j], np), (&ring[k], &proposed[li][k]), tol))
                                || old_grid.crosses(li, j, &path, tol)
                                || new_grid.crosses(li, j, &path, tol)
                        }
                        _ => false,
                    })
                    .collect()
            })
            .collect()
    }

    /// Moves every point as proposed unless `blocked` (then it goes out), dropping flame roots
    /// along the way; a point that hit a boundary edge goes out where it stopped.
    fn apply_moves(&mut self, moves: &[Vec<Move>], blocked: &[Vec<bool>]) {
        let dd = self.params.d_d;
        for (li, ring) in self.loops.iter_mut().enumerate() {
            for (j, cp) in ring.iter_mut().enumerate() {
                let Some((np, hit, moved)) = moves[li][j] else { continue };
                if blocked.get(li).and_then(|b| b.get(j)).copied().unwrap_or(false) {
                    cp.alive = false;
                    self.extinguished.push(cp.position.to_array());
                    continue;
                }
                let old = cp.position;
                *cp = np;
                cp.since_drop += moved;
                // Drop a flame root every d_d travelled (§3.4).
                let drops = (cp.since_drop / dd).floor() as u32;
                if drops > 0 {
                    let n = self.surface.faces[cp.face as usize].n;
                    for k in 0..drops {
                        let back = (cp.since_drop - dd * (k + 1) as f32).max(0.0);
                        let frac = if moved > 0.0 { 1.0 - back / moved } else { 1.0 };
                        let position = old.lerp(cp.position, frac.clamp(0.0, 1.0));
                        let id = self.dropped as u32;
                        let jitter = self.params.lifetime_jitter.clamp(0.0, 1.0)
                            * (2.0 * unit_random(self.params.seed, id as usize, 21) - 1.0);
                        self.roots.push(FlameRoot {
                            position: position.to_array(),
                            direction: n.to_array(),
                            age: 0.0,
                            lifetime: (self.lifetime * (1.0 + jitter)).max(1e-3),
                            id,
                        });
                        self.dropped += 1;
                    }
                    cp.since_drop -= dd * drops as f32;
                }
                if hit {
                    cp.alive = false;
                    self.extinguished.push(cp.position.to_array());
                }
            }
        }
    }

    /// Drops an extinguished point between extinguished neighbours when the boundary hardly
    /// changes: they are within `d_s` of each other (the tip of a slit where two fronts met,
    /// burnt on both sides), or within `2 d_s` with the point at most `d_s/4` off the line between
    /// them. The loop stays closed and a barrier for the double-burn test; without this every
    /// stopped front keeps its points forever.
    fn thin_dead_runs(&mut self) {
        let ds = self.params.d_s;
        for ring in &mut self.loops {
            let n = ring.len();
            if n <= 4 || ring.iter().all(|c| c.alive) {
                continue;
            }
            // Start at a live point when there is one: the first kept point is never dropped.
            let start = ring.iter().position(|c| c.alive).unwrap_or(0);
            let mut out: Vec<ControlPoint> = Vec::with_capacity(n);
            out.push(ring[start]);
            for k in 1..n {
                let (cp, next) = (ring[(start + k) % n], ring[(start + k + 1) % n]);
                let last = out[out.len() - 1];
                let span = (next.position - last.position).length();
                let off = segment_distance(cp.position, cp.position, last.position, next.position).1;
                let dead = !cp.alive && !last.alive && !next.alive;
                // Keep at least four points, so the loop stays a loop.
                let left = out.len() + (n - k);
                if dead && left > 4 && (span <= ds || (span <= 2.0 * ds && off <= 0.25 * ds)) {
                    continue;
                }
                out.push(cp);
            }
            *ring = out;
        }
    }

    /// Inserts a point between neighbours more than `d_s` apart (§3.3.2).
    fn insert_points(&mut self) {
        let mut total = self.point_count();
        let ds = self.params.d_s;
        let surface = self.surface.clone();
        for ring in &mut self.loops {
            let n = ring.len();
            if n < 2 {
                continue;
            }
            let mut out = Vec::with_capacity(n + n / 4);
            for j in 0..n {
                let (a, b) = (ring[j], ring[(j + 1) % n]);
                out.push(a);
                if total >= self.params.max_points || (!a.alive && !b.alive) {
                    continue;
                }
                let gap = b.position - a.position;
                let len = gap.length();
                if len <= ds {
                    continue;
                }
                let fa = &surface.faces[a.face as usize];
                let dir = (gap - fa.n * gap.dot(fa.n)).normalize_or_zero();
                if dir == Vec3::ZERO {
                    continue;
                }
                let (face, position, _, hit) = surface.advance(a.face, a.position, dir, len * 0.5);
                let fm = &surface.faces[face as usize];
                let tangent = b.position - a.position;
                let outward = (tangent - fm.n * tangent.dot(fm.n)).cross(fm.n).normalize_or_zero();
                // Between the live neighbours' headings, carried into this face, like the ignition
                // ring's own points: the gap's outward normal would drift sideways across the
                // neighbours wherever the speed depends on the heading (wind) and fold the front.
                let fb = &surface.faces[b.face as usize];
                let carried = |c: &ControlPoint, from: Vec3| {
                    if c.alive { Quat::from_rotation_arc(from, fm.n) * c.heading } else { Vec3::ZERO }
                };
                let h = carried(&a, fa.n) + carried(&b, fb.n);
                let mut heading = (h - fm.n * h.dot(fm.n)).normalize_or_zero();
                if heading == Vec3::ZERO {
                    heading = outward;
                }
                // A point heading into the burnt side cannot move the front (it would run along
                // a trail or die at once, every step): leave the gap open.
                if !hit && heading.dot(outward) < 0.0 {
                    continue;
                }
                let alive = !hit && heading != Vec3::ZERO;
                if !alive {
                    self.extinguished.push(position.to_array());
                }
                out.push(ControlPoint { position, face, heading, since_drop: (a.since_drop + b.since_drop) * 0.5, alive });
                total += 1;
            }
            *ring = out;
        }
    }

    /// The state as a value: closed boundary polylines, live roots, extinguished points, char.
    pub fn state(&self) -> SpreadState {
        SpreadState {
            time: self.time,
            boundaries: self.loops.iter().map(|r| r.iter().map(|c| c.position.to_array()).collect()).collect(),
            roots: self.roots.clone(),
            extinguished: self.extinguished.clone(),
            char_marks: self.chars.clone(),
            flames_dropped: self.dropped,
        }
    }
}

/// Whether point `a` (moving from `a.0` to `a.1`) has met its neighbour `b` (moving from `b.0`
/// to `b.1`), which Figure 3-9's test cannot see as it skips a point's own segments: the
/// segment between them turns over (one end crosses it forwards, the other backwards: two
/// fronts closing in on each other), or `a` ends up on it (it runs along its own boundary,
/// burning nothing, and would draw a needle of points behind it).
fn met_neighbour(surface: &Surface, a: (&ControlPoint, &ControlPoint), b: (&ControlPoint, &ControlPoint), tol: f32) -> bool {
    let before = surface.chord(a.0.face, a.0.position, b.0.face, b.0.position);
    let inside = |t: f32| t > 0.01 && t < 0.99;
    if before.meets(a.1.position, a.1.position, tol, inside) {
        return true;
    }
    let after = surface.chord(a.1.face, a.1.position, b.1.face, b.1.position);
    let out = |from: Vec3, to: Vec3, c: &ControlPoint, moved: Vec3| {
        (to - from).cross(surface.faces[c.face as usize].n).normalize_or_zero().dot(moved)
    };
    let da = out(before.a, before.mid, a.0, a.1.position - a.0.position);
    let db = out(before.mid, before.b, b.0, b.1.position - b.0.position);
    da.min(db) < -tol && da.max(db) > tol && before.pieces().into_iter().any(|(c, d)| after.meets(c, d, tol, inside))
}

/// A uniform hash grid of the boundary's segments (Figure 3-9's test without O(n²)).
struct SegmentGrid {
    cell: f32,
    /// Each loop's segments `j → j + 1` over the surface.
    segments: Vec<Vec<Chord>>,
    /// (cell key, loop, segment start index), sorted by key.
    entries: Vec<(u64, u32, u32)>,
}

fn cell_key(c: [i32; 3]) -> u64 {
    let h = (c[0] as u32 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (c[1] as u32 as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (c[2] as u32 as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^ (h >> 29)
}

impl SegmentGrid {
    fn cells(&self, c: &Chord, pad: f32, mut f: impl FnMut(u64)) {
        let lo = ((c.a.min(c.mid).min(c.b) - Vec3::splat(pad)) / self.cell).floor();
        let hi = ((c.a.max(c.mid).max(c.b) + Vec3::splat(pad)) / self.cell).floor();
        let span = hi - lo;
        if span.x > 64.0 || span.y > 64.0 || span.z > 64.0 {
            // A segment this long is degenerate input; test it against its end cells only.
            for p in [c.a, c.b] {
                let c = (p / self.cell).floor();
                f(cell_key([c.x as i32, c.y as i32, c.z as i32]));
            }
            return;
        }
        for x in lo.x as i32..=hi.x as i32 {
            for y in lo.y as i32..=hi.y as i32 {
                for z in lo.z as i32..=hi.z as i32 {
                    f(cell_key([x, y, z]));
                }
            }
        }
    }

    fn new(surface: &Surface, loops: &[Vec<ControlPoint>], cell: f32) -> SegmentGrid {
        let segments: Vec<Vec<Chord>> = loops
            .par_iter()
            .map(|ring| {
                let n = ring.len();
                (0..n)
                    .map(|j| {
                        let (p, q) = (ring[j], ring[(j + 1) % n]);
                        surface.chord(p.face, p.position, q.face, q.position)
                    })
                    .collect()
            })
            .collect();
        let mut g = SegmentGrid { cell, segments, entries: Vec::new() };
        let mut entries = Vec::new();
        for (li, ring) in g.segments.iter().enumerate() {
            for (j, seg) in ring.iter().enumerate() {
                g.cells(seg, 0.0, |k| entries.push((k, li as u32, j as u32)));
            }
        }
        entries.par_sort_unstable();
        entries.dedup();
        g.entries = entries;
        g
    }

    /// Whether the move `path` of point `j` of loop `li` meets a boundary segment not incident to it.
    fn crosses(&self, li: usize, j: usize, path: &Chord, tol: f32) -> bool {
        let n = self.segments[li].len();
        let prev = (j + n - 1) % n;
        let mut hit = false;
        self.cells(path, tol, |k| {
            if hit {
                return;
            }
            let start = self.entries.partition_point(|e| e.0 < k);
            for &(key, sl, sj) in &self.entries[start..] {
                if key != k {
                    break;
                }
                let (sl, sj) = (sl as usize, sj as usize);
                if sl == li && (sj == j || sj == prev) {
                    continue;
                }
                // Touching at the start of the move is not a crossing.
                if self.segments[sl][sj].pieces().into_iter().any(|(c, d)| path.meets(c, d, tol, |t| t > 0.01)) {
                    hit = true;
                    return;
                }
            }
        });
        hit
    }
}
