//! Polygon meshes for fire spread (Perry 1994 §3.3.2): OBJ loading through `tobj`, primitives
//! (cube, plane grid, sphere, open cylinder, a house with a garage), fan triangulation, face
//! normals, face adjacency and the per-edge rotations that carry a spread heading from one face
//! into its neighbour; and the `particles.mesh_load` node.
//!
//! Problems are reported, never guessed around: a degenerate (zero-area) face, an edge shared by
//! more than two faces, or two neighbours wound in opposite directions is an error naming the
//! face (1-based, in file order) unless `strict` is off, in which case degenerate faces are
//! dropped and bad edges become boundaries.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use crate::types::{Mesh, NO_NEIGHBOR};
use glam::{Quat, Vec3};
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, InputPath, NodeError, port};

/// Polygons over shared vertex positions, before triangulation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolygonSoup {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Polygons as vertex indices, counter-clockwise seen from outside.
    pub polygons: Vec<Vec<u32>>,
}

impl PolygonSoup {
    /// Adds a vertex, returning its index.
    pub fn vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// Appends another soup (indices shifted).
    pub fn append(&mut self, other: &PolygonSoup) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.polygons.extend(other.polygons.iter().map(|p| p.iter().map(|i| i + base).collect()));
    }

    /// Merges vertices with bit-identical positions (OBJ objects that share corners, seams).
    pub fn weld(&mut self) {
        let mut map: HashMap<[u32; 3], u32> = HashMap::new();
        let mut positions = Vec::new();
        let remap: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                *map.entry(key).or_insert_with(|| {
                    positions.push(*p);
                    (positions.len() - 1) as u32
                })
            })
            .collect();
        for poly in &mut self.polygons {
            for i in poly.iter_mut() {
                *i = remap[*i as usize];
            }
        }
        self.positions = positions;
    }
}

/// An axis-aligned box from `min` to `max` as six quads with `n` divisions per side (outward CCW).
pub fn box_soup(min: Vec3, max: Vec3, n: usize) -> PolygonSoup {
    let n = n.max(1);
    let mut soup = PolygonSoup::default();
    let mut index: HashMap<[usize; 3], u32> = HashMap::new();
    let lerp = |a: f32, b: f32, k: usize| if k == n { b } else { a + (b - a) * k as f32 / n as f32 };
    let mut vid = |soup: &mut PolygonSoup, c: [usize; 3]| {
        *index.entry(c).or_insert_with(|| {
            soup.vertex(Vec3::new(lerp(min.x, max.x, c[0]), lerp(min.y, max.y, c[1]), lerp(min.z, max.z, c[2])))
        })
    };
    // (normal axis, side, u axis, v axis) with u × v along the outward normal.
    let faces: [(usize, usize, usize, usize); 6] =
        [(0, n, 1, 2), (0, 0, 2, 1), (1, n, 2, 0), (1, 0, 0, 2), (2, n, 0, 1), (2, 0, 1, 0)];
    for (axis, side, u, v) in faces {
        for i in 0..n {
            for j in 0..n {
                let at = |a: usize, b: usize| {
                    let mut c = [0usize; 3];
                    c[axis] = side;
                    c[u] = a;
                    c[v] = b;
                    c
                };
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                let poly: Vec<u32> = q.iter().map(|c| vid(&mut soup, *c)).collect();
                soup.polygons.push(poly);
            }
        }
    }
    soup
}

/// A cube of side `size` centred at the origin, `n` quads per edge.
pub fn cube(size: f32, n: usize) -> PolygonSoup {
    box_soup(Vec3::splat(-size / 2.0), Vec3::splat(size / 2.0), n)
}

/// A square grid in the XZ plane (normal +Y) of side `size`, `n` × `n` quads, centred at the origin.
pub fn plane(size: f32, n: usize) -> PolygonSoup {
    let n = n.max(1);
    let mut soup = PolygonSoup::default();
    let c = |k: usize| -size / 2.0 + size * k as f32 / n as f32;
    for j in 0..=n {
        for i in 0..=n {
            soup.vertex(Vec3::new(c(i), 0.0, c(j)));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +Y: x then −z.
            soup.polygons.push(vec![id(i, j + 1), id(i + 1, j + 1), id(i + 1, j), id(i, j)]);
        }
    }
    soup
}

