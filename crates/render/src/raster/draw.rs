//! Draw lists: geometry transformed, clipped and snapped to fixed point when it is added, and
//! binned into bands for [`render`](super::render).

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use pyrograph_core::{Channels, Image};

use super::fan::{FanEdge, FanSetup, KeptEdge, MAX_FAN, raster_fan};
use super::isa::Isa;
use super::tiles::raster_tri;
use super::view::{ClipVert, View, clip_polygon, inside_all};
use super::{BAND_ROWS, Band, Blend, SUB, SVert, ScreenVertex, Vertex, add_in_range, blend_vec4, ceil_sub, floor_sub, round_i64};

/// A primitive of a [`DrawList`], binned into the bands it touches.
#[derive(Clone, Copy, Debug)]
enum Prim {
    /// Three vertex indices; `tex` indexes the list's textures.
    Tri { v: [u32; 3], blend: Blend, tex: Option<u32> },
    /// A fuzzy particle: index into the list's scanline setups.
    Fan { fan: u32, blend: Blend },
    /// Segments `segs.0..=segs.1` of grid strip `strip` (see [`DrawList::strip`]): those that may
    /// touch the one band this primitive is binned into.
    Strip { strip: u32, segs: (u32, u32), blend: Blend },
}

/// A grid strip's snapped vertices: rows of `across` from `first` in `DrawList::verts`, one row
/// per sample along the strip, segment `s` joining rows `s` and `s + 1`.
#[derive(Clone, Copy, Debug)]
struct StripSetup {
    first: u32,
    across: u32,
}

/// Geometry ready for [`render`](super::render): built on one thread, many lists may be built in
/// parallel and rendered together (in list order).
pub struct DrawList {
    pub(super) view: View,
    verts: Vec<SVert>,
    prims: Vec<Prim>,
    pub(super) fans: Vec<FanSetup>,
    pub(super) fan_edges: Vec<FanEdge>,
    /// `FanSetup::new`'s per-edge working list, reused.
    pub(super) fan_scratch: Vec<KeptEdge>,
    textures: Vec<Arc<Image>>,
    /// Per pass (0 opaque, 1 blended), per band, the primitives touching it in submission order.
    pub(super) bins: [Vec<Vec<u32>>; 2],
    /// `(cos, sin)` of the rim angles for the last particle side count.
    ring: Vec<(f32, f32)>,
    /// The current disc's rim in clip space, reused.
    rim_clip: Vec<Vec4>,
    /// The current disc's centre and rim snapped to the screen, reused.
    rim_snapped: Vec<SVert>,
    /// `mesh`'s clip-space vertices and their snapped indices, reused.
    mesh_scratch: (Vec<ClipVert>, Vec<u32>),
    strips: Vec<StripSetup>,
    /// `strip`'s first and last segment touching each band, reused.
    strip_bands: Vec<(u32, u32)>,
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
            strips: Vec::new(),
            strip_bands: Vec::new(),
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

    /// Number of primitives (triangles and particles) kept after clipping and culling; a grid
    /// strip counts once per band it touches.
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

