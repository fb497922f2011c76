//! `volume.render`: a lit, self-shadowed ray march of a volume (single scattering from the sun,
//! point lights and the fire's own glow, blackbody emission), through the camera the particle and
//! spread renderers use. The march is in [`march`], lights and shadow volumes in [`light`], the
//! blackbody colours in [`blackbody`].

pub mod blackbody;
pub mod clear;
pub mod compose;
pub mod flames;
pub mod light;
pub mod march;
pub mod sixway;
pub mod sweep;

#[cfg(test)]
mod tests;

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use pyrograph_core::{AtPort, Cook, CookCtx, Image, NodeError, port};
use pyrograph_nodes_particles::lit_mesh::MeshShading;
use pyrograph_nodes_particles::swept::Exposure;
use pyrograph_nodes_particles::types::Mesh;
use pyrograph_render::ports::CameraPorts;
use pyrograph_render::{Particle, Particles};

use crate::grid::Volume;
use compose::{PassMap, VolumePass, mesh_surfaces};
use flames::{Smoke, flame_light};
use light::{Light, LightKind};
use march::{Look, MAX_OCTAVES, Octaves, Scene};

pyrograph_core::ports! {
    /// How a volume's smoke absorbs, how its fire glows and how finely it is marched: the ports
    /// volume.render and volume.render_sixway share.
    pub struct MarchPorts {
        /// Smoke extinction per unit of density per world unit.
        #[range(0.0, 1e6)]
        extinction: f32 = 8.0,
        /// Light emitted per world unit by a flame value of 1.
        #[range(0.0, 1e6)]
        exposure: f32 = 8.0,
        /// Light emitted by heat (temperature) relative to the flame's.
        #[range(0.0, 1e3)]
        glow: f32 = 0.02,
        /// Blackbody temperature, in kelvin, of temperature 0.
        #[range(100.0, 1e5)]
        kelvin_cold: f32 = 1000.0,
        /// Blackbody temperature, in kelvin, of temperature 1 (hotter gas extrapolates).
        #[range(100.0, 1e5)]
        kelvin_hot: f32 = 2600.0,
        /// March step in voxels.
        #[range(0.05, 8.0)]
        step_size: f32 = 0.5,
        /// Orders of scattering, approximated by octaves (Wrenninge 2015): 1 is single scattering; more
        /// brighten the smoke's shadowed, dense parts as light bouncing inside it does (4 with the octave
        /// defaults come closest to Mitsuba 3's path tracer on dense smoke: BENCHMARKS.md).
        #[range(1, 8)]
        scattering_octaves: u32 = 1,
        /// Each octave's share of the previous octave's light (at most `octave_extinction`).
        #[range(0.0, 1.0)]
        octave_albedo: f32 = 0.25,
        /// Each octave's shadow extinction relative to the previous octave's (thinner shadows).
        #[range(0.0, 1.0)]
        octave_extinction: f32 = 0.25,
        /// Each octave's anisotropy relative to the previous octave's (more even scattering).
        #[range(0.0, 1.0)]
        octave_anisotropy: f32 = 0.5,
    }
}

impl MarchPorts {
    /// The march's look with these ports and the node's own light and colours; an octave that
    /// would scatter more light than it lets through is an error.
    pub fn look(&self, albedo: Vec3, anisotropy: f32, ambient: Vec3, background: Vec4, seed: u64) -> Result<Look, NodeError> {
        if self.octave_albedo > self.octave_extinction {
            return Err(NodeError::port(
                port!(MarchPorts, octave_albedo),
                format!(
                    "{} is more than octave_extinction ({}): each octave would scatter more light than its thinner \
                     shadows let through, and the smoke would glow; keep octave_albedo at most octave_extinction",
                    self.octave_albedo, self.octave_extinction
                ),
            ));
        }
        let octaves = Octaves {
            count: self.scattering_octaves.clamp(1, MAX_OCTAVES as u32),
            albedo: self.octave_albedo,
            extinction: self.octave_extinction,
            anisotropy: self.octave_anisotropy,
        };
        Ok(Look {
            extinction: self.extinction,
            albedo,
            anisotropy,
            ambient,
            exposure: self.exposure,
            glow: self.glow,
            kelvin: [self.kelvin_cold, self.kelvin_hot],
            step: self.step_size,
            background,
            seed,
            octaves,
        })
    }
}