/// A UV sphere of `radius` with `n` rings (at least 3) and `2n` segments, poles on ±Y.
pub fn sphere(radius: f32, n: usize) -> PolygonSoup {
    let rings = n.max(3);
    let segs = 2 * rings;
    let mut soup = PolygonSoup::default();
    let top = soup.vertex(Vec3::new(0.0, radius, 0.0));
    for r in 1..rings {
        let phi = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segs {
            let th = std::f32::consts::TAU * s as f32 / segs as f32;
            soup.vertex(Vec3::new(radius * phi.sin() * th.cos(), radius * phi.cos(), -radius * phi.sin() * th.sin()));
        }
    }
    let bottom = soup.vertex(Vec3::new(0.0, -radius, 0.0));
    let id = |r: usize, s: usize| (1 + (r - 1) * segs + s % segs) as u32;
    for s in 0..segs {
        soup.polygons.push(vec![top, id(1, s), id(1, s + 1)]);
        for r in 1..rings - 1 {
            soup.polygons.push(vec![id(r, s), id(r + 1, s), id(r + 1, s + 1), id(r, s + 1)]);
        }
        soup.polygons.push(vec![id(rings - 1, s), bottom, id(rings - 1, s + 1)]);
    }
    soup
}

/// An open tube (no caps) of `radius` and `height` around +Y from y = 0, `segments` around and
/// `rows` along; its top and bottom rims are boundary edges.
pub fn cylinder(radius: f32, height: f32, segments: usize, rows: usize) -> PolygonSoup {
    let (segs, rows) = (segments.max(3), rows.max(1));
    let mut soup = PolygonSoup::default();
    for r in 0..=rows {
        for s in 0..segs {
            let th = std::f32::consts::TAU * s as f32 / segs as f32;
            soup.vertex(Vec3::new(radius * th.cos(), height * r as f32 / rows as f32, -radius * th.sin()));
        }
    }
    let id = |r: usize, s: usize| (r * segs + s % segs) as u32;
    for r in 0..rows {
        for s in 0..segs {
            soup.polygons.push(vec![id(r, s), id(r, s + 1), id(r + 1, s + 1), id(r + 1, s)]);
        }
    }
    soup
}

/// A house of `size` (its width): a box body with a gable roof (pentagonal gable walls, one closed
/// manifold) standing on y = 0, and a separate box garage beside it (a second component: fire only
/// reaches it when it is ignited too, §4.6).
pub fn house(size: f32) -> PolygonSoup {
    let (w, d, h, ridge) = (size / 2.0, size * 0.375, size * 0.6, size * 0.95);
    let mut soup = PolygonSoup::default();
    let b = [Vec3::new(-w, 0.0, d), Vec3::new(w, 0.0, d), Vec3::new(w, 0.0, -d), Vec3::new(-w, 0.0, -d)];
    let base: Vec<u32> = b.iter().map(|p| soup.vertex(*p)).collect();
    let eave: Vec<u32> = b.iter().map(|p| soup.vertex(Vec3::new(p.x, h, p.z))).collect();
    let r0 = soup.vertex(Vec3::new(-w, ridge, 0.0));
    let r1 = soup.vertex(Vec3::new(w, ridge, 0.0));
    soup.polygons.push(vec![base[0], base[3], base[2], base[1]]); // floor, facing down
    soup.polygons.push(vec![base[0], base[1], eave[1], eave[0]]); // front (+z)
    soup.polygons.push(vec![base[2], base[3], eave[3], eave[2]]); // back (−z)
    soup.polygons.push(vec![base[1], base[2], eave[2], r1, eave[1]]); // gable +x (pentagon)
    soup.polygons.push(vec![base[3], base[0], eave[0], r0, eave[3]]); // gable −x (pentagon)
    soup.polygons.push(vec![eave[0], eave[1], r1, r0]); // front roof
    soup.polygons.push(vec![eave[2], eave[3], r0, r1]); // back roof
    let gap = size * 0.1;
    let garage = box_soup(Vec3::new(w + gap, 0.0, -d * 0.8), Vec3::new(w + gap + size * 0.55, h * 0.75, d * 0.8), 1);
    soup.append(&garage);
    soup
}

