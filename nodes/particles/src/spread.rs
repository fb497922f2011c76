//! Perry's fire spread over polygon meshes (Perry 1994 §3.3–3.4) and the `particles.fire_spread`
//! node.
//!
//! The inception boundary is a counter-clockwise ring of spread control points per ignition
//! (burnt region on the left, seen from outside). Each point moves along its heading, in the
//! plane of its face, at the speed of eq. 3.4:
//!
//! `v_s = (1 + κ) · (A_o q_o + A_c q_c) / K`, with `A_o = 1`, `A_c = max(0, ĥ · û∞,face)`,
//!
//! where `û∞,face` is the normalized projection of the wind `u∞ = −k_g g + w_L` on the face and
//! `κ = (1 − d/d_t)·Θ/π` within `d_t` of an edge whose faces meet at the signed angle `Θ`
//! (positive on convex edges, negative on concave ones), else 0. Eq. 3.4 as printed multiplies by
//! the curvature coefficient, which would stop the spread on flat faces (Θ = 0); we apply it as a
//! relative change, which keeps the linear ramp to the edge and the preference for convex edges.
//! Speeds are in distance units per second. A point that would leave its face is split at the
//! edge and its heading rotated into the neighbour by the edge's pre-stored rotation (§3.3.2,
//! Figure 3-8); on a boundary edge it stops. Neighbours more than `d_s` apart get a new point
//! between them, placed by walking the surface and heading between its live neighbours' headings;
//! none is inserted that would head into the burnt side. With double-burn prevention on, a point
//! whose move (position at t−1 → t) meets another segment of the boundary at t−1 (or as proposed
//! at t) is not allowed to move and goes out (Figure 3-9), and so are two neighbours whose
//! segment turns over (they met) and a point that runs along its own segment. Segments and moves
//! bend where they cross an edge (Perry §4: geodesics, not chords). The test uses a uniform grid
//! of boundary segments, so a step is O(n) for n points. Runs of extinguished points are thinned
//! where that hardly changes the boundary, so stopped fronts do not pile up. Every point drops a
//! flame root each `d_d` it travels (§3.4): the face normal is the flame's initial direction, and
//! the root lives `l_f`; when it dies it leaves a char mark (§3.4.1).

use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use glam::{Quat, Vec3};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{
    CharMark, Clip, CookCtx, FlameRoot, FnNode, FrameSource, Inputs, Mesh, NO_NEIGHBOR, NodeDesc, NodeError, PortDesc, PortType,
    Registry, SpreadState, TimeDep, Value, WindField,
};
use rayon::prelude::*;

use crate::flame::unit_random;
use crate::wind::{WindSampler, validate_wind};

/// Adds `particles.fire_spread`.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(fire_spread_desc(), cook_fire_spread));
}

/// Parameters of the spread (Perry 1994 §3.3–3.4, Table 3.1).
#[derive(Clone, Debug, PartialEq)]
pub struct SpreadParams {
    /// Opposed-flow heat flux q_o (footnote 10: 0.09).
    pub q_o: f32,
    /// Concurrent-flow heat flux q_c (footnote 10: 0.13).
    pub q_c: f32,
    /// Global time scale K of eq. 3.4 (Table 3.1: 0.004 … 0.4).
    pub k: f32,
    /// Curvature distance d_t (Table 3.1: 0.01 … 0.5); 0 disables the curvature term.
    pub d_t: f32,
    /// Control point separation d_s (Table 3.1: 0.01 … 0.2).
    pub d_s: f32,
    /// Flame drop distance d_d (Table 3.1: 0.01 … 1.0).
    pub d_d: f32,
    /// Flame lifetime l_f in seconds.
    pub lifetime: f32,
    /// Random per-flame lifetime variation, 0..1.
    pub lifetime_jitter: f32,
    /// Control points of a new ignition ring (≥ 8, footnote 13).
    pub points: usize,
    /// No new points are inserted beyond this many.
    pub max_points: usize,
    /// Prevent double burning with the segment test of Figure 3-9.
    pub double_burn: bool,
    /// Seed of the per-flame variations.
    pub seed: u32,
}

impl Default for SpreadParams {
    fn default() -> Self {
        SpreadParams {
            q_o: 0.09,
            q_c: 0.13,
            k: 0.4,
            d_t: 0.05,
            d_s: 0.05,
            d_d: 0.05,
            lifetime: 2.0,
            lifetime_jitter: 0.3,
            points: 16,
            max_points: 200_000,
            double_burn: true,
            seed: 0,
        }
    }
}

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

/// Per-face geometry derived from a [`Mesh`] once.
#[derive(Clone, Debug)]
struct Face {
    v: [Vec3; 3],
    n: Vec3,
    /// Inward unit normals of the edges, in the face plane.
    inward: [Vec3; 3],
    neighbor: [u32; 3],
    rotation: [Quat; 3],
    /// Edge index in the neighbour that leads back here.
    back: [u8; 3],
    /// Signed curvature Θ/π of each edge (positive convex).
    kappa: [f32; 3],
}

/// A mesh prepared for spreading.
#[derive(Clone, Debug)]
pub struct Surface {
    faces: Vec<Face>,
}

