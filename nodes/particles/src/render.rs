//! Rendering particle flames through a camera (`particles.render_flames`, Perry 1994 §3.2.1–3.2.2)
//! and the per-flame point lights of §3.2.4 (`particles.flame_lights`).

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use noise::{NoiseFn, Perlin};
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, Image, NodeError, port};
use pyrograph_render::ports::CameraPorts;
use pyrograph_render::{Blend, DrawList, Vertex, View, render_image};
use pyrograph_render::{Particle, Particles};
use rayon::prelude::*;

use crate::lit_mesh::{MeshShading, draw_mesh, holdout_mesh};
use crate::passes::{RenderPass, depth_image, emission_image};
use crate::swept::{Exposure, SweptScratch, draw_steps, swept_flame, trails};
use crate::types::Mesh;

pyrograph_core::ports! {
    /// A ground plane (a horizontal square) lit by point lights: ports of `particles.render_flames`.
    #[derive(PartialEq)]
    pub struct Ground {
        /// Height of the ground plane.
        #[range(-1e6, 1e6)]
        ground_height: f32 = 0.0,
        /// Side of the ground square, centred under the camera target.
        #[range(0.0, 1e6)]
        ground_size: f32 = 30.0,
        /// Ground albedo.
        ground_color: [f32; 4] = [0.35, 0.3, 0.26, 1.0],
        /// Ambient light on the ground.
        #[range(0.0, 1.0)]
        ambient: f32 = 0.05,
    }
}

/// Cells per side of the ground grid (lighting is evaluated at the vertices, Gouraud-shaded).
const GROUND_CELLS: usize = 48;

/// Light arriving at ground point `p` (normal up) from `lights`: Σ I·rgb·cosθ / (1 + d²).
pub fn light_at(p: Vec3, lights: &Particles) -> Vec3 {
    lights
        .particles
        .iter()
        .map(|l| {
            let d = Vec3::from_array(l.position) - p;
            let dist2 = d.length_squared();
            let cos = if dist2 > 0.0 { (d.y / dist2.sqrt()).max(0.0) } else { 1.0 };
            Vec3::new(l.center[0], l.center[1], l.center[2]) * (l.weight * cos / (1.0 + dist2))
        })
        .sum()
}

/// Draws the ground plane lit by `lights`, or as a holdout (transparent black that still hides what
/// is behind it) for the emission pass.
fn draw_ground(list: &mut DrawList, ground: &Ground, center: Vec3, lights: &Particles, holdout: bool) {
    let n = GROUND_CELLS;
    let half = ground.ground_size * 0.5;
    let at = |i: usize, j: usize| {
        Vec3::new(
            center.x - half + ground.ground_size * i as f32 / n as f32,
            ground.ground_height,
            center.z - half + ground.ground_size * j as f32 / n as f32,
        )
    };
    let albedo = Vec3::new(ground.ground_color[0], ground.ground_color[1], ground.ground_color[2]);
    let vertex = |i: usize, j: usize| {
        let p = at(i, j);
        if holdout {
            return Vertex::new(p, [0.0; 4]);
        }
        let lit = albedo * (light_at(p, lights) + Vec3::splat(ground.ambient));
        Vertex::new(p, [lit.x, lit.y, lit.z, 1.0])
    };
    let verts: Vec<Vertex> = (0..=n).flat_map(|i| (0..=n).map(move |j| (i, j))).map(|(i, j)| vertex(i, j)).collect();
    let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    let tris: Vec<[u32; 3]> = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            [[a, b, c], [a, c, d]]
        })
        .collect();
    list.mesh(&verts, &tris, None, Blend::Opaque);
}