/// A closed log: a prism of `segments` sides and `radius` around the horizontal axis at `yaw`
/// radians from +x through `centre`, `length` long, cut into `rows` along its length (so flame
/// light on it varies along the log), with flat end caps; outward, counter-clockwise.
pub fn log(centre: Vec3, yaw: f32, length: f32, radius: f32, segments: usize, rows: usize) -> PolygonSoup {
    let (segs, rows) = (segments.max(3), rows.max(1));
    let axis = Vec3::new(yaw.cos(), 0.0, -yaw.sin());
    // A right-handed frame (u, v, axis): u × v = axis.
    let u = Vec3::Y;
    let v = axis.cross(u);
    let mut soup = PolygonSoup::default();
    for r in 0..=rows {
        let along = length * (r as f32 / rows as f32 - 0.5);
        for k in 0..segs {
            let th = std::f32::consts::TAU * k as f32 / segs as f32;
            soup.vertex(centre + axis * along + (u * th.cos() + v * th.sin()) * radius);
        }
    }
    let id = |r: usize, k: usize| (r * segs + k % segs) as u32;
    for r in 0..rows {
        for k in 0..segs {
            soup.polygons.push(vec![id(r, k), id(r, k + 1), id(r + 1, k + 1), id(r + 1, k)]);
        }
    }
    soup.polygons.push((0..segs).rev().map(|k| id(0, k)).collect());
    soup.polygons.push((0..segs).map(|k| id(rows, k)).collect());
    soup
}

/// A campfire's logs, `size` across, resting on y = 0: two crossed layers of two logs (a log
/// cabin) and two shorter logs leaning diagonally on top, each a closed [`log`] (separate
/// components that interpenetrate a little where they rest on each other).
pub fn logs(size: f32, segments: usize) -> PolygonSoup {
    let r = size * 0.08;
    let mut soup = PolygonSoup::default();
    let q = std::f32::consts::FRAC_PI_4;
    let placed = [
        (Vec3::new(0.0, r, size * 0.24), 0.0, size),
        (Vec3::new(0.0, r, -size * 0.24), 0.0, size),
        (Vec3::new(size * 0.24, r * 2.6, 0.0), 2.0 * q, size),
        (Vec3::new(-size * 0.24, r * 2.6, 0.0), 2.0 * q, size),
        (Vec3::new(0.0, r * 4.1, 0.0), q, size * 0.7),
        (Vec3::new(0.0, r * 4.6, 0.0), -q, size * 0.7),
    ];
    for (centre, yaw, length) in placed {
        soup.append(&log(centre, yaw, length, r, segments.max(6), 6));
    }
    soup
}

/// Splits every polygon into triangles (fans), then every triangle into four `levels` times
/// (edge midpoints shared between neighbours, so the mesh stays watertight). Polygon ids are kept.
fn subdivide(positions: &mut Vec<Vec3>, tris: &mut Vec<[u32; 3]>, polys: &mut Vec<u32>, levels: usize) {
    for _ in 0..levels {
        let mut mids: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            let key = (a.min(b), a.max(b));
            *mids.entry(key).or_insert_with(|| {
                positions.push((positions[a as usize] + positions[b as usize]) * 0.5);
                (positions.len() - 1) as u32
            })
        };
        let mut out = Vec::with_capacity(tris.len() * 4);
        let mut out_polys = Vec::with_capacity(tris.len() * 4);
        for (t, &[a, b, c]) in tris.iter().enumerate() {
            let (ab, bc, ca) = (mid(a, b, positions), mid(b, c, positions), mid(c, a, positions));
            out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            out_polys.extend([polys[t]; 4]);
        }
        *tris = out;
        *polys = out_polys;
    }
}

fn fmt_v(p: Vec3) -> String {
    format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z)
}

