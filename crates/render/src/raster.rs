//! Draw lists and the band-parallel rasterizer.
//!
//! Geometry is transformed, clipped (near plane plus a guard band) and snapped to 1/256-pixel
//! fixed point when it is added to a [`DrawList`], and binned into horizontal bands of
//! [`BAND_ROWS`] rows. [`render`] then rasterizes the bands in parallel: each band walks its
//! primitives in submission order with integer edge functions and the top-left fill rule, so
//! triangles that share an edge (the fan of a fuzzy particle) never touch a pixel twice.
//! Opaque primitives are drawn first (depth test and write), blended ones after (depth test only).

use std::mem::MaybeUninit;
use std::sync::Arc;

use glam::{BVec4A, Mat4, Vec2, Vec3, Vec4, Vec4Swizzles};
use pyrograph_core::{Channels, Image};
use rayon::prelude::*;

use crate::camera::{Camera, CameraError};

/// Rows per band: the unit of parallel work.
pub const BAND_ROWS: usize = 16;
/// Sub-pixel precision: 1/256 pixel.
const SUB: i64 = 256;
/// Guard band: geometry is clipped to `|x|, |y| <= GUARD * w` in clip space, which keeps every
/// screen coordinate small enough for exact 64-bit edge functions.
const GUARD: f32 = 8.0;
/// Largest viewport side.
pub const MAX_SIZE: u32 = 16384;

/// How a primitive's colour combines with the framebuffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Blend {
    /// Replaces colour (alpha becomes 1) and writes depth: solid meshes.
    Opaque,
    /// Porter–Duff "over" with the source alpha.
    Over,
    /// Adds `rgb·a` and `a` to the framebuffer, each component saturating at 1 (Perry 1994 §3.2.2).
    Additive,
}

/// A world-space vertex with straight RGBA and texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// World position.
    pub position: Vec3,
    /// Straight RGBA.
    pub color: [f32; 4],
    /// Texture coordinates (0,0 top-left of the texture), ignored without a texture.
    pub uv: [f32; 2],
}

impl Vertex {
    /// A vertex without texture coordinates.
    pub fn new(position: Vec3, color: [f32; 4]) -> Self {
        Vertex { position, color, uv: [0.0, 0.0] }
    }
}

/// A screen-space vertex: pixel coordinates (x right, y down, pixel centres at +0.5), depth in 0..1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    /// Pixel x.
    pub x: f32,
    /// Pixel y.
    pub y: f32,
    /// Depth, 0 (near) to 1 (far).
    pub depth: f32,
    /// Straight RGBA.
    pub color: [f32; 4],
    /// Texture coordinates.
    pub uv: [f32; 2],
}

/// A camera and a viewport: everything needed to turn world geometry into pixels.
#[derive(Clone, Debug)]
pub struct View {
    camera: Camera,
    width: u32,
    height: u32,
    view_proj: Mat4,
}

impl View {
    /// A view of `width × height` pixels (each 1..=[`MAX_SIZE`]).
    pub fn new(camera: Camera, width: u32, height: u32) -> Result<Self, CameraError> {
        for (field, v) in [("width", width), ("height", height)] {
            if v == 0 || v > MAX_SIZE {
                return Err(CameraError { field, message: format!("must be 1..={MAX_SIZE} pixels, got {v}") });
            }
        }
        let view_proj = camera.projection_matrix(width as f32 / height as f32) * camera.view_matrix();
        Ok(View { camera, width, height, view_proj })
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Projection × view.
    pub fn view_proj(&self) -> Mat4 {
        self.view_proj
    }

    fn bands(&self) -> usize {
        (self.height as usize).div_ceil(BAND_ROWS)
    }

    /// Pixel coordinates and depth of a world point, `None` when it is not in front of the near plane.
    pub fn project(&self, p: Vec3) -> Option<Vec3> {
        let c = self.view_proj * p.extend(1.0);
        if c.z < 0.0 || c.w <= 0.0 {
            return None;
        }
        let s = self.to_screen(c);
        Some(Vec3::new(s.x, s.y, c.z / c.w))
    }

    fn to_screen(&self, c: Vec4) -> Vec2 {
        let iw = 1.0 / c.w;
        Vec2::new((c.x * iw * 0.5 + 0.5) * self.width as f32, (0.5 - c.y * iw * 0.5) * self.height as f32)
    }
}

/// A vertex in clip space, before the perspective divide.
#[derive(Clone, Copy, Debug)]
struct ClipVert {
    pos: Vec4,
    color: Vec4,
    uv: Vec2,
}

impl ClipVert {
    fn lerp(&self, o: &ClipVert, t: f32) -> ClipVert {
        ClipVert { pos: self.pos.lerp(o.pos, t), color: self.color.lerp(o.color, t), uv: self.uv.lerp(o.uv, t) }
    }
}

/// A snapped screen vertex; colour and uv are pre-multiplied by `iw` (1/w) for
/// perspective-correct interpolation.
#[derive(Clone, Copy, Debug)]
struct SVert {
    x: i64,
    y: i64,
    z: f32,
    iw: f32,
    c: [f32; 4],
    uv: [f32; 2],
}

#[derive(Clone, Copy, Debug)]
enum Prim {
    /// Three vertex indices; `tex` indexes the list's textures.
    Tri { v: [u32; 3], blend: Blend, tex: Option<u32> },
    /// A fuzzy particle: index into the list's scanline setups.
    Fan { fan: u32, blend: Blend },
}

/// The planes geometry is clipped against: near (`z >= 0`) and the guard band.
fn plane_distances(p: Vec4) -> [f32; 5] {
    [p.z, GUARD * p.w - p.x, GUARD * p.w + p.x, GUARD * p.w - p.y, GUARD * p.w + p.y]
}

fn inside_all(p: Vec4) -> bool {
    plane_distances(p).iter().all(|d| *d >= 0.0) && p.w > 0.0
}

/// Sutherland–Hodgman clipping of a convex polygon against the near and guard-band planes.
fn clip_polygon(mut poly: Vec<ClipVert>) -> Vec<ClipVert> {
    for plane in 0..5 {
        if poly.is_empty() {
            break;
        }
        let mut out = Vec::with_capacity(poly.len() + 2);
        for i in 0..poly.len() {
            let a = &poly[i];
            let b = &poly[(i + 1) % poly.len()];
            let da = plane_distances(a.pos)[plane];
            let db = plane_distances(b.pos)[plane];
            if da >= 0.0 {
                out.push(*a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a.lerp(b, da / (da - db)));
            }
        }
        poly = out;
    }
    poly
}

/// Most rim vertices a particle may have and still take the scanline fast path (its per-pixel
/// cost grows with the side count; Perry's particles have 3–20 sides).
const MAX_FAN: usize = 64;

/// One rim edge of a fuzzy particle, `[b, c, p, q, reach]`: the affine function
/// `L(p) = 1 + b·dx + c·dy` of the pixel offset `(dx, dy)` from the particle's centre, 1 at the
/// centre and 0 on the edge's line; that line's crossing of row `dy` at `dx = p + q·dy`
/// (`p = −1/b`, `q = −c/b`; both 0 for a horizontal edge); and how far from the centre its fan
/// triangle reaches, in pixels, signed so that the rows of its half it crosses are those with
/// `reach ≤ ±dy` (− for the rows above the centre, + below). Inside the fan triangle of the edge
/// `L` is exactly the centre vertex's barycentric weight.
type FanEdge = [f32; 5];

/// A fan edge during setup: the edge, the halves its triangle reaches (bit 0: rows at or above
/// the centre, bit 1: at or below), its side (0 left-facing, 1 right-facing, 2 horizontal) and the
/// y range of its ends relative to the centre, in pixels.
type KeptEdge = (FanEdge, u8, u8, (f32, f32));

/// Slack on [`FanEdge`]'s reach test, in pixels: taking an edge a row does not cross is harmless
/// (its `L` is not the smallest there), missing one is not.
const REACH_SLACK: f32 = 1e-3;

/// A fuzzy particle ready for scanline rasterization: a convex polygon around `(cx, cy)` whose
/// colour is `edge + (center − edge)·L` with `L = min_k L_k` (the Gouraud fan, computed per row
/// as the lower envelope of the rim edges' functions instead of triangle by triangle).
#[derive(Clone, Copy, Debug)]
struct FanSetup {
    cx: f32,
    cy: f32,
    /// Pixel rows touched, inclusive, clamped to the viewport.
    rows: (i32, i32),
    /// First of this fan's edges in `DrawList::fan_edges`: the edges whose fan triangles reach
    /// the rows at or above the centre (`dy ≤ 0`), then those reaching the rows at or below it (a
    /// row needs only the triangles it crosses); each half ordered left-facing (`b > 0`),
    /// right-facing (`b < 0`), then horizontal, with these counts.
    first: u32,
    counts: [[u8; 3]; 2],
    /// Alpha within [0, 1] and colour ≥ 0 at the centre and at the rim (so everywhere between):
    /// additive blending needs no clamping of the source.
    in_range: bool,
    /// Straight RGBA at the rim and centre − rim.
    edge: [f32; 4],
    delta: [f32; 4],
    /// Depth at the centre and its gradient in x and y per pixel (depth is affine in screen
    /// space over a planar polygon).
    z: [f32; 3],
}

/// Geometry ready for [`render`]: built on one thread, many lists may be built in parallel and
/// rendered together (in list order).
pub struct DrawList {
    view: View,
    verts: Vec<SVert>,
    prims: Vec<Prim>,
    fans: Vec<FanSetup>,
    fan_edges: Vec<FanEdge>,
    /// `fan_setup`'s per-edge working list, reused.
    fan_scratch: Vec<KeptEdge>,
    textures: Vec<Arc<Image>>,
    /// Per pass (0 opaque, 1 blended), per band, the primitives touching it in submission order.
    bins: [Vec<Vec<u32>>; 2],
    /// `(cos, sin)` of the rim angles for the last particle side count.
    ring: Vec<(f32, f32)>,
    /// The current disc's rim in clip space, reused.
    rim_clip: Vec<Vec4>,
    /// The current disc's centre and rim snapped to the screen, reused.
    rim_snapped: Vec<SVert>,
    /// `mesh`'s clip-space vertices and their snapped indices, reused.
    mesh_scratch: (Vec<ClipVert>, Vec<u32>),
}

/// A texture added to a [`DrawList`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureId(u32);

impl DrawList {
    /// An empty list for `view`.
    pub fn new(view: &View) -> Self {
        let bands = view.bands();
        DrawList {
            view: view.clone(),
            verts: Vec::new(),
            prims: Vec::new(),
            fans: Vec::new(),
            fan_edges: Vec::new(),
            fan_scratch: Vec::new(),
            textures: Vec::new(),
            bins: [vec![Vec::new(); bands], vec![Vec::new(); bands]],
            ring: Vec::new(),
            rim_clip: Vec::new(),
            rim_snapped: Vec::new(),
            mesh_scratch: (Vec::new(), Vec::new()),
        }
    }

    /// Makes room for `count` more particles of `sides` sides, so a list of many particles is
    /// not copied each time one of its arrays outgrows its capacity.
    pub fn reserve_particles(&mut self, count: usize, sides: u32) {
        self.prims.reserve(count);
        self.fans.reserve(count);
        // Each rim edge is kept once per half of the particle its fan triangle reaches: all of
        // them once, plus the (at most two) edges whose triangles span the centre row.
        self.fan_edges.reserve(count * (sides.min(MAX_FAN as u32) as usize + 2));
    }

    /// The view this list draws for.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// Number of primitives (triangles and particles) kept after clipping and culling.
    pub fn primitive_count(&self) -> usize {
        self.prims.len()
    }

    /// Makes `image` available to textured primitives (gray images are expanded to RGBA).
    pub fn add_texture(&mut self, image: &Arc<Image>) -> TextureId {
        let tex = if image.channels() == Channels::Rgba { image.clone() } else { Arc::new(image.to_rgba()) };
        self.textures.push(tex);
        TextureId(self.textures.len() as u32 - 1)
    }

    fn clip_vert(&self, v: &Vertex) -> ClipVert {
        ClipVert {
            pos: self.view.view_proj * v.position.extend(1.0),
            color: Vec4::from_array(v.color),
            uv: Vec2::from_array(v.uv),
        }
    }

    /// [`DrawList::snap`] of a position alone (colour and uv left zero).
    fn snap_position(&self, pos: Vec4) -> SVert {
        let iw = 1.0 / pos.w;
        let s = self.view.to_screen(pos);
        SVert { x: round_i64(s.x * SUB as f32), y: round_i64(s.y * SUB as f32), z: pos.z * iw, iw, c: [0.0; 4], uv: [0.0; 2] }
    }

    fn snap(&self, v: &ClipVert) -> SVert {
        let iw = 1.0 / v.pos.w;
        let s = self.view.to_screen(v.pos);
        SVert {
            x: round_i64(s.x * SUB as f32),
            y: round_i64(s.y * SUB as f32),
            z: v.pos.z * iw,
            iw,
            c: (v.color * iw).to_array(),
            uv: (v.uv * iw).to_array(),
        }
    }

