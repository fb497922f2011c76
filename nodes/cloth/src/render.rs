//! Drawing mass-spring flames (mass-spring flame project 2019 §Textures, §User Interface "Draw"):
//! each cloth as a textured, alpha-blended mesh turned to face the camera, or as a wireframe of
//! its springs, or as plain shaded cloth (the project's Figure 4). Nodes `cloth.cloth_render`
//! (built-in procedural textures) and `cloth.cloth_render_textured` (a required texture input).

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::{AtPort, CookCtx, Image, NodeError, port};
use pyrograph_render::ports::CameraPorts;
use pyrograph_render::{Blend, Camera, DrawList, TextureId, Vertex, View, render_image};
use rayon::prelude::*;

use crate::state::ClothState;
use crate::textures::builtin_textures;

pyrograph_core::choice! {
    /// How the cloths are drawn.
    pub enum Mode {
        /// Textured, alpha-blended mesh (the flame).
        Textured = "textured",
        /// The structural springs as thin camera-facing strips.
        Wireframe = "wireframe",
        /// Plain shaded cloth, without a texture (Figure 4).
        Cloth = "cloth",
    }
}

pyrograph_core::choice! {
    /// How textured and cloth meshes blend.
    pub enum ClothBlend {
        /// Alpha blending.
        Over = "over",
        /// Additive light.
        Additive = "additive",
    }
}

impl ClothBlend {
    /// The rasterizer's blend mode.
    pub fn blend(self) -> Blend {
        match self {
            ClothBlend::Over => Blend::Over,
            ClothBlend::Additive => Blend::Additive,
        }
    }
}

/// Where the textures come from.
#[derive(Clone, Copy, Debug)]
pub enum Textures<'a> {
    /// The eight built-in procedural textures, one per flame chosen by its seed.
    Builtin,
    /// One texture for every flame.
    Single(&'a Arc<Image>),
}

pyrograph_core::ports! {
    /// Drawing parameters other than the view: the ports of the cloth renderers after the camera.
    #[derive(PartialEq)]
    pub struct RenderParams {
        /// Textured flame, spring wireframe, or plain cloth.
        mode: Mode = Mode::Textured,
        /// Alpha blending (over) or additive light.
        blend: ClothBlend = ClothBlend::Over,
        /// Multiplies the texture; the colour of wireframe and cloth.
        tint: [f32; 4] = [1.0, 1.0, 1.0, 1.0],
        /// Width of wireframe strips in pixels.
        #[range(0.0, 1e3)]
        line_width: f32 = 1.5,
        /// Background colour (straight RGBA).
        background: [f32; 4] = [0.0, 0.0, 0.0, 1.0],
    }
}

/// The world axes of a flame at `root` facing the camera about the vertical: `(across, up,
/// toward the eye)`. Flames stay upright; looking straight down falls back to a billboard.
pub fn flame_axes(camera: &Camera, root: Vec3) -> (Vec3, Vec3, Vec3) {
    let to_eye = camera.position() - root;
    let flat = Vec3::new(to_eye.x, 0.0, to_eye.z);
    if flat.length_squared() > 1e-8 {
        let f = flat.normalize();
        (Vec3::Y.cross(f), Vec3::Y, f)
    } else {
        let (r, u) = camera.billboard_axes(root);
        (r, u, r.cross(u))
    }
}

/// World positions of flame `i` of `cloth`, turned to face the camera.
fn world_positions(camera: &Camera, cloth: &ClothState, i: usize) -> Vec<Vec3> {
    let to_world = flame_to_world(camera, cloth, i);
    cloth.flame(i).unwrap_or(&[]).iter().map(|p| to_world(*p)).collect()
}

/// Flame `i`'s local-to-world map, turned to face the camera.
fn flame_to_world(camera: &Camera, cloth: &ClothState, i: usize) -> impl Fn([f32; 3]) -> Vec3 + use<> {
    let root = Vec3::from_array(cloth.roots[i]);
    let (r, u, f) = flame_axes(camera, root);
    move |p| root + r * p[0] + u * p[1] + f * p[2]
}

