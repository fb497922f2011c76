//! `volume.render_sixway`: six-way lighting maps of a volume, the textures game engines relight
//! baked smoke with at run time (Unity's Six Way: URP/HDRP Six-way Lit and VFX Graph's Six-way
//! Smoke Lit), and the engines' decode of them ([`relight`]).

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use pyrograph_core::{AtPort, Channels, Cook, CookCtx, Image, NodeError, port};
use pyrograph_render::View;
use pyrograph_render::ports::CameraPorts;

use super::light::{Light, LightKind};
use super::march::{GROUPS, Look, Scene, gather};
use super::{MarchPorts, check_fields};
use crate::grid::Volume;

pyrograph_core::node! {
    /// Six-way lighting maps of a volume for the engines' smoke shaders (Unity's Six Way lighting: URP/HDRP
    /// Six-way Lit, VFX Graph's Six-way Smoke Lit): the smoke lit by one directional light at a time, from the
    /// camera's right, top, back (behind the smoke, away from the viewer), left, bottom and front, each the
    /// single scattering of volume.render with its shadows through the smoke. `positive` holds right, top and
    /// back in R, G, B and the opacity in A; `negative` holds left, bottom and front in R, G, B and the
    /// emission mask in A (the luminance of the fire's light × `emission_scale`, at most 1: Unity's
    /// single-channel emission, coloured by the material's gradient). Values are linear and premultiplied:
    /// π × the scattered radiance per unit of irradiance (URP's units, where a white surface facing the light
    /// reads 1); write EXR, or PNG imported with sRGB off. An engine relights a pixel from direction L (toward
    /// the light, in the camera's right, up, away frame) as Σ L_i² × the map of L_i's sign, times its base
    /// colour. Lay each clip out as a sheet with imaging.write_flipbook.
    #[node("volume.render_sixway", "Volume", PerFrame)]
    pub struct RenderSixway {
        /// The volume (volume.simulate, volume.load_vdb): density, temperature and flame fields.
        volume: Arc<Volume>,
        /// The camera the maps face (a flipbook's cells are square: make width and height equal).
        camera: CameraPorts = CameraPorts::looking(256, 256, [0.0, 2.0, 9.0], [0.0, 2.0, 0.0]),
        /// Extinction, the fire's glow and the march's step.
        march: MarchPorts,
        /// The smoke's single-scattering albedo (its colour is the engine material's base colour).
        #[range(0.0, 1.0)]
        albedo: f32 = 0.9,
        /// Henyey–Greenstein anisotropy; 0 (even scattering) suits the engines' blend of six lights best.
        #[range(-0.95, 0.95)]
        anisotropy: f32 = 0.0,
        /// The emission mask per unit of the fire light's luminance.
        #[range(0.0, 1e6)]
        emission_scale: f32 = 1.0,
    }
    pub struct RenderSixwayOut {
        /// Right, top, back lighting and opacity (RGBA, premultiplied).
        positive: Arc<Image>,
        /// Left, bottom, front lighting and the emission mask (RGBA, premultiplied).
        negative: Arc<Image>,
    }
}

impl Cook for RenderSixway {
    fn cook(self, ctx: &CookCtx) -> Result<RenderSixwayOut, NodeError> {
        let view = self.camera.view()?;
        check_fields(&self.volume).at_port(port!(RenderSixway, volume))?;
        ctx.check_cancel()?;
        let look =
            self.march.look(Vec3::splat(self.albedo), self.anisotropy, Vec3::ZERO, Vec4::ZERO, self.volume.time.to_bits())?;
        let (positive, negative) = sixway_maps(&self.volume, &view, &look, self.emission_scale);
        Ok(RenderSixwayOut { positive: Arc::new(positive), negative: Arc::new(negative) })
    }
}

/// The camera's frame: right, up and away from the viewer (unit vectors, world space).
pub fn camera_frame(view: &View) -> [Vec3; 3] {
    let camera = view.camera();
    let away = (camera.target() - camera.position()).normalize();
    let right = away.cross(camera.up()).normalize();
    [right, right.cross(away), away]
}

/// The six lights' directions (toward the light, world space) in map order: right, top, back,
/// left, bottom, front.
pub fn six_directions(view: &View) -> [Vec3; GROUPS] {
    let [r, u, f] = camera_frame(view);
    [r, u, f, -r, -u, -f]
}

/// The positive and negative maps of `v` seen through `view`.
pub fn sixway_maps(v: &Volume, view: &View, look: &Look, emission_scale: f32) -> (Image, Image) {
    let lights = six_directions(view).map(|d| Light { kind: LightKind::Directional(d), color: Vec3::ONE });
    let groups: Vec<usize> = (0..GROUPS).collect();
    let scene = Scene { lights: &lights, groups: &groups, surfaces: None, motion: false };
    let pixels = gather(v, view, &scene, look, |g, _, _| {
        // Grey albedo and white lights: the channels agree; R stands for them.
        let s = g.scattered.map(|c| PI * c.x);
        let luminance = g.emitted.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let mask = (luminance * emission_scale).clamp(0.0, 1.0);
        [s[0], s[1], s[2], 1.0 - g.transmit, s[3], s[4], s[5], mask]
    });
    let (w, h) = (view.width(), view.height());
    let half = |range: std::ops::Range<usize>| {
        let data = pixels.iter().flat_map(|p| p[range.clone()].to_vec()).collect();
        Image::from_vec(w, h, Channels::Rgba, data).unwrap_or_else(|| Image::new(w, h, Channels::Rgba))
    };
    (half(0..4), half(4..8))
}

/// Unity's six-way decode (URP and HDRP `SixWayLighting.hlsl`: the weights are the squared
/// components of the light direction, each axis read from the map of its sign): the light a
/// pixel sends toward the camera from unit irradiance along `l` (toward the light, in the
/// camera's right, up, away frame), before the material's base colour. `positive` and
/// `negative` are the maps' RGB.
pub fn relight(positive: Vec3, negative: Vec3, l: Vec3) -> f32 {
    (0..3).map(|i| l[i] * l[i] * if l[i] >= 0.0 { positive[i] } else { negative[i] }).sum()
}

#[cfg(test)]
mod tests;