    /// The pixel rows and bands covered by the bounding box of `verts`, `None` when it covers no pixel.
    fn pixel_rows<'v>(&self, verts: impl Iterator<Item = &'v SVert>) -> Option<(i64, i64)> {
        let (mut x0, mut x1, mut y0, mut y1) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        for v in verts {
            x0 = x0.min(v.x);
            x1 = x1.max(v.x);
            y0 = y0.min(v.y);
            y1 = y1.max(v.y);
        }
        let (w, h) = (self.view.width as i64, self.view.height as i64);
        let row0 = ceil_sub(y0 - SUB / 2).max(0);
        let row1 = floor_sub(y1 - SUB / 2).min(h - 1);
        let col0 = ceil_sub(x0 - SUB / 2).max(0);
        let col1 = floor_sub(x1 - SUB / 2).min(w - 1);
        (row0 <= row1 && col0 <= col1).then_some((row0, row1))
    }

    fn band_range<'v>(&self, verts: impl Iterator<Item = &'v SVert>) -> Option<(usize, usize)> {
        self.pixel_rows(verts).map(|(r0, r1)| (r0 as usize / BAND_ROWS, r1 as usize / BAND_ROWS))
    }

    fn push_prim(&mut self, prim: Prim, blend: Blend, bands: (usize, usize)) {
        let index = self.prims.len() as u32;
        self.prims.push(prim);
        let pass = usize::from(blend != Blend::Opaque);
        for band in bands.0..=bands.1 {
            self.bins[pass][band].push(index);
        }
    }

    fn push_clipped(&mut self, cv: [ClipVert; 3], blend: Blend, tex: Option<u32>) {
        if cv.iter().all(|v| inside_all(v.pos)) {
            let base = self.verts.len() as u32;
            for v in &cv {
                let s = self.snap(v);
                self.verts.push(s);
            }
            self.bin_tri([base, base + 1, base + 2], blend, tex);
            return;
        }
        let poly = clip_polygon(cv.to_vec());
        if poly.len() < 3 {
            return;
        }
        let base = self.verts.len();
        for v in &poly {
            let s = self.snap(v);
            self.verts.push(s);
        }
        for k in 1..poly.len() - 1 {
            let v = [base as u32, (base + k) as u32, (base + k + 1) as u32];
            self.bin_tri(v, blend, tex);
        }
    }

    fn bin_tri(&mut self, v: [u32; 3], blend: Blend, tex: Option<u32>) {
        if let Some(bands) = self.band_range(v.iter().map(|&i| &self.verts[i as usize])) {
            self.push_prim(Prim::Tri { v, blend, tex }, blend, bands);
        }
    }

    /// A Gouraud-shaded world-space triangle.
    pub fn triangle(&mut self, v: [Vertex; 3], blend: Blend) {
        let cv = v.map(|v| self.clip_vert(&v));
        self.push_clipped(cv, blend, None);
    }

    /// A textured world-space triangle: colour = vertex colour × bilinear texel.
    pub fn textured_triangle(&mut self, v: [Vertex; 3], texture: TextureId, blend: Blend) {
        if texture.0 as usize >= self.textures.len() {
            return;
        }
        let cv = v.map(|v| self.clip_vert(&v));
        self.push_clipped(cv, blend, Some(texture.0));
    }

    /// An indexed triangle mesh, optionally textured (colour = vertex colour × bilinear texel):
    /// every vertex is transformed and snapped once however many triangles share it, which is
    /// what makes dense meshes (cloth, a lit ground grid) cheap. Triangles with an index out of
    /// range, and a texture not added to this list, are skipped.
    pub fn mesh(&mut self, vertices: &[Vertex], triangles: &[[u32; 3]], texture: Option<TextureId>, blend: Blend) {
        if texture.is_some_and(|t| t.0 as usize >= self.textures.len()) {
            return;
        }
        let tex = texture.map(|t| t.0);
        let (mut clip, mut index) = std::mem::take(&mut self.mesh_scratch);
        clip.clear();
        clip.extend(vertices.iter().map(|v| self.clip_vert(v)));
        index.clear();
        self.verts.reserve(clip.len());
        self.prims.reserve(triangles.len());
        for cv in &clip {
            if inside_all(cv.pos) {
                index.push(self.verts.len() as u32);
                let s = self.snap(cv);
                self.verts.push(s);
            } else {
                index.push(u32::MAX);
            }
        }
        for t in triangles {
            if t.iter().any(|&i| i as usize >= clip.len()) {
                continue;
            }
            let v = t.map(|i| index[i as usize]);
            if v.iter().all(|&i| i != u32::MAX) {
                self.bin_tri(v, blend, tex);
            } else {
                self.push_clipped(t.map(|i| clip[i as usize]), blend, tex);
            }
        }
        self.mesh_scratch = (clip, index);
    }

    /// A textured quad with corners in order top-left, top-right, bottom-right, bottom-left of
    /// the texture, tinted by `tint` (straight RGBA).
    pub fn textured_quad(&mut self, corners: [Vec3; 4], texture: TextureId, tint: [f32; 4], blend: Blend) {
        let uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let v: Vec<Vertex> = corners.iter().zip(uv).map(|(p, uv)| Vertex { position: *p, color: tint, uv }).collect();
        self.textured_triangle([v[0], v[1], v[2]], texture, blend);
        self.textured_triangle([v[0], v[2], v[3]], texture, blend);
    }

    /// A camera-facing textured quad centred at `center` with half extents `half` (x right, y up).
    pub fn billboard(&mut self, center: Vec3, half: Vec2, texture: TextureId, tint: [f32; 4], blend: Blend) {
        let (r, u) = self.view.camera.billboard_axes(center);
        let (r, u) = (r * half.x, u * half.y);
        self.textured_quad([center - r + u, center + r + u, center + r - u, center - r - u], texture, tint, blend);
    }

    /// A fuzzy particle (Perry 1994 §3.2.1): a camera-facing N-gon of `sides` triangles around
    /// `center`, rim vertices on an ellipse of half extents `half` (billboard x and y), the centre
    /// vertex coloured `center_rgba` and the rim `edge_rgba`, Gouraud-shaded.
    ///
    /// A blended particle wholly inside the guard band is rasterized as one convex polygon, row
    /// by row (see [`FanSetup`]): every pixel is touched once and coloured exactly as its fan
    /// triangle's Gouraud interpolation would (in screen space, which for a camera-facing
    /// billboard differs from perspective-correct by far less than one 8-bit level).
    pub fn particle(&mut self, center: Vec3, half: Vec2, sides: u32, center_rgba: [f32; 4], edge_rgba: [f32; 4], blend: Blend) {
        if sides < 3 || !center.is_finite() || !half.is_finite() {
            return;
        }
        let (r, u) = self.view.camera.billboard_axes(center);
        self.disc(center, (r * half.x, u * half.y), sides, center_rgba, edge_rgba, blend);
    }

    /// A fuzzy disc in any plane: the N-gon of `sides` triangles around `center` with rim vertices
    /// at `center + axis_a·cos θ + axis_b·sin θ` (`axes` = `(axis_a, axis_b)`), coloured like [`DrawList::particle`] (which is
    /// the camera-facing case) and rasterized the same way. For small discs, such as char marks
    /// lying on a surface, screen-space interpolation differs from perspective-correct by far
    /// less than one 8-bit level.
    pub fn disc(
        &mut self,
        center: Vec3,
        (axis_a, axis_b): (Vec3, Vec3),
        sides: u32,
        center_rgba: [f32; 4],
        edge_rgba: [f32; 4],
        blend: Blend,
    ) {
        if sides < 3 || !center.is_finite() || !axis_a.is_finite() || !axis_b.is_finite() {
            return;
        }
        let vp = self.view.view_proj;
        // Projection is linear in homogeneous coordinates: project the centre and the two axes once.
        let c = vp * center.extend(1.0);
        let rc = vp * axis_a.extend(0.0);
        let uc = vp * axis_b.extend(0.0);
        let (cc, ec) = (Vec4::from_array(center_rgba), Vec4::from_array(edge_rgba));
        if self.ring.len() != sides as usize {
            let step = std::f32::consts::TAU / sides as f32;
            self.ring = (0..sides).map(|k| (k as f32 * step).sin_cos()).map(|(s, co)| (co, s)).collect();
        }
        let centre = ClipVert { pos: c, color: cc, uv: Vec2::ZERO };
        let ring_at = |k: usize, ring: &[(f32, f32)]| {
            let (co, s) = ring[k];
            ClipVert { pos: c + rc * co + uc * s, color: ec, uv: Vec2::ZERO }
        };
        let n = sides as usize;
        let mut rim = std::mem::take(&mut self.rim_clip);
        rim.clear();
        rim.extend(self.ring.iter().map(|&(co, s)| c + rc * co + uc * s));
        let all_inside = inside_all(c) && rim.iter().all(|&p| inside_all(p));
        if !all_inside {
            for k in 0..n {
                let (a, b) = (ring_at(k, &self.ring), ring_at((k + 1) % n, &self.ring));
                self.push_clipped([centre, a, b], blend, None);
            }
            self.rim_clip = rim;
            return;
        }
        if n <= MAX_FAN && blend != Blend::Opaque {
            // The scanline path needs positions only: snap them (no colours) into a reused list
            // (a fresh array per particle was 3 KB of zeroing each).
            let mut pts = std::mem::take(&mut self.rim_snapped);
            pts.clear();
            pts.push(self.snap_position(c));
            pts.extend(rim.iter().map(|&q| self.snap_position(q)));
            self.rim_clip = rim;
            let rows = self.pixel_rows(pts.iter());
            let fanned = rows.is_some_and(|rows| self.fan_setup(&pts, rows, center_rgba, edge_rgba));
            self.rim_snapped = pts;
            match (rows, fanned) {
                (None, _) => return,
                (Some(rows), true) => {
                    let bands = (rows.0 as usize / BAND_ROWS, rows.1 as usize / BAND_ROWS);
                    let fan = self.fans.len() as u32 - 1;
                    self.push_prim(Prim::Fan { fan, blend }, blend, bands);
                    return;
                }
                (Some(_), false) => {}
            }
        }
        let first = self.verts.len();
        let s = self.snap(&centre);
        self.verts.push(s);
        for k in 0..n {
            let s = self.snap(&ring_at(k, &self.ring));
            self.verts.push(s);
        }
        for k in 0..n {
            let v = [first as u32, (first + 1 + k) as u32, (first + 1 + (k + 1) % n) as u32];
            self.bin_tri(v, blend, None);
        }
    }

    /// Prepares the scanline form of the fan whose centre is `vs[0]` and rim the rest of `vs`;
    /// `false` (nothing pushed) when it cannot take that path: degenerate, not convex around its
    /// centre, beyond the far plane or too many sides.
    fn fan_setup(&mut self, vs: &[SVert], rows: (i64, i64), center: [f32; 4], edge: [f32; 4]) -> bool {
        let n = vs.len() - 1;
        if !(3..=MAX_FAN).contains(&n) {
            return false;
        }
        let (c, rim) = (&vs[0], &vs[1..]);
        if vs.iter().any(|v| !(0.0..=1.0).contains(&v.z)) {
            return false;
        }
        // Each kept edge with the halves its fan triangle reaches (bit 0: rows at or above the
        // centre, bit 1: at or below) and its side (0 left-facing, 1 right-facing, 2 horizontal).
        let mut kept = std::mem::take(&mut self.fan_scratch);
        kept.clear();
        let mut sign = 0i64;
        for k in 0..n {
            let (p, q) = (&rim[k], &rim[(k + 1) % n]);
            let (ex, ey) = (q.x - p.x, q.y - p.y);
            if ex == 0 && ey == 0 {
                continue; // Two rim vertices snapped together: the edge vanishes, its triangle too.
            }
            let ec = edge_fn(p, q, c.x, c.y);
            if ec == 0 || (sign != 0 && ec.signum() != sign) {
                self.fan_scratch = kept;
                return false;
            }
            sign = ec.signum();
            let (exf, eyf, ecf, sub) = (ex as f64, ey as f64, ec as f64, SUB as f64);
            // One division for all four coefficients: 1/ec = ey·r and 1/ey = ec·r.
            let edge = if ey != 0 {
                let r = 1.0 / (ecf * eyf);
                [-eyf * eyf * sub * r, exf * eyf * sub * r, ecf * ecf * r / sub, exf * ecf * r, 0.0].map(|v| v as f32)
            } else {
                [0.0, (exf * sub / ecf) as f32, 0.0, 0.0, 0.0]
            };
            let b = edge[0];
            let (py, qy) = (p.y - c.y, q.y - c.y);
            let halves = u8::from(py.min(qy) <= 0) | (u8::from(py.max(qy) >= 0) << 1);
            let side = if b > 0.0 {
                0
            } else if b < 0.0 {
                1
            } else {
                2
            };
            let (ymin, ymax) = (py.min(qy) as f32 / SUB as f32, py.max(qy) as f32 / SUB as f32);
            kept.push((edge, halves, side, (ymin, ymax)));
        }
        if kept.len() < 3 {
            self.fan_scratch = kept;
            return false;
        }
        let first = self.fan_edges.len();
        let mut counts = [[0u8; 3]; 2];
        for (half, count) in counts.iter_mut().enumerate() {
            for (side, count) in count.iter_mut().enumerate() {
                let group = self.fan_edges.len();
                for (e, halves, s, (ymin, ymax)) in &kept {
                    if halves & (1 << half) != 0 && usize::from(*s) == side {
                        let mut e = *e;
                        e[4] = if half == 0 { *ymin } else { -*ymax };
                        self.fan_edges.push(e);
                        *count += 1;
                    }
                }
                // Nearest reach first, so a row's edges are a prefix of the group.
                self.fan_edges[group..].sort_unstable_by(|a, b| a[4].total_cmp(&b[4]));
            }
        }
        self.fan_scratch = kept;
        // Depth plane through the centre and the two rim vertices spanning the largest area
        // (found with exact fixed-point cross products).
        let (x0, y0) = (rim[0].x - c.x, rim[0].y - c.y);
        let far = rim[1..].iter().max_by_key(|v| ((v.y - c.y) * x0 - (v.x - c.x) * y0).abs()).unwrap_or(&rim[0]);
        let px = |v: &SVert| ((v.x - c.x) as f64 / SUB as f64, (v.y - c.y) as f64 / SUB as f64, (v.z - c.z) as f64);
        let (p0, best) = (px(&rim[0]), px(far));
        let det = p0.0 * best.1 - best.0 * p0.1;
        let (gx, gy) = if det.abs() > 1e-9 {
            ((p0.2 * best.1 - best.2 * p0.1) / det, (p0.0 * best.2 - best.0 * p0.2) / det)
        } else {
            (0.0, 0.0)
        };
        let delta = std::array::from_fn(|i| center[i] - edge[i]);
        let in_range = [center, edge].iter().all(|c| (0.0..=1.0).contains(&c[3]) && c[..3].iter().all(|&v| v >= 0.0));
        self.fans.push(FanSetup {
            cx: c.x as f32 / SUB as f32,
            cy: c.y as f32 / SUB as f32,
            rows: (rows.0 as i32, rows.1 as i32),
            first: first as u32,
            counts,
            in_range,
            edge,
            delta,
            z: [c.z, gx as f32, gy as f32],
        });
        true
    }

    /// A triangle given directly in pixel coordinates (no camera, no perspective). Coordinates
    /// beyond ±65,536 pixels or not finite drop the triangle.
    pub fn screen_triangle(&mut self, v: [ScreenVertex; 3], blend: Blend) {
        if v.iter().any(|p| !(p.x.abs() <= 65_536.0 && p.y.abs() <= 65_536.0 && p.depth.is_finite())) {
            return;
        }
        let base = self.verts.len() as u32;
        for p in &v {
            self.verts.push(SVert {
                x: (p.x * SUB as f32).round() as i64,
                y: (p.y * SUB as f32).round() as i64,
                z: p.depth,
                iw: 1.0,
                c: p.color,
                uv: p.uv,
            });
        }
        self.bin_tri([base, base + 1, base + 2], blend, None);
    }

    #[inline(always)]
    fn raster_prim<const AVX2: bool>(&self, index: u32, band: &mut Band<'_>) {
        match self.prims[index as usize] {
            Prim::Tri { v, blend, tex } => {
                let tex = tex.and_then(|t| self.textures.get(t as usize)).map(|t| &**t);
                let [a, b, c] = v.map(|i| &self.verts[i as usize]);
                raster_tri::<true, AVX2>(band, a, b, c, blend, tex);
            }
            Prim::Fan { fan, blend } => {
                let f = &self.fans[fan as usize];
                let (first, [above, below]) = (f.first as usize, f.counts.map(|c| c.iter().map(|&n| n as usize).sum::<usize>()));
                let halves = [&self.fan_edges[first..first + above], &self.fan_edges[first + above..first + above + below]];
                match blend {
                    Blend::Additive if f.in_range => raster_fan::<AVX2, true>(band, f, halves, add_in_range),
                    Blend::Additive => raster_fan::<AVX2, false>(band, f, halves, |d, s| blend_vec4(d, s, Blend::Additive)),
                    Blend::Over => raster_fan::<AVX2, false>(band, f, halves, |d, s| blend_vec4(d, s, Blend::Over)),
                    Blend::Opaque => raster_fan::<AVX2, false>(band, f, halves, |d, s| blend_vec4(d, s, Blend::Opaque)),
                }
            }
        }
    }
}

