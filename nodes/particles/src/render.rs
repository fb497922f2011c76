//! Rendering particle flames through a camera (`particles.render_flames`, Perry 1994 §3.2.1–3.2.2)
//! and the per-flame point lights of §3.2.4 (`particles.flame_lights`).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use noise::{NoiseFn, Perlin};
use pyrograph_core::{
    CookCtx, FnNode, Image, Inputs, NodeDesc, NodeError, Particle, Particles, PortDesc, PortType, Registry, TimeDep, Value,
};
use pyrograph_render::{Blend, DrawList, Vertex, View, render_image};
use rayon::prelude::*;

/// Adds `particles.render_flames` and `particles.flame_lights`.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(render_flames_desc(), cook_render_flames));
    registry.add(FnNode::new(flame_lights_desc(), cook_flame_lights));
}

/// A ground plane (a horizontal square) lit by point lights.
#[derive(Clone, Debug, PartialEq)]
pub struct Ground {
    /// Height `y` of the plane.
    pub height: f32,
    /// Side length, centred under the camera target.
    pub size: f32,
    /// Straight RGBA albedo.
    pub color: [f32; 4],
    /// Light reaching the ground from elsewhere, 0..1.
    pub ambient: f32,
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

fn draw_ground(list: &mut DrawList, ground: &Ground, center: Vec3, lights: &Particles) {
    let n = GROUND_CELLS;
    let half = ground.size * 0.5;
    let at = |i: usize, j: usize| {
        Vec3::new(
            center.x - half + ground.size * i as f32 / n as f32,
            ground.height,
            center.z - half + ground.size * j as f32 / n as f32,
        )
    };
    let albedo = Vec3::new(ground.color[0], ground.color[1], ground.color[2]);
    let vertex = |i: usize, j: usize| {
        let p = at(i, j);
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

/// Renders `particles` as camera-facing fuzzy N-gons (Perry 1994 §3.2.1) over `background`
/// (straight RGBA), with an optional lit ground plane. Geometry is built in parallel chunks and
/// rasterized in parallel bands.
pub fn render_particles(
    view: &View,
    particles: &Particles,
    blend: Blend,
    background: [f32; 4],
    ground: Option<&Ground>,
    lights: &Particles,
) -> Image {
    let sides = particles.sides.max(3);
    let chunk = (particles.particles.len() / (rayon::current_num_threads() * 4)).max(512);
    let mut lists: Vec<DrawList> = particles
        .particles
        .par_chunks(chunk)
        .map(|c| {
            let mut list = DrawList::new(view);
            list.reserve_particles(c.len(), sides);
            for q in c {
                list.particle(Vec3::from_array(q.position), Vec2::from_array(q.size), sides, q.center, q.edge, blend);
            }
            list
        })
        .collect();
    if let Some(g) = ground {
        let mut list = DrawList::new(view);
        draw_ground(&mut list, g, view.camera().target(), lights);
        lists.push(list);
    }
    render_image(view, &lists, background)
}

fn empty_particles() -> Value {
    Value::Particles(Arc::new(Particles::default()))
}

fn render_flames_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.render_flames",
        "Particles",
        TimeDep::PerFrame,
        "Renders particle flames through a perspective camera (Perry 1994 §3.2.1–3.2.2): every particle is a \
         camera-facing N-gon of Gouraud triangles, blended additively to saturation (as Perry's Figure 3-3) \
         or with \"over\". An optional ground plane is lit by the flame lights of §3.2.4 (connect \
         particles.flame_lights). Connect a Clip of flames to get a clip of frames (RGBA, straight alpha).",
    )
    .input(PortDesc::new("flames", PortType::Particles, "The particles to draw (particles.particle_flame)."))
    .input(PortDesc {
        default: Some(empty_particles()),
        ..PortDesc::new("lights", PortType::Particles, "Point lights for the ground (particles.flame_lights); default none.")
    })
    .input(PortDesc::int("width", 640, (1, 16384), "Image width in pixels."))
    .input(PortDesc::int("height", 480, (1, 16384), "Image height in pixels."))
    .input(PortDesc::vec3("camera_position", [0.0, 3.0, 14.0], "Eye position."))
    .input(PortDesc::vec3("camera_target", [0.0, 2.5, 0.0], "Point looked at."))
    .input(PortDesc::vec3("camera_up", [0.0, 1.0, 0.0], "Up hint."))
    .input(PortDesc::float("fov", 40.0, (1.0, 179.0), "Vertical field of view in degrees."))
    .input(PortDesc::float("near", 0.1, (0.0001, 1e6), "Near plane distance."))
    .input(PortDesc::float("far", 1000.0, (0.001, 1e7), "Far plane distance."))
    .input(PortDesc::choice("blend", &["additive", "over"], "additive", "Additive to saturation (Perry) or over."))
    .input(PortDesc::color("background", [0.0, 0.0, 0.0, 0.0], "Background colour (straight RGBA)."))
    .input(PortDesc::bool("ground", false, "Draw a ground plane lit by `lights`."))
    .input(PortDesc::float("ground_height", 0.0, (-1e6, 1e6), "Height of the ground plane."))
    .input(PortDesc::float("ground_size", 30.0, (0.0, 1e6), "Side of the ground square, centred under the camera target."))
    .input(PortDesc::color("ground_color", [0.35, 0.3, 0.26, 1.0], "Ground albedo."))
    .input(PortDesc::float("ambient", 0.05, (0.0, 1.0), "Ambient light on the ground."))
    .output("image", PortType::Image, "The rendered frame (RGBA, straight alpha).")
}

pub use pyrograph_render::ports::view_from_inputs;

fn cook_render_flames(i: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let view = view_from_inputs(i)?;
    let flames = i.particles("flames")?;
    if let Some(k) = flames.particles.iter().position(|q| !q.position.iter().chain(&q.size).all(|x| x.is_finite())) {
        return Err(NodeError::port("flames", format!("particle {k} has a non-finite position or size")));
    }
    let lights = i.particles("lights")?;
    let blend = if i.choice("blend")? == "over" { Blend::Over } else { Blend::Additive };
    let ground = if i.bool("ground")? {
        Some(Ground {
            height: i.float("ground_height")? as f32,
            size: i.float("ground_size")? as f32,
            color: i.color("ground_color")?,
            ambient: i.float("ambient")? as f32,
        })
    } else {
        None
    };
    ctx.check_cancel()?;
    let image = render_particles(&view, flames, blend, i.color("background")?, ground.as_ref(), lights);
    Ok(vec![Value::Image(Arc::new(image))])
}

/// Parameters of [`flame_lights`].
#[derive(Clone, Debug, PartialEq)]
pub struct LightParams {
    /// Mean intensity of each light.
    pub intensity: f32,
    /// Relative flicker amplitude, 0..1.
    pub flicker: f32,
    /// Flicker rate: noise cycles per frame.
    pub rate: f32,
    /// Flicker seed.
    pub seed: u32,
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
    Particles { particles, sides: 0, time: flames.time }
}

fn flame_lights_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.flame_lights",
        "Particles",
        TimeDep::PerFrame,
        "A point light per flame (Perry 1994 §3.2.4) at the mean particle position, coloured by the flame, \
         with an intensity that flickers with band-limited noise over time. Lights are particles (colour in \
         `center`, intensity in `weight`); particles.render_flames uses them to light its ground plane.",
    )
    .input(PortDesc::new("flames", PortType::Particles, "Flame particles (particles.particle_flame)."))
    .input(PortDesc::float("intensity", 1.0, (0.0, 1000.0), "Mean light intensity."))
    .input(PortDesc::float("flicker", 0.3, (0.0, 1.0), "Relative flicker amplitude."))
    .input(PortDesc::float("rate", 0.35, (0.0, 10.0), "Flicker rate in noise cycles per frame."))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Flicker seed."))
    .output("lights", PortType::Particles, "One light per flame.")
}