impl Surface {
    /// Checks and prepares `mesh`; errors say what is wrong with it.
    pub fn new(mesh: &Mesh) -> Result<Surface, String> {
        let nt = mesh.triangles.len();
        if nt == 0 {
            return Err("the mesh has no faces".into());
        }
        if mesh.neighbors.len() != nt || mesh.normals.len() != nt {
            return Err(format!(
                "the mesh is inconsistent: {nt} triangles but {} normals and {} adjacency rows (load it with particles.mesh_load)",
                mesh.normals.len(),
                mesh.neighbors.len()
            ));
        }
        let np = mesh.positions.len();
        let mut faces = Vec::with_capacity(nt);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if tri.iter().any(|v| *v as usize >= np) {
                return Err(format!("triangle {t} refers to a vertex past the {np} positions"));
            }
            let v = tri.map(|i| Vec3::from_array(mesh.positions[i as usize]));
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            if n == Vec3::ZERO {
                return Err(format!("triangle {t} is degenerate (zero area)"));
            }
            let inward = std::array::from_fn(|e| n.cross(v[(e + 1) % 3] - v[e]).normalize_or_zero());
            let rotation = std::array::from_fn(|e| {
                mesh.edge_rotations.get(t).map_or_else(
                    || Quat::IDENTITY,
                    |r| {
                        let q = Quat::from_array(r[e]);
                        if q.is_finite() && q.length_squared() > 0.5 { q.normalize() } else { Quat::IDENTITY }
                    },
                )
            });
            faces.push(Face { v, n, inward, neighbor: mesh.neighbors[t], rotation, back: [0; 3], kappa: [0.0; 3] });
        }
        for t in 0..nt {
            for e in 0..3 {
                let g = faces[t].neighbor[e];
                if g == NO_NEIGHBOR {
                    continue;
                }
                if g as usize >= nt {
                    return Err(format!("triangle {t} has neighbour {g} past the {nt} triangles"));
                }
                let (a, b) = (mesh.triangles[t][e], mesh.triangles[t][(e + 1) % 3]);
                let gt = mesh.triangles[g as usize];
                let back = (0..3).find(|&k| gt[k] == b && gt[(k + 1) % 3] == a);
                let Some(back) = back else {
                    return Err(format!("triangles {t} and {g} are listed as neighbours but do not share edge {a}–{b}"));
                };
                let (nf, ng) = (faces[t].n, faces[g as usize].n);
                let axis = (faces[t].v[(e + 1) % 3] - faces[t].v[e]).normalize_or_zero();
                let angle = nf.cross(ng).dot(axis).atan2(nf.dot(ng));
                faces[t].back[e] = back as u8;
                faces[t].kappa[e] = angle / std::f32::consts::PI;
                // Rebuild the rotation when the mesh carries none (hand-made meshes).
                if mesh.edge_rotations.len() != nt {
                    faces[t].rotation[e] = Quat::from_axis_angle(axis, angle);
                }
            }
        }
        Ok(Surface { faces })
    }

    /// Number of faces.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether there are no faces (never, for a built surface).
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The point of face `face` at barycentric `bary`.
    pub fn point(&self, face: u32, bary: [f32; 3]) -> Vec3 {
        let f = &self.faces[face as usize];
        let s = bary[0] + bary[1] + bary[2];
        (f.v[0] * bary[0] + f.v[1] * bary[1] + f.v[2] * bary[2]) / s
    }

    /// Unit normal of face `face`.
    pub fn normal(&self, face: u32) -> Vec3 {
        self.faces[face as usize].n
    }

    /// The nearest surface point to `p`: (face, barycentric, distance).
    pub fn nearest(&self, p: Vec3) -> (u32, [f32; 3], f32) {
        let mut best = (0u32, [1.0 / 3.0; 3], f32::INFINITY);
        for (t, f) in self.faces.iter().enumerate() {
            let (q, bary) = closest_on_triangle(p, f.v);
            let d = (q - p).length();
            if d < best.2 {
                best = (t as u32, bary, d);
            }
        }
        best
    }

    /// Curvature factor `1 + κ` at `p` on face `face` (eq. 3.4's ramp over `d_t`).
    fn curvature(&self, face: u32, p: Vec3, d_t: f32) -> f32 {
        if d_t <= 0.0 {
            return 1.0;
        }
        let f = &self.faces[face as usize];
        let mut kappa = 0.0f32;
        for e in 0..3 {
            if f.neighbor[e] == NO_NEIGHBOR || f.kappa[e] == 0.0 {
                continue;
            }
            let d = (p - f.v[e]).dot(f.inward[e]).max(0.0);
            if d < d_t {
                let k = f.kappa[e] * (1.0 - d / d_t);
                if k.abs() > kappa.abs() {
                    kappa = k;
                }
            }
        }
        (1.0 + kappa).max(0.0)
    }

    /// Moves a point `dist` along `heading` over the surface, crossing edges by the stored
    /// rotations (§3.3.2, Figure 3-8). Returns the end state and whether a boundary edge stopped it.
    fn advance(&self, mut face: u32, mut pos: Vec3, mut heading: Vec3, dist: f32) -> (u32, Vec3, Vec3, bool) {
        let mut remaining = dist;
        let mut skip: Option<usize> = None;
        for _ in 0..1024 {
            let f = &self.faces[face as usize];
            let mut exit: Option<(f32, usize)> = None;
            for e in 0..3 {
                if skip == Some(e) {
                    continue;
                }
                let rate = heading.dot(f.inward[e]);
                if rate < -1e-9 {
                    let t = (pos - f.v[e]).dot(f.inward[e]).max(0.0) / -rate;
                    if exit.is_none_or(|(b, _)| t < b) {
                        exit = Some((t, e));
                    }
                }
            }
            match exit {
                Some((t, e)) if t < remaining => {
                    pos += heading * t;
                    remaining -= t;
                    let g = f.neighbor[e];
                    if g == NO_NEIGHBOR {
                        return (face, project(f, pos), heading, true);
                    }
                    let back = f.back[e] as usize;
                    heading = f.rotation[e] * heading;
                    let nf = &self.faces[g as usize];
                    heading -= nf.n * heading.dot(nf.n);
                    // Sliding along the shared edge must not lead straight back out.
                    let out = heading.dot(nf.inward[back]);
                    if out < 0.0 {
                        heading -= nf.inward[back] * out;
                    }
                    heading = heading.normalize_or_zero();
                    if heading == Vec3::ZERO {
                        return (g, project(nf, pos), nf.inward[back], false);
                    }
                    face = g;
                    pos = project(nf, pos);
                    skip = Some(back);
                }
                _ => {
                    pos += heading * remaining;
                    return (face, project(f, pos), heading, false);
                }
            }
        }
        (face, project(&self.faces[face as usize], pos), heading, false)
    }

    /// The straight way from `a` on face `fa` to `b` on face `fb` over the surface: on adjacent
    /// faces it bends where the unfolded line crosses their shared edge. Perry §4: the boundary
    /// test needs geodesics; a 3D chord across a convex edge runs inside the solid, and fronts
    /// meeting at the edge slip past each other under it.
    fn chord(&self, fa: u32, a: Vec3, fb: u32, b: Vec3) -> Chord {
        let straight = Chord { a, mid: (a + b) * 0.5, b };
        if fa == fb {
            return straight;
        }
        let f = &self.faces[fa as usize];
        let Some(e) = (0..3).find(|&e| f.neighbor[e] == fb) else { return straight };
        let (v0, v1) = (f.v[e], f.v[(e + 1) % 3]);
        let flat = v0 + f.rotation[e].inverse() * (b - v0);
        let (da, db) = ((a - v0).dot(f.inward[e]), (flat - v0).dot(f.inward[e]));
        let s = if da - db > 1e-9 { (da / (da - db)).clamp(0.0, 1.0) } else { 0.5 };
        let edge = v1 - v0;
        let t = ((a.lerp(flat, s) - v0).dot(edge) / edge.length_squared()).clamp(0.0, 1.0);
        Chord { a, mid: v0 + edge * t, b }
    }
}