/// Rounds half away from zero, without a libm call; saturates like `as`.
#[inline(always)]
fn round_i64(v: f32) -> i64 {
    (v + 0.5f32.copysign(v)) as i64
}

/// `floor(a / SUB)`.
fn floor_sub(a: i64) -> i64 {
    a >> 8
}

/// `ceil(a / SUB)`.
fn ceil_sub(a: i64) -> i64 {
    -((-a) >> 8)
}

const _: () = assert!(SUB == 1 << 8, "floor_sub and ceil_sub shift by log2(SUB)");

/// Rows `y0..y1` of the framebuffer.
struct Band<'a> {
    color: &'a mut [[f32; 4]],
    depth: &'a mut [f32],
    width: usize,
    y0: usize,
    y1: usize,
    /// Whether any opaque primitive touches this band (otherwise depth is 1 everywhere,
    /// blended primitives skip the depth test and `depth` is not used: `render_image` leaves it
    /// empty).
    has_opaque: bool,
}

/// `(b − a) × (p − a)` in fixed point: positive when `p` is on the inner side of a
/// positively-oriented triangle.
#[inline(always)]
fn edge_fn(a: &SVert, b: &SVert, px: i64, py: i64) -> i64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}

/// Top-left rule for an edge `a → b` of a positively oriented triangle (y down).
fn is_top_left(a: &SVert, b: &SVert) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Scanline rasterization of a fuzzy particle within one band. Per row: the span is the
/// intersection of the rim edges' half-planes `L_k ≥ 0` (pixel centres in `[x_left, x_right)`),
/// and the colour follows the lower envelope `min_k L_k` (inside the fan triangle of edge k,
/// `L_k` is the smallest; see [`fill_fan_span`]).
#[inline(always)]
fn raster_fan<const AVX2: bool, const ADD_IN_RANGE: bool>(
    band: &mut Band<'_>,
    f: &FanSetup,
    halves: [&[FanEdge]; 2],
    blend: impl Fn(&mut [f32; 4], Vec4),
) {
    let r0 = f.rows.0.max(band.y0 as i32);
    let r1 = f.rows.1.min(band.y1 as i32 - 1);
    let w = band.width as i32;
    let mut offsets = [[0.0f32; 2]; MAX_FAN];
    for y in r0..=r1 {
        let dy = y as f32 + 0.5 - f.cy;
        let half = usize::from(dy > 0.0);
        let (edges, [left, right, _]) = (halves[half], f.counts[half].map(usize::from));
        let (lefts, rest) = edges.split_at(left);
        let (rights, flats) = rest.split_at(right);
        // The edges whose fan triangles this row crosses: a prefix of each group.
        let limit = if half == 0 { dy } else { -dy } + REACH_SLACK;
        let (lefts, rights, flats) = (crossed(lefts, limit), crossed(rights, limit), crossed(flats, limit));
        // Where each edge's line crosses the row, relative to the centre: the span is right of
        // every left-facing edge's crossing and left of every right-facing one's.
        let cross = |&[_, _, p, q, _]: &FanEdge| p + q * dy;
        let xl = lefts.iter().map(cross).fold(f32::NEG_INFINITY, |m, x| if x > m { x } else { m });
        let xr = rights.iter().map(cross).fold(f32::INFINITY, |m, x| if x < m { x } else { m });
        // Written so an unbounded side (no such edge) also skips the row.
        if !(xl < xr && xl.is_finite() && xr.is_finite()) {
            continue;
        }
        let px0 = ceil_i32(f.cx + xl - 0.5).max(0);
        let px1 = (ceil_i32(f.cx + xr - 0.5) - 1).min(w - 1);
        if px0 > px1 {
            continue;
        }
        let line = (y as usize - band.y0) * band.width;
        let zrow = f.z[0] + f.z[2] * dy;
        let mut count = 0;
        // A loop per group: a chained iterator branched at every edge on which group it was in.
        for group in [lefts, rights, flats] {
            for [b, c, ..] in group {
                offsets[count] = [1.0 + c * dy, *b];
                count += 1;
            }
        }
        let env = &offsets[..count];
        let span = line + px0 as usize..line + px1 as usize + 1;
        let xd0 = px0 as f32 + 0.5 - f.cx;
        let z = (zrow + f.z[1] * xd0, f.z[1]);
        if band.has_opaque {
            fill_fan_span::<AVX2, ADD_IN_RANGE>(&mut band.color[span.clone()], Some(&band.depth[span]), xd0, z, env, f, &blend);
        } else {
            fill_fan_span::<AVX2, ADD_IN_RANGE>(&mut band.color[span], None, xd0, z, env, f, &blend);
        }
    }
}

/// The first edges of `group` (sorted by reach) that reach `limit`.
#[inline(always)]
fn crossed(group: &[FanEdge], limit: f32) -> &[FanEdge] {
    &group[..group.iter().take_while(|e| e[4] <= limit).count()]
}

/// `ceil(x)` for values well inside the `i32` range (no libm call without SSE4.1).
#[inline(always)]
fn ceil_i32(x: f32) -> i32 {
    let i = x as i32;
    i + i32::from((i as f32) < x)
}

/// Pixels per block of [`fill_fan_span`]: the lower envelope is evaluated for a block at a time
/// so the loop over edges vectorizes.
const FAN_LANES: usize = 8;

/// Blends one row span of a particle starting `xd0` pixels right of its centre: per pixel,
/// `L = min_k (offset_k + slope_k·xd)` over every rim edge, branch-free in blocks of
/// [`FAN_LANES`]. Walking the envelope sector by sector needs fewer multiplies but a
/// data-dependent branch per sector, and particles a few pixels wide cross a sector every
/// three pixels; measured 2–3× slower at 1,000 flames.
#[inline(always)]
fn fill_fan_span<const AVX2: bool, const ADD_IN_RANGE: bool>(
    color: &mut [[f32; 4]],
    depth: Option<&[f32]>,
    xd0: f32,
    (z0, dz): (f32, f32),
    env: &[[f32; 2]],
    f: &FanSetup,
    blend: &impl Fn(&mut [f32; 4], Vec4),
) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 && ADD_IN_RANGE && depth.is_none() {
        // SAFETY: `AVX2` is set only below `raster_band_avx2` (see `envelope`).
        unsafe { add_span_avx2(color, xd0, env, f.edge, f.delta) };
        return;
    }
    let (e, d) = (Vec4::from_array(f.edge), Vec4::from_array(f.delta));
    for (block, dst) in color.chunks_mut(FAN_LANES).enumerate() {
        let base = xd0 + (block * FAN_LANES) as f32;
        let xd: [f32; FAN_LANES] = std::array::from_fn(|i| base + i as f32);
        let l = envelope::<AVX2>(env, base);
        for (i, px) in dst.iter_mut().enumerate() {
            let visible = depth.is_none_or(|zb| z0 + dz * (xd[i] - xd0) <= zb[block * FAN_LANES + i]);
            if visible {
                blend(px, e + d * l[i].clamp(0.0, 1.0));
            }
        }
    }
}

/// The lower envelope `min_k (offset_k + slope_k·xd)` of a fan row's edges at the
/// [`FAN_LANES`] pixels `xd = base, base + 1, …` (offsets from the particle's centre).
/// `AVX2` is true only below [`raster_band_avx2`].
#[inline(always)]
fn envelope<const AVX2: bool>(env: &[[f32; 2]], base: f32) -> [f32; FAN_LANES] {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is set only on the path below `raster_band_avx2`, which runs only
        // after checking that the CPU supports AVX2.
        return unsafe { envelope_avx2(env, base) };
    }
    let xd: [f32; FAN_LANES] = std::array::from_fn(|i| base + i as f32);
    let mut l = [f32::INFINITY; FAN_LANES];
    for &[offset, slope] in env {
        for (li, &x) in l.iter_mut().zip(&xd) {
            *li = lane_min(offset + slope * x, *li);
        }
    }
    l
}

/// [`envelope`] in AVX2 with four running minima merged at the end. Written with intrinsics
/// because a single chain of `vminps` waits out its latency (4 cycles on recent Intel cores)
/// at every edge, and the compiler, given the independent chains in plain Rust, split them
/// across mismatched registers and branched on the merge (measured 13 % slower than one
/// chain); this form was 5 % faster at 1,000 flames. Bit-identical to the portable loop: the
/// same separate multiply and add per lane (no FMA), and the minimum of non-NaN values does
/// not depend on the order (`vminps(v, m)` keeps `m` when `v` is NaN, as `lane_min` does).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn envelope_avx2(env: &[[f32; 2]], base: f32) -> [f32; FAN_LANES] {
    lanes(envelope_m256(env, base))
}

/// The eight lanes of `v`, in order.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lanes(v: std::arch::x86_64::__m256) -> [f32; FAN_LANES] {
    // SAFETY: `__m256` and `[f32; 8]` are both 32 bytes of eight `f32` lanes in order.
    unsafe { std::mem::transmute::<std::arch::x86_64::__m256, [f32; FAN_LANES]>(v) }
}

