//! What `volume.render` composes and writes: opaque meshes seen through the volume (drawn by the
//! rasterizer the particle renderers use, their depth stopping the march) and the compositing
//! passes a frame's rays are mapped to.

use glam::{Vec3, Vec4};
use pyrograph_core::{Channels, Image};
use pyrograph_nodes_particles::lit_mesh::{MeshShading, draw_mesh};
use pyrograph_nodes_particles::types::Mesh;
use pyrograph_render::{Particles, View};

use super::march::{Gathered, Ray, Surface};

pyrograph_core::choice! {
    /// What `volume.render` draws: a compositor's pass.
    pub enum VolumePass {
        /// The whole frame: smoke, fire and meshes over the background.
        Beauty = "beauty",
        /// The fire's light alone (attenuated by the smoke in front of it, hidden behind meshes) on
        /// transparent black; alpha is the brightest channel, as the flame renderers' emission pass.
        Emission = "emission",
        /// The smoke's scattered light alone (sun, lights, fire light and ambient) on transparent black;
        /// alpha is the smoke's coverage.
        Scattering = "scattering",
        /// The beauty's alpha (gray).
        Alpha = "alpha",
        /// Distance along the camera's view axis where the smoke's opacity reaches one half, or of the mesh
        /// in front of it, in world units; the far plane where there is neither (gray).
        Depth = "depth",
        /// Motion vectors from the velocity field: R, G the screen motion of the smoke (its opacity-weighted
        /// mean position moved by its mean velocity) in pixels per frame, x right and y down; B 0; A the
        /// smoke's coverage.
        Motion = "motion",
    }
}

/// The surfaces of `mesh` seen through each pixel of `view` (row major), lit like the flame
/// renderers' meshes (albedo × (ambient + sun + point lights)) by `lights`.
pub fn mesh_surfaces(view: &View, mesh: &Mesh, lights: &Particles, shading: &MeshShading) -> Vec<Surface> {
    let frame = pyrograph_render::render(view, &draw_mesh(view, mesh, lights, shading), [0.0; 4]);
    let inverse = view.view_proj().inverse();
    let (w, h) = (view.width(), view.height());
    let mut out = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            let d = frame.depth(x, y);
            if d >= 1.0 {
                out.push(Surface { distance: f32::INFINITY, colour: Vec3::ZERO });
                continue;
            }
            let ndc = |z: f32| {
                let p = Vec3::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0, z);
                inverse.project_point3(p)
            };
            let [r, g, b, _] = frame.premultiplied(x, y);
            out.push(Surface { distance: (ndc(d) - ndc(0.0)).length(), colour: Vec3::new(r, g, b) });
        }
    }
    out
}

/// How a pass turns what a ray gathered into a pixel.
pub struct PassMap<'a> {
    /// The pass.
    pub pass: VolumePass,
    /// Straight RGBA behind the volume (the beauty's).
    pub background: Vec4,
    /// The view (the depth pass's axis, the motion pass's projection).
    pub view: &'a View,
    /// Seconds per frame, for the motion pass.
    pub frame_seconds: f32,
}

impl PassMap<'_> {
    /// The pixel (straight RGBA; gray passes in R) of a ray that gathered `g` in front of `surface`.
    pub fn pixel(&self, g: &Gathered, surface: Option<&Surface>, ray: Ray) -> [f32; 4] {
        let straight = |c: Vec3, alpha: f32| {
            let s = if alpha > 0.0 { c / alpha } else { Vec3::ZERO };
            [s.x, s.y, s.z, alpha]
        };
        let bg = self.background;
        let behind = surface.map_or((bg.truncate() * bg.w, bg.w), |s| (s.colour, 1.0));
        match self.pass {
            VolumePass::Beauty => straight(g.light() + behind.0 * g.transmit, 1.0 - g.transmit * (1.0 - behind.1)),
            VolumePass::Emission => straight(g.emitted, g.emitted.max_element().min(1.0)),
            VolumePass::Scattering => straight(g.light() - g.emitted, 1.0 - g.transmit),
            VolumePass::Alpha => [1.0 - g.transmit * (1.0 - behind.1), 0.0, 0.0, 1.0],
            VolumePass::Depth => {
                let camera = self.view.camera();
                let axis = (camera.target() - camera.position()).normalize();
                let t = g.depth.min(surface.map_or(f32::INFINITY, |s| s.distance));
                let z =
                    if t.is_finite() { (ray.origin + ray.direction * t - camera.position()).dot(axis) } else { f32::INFINITY };
                [z.min(camera.far()), 0.0, 0.0, 1.0]
            }
            VolumePass::Motion => {
                let (p, u, weight) = g.motion;
                let alpha = 1.0 - g.transmit;
                if weight <= 0.0 {
                    return [0.0; 4];
                }
                let at = p / weight;
                match (self.view.project(at), self.view.project(at + u / weight * self.frame_seconds)) {
                    (Some(a), Some(b)) => [b.x - a.x, b.y - a.y, 0.0, alpha],
                    _ => [0.0, 0.0, 0.0, alpha],
                }
            }
        }
    }

    /// Adds the light of particle flames inside the smoke (premultiplied per pixel, from
    /// [`super::flames::flame_light`]) to `pixels` (from [`PassMap::pixel`]): light in the beauty and
    /// the emission, coverage in the alpha; the scattering, depth and motion are the smoke's alone
    /// (flames are light, not matter).
    pub fn add_flames(&self, pixels: &mut [[f32; 4]], flames: &[[f32; 4]]) {
        for (px, f) in pixels.iter_mut().zip(flames) {
            let (light, cover) = (Vec3::new(f[0], f[1], f[2]), f[3]);
            let c = Vec3::new(px[0], px[1], px[2]) * px[3] + light;
            let alpha = match self.pass {
                VolumePass::Beauty => px[3] + cover * (1.0 - px[3]),
                VolumePass::Emission => c.max_element().min(1.0),
                VolumePass::Alpha => {
                    px[0] += cover * (1.0 - px[0]);
                    continue;
                }
                VolumePass::Scattering | VolumePass::Depth | VolumePass::Motion => continue,
            };
            let s = if alpha > 0.0 { c / alpha } else { Vec3::ZERO };
            *px = [s.x, s.y, s.z, alpha];
        }
    }

    /// Whether the pass is one gray channel.
    pub fn gray(&self) -> bool {
        matches!(self.pass, VolumePass::Alpha | VolumePass::Depth)
    }

    /// The frame of `pixels` (from [`PassMap::pixel`]).
    pub fn image(&self, pixels: Vec<[f32; 4]>) -> Image {
        let (w, h) = (self.view.width(), self.view.height());
        let image = if self.gray() {
            Image::from_vec(w, h, Channels::Gray, pixels.iter().map(|p| p[0]).collect())
        } else {
            Image::from_vec(w, h, Channels::Rgba, pixels.into_flattened())
        };
        image.unwrap_or_else(|| Image::new(w, h, if self.gray() { Channels::Gray } else { Channels::Rgba }))
    }
}
