//! The mesh a fire spreads over (Perry 1994 §3.3.2): per-face geometry, moving a point over the
//! surface across edges by the stored rotations, and the bent chords the double-burn test of
//! Figure 3-9 measures along.

use crate::types::{Mesh, NO_NEIGHBOR};
use glam::{Quat, Vec3};

/// Per-face geometry derived from a [`Mesh`] once.
#[derive(Clone, Debug)]
pub(crate) struct Face {
    /// Corners.
    pub(crate) v: [Vec3; 3],
    /// Unit normal.
    pub(crate) n: Vec3,
    /// Inward unit normals of the edges, in the face plane.
    pub(crate) inward: [Vec3; 3],
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
    pub(crate) faces: Vec<Face>,
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
    pub(crate) fn curvature(&self, face: u32, p: Vec3, d_t: f32) -> f32 {
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
    pub(crate) fn advance(&self, mut face: u32, mut pos: Vec3, mut heading: Vec3, dist: f32) -> (u32, Vec3, Vec3, bool) {
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
    pub(crate) fn chord(&self, fa: u32, a: Vec3, fb: u32, b: Vec3) -> Chord {
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
pub(crate) struct Chord {
    pub(crate) a: Vec3,
    pub(crate) mid: Vec3,
    pub(crate) b: Vec3,
}

impl Chord {
    pub(crate) fn pieces(&self) -> [(Vec3, Vec3); 2] {
        [(self.a, self.mid), (self.mid, self.b)]
    }

    /// Whether it passes within `tol` of the segment `c → d` at a fraction of its length (0 at
    /// `a`, 1 at `b`) that `at` accepts.
    pub(crate) fn meets(&self, c: Vec3, d: Vec3, tol: f32, at: impl Fn(f32) -> bool) -> bool {
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

/// Closest approach of segments `a→b` and `c→d`: (parameter along `a→b`, distance).
pub(crate) fn segment_distance(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> (f32, f32) {
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
