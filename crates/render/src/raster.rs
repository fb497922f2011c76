//! Draw lists and the band-parallel rasterizer.
//!
//! Geometry is transformed, clipped (near plane plus a guard band) and snapped to 1/256-pixel
//! fixed point when it is added to a [`DrawList`], and binned into horizontal bands of
//! [`BAND_ROWS`] rows. [`render`] then rasterizes the bands in parallel: each band walks its
//! primitives in submission order with integer edge functions and the top-left fill rule, so
//! triangles that share an edge (the fan of a fuzzy particle) never touch a pixel twice.
//! Opaque primitives are drawn first (depth test and write), blended ones after (depth test only).

use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};
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
    /// A triangle fan: vertex `first` is the centre, the next `n` the closed rim.
    Fan { first: u32, n: u32, blend: Blend },
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

/// Geometry ready for [`render`]: built on one thread, many lists may be built in parallel and
/// rendered together (in list order).
pub struct DrawList {
    view: View,
    verts: Vec<SVert>,
    prims: Vec<Prim>,
    textures: Vec<Arc<Image>>,
    /// Per pass (0 opaque, 1 blended), per band, the primitives touching it in submission order.
    bins: [Vec<Vec<u32>>; 2],
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
            textures: Vec::new(),
            bins: [vec![Vec::new(); bands], vec![Vec::new(); bands]],
        }
    }

    /// The view this list draws for.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// Number of primitives (triangles and fans) kept after clipping and culling.
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

    fn snap(&self, v: &ClipVert) -> SVert {
        let iw = 1.0 / v.pos.w;
        let s = self.view.to_screen(v.pos);
        SVert {
            x: (s.x * SUB as f32).round() as i64,
            y: (s.y * SUB as f32).round() as i64,
            z: v.pos.z * iw,
            iw,
            c: (v.color * iw).to_array(),
            uv: (v.uv * iw).to_array(),
        }
    }

    /// The bands covered by the bounding box of `verts`, `None` when it covers no pixel.
    fn band_range<'v>(&self, verts: impl Iterator<Item = &'v SVert>) -> Option<(usize, usize)> {
        let (mut x0, mut x1, mut y0, mut y1) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        for v in verts {
            x0 = x0.min(v.x);
            x1 = x1.max(v.x);
            y0 = y0.min(v.y);
            y1 = y1.max(v.y);
        }
        let (w, h) = (self.view.width as i64, self.view.height as i64);
        let row0 = ceil_div(y0 - SUB / 2, SUB).max(0);
        let row1 = floor_div(y1 - SUB / 2, SUB).min(h - 1);
        let col0 = ceil_div(x0 - SUB / 2, SUB).max(0);
        let col1 = floor_div(x1 - SUB / 2, SUB).min(w - 1);
        (row0 <= row1 && col0 <= col1).then_some((row0 as usize / BAND_ROWS, row1 as usize / BAND_ROWS))
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
        let poly = if cv.iter().all(|v| inside_all(v.pos)) { cv.to_vec() } else { clip_polygon(cv.to_vec()) };
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
    pub fn particle(&mut self, center: Vec3, half: Vec2, sides: u32, center_rgba: [f32; 4], edge_rgba: [f32; 4], blend: Blend) {
        if sides < 3 || !center.is_finite() || !half.is_finite() {
            return;
        }
        let (r, u) = self.view.camera.billboard_axes(center);
        let vp = self.view.view_proj;
        // Projection is linear in homogeneous coordinates: project the centre and the two axes once.
        let c = vp * center.extend(1.0);
        let rc = vp * (r * half.x).extend(0.0);
        let uc = vp * (u * half.y).extend(0.0);
        let (cc, ec) = (Vec4::from_array(center_rgba), Vec4::from_array(edge_rgba));
        let step = std::f32::consts::TAU / sides as f32;
        let ring: Vec<ClipVert> = (0..sides)
            .map(|k| {
                let (s, co) = (k as f32 * step).sin_cos();
                ClipVert { pos: c + rc * co + uc * s, color: ec, uv: Vec2::ZERO }
            })
            .collect();
        let centre = ClipVert { pos: c, color: cc, uv: Vec2::ZERO };
        if inside_all(c) && ring.iter().all(|v| inside_all(v.pos)) {
            let first = self.verts.len();
            let s = self.snap(&centre);
            self.verts.push(s);
            for v in &ring {
                let s = self.snap(v);
                self.verts.push(s);
            }
            if let Some(bands) = self.band_range(self.verts[first..].iter()) {
                self.push_prim(Prim::Fan { first: first as u32, n: sides, blend }, blend, bands);
            } else {
                self.verts.truncate(first);
            }
        } else {
            for k in 0..ring.len() {
                self.push_clipped([centre, ring[k], ring[(k + 1) % ring.len()]], blend, None);
            }
        }
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

    fn raster_prim(&self, index: u32, band: &mut Band<'_>) {
        match self.prims[index as usize] {
            Prim::Tri { v, blend, tex } => {
                let tex = tex.and_then(|t| self.textures.get(t as usize)).map(|t| &**t);
                let [a, b, c] = v.map(|i| &self.verts[i as usize]);
                raster_tri(band, a, b, c, blend, tex);
            }
            Prim::Fan { first, n, blend } => {
                let first = first as usize;
                let centre = &self.verts[first];
                let rim = &self.verts[first + 1..first + 1 + n as usize];
                let (lo, hi) = ((band.y0 as i64) * SUB, (band.y1 as i64) * SUB + SUB);
                for k in 0..rim.len() {
                    let (p, q) = (&rim[k], &rim[(k + 1) % rim.len()]);
                    // Skip fan triangles entirely above or below the band.
                    if centre.y.max(p.y).max(q.y) < lo || centre.y.min(p.y).min(q.y) > hi {
                        continue;
                    }
                    raster_tri(band, centre, p, q, blend, None);
                }
            }
        }
    }
}

fn floor_div(a: i64, b: i64) -> i64 {
    a.div_euclid(b)
}

fn ceil_div(a: i64, b: i64) -> i64 {
    -((-a).div_euclid(b))
}

/// Rows `y0..y1` of the framebuffer.
struct Band<'a> {
    color: &'a mut [[f32; 4]],
    depth: &'a mut [f32],
    width: usize,
    y0: usize,
    y1: usize,
}