/// A boundary segment or a move over the surface, `a → mid → b`: bent at `mid` where it
/// crosses an edge, else `mid` is the midpoint.
#[derive(Clone, Copy, Debug)]
struct Chord {
    a: Vec3,
    mid: Vec3,
    b: Vec3,
}

impl Chord {
    fn pieces(&self) -> [(Vec3, Vec3); 2] {
        [(self.a, self.mid), (self.mid, self.b)]
    }

    /// Whether it passes within `tol` of the segment `c → d` at a fraction of its length (0 at
    /// `a`, 1 at `b`) that `at` accepts.
    fn meets(&self, c: Vec3, d: Vec3, tol: f32, at: impl Fn(f32) -> bool) -> bool {
        let first = (self.mid - self.a).length();
        let total = (first + (self.b - self.mid).length()).max(1e-12);
        self.pieces().into_iter().enumerate().any(|(k, (a, b))| {
            let (s, dist) = segment_distance(a, b, c, d);
            let along = if k == 0 { s * first } else { first + s * (total - first) };
            dist < tol && at(along / total)
        })
    }
}

fn project(f: &Face, p: Vec3) -> Vec3 {
    p - f.n * (p - f.v[0]).dot(f.n)
}

/// Closest point of triangle `v` to `p` and its barycentric coordinates (Ericson, RTCD §5.1.5).
fn closest_on_triangle(p: Vec3, v: [Vec3; 3]) -> (Vec3, [f32; 3]) {
    let (a, b, c) = (v[0], v[1], v[2]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let w = d1 / (d1 - d3);
        return (a + ab * w, [1.0 - w, w, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v2, w2) = (vb * denom, vc * denom);
    (a + ab * v2 + ac * w2, [1.0 - v2 - w2, v2, w2])
}

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
    pending: Vec<Ignition>,
    loops: Vec<Vec<ControlPoint>>,
    roots: Vec<FlameRoot>,
    chars: Vec<CharMark>,
    extinguished: Vec<[f32; 3]>,
    time: f32,
    dropped: u64,
}

/// Checks spread parameters no port range can; errors name the port.
pub fn validate_params(p: &SpreadParams) -> Result<(), NodeError> {
    for (name, v) in
        [("q_o", p.q_o), ("q_c", p.q_c), ("K", p.k), ("d_t", p.d_t), ("d_s", p.d_s), ("d_d", p.d_d), ("lifetime", p.lifetime)]
    {
        if !v.is_finite() || v < 0.0 {
            return Err(NodeError::port(name, format!("must be a finite number ≥ 0, got {v}")));
        }
    }
    if p.k <= 0.0 {
        return Err(NodeError::port("K", "the global time scale K must be positive"));
    }
    for (name, v) in [("d_s", p.d_s), ("d_d", p.d_d)] {
        if v <= 0.0 {
            return Err(NodeError::port(name, "must be positive"));
        }
    }
    if p.points < 3 {
        return Err(NodeError::port(
            "points",
            format!("an ignition ring needs at least 3 points (Perry used ≥ 8), got {}", p.points),
        ));
    }
    Ok(())
}

impl Spread {
    /// A spread over `surface` that will ignite at each of `ignitions` (at its time).
    pub fn new(surface: Arc<Surface>, ignitions: Vec<Ignition>, params: SpreadParams) -> Result<Spread, NodeError> {
        validate_params(&params)?;
        for (k, ig) in ignitions.iter().enumerate() {
            if ig.face as usize >= surface.len() {
                return Err(NodeError::port(
                    "ignite",
                    format!("ignition {}: face {} is past the mesh's {} faces", k + 1, ig.face, surface.len()),
                ));
            }
            if ig.bary.iter().any(|b| !b.is_finite() || *b < 0.0) || ig.bary.iter().sum::<f32>() <= 0.0 {
                return Err(NodeError::port(
                    "ignite",
                    format!(
                        "ignition {}: barycentric coordinates {:?} are not a point of the face (need ≥ 0, not all 0)",
                        k + 1,
                        ig.bary
                    ),
                ));
            }
        }
        let mut pending = ignitions;
        pending.sort_by(|a, b| b.time.total_cmp(&a.time));
        let mut s = Spread {
            surface,
            params,
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
        self.surface.curvature(face, p, self.params.d_t) * q / self.params.k
    }

    /// Advances the spread by `dt` seconds in the wind `wind(p)` (the external wind u∞).
    pub fn step(&mut self, dt: f32, wind: &(dyn Fn(Vec3) -> Vec3 + Sync)) {
        let dt = dt.max(0.0);
        // Flame roots age; the dead leave char (§3.4.1).
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

        // Proposed moves, in parallel (each point moves without knowledge of the others, §3.4.2).
        let moves: Vec<Vec<Option<(ControlPoint, bool, f32)>>> = self
            .loops
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
            .collect();

        // Double-burn prevention against the boundary at t − 1 (Figure 3-9).
        let blocked: Vec<Vec<bool>> = if self.params.double_burn {
            // Points move at once, so the test also runs against the proposed boundary at t:
            // two fronts closing in by less than two steps would otherwise pass through each other.
            let proposed: Vec<Vec<ControlPoint>> = self
                .loops
                .iter()
                .zip(&moves)
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
        } else {
            Vec::new()
        };

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
                            lifetime: (self.params.lifetime * (1.0 + jitter)).max(1e-3),
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
        self.thin_dead_runs();
        self.insert_points();
        self.time += dt;
        self.ignite_due();
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

/// Closest approach of segments `a→b` and `c→d`: (parameter along `a→b`, distance).
fn segment_distance(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> (f32, f32) {
    let (d1, d2, r) = (b - a, d - c, a - c);
    let (aa, ee, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let eps = 1e-12;
    let (s, t) = if aa <= eps && ee <= eps {
        (0.0, 0.0)
    } else if aa <= eps {
        (0.0, (f / ee).clamp(0.0, 1.0))
    } else {
        let cc = d1.dot(r);
        if ee <= eps {
            ((-cc / aa).clamp(0.0, 1.0), 0.0)
        } else {
            let bb = d1.dot(d2);
            let denom = aa * ee - bb * bb;
            let mut s = if denom > eps { ((bb * f - cc * ee) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (bb * s + f) / ee;
            if t < 0.0 {
                t = 0.0;
                s = (-cc / aa).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((bb - cc) / aa).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (s, ((a + d1 * s) - (c + d2 * t)).length())
}

/// Parses the `ignite` text: entries separated by `;`, each `x y z` (the nearest surface point)
/// or `face F b0 b1 b2` (a face and barycentric point), optionally followed by `@ T` (seconds).
/// A position farther than `snap` from the surface is an error.
pub fn parse_ignitions(text: &str, surface: &Surface, snap: f32) -> Result<Vec<Ignition>, NodeError> {
    let err = |m: String| NodeError::port("ignite", m);
    let mut out = Vec::new();
    for (k, entry) in text.split(';').map(str::trim).filter(|s| !s.is_empty()).enumerate() {
        let (body, time) = match entry.split_once('@') {
            Some((b, t)) => {
                let t: f32 = t
                    .trim()
                    .parse()
                    .map_err(|_| err(format!("ignition {} ('{entry}'): time '{}' is not a number", k + 1, t.trim())))?;
                if !t.is_finite() || t < 0.0 {
                    return Err(err(format!("ignition {} ('{entry}'): time must be ≥ 0", k + 1)));
                }
                (b.trim(), t)
            }
            None => (entry, 0.0),
        };
        let words: Vec<&str> = body.split([' ', ',', '\t']).filter(|w| !w.is_empty()).collect();
        let nums = |ws: &[&str]| -> Result<Vec<f32>, NodeError> {
            ws.iter()
                .map(|w| {
                    w.parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| err(format!("ignition {} ('{entry}'): '{w}' is not a finite number", k + 1)))
                })
                .collect()
        };
        if words.first() == Some(&"face") {
            let face: u32 = words
                .get(1)
                .and_then(|w| w.parse().ok())
                .ok_or_else(|| err(format!("ignition {} ('{entry}'): 'face' needs a face index", k + 1)))?;
            let b = nums(&words[2..])?;
            let bary = match b.len() {
                0 => [1.0 / 3.0; 3],
                2 => [1.0 - b[0] - b[1], b[0], b[1]],
                3 => [b[0], b[1], b[2]],
                m => {
                    return Err(err(format!("ignition {} ('{entry}'): needs 0, 2 or 3 barycentric coordinates, got {m}", k + 1)));
                }
            };
            if face as usize >= surface.len() {
                return Err(err(format!("ignition {}: face {face} is past the mesh's {} faces", k + 1, surface.len())));
            }
            out.push(Ignition { face, bary, time });
        } else {
            let p = nums(&words)?;
            if p.len() != 3 {
                return Err(err(format!("ignition {} ('{entry}'): needs 'x y z' or 'face F [b0 b1 b2]'", k + 1)));
            }
            let p = Vec3::new(p[0], p[1], p[2]);
            let (face, bary, dist) = surface.nearest(p);
            if dist > snap {
                return Err(err(format!(
                    "ignition {} at ({}, {}, {}) is off the mesh: the nearest surface point (face {face}) is {dist:.4} away, \
                     more than snap = {snap}; move it onto the surface or raise snap",
                    k + 1,
                    p.x,
                    p.y,
                    p.z
                )));
            }
            out.push(Ignition { face, bary, time });
        }
    }
    if out.is_empty() {
        return Err(err("no ignition point: give 'x y z' or 'face F b0 b1 b2' (several separated by ';')".into()));
    }
    Ok(out)
}

/// Frames between kept checkpoints of the stepping cache.
const CHECKPOINT_EVERY: usize = 16;
/// Bytes of checkpoints kept per clip.
const CHECKPOINT_BUDGET: usize = 256 << 20;

struct Cache {
    current: Option<(usize, Spread)>,
    checkpoints: BTreeMap<usize, Spread>,
    bytes: usize,
}

/// A `Clip<SpreadState>` source: frame n after frame n − 1 costs one frame of steps.
pub struct SpreadSource {
    initial: Spread,
    wind: WindField,
    frames: usize,
    substeps: usize,
    fps: f32,
    cache: Mutex<Cache>,
}

impl SpreadSource {
    /// A source of `frames` frames at `fps`, each `substeps` steps, frame 0 at ignition.
    pub fn new(initial: Spread, wind: WindField, frames: usize, fps: f32, substeps: usize) -> Self {
        let cache = Cache { current: None, checkpoints: BTreeMap::new(), bytes: 0 };
        SpreadSource { initial, wind, frames, substeps: substeps.max(1), fps, cache: Mutex::new(cache) }
    }

    fn lock(&self) -> Result<std::sync::MutexGuard<'_, Cache>, NodeError> {
        self.cache.lock().map_err(|_| NodeError::msg("the spread cache was poisoned by an earlier panic"))
    }

    /// The simulation at frame `index`.
    pub fn spread(&self, index: usize, ctx: &CookCtx) -> Result<Spread, NodeError> {
        let (mut frame, mut sim) = {
            let mut c = self.lock()?;
            match c.current.take() {
                Some((f, s)) if f <= index => (f, s),
                other => {
                    c.current = other;
                    c.checkpoints
                        .range(..=index)
                        .next_back()
                        .map(|(f, s)| (*f, s.clone()))
                        .unwrap_or_else(|| (0, self.initial.clone()))
                }
            }
        };
        let wind = spread_wind(&self.wind);
        let dt = 1.0 / (self.fps * self.substeps as f32);
        while frame < index {
            ctx.check_cancel()?;
            for _ in 0..self.substeps {
                sim.step(dt, &wind);
            }
            frame += 1;
            if frame % CHECKPOINT_EVERY == 0 {
                let mut c = self.lock()?;
                if !c.checkpoints.contains_key(&frame) && c.bytes + sim.bytes() <= CHECKPOINT_BUDGET {
                    c.bytes += sim.bytes();
                    c.checkpoints.insert(frame, sim.clone());
                }
            }
        }
        self.lock()?.current = Some((frame, sim.clone()));
        Ok(sim)
    }
}

impl FrameSource for SpreadSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::SpreadState(Arc::new(self.spread(index, ctx)?.state())))
    }
}

fn fire_spread_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.fire_spread",
        "Particles",
        TimeDep::Simulation,
        "Perry's fire spread over a polygon mesh (Perry 1994 §3.3–3.4): each ignition starts a \
         counter-clockwise ring of control points moving at v_s = (1 + κ)(A_o q_o + A_c q_c)/K (eq. 3.4; \
         A_o = 1, A_c = max(0, heading · wind projected on the face), κ the curvature ramp (1 − d/d_t)Θ/π near \
         edges, positive on convex edges) in the wind u∞ = −k_g g + w_L. Crossing an edge rotates the heading \
         into the next face by the mesh's stored rotation (§3.3.2); a boundary edge stops the point. A new \
         point is inserted where neighbours are more than d_s apart; with double_burn on, a point whose move \
         crosses the boundary (Figure 3-9) goes out. Every point drops a flame root each d_d travelled, with \
         the face normal as direction and lifetime l_f (§3.4); dead roots leave char marks (§3.4.1). Ranges \
         of K, d_d, d_s, d_t and l_f are Table 3.1. Deterministic for a seed; the clip steps a cache.",
    )
    .input(PortDesc::new("mesh", PortType::Mesh, "The mesh to burn (particles.mesh_load)."))
    .input(PortDesc {
        default: Some(Value::WindField(Arc::new(WindField::default()))),
        ..PortDesc::new("wind", PortType::WindField, "External wind: convection −k_g g plus w_L (particles.wind_field).")
    })
    .input(PortDesc::string(
        "ignite",
        "face 0",
        "Ignition points separated by ';': 'x y z' (nearest surface point) or 'face F [b0 b1 b2]', optional '@ seconds'.",
    ))
    .input(PortDesc::float("snap", 0.05, (0.0, 1e6), "Largest distance from an ignition position to the surface."))
    .input(PortDesc::int("frames", 96, (1, 100_000), "Number of frames."))
    .input(PortDesc::float("fps", 24.0, (1.0, 240.0), "Frames per second (speeds are per second)."))
    .input(PortDesc::int("substeps", 1, (1, 64), "Spread steps per frame."))
    .input(PortDesc::float("q_o", 0.09, (0.0, 10.0), "Opposed-flow heat flux q_o (footnote 10: 0.09)."))
    .input(PortDesc::float("q_c", 0.13, (0.0, 10.0), "Concurrent-flow heat flux q_c (footnote 10: 0.13)."))
    .input(PortDesc::float("K", 0.4, (0.004, 0.4), "Global time scale K of eq. 3.4 (Table 3.1)."))
    .input(PortDesc::float("d_t", 0.05, (0.01, 0.5), "Curvature distance d_t (Table 3.1)."))
    .input(PortDesc::bool("curvature", true, "Use the curvature ramp of eq. 3.4 (off: flat speed everywhere)."))
    .input(PortDesc::float("d_s", 0.05, (0.01, 0.2), "Control point separation d_s (Table 3.1)."))
    .input(PortDesc::float("d_d", 0.05, (0.01, 1.0), "Flame drop distance d_d (Table 3.1)."))
    .input(PortDesc::int("lifetime", 48, (1, 1000), "Flame lifetime l_f in frames (Table 3.1)."))
    .input(PortDesc::float("lifetime_jitter", 0.3, (0.0, 1.0), "Random per-flame lifetime variation."))
    .input(PortDesc::int("points", 16, (8, 4096), "Control points of each ignition ring (footnote 13: eight or more)."))
    .input(PortDesc::int("max_points", 200_000, (8, 10_000_000), "No points are inserted beyond this many."))
    .input(PortDesc::bool(
        "double_burn",
        true,
        "Prevent double burning by the segment test of Figure 3-9 (off for planar cases).",
    ))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Seed of the per-flame lifetime variation."))
    .output(
        "spread",
        PortType::clip_of(PortType::SpreadState),
        "Per frame: boundary, live flame roots, extinguished points, char.",
    )
}

/// Reads [`SpreadParams`] from the node's inputs (fps converts l_f from frames to seconds).
pub fn params_from_inputs(i: &Inputs<'_>) -> Result<SpreadParams, NodeError> {
    let fps = i.float("fps")? as f32;
    let seed = i.int("seed")?;
    let p = SpreadParams {
        q_o: i.float("q_o")? as f32,
        q_c: i.float("q_c")? as f32,
        k: i.float("K")? as f32,
        d_t: if i.bool("curvature")? { i.float("d_t")? as f32 } else { 0.0 },
        d_s: i.float("d_s")? as f32,
        d_d: i.float("d_d")? as f32,
        lifetime: i.usize("lifetime")? as f32 / fps,
        lifetime_jitter: i.float("lifetime_jitter")? as f32,
        points: i.usize("points")?,
        max_points: i.usize("max_points")?,
        double_burn: i.bool("double_burn")?,
        seed: u32::try_from(seed).map_err(|_| NodeError::port("seed", format!("must be 0..=4294967295, got {seed}")))?,
    };
    validate_params(&p)?;
    Ok(p)
}

fn cook_fire_spread(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let mesh_value = i.get("mesh")?;
    let surface = Arc::new(Surface::new(i.mesh("mesh")?).map_err(|m| NodeError::port("mesh", m))?);
    let wind_value = i.get("wind")?;
    let wind = (**i.wind_field("wind")?).clone();
    validate_wind(&wind, "wind")?;
    let params = params_from_inputs(i)?;
    let ignite = i.string("ignite")?;
    let ignitions = parse_ignitions(ignite, &surface, i.float("snap")? as f32)?;
    let (frames, fps, substeps) = (i.usize("frames")?, i.float("fps")?, i.usize("substeps")?);
    let mut h = Fingerprinter::new();
    "particles.fire_spread".hash(&mut h);
    mesh_value.hash_into(&mut h);
    wind_value.hash_into(&mut h);
    format!("{params:?}{ignitions:?}").hash(&mut h);
    (frames, fps.to_bits(), substeps).hash(&mut h);
    let spread = Spread::new(surface, ignitions, params)?;
    let source = SpreadSource::new(spread, wind, frames, fps as f32, substeps);
    Ok(vec![Value::Clip(Clip::new(PortType::SpreadState, fps, h.finish(), Arc::new(source)))])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{build_mesh, cube, cylinder, plane};
    use pyrograph_core::LargeWind;

    fn still() -> impl Fn(Vec3) -> Vec3 + Sync {
        |_| Vec3::ZERO
    }

    fn surface(soup: &crate::mesh::PolygonSoup) -> Arc<Surface> {
        Arc::new(Surface::new(&build_mesh(soup, 0, true).unwrap()).unwrap())
    }

    fn at(s: &Surface, p: Vec3) -> Ignition {
        let (face, bary, d) = s.nearest(p);
        assert!(d < 1e-5);
        Ignition { face, bary, time: 0.0 }
    }

    fn run(s: &mut Spread, seconds: f32, dt: f32, wind: &(dyn Fn(Vec3) -> Vec3 + Sync)) {
        let steps = (seconds / dt).round() as usize;
        for _ in 0..steps {
            s.step(dt, wind);
        }
    }

    #[test]
    fn on_a_flat_plane_without_wind_the_boundary_is_a_circle_growing_linearly() {
        let surf = surface(&plane(4.0, 16));
        let p = SpreadParams { d_s: 0.05, double_burn: false, ..SpreadParams::default() };
        let v = p.q_o / p.k;
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.1, 0.0, -0.07))], p).unwrap();
        let centre = Vec3::new(0.1, 0.0, -0.07);
        let mut radii = Vec::new();
        for t in [2.0f32, 4.0, 6.0] {
            run(&mut s, 2.0, 0.05, &still());
            let r: Vec<f32> = s.loops()[0].iter().map(|c| (c.position - centre).length()).collect();
            let mean = r.iter().sum::<f32>() / r.len() as f32;
            let dev = r.iter().map(|x| (x - mean).abs()).fold(0.0, f32::max) / mean;
            println!(
                "t = {t}: {} points, mean radius {mean:.4} (v·t = {:.4}), max radial deviation {:.2} %",
                r.len(),
                v * t,
                dev * 100.0
            );
            assert!(dev < 0.05, "t = {t}: radial deviation {dev}");
            assert!((mean - v * t).abs() / (v * t) < 0.05, "t = {t}: radius {mean} vs {}", v * t);
            assert!(s.loops()[0].iter().all(|c| c.alive && c.position.y.abs() < 1e-5));
            radii.push(mean);
        }
        // Linear growth: equal increments.
        let (d1, d2) = (radii[1] - radii[0], radii[2] - radii[1]);
        assert!((d1 - d2).abs() / d1 < 0.03, "increments {d1} and {d2}");
        // Every gap at most d_s (after the insertion pass).
        let ring = &s.loops()[0];
        let max_gap =
            (0..ring.len()).map(|j| (ring[j].position - ring[(j + 1) % ring.len()].position).length()).fold(0.0, f32::max);
        assert!(max_gap <= 0.05 + 1e-4, "gap {max_gap}");
    }

    #[test]
    fn with_wind_the_concurrent_side_outruns_the_opposed_side_by_the_flux_ratio() {
        let surf = surface(&plane(6.0, 12));
        let p = SpreadParams { double_burn: false, ..SpreadParams::default() };
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::ZERO)], p.clone()).unwrap();
        let wind = |_: Vec3| Vec3::new(2.0, 0.3, 0.0); // the vertical part is normal to the plane
        run(&mut s, 5.0, 0.05, &wind);
        let xs: Vec<f32> = s.loops()[0].iter().map(|c| c.position.x).collect();
        let (lo, hi) = xs.iter().fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
        let ratio = hi / -lo;
        let expected = (p.q_o + p.q_c) / p.q_o;
        println!("downwind {hi:.4}, upwind {:.4}: ratio {ratio:.4}, model (q_o + q_c)/q_o = {expected:.4}", -lo);
        assert!((ratio - expected).abs() / expected < 0.03, "ratio {ratio} vs {expected}");
    }

    #[test]
    fn after_crossing_cube_edges_every_control_point_lies_on_the_surface() {
        let surf = surface(&cube(1.0, 3));
        let p = SpreadParams { d_s: 0.04, ..SpreadParams::default() };
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.5, 0.1, -0.05))], p).unwrap();
        let wind = spread_wind(&WindField { large: LargeWind::Constant([0.5, 0.0, 0.2]), ..WindField::default() });
        let mut faces_seen = std::collections::HashSet::new();
        let mut worst = 0.0f32;
        for _ in 0..160 {
            s.step(1.0 / 24.0, &wind);
            for c in s.loops().iter().flatten() {
                let m = c.position.abs().max_element();
                let d = (m - 0.5).abs().max(c.position.abs().max_element() - 0.5);
                worst = worst.max(d);
                let n = surf.normal(c.face);
                faces_seen.insert((n * 2.0).round().to_array().map(|x| x as i32));
                assert!((c.heading.dot(n)).abs() < 1e-4, "heading in the face plane");
            }
        }
        println!("{} points on {} cube sides, worst distance to the surface {worst:e}", s.point_count(), faces_seen.len());
        assert!(worst < 1e-5, "{worst}");
        assert!(faces_seen.len() >= 5, "the fire crossed onto {} sides", faces_seen.len());
    }

    /// Points on an open tube around +Y ignited at angle 0: a point moving strongly around the tube
    /// (|ĥ·θ̂| > 0.5) must stay on its own half; past the far side means it is burning burnt ground.
    fn trespassers(s: &Spread) -> usize {
        let tol = 0.15;
        s.loops()
            .iter()
            .flatten()
            .filter(|c| {
                let th = (-c.position.z).atan2(c.position.x).rem_euclid(std::f32::consts::TAU);
                let e_th = Vec3::new(-th.sin(), 0.0, -th.cos());
                let around = c.heading.dot(e_th);
                let pi = std::f32::consts::PI;
                (around > 0.5 && th > pi + tol && th < 2.0 * pi - tol) || (around < -0.5 && th > tol && th < pi - tol)
            })
            .count()
    }

    #[test]
    fn with_double_burn_prevention_no_point_enters_the_burnt_region_of_a_cylinder() {
        let surf = surface(&cylinder(0.5, 0.6, 48, 3));
        let (face, bary, _) = surf.nearest(Vec3::new(0.5, 0.3, -0.02));
        let ig = Ignition { face, bary, time: 0.0 };
        let params = SpreadParams { d_t: 0.0, d_s: 0.03, ..SpreadParams::default() };
        let mut on = Spread::new(surf.clone(), vec![ig], params.clone()).unwrap();
        let mut off = Spread::new(surf.clone(), vec![ig], SpreadParams { double_burn: false, ..params }).unwrap();
        // Half the circumference is π·0.5 ≈ 1.57 at 0.225/s ≈ 7 s; run well past the meeting.
        let (mut worst_on, mut worst_off) = (0, 0);
        for _ in 0..(11.0f32 / 0.05) as usize {
            on.step(0.05, &still());
            off.step(0.05, &still());
            worst_on = worst_on.max(trespassers(&on));
            worst_off = worst_off.max(trespassers(&off));
        }
        println!("points in the burnt region: {worst_on} with prevention, {worst_off} without");
        assert_eq!(worst_on, 0);
        assert!(worst_off > 0, "the test has teeth: without prevention the fronts pass through each other");
        assert!(on.loops()[0].iter().all(|c| !c.alive), "with prevention the fire goes out");
    }

    fn dead_points(s: &Spread) -> usize {
        s.loops().iter().flatten().filter(|c| !c.alive).count()
    }

    /// Perimeter of the convex hull of the control points seen from above (the XZ plane).
    fn hull_perimeter_xz(s: &Spread) -> f32 {
        let mut p: Vec<(f32, f32)> = s.loops().iter().flatten().map(|c| (c.position.x, c.position.z)).collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        p.dedup();
        let turns_left =
            |o: (f32, f32), a: (f32, f32), b: (f32, f32)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0) > 0.0;
        let half = |points: &mut dyn Iterator<Item = (f32, f32)>| {
            let mut h: Vec<(f32, f32)> = Vec::new();
            for q in points {
                while h.len() >= 2 && !turns_left(h[h.len() - 2], h[h.len() - 1], q) {
                    h.pop();
                }
                h.push(q);
            }
            h.pop();
            h
        };
        let mut hull = half(&mut p.iter().copied());
        hull.extend(half(&mut p.iter().rev().copied()));
        (0..hull.len())
            .map(|k| {
                let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
                (a.0 - b.0).hypot(a.1 - b.1)
            })
            .sum()
    }

    /// Fraction of a grid of points on the sides of the unit cube within `r` of a flame root or
    /// char mark: how much of it has burnt.
    fn burnt_fraction_of_unit_cube(s: &Spread, r: f32) -> f32 {
        let st = s.state();
        let marks: Vec<Vec3> =
            st.roots.iter().map(|m| m.position).chain(st.char_marks.iter().map(|m| m.position)).map(Vec3::from_array).collect();
        let n = 20;
        let mut burnt = 0;
        for axis in 0..3 {
            for side in [-0.5f32, 0.5] {
                for (i, j) in (0..n).flat_map(|i| (0..n).map(move |j| (i, j))) {
                    let mut p = Vec3::ZERO;
                    p[axis] = side;
                    p[(axis + 1) % 3] = (i as f32 + 0.5) / n as f32 - 0.5;
                    p[(axis + 2) % 3] = (j as f32 + 0.5) / n as f32 - 0.5;
                    burnt += usize::from(marks.iter().any(|m| (*m - p).length() < r));
                }
            }
        }
        burnt as f32 / (6 * n * n) as f32
    }

    #[test]
    fn in_wind_the_point_count_stays_within_three_per_d_s_of_the_burnt_perimeter() {
        let surf = surface(&plane(4.0, 16));
        let p = SpreadParams { d_s: 0.05, ..SpreadParams::default() };
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::ZERO)], p.clone()).unwrap();
        let wind = |_: Vec3| Vec3::new(2.0, 0.3, 0.5);
        let rim = 16.0;
        let mut most = 0;
        for step in 1..=360 {
            s.step(1.0 / 24.0, &wind);
            let (n, dead) = (s.point_count(), dead_points(&s));
            let bound = 3.0 * hull_perimeter_xz(&s) / p.d_s + p.points as f32;
            assert!(n as f32 <= bound, "step {step}: {n} points, more than {bound:.0}");
            // Points only stop on the rim here (one ignition, no fronts meet).
            assert!(dead as f32 <= 3.0 * rim / p.d_s, "step {step}: {dead} stopped points along a rim of {rim}");
            most = most.max(n);
        }
        // After 15 s even the upwind front (0.225/s) has reached the farthest corner (≈ 2.8 away).
        assert!(s.loops().iter().flatten().all(|c| !c.alive), "the fire is out");
        let out = s.point_count();
        run(&mut s, 2.0, 1.0 / 24.0, &wind);
        println!("at most {most} points; {out} when the fire is out, on a rim of {rim} (d_s = {})", p.d_s);
        assert_eq!(s.point_count(), out, "a fire that is out keeps its points");
    }

    #[test]
    fn the_burning_cube_needs_a_few_hundred_points_and_still_burns_all_over() {
        // graphs/burning-cube.ron without its translation.
        let surf = surface(&cube(1.0, 8));
        let p = SpreadParams { d_t: 0.1, d_s: 0.05, ..SpreadParams::default() };
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.5, -0.3, -0.15))], p.clone()).unwrap();
        let wind = spread_wind(&WindField { k_g: 2.0, large: LargeWind::Constant([-0.15, 0.0, 0.35]), ..WindField::default() });
        // Generous: three points per d_s along fronts as long as the cube's twelve edges together.
        let bound = 3.0 * 12.0 / p.d_s + p.points as f32;
        let mut counts = Vec::new();
        for frame in 1..=240 {
            s.step(1.0 / 24.0, &wind);
            assert!(s.point_count() as f32 <= bound, "frame {frame}: {} points, more than {bound}", s.point_count());
            if frame % 48 == 0 {
                counts.push((s.point_count(), dead_points(&s)));
            }
        }
        let burnt = burnt_fraction_of_unit_cube(&s, 0.06);
        println!("(points, stopped) every 2 s: {counts:?}; {:.1} % of the cube burnt", burnt * 100.0);
        assert!(burnt > 0.99, "only {:.1} % of the cube burnt", burnt * 100.0);
        assert!(s.loops().iter().flatten().all(|c| !c.alive), "the fire is out after 10 s");
        let out = s.point_count();
        run(&mut s, 2.0, 1.0 / 24.0, &wind);
        assert_eq!(s.point_count(), out, "a fire that is out keeps its points");
    }

    #[test]
    fn more_flames_drop_as_d_d_shrinks_and_roots_face_outwards() {
        let surf = surface(&cube(1.0, 2));
        let counts: Vec<u64> = [0.4f32, 0.2, 0.1, 0.05]
            .iter()
            .map(|&d_d| {
                let p = SpreadParams { d_d, lifetime: 100.0, ..SpreadParams::default() };
                let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.0, 0.5, 0.0))], p).unwrap();
                run(&mut s, 2.0, 1.0 / 24.0, &still());
                assert!(
                    s.state()
                        .roots
                        .iter()
                        .all(|r| (Vec3::from_array(r.direction) - Vec3::Y).length() < 1e-5 || r.position[1] < 0.5)
                );
                s.flames_dropped()
            })
            .collect();
        println!("flames dropped for d_d = 0.4, 0.2, 0.1, 0.05: {counts:?}");
        assert!(counts.windows(2).all(|w| w[1] > w[0]), "{counts:?}");
    }

    #[test]
    fn dead_flames_leave_char_and_the_state_is_deterministic() {
        let surf = surface(&cube(1.0, 2));
        let p = SpreadParams { lifetime: 0.5, seed: 3, ..SpreadParams::default() };
        let mut a = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.0, 0.5, 0.0))], p.clone()).unwrap();
        let mut b = a.clone();
        run(&mut a, 2.0, 1.0 / 24.0, &still());
        run(&mut b, 2.0, 1.0 / 24.0, &still());
        assert_eq!(a.state(), b.state());
        let st = a.state();
        assert!(!st.char_marks.is_empty() && !st.roots.is_empty());
        assert_eq!(st.flames_dropped as usize, st.roots.len() + st.char_marks.len());
        assert!(st.roots.iter().all(|r| r.age < r.lifetime));
    }

    #[test]
    fn ignitions_parse_snap_and_report_errors_naming_the_port() {
        let surf = surface(&cube(1.0, 1));
        let ig = parse_ignitions("0.5 0 0; face 3 0.2 0.3 0.5 @ 1.5", &surf, 0.01).unwrap();
        assert_eq!(ig.len(), 2);
        assert!((surf.point(ig[0].face, ig[0].bary) - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-5);
        assert_eq!((ig[1].face, ig[1].time), (3, 1.5));
        let e = parse_ignitions("3 0 0", &surf, 0.05).unwrap_err();
        assert!(matches!(&e, NodeError::Port { port, message } if port == "ignite" && message.contains("off the mesh")), "{e}");
        assert!(parse_ignitions("face 99", &surf, 0.05).is_err());
        assert!(parse_ignitions("1 x 2", &surf, 0.05).is_err());
        assert!(parse_ignitions(" ; ", &surf, 0.05).is_err());
        // A delayed ignition starts its own ring when its time comes.
        let mut s = Spread::new(surf, ig, SpreadParams::default()).unwrap();
        assert_eq!(s.loops().len(), 1);
        run(&mut s, 1.6, 0.1, &still());
        assert_eq!(s.loops().len(), 2);
    }

    #[test]
    fn a_boundary_edge_stops_every_point_on_the_edge() {
        let surf = surface(&plane(1.0, 2));
        let p = SpreadParams { double_burn: false, ..SpreadParams::default() };
        let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.05, 0.0, -0.1))], p).unwrap();
        // The farthest corner is ≈ 0.78 away; at q_o/K = 0.225 per second that is ≈ 3.5 s.
        run(&mut s, 5.0, 1.0 / 24.0, &still());
        let ring = &s.loops()[0];
        assert!(ring.len() > 16, "points were inserted as the ring grew");
        for c in ring {
            assert!(!c.alive, "point at {} still moving", c.position);
            let off = (c.position.x.abs().max(c.position.z.abs()) - 0.5).abs();
            assert!(off < 1e-4 && c.position.y.abs() < 1e-6, "stopped at {}, {off} from the rim", c.position);
        }
        assert!(s.state().extinguished.len() >= ring.len());
        // A stopped fire stays stopped.
        let before = s.state().boundaries;
        run(&mut s, 0.5, 1.0 / 24.0, &still());
        assert_eq!(s.state().boundaries, before);
    }

    #[test]
    fn curvature_speeds_the_spread_towards_convex_edges_and_slows_it_towards_concave_ones() {
        let outside = surface(&cube(1.0, 1));
        let mut inverted = cube(1.0, 1);
        inverted.polygons.iter_mut().for_each(|p| p.reverse());
        let inside = surface(&inverted);
        let d_t = 0.2;
        // Points on the y = +0.5 face, at distances from its edge x = +0.5.
        for (surf, sign) in [(&outside, 1.0f32), (&inside, -1.0)] {
            for (d, want) in [(0.0f32, 0.5f32), (0.05, 0.375), (0.1, 0.25), (0.3, 0.0)] {
                let p = Vec3::new(0.5 - d, 0.5, 0.03);
                let (face, _, dist) = surf.nearest(p);
                assert!(dist < 1e-6);
                let got = surf.curvature(face, p, d_t);
                assert!((got - (1.0 + sign * want)).abs() < 1e-4, "sign {sign}, d = {d}: factor {got}");
                assert_eq!(surf.curvature(face, p, 0.0), 1.0, "d_t = 0 turns curvature off");
            }
        }
        // A spreading fire reaches a convex edge sooner with the curvature term than without.
        let reach = |d_t: f32| {
            let p = SpreadParams { d_t, double_burn: false, ..SpreadParams::default() };
            let mut s = Spread::new(outside.clone(), vec![at(&outside, Vec3::new(0.2, 0.5, 0.0))], p).unwrap();
            let mut steps = 0;
            while s.loops()[0].iter().all(|c| c.position.y > 0.5 - 1e-6) {
                s.step(0.01, &still());
                steps += 1;
                assert!(steps < 1000, "never left the top face");
            }
            steps
        };
        let (with, without) = (reach(0.2), reach(0.0));
        println!("steps to the first edge: {with} with curvature, {without} without");
        assert!(with < without, "{with} vs {without}");
    }

    #[test]
    fn a_mesh_without_faces_cannot_burn() {
        let e = Surface::new(&Mesh::default()).unwrap_err();
        assert!(e.contains("no faces"), "{e}");
        let mesh = build_mesh(&cube(1.0, 1), 0, true).unwrap();
        let broken = Mesh { neighbors: Vec::new(), ..mesh };
        let e = Surface::new(&broken).unwrap_err();
        assert!(e.contains("inconsistent"), "{e}");
    }

    #[test]
    fn table_3_1_ranges_are_the_port_ranges() {
        let d = fire_spread_desc();
        let range = |n: &str| d.inputs[d.input_index(n).unwrap()].range;
        assert_eq!(range("K"), Some((0.004, 0.4)));
        assert_eq!(range("d_d"), Some((0.01, 1.0)));
        assert_eq!(range("d_s"), Some((0.01, 0.2)));
        assert_eq!(range("d_t"), Some((0.01, 0.5)));
        assert_eq!(range("lifetime"), Some((1.0, 1000.0)));
        assert_eq!(range("points").map(|r| r.0), Some(8.0));
    }
}