/// Triangulates `soup` (fans), subdivides `levels` times, and builds face normals, face adjacency
/// and the per-edge rotations of Perry §3.3.2. With `strict`, degenerate faces, edges shared by
/// more than two faces and neighbours of opposite winding are errors naming the face; without,
/// degenerate triangles are dropped and bad edges become boundaries.
pub fn build_mesh(soup: &PolygonSoup, levels: usize, strict: bool) -> Result<Mesh, String> {
    if soup.polygons.is_empty() {
        return Err("the mesh has no faces".into());
    }
    if let Some(p) = soup.positions.iter().find(|p| !p.is_finite()) {
        return Err(format!("a vertex position is not finite: {}", fmt_v(*p)));
    }
    let mut positions = soup.positions.clone();
    let (mut tris, mut polys) = fan_triangles(soup, strict)?;
    subdivide(&mut positions, &mut tris, &mut polys, levels);
    let normals: Vec<Vec3> = tris
        .iter()
        .map(|t| {
            let (a, b, c) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    let (neighbors, rotations) = adjacency(&positions, &tris, &polys, &normals, strict)?;
    Ok(Mesh {
        positions: positions.iter().map(|p| p.to_array()).collect(),
        triangles: tris,
        normals: normals.iter().map(|n| n.to_array()).collect(),
        neighbors,
        edge_rotations: rotations,
        polygons: polys,
    })
}

/// The polygons of `soup` as fans of triangles, with each triangle's polygon index; zero-area
/// polygons are errors naming the face with `strict`, else dropped (as are zero-area triangles).
fn fan_triangles(soup: &PolygonSoup, strict: bool) -> Result<(Vec<[u32; 3]>, Vec<u32>), String> {
    let n = soup.positions.len();
    let (lo, hi) = soup.positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(a, b), p| (a.min(*p), b.max(*p)));
    let diag2 = (hi - lo).length_squared().max(f32::MIN_POSITIVE);
    let positions = &soup.positions;
    let mut tris: Vec<[u32; 3]> = Vec::new();
    let mut polys: Vec<u32> = Vec::new();
    for (k, poly) in soup.polygons.iter().enumerate() {
        if let Some(i) = poly.iter().find(|i| **i as usize >= n) {
            return Err(format!("face {} refers to vertex {} but there are only {n} vertices", k + 1, i + 1));
        }
        let area: Vec3 = (1..poly.len().saturating_sub(1))
            .map(|i| {
                let (a, b, c) = (positions[poly[0] as usize], positions[poly[i] as usize], positions[poly[i + 1] as usize]);
                (b - a).cross(c - a)
            })
            .sum();
        if poly.len() < 3 || area.length_squared() <= 1e-14 * diag2 * diag2 {
            if strict {
                let corners: Vec<String> = poly.iter().map(|i| fmt_v(positions[*i as usize])).collect();
                return Err(format!(
                    "face {} is degenerate (zero area, {} vertices: {}); fix the model or turn `strict` off to drop it",
                    k + 1,
                    poly.len(),
                    corners.join(", ")
                ));
            }
            continue;
        }
        for i in 1..poly.len() - 1 {
            let t = [poly[0], poly[i], poly[i + 1]];
            let (a, b, c) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
            if (b - a).cross(c - a).length_squared() > 1e-14 * diag2 * diag2 {
                tris.push(t);
                polys.push(k as u32);
            }
        }
    }
    if tris.is_empty() {
        return Err("the mesh has no faces with a non-zero area".into());
    }
    Ok((tris, polys))
}

/// Per triangle, the neighbour across each edge ([`NO_NEIGHBOR`] on a boundary) and the
/// rotation (a quaternion) that carries a heading across that edge.
type Adjacency = (Vec<[u32; 3]>, Vec<[[f32; 4]; 3]>);

/// Face adjacency and the per-edge rotations of Perry §3.3.2 (the rotation carrying a heading
/// across each edge into the neighbour's plane). Neighbours of opposite winding and edges of more
/// than two faces are errors with `strict`, else boundaries.
fn adjacency(positions: &[Vec3], tris: &[[u32; 3]], polys: &[u32], normals: &[Vec3], strict: bool) -> Result<Adjacency, String> {
    let mut directed: HashMap<(u32, u32), (u32, u8)> = HashMap::with_capacity(tris.len() * 3);
    let mut uses: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3);
    let mut bad_edges: Vec<(u32, u32)> = Vec::new();
    for (t, tri) in tris.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            if let Some((other, _)) = directed.insert((a, b), (t as u32, e as u8)) {
                if strict {
                    return Err(format!(
                        "faces {} and {} both run along the edge {} → {} in the same direction: opposite winding \
                         or a non-manifold edge; fix the model or turn `strict` off",
                        polys[other as usize] + 1,
                        polys[t] + 1,
                        fmt_v(positions[a as usize]),
                        fmt_v(positions[b as usize])
                    ));
                }
                bad_edges.push((a, b));
            }
        }
    }
    if let Some(((a, b), count)) = uses.iter().filter(|(_, c)| **c > 2).min_by_key(|((a, b), _)| (*a, *b)) {
        if strict {
            let faces: Vec<String> = tris
                .iter()
                .enumerate()
                .filter(|(_, t)| t.contains(a) && t.contains(b))
                .map(|(i, _)| (polys[i] + 1).to_string())
                .collect();
            return Err(format!(
                "non-manifold edge {} – {} is shared by {count} faces ({}); fire spread needs at most two faces per edge",
                fmt_v(positions[*a as usize]),
                fmt_v(positions[*b as usize]),
                faces.join(", ")
            ));
        }
        bad_edges.extend(uses.iter().filter(|(_, c)| **c > 2).map(|(k, _)| *k));
    }
    let is_bad = |a: u32, b: u32| bad_edges.iter().any(|&(x, y)| (x, y) == (a, b) || (x, y) == (b, a));
    let mut neighbors = vec![[NO_NEIGHBOR; 3]; tris.len()];
    let mut rotations = vec![[[0.0, 0.0, 0.0, 1.0]; 3]; tris.len()];
    for (t, tri) in tris.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            if !bad_edges.is_empty() && is_bad(a, b) {
                continue;
            }
            if let Some(&(g, _)) = directed.get(&(b, a)) {
                neighbors[t][e] = g;
                let axis = (positions[b as usize] - positions[a as usize]).normalize_or_zero();
                let (nf, ng) = (normals[t], normals[g as usize]);
                let angle = nf.cross(ng).dot(axis).atan2(nf.dot(ng));
                rotations[t][e] = Quat::from_axis_angle(axis, angle).to_array();
            }
        }
    }
    Ok((neighbors, rotations))
}