/// Draw lists of `particles` as camera-facing fuzzy N-gons (Perry 1994 §3.2.1), trajectories
/// (`particles.trails`) as one swept shape each when `exposure` is continuous (see
/// [`crate::swept`]), built in parallel chunks.
pub fn particle_lists(view: &View, particles: &Particles, exposure: Exposure, blend: Blend) -> Vec<DrawList> {
    let sides = particles.sides.max(3);
    let all = &particles.particles;
    if particles.trails && exposure == Exposure::Continuous {
        let runs = trails(all);
        let chunk = (runs.len() / (rayon::current_num_threads() * 4)).max(16);
        runs.par_chunks(chunk)
            .map(|c| {
                let mut list = DrawList::new(view);
                let mut scratch = SweptScratch::default();
                for run in c {
                    swept_flame(&mut list, &all[run.clone()], sides, blend, &mut scratch);
                }
                list
            })
            .collect()
    } else {
        let chunk = (all.len() / (rayon::current_num_threads() * 4)).max(512);
        all.par_chunks(chunk)
            .map(|c| {
                let mut list = DrawList::new(view);
                list.reserve_particles(c.len(), sides);
                draw_steps(&mut list, c, sides, blend);
                list
            })
            .collect()
    }
}

/// Renders `particles` as camera-facing fuzzy N-gons (Perry 1994 §3.2.1) over `background`
/// (straight RGBA), with an optional lit ground plane. Trajectories (`particles.trails`) are
/// drawn as one swept shape each when `exposure` is continuous (see [`crate::swept`]). Geometry
/// is built in parallel chunks and rasterized in parallel bands.
pub fn render_particles(
    view: &View,
    particles: &Particles,
    exposure: Exposure,
    blend: Blend,
    background: [f32; 4],
    ground: Option<&Ground>,
    lights: &Particles,
) -> Image {
    render_with(view, particles, exposure, blend, background, ground, lights, Vec::new())
}

/// [`render_particles`] with more draw lists (a mesh, sparks) drawn first.
#[allow(clippy::too_many_arguments)]
fn render_with(
    view: &View,
    particles: &Particles,
    exposure: Exposure,
    blend: Blend,
    background: [f32; 4],
    ground: Option<&Ground>,
    lights: &Particles,
    mut lists: Vec<DrawList>,
) -> Image {
    lists.extend(particle_lists(view, particles, exposure, blend));
    if let Some(g) = ground {
        let mut list = DrawList::new(view);
        draw_ground(&mut list, g, view.camera().target(), lights, false);
        lists.push(list);
    }
    render_image(view, &lists, background)
}

pyrograph_core::choice! {
    /// How `particles.render_flames` blends particles.
    pub enum FlameBlend {
        /// Additive to saturation (Perry).
        Additive = "additive",
        /// Alpha "over".
        Over = "over",
    }
}

impl FlameBlend {
    /// The rasterizer's blend mode.
    pub fn blend(self) -> Blend {
        match self {
            FlameBlend::Additive => Blend::Additive,
            FlameBlend::Over => Blend::Over,
        }
    }
}

/// No particles: the default of optional particle inputs (no lights, no char).
pub(crate) fn no_particles() -> Arc<Particles> {
    Arc::new(Particles::default())
}

pyrograph_core::node! {
    /// Renders particle flames through a perspective camera (Perry 1994 §3.2.1–3.2.2), blended additively to
    /// saturation (as Perry's Figure 3-3) or with "over". A flame's trajectory is drawn as its long exposure:
    /// one continuous camera-facing swept shape with the particle's cross-section and half N-gon caps
    /// (exposure = continuous), or as its discrete steps, each a camera-facing N-gon of Gouraud triangles.
    /// Sparks (particles.embers) are drawn the same way, and an optional mesh (logs) opaque, lit like the
    /// ground. An optional ground plane is lit by the flame lights of §3.2.4 (connect
    /// particles.flame_lights). Connect a Clip of flames to get a clip of frames (RGBA, straight alpha).
    /// `pass` picks what is drawn, for compositors' layers: the whole frame (beauty), the flames and sparks
    /// alone on transparent black, hidden behind the mesh and ground (emission), or the depth of the opaque mesh
    /// and ground (gray: distance along the camera's view axis in world units, the far plane where there
    /// is none). Render each pass with its own node and write them with imaging.write_exr_layers.
    #[node("particles.render_flames", "Particles", PerFrame)]
    pub struct RenderFlames {
        /// The particles to draw (particles.particle_flame).
        flames: Arc<Particles>,
        /// Point lights for the ground and the mesh (particles.flame_lights); default none.
        lights: Arc<Particles> = no_particles(),
        /// A second particle family drawn with the flames: sparks (particles.embers); default none.
        sparks: Arc<Particles> = no_particles(),
        /// An opaque mesh lit by `lights` — the logs under a campfire (particles.mesh_load); default none.
        mesh: Arc<Mesh> = Arc::new(Mesh::default()),
        /// The mesh's albedo.
        mesh_color: [f32; 4] = [0.3, 0.2, 0.14, 1.0],
        /// The camera.
        camera: CameraPorts = CameraPorts::looking(640, 480, [0.0, 3.0, 14.0], [0.0, 2.5, 0.0]),
        /// Additive to saturation (Perry) or over.
        blend: FlameBlend = FlameBlend::Additive,
        /// Flames as one continuous swept shape each (the long exposure), or as their discrete steps.
        exposure: Exposure = Exposure::Continuous,
        /// Background colour (straight RGBA).
        background: [f32; 4] = [0.0, 0.0, 0.0, 0.0],
        /// Draw a ground plane lit by `lights`.
        ground: bool = false,
        /// The ground plane.
        ground_plane: Ground,
        /// What to draw: the frame, the flames' emission alone, or the opaque geometry's depth.
        pass: RenderPass = RenderPass::Beauty,
    }
    /// The rendered frame (RGBA, straight alpha).
    -> image: Arc<Image>
}