fn no_particles() -> Arc<Particles> {
    Arc::new(Particles::default())
}

pyrograph_core::node! {
    /// Ray-marches a volume through a perspective camera (Kajiya & Von Herzen 1984's single-scattering model,
    /// as Fedkiw, Stam & Jensen 2001 §4 render smoke): smoke absorbs (Beer–Lambert, `extinction` per unit
    /// density per world unit) and scatters the sun, point lights (particles.flame_lights) and the fire's own
    /// glow once, shadowed through the smoke (a transmittance volume per light) with a Henyey–Greenstein phase
    /// function, plus an unshadowed ambient light; flame and heat glow in blackbody colours (Planck's law,
    /// `temperature` 0 and 1 at `kelvin_cold` and `kelvin_hot`). Steps of `step_size` voxels, jittered per pixel,
    /// skip empty bricks and stop once a ray is opaque. An opaque mesh (the burning house) hides the smoke
    /// behind it and is seen through the smoke in front of it, lit by the sun, the lights and the fire's own
    /// light. Particle flames and sparks (Perry 1994 §3.2) sit inside the smoke: their light, drawn as
    /// particles.render_flames draws it, is dimmed by the smoke in front of each particle and hidden behind
    /// the mesh. RGBA, straight alpha, over `background`; `pass` draws a compositor's layer instead (emission,
    /// scattering, alpha, depth, motion vectors from the velocity field): render each pass with its own node
    /// and write them with imaging.write_exr_layers.
    #[node("volume.render", "Volume", PerFrame)]
    pub struct Render {
        /// The volume (volume.simulate, volume.load_vdb): density, temperature and flame fields.
        volume: Arc<Volume>,
        /// Point lights (particles.flame_lights: position, colour, intensity); default none.
        lights: Arc<Particles> = no_particles(),
        /// Particle flames inside the smoke (particles.particle_flame), drawn additively as
        /// particles.render_flames draws them, each particle dimmed by the smoke in front of it; default none.
        flames: Arc<Particles> = no_particles(),
        /// Sparks drawn with the flames (particles.embers); default none.
        sparks: Arc<Particles> = no_particles(),
        /// The flames as one continuous swept shape each (the long exposure), or as their discrete steps.
        flame_exposure: Exposure = Exposure::Continuous,
        /// An opaque mesh seen with the volume (particles.mesh_load); default none.
        mesh: Arc<Mesh> = Arc::new(Mesh::default()),
        /// The mesh's albedo.
        mesh_color: [f32; 4] = [0.3, 0.2, 0.14, 1.0],
        /// The camera.
        camera: CameraPorts = CameraPorts::looking(640, 360, [0.0, 3.0, 8.0], [0.0, 2.4, 0.0]),
        /// Extinction, the fire's glow and the march's step.
        march: MarchPorts,
        /// The smoke's single-scattering albedo (the fraction of extinction that scatters), per channel.
        albedo: [f32; 3] = [0.85, 0.85, 0.85],
        /// Henyey–Greenstein anisotropy: 0 scatters evenly, toward 1 forward (bright toward the light).
        #[range(-0.95, 0.95)]
        anisotropy: f32 = 0.3,
        /// Ambient (sky) light on the smoke, unshadowed.
        ambient: [f32; 3] = [0.2, 0.22, 0.26],
        /// Direction toward the sun (any length but 0).
        sun_direction: [f32; 3] = [0.5, 1.0, 0.3],
        /// The sun's colour and intensity: the irradiance it brings, per channel (0 for none).
        sun_color: [f32; 3] = [6.0, 5.6, 5.0],
        /// The fire lights its own smoke: a point light at the flame's centroid whose intensity is this times
        /// `exposure` times the flame's total (flame × voxel volume), in the hot blackbody colour.
        #[range(0.0, 1e6)]
        fire_light: f32 = 0.2,
        /// Background colour (straight RGBA).
        background: [f32; 4] = [0.0, 0.0, 0.0, 1.0],
        /// What to draw: the frame or one compositing pass.
        pass: VolumePass = VolumePass::Beauty,
        /// Frames per second, for the motion pass's pixels per frame.
        #[range(0.001, 1e4)]
        frame_rate: f64 = 24.0,
    }
    /// The rendered frame (RGBA, straight alpha).
    -> image: Arc<Image>
}