/// What every textured cloth of a `w × h` grid shares: the texture coordinates of its masses
/// (uv (0,0) is the texture's top-left: the top row of the cloth) and its two triangles per cell.
struct ClothMesh {
    uv: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
}

impl ClothMesh {
    fn new(w: usize, h: usize) -> Self {
        let (wd, hd) = ((w.max(2) - 1) as f32, (h.max(2) - 1) as f32);
        let uv = (0..h).flat_map(|r| (0..w).map(move |c| [c as f32 / wd, 1.0 - r as f32 / hd])).collect();
        let idx = |r: usize, c: usize| (r * w + c) as u32;
        let triangles = (0..h.saturating_sub(1))
            .flat_map(|r| (0..w.saturating_sub(1)).map(move |c| (r, c)))
            .flat_map(|(r, c)| {
                let (a, b, cc, d) = (idx(r, c), idx(r, c + 1), idx(r + 1, c + 1), idx(r + 1, c));
                [[a, b, cc], [a, cc, d]]
            })
            .collect();
        ClothMesh { uv, triangles }
    }
}

/// Flame `i` as one indexed textured mesh (each cloth vertex is projected once), its vertices
/// built in `verts` (reused between flames).
fn draw_textured_flame(
    list: &mut DrawList,
    cloth: &ClothState,
    i: usize,
    mesh: &ClothMesh,
    verts: &mut Vec<Vertex>,
    tex: TextureId,
    p: &RenderParams,
) {
    let to_world = flame_to_world(list.view().camera(), cloth, i);
    let masses = cloth.flame(i).unwrap_or(&[]);
    if masses.len() != mesh.uv.len() {
        return;
    }
    verts.clear();
    verts.extend(masses.iter().zip(&mesh.uv).map(|(q, &uv)| Vertex { position: to_world(*q), color: p.tint, uv }));
    list.mesh(verts, &mesh.triangles, Some(tex), p.blend.blend());
}

fn draw_flame(list: &mut DrawList, cloth: &ClothState, i: usize, p: &RenderParams) {
    let camera = *list.view().camera();
    let (w, h) = (cloth.width as usize, cloth.height as usize);
    let pos = world_positions(&camera, cloth, i);
    if pos.len() != w * h || w < 2 || h < 2 {
        return;
    }
    let at = |r: usize, c: usize| pos[r * w + c];
    match p.mode {
        Mode::Wireframe => {
            // World size of one pixel at unit distance: 2·tan(fov/2) / height.
            let focal = camera.projection_matrix(1.0).y_axis.y;
            let pixel = 2.0 / (focal * list.view().height() as f32);
            let mut strip = |a: Vec3, b: Vec3| {
                let to_eye = camera.position() - (a + b) * 0.5;
                let half = 0.5 * p.line_width * pixel * to_eye.length();
                let side = (b - a).cross(to_eye).normalize_or_zero() * half;
                let v = |q: Vec3| Vertex::new(q, p.tint);
                list.triangle([v(a - side), v(b - side), v(b + side)], Blend::Over);
                list.triangle([v(a - side), v(b + side), v(a + side)], Blend::Over);
            };
            for r in 0..h {
                for c in 0..w {
                    if c + 1 < w {
                        strip(at(r, c), at(r, c + 1));
                    }
                    if r + 1 < h {
                        strip(at(r, c), at(r + 1, c));
                    }
                }
            }
        }
        Mode::Cloth | Mode::Textured => {
            let eye = camera.position();
            for r in 0..h - 1 {
                for c in 0..w - 1 {
                    for tri in [[at(r, c), at(r, c + 1), at(r + 1, c + 1)], [at(r, c), at(r + 1, c + 1), at(r + 1, c)]] {
                        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
                        let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
                        let lit = 0.3 + 0.7 * n.dot((eye - centre).normalize_or_zero()).abs();
                        let col = [p.tint[0] * lit, p.tint[1] * lit, p.tint[2] * lit, p.tint[3]];
                        list.triangle(tri.map(|q| Vertex::new(q, col)), p.blend.blend());
                    }
                }
            }
        }
    }
}