impl Cook for RenderFlames {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let view = self.camera.view()?;
        for (set, name) in [(&self.flames, port!(RenderFlames, flames)), (&self.sparks, port!(RenderFlames, sparks))] {
            if let Some(k) = set.particles.iter().position(|q| !q.position.iter().chain(&q.size).all(|x| x.is_finite())) {
                return Err(NodeError::port(name, format!("particle {k} has a non-finite position or size")));
            }
        }
        if self.mesh.normals.len() != self.mesh.triangles.len() {
            return Err(NodeError::port(
                port!(RenderFlames, mesh),
                "the mesh has no face normals: load it with particles.mesh_load",
            ));
        }
        let ground = self.ground.then_some(&self.ground_plane);
        ctx.check_cancel()?;
        let blend = self.blend.blend();
        let mut lists = Vec::new();
        if self.pass == RenderPass::Emission {
            // The flames and sparks alone on transparent black, hidden where the mesh or the ground
            // is in front of them (holdouts), as a compositor layers them back over the beauty.
            if !self.mesh.triangles.is_empty() {
                lists.push(holdout_mesh(&view, &self.mesh));
            }
            if let Some(g) = ground {
                let mut list = DrawList::new(&view);
                draw_ground(&mut list, g, view.camera().target(), &self.lights, true);
                lists.push(list);
            }
            let holdouts = !lists.is_empty();
            if holdouts && blend != Blend::Additive {
                // The pass gives the light back its alpha (max of rgb over the opaque holdouts):
                // right for added light, wrong for flames laid "over" (a dark opaque flame would
                // turn transparent in front of the mesh only).
                return Err(NodeError::port(
                    port!(RenderFlames, blend),
                    "the emission pass over a mesh or the ground needs additive flames; use blend additive, \
                     or turn the ground off and leave the mesh unconnected for this pass",
                ));
            }
            lists.extend(particle_lists(&view, &self.sparks, self.exposure, blend));
            lists.extend(particle_lists(&view, &self.flames, self.exposure, blend));
            let image = if holdouts { emission_image(&view, &lists) } else { render_image(&view, &lists, [0.0; 4]) };
            return Ok(Arc::new(image));
        }
        if !self.mesh.triangles.is_empty() {
            let shading = MeshShading {
                albedo: Vec3::new(self.mesh_color[0], self.mesh_color[1], self.mesh_color[2]),
                ambient: self.ground_plane.ambient,
                sun_direction: Vec3::Y,
                sun: 0.0,
            };
            lists.extend(draw_mesh(&view, &self.mesh, &self.lights, &shading));
        }
        if self.pass == RenderPass::Depth {
            // Flames are light, not surfaces: only the mesh and the ground have a depth.
            if let Some(g) = ground {
                let mut list = DrawList::new(&view);
                draw_ground(&mut list, g, view.camera().target(), &self.lights, false);
                lists.push(list);
            }
            return Ok(Arc::new(depth_image(&view, &lists)));
        }
        lists.extend(particle_lists(&view, &self.sparks, self.exposure, blend));
        let image = render_with(&view, &self.flames, self.exposure, blend, self.background, ground, &self.lights, lists);
        Ok(Arc::new(image))
    }
}