/// [`envelope_avx2`] left in its register.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn envelope_m256(env: &[[f32; 2]], base: f32) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::{_mm256_add_ps, _mm256_min_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setr_ps};
    const _: () = assert!(FAN_LANES == 8, "one __m256 per block");
    let xd = _mm256_add_ps(_mm256_set1_ps(base), _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0));
    let line = |&[offset, slope]: &[f32; 2]| _mm256_add_ps(_mm256_set1_ps(offset), _mm256_mul_ps(_mm256_set1_ps(slope), xd));
    let mut m = [_mm256_set1_ps(f32::INFINITY); 4];
    let mut quads = env.chunks_exact(4);
    for quad in &mut quads {
        for (m, e) in m.iter_mut().zip(quad) {
            *m = _mm256_min_ps(line(e), *m);
        }
    }
    for (m, e) in m.iter_mut().zip(quads.remainder()) {
        *m = _mm256_min_ps(line(e), *m);
    }
    _mm256_min_ps(_mm256_min_ps(m[0], m[1]), _mm256_min_ps(m[2], m[3]))
}

/// `v` if it is below `m`, else `m`: written as a compare, not `f32::min`, so it lowers to one
/// `minps` (a NaN `v` never replaces `m`).
#[inline(always)]
fn lane_min(v: f32, m: f32) -> f32 {
    if v < m { v } else { m }
}

/// A span of [`fill_fan_span`] blended with [`add_in_range`] (`blend` there) and no depth test,
/// two pixels per AVX register instead of one per SSE register: the particles' usual case,
/// where the per-pixel blend had become the larger half of a fan row's time. Written for the
/// whole span (the constants set up once, the envelope kept in its register, the pixel pairs
/// addressed directly) because the per-block form's slicing and set-up cost as much as its
/// blending. The same operations in the same order per channel as the portable loop, so
/// bit-identical: the clamp as `min(1, max(0, l))` (what `f32::clamp` computes for a non-NaN
/// `l`; the envelope is never NaN), `edge + delta·l`, then `min(dst + src·[a, a, a, 1], 1)`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add_span_avx2(color: &mut [[f32; 4]], xd0: f32, env: &[[f32; 2]], edge: [f32; 4], delta: [f32; 4]) {
    use std::arch::x86_64::{
        _mm256_add_ps, _mm256_blend_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps, _mm256_mul_ps, _mm256_permutevar8x32_ps,
        _mm256_set1_ps, _mm256_setr_epi32, _mm256_setr_ps, _mm256_setzero_ps, _mm256_shuffle_ps, _mm256_storeu_ps,
    };
    let twice = |[x, y, z, w]: [f32; 4]| _mm256_setr_ps(x, y, z, w, x, y, z, w);
    let (one, e, d) = (_mm256_set1_ps(1.0), twice(edge), twice(delta));
    for (block, dst) in color.chunks_mut(FAN_LANES).enumerate() {
        let l = envelope_m256(env, xd0 + (block * FAN_LANES) as f32);
        let clamped = _mm256_min_ps(one, _mm256_max_ps(_mm256_setzero_ps(), l));
        let p = dst.as_mut_ptr().cast::<f32>();
        for k in 0..dst.len() / 2 {
            let k = 2 * k as i32;
            let lk = _mm256_permutevar8x32_ps(clamped, _mm256_setr_epi32(k, k, k, k, k + 1, k + 1, k + 1, k + 1));
            let src = _mm256_add_ps(e, _mm256_mul_ps(d, lk));
            let weight = _mm256_blend_ps::<0b1000_1000>(_mm256_shuffle_ps::<0xff>(src, src), one);
            // SAFETY: pixels `k` and `k + 1` are in `dst` (`k + 1 < dst.len()`), so `p + 4k` is
            // the start of their eight contiguous `f32`s; the unaligned load and store accept
            // any address.
            unsafe {
                let px = p.add(4 * k as usize);
                let sum = _mm256_add_ps(_mm256_loadu_ps(px), _mm256_mul_ps(src, weight));
                _mm256_storeu_ps(px, _mm256_min_ps(sum, one));
            }
        }
        if let Some(last) = dst.len().checked_sub(1).filter(|n| n % 2 == 0) {
            add_in_range(&mut dst[last], Vec4::from_array(edge) + Vec4::from_array(delta) * lanes(l)[last].clamp(0.0, 1.0));
        }
    }
}

/// Additive blending of a straight-alpha source already known to have alpha in [0, 1] and
/// colour ≥ 0 (see `FanSetup::in_range`): [`blend_pixel`]'s `Additive` without its clamps, four
/// lanes at once.
#[inline(always)]
fn add_in_range(dst: &mut [f32; 4], src: Vec4) {
    let weight = Vec4::select(BVec4A::new(true, true, true, false), src.wwww(), Vec4::ONE);
    *dst = (Vec4::from_array(*dst) + src * weight).min(Vec4::ONE).to_array();
}

#[inline(always)]
fn raster_tri<const SMALL: bool, const AVX2: bool>(
    band: &mut Band<'_>,
    a: &SVert,
    b: &SVert,
    c: &SVert,
    blend: Blend,
    tex: Option<&Image>,
) {
    let area = edge_fn(a, b, c.x, c.y);
    let (b, c, area) = match area.cmp(&0) {
        std::cmp::Ordering::Equal => return,
        std::cmp::Ordering::Less => (c, b, -area),
        std::cmp::Ordering::Greater => (b, c, area),
    };
    let x0 = ceil_sub(a.x.min(b.x).min(c.x) - SUB / 2).max(0);
    let x1 = floor_sub(a.x.max(b.x).max(c.x) - SUB / 2).min(band.width as i64 - 1);
    let y0 = ceil_sub(a.y.min(b.y).min(c.y) - SUB / 2).max(band.y0 as i64);
    let y1 = floor_sub(a.y.max(b.y).max(c.y) - SUB / 2).min(band.y1 as i64 - 1);
    if x0 > x1 || y0 > y1 {
        return;
    }
    // Edge functions at the first pixel centre (top-left bias folded in, so a pixel is covered
    // when all three are >= 0; the bias is below one fixed-point unit of area), and their steps.
    let (px, py) = (x0 * SUB + SUB / 2, y0 * SUB + SUB / 2);
    let edges = [(b, c), (c, a), (a, b)];
    let mut row = [0i64; 3];
    let mut dx = [0i64; 3];
    let mut dy = [0i64; 3];
    for (k, (p, q)) in edges.iter().enumerate() {
        row[k] = edge_fn(p, q, px, py) - i64::from(!is_top_left(p, q));
        dx[k] = -(q.y - p.y) * SUB;
        dy[k] = (q.x - p.x) * SUB;
    }
    let inv_area = 1.0 / area as f32;
    let [ca, cb, cc] = [a, b, c].map(|v| Vec4::from_array(v.c));
    let tex = tex.and_then(Texels::new);
    let depth_write = blend == Blend::Opaque;
    let depth_test = depth_write || band.has_opaque;
    if SMALL && x1 - x0 < SMALL_LANES as i64 && small_extent(a, b, c) {
        let tri = SmallTri {
            x0: x0 as usize,
            span: (x1 - x0) as usize,
            row: row.map(|r| r as i32),
            dx: dx.map(|d| d as i32),
            // The steps per row fit an `i32` like the edge functions (see `small_extent`).
            dy: dy.map(|d| d as i32),
            inv_area,
            z: [a.z, b.z, c.z],
            iw: [a.iw, b.iw, c.iw],
            u: [a.uv[0], b.uv[0], c.uv[0]],
            v: [a.uv[1], b.uv[1], c.uv[1]],
            colors: [ca, cb, cc],
        };
        let shade = PixelShade { tex: tex.as_ref(), blend, depth_test, depth_write };
        let rows = (y0 as usize, y1 as usize);
        // As many rows per tile as the box's width leaves lanes for: a dense cloth's triangles
        // are 2–4 pixels wide, so one row per call left most lanes empty.
        match tri.span {
            0..=1 => small_tri_tiles::<2, AVX2>(band, &tri, rows, &shade),
            2..=3 => small_tri_tiles::<4, AVX2>(band, &tri, rows, &shade),
            _ => small_tri_tiles::<8, AVX2>(band, &tri, rows, &shade),
        }
        return;
    }
    let wide = x1 - x0 >= 8;
    for y in y0..=y1 {
        let mut w = row;
        let line = (y as usize - band.y0) * band.width;
        let (mut lo, mut hi) = (x0, x1);
        if wide {
            // Jump to the covered run of the row: an edge with a positive x step holds from some
            // x on, one with a negative step up to some x.
            for k in 0..3 {
                if dx[k] > 0 && w[k] < 0 {
                    lo = lo.max(x0 + (-w[k] + dx[k] - 1) / dx[k]);
                } else if dx[k] < 0 {
                    hi = if w[k] < 0 { -1 } else { hi.min(x0 + w[k] / -dx[k]) };
                } else if dx[k] == 0 && w[k] < 0 {
                    hi = -1;
                }
            }
            if lo <= hi {
                for k in 0..3 {
                    w[k] += dx[k] * (lo - x0);
                }
            }
        }
        for x in lo..=hi {
            if w[0] >= 0 && w[1] >= 0 && w[2] >= 0 {
                let l1 = w[1] as f32 * inv_area;
                let l2 = w[2] as f32 * inv_area;
                let l0 = 1.0 - l1 - l2;
                let z = a.z * l0 + b.z * l1 + c.z * l2;
                let i = line + x as usize;
                if (0.0..=1.0).contains(&z) && (!depth_test || z <= band.depth[i]) {
                    let iw = a.iw * l0 + b.iw * l1 + c.iw * l2;
                    let inv = 1.0 / iw;
                    let mut src = (ca * l0 + cb * l1 + cc * l2) * inv;
                    if let Some(t) = &tex {
                        let u = (a.uv[0] * l0 + b.uv[0] * l1 + c.uv[0] * l2) * inv;
                        let v = (a.uv[1] * l0 + b.uv[1] * l1 + c.uv[1] * l2) * inv;
                        src *= t.sample(u, v);
                    }
                    blend_vec4(&mut band.color[i], src, blend);
                    if depth_write {
                        band.depth[i] = z;
                    }
                }
            }
            w[0] += dx[0];
            w[1] += dx[1];
            w[2] += dx[2];
        }
        row[0] += dy[0];
        row[1] += dy[1];
        row[2] += dy[2];
    }
}

/// Lanes of [`small_tri_tile`]: triangles whose bounding box is at most this many pixels wide
/// are rasterized a tile of rows at a time in vector lanes.
const SMALL_LANES: usize = 8;

/// Whether a triangle's edge functions, evaluated anywhere within its bounding box widened by
/// [`SMALL_LANES`] pixels (and one row), fit an `i32`: both sides of its box below 64 pixels
/// bound them by `2 · (64·SUB) · (73·SUB) < 2^31`, and their steps per row by `64·SUB²`.
/// (A tile of [`small_tri_tile`] reaches at most `SMALL_LANES / 2 − 1` rows below the box, and
/// the steps between tiles `SMALL_LANES / 2` rows, both inside that margin.)
#[inline(always)]
fn small_extent(a: &SVert, b: &SVert, c: &SVert) -> bool {
    let span = |p: i64, q: i64, r: i64| p.max(q).max(r) - p.min(q).min(r);
    span(a.x, b.x, c.x) < 64 * SUB && span(a.y, b.y, c.y) < 64 * SUB
}

/// A triangle set up for [`small_tri_tile`]: the edge functions at the first pixel of its box
/// (top-left bias folded in) and their x and y steps, in `i32` (see [`small_extent`]), and its
/// vertices' attributes (colour and uv pre-multiplied by `iw`).
struct SmallTri {
    x0: usize,
    /// Pixels of the box right of `x0` (`< SMALL_LANES`).
    span: usize,
    row: [i32; 3],
    dx: [i32; 3],
    dy: [i32; 3],
    inv_area: f32,
    z: [f32; 3],
    iw: [f32; 3],
    u: [f32; 3],
    v: [f32; 3],
    colors: [Vec4; 3],
}

/// How a covered pixel is shaded and blended.
struct PixelShade<'t, 'a> {
    tex: Option<&'t Texels<'a>>,
    blend: Blend,
    depth_test: bool,
    depth_write: bool,
}

/// The rows `rows.0..=rows.1` of a small triangle, in tiles of `W` pixels by
/// `SMALL_LANES / W` rows.
#[inline(always)]
fn small_tri_tiles<const W: usize, const AVX2: bool>(
    band: &mut Band<'_>,
    t: &SmallTri,
    rows: (usize, usize),
    shade: &PixelShade<'_, '_>,
) {
    let tall = (SMALL_LANES / W) as i32;
    let mut w = t.row;
    for y in (rows.0..=rows.1).step_by(SMALL_LANES / W) {
        small_tri_tile::<W, AVX2>(band, t, w, (y, rows.1 - y), shade);
        for (w, d) in w.iter_mut().zip(t.dy) {
            *w += d * tall;
        }
    }
}