fn obj_options() -> tobj::LoadOptions {
    tobj::LoadOptions { single_index: false, triangulate: false, ignore_points: true, ignore_lines: true }
}

fn parse_obj_text(text: &str) -> Result<Vec<tobj::Model>, tobj::LoadError> {
    let mut reader = std::io::BufReader::new(text.as_bytes());
    tobj::load_obj_buf(&mut reader, &obj_options(), |_| Err(tobj::LoadError::OpenFileFailed)).map(|(m, _)| m)
}

/// The 1-based line at which `text` stops parsing: the shortest prefix of lines that fails.
fn failing_line(text: &str) -> Option<usize> {
    let ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).chain(std::iter::once(text.len())).collect();
    let fails = |k: usize| parse_obj_text(&text[..ends[k]]).is_err();
    if !fails(ends.len() - 1) {
        return None;
    }
    let (mut lo, mut hi) = (0usize, ends.len() - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if fails(mid) { hi = mid } else { lo = mid + 1 }
    }
    Some(lo + 1)
}

/// Reads a Wavefront OBJ (triangles and polygons; objects welded where their vertices coincide).
/// Errors name the file and, for a parse error, the line and its text.
pub fn load_obj(path: &Path) -> Result<PolygonSoup, String> {
    pyrograph_core::limits::may_read(path)?;
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read OBJ file {}: {e}", path.display()))?;
    let models = parse_obj_text(&text).map_err(|e| match failing_line(&text) {
        Some(line) => format!(
            "OBJ file {} does not parse at line {line} ({e}): '{}'",
            path.display(),
            text.lines().nth(line - 1).unwrap_or("").trim()
        ),
        None => format!("OBJ file {} does not parse: {e}", path.display()),
    })?;
    let mut soup = PolygonSoup::default();
    for m in &models {
        let mesh = &m.mesh;
        let base = soup.positions.len() as u32;
        soup.positions.extend(mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        let arities: Vec<u32> =
            if mesh.face_arities.is_empty() { vec![3; mesh.indices.len() / 3] } else { mesh.face_arities.clone() };
        let mut at = 0usize;
        for a in arities {
            let end = at + a as usize;
            let Some(idx) = mesh.indices.get(at..end) else {
                return Err(format!(
                    "OBJ file {}: object '{}' has a face past the end of its index list",
                    path.display(),
                    m.name
                ));
            };
            let mut poly: Vec<u32> = idx.iter().map(|i| i + base).collect();
            // Respect authored vertex normals: a face wound against them is flipped.
            if !mesh.normals.is_empty() && mesh.normal_indices.len() >= end && poly.len() >= 3 {
                let vn: Vec3 = mesh.normal_indices[at..end]
                    .iter()
                    .filter_map(|&k| mesh.normals.get(3 * k as usize..3 * k as usize + 3))
                    .map(|n| Vec3::new(n[0], n[1], n[2]))
                    .sum();
                let p = |i: u32| soup.positions[i as usize];
                let geo: Vec3 = (1..poly.len() - 1).map(|i| (p(poly[i]) - p(poly[0])).cross(p(poly[i + 1]) - p(poly[0]))).sum();
                if geo.dot(vn) < 0.0 {
                    poly.reverse();
                }
            }
            soup.polygons.push(poly);
            at = end;
        }
    }
    if soup.polygons.is_empty() {
        return Err(format!("OBJ file {} has no faces (no 'f' lines)", path.display()));
    }
    soup.weld();
    Ok(soup)
}

pyrograph_core::choice! {
    /// Where `particles.mesh_load` takes its mesh from.
    pub enum MeshSource {
        /// A Wavefront OBJ file.
        Obj = "obj",
        /// [`cube`].
        Cube = "cube",
        /// [`plane`].
        Plane = "plane",
        /// [`sphere`].
        Sphere = "sphere",
        /// [`cylinder`].
        Cylinder = "cylinder",
        /// [`house`].
        House = "house",
        /// [`logs`]: a campfire's log pile.
        Logs = "logs",
    }
}

pyrograph_core::node! {
    /// A polygon mesh for fire spread (Perry 1994 §3.3.2): a Wavefront OBJ (through tobj; triangles and
    /// polygons, fan-triangulated) or a primitive (cube, plane grid, sphere, open cylinder, a house with a
    /// garage, a campfire's log pile). Face normals are computed from the winding (an OBJ face wound against its vertex normals is
    /// flipped); the loader builds face adjacency and, per edge, the rotation that takes one face's normal to
    /// its neighbour's, which carries spread headings across edges. Degenerate faces and non-manifold or
    /// inconsistently wound edges are errors naming the face (strict), or are dropped / made boundaries.
    #[node("particles.mesh_load", "Particles", Source)]
    pub struct MeshLoad {
        /// Where the mesh comes from.
        source: MeshSource = MeshSource::Cube,
        /// OBJ file (source = obj).
        path: InputPath = "".into(),
        /// Primitive size: cube side, plane side, sphere radius, cylinder radius, house width, log pile width.
        #[range(1e-6, 1e6)]
        size: f32 = 1.0,
        /// Cylinder height.
        #[range(1e-6, 1e6)]
        height: f32 = 2.0,
        /// Primitive resolution: quads per cube edge / plane side, sphere rings, cylinder rows; a log has
        /// 2·divisions + 2 sides.
        #[range(1, 512)]
        divisions: usize = 4,
        /// Split every triangle into four this many times (smoother lighting).
        #[range(0, 6)]
        subdivide: usize = 0,
        /// Uniform scale applied to the mesh.
        #[range(1e-6, 1e6)]
        scale: f32 = 1.0,
        /// Offset applied after scaling.
        translate: [f32; 3] = [0.0, 0.0, 0.0],
        /// Degenerate faces and non-manifold edges are errors (off: dropped / boundaries).
        strict: bool = true,
    }
    /// The triangle mesh with adjacency and edge rotations.
    -> mesh: Arc<Mesh>
}

impl Cook for MeshLoad {
    fn cook(self, _: &CookCtx) -> Result<Arc<Mesh>, NodeError> {
        let (size, div) = (self.size, self.divisions);
        let path_port = port!(MeshLoad, path);
        let mut soup = match self.source {
            MeshSource::Obj => {
                if self.path.as_os_str().is_empty() {
                    return Err(NodeError::port(path_port, "source is 'obj' but no OBJ file is set"));
                }
                load_obj(&self.path).map_err(|m| NodeError::port(path_port, m))?
            }
            MeshSource::Plane => plane(size, div),
            MeshSource::Sphere => sphere(size, div),
            MeshSource::Cylinder => cylinder(size, self.height, 4 * div, div),
            MeshSource::House => house(size),
            MeshSource::Logs => logs(size, 2 * div + 2),
            MeshSource::Cube => cube(size, div),
        };
        let t = Vec3::from_array(self.translate);
        for p in &mut soup.positions {
            *p = *p * self.scale + t;
        }
        let mesh = build_mesh(&soup, self.subdivide, self.strict).map_err(|m| match self.source {
            MeshSource::Obj => NodeError::port(path_port, format!("{}: {m}", self.path.display())),
            _ => NodeError::port(port!(MeshLoad, source), m),
        })?;
        Ok(Arc::new(mesh))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn closed(m: &Mesh) -> bool {
        m.neighbors.iter().flatten().all(|n| *n != NO_NEIGHBOR)
    }

    #[test]
    fn primitives_are_watertight_and_consistently_wound() {
        let one_log = log(Vec3::new(0.3, 0.2, -0.1), 0.7, 1.5, 0.1, 8, 3);
        for (name, soup) in [("cube", cube(1.0, 3)), ("sphere", sphere(1.0, 6)), ("house", house(2.0)), ("log", one_log)] {
            let m = build_mesh(&soup, 0, true).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(closed(&m), "{name} is closed");
            // Outward normals: the face centre moves away from the mesh centre along the normal.
            let c: Vec3 = m.positions.iter().map(|p| Vec3::from_array(*p)).sum::<Vec3>() / m.positions.len() as f32;
            if name != "house" {
                for (t, tri) in m.triangles.iter().enumerate() {
                    let mid: Vec3 = tri.iter().map(|v| Vec3::from_array(m.positions[*v as usize])).sum::<Vec3>() / 3.0;
                    assert!((mid - c).dot(Vec3::from_array(m.normals[t])) > 0.0, "{name} face {t} faces outwards");
                }
            }
        }
        let pile = build_mesh(&logs(1.0, 10), 0, true).unwrap();
        assert!(closed(&pile), "every log is closed");
        assert_eq!(pile.triangles.len(), 6 * (10 * 6 * 2 + 2 * 8), "six logs of 10 sides, 6 rows, two 10-gon caps");
        let plane = build_mesh(&plane(2.0, 4), 0, true).unwrap();
        assert_eq!(plane.triangles.len(), 32);
        assert!(plane.normals.iter().all(|n| (Vec3::from_array(*n) - Vec3::Y).length() < 1e-6));
        let tube = build_mesh(&cylinder(1.0, 1.0, 16, 2), 0, true).unwrap();
        assert_eq!(tube.neighbors.iter().flatten().filter(|n| **n == NO_NEIGHBOR).count(), 32, "two open rims");
    }

    #[test]
    fn edge_rotations_take_each_normal_to_its_neighbours() {
        let m = build_mesh(&cube(1.0, 2), 1, true).unwrap();
        for t in 0..m.triangles.len() {
            for e in 0..3 {
                let g = m.neighbors[t][e] as usize;
                let q = Quat::from_array(m.edge_rotations[t][e]);
                let turned = q * Vec3::from_array(m.normals[t]);
                assert!((turned - Vec3::from_array(m.normals[g])).length() < 1e-5, "face {t} edge {e}");
            }
        }
    }

    #[test]
    fn bad_meshes_are_clear_errors() {
        let mut soup = cube(1.0, 1);
        soup.polygons.push(vec![0, 1, 0]);
        let e = build_mesh(&soup, 0, true).unwrap_err();
        assert!(e.contains("face 7 is degenerate"), "{e}");
        assert!(build_mesh(&soup, 0, false).is_ok());
        let mut soup = cube(1.0, 1);
        let first = soup.polygons[0].clone();
        soup.polygons.push(first.iter().rev().copied().collect());
        let e = build_mesh(&soup, 0, true).unwrap_err();
        assert!(e.contains("non-manifold") || e.contains("same direction"), "{e}");
        assert!(build_mesh(&PolygonSoup::default(), 0, true).unwrap_err().contains("no faces"));
    }

    #[test]
    fn obj_files_load_and_bad_ones_name_the_line() {
        let dir = std::env::temp_dir().join(format!("pyrograph-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("quad.obj");
        std::fs::write(&good, "# a square and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n")
            .unwrap();
        let m = build_mesh(&load_obj(&good).unwrap(), 0, true).unwrap();
        assert_eq!((m.triangles.len(), m.polygons.clone()), (3, vec![0, 0, 1]));
        let bad = dir.join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n").unwrap();
        let e = load_obj(&bad).unwrap_err();
        assert!(e.contains("bad.obj") && e.contains("line 3"), "{e}");
        let e = load_obj(&dir.join("missing.obj")).unwrap_err();
        assert!(e.contains("missing.obj"), "{e}");
        let empty = dir.join("empty.obj");
        std::fs::write(&empty, "v 0 0 0\n").unwrap();
        assert!(load_obj(&empty).unwrap_err().contains("no faces"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