impl Cook for Render {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let view = self.camera.view()?;
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        for (name, v) in [
            (port!(Render, albedo), &self.albedo[..]),
            (port!(Render, ambient), &self.ambient[..]),
            (port!(Render, sun_color), &self.sun_color[..]),
            (port!(Render, sun_direction), &self.sun_direction[..]),
            (port!(Render, background), &self.background[..]),
            (port!(Render, mesh_color), &self.mesh_color[..]),
        ] {
            if !finite(v) {
                return Err(NodeError::port(name, format!("must be finite, got {v:?}")));
            }
        }
        // Light and colours are not negative; an albedo is a fraction.
        for (name, v, most) in [
            (port!(Render, albedo), &self.albedo[..], 1.0),
            (port!(Render, ambient), &self.ambient[..], f32::INFINITY),
            (port!(Render, sun_color), &self.sun_color[..], f32::INFINITY),
            (port!(Render, background), &self.background[..], f32::INFINITY),
            (port!(Render, mesh_color), &self.mesh_color[..], f32::INFINITY),
        ] {
            if v.iter().any(|x| !(0.0..=most).contains(x)) {
                let range = if most == 1.0 { "between 0 and 1" } else { "at least 0" };
                return Err(NodeError::port(name, format!("every component must be {range}, got {v:?}")));
            }
        }
        let sun = Vec3::from_array(self.sun_direction);
        if sun.length_squared() < 1e-12 {
            return Err(NodeError::port(port!(Render, sun_direction), "must not be zero: it points toward the sun"));
        }
        if let Some(k) =
            self.lights.particles.iter().position(|q| !finite(&q.position) || !q.weight.is_finite() || !finite(&q.center))
        {
            return Err(NodeError::port(
                port!(Render, lights),
                format!("light {k} has a non-finite position, colour or intensity"),
            ));
        }
        for (set, name) in [(&self.flames, port!(Render, flames)), (&self.sparks, port!(Render, sparks))] {
            if let Some(k) = set
                .particles
                .iter()
                .position(|q| !q.position.iter().chain(&q.size).chain(&q.center).chain(&q.edge).all(|x| x.is_finite()))
            {
                return Err(NodeError::port(name, format!("particle {k} has a non-finite position, size or colour")));
            }
        }
        check_fields(&self.volume).at_port(port!(Render, volume))?;
        if self.mesh.normals.len() != self.mesh.triangles.len() {
            return Err(NodeError::port(port!(Render, mesh), "the mesh has no face normals: load it with particles.mesh_load"));
        }
        if let Some(k) = self.mesh.positions.iter().position(|p| !finite(p)) {
            return Err(NodeError::port(port!(Render, mesh), format!("vertex {k} has a non-finite position")));
        }
        let vertices = self.mesh.positions.len();
        if let Some(t) = self.mesh.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= vertices)) {
            return Err(NodeError::port(
                port!(Render, mesh),
                format!("triangle {t} names a vertex past the mesh's {vertices} vertices"),
            ));
        }
        ctx.check_cancel()?;
        let mut lights = Vec::new();
        let sun_color = Vec3::from_array(self.sun_color);
        if sun_color != Vec3::ZERO {
            lights.push(Light { kind: LightKind::Directional(sun.normalize()), color: sun_color });
        }
        lights.extend(self.lights.particles.iter().map(point_light));
        lights.extend(self.fire_glow());
        let look = self.march.look(
            Vec3::from_array(self.albedo),
            self.anisotropy,
            Vec3::from_array(self.ambient),
            Vec4::from_array(self.background),
            self.volume.time.to_bits(),
        )?;
        let surfaces = (!self.mesh.triangles.is_empty()).then(|| self.surfaces(&view, sun));
        let scene =
            Scene { lights: &lights, groups: &[], surfaces: surfaces.as_deref(), motion: self.pass == VolumePass::Motion };
        let map =
            PassMap { pass: self.pass, background: look.background, view: &view, frame_seconds: (1.0 / self.frame_rate) as f32 };
        let mut pixels = march::gather(&self.volume, &view, &scene, &look, |g, s, ray| map.pixel(g, s, ray));
        // Flames are light: the scattering, depth and motion passes are the smoke's alone.
        let shows_flames = matches!(self.pass, VolumePass::Beauty | VolumePass::Emission | VolumePass::Alpha);
        if shows_flames && !(self.flames.particles.is_empty() && self.sparks.particles.is_empty()) {
            ctx.check_cancel()?;
            let smoke = Smoke { extinction: look.extinction, step: look.step * self.volume.transform.voxel_size as f32 };
            let families = [&*self.sparks, &*self.flames];
            map.add_flames(&mut pixels, &flame_light(&view, &self.volume, smoke, &families, self.flame_exposure, &self.mesh));
        }
        Ok(Arc::new(map.image(pixels)))
    }
}