/// One tile of a small triangle, `W` pixels wide from `t.x0` and `SMALL_LANES / W` rows down
/// from `y` (lane `i` is pixel `(i % W, i / W)`; lanes past `t.span` or past the last of the
/// `rows_left` rows are off): coverage, barycentric weights, depth, `1/w` and the texel
/// footprints of all [`SMALL_LANES`] pixels at once (vector lanes, branch-free), then colour,
/// texture and blending for the covered pixels only. Each lane does exactly the arithmetic of
/// the per-pixel loop of [`raster_tri`] (the edge functions are exact integers however they are
/// stepped), so the pixels are bit-identical to it; tiny triangles (a dense cloth or mesh far
/// from the camera covers 2–4 pixels per triangle) spend most of their time on coverage tests
/// and set-up that this does eight at a time.
#[inline(always)]
fn small_tri_tile<const W: usize, const AVX2: bool>(
    band: &mut Band<'_>,
    t: &SmallTri,
    w: [i32; 3],
    (y, rows_left): (usize, usize),
    shade: &PixelShade<'_, '_>,
) {
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    #[cfg(target_arch = "x86_64")]
    let lanes = if AVX2 {
        // SAFETY: `AVX2` is set only after checking that the CPU supports AVX2: on the path below
        // `raster_band_avx2`, and in the test that compares the tiles with the per-pixel loop.
        unsafe { tile_lanes_avx2::<W>(t, w, rows_left, shade.tex) }
    } else {
        tile_lanes::<W>(t, w, rows_left, shade.tex)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let lanes = tile_lanes::<W>(t, w, rows_left, shade.tex);
    let Some(TileShading { mask, l: [l0, l1, l2], z, inv, foot }) = lanes else { return };
    let mut mask = mask;
    let [ca, cb, cc] = t.colors;
    let first = (y - band.y0) * band.width + t.x0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let p = first + row[i] as usize * band.width + col[i] as usize;
        if !((0.0..=1.0).contains(&z[i]) && (!shade.depth_test || z[i] <= band.depth[p])) {
            continue;
        }
        let mut src = (ca * l0[i] + cb * l1[i] + cc * l2[i]) * inv[i];
        if let (Some(tx), Some(f)) = (shade.tex, &foot) {
            src *= tx.bilinear(f.x[i] as usize, f.y[i] as usize, f.tx[i], f.ty[i]);
        }
        blend_vec4(&mut band.color[p], src, shade.blend);
        if shade.depth_write {
            band.depth[p] = z[i];
        }
    }
}

/// What [`small_tri_tile`] needs per lane before shading: the covered lanes (bit `i` for lane
/// `i`), the barycentric weights, depth, `1/w` and, for a textured triangle, the texel footprints.
struct TileShading {
    mask: u32,
    l: [[f32; SMALL_LANES]; 3],
    z: [f32; SMALL_LANES],
    inv: [f32; SMALL_LANES],
    foot: Option<Footprints>,
}

/// The lanes of a tile of [`small_tri_tile`] whose top-left pixel has edge functions `w`;
/// `None` when it covers no pixel.
#[inline(always)]
fn tile_lanes<const W: usize>(t: &SmallTri, w: [i32; 3], rows_left: usize, tex: Option<&Texels<'_>>) -> Option<TileShading> {
    const N: usize = SMALL_LANES;
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    let mut we = [[0i32; N]; 3];
    for (e, we) in we.iter_mut().enumerate() {
        for i in 0..N {
            we[i] = w[e] + t.dx[e] * col[i] + t.dy[e] * row[i];
        }
    }
    // A pixel is covered when no edge function is negative: when their OR has no sign bit.
    let covered = (0..N).filter(|&i| (we[0][i] | we[1][i] | we[2][i]) >= 0);
    let mask = covered.fold(0u32, |m, i| m | 1 << i) & TileLanes::<W>::inside(t.span, rows_left);
    if mask == 0 {
        return None;
    }
    let (mut l0, mut l1, mut l2, mut z, mut inv) = ([0.0f32; N], [0.0f32; N], [0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        l1[i] = we[1][i] as f32 * t.inv_area;
        l2[i] = we[2][i] as f32 * t.inv_area;
        l0[i] = 1.0 - l1[i] - l2[i];
        z[i] = t.z[0] * l0[i] + t.z[1] * l1[i] + t.z[2] * l2[i];
        inv[i] = 1.0 / (t.iw[0] * l0[i] + t.iw[1] * l1[i] + t.iw[2] * l2[i]);
    }
    let foot = tex.map(|tx| {
        let (mut u, mut v) = ([0.0f32; N], [0.0f32; N]);
        for i in 0..N {
            u[i] = (t.u[0] * l0[i] + t.u[1] * l1[i] + t.u[2] * l2[i]) * inv[i];
            v[i] = (t.v[0] * l0[i] + t.v[1] * l1[i] + t.v[2] * l2[i]) * inv[i];
        }
        tx.footprints(&u, &v)
    });
    Some(TileShading { mask, l: [l0, l1, l2], z, inv, foot })
}

/// [`tile_lanes`] in AVX2 intrinsics, one register per quantity: the compiler left the
/// portable loops partly scalar (the coverage mask and the texel conversions lane by lane),
/// and a dense cloth's triangles spend most of their time here. Bit-identical to it: the same
/// exact integer edge functions, the same separate multiplies and adds in the same order (no
/// FMA), an exact division, and `max`/`min` operand orders that give `f32::clamp`'s result
/// for every input, a NaN included (see [`lane_floor`] and [`Texels::texel_coords`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn tile_lanes_avx2<const W: usize>(t: &SmallTri, w: [i32; 3], rows_left: usize, tex: Option<&Texels<'_>>) -> Option<TileShading> {
    use std::arch::x86_64::*;
    let (col, row) = (TileLanes::<W>::COL, TileLanes::<W>::ROW);
    // SAFETY: `[i32; 8]` is 32 bytes, what the unaligned load reads.
    let (col, row) = unsafe { (_mm256_loadu_si256(col.as_ptr().cast()), _mm256_loadu_si256(row.as_ptr().cast())) };
    let edge = |e: usize| {
        let steps = _mm256_add_epi32(
            _mm256_mullo_epi32(_mm256_set1_epi32(t.dx[e]), col),
            _mm256_mullo_epi32(_mm256_set1_epi32(t.dy[e]), row),
        );
        _mm256_add_epi32(_mm256_set1_epi32(w[e]), steps)
    };
    let (w0, w1, w2) = (edge(0), edge(1), edge(2));
    let signs = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_or_si256(_mm256_or_si256(w0, w1), w2))) as u32;
    let mask = !signs & 0xff & TileLanes::<W>::inside(t.span, rows_left);
    if mask == 0 {
        return None;
    }
    let inv_area = _mm256_set1_ps(t.inv_area);
    let l1 = _mm256_mul_ps(_mm256_cvtepi32_ps(w1), inv_area);
    let l2 = _mm256_mul_ps(_mm256_cvtepi32_ps(w2), inv_area);
    let l0 = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(1.0), l1), l2);
    let lerp = |k: [f32; 3]| {
        let a = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(k[0]), l0), _mm256_mul_ps(_mm256_set1_ps(k[1]), l1));
        _mm256_add_ps(a, _mm256_mul_ps(_mm256_set1_ps(k[2]), l2))
    };
    let (z, inv) = (lerp(t.z), _mm256_div_ps(_mm256_set1_ps(1.0), lerp(t.iw)));
    let foot = tex.map(|tx| {
        let coords = |uv: [f32; 3], size: usize| {
            let s = _mm256_mul_ps(_mm256_mul_ps(lerp(uv), inv), _mm256_set1_ps(size as f32));
            let f = _mm256_sub_ps(s, _mm256_set1_ps(0.5));
            // `clamp(0, size − 1)`: `max(0, f)` and `min(limit, ·)` keep their second operand,
            // so a NaN passes through as it does `f32::clamp`.
            let f = _mm256_min_ps(_mm256_set1_ps((size - 1) as f32), _mm256_max_ps(_mm256_setzero_ps(), f));
            // `lane_floor`: `max(f, 0)` turns a NaN into 0, then the limit, then truncation.
            let limited = _mm256_min_ps(_mm256_max_ps(f, _mm256_setzero_ps()), _mm256_set1_ps((1u32 << 30) as f32));
            let x = _mm256_cvttps_epi32(limited);
            (lanes_i32(x), lanes(_mm256_sub_ps(f, _mm256_cvtepi32_ps(x))))
        };
        let ((x, tx_), (y, ty)) = (coords(t.u, tx.width), coords(t.v, tx.height));
        Footprints { x, y, tx: tx_, ty }
    });
    Some(TileShading { mask, l: [lanes(l0), lanes(l1), lanes(l2)], z: lanes(z), inv: lanes(inv), foot })
}

/// The eight lanes of `v`, in order.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lanes_i32(v: std::arch::x86_64::__m256i) -> [i32; SMALL_LANES] {
    // SAFETY: `__m256i` and `[i32; 8]` are both 32 bytes of eight `i32` lanes in order.
    unsafe { std::mem::transmute::<std::arch::x86_64::__m256i, [i32; SMALL_LANES]>(v) }
}

/// The pixel of each lane of a tile `W` pixels wide: its column and row in the tile.
struct TileLanes<const W: usize>;

impl<const W: usize> TileLanes<W> {
    const COL: [i32; SMALL_LANES] = Self::lanes(true);
    const ROW: [i32; SMALL_LANES] = Self::lanes(false);

    const fn lanes(col: bool) -> [i32; SMALL_LANES] {
        let mut a = [0; SMALL_LANES];
        let mut i = 0;
        while i < SMALL_LANES {
            a[i] = if col { i % W } else { i / W } as i32;
            i += 1;
        }
        a
    }

    /// The lanes of the columns `0..=span` (`span < W`) of the rows `0..=rows_left` of the tile.
    #[inline(always)]
    fn inside(span: usize, rows_left: usize) -> u32 {
        // One row's columns, repeated in every row of the tile.
        let (one_row, every_row) = ((2u32 << span) - 1, Self::every_row());
        let rows = (rows_left + 1).min(SMALL_LANES / W);
        (one_row * every_row) & (u32::MAX >> (32 - rows * W))
    }

    /// Bit 0 of every row of the tile.
    const fn every_row() -> u32 {
        let mut m = 0;
        let mut r = 0;
        while r < SMALL_LANES / W {
            m |= 1 << (r * W);
            r += 1;
        }
        m
    }
}

/// `fx as usize` of [`Texels::sample_at`] for a clamped texel coordinate (`0 ≤ fx ≤ width − 1`,
/// or NaN, which gives 0), in a form that vectorizes: a plain truncating conversion, its
/// operand kept within `[0, 2^30]` so that it is always defined.
#[inline(always)]
fn lane_floor(fx: f32) -> i32 {
    const LIMIT: f32 = (1u32 << 30) as f32;
    let f = if fx > 0.0 { fx } else { 0.0 };
    let f = if f < LIMIT { f } else { LIMIT };
    // SAFETY: `f` is finite and within `[0, 2^30]`, so it truncates to an `i32` exactly.
    unsafe { f.to_int_unchecked::<i32>() }
}

/// Where the bilinear samples of [`SMALL_LANES`] pixels read ([`Texels::footprints`]): the
/// top-left texel of each and the weights of the texels right of and below it.
struct Footprints {
    x: [i32; SMALL_LANES],
    y: [i32; SMALL_LANES],
    tx: [f32; SMALL_LANES],
    ty: [f32; SMALL_LANES],
}

/// An RGBA texture's samples, checked once per triangle instead of once per pixel.
struct Texels<'a> {
    data: &'a [f32],
    width: usize,
    height: usize,
}