/// Renders every flame of `cloth` through `view`, far flames first (so "over" blends correctly);
/// geometry is built in parallel chunks and rasterized in parallel bands.
pub fn render_cloth(view: &View, cloth: &ClothState, textures: Textures<'_>, p: &RenderParams) -> Image {
    let eye = view.camera().position();
    let mut order: Vec<usize> = (0..cloth.flames()).collect();
    let dist = |i: usize| (Vec3::from_array(cloth.roots[i]) - eye).length_squared();
    order.sort_by(|&a, &b| dist(b).total_cmp(&dist(a)).then(a.cmp(&b)));
    let chunk = (order.len() / (rayon::current_num_threads() * 4)).max(4);
    let mesh = ClothMesh::new(cloth.width as usize, cloth.height as usize);
    let lists: Vec<DrawList> = order
        .par_chunks(chunk)
        .map(|flames| {
            let mut list = DrawList::new(view);
            let ids: Vec<_> = match textures {
                Textures::Builtin => builtin_textures().iter().map(|t| list.add_texture(t)).collect(),
                Textures::Single(t) => vec![list.add_texture(t)],
            };
            let mut verts = Vec::new();
            for &i in flames {
                let seed = cloth.seeds.get(i).copied().unwrap_or(i as u32) as usize;
                match (p.mode, ids.get(seed % ids.len().max(1))) {
                    (Mode::Textured, Some(&tex)) => draw_textured_flame(&mut list, cloth, i, &mesh, &mut verts, tex, p),
                    _ => draw_flame(&mut list, cloth, i, p),
                }
            }
            list
        })
        .collect();
    render_image(view, &lists, p.background)
}

/// The camera of both cloth renderers: nine flames on a grid, seen from the front.
fn cloth_camera() -> CameraPorts {
    CameraPorts::looking(640, 480, [0.0, 2.5, 9.0], [0.0, 1.0, 0.0])
}

pyrograph_core::node! {
    /// Renders mass-spring flames (mass-spring flame project 2019 §Textures): each cloth is a mesh turned
    /// about the vertical to face the camera, textured with one of 8 built-in procedural flame textures
    /// (Figure 3; generated with gradient noise, chosen at random per flame by its seed) and alpha-blended
    /// far to near; or drawn as a wireframe of its springs, or as plain shaded cloth (Figure 4). Connect the
    /// Clip<ClothState> of cloth.mass_spring_flame to get a clip of frames (RGBA, straight alpha). Use
    /// cloth.cloth_render_textured to texture the cloth with another node's image or clip.
    #[node("cloth.cloth_render", "Cloth", PerFrame)]
    pub struct ClothRender {
        /// The cloths to draw (cloth.mass_spring_flame).
        cloth: Arc<ClothState>,
        /// The camera.
        camera: CameraPorts = cloth_camera(),
        /// How the cloths are drawn.
        params: RenderParams,
    }
    /// The rendered frame (RGBA, straight alpha).
    -> image: Arc<Image>
}

pyrograph_core::node! {
    /// Renders mass-spring flames with a texture from another node (mass-spring flame project 2019
    /// §Textures): like cloth.cloth_render, but every cloth is textured with the required `texture`
    /// input. Connect an image, or a Clip<Image> (imaging.turbulence_flame, Eigenfires reconstructions)
    /// together with the cloth clip: the render is lifted over both and frame n uses texture frame n.
    /// A separate node because an optional texture input would need a default image.
    #[node("cloth.cloth_render_textured", "Cloth", PerFrame)]
    pub struct ClothRenderTextured {
        /// The cloths to draw (cloth.mass_spring_flame).
        cloth: Arc<ClothState>,
        /// Texture for every cloth (top of the image at the flame's tip).
        texture: Arc<Image>,
        /// The camera.
        camera: CameraPorts = cloth_camera(),
        /// How the cloths are drawn.
        params: RenderParams,
    }
    /// The rendered frame (RGBA, straight alpha).
    -> image: Arc<Image>
}