pyrograph_core::ports! {
    /// Parameters of [`flame_lights`]: the ports of `particles.flame_lights` after its input.
    #[derive(PartialEq)]
    pub struct LightParams {
        /// Mean light intensity.
        #[range(0.0, 1000.0)]
        intensity: f32 = 1.0,
        /// Relative flicker amplitude.
        #[range(0.0, 1.0)]
        flicker: f32 = 0.3,
        /// Flicker rate in noise cycles per frame.
        #[range(0.0, 10.0)]
        rate: f32 = 0.35,
        /// Flicker seed.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

/// One point light per flame (Perry 1994 §3.2.4): at the mean position of the flame's particles,
/// coloured by the alpha-weighted mean centre colour (brightest channel 1), with an intensity
/// that flickers by band-limited noise over time. Lights are particles: `position`, colour in
/// `center` (alpha 1), intensity in `weight`, flame index in `group`.
pub fn flame_lights(flames: &Particles, p: &LightParams) -> Particles {
    let mut order: Vec<u32> = Vec::new();
    let mut sums: HashMap<u32, (Vec3, Vec3, usize)> = HashMap::new();
    for q in &flames.particles {
        let e = sums.entry(q.group).or_insert_with(|| {
            order.push(q.group);
            (Vec3::ZERO, Vec3::ZERO, 0)
        });
        e.0 += Vec3::from_array(q.position);
        e.1 += Vec3::new(q.center[0], q.center[1], q.center[2]) * q.center[3].max(0.0);
        e.2 += 1;
    }
    let perlin = Perlin::new(p.seed);
    let particles = order
        .iter()
        .filter_map(|g| sums.get(g).map(|s| (*g, s)))
        .map(|(g, (pos, col, n))| {
            let m = col.max_element();
            let rgb = if m > 0.0 { *col / m } else { Vec3::ONE };
            let wobble = perlin.get([(flames.time * p.rate) as f64, g as f64 * 7.31 + 0.5, 0.5]) as f32;
            let intensity = (p.intensity * (1.0 + p.flicker * 2.0 * wobble)).max(0.0);
            Particle {
                position: (*pos / *n as f32).to_array(),
                center: [rgb.x, rgb.y, rgb.z, 1.0],
                edge: [rgb.x, rgb.y, rgb.z, 1.0],
                weight: intensity,
                group: g,
                ..Particle::default()
            }
        })
        .collect();
    Particles { particles, sides: 0, time: flames.time, trails: false }
}

pyrograph_core::node! {
    /// A point light per flame (Perry 1994 §3.2.4) at the mean particle position, coloured by the flame,
    /// with an intensity that flickers with band-limited noise over time. Lights are particles (colour in
    /// `center`, intensity in `weight`); particles.render_flames uses them to light its ground plane.
    #[node("particles.flame_lights", "Particles", PerFrame)]
    pub struct FlameLights {
        /// Flame particles (particles.particle_flame).
        flames: Arc<Particles>,
        /// The lights' intensity and flicker.
        params: LightParams,
    }
    /// One light per flame.
    -> lights: Arc<Particles>
}

impl Cook for FlameLights {
    fn cook(self, _: &CookCtx) -> Result<Arc<Particles>, NodeError> {
        Ok(Arc::new(flame_lights(&self.flames, &self.params)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flame::{FlameParams, Root, simulate_frame};
    use crate::types::WindField;
    use pyrograph_core::Value;
    use pyrograph_core::declare::Declared;
    use pyrograph_render::Camera;

    fn view(w: u32, h: u32) -> View {
        let cam = Camera::new(Vec3::new(0.0, 3.0, 14.0), Vec3::new(0.0, 2.5, 0.0), Vec3::Y, 40.0, 0.1, 100.0).unwrap();
        View::new(cam, w, h).unwrap()
    }

    fn candle_frame(frame: usize) -> Particles {
        let roots = [Root { position: Vec3::ZERO, direction: Vec3::Y }];
        simulate_frame(&roots, &WindField::default(), &FlameParams::default(), frame).unwrap()
    }

    #[test]
    fn a_candle_renders_bright_in_its_core_and_dark_away_from_it() {
        let img = render_particles(
            &view(80, 60),
            &candle_frame(0),
            Exposure::Continuous,
            Blend::Additive,
            [0.0, 0.0, 0.0, 1.0],
            None,
            &Particles::default(),
        );
        let core = view(80, 60).project(Vec3::new(0.0, 2.5, 0.0)).unwrap();
        let px = img.pixel(core.x as u32, core.y as u32);
        assert!(px[0] > 0.6 && px[1] > 0.25, "core {px:?}");
        assert!(px[0] >= px[1] && px[1] >= px[2], "R ≥ G ≥ B in the flame: {px:?}");
        assert_eq!(img.pixel(2, 2), &[0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn lights_sit_at_the_mean_particle_position_and_flicker() {
        let flames = candle_frame(0);
        let p = LightParams { intensity: 2.0, flicker: 0.5, rate: 0.35, seed: 1 };
        let lights = flame_lights(&flames, &p);
        assert_eq!(lights.particles.len(), 1);
        let mean: Vec3 =
            flames.particles.iter().map(|q| Vec3::from_array(q.position)).sum::<Vec3>() / flames.particles.len() as f32;
        assert!((Vec3::from_array(lights.particles[0].position) - mean).length() < 1e-5);
        let intensities: Vec<f32> =
            (0..12).map(|t| flame_lights(&Particles { time: t as f32, ..flames.clone() }, &p).particles[0].weight).collect();
        assert!(intensities.iter().all(|i| (0.0..=4.0).contains(i)));
        assert!(intensities.windows(2).any(|w| (w[0] - w[1]).abs() > 1e-3), "{intensities:?}");
        let steady = flame_lights(&flames, &LightParams { flicker: 0.0, ..p });
        assert_eq!(steady.particles[0].weight, 2.0);
    }

    #[test]
    fn the_ground_is_brighter_under_a_light() {
        let light = Particles {
            particles: vec![Particle {
                position: [0.0, 1.0, 0.0],
                center: [1.0, 0.5, 0.2, 1.0],
                weight: 1.0,
                ..Particle::default()
            }],
            sides: 0,
            time: 0.0,
            trails: false,
        };
        let near = light_at(Vec3::ZERO, &light);
        let far = light_at(Vec3::new(5.0, 0.0, 0.0), &light);
        assert!((near - Vec3::new(0.5, 0.25, 0.1)).length() < 1e-6, "{near}");
        assert!(far.x < near.x * 0.1);
    }

    #[test]
    fn a_camera_with_zero_near_is_an_error_naming_the_port() {
        let desc = RenderFlames::desc();
        let empty = || Value::custom(no_particles());
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or_else(empty)).collect();
        let cook = |values: &[Value]| pyrograph_core::testing::read::<RenderFlames>(values)?.cook(&CookCtx::default());
        values[desc.input_index("near").unwrap()] = Value::Float(0.0);
        match cook(&values) {
            Err(NodeError::Port { port, .. }) => assert_eq!(port, "near"),
            other => panic!("{:?}", other.err()),
        }
        values[desc.input_index("near").unwrap()] = Value::Float(20.0);
        match cook(&values) {
            Err(NodeError::Port { port, .. }) => assert_eq!(port, "camera_target", "target 11 units away, near 20"),
            other => panic!("{:?}", other.err()),
        }
    }

    /// Cooks render_flames on a candle over the ground with `pass`, returning its image.
    fn pass_image(pass: &str, ground: bool) -> Arc<Image> {
        pass_image_with(pass, ground, Mesh::default())
    }

    /// [`pass_image`] with a mesh in the scene.
    fn pass_image_with(pass: &str, ground: bool, mesh: Mesh) -> Arc<Image> {
        pass_result(pass, ground, mesh, "additive").unwrap()
    }

    /// Cooks render_flames on a candle with `pass`, the ground or not, `mesh` and `blend`.
    fn pass_result(pass: &str, ground: bool, mesh: Mesh, blend: &str) -> Result<Arc<Image>, NodeError> {
        let desc = RenderFlames::desc();
        let empty = || Value::custom(no_particles());
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or_else(empty)).collect();
        let mut set = |name: &str, v: Value| values[desc.input_index(name).unwrap()] = v;
        set("flames", Value::custom(Arc::new(candle_frame(0))));
        set("width", Value::Int(80));
        set("height", Value::Int(60));
        set("ground", Value::Bool(ground));
        set("pass", Value::Enum(pass.into()));
        set("mesh", Value::custom(Arc::new(mesh)));
        set("blend", Value::Enum(blend.into()));
        pyrograph_core::testing::read::<RenderFlames>(&values)?.cook(&CookCtx::default())
    }

    #[test]
    fn the_emission_pass_over_holdouts_takes_additive_flames_only() {
        match pass_result("emission", true, Mesh::default(), "over") {
            Err(NodeError::Port { port, message }) => {
                assert_eq!(port, "blend");
                assert!(message.contains("additive"), "{message}");
            }
            other => panic!("{:?}", other.err()),
        }
        // Without holdouts the over-blended flames are their own emission, as the beauty is.
        let (emission, beauty) =
            (pass_result("emission", false, Mesh::default(), "over"), pass_result("beauty", false, Mesh::default(), "over"));
        assert_eq!(emission.unwrap().data(), beauty.unwrap().data());
    }

    #[test]
    fn the_emission_pass_is_the_flames_alone() {
        // Without ground or background, the beauty is the flames: the two passes agree exactly.
        assert_eq!(pass_image("emission", false).data(), pass_image("beauty", false).data());
        // Over the ground, the beauty has it and the emission does not.
        let (emission, beauty) = (pass_image("emission", true), pass_image("beauty", true));
        assert_eq!(emission.pixel(40, 58), &[0.0; 4], "the ground is not emission");
        assert!(beauty.pixel(40, 58)[3] > 0.99, "the beauty shows the ground there");
        let core = view(80, 60).project(Vec3::new(0.0, 2.5, 0.0)).unwrap();
        assert!(emission.pixel(core.x as u32, core.y as u32)[0] > 0.5);
    }

    #[test]
    fn a_mesh_in_front_hides_the_flame_in_the_emission_pass() {
        // A card between the camera (z = 14) and the candle's core (z = 0), over the core only.
        let mesh = Mesh {
            positions: vec![[-0.3, 2.2, 5.0], [0.3, 2.2, 5.0], [0.3, 2.8, 5.0], [-0.3, 2.8, 5.0]],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals: vec![[0.0, 0.0, 1.0]; 2],
            ..Default::default()
        };
        let core = view(80, 60).project(Vec3::new(0.0, 2.5, 0.0)).unwrap();
        let (cx, cy) = (core.x as u32, core.y as u32);
        assert!(pass_image("emission", false).pixel(cx, cy)[0] > 0.5, "the core is bright without the card");
        let emission = pass_image_with("emission", false, mesh.clone());
        assert_eq!(emission.pixel(cx, cy), &[0.0; 4], "the card holds the flame out");
        // Beside the card the flame still shows, and the beauty has the card where the emission has none.
        assert!(emission.data().chunks(4).any(|p| p[0] > 0.5));
        assert_eq!(pass_image_with("beauty", false, mesh).pixel(cx, cy)[3], 1.0);
    }

    #[test]
    fn the_depth_pass_is_the_distance_along_the_view_axis() {
        let depth = pass_image("depth", true);
        assert_eq!(depth.channels(), pyrograph_core::Channels::Gray);
        let v = view(80, 60);
        let forward = (Vec3::new(0.0, 2.5, 0.0) - Vec3::new(0.0, 3.0, 14.0)).normalize();
        // Points of the ground plane (y = 0): the pass gives their distance along the view axis.
        for p in [Vec3::new(0.0, 0.0, 6.0), Vec3::new(-2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, -6.0)] {
            let px = v.project(p).unwrap();
            // The pixel's centre is up to half a pixel from p: 3 % covers the difference.
            let got = depth.pixel(px.x as u32, px.y as u32)[0];
            let expected = (p - Vec3::new(0.0, 3.0, 14.0)).dot(forward);
            assert!((got - expected).abs() < 0.03 * expected, "{p}: {got} vs {expected}");
        }
        // Above the horizon there is nothing: the far plane.
        assert_eq!(depth.pixel(40, 0)[0], 1000.0);
        // Without ground, every pixel is far: flames have no depth.
        assert!(pass_image("depth", false).data().iter().all(|&d| d == 1000.0));
    }
}