impl Render {
    /// The mesh seen through each pixel, lit by the sun, the ambient light, the point lights and
    /// the fire's own light.
    fn surfaces(&self, view: &pyrograph_render::View, sun: Vec3) -> Vec<march::Surface> {
        // The smoke's lights are irradiances; a Lambert surface sends albedo × irradiance / π
        // (and albedo × the sky's radiance under the ambient sky).
        let mut lights: Vec<Particle> = self.lights.particles.iter().map(|q| Particle { weight: q.weight / PI, ..*q }).collect();
        if let Some(Light { kind: LightKind::Point(at), color }) = self.fire_glow() {
            let center = (color / PI).extend(1.0).to_array();
            lights.push(Particle { position: at.to_array(), center, weight: 1.0, ..Particle::default() });
        }
        let mean = |c: [f32; 3]| (c[0] + c[1] + c[2]) / 3.0;
        let shading = MeshShading {
            albedo: Vec3::new(self.mesh_color[0], self.mesh_color[1], self.mesh_color[2]),
            ambient: mean(self.ambient),
            sun_direction: sun.normalize(),
            sun: mean(self.sun_color) / PI,
        };
        mesh_surfaces(view, &self.mesh, &Particles { particles: lights, ..Particles::default() }, &shading)
    }

    /// The fire's own light: at the flame's centroid, its intensity the flame's total.
    fn fire_glow(&self) -> Option<Light> {
        if self.fire_light <= 0.0 {
            return None;
        }
        let at = self.volume.centroid("flame")?;
        let h = self.volume.transform.voxel_size;
        let total = (self.volume.total("flame") * h * h * h) as f32;
        let colour = blackbody::rgb(f64::from(self.march.kelvin_hot));
        (total > 0.0)
            .then(|| Light { kind: LightKind::Point(at), color: colour * (self.fire_light * self.march.exposure * total) })
    }
}

/// A flame light (particles.flame_lights) as a point light: colour in `center`, intensity in `weight`.
fn point_light(q: &Particle) -> Light {
    let rgb = Vec3::new(q.center[0], q.center[1], q.center[2]);
    Light { kind: LightKind::Point(Vec3::from_array(q.position)), color: rgb * q.weight.max(0.0) }
}

/// The fields the march reads must be finite, and the density not negative; else which is not.
fn check_fields(v: &Volume) -> Result<(), String> {
    for name in ["density", "temperature", "flame"] {
        let Some(data) = v.scalar(name) else { continue };
        if let Some(bad) = data.iter().find(|x| !x.is_finite()) {
            return Err(format!("the volume's {name} field holds {bad}"));
        }
        if name == "density"
            && let Some(min) = data.iter().copied().reduce(f32::min).filter(|m| *m < 0.0)
        {
            return Err(format!("the volume's density field goes negative (down to {min}); a density is at least 0"));
        }
    }
    Ok(())
}