impl RenderParams {
    /// The parameters when the line width is usable; the error names the port.
    fn checked(self) -> Result<RenderParams, NodeError> {
        let line_width = self.line_width;
        if !line_width.is_finite() || line_width < 0.0 {
            return Err(NodeError::port(
                port!(RenderParams, line_width),
                format!("must be a finite non-negative width, got {line_width}"),
            ));
        }
        Ok(self)
    }
}

/// Why `cloth` cannot be drawn, if it cannot: its arrays disagree, or a position is not finite.
fn check_cloth(cloth: &ClothState) -> Result<(), &'static str> {
    let n = cloth.width as usize * cloth.height as usize;
    if cloth.positions.len() != n * cloth.flames() || cloth.seeds.len() != cloth.flames() {
        return Err("inconsistent cloth state: positions or seeds do not match the flame count");
    }
    if !cloth.positions.iter().chain(&cloth.roots).all(|p| p.iter().all(|x| x.is_finite())) {
        return Err("the cloth has non-finite positions");
    }
    Ok(())
}

impl Cook for ClothRender {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let view = self.camera.view()?;
        check_cloth(&self.cloth).at_port(port!(ClothRender, cloth))?;
        let cloth = &self.cloth;
        let p = self.params.checked()?;
        ctx.check_cancel()?;
        Ok(Arc::new(render_cloth(&view, cloth, Textures::Builtin, &p)))
    }
}

impl Cook for ClothRenderTextured {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let view = self.camera.view()?;
        check_cloth(&self.cloth).at_port(port!(ClothRenderTextured, cloth))?;
        let cloth = &self.cloth;
        if self.texture.width() == 0 || self.texture.height() == 0 {
            return Err(NodeError::port(port!(ClothRenderTextured, texture), "is an empty image"));
        }
        let p = self.params.checked()?;
        ctx.check_cancel()?;
        Ok(Arc::new(render_cloth(&view, cloth, Textures::Single(&self.texture), &p)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{ClothParams, Simulation, grid_roots};
    use pyrograph_core::Channels;

    fn view(w: u32, h: u32) -> View {
        let cam = Camera::new(Vec3::new(0.0, 1.0, 6.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 0.1, 100.0).unwrap();
        View::new(cam, w, h).unwrap()
    }

    fn one_flame() -> ClothState {
        Simulation::new(&ClothParams::default(), &grid_roots(1, 1.0)).unwrap().snapshot()
    }

    #[test]
    fn a_textured_flame_is_bright_in_its_body_and_clear_outside() {
        let v = view(96, 96);
        let img = render_cloth(&v, &one_flame(), Textures::Builtin, &RenderParams::default());
        let body = v.project(Vec3::new(0.0, 0.5, 0.0)).unwrap();
        let px = img.pixel(body.x as u32, body.y as u32);
        assert!(px[0] > 0.5, "flame body {px:?}");
        assert_eq!(img.pixel(2, 2), &[0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn a_given_texture_colours_the_cloth_and_wireframe_and_cloth_modes_draw() {
        let v = view(64, 64);
        let green = Arc::new(Image::from_vec(2, 2, Channels::Rgba, [0.0, 1.0, 0.0, 1.0].repeat(4)).unwrap());
        let img = render_cloth(&v, &one_flame(), Textures::Single(&green), &RenderParams::default());
        let c = v.project(Vec3::new(0.0, 1.0, 0.0)).unwrap();
        assert_eq!(img.pixel(c.x as u32, c.y as u32), &[0.0, 1.0, 0.0, 1.0]);
        for mode in [Mode::Wireframe, Mode::Cloth] {
            let p = RenderParams { mode, ..RenderParams::default() };
            let img = render_cloth(&v, &one_flame(), Textures::Builtin, &p);
            assert!(img.data().chunks(4).any(|q| q[0] > 0.2), "{mode:?} draws something");
        }
    }
}