impl<'a> Texels<'a> {
    /// `None` for an empty or non-RGBA image (which samples as transparent black).
    #[inline(always)]
    fn new(img: &'a Image) -> Option<Texels<'a>> {
        let (width, height) = (img.width() as usize, img.height() as usize);
        (width > 0 && height > 0 && img.channels() == Channels::Rgba).then(|| Texels { data: img.data(), width, height })
    }

    /// Bilinear, clamp-to-edge sample at `(u, v)` (0,0 = top-left corner), four channels at once.
    #[inline(always)]
    fn sample(&self, u: f32, v: f32) -> Vec4 {
        let (fx, fy) = self.texel_coords(u, v);
        self.sample_at(fx, fy)
    }

    /// The texel-space position of `(u, v)`, clamped to the texel centres at the edges.
    #[inline(always)]
    fn texel_coords(&self, u: f32, v: f32) -> (f32, f32) {
        let (w, h) = (self.width, self.height);
        ((u * w as f32 - 0.5).clamp(0.0, (w - 1) as f32), (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32))
    }

    /// Bilinear sample at a position from [`Texels::texel_coords`].
    #[inline(always)]
    fn sample_at(&self, fx: f32, fy: f32) -> Vec4 {
        // Both ≥ 0 after the clamp (a NaN clamps to NaN and casts to 0): truncation is floor.
        let (x0, y0) = (fx as usize, fy as usize);
        self.bilinear(x0, y0, fx - x0 as f32, fy - y0 as f32)
    }

    /// [`Texels::sample_at`] of eight positions from [`Texels::texel_coords`] at once, as far
    /// as it goes without reading texels: in lanes, so the float-to-integer conversions (each a
    /// dozen scalar instructions, with their saturation checks) vectorize. The same values as
    /// `sample_at`'s: `max(fx, 0)` is `fx` for the clamped coordinates and 0 for a NaN, which
    /// `as usize` makes 0 too.
    #[inline(always)]
    fn footprints(&self, u: &[f32; SMALL_LANES], v: &[f32; SMALL_LANES]) -> Footprints {
        let mut f = Footprints { x: [0; SMALL_LANES], y: [0; SMALL_LANES], tx: [0.0; SMALL_LANES], ty: [0.0; SMALL_LANES] };
        for i in 0..SMALL_LANES {
            let (fx, fy) = self.texel_coords(u[i], v[i]);
            (f.x[i], f.y[i]) = (lane_floor(fx), lane_floor(fy));
            (f.tx[i], f.ty[i]) = (fx - f.x[i] as f32, fy - f.y[i] as f32);
        }
        f
    }

    /// The bilinear blend of texel `(x0, y0)` (inside the texture) and its neighbours right
    /// and below (clamped to the edge), with weights `tx` and `ty`.
    #[inline(always)]
    fn bilinear(&self, x0: usize, y0: usize, tx: f32, ty: f32) -> Vec4 {
        let (w, h) = (self.width, self.height);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let at = |x: usize, y: usize| {
            let i = (y * w + x) * 4;
            Vec4::from_slice(&self.data[i..i + 4])
        };
        let top = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
        let bottom = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

/// Bilinear, clamp-to-edge sample of an RGBA image at `(u, v)` (0,0 = top-left corner);
/// transparent black for an empty or non-RGBA image.
pub fn sample_bilinear(img: &Image, u: f32, v: f32) -> [f32; 4] {
    Texels::new(img).map_or([0.0; 4], |t| t.sample(u, v).to_array())
}

/// Blends straight-alpha `src` into the premultiplied framebuffer pixel `dst`.
pub fn blend_pixel(dst: &mut [f32; 4], src: [f32; 4], blend: Blend) {
    blend_vec4(dst, Vec4::from_array(src), blend);
}

/// [`blend_pixel`], four channels at once.
#[inline(always)]
fn blend_vec4(dst: &mut [f32; 4], src: Vec4, blend: Blend) {
    let a = src.w.clamp(0.0, 1.0);
    let rgb = BVec4A::new(true, true, true, false);
    let d = Vec4::from_array(*dst);
    *dst = match blend {
        Blend::Opaque => Vec4::select(rgb, src, Vec4::ONE),
        // rgb: src·a + dst·(1 − a); alpha: a + dst·(1 − a).
        Blend::Over => Vec4::select(rgb, src, Vec4::ONE) * a + d * (1.0 - a),
        Blend::Additive => (d + Vec4::select(rgb, src.max(Vec4::ZERO), Vec4::ONE) * a).min(Vec4::ONE),
    }
    .to_array();
}

/// A rendered frame: premultiplied RGBA and depth.
#[derive(Clone, Debug, PartialEq)]
pub struct Framebuffer {
    width: u32,
    height: u32,
    color: Vec<[f32; 4]>,
    depth: Vec<f32>,
}

impl Framebuffer {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Premultiplied RGBA of pixel `(x, y)`.
    pub fn premultiplied(&self, x: u32, y: u32) -> [f32; 4] {
        self.color[y as usize * self.width as usize + x as usize]
    }

    /// Depth of pixel `(x, y)` (1 where no opaque primitive was drawn).
    pub fn depth(&self, x: u32, y: u32) -> f32 {
        self.depth[y as usize * self.width as usize + x as usize]
    }

    /// The frame as a straight-alpha RGBA image. Additive light can make premultiplied colour
    /// exceed alpha; such pixels get `alpha = max(r, g, b)` so that compositing the image over
    /// black gives back exactly the rendered colour.
    pub fn to_image(&self) -> Image {
        let mut image = Image::new(self.width, self.height, Channels::Rgba);
        let w = self.width as usize;
        image
            .data_mut()
            .par_chunks_mut(w * 4 * BAND_ROWS)
            .zip(self.color.par_chunks(w * BAND_ROWS))
            .for_each(|(out, color)| write_straight(color, out));
        image
    }
}

/// Premultiplied pixels to straight-alpha RGBA samples (see [`Framebuffer::to_image`]).
fn write_straight(color: &[[f32; 4]], out: &mut [f32]) {
    let out = &mut out[..4 * color.len()];
    // SAFETY: `out` holds the four samples of every pixel of `color`.
    let done = unsafe { straight_vectorized(color, out.as_mut_ptr()) };
    for (p, o) in color[done..].iter().zip(out[4 * done..].chunks_exact_mut(4)) {
        o.copy_from_slice(&straight(*p));
    }
}

/// [`write_straight`] into samples not yet initialised; every sample of `out` (4 per pixel of
/// `color`) is written.
fn write_straight_uninit(color: &[[f32; 4]], out: &mut [MaybeUninit<f32>]) {
    let out = &mut out[..4 * color.len()];
    // SAFETY: `out` holds the four samples of every pixel of `color` (`MaybeUninit<f32>` has
    // the layout of `f32`), and only initialised values are written through the pointer.
    let done = unsafe { straight_vectorized(color, out.as_mut_ptr().cast()) };
    for (p, o) in color[done..].iter().zip(out[4 * done..].chunks_exact_mut(4)) {
        for (slot, v) in o.iter_mut().zip(straight(*p)) {
            slot.write(v);
        }
    }
}

/// Converts the first pixels of `color` with [`straight_pairs_avx2`] where the CPU has AVX2;
/// returns how many (the rest are left to [`straight`]).
///
/// # Safety
/// `out` must be valid for writes of `4 · color.len()` samples.
unsafe fn straight_vectorized(color: &[[f32; 4]], out: *mut f32) -> usize {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above; `out`'s extent is the caller's.
        return unsafe { straight_pairs_avx2(color, out) };
    }
    let _ = (color, out);
    0
}

/// [`straight`] for two pixels per AVX register, branch-free: the same operations as the
/// scalar form, which are SSE operations through glam (the alpha as `maxps` over the same
/// shuffles, `minps` against 1, `divps` by it), so bit-identical. Its two branches are one
/// here: for `a == 1` dividing by `a` changes nothing; `a ≤ 0` is masked to zero. Over a
/// 1280×720 frame the scalar form took about 15 instructions per pixel (a tenth of the
/// instructions of a 144-flame cloth frame's drawing). Returns the pixels converted (all but an
/// odd last one).
///
/// # Safety
/// The CPU must support AVX2, and `out` must be valid for writes of `4 · color.len()` samples.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn straight_pairs_avx2(color: &[[f32; 4]], out: *mut f32) -> usize {
    use std::arch::x86_64::{
        _CMP_GT_OQ, _mm256_and_ps, _mm256_blend_ps, _mm256_cmp_ps, _mm256_div_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
        _mm256_set1_ps, _mm256_setzero_ps, _mm256_shuffle_ps, _mm256_storeu_ps,
    };
    let one = _mm256_set1_ps(1.0);
    let pairs = color.len() / 2;
    for (k, pair) in color.chunks_exact(2).enumerate() {
        // SAFETY: `pair` is two pixels, eight contiguous `f32`s.
        let p = unsafe { _mm256_loadu_ps(pair.as_ptr().cast()) };
        // glam's `max_element`: lane 0 of each pixel ends up as the maximum of its four.
        let m = _mm256_max_ps(p, _mm256_shuffle_ps::<0b00_00_11_10>(p, p));
        let m = _mm256_max_ps(m, _mm256_shuffle_ps::<0b00_00_00_01>(m, m));
        // `f32::min(max, 1.0)`: a NaN maximum gives 1, as `minps` keeps its second operand.
        let a = _mm256_min_ps(_mm256_shuffle_ps::<0>(m, m), one);
        let rgb = _mm256_min_ps(_mm256_div_ps(p, a), one);
        let px = _mm256_and_ps(_mm256_blend_ps::<0b1000_1000>(rgb, a), _mm256_cmp_ps::<_CMP_GT_OQ>(a, _mm256_setzero_ps()));
        // SAFETY: pixels `2k` and `2k + 1` are within `color`, so their eight samples within `out`.
        unsafe { _mm256_storeu_ps(out.add(8 * k), px) };
    }
    2 * pairs
}

/// One premultiplied pixel as straight alpha.
#[inline(always)]
fn straight(p: [f32; 4]) -> [f32; 4] {
    let p = Vec4::from_array(p);
    let a = p.max_element().min(1.0);
    let rgb = BVec4A::new(true, true, true, false);
    if a == 1.0 {
        // The usual pixel over an opaque background (and every pixel of saturated additive
        // light): dividing by 1 changes nothing, so skip the division.
        Vec4::select(rgb, p.min(Vec4::ONE), Vec4::ONE).to_array()
    } else if a > 0.0 {
        Vec4::select(rgb, (p / a).min(Vec4::ONE), Vec4::splat(a)).to_array()
    } else {
        [0.0; 4]
    }
}

/// Rasterizes every list's primitives that touch band `bi` into `band`: opaque ones first
/// (depth test and write), then blended ones (depth test only where something opaque was drawn).
fn raster_band(lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above; the function only lets the compiler
        // vectorize safe code with it.
        return unsafe { raster_band_avx2(lists, view, bi, band) };
    }
    raster_band_generic::<false>(lists, view, bi, band)
}

/// [`raster_band_generic`] compiled for AVX2 (the particle envelope runs 8 lanes wide). Results
/// are bit-identical to the baseline build: no fused multiply-adds, no library calls.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn raster_band_avx2(lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    raster_band_generic::<true>(lists, view, bi, band)
}

#[inline(always)]
fn raster_band_generic<const AVX2: bool>(lists: &[DrawList], view: &View, bi: usize, band: &mut Band<'_>) {
    band.has_opaque = band_has_opaque(lists, view, bi);
    for pass in 0..2 {
        for list in lists.iter().filter(|l| usable(l, view)) {
            for &p in &list.bins[pass][bi] {
                list.raster_prim::<AVX2>(p, band);
            }
        }
    }
}

/// Whether `list` was built for a view of `view`'s size (others are skipped).
fn usable(list: &DrawList, view: &View) -> bool {
    list.view.width == view.width && list.view.height == view.height
}

/// Whether any opaque primitive touches band `bi`: only then is its depth buffer read or written.
fn band_has_opaque(lists: &[DrawList], view: &View, bi: usize) -> bool {
    lists.iter().any(|l| usable(l, view) && !l.bins[0][bi].is_empty())
}

fn premultiply(background: [f32; 4]) -> [f32; 4] {
    let a = background[3].clamp(0.0, 1.0);
    [background[0] * a, background[1] * a, background[2] * a, a]
}

/// Rasterizes `lists` (in order) over a `background` (straight RGBA), bands in parallel,
/// keeping the premultiplied colour and the depth of every pixel.
pub fn render(view: &View, lists: &[DrawList], background: [f32; 4]) -> Framebuffer {
    let (w, h) = (view.width as usize, view.height as usize);
    let mut color = vec![premultiply(background); w * h];
    let mut depth = vec![1.0f32; w * h];
    color.par_chunks_mut(w * BAND_ROWS).zip(depth.par_chunks_mut(w * BAND_ROWS)).enumerate().for_each(|(bi, (c, d))| {
        let y0 = bi * BAND_ROWS;
        let mut band = Band { y1: y0 + c.len() / w, color: c, depth: d, width: w, y0, has_opaque: false };
        raster_band(lists, view, bi, &mut band);
    });
    Framebuffer { width: view.width, height: view.height, color, depth }
}