    /// Prepares the scanline form of the fan whose centre is `vs[0]` and rim the rest of `vs`
    /// (see [`FanSetup::new`]) and keeps it with its edges; `false` (nothing kept) when it cannot
    /// take that path.
    fn fan_setup(&mut self, vs: &[SVert], rows: (i64, i64), center: [f32; 4], edge: [f32; 4]) -> bool {
        match FanSetup::new(vs, rows, center, edge, &mut self.fan_edges, &mut self.fan_scratch) {
            Some(fan) => {
                self.fans.push(fan);
                true
            }
            None => false,
        }
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

    /// A grid strip: `vertices` in rows of `across` (one row per sample along the strip), each
    /// two consecutive rows `a`, `b` (their first vertices' indices) joined by the triangles
    /// `[a+j, a+j+1, b+j+1]` and `[a+j, b+j+1, b+j]` for `j` in `0..across − 1`. It draws exactly
    /// the pixels [`DrawList::mesh`] draws for those triangles in that order, but is binned once
    /// per band instead of once per triangle and rasterized straight from its rows: the swept
    /// flames' hundreds of thousands of one- and two-pixel triangles a frame spent about a third
    /// of their time binning and fetching indexed triangles (issue 45).
    pub fn strip(&mut self, vertices: &[Vertex], across: u32, blend: Blend) {
        let n = across as usize;
        let rows = if n >= 2 { vertices.len() / n } else { 0 };
        if rows < 2 {
            return;
        }
        let vertices = &vertices[..rows * n];
        let (mut clip, index) = std::mem::take(&mut self.mesh_scratch);
        clip.clear();
        clip.extend(vertices.iter().map(|v| self.clip_vert(v)));
        let inside = clip.iter().all(|v| inside_all(v.pos));
        if inside {
            self.verts.reserve(clip.len());
            for v in &clip {
                let s = self.snap(v);
                self.verts.push(s);
            }
        }
        self.mesh_scratch = (clip, index);
        if !inside {
            // Near the camera or far off screen: clip triangle by triangle, as a mesh.
            let tris: Vec<[u32; 3]> = (0..rows as u32 - 1)
                .flat_map(|k| (0..across - 1).flat_map(move |j| strip_quad(k * across, (k + 1) * across, j)))
                .collect();
            self.mesh(vertices, &tris, None, blend);
            return;
        }
        let first = self.verts.len() - vertices.len();
        let mut bands = std::mem::take(&mut self.strip_bands);
        bands.clear();
        bands.resize(self.bins[0].len(), (u32::MAX, 0));
        let (mut lo, mut hi) = (usize::MAX, 0);
        for seg in 0..rows - 1 {
            let row = first + seg * n;
            if let Some((b0, b1)) = self.band_range(self.verts[row..row + 2 * n].iter()) {
                for b in &mut bands[b0..=b1] {
                    *b = (b.0.min(seg as u32), seg as u32);
                }
                (lo, hi) = (lo.min(b0), hi.max(b1));
            }
        }
        if lo <= hi {
            let strip = self.strips.len() as u32;
            self.strips.push(StripSetup { first: first as u32, across });
            for (band, &segs) in bands.iter().enumerate().take(hi + 1).skip(lo) {
                if segs.0 != u32::MAX {
                    self.push_prim(Prim::Strip { strip, segs, blend }, blend, (band, band));
                }
            }
        }
        self.strip_bands = bands;
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

    /// Rasterizes primitive `index` into `band` with the instruction set `isa`.
    #[inline(always)]
    pub(super) fn raster_prim<I: Isa>(&self, isa: I, index: u32, band: &mut Band<'_>) {
        match self.prims[index as usize] {
            Prim::Tri { v, blend, tex } => {
                let tex = tex.and_then(|t| self.textures.get(t as usize)).map(|t| &**t);
                let [a, b, c] = v.map(|i| &self.verts[i as usize]);
                raster_tri::<true, _>(isa, band, a, b, c, blend, tex);
            }
            Prim::Fan { fan, blend } => {
                let f = &self.fans[fan as usize];
                let (first, [above, below]) = (f.first as usize, f.counts.map(|c| c.iter().map(|&n| n as usize).sum::<usize>()));
                let halves = [&self.fan_edges[first..first + above], &self.fan_edges[first + above..first + above + below]];
                match blend {
                    Blend::Additive if f.in_range => raster_fan::<_, true>(isa, band, f, halves, add_in_range),
                    Blend::Additive => raster_fan::<_, false>(isa, band, f, halves, |d, s| blend_vec4(d, s, Blend::Additive)),
                    Blend::Over => raster_fan::<_, false>(isa, band, f, halves, |d, s| blend_vec4(d, s, Blend::Over)),
                    Blend::Opaque => raster_fan::<_, false>(isa, band, f, halves, |d, s| blend_vec4(d, s, Blend::Opaque)),
                }
            }
            Prim::Strip { strip, segs, blend } => {
                let StripSetup { first, across } = self.strips[strip as usize];
                let (first, n) = (first as usize, across as usize);
                for seg in segs.0 as usize..=segs.1 as usize {
                    let rows = &self.verts[first + seg * n..first + (seg + 2) * n];
                    if !touches_rows(rows, band) {
                        continue;
                    }
                    let (a, b) = rows.split_at(n);
                    for j in 0..n - 1 {
                        raster_tri::<true, _>(isa, band, &a[j], &a[j + 1], &b[j + 1], blend, None);
                        raster_tri::<true, _>(isa, band, &a[j], &b[j + 1], &b[j], blend, None);
                    }
                }
            }
        }
    }
}

/// The two triangles of quad `j` between the strip rows starting at vertices `a` and `b` (see
/// [`DrawList::strip`]).
fn strip_quad(a: u32, b: u32, j: u32) -> [[u32; 3]; 2] {
    [[a + j, a + j + 1, b + j + 1], [a + j, b + j + 1, b + j]]
}

/// Whether the box of `verts` covers a pixel row of `band` (a quick test before rasterizing a
/// strip segment's triangles, each of which would find the same and return).
#[inline(always)]
fn touches_rows(verts: &[SVert], band: &Band<'_>) -> bool {
    let (y0, y1) = verts.iter().fold((i64::MAX, i64::MIN), |(lo, hi), v| (lo.min(v.y), hi.max(v.y)));
    ceil_sub(y0 - SUB / 2) < band.y1 as i64 && floor_sub(y1 - SUB / 2) >= band.y0 as i64
}