fn cook_flame_lights(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let seed = i.int("seed")?;
    let p = LightParams {
        intensity: i.float("intensity")? as f32,
        flicker: i.float("flicker")? as f32,
        rate: i.float("rate")? as f32,
        seed: u32::try_from(seed).map_err(|_| NodeError::port("seed", format!("must be 0..=4294967295, got {seed}")))?,
    };
    Ok(vec![Value::Particles(Arc::new(flame_lights(i.particles("flames")?, &p)))])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flame::{FlameParams, Root, simulate_frame};
    use pyrograph_core::WindField;
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
        let img =
            render_particles(&view(80, 60), &candle_frame(0), Blend::Additive, [0.0, 0.0, 0.0, 1.0], None, &Particles::default());
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
        };
        let near = light_at(Vec3::ZERO, &light);
        let far = light_at(Vec3::new(5.0, 0.0, 0.0), &light);
        assert!((near - Vec3::new(0.5, 0.25, 0.1)).length() < 1e-6, "{near}");
        assert!(far.x < near.x * 0.1);
    }

    #[test]
    fn a_camera_with_zero_near_is_an_error_naming_the_port() {
        let desc = render_flames_desc();
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or_else(empty_particles)).collect();
        values[desc.input_index("near").unwrap()] = Value::Float(0.0);
        match cook_render_flames(&Inputs::new(&desc, &values), &CookCtx::default()) {
            Err(NodeError::Port { port, .. }) => assert_eq!(port, "near"),
            other => panic!("{other:?}"),
        }
        values[desc.input_index("near").unwrap()] = Value::Float(20.0);
        match cook_render_flames(&Inputs::new(&desc, &values), &CookCtx::default()) {
            Err(NodeError::Port { port, .. }) => assert_eq!(port, "camera_target", "target 11 units away, near 20"),
            other => panic!("{other:?}"),
        }
    }
}