/// `(b − a) × (p − a)` in fixed point: positive when `p` is on the inner side of a
/// positively-oriented triangle.
fn edge(a: &SVert, b: &SVert, px: i64, py: i64) -> i64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}

/// Top-left rule for an edge `a → b` of a positively oriented triangle (y down).
fn is_top_left(a: &SVert, b: &SVert) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    dy < 0 || (dy == 0 && dx > 0)
}

fn raster_tri(band: &mut Band<'_>, a: &SVert, b: &SVert, c: &SVert, blend: Blend, tex: Option<&Image>) {
    let area = edge(a, b, c.x, c.y);
    let (b, c, area) = match area.cmp(&0) {
        std::cmp::Ordering::Equal => return,
        std::cmp::Ordering::Less => (c, b, -area),
        std::cmp::Ordering::Greater => (b, c, area),
    };
    let x0 = ceil_div(a.x.min(b.x).min(c.x) - SUB / 2, SUB).max(0);
    let x1 = floor_div(a.x.max(b.x).max(c.x) - SUB / 2, SUB).min(band.width as i64 - 1);
    let y0 = ceil_div(a.y.min(b.y).min(c.y) - SUB / 2, SUB).max(band.y0 as i64);
    let y1 = floor_div(a.y.max(b.y).max(c.y) - SUB / 2, SUB).min(band.y1 as i64 - 1);
    if x0 > x1 || y0 > y1 {
        return;
    }
    // Edge functions at the first pixel centre, their steps, and top-left biases.
    let (px, py) = (x0 * SUB + SUB / 2, y0 * SUB + SUB / 2);
    let edges = [(b, c), (c, a), (a, b)];
    let mut row = [0i64; 3];
    let mut dx = [0i64; 3];
    let mut dy = [0i64; 3];
    let mut bias = [0i64; 3];
    for (k, (p, q)) in edges.iter().enumerate() {
        row[k] = edge(p, q, px, py);
        dx[k] = -(q.y - p.y) * SUB;
        dy[k] = (q.x - p.x) * SUB;
        bias[k] = if is_top_left(p, q) { 0 } else { -1 };
    }
    let inv_area = 1.0 / area as f32;
    let depth_write = blend == Blend::Opaque;
    for y in y0..=y1 {
        let mut w = row;
        let line = (y as usize - band.y0) * band.width;
        for x in x0..=x1 {
            if w[0] + bias[0] >= 0 && w[1] + bias[1] >= 0 && w[2] + bias[2] >= 0 {
                let l1 = w[1] as f32 * inv_area;
                let l2 = w[2] as f32 * inv_area;
                let l0 = 1.0 - l1 - l2;
                let z = a.z * l0 + b.z * l1 + c.z * l2;
                let i = line + x as usize;
                if (0.0..=1.0).contains(&z) && z <= band.depth[i] {
                    let iw = a.iw * l0 + b.iw * l1 + c.iw * l2;
                    let inv = 1.0 / iw;
                    let mut src = [0.0f32; 4];
                    for (ch, s) in src.iter_mut().enumerate() {
                        *s = (a.c[ch] * l0 + b.c[ch] * l1 + c.c[ch] * l2) * inv;
                    }
                    if let Some(t) = tex {
                        let u = (a.uv[0] * l0 + b.uv[0] * l1 + c.uv[0] * l2) * inv;
                        let v = (a.uv[1] * l0 + b.uv[1] * l1 + c.uv[1] * l2) * inv;
                        let texel = sample_bilinear(t, u, v);
                        for ch in 0..4 {
                            src[ch] *= texel[ch];
                        }
                    }
                    blend_pixel(&mut band.color[i], src, blend);
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

/// Bilinear, clamp-to-edge sample of an RGBA image at `(u, v)` (0,0 = top-left corner).
pub fn sample_bilinear(img: &Image, u: f32, v: f32) -> [f32; 4] {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 || img.channels() != Channels::Rgba {
        return [0.0; 4];
    }
    let fx = (u * w as f32 - 0.5).clamp(0.0, (w - 1) as f32);
    let fy = (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
    let d = img.data();
    let px = |x: usize, y: usize, ch: usize| d[(y * w + x) * 4 + ch];
    let mut out = [0.0; 4];
    for (ch, o) in out.iter_mut().enumerate() {
        let top = px(x0, y0, ch) * (1.0 - tx) + px(x1, y0, ch) * tx;
        let bottom = px(x0, y1, ch) * (1.0 - tx) + px(x1, y1, ch) * tx;
        *o = top * (1.0 - ty) + bottom * ty;
    }
    out
}

/// Blends straight-alpha `src` into the premultiplied framebuffer pixel `dst`.
pub fn blend_pixel(dst: &mut [f32; 4], src: [f32; 4], blend: Blend) {
    let a = src[3].clamp(0.0, 1.0);
    match blend {
        Blend::Opaque => *dst = [src[0], src[1], src[2], 1.0],
        Blend::Over => {
            for ch in 0..3 {
                dst[ch] = src[ch] * a + dst[ch] * (1.0 - a);
            }
            dst[3] = a + dst[3] * (1.0 - a);
        }
        Blend::Additive => {
            for ch in 0..3 {
                dst[ch] = (dst[ch] + src[ch].max(0.0) * a).min(1.0);
            }
            dst[3] = (dst[3] + a).min(1.0);
        }
    }
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
        let mut data = Vec::with_capacity(self.color.len() * 4);
        for p in &self.color {
            let a = p[3].max(p[0]).max(p[1]).max(p[2]).min(1.0);
            if a > 0.0 {
                data.extend_from_slice(&[(p[0] / a).min(1.0), (p[1] / a).min(1.0), (p[2] / a).min(1.0), a]);
            } else {
                data.extend_from_slice(&[0.0; 4]);
            }
        }
        Image::from_vec(self.width, self.height, Channels::Rgba, data)
            .unwrap_or_else(|| Image::new(self.width, self.height, Channels::Rgba))
    }
}

/// Rasterizes `lists` (in order) over a `background` (straight RGBA), bands in parallel.
pub fn render(view: &View, lists: &[DrawList], background: [f32; 4]) -> Framebuffer {
    let (w, h) = (view.width as usize, view.height as usize);
    let a = background[3].clamp(0.0, 1.0);
    let bg = [background[0] * a, background[1] * a, background[2] * a, a];
    let mut color = vec![bg; w * h];
    let mut depth = vec![1.0f32; w * h];
    color.par_chunks_mut(w * BAND_ROWS).zip(depth.par_chunks_mut(w * BAND_ROWS)).enumerate().for_each(|(bi, (c, d))| {
        let y0 = bi * BAND_ROWS;
        let mut band = Band { y1: y0 + c.len() / w, color: c, depth: d, width: w, y0 };
        for pass in 0..2 {
            for list in lists {
                if list.view.width != view.width || list.view.height != view.height {
                    continue;
                }
                for &p in &list.bins[pass][bi] {
                    list.raster_prim(p, &mut band);
                }
            }
        }
    });
    Framebuffer { width: view.width, height: view.height, color, depth }
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
