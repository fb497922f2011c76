//! Rendering a spreading fire (Perry 1994 §3.4): the burning mesh shaded by a key light and by the
//! flame lights of §3.2.4, char on its surface (§3.4.1), and a particle flame (§3.2.1–3.2.3)
//! grown from every live flame root of the spread; the `particles.render_fire` node.

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, Image, NodeError, port};
use pyrograph_render::ports::CameraPorts;
use pyrograph_render::{Blend, DrawList, View, render_image};
use rayon::prelude::*;

use crate::flame::{FlameColors, FlameParams, Ramp, Root, Shape, trace};
use crate::lit_mesh::{MeshShading, draw_mesh, holdout_mesh};
use crate::passes::{RenderPass, depth_image, emission_image};
use crate::render::{LightParams, flame_lights, no_particles, particle_lists};
use crate::swept::Exposure;
use crate::types::{Mesh, SpreadState, WindField};
use crate::wind::{WindSampler, validate_wind};
use pyrograph_render::{Particle, Particles};

const WIDTH_RAMP: &str = "0: 0.67; 0.5: 1.07; 1: 0.5";
const HEIGHT_RAMP: &str = "0: 0.2; 1: 0.9";

pyrograph_core::ports! {
    /// How a fire is drawn: the ports of `particles.render_fire` after its inputs and camera.
    #[derive(PartialEq)]
    pub struct FireLook {
        /// Background colour (straight RGBA).
        background: [f32; 4] = [0.02, 0.02, 0.03, 1.0],
        /// Mesh albedo.
        mesh_color: [f32; 4] = [0.62, 0.55, 0.45, 1.0],
        /// Ambient light on the mesh.
        #[range(0.0, 1.0)]
        ambient: f32 = 0.2,
        /// Direction towards the key light.
        sun_direction: [f32; 3] = [0.4, 1.0, 0.7],
        /// Key light strength.
        #[range(0.0, 10.0)]
        sun: f32 = 0.55,
        /// Frames per second of the spread (noise time = time · fps).
        #[range(1.0, 240.0)]
        fps: f32 = 24.0,
        /// Particle steps per flame.
        #[range(1, 1000)]
        steps: usize = 14,
        /// Triangles per particle.
        #[range(3, 256)]
        triangles: u32 = 12,
        /// Time step of the flame trajectory integration.
        #[range(0.001, 10.0)]
        dt: f32 = 0.03,
        /// Initial speed along the face normal.
        #[range(0.0, 100.0)]
        speed: f32 = 1.0,
        /// Re-normalize |v_p| every step (§3.2.3).
        normalize: bool = true,
        /// Particle radius in world units.
        #[range(0.0, 1000.0)]
        flame_size: f32 = 0.06,
        /// Random per-flame size variation.
        #[range(0.0, 1.0)]
        size_jitter: f32 = 0.3,
        /// Particle width scale over normalized age.
        width_ramp: Ramp<1> = Ramp::preset(WIDTH_RAMP),
        /// Particle height scale over normalized age.
        height_ramp: Ramp<1> = Ramp::preset(HEIGHT_RAMP),
        /// The particles' colours.
        colors: FlameColors = FlameColors::default(),
        /// Flames as one continuous swept shape each (the long exposure), or as their discrete steps.
        exposure: Exposure = Exposure::Continuous,
        /// Fraction of a root's life over which its flame grows in.
        #[range(0.0, 1.0)]
        grow: f32 = 0.15,
        /// Fraction of a root's life over which its flame dies out.
        #[range(0.0, 1.0)]
        die: f32 = 0.35,
        /// Light the mesh by a point light per flame (§3.2.4).
        lights: bool = true,
        /// Mean intensity of each flame light.
        #[range(0.0, 1000.0)]
        light_intensity: f32 = 0.01,
        /// Relative flicker of the flame lights.
        #[range(0.0, 1.0)]
        flicker: f32 = 0.35,
        /// Seed of the flame size variation and light flicker.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

impl FireLook {
    /// The flame grown at each root: ramp-shaped; its `lifetime`, `respawn` and `fade` are unused
    /// (roots carry their own).
    pub fn flame(&self) -> FlameParams {
        FlameParams {
            steps: self.steps,
            triangles: self.triangles,
            dt: self.dt,
            speed: self.speed,
            normalize: self.normalize,
            size: pyrograph_core::declare::Anim::constant(self.flame_size),
            size_jitter: self.size_jitter,
            shape: Shape::Ramp,
            width_ramp: self.width_ramp.clone(),
            height_ramp: self.height_ramp.clone(),
            colors: self.colors.clone(),
            seed: self.seed,
            ..FlameParams::default()
        }
    }

    /// The flame lights on the mesh (§3.2.4), if any.
    pub fn light_params(&self) -> Option<LightParams> {
        self.lights.then_some(LightParams { intensity: self.light_intensity, flicker: self.flicker, rate: 0.35, seed: self.seed })
    }
}

fn fade(age: f32, life: f32, (grow, die): (f32, f32)) -> f32 {
    let a = if life > 0.0 { (age / life).clamp(0.0, 1.0) } else { 1.0 };
    let up = if grow > 0.0 { a / grow } else { 1.0 };
    let down = if die > 0.0 { (1.0 - a) / die } else { 1.0 };
    up.min(down).clamp(0.0, 1.0)
}

/// A particle flame at every live root of `state` (Perry §3.4: the root is `p(0)`, the face normal
/// the initial direction of `v_p`), faded in and out over the root's life. Group = root id.
pub fn root_flames(state: &SpreadState, wind: &WindSampler, look: &FireLook) -> Particles {
    let p = &look.flame();
    let t = state.time * look.fps;
    let per_root: Vec<Vec<Particle>> = state
        .roots
        .par_iter()
        .map(|r| {
            let f = fade(r.age, r.lifetime, (look.grow, look.die));
            if f <= 0.0 {
                return Vec::new();
            }
            let root = Root { position: Vec3::from_array(r.position), direction: Vec3::from_array(r.direction) };
            let path = trace(&root, wind, p, t);
            if path.iter().any(|(q, _)| !q.is_finite()) {
                return Vec::new();
            }
            let jitter = 1.0 + p.size_jitter * (2.0 * crate::flame::unit_random(p.seed, r.id as usize, 3) - 1.0);
            let size = *p.size.value() * jitter * (0.35 + 0.65 * f);
            let n = path.len();
            path.iter()
                .enumerate()
                .map(|(s, (q, v))| {
                    let a = if n > 1 { s as f32 / (n - 1) as f32 } else { 0.0 };
                    let (mut center, mut edge) = (p.colors.center_ramp.eval(a), p.colors.edge_ramp.eval(a));
                    center[3] *= f;
                    edge[3] *= f;
                    Particle {
                        position: q.to_array(),
                        velocity: v.to_array(),
                        size: (p.scale(s, n) * size).to_array(),
                        center,
                        edge,
                        weight: s as f32,
                        group: r.id,
                    }
                })
                .collect()
        })
        .collect();
    Particles { particles: per_root.concat(), sides: p.triangles, time: t, trails: true }
}

fn draw_char(view: &View, chars: &Particles) -> DrawList {
    let mut list = DrawList::new(view);
    let sides = chars.sides.clamp(3, 64);
    list.reserve_particles(chars.particles.len(), sides);
    for q in &chars.particles {
        let c = Vec3::from_array(q.position);
        let n = Vec3::from_array(q.velocity).normalize_or_zero();
        if n == Vec3::ZERO || !c.is_finite() {
            continue;
        }
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        list.disc(c, (u * q.size[0], w * q.size[1]), sides, q.center, q.edge, Blend::Over);
    }
    list
}

/// Why a frame of a burning mesh could not be drawn.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FireError {
    /// A flame parameter no flame can be made with: its field (port) and why.
    #[error("port '{0}': {1}")]
    Param(&'static str, String),
    /// The wind field is not finite.
    #[error("{0}")]
    Wind(String),
    /// The mesh cannot be drawn.
    #[error("{0}")]
    Mesh(&'static str),
}

/// One frame of a burning mesh (Perry §3.4): the mesh shaded by a key light and the flame lights,
/// char discs laid on the surface (blended "over"), and the root flames added to saturation; or
/// one of its compositing passes (the flames alone behind the mesh as a holdout, the mesh's depth).
pub fn render_fire(
    view: &View,
    mesh: &Mesh,
    state: &SpreadState,
    wind: &WindField,
    chars: &Particles,
    look: &FireLook,
    pass: RenderPass,
) -> Result<Image, FireError> {
    if let Some((field, why)) = look.flame().problem() {
        return Err(FireError::Param(field, why));
    }
    validate_wind(wind).map_err(FireError::Wind)?;
    if mesh.normals.len() != mesh.triangles.len() {
        return Err(FireError::Mesh("the mesh has no face normals: load it with particles.mesh_load"));
    }
    let sampler = WindSampler::new(wind);
    let flames = root_flames(state, &sampler, look);
    let lights = match look.light_params() {
        Some(lp) => flame_lights(&flames, &lp),
        None => Particles::default(),
    };
    let shading = MeshShading {
        albedo: Vec3::new(look.mesh_color[0], look.mesh_color[1], look.mesh_color[2]),
        ambient: look.ambient,
        sun_direction: Vec3::from_array(look.sun_direction).normalize_or_zero(),
        sun: look.sun,
    };
    match pass {
        RenderPass::Beauty => {
            let mut lists = draw_mesh(view, mesh, &lights, &shading);
            lists.push(draw_char(view, chars));
            lists.extend(particle_lists(view, &flames, look.exposure, Blend::Additive));
            Ok(render_image(view, &lists, look.background))
        }
        // The flames alone, hidden behind the mesh; the char is the surface's, not light.
        RenderPass::Emission => {
            let mut lists = vec![holdout_mesh(view, mesh)];
            lists.extend(particle_lists(view, &flames, look.exposure, Blend::Additive));
            Ok(emission_image(view, &lists))
        }
        RenderPass::Depth => Ok(depth_image(view, &[holdout_mesh(view, mesh)])),
    }
}

pyrograph_core::node! {
    /// Renders a spreading fire (Perry 1994 §3.4): the mesh, Gouraud-shaded by a key light and by a point light
    /// per flame (§3.2.4); char discs laid flat on the surface (§3.4.1, connect particles.char); and at every
    /// live flame root of the spread a particle flame (§3.2.1–3.2.3) that starts along the face normal, moves
    /// through the wind field, grows in after the root is dropped and dies out at the end of its lifetime l_f.
    /// Flames blend additively to saturation. Connect the Clip<SpreadState> of particles.fire_spread to get a
    /// clip of frames. `pass` draws a compositor's layer instead of the frame: the flames alone on transparent
    /// black, hidden behind the mesh (emission), or the mesh's distance along the view axis (depth, gray).
    #[node("particles.render_fire", "Particles", PerFrame)]
    pub struct RenderFire {
        /// Spread state (particles.fire_spread).
        spread: Arc<SpreadState>,
        /// The burning mesh (particles.mesh_load).
        mesh: Arc<Mesh>,
        /// Wind field the flames move in (particles.wind_field).
        wind: Arc<WindField> = Arc::new(WindField::default()),
        /// Char discs (particles.char); default none.
        char: Arc<Particles> = no_particles(),
        /// The camera.
        camera: CameraPorts = CameraPorts {
            near: 0.05,
            far: 100.0,
            ..CameraPorts::looking(640, 360, [2.2, 1.5, 2.6], [0.0, 0.2, 0.0])
        },
        /// How the fire looks.
        look: FireLook,
        /// What to draw: the frame, the flames' emission alone, or the mesh's depth.
        pass: RenderPass = RenderPass::Beauty,
    }
    /// The rendered frame (RGBA, straight alpha).
    -> image: Arc<Image>
}

impl Cook for RenderFire {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let view = self.camera.view()?;
        ctx.check_cancel()?;
        let image =
            render_fire(&view, &self.mesh, &self.spread, &self.wind, &self.char, &self.look, self.pass).map_err(|e| match e {
                // The look's port for the flames' size is `flame_size`.
                FireError::Param(port, why) if port == port!(FlameParams, size) => {
                    NodeError::port(port!(FireLook, flame_size), why)
                }
                FireError::Param(port, why) => NodeError::port(port, why),
                FireError::Wind(why) => NodeError::port(port!(RenderFire, wind), why),
                FireError::Mesh(why) => NodeError::port(port!(RenderFire, mesh), why),
            })?;
        Ok(Arc::new(image))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{build_mesh, cube};
    use crate::spread::{Ignition, Spread, SpreadParams, Surface, spread_wind};
    use pyrograph_render::Camera;

    #[test]
    fn a_burning_cube_shows_the_mesh_the_flames_and_the_char() {
        let mesh = build_mesh(&cube(1.0, 4), 0, true).unwrap();
        let surface = Arc::new(Surface::new(&mesh).unwrap());
        let (face, bary, _) = surface.nearest(Vec3::new(0.0, 0.5, 0.0));
        // l_f = 6 frames at 10 fps: 0.6 s.
        let params = SpreadParams { lifetime: 6, ..SpreadParams::default() };
        let mut s = Spread::new(surface, vec![Ignition { face, bary, time: 0.0 }], params, 10.0).unwrap();
        let wind = WindField::default();
        let w = spread_wind(&wind);
        for _ in 0..36 {
            s.step(1.0 / 24.0, &w);
        }
        let state = s.state();
        assert!(!state.roots.is_empty() && !state.char_marks.is_empty());
        let chars =
            crate::char_marks::char_particles(&state, &crate::char_marks::CharParams { glow: false, ..Default::default() });
        let cam = Camera::new(Vec3::new(0.0, 3.0, 0.01), Vec3::ZERO, Vec3::Y, 40.0, 0.05, 100.0).unwrap();
        let view = View::new(cam, 96, 96).unwrap();
        let look = FireLook::default();
        let img = render_fire(&view, &mesh, &state, &wind, &chars, &look, RenderPass::Beauty).unwrap();
        let px = |x: u32, y: u32| {
            let d = img.data();
            let k = ((y * 96 + x) * 4) as usize;
            [d[k], d[k + 1], d[k + 2]]
        };
        // Looking down on the top face (it spans pixels ≈ 22–74): its corner is lit mesh, the
        // burning ring around the ignition point is bright flame.
        let corner = px(25, 25);
        assert!(corner[0] > 0.1 && corner[0] < 0.9, "mesh {corner:?}");
        let bright = img.data().chunks(4).filter(|p| p[0] > 0.95 && p[1] > 0.3).count();
        assert!(bright > 20, "flame pixels: {bright}");
        let none =
            render_fire(&view, &mesh, &SpreadState::default(), &wind, &Particles::default(), &look, RenderPass::Beauty).unwrap();
        assert!(none.data().chunks(4).all(|p| p[0] < 0.95), "no roots, no flames");
        // The emission pass: the flames without the mesh (its corner transparent black), as bright.
        let emission = render_fire(&view, &mesh, &state, &wind, &chars, &look, RenderPass::Emission).unwrap();
        assert_eq!(&emission.data()[((25 * 96 + 25) * 4)..][..4], &[0.0; 4], "the mesh is a holdout");
        let lit = emission.data().chunks(4).filter(|p| p[0] > 0.95 && p[1] > 0.3).count();
        assert!(lit > 20 && lit <= bright + 5, "emission flame pixels: {lit} (beauty {bright})");
        // The depth pass: the top face (y = 0.5 under a camera at y = 3 looking down) is 2.5 away.
        let depth = render_fire(&view, &mesh, &state, &wind, &chars, &look, RenderPass::Depth).unwrap();
        let top = depth.pixel(48, 48)[0];
        assert!((top - 2.5).abs() < 0.01, "{top}");
        assert_eq!(depth.pixel(2, 2)[0], 100.0, "beside the cube: the far plane");
    }
}