/// [`render`] straight to an RGBA image (as [`Framebuffer::to_image`]), without keeping a
/// full-frame premultiplied buffer: each band is rasterized into a small per-thread buffer that
/// stays in cache and is converted as soon as it is done. This is the fast path of the
/// render nodes.
pub fn render_image(view: &View, lists: &[DrawList], background: [f32; 4]) -> Image {
    let w = view.width as usize;
    let len = w * view.height as usize * 4;
    let bg = premultiply(background);
    // Every sample is written below, so the frame is not zeroed first (zeroing 15 MB at
    // 1280×720 took 1.9 ms on one core, half the cost of an empty frame).
    let mut data: Vec<f32> = Vec::with_capacity(len);
    data.spare_capacity_mut()[..len].par_chunks_mut(w * 4 * BAND_ROWS).enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(color, depth): &mut (Vec<[f32; 4]>, Vec<f32>), (bi, out)| {
            let rows = out.len() / (4 * w);
            color.clear();
            color.resize(rows * w, bg);
            depth.clear();
            if band_has_opaque(lists, view, bi) {
                // Otherwise nothing reads or writes depth (see `Band::has_opaque`).
                depth.resize(rows * w, 1.0);
            }
            let y0 = bi * BAND_ROWS;
            let mut band = Band { color, depth, width: w, y0, y1: y0 + rows, has_opaque: false };
            raster_band(lists, view, bi, &mut band);
            write_straight_uninit(color, out);
        },
    );
    // SAFETY: the chunks cover `[0, len)` of the spare capacity exactly (`len` is a multiple of
    // `4·w`, each chunk `4·w·rows` samples), and `write_straight_uninit` writes all four samples
    // of each of the chunk's `w·rows` pixels; a panic in a band propagates before this line.
    unsafe { data.set_len(len) };
    Image::from_vec(view.width, view.height, Channels::Rgba, data)
        .unwrap_or_else(|| Image::new(view.width, view.height, Channels::Rgba))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn screen_view(w: u32, h: u32) -> View {
        let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, 0.1, 100.0).unwrap();
        View::new(cam, w, h).unwrap()
    }

    fn sv(x: f32, y: f32, depth: f32, color: [f32; 4]) -> ScreenVertex {
        ScreenVertex { x, y, depth, color, uv: [0.0, 0.0] }
    }

    const WHITE: [f32; 4] = [1.0, 1.0, 1.0, 1.0];

    #[test]
    fn one_triangle_covers_exactly_the_pixels_whose_centres_it_contains() {
        let view = screen_view(8, 8);
        let mut list = DrawList::new(&view);
        list.screen_triangle([sv(0.0, 0.0, 0.5, WHITE), sv(4.5, 0.0, 0.5, WHITE), sv(0.0, 4.5, 0.5, WHITE)], Blend::Over);
        let fb = render(&view, &[list], [0.0; 4]);
        let mut covered = 0;
        for y in 0..8 {
            for x in 0..8 {
                let a = fb.premultiplied(x, y)[3];
                assert_eq!(a, if x + y <= 3 { 1.0 } else { 0.0 }, "pixel ({x}, {y})");
                covered += (a > 0.0) as usize;
            }
        }
        assert_eq!(covered, 10);
    }

    #[test]
    fn colour_at_the_centroid_is_the_mean_of_the_vertex_colours() {
        let view = screen_view(12, 12);
        let mut list = DrawList::new(&view);
        let (r, g, b) = ([1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]);
        list.screen_triangle([sv(1.5, 1.5, 0.5, r), sv(10.5, 1.5, 0.5, g), sv(1.5, 10.5, 0.5, b)], Blend::Over);
        let px = render(&view, &[list], [0.0; 4]).premultiplied(4, 4);
        for (ch, want) in [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 1.0].iter().enumerate() {
            assert!((px[ch] - want).abs() < 1e-5, "channel {ch}: {px:?}");
        }
    }

    #[test]
    fn world_triangle_facing_the_camera_interpolates_barycentrically() {
        let view = screen_view(101, 101);
        let mut list = DrawList::new(&view);
        let (p0, p1, p2) = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        list.triangle(
            [Vertex::new(p0, [1.0, 0.0, 0.0, 1.0]), Vertex::new(p1, [0.0, 1.0, 0.0, 1.0]), Vertex::new(p2, [0.0, 0.0, 1.0, 1.0])],
            Blend::Over,
        );
        let s = view.project((p0 + p1 + p2) / 3.0).unwrap();
        let px = render(&view, &[list], [0.0; 4]).premultiplied(s.x as u32, s.y as u32);
        for ch in 0..3 {
            assert!((px[ch] - 1.0 / 3.0).abs() < 0.03, "{px:?}");
        }
    }

    #[test]
    fn additive_blending_saturates_at_one_and_not_beyond() {
        let view = screen_view(4, 4);
        let mut list = DrawList::new(&view);
        let c = [0.7, 0.3, 0.1, 0.6];
        for _ in 0..2 {
            list.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
        }
        let once = {
            let mut l = DrawList::new(&view);
            l.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
            render(&view, &[l], [0.0; 4]).premultiplied(0, 0)
        };
        let twice = render(&view, &[list], [0.0; 4]).premultiplied(0, 0);
        let expect_once = [0.42, 0.18, 0.06, 0.6];
        let expect_twice = [0.84, 0.36, 0.12, 1.0];
        for ch in 0..4 {
            assert!((once[ch] - expect_once[ch]).abs() < 1e-6, "{once:?}");
            assert!((twice[ch] - expect_twice[ch]).abs() < 1e-6, "{twice:?}");
        }
        // Many more layers: every component stops at exactly 1.
        let mut many = DrawList::new(&view);
        for _ in 0..20 {
            many.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
        }
        assert_eq!(render(&view, &[many], [0.0; 4]).premultiplied(0, 0), [1.0, 1.0, 1.0, 1.0]);
        let mut d = [0.9, 0.2, 0.0, 0.5];
        blend_pixel(&mut d, [1.0, 1.0, 1.0, 1.0], Blend::Additive);
        assert_eq!(d, [1.0, 1.0, 1.0, 1.0]);
    }

    #[test]
    fn depth_test_keeps_the_nearest_opaque_surface_in_either_order() {
        let view = screen_view(4, 4);
        let red = [1.0, 0.0, 0.0, 1.0];
        let green = [0.0, 1.0, 0.0, 1.0];
        let tri = |d: f32, c| [sv(-1.0, -1.0, d, c), sv(9.0, -1.0, d, c), sv(-1.0, 9.0, d, c)];
        for near_first in [true, false] {
            let mut list = DrawList::new(&view);
            if near_first {
                list.screen_triangle(tri(0.2, red), Blend::Opaque);
                list.screen_triangle(tri(0.5, green), Blend::Opaque);
            } else {
                list.screen_triangle(tri(0.5, green), Blend::Opaque);
                list.screen_triangle(tri(0.2, red), Blend::Opaque);
            }
            // Blended geometry behind the opaque surface is hidden, in front of it is seen,
            // even when submitted before the opaque surfaces.
            let mut glow = DrawList::new(&view);
            glow.screen_triangle(tri(0.8, [0.0, 0.0, 1.0, 1.0]), Blend::Additive);
            glow.screen_triangle(tri(0.1, [0.0, 0.5, 0.0, 1.0]), Blend::Additive);
            let fb = render(&view, &[glow, list], [0.0; 4]);
            assert_eq!(fb.premultiplied(1, 1), [1.0, 0.5, 0.0, 1.0], "near_first = {near_first}");
            assert_eq!(fb.depth(1, 1), 0.2);
        }
    }

    #[test]
    fn fan_triangles_share_edges_without_double_blending() {
        let view = screen_view(64, 64);
        let mut list = DrawList::new(&view);
        let c = [0.1, 0.1, 0.1, 1.0];
        list.particle(Vec3::ZERO, Vec2::splat(1.0), 20, c, c, Blend::Additive);
        let fb = render(&view, &[list], [0.0; 4]);
        let mut covered = 0;
        for y in 0..64 {
            for x in 0..64 {
                let p = fb.premultiplied(x, y);
                assert!(p[0] == 0.0 || (p[0] - 0.1).abs() < 1e-6, "pixel ({x}, {y}) = {p:?}");
                covered += (p[0] > 0.0) as usize;
            }
        }
        // A 20-gon of radius 1 at distance 5 with a 60° field of view: about π·11.1² pixels.
        assert!((300..420).contains(&covered), "{covered}");
    }

    /// The same particle drawn through the scanline fast path and as 20 screen-space Gouraud
    /// triangles (the definition): same pixels, same colours.
    #[test]
    fn scanline_particles_match_their_fan_of_triangles() {
        let view = screen_view(120, 90);
        let cases = [
            (Vec3::new(0.0, 0.0, 0.0), Vec2::new(1.0, 0.4), Blend::Additive),
            (Vec3::new(-2.9, 1.0, 0.5), Vec2::new(0.8, 1.3), Blend::Over),
            (Vec3::new(3.4, -1.2, -1.0), Vec2::new(1.07, 0.032), Blend::Additive),
            (Vec3::new(1.0, 1.5, 2.0), Vec2::new(0.05, 0.05), Blend::Additive),
        ];
        let (cc, ec) = ([1.0, 0.8, 0.3, 0.9], [0.6, 0.1, 0.0, 0.0]);
        for (center, half, blend) in cases {
            let mut fast = DrawList::new(&view);
            fast.particle(center, half, 20, cc, ec, blend);
            assert_eq!(fast.fans.len(), 1, "{center} takes the scanline path");
            let mut slow = DrawList::new(&view);
            let (r, u) = view.camera().billboard_axes(center);
            let s = |p: Vec3, c: [f32; 4]| {
                let q = view.project(p).unwrap();
                sv(q.x, q.y, q.z, c)
            };
            for k in 0..20 {
                let at = |k: usize| {
                    let a = std::f32::consts::TAU * (k % 20) as f32 / 20.0;
                    center + r * (half.x * a.cos()) + u * (half.y * a.sin())
                };
                slow.screen_triangle([s(center, cc), s(at(k), ec), s(at(k + 1), ec)], blend);
            }
            let (a, b) = (render(&view, &[fast], [0.0; 4]), render(&view, &[slow], [0.0; 4]));
            let (mut differ, mut lit) = (0, 0);
            for y in 0..90 {
                for x in 0..120 {
                    let (p, q) = (a.premultiplied(x, y), b.premultiplied(x, y));
                    lit += usize::from(q[3] > 0.0);
                    if (p[3] > 0.0) != (q[3] > 0.0) {
                        differ += 1;
                    } else {
                        for ch in 0..4 {
                            assert!((p[ch] - q[ch]).abs() < 2e-3, "{center}: ({x}, {y}) {p:?} vs {q:?}");
                        }
                    }
                }
            }
            // Pixel centres exactly on an edge may fall either way.
            assert!(differ <= 2, "{center}: {differ} of {lit} pixels covered by one and not the other");
            assert!(lit > 0 || half.y < 0.1, "{center}: draws something");
        }
    }

    #[test]
    fn particles_clipped_by_the_viewport_and_hidden_by_opaque_geometry() {
        let view = screen_view(64, 64);
        let c = [1.0, 1.0, 1.0, 1.0];
        // Half off the left side of the view: still a disc, brightest at the centre.
        let mut list = DrawList::new(&view);
        let centre = Vec3::new(-2.9, 0.0, 0.0);
        list.particle(centre, Vec2::splat(1.0), 20, c, [0.0, 0.0, 0.0, 0.0], Blend::Additive);
        let fb = render(&view, &[list], [0.0; 4]);
        let p = view.project(centre).unwrap();
        let (row, x_in) = (p.y as u32, (p.x.max(0.0) as u32).min(63));
        assert!(fb.premultiplied(0, row)[0] > 0.3, "{:?}", fb.premultiplied(0, row));
        assert!(fb.premultiplied(0, row)[0] <= fb.premultiplied(x_in, row)[0] + 1e-6);
        // Behind an opaque wall nothing shows; in front of it, everything does.
        for (z, seen) in [(-1.0, false), (1.0, true)] {
            let mut wall = DrawList::new(&view);
            let red = [1.0, 0.0, 0.0, 1.0];
            wall.triangle(
                [
                    Vertex::new(Vec3::new(-9.0, -9.0, 0.0), red),
                    Vertex::new(Vec3::new(9.0, -9.0, 0.0), red),
                    Vertex::new(Vec3::new(0.0, 9.0, 0.0), red),
                ],
                Blend::Opaque,
            );
            wall.particle(
                Vec3::new(0.0, 0.0, z),
                Vec2::splat(0.5),
                20,
                [0.0, 1.0, 0.0, 1.0],
                [0.0, 1.0, 0.0, 1.0],
                Blend::Additive,
            );
            let fb = render(&view, &[wall], [0.0; 4]);
            assert_eq!(fb.premultiplied(32, 32)[1] > 0.5, seen, "particle at z = {z}");
        }
    }

    #[test]
    fn render_image_equals_the_framebuffer_converted() {
        let view = screen_view(50, 37);
        let mut list = DrawList::new(&view);
        list.particle(Vec3::ZERO, Vec2::new(1.5, 1.0), 20, [1.0, 0.7, 0.2, 0.8], [0.8, 0.2, 0.0, 0.0], Blend::Additive);
        let g = [0.2, 0.3, 0.1, 1.0];
        let verts = [
            Vertex::new(Vec3::new(-3.0, -1.0, -2.0), g),
            Vertex::new(Vec3::new(3.0, -1.0, -2.0), g),
            Vertex::new(Vec3::new(3.0, -1.0, 2.0), g),
            Vertex::new(Vec3::new(-3.0, -1.0, 2.0), g),
        ];
        list.mesh(&verts, &[[0, 1, 2], [0, 2, 3], [0, 9, 2]], None, Blend::Opaque);
        let lists = [list];
        let bg = [0.0, 0.0, 0.1, 0.5];
        assert_eq!(render_image(&view, &lists, bg), render(&view, &lists, bg).to_image());
    }

    /// Whether this CPU runs the AVX2 paths.
    fn has_avx2() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx2")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// A small deterministic generator (no dependency for one test).
    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_envelope_is_bit_identical_to_the_portable_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2, so only the portable envelope runs");
            return;
        }
        // Every edge count a fan row can have up to 13 (each remainder of the four chains),
        // offsets and slopes of both signs, blocks left and right of the centre.
        let mut seed = 3u64;
        let mut lowered = 0;
        for edges in 0..=13 {
            for _ in 0..200 {
                let env: Vec<[f32; 2]> = (0..edges).map(|_| [2.0 * lcg(&mut seed) - 0.5, 0.6 * lcg(&mut seed) - 0.3]).collect();
                let base = 40.0 * lcg(&mut seed) - 20.0;
                let portable = envelope::<false>(&env, base);
                let avx2 = envelope::<true>(&env, base);
                assert_eq!(portable.map(f32::to_bits), avx2.map(f32::to_bits), "{edges} edges at {base}");
                lowered += usize::from(portable.iter().any(|v| v.is_finite()));
            }
        }
        // Guard against a vacuous pass: all rows but the empty ones have a finite envelope.
        assert_eq!(lowered, 13 * 200);
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn particles_rasterize_bit_identically_with_and_without_avx2() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2, so only the portable path runs");
            return;
        }
        // Particles from under a pixel to 40 px wide, 3 to 24 sides, additive in range (the
        // AVX2 blend path), additive out of range and "over", some over an opaque triangle
        // (the depth-tested path), spans of every length modulo the 8-pixel block.
        let view = screen_view(96, 64);
        let mut list = DrawList::new(&view);
        list.triangle(
            [
                Vertex::new(Vec3::new(-3.0, -3.0, -1.0), [0.2, 0.3, 0.4, 1.0]),
                Vertex::new(Vec3::new(0.5, -3.0, -1.0), [0.2, 0.3, 0.4, 1.0]),
                Vertex::new(Vec3::new(-3.0, 0.5, -1.0), [0.2, 0.3, 0.4, 1.0]),
            ],
            Blend::Opaque,
        );
        let mut seed = 11u64;
        for k in 0..600 {
            let center = Vec3::new(6.0 * lcg(&mut seed) - 3.0, 4.0 * lcg(&mut seed) - 2.0, lcg(&mut seed) - 0.5);
            let half = Vec2::new(0.01 + 0.6 * lcg(&mut seed), 0.01 + 0.6 * lcg(&mut seed));
            let sides = 3 + (lcg(&mut seed) * 22.0) as u32;
            let (c, e) = (
                [lcg(&mut seed), lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)],
                [lcg(&mut seed), 0.5, 0.1, 0.3 * lcg(&mut seed)],
            );
            let (blend, c) = match k % 5 {
                3 => (Blend::Additive, [1.5, c[1], c[2], c[3]]),
                4 => (Blend::Over, c),
                _ => (Blend::Additive, c),
            };
            list.particle(center, half, sides, c, e, blend);
        }
        let frame = |avx2: bool| {
            let (w, rows) = (96usize, 64usize);
            let (mut color, mut depth) = (vec![[0.05, 0.0, 0.1, 1.0]; w * rows], vec![1.0f32; w * rows]);
            for (bi, (c, d)) in color.chunks_mut(w * BAND_ROWS).zip(depth.chunks_mut(w * BAND_ROWS)).enumerate() {
                let y0 = bi * BAND_ROWS;
                let mut band = Band { y1: y0 + c.len() / w, color: c, depth: d, width: w, y0, has_opaque: false };
                let lists = std::slice::from_ref(&list);
                if avx2 {
                    // SAFETY: AVX2 support is checked at the top of this test.
                    unsafe { raster_band_avx2(lists, &view, bi, &mut band) };
                } else {
                    raster_band_generic::<false>(lists, &view, bi, &mut band);
                }
            }
            color.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        let (portable, avx2) = (frame(false), frame(true));
        let lit = portable.chunks(4).filter(|p| p[..3] != [0.05f32.to_bits(), 0, 0.1f32.to_bits()]).count();
        assert!(lit > 96 * 64 / 2, "most of the frame is drawn ({lit} pixels)");
        assert!(portable == avx2, "AVX2 and portable frames differ");
    }

    #[test]
    fn small_triangles_rasterize_bit_identically_to_the_general_loop() {
        // Random triangles up to 9 px wide (some take the 8-lane row path, some are too wide)
        // over a band, textured and not, with each blend and with a depth buffer to test against:
        // the row path must give exactly the same colours and depths as the per-pixel loop.
        let texture = Image::from_vec(5, 3, Channels::Rgba, (0..60).map(|i| (i % 7) as f32 / 6.0).collect()).unwrap();
        let (w, h) = (48usize, 16usize);
        let mut seed = 7u64;
        let mut small_path = 0;
        for blend in [Blend::Over, Blend::Additive, Blend::Opaque] {
            for textured in [false, true] {
                let depth0: Vec<f32> = (0..w * h).map(|_| 0.3 + 0.7 * lcg(&mut seed)).collect();
                let mut runs = Vec::new();
                // The per-pixel loop, the tiles in portable code, and in AVX2 where the CPU has it.
                let avx2 = has_avx2();
                for (small, vector) in [(false, false), (true, false), (true, true)] {
                    if vector && !avx2 {
                        continue;
                    }
                    let (mut color, mut depth) = (vec![[0.1, 0.2, 0.3, 0.4]; w * h], depth0.clone());
                    let mut band = Band { color: &mut color, depth: &mut depth, width: w, y0: 16, y1: 32, has_opaque: true };
                    let mut s = 99u64;
                    for _ in 0..400 {
                        let (cx, cy) = (-2.0 + 52.0 * lcg(&mut s), 13.0 + 22.0 * lcg(&mut s));
                        let vert = |s: &mut u64| {
                            let (x, y) = (cx + 9.0 * lcg(s) - 4.5, cy + 6.0 * lcg(s) - 3.0);
                            let iw = 0.5 + lcg(s);
                            let c = [lcg(s), lcg(s), lcg(s), lcg(s)].map(|v| v * iw);
                            SVert {
                                x: round_i64(x * 256.0),
                                y: round_i64(y * 256.0),
                                z: lcg(s),
                                iw,
                                c,
                                uv: [lcg(s) * iw, lcg(s) * iw],
                            }
                        };
                        let [a, b, c] = [vert(&mut s), vert(&mut s), vert(&mut s)];
                        let tex = textured.then_some(&texture);
                        if small && vector {
                            // AVX2 was detected above.
                            raster_tri::<true, true>(&mut band, &a, &b, &c, blend, tex);
                        } else if small {
                            raster_tri::<true, false>(&mut band, &a, &b, &c, blend, tex);
                        } else {
                            raster_tri::<false, false>(&mut band, &a, &b, &c, blend, tex);
                            let xs = [a.x, b.x, c.x];
                            let (lo, hi) = (xs.into_iter().min().unwrap_or(0), xs.into_iter().max().unwrap_or(0));
                            small_path += usize::from(floor_sub(hi - SUB / 2) - ceil_sub(lo - SUB / 2) < SMALL_LANES as i64);
                        }
                    }
                    runs.push((color, depth));
                }
                let bits = |(c, d): &(Vec<[f32; 4]>, Vec<f32>)| {
                    (
                        c.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        d.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    )
                };
                assert!(runs[0].0.iter().any(|p| *p != [0.1, 0.2, 0.3, 0.4]), "{blend:?}: nothing was drawn");
                for run in &runs[1..] {
                    assert_eq!(bits(&runs[0]), bits(run), "{blend:?}, textured {textured}");
                }
            }
        }
        assert!(small_path > 1000, "only {small_path} triangles were narrow enough for the row path");
    }

    #[test]
    fn a_mesh_draws_like_its_triangles() {
        let view = screen_view(40, 40);
        let (r, g, b) = ([1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]);
        let v = [
            Vertex::new(Vec3::new(-2.0, -2.0, 0.0), r),
            Vertex::new(Vec3::new(2.0, -2.0, 0.0), g),
            Vertex::new(Vec3::new(2.0, 2.0, 0.0), b),
            Vertex::new(Vec3::new(-2.0, 2.0, 0.0), g),
        ];
        let mut mesh = DrawList::new(&view);
        mesh.mesh(&v, &[[0, 1, 2], [0, 2, 3]], None, Blend::Over);
        let mut tris = DrawList::new(&view);
        tris.triangle([v[0], v[1], v[2]], Blend::Over);
        tris.triangle([v[0], v[2], v[3]], Blend::Over);
        assert_eq!(render(&view, &[mesh], [0.0; 4]), render(&view, &[tris], [0.0; 4]));
    }

    #[test]
    fn billboards_face_the_camera_from_any_side() {
        let white = Arc::new(Image::from_vec(1, 1, Channels::Rgba, vec![1.0; 4]).unwrap());
        // Seen from +x, a 2 × 2 billboard at distance 10 through a 90° lens on 100 px is 10 × 10 px.
        let cam = Camera::new(Vec3::new(10.0, 0.0, 0.0), Vec3::ZERO, Vec3::Y, 90.0, 0.1, 100.0).unwrap();
        let view = View::new(cam, 100, 100).unwrap();
        let mut list = DrawList::new(&view);
        let t = list.add_texture(&white);
        list.billboard(Vec3::ZERO, Vec2::ONE, t, WHITE, Blend::Over);
        let fb = render(&view, &[list], [0.0; 4]);
        let covered: Vec<(u32, u32)> =
            (0..100).flat_map(|y| (0..100).map(move |x| (x, y))).filter(|&(x, y)| fb.premultiplied(x, y)[3] > 0.0).collect();
        assert_eq!(covered.len(), 100);
        assert!(covered.iter().all(|&(x, y)| (45..55).contains(&x) && (45..55).contains(&y)));
        // The same quad fixed in the xy plane is seen edge-on and covers nothing.
        let mut flat = DrawList::new(&view);
        let t = flat.add_texture(&white);
        let q = [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
        flat.textured_quad(q, t, WHITE, Blend::Over);
        let fb = render(&view, &[flat], [0.0; 4]);
        assert!((0..100).all(|y| (0..100).all(|x| fb.premultiplied(x, y)[3] == 0.0)));
    }

    #[test]
    fn textured_quad_maps_the_texture_left_to_right() {
        let tex = Arc::new(Image::from_vec(2, 1, Channels::Rgba, vec![1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]).unwrap());
        let cam = Camera::new(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y, 90.0, 0.1, 10.0).unwrap();
        let view = View::new(cam, 20, 20).unwrap();
        let mut list = DrawList::new(&view);
        let t = list.add_texture(&tex);
        let q = [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
        list.textured_quad(q, t, WHITE, Blend::Over);
        let img = render(&view, &[list], [0.0; 4]).to_image();
        assert_eq!(img.pixel(1, 10), &[1.0, 0.0, 0.0, 1.0]);
        assert_eq!(img.pixel(18, 10), &[0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn geometry_through_the_near_plane_is_clipped_not_dropped() {
        let view = screen_view(32, 32);
        let mut list = DrawList::new(&view);
        // From behind the camera to far in front of it.
        let c = [1.0, 1.0, 1.0, 1.0];
        list.triangle(
            [
                Vertex::new(Vec3::new(-1.0, -0.5, 10.0), c),
                Vertex::new(Vec3::new(1.0, -0.5, 10.0), c),
                Vertex::new(Vec3::new(0.0, -0.5, -20.0), c),
            ],
            Blend::Over,
        );
        let fb = render(&view, &[list], [0.0; 4]);
        let covered =
            (0..32).flat_map(|y| (0..32).map(move |x| (x, y))).filter(|&(x, y)| fb.premultiplied(x, y)[3] > 0.0).count();
        assert!(covered > 0 && covered < 32 * 32, "{covered}");
        assert!(view.project(Vec3::new(0.0, 0.0, 6.0)).is_none());
    }

    #[test]
    fn the_vectorized_straight_alpha_conversion_is_bit_identical_to_the_scalar_one() {
        // Ordinary, saturated, over-bright, transparent, negative, tiny and NaN samples, in every
        // channel, and an odd count so the scalar remainder runs too.
        let special = [0.0, -0.0, 1.0, 0.5, 1.5, 1e-30, -0.25, 0.999_999_9, f32::NAN, f32::INFINITY];
        let mut seed = 3u64;
        let pick = |s: &mut u64| {
            let r = lcg(s);
            if r < 0.4 { special[(lcg(s) * special.len() as f32) as usize % special.len()] } else { 1.2 * lcg(s) }
        };
        let color: Vec<[f32; 4]> =
            (0..4001).map(|_| [pick(&mut seed), pick(&mut seed), pick(&mut seed), pick(&mut seed)]).collect();
        let mut out = vec![0.0f32; 4 * color.len()];
        write_straight(&color, &mut out);
        let mut uninit = vec![MaybeUninit::new(7.0f32); 4 * color.len()];
        write_straight_uninit(&color, &mut uninit);
        for (i, p) in color.iter().enumerate() {
            let want = straight(*p).map(f32::to_bits);
            assert_eq!(out[4 * i..4 * i + 4].iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want, "pixel {i}: {p:?}");
            // SAFETY: `write_straight_uninit` wrote every sample (and they started initialised).
            let got: Vec<u32> = uninit[4 * i..4 * i + 4].iter().map(|v| unsafe { v.assume_init() }.to_bits()).collect();
            assert_eq!(got, want, "pixel {i}: {p:?}");
        }
    }

    #[test]
    fn additive_light_over_black_round_trips_through_straight_alpha() {
        let view = screen_view(2, 2);
        let mut list = DrawList::new(&view);
        let c = [1.0, 0.5, 0.25, 0.5];
        list.screen_triangle([sv(-1.0, -1.0, 0.5, c), sv(5.0, -1.0, 0.5, c), sv(-1.0, 5.0, 0.5, c)], Blend::Additive);
        list.screen_triangle([sv(-1.0, -1.0, 0.5, c), sv(5.0, -1.0, 0.5, c), sv(-1.0, 5.0, 0.5, c)], Blend::Additive);
        let fb = render(&view, &[list], [0.0; 4]);
        assert_eq!(fb.premultiplied(0, 0), [1.0, 0.5, 0.25, 1.0]);
        assert_eq!(fb.to_image().pixel(0, 0), &[1.0, 0.5, 0.25, 1.0]);
    }
}
