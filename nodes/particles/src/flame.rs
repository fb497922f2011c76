//! Perry's particle flames (Perry 1994 §3.2.1–3.2.3): each flame is the long-exposure
//! trajectory of one fuzzy particle moved through the wind field, plus the `particles.roots`
//! and `particles.particle_flame` nodes.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{
    Clip, CookCtx, FnNode, FrameSource, Inputs, NodeDesc, NodeError, Particle, Particles, PortDesc, PortType, Registry, TimeDep,
    Value, WindField,
};
use rayon::prelude::*;

use crate::wind::{WindSampler, validate_wind};

/// Adds `particles.roots` and `particles.particle_flame`.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(roots_desc(), cook_roots));
    registry.add(FnNode::new(particle_flame_desc(), cook_particle_flame));
}

/// A piecewise-linear ramp over normalized age 0..1 with `N` components per key.
#[derive(Clone, Debug, PartialEq)]
pub struct Ramp<const N: usize> {
    keys: Vec<(f32, [f32; N])>,
}

impl<const N: usize> Ramp<N> {
    /// A ramp from keys `(position, value)`; sorted by position. `None` when empty or not finite.
    pub fn new(mut keys: Vec<(f32, [f32; N])>) -> Option<Self> {
        if keys.is_empty() || keys.iter().any(|(p, v)| !p.is_finite() || v.iter().any(|x| !x.is_finite())) {
            return None;
        }
        keys.sort_by(|a, b| a.0.total_cmp(&b.0));
        Some(Ramp { keys })
    }

    /// Parses `"pos: v…; pos: v…"`, e.g. `"0: 1 0.5 0 1; 1: 1 0 0 0"` (N = 4) or `"0: 1; 1: 0.5"`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut keys = Vec::new();
        for part in text.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            let (pos, vals) =
                part.split_once(':').ok_or_else(|| format!("key '{part}' is not of the form 'position: values'"))?;
            let pos: f32 = pos.trim().parse().map_err(|_| format!("'{}' is not a number", pos.trim()))?;
            let nums: Vec<f32> = vals
                .split([' ', ','])
                .filter(|s| !s.is_empty())
                .map(|s| s.parse::<f32>().map_err(|_| format!("'{s}' is not a number")))
                .collect::<Result<_, _>>()?;
            let vals: [f32; N] =
                nums.try_into().map_err(|v: Vec<f32>| format!("key at {pos} has {} values, needs {N}", v.len()))?;
            keys.push((pos, vals));
        }
        Ramp::new(keys).ok_or_else(|| "needs at least one key of finite numbers".to_string())
    }

    /// The value at `t`, clamped to the first and last keys.
    pub fn eval(&self, t: f32) -> [f32; N] {
        let k = &self.keys;
        let i = k.partition_point(|(p, _)| *p <= t);
        if i == 0 {
            return k[0].1;
        }
        if i == k.len() {
            return k[k.len() - 1].1;
        }
        let ((p0, a), (p1, b)) = (k[i - 1], k[i]);
        let f = if p1 > p0 { (t - p0) / (p1 - p0) } else { 0.0 };
        std::array::from_fn(|c| a[c] + (b[c] - a[c]) * f)
    }
}

/// How a particle's x/y scale changes with age.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Perry's footnote 1: `x = x_base + x_amp·sin(π·age/max_age)`, `y = y_slope·age` (age in steps).
    Perry {
        /// 0.67 in Figure 3-3.
        x_base: f32,
        /// 0.4 in Figure 3-3.
        x_amp: f32,
        /// 0.032 in Figure 3-3.
        y_slope: f32,
    },
    /// User ramps of the x and y scale over normalized age.
    Ramp {
        /// Width (x) scale.
        width: Ramp<1>,
        /// Height (y) scale.
        height: Ramp<1>,
    },
}

impl Shape {
    /// Perry's Figure 3-3 constants.
    pub fn perry() -> Self {
        Shape::Perry { x_base: 0.67, x_amp: 0.4, y_slope: 0.032 }
    }

    /// The `(x, y)` scale of a particle of age `step` in a trajectory of `steps` steps.
    pub fn scale(&self, step: usize, steps: usize) -> Vec2 {
        let a = if steps > 1 { step as f32 / (steps - 1) as f32 } else { 0.0 };
        match self {
            Shape::Perry { x_base, x_amp, y_slope } => {
                Vec2::new(x_base + x_amp * (std::f32::consts::PI * a).sin(), y_slope * step as f32)
            }
            Shape::Ramp { width, height } => Vec2::new(width.eval(a)[0], height.eval(a)[0]),
        }
    }
}

/// Everything about a flame but its root and its wind.
#[derive(Clone, Debug, PartialEq)]
pub struct FlameParams {
    /// Particle steps per flame (Figure 3-3: 25).
    pub steps: usize,
    /// Triangles per particle (Figure 3-3: 20).
    pub sides: u32,
    /// Time step of the finite-difference integration.
    pub dt: f32,
    /// Initial speed along the root's direction; with `normalize`, the speed kept at every step.
    pub speed: f32,
    /// Re-normalize the velocity magnitude every step (§3.2.3, used for intense winds).
    pub normalize: bool,
    /// Radius of the unit-circle particle in world units.
    pub size: f32,
    /// Per-flame random size variation, 0..1.
    pub size_jitter: f32,
    /// Particle shape over age.
    pub shape: Shape,
    /// Centre vertex RGBA over normalized age.
    pub center: Ramp<4>,
    /// Rim vertex RGBA over normalized age.
    pub edge: Ramp<4>,
    /// Flame lifetime l_f in frames (Table 3.1).
    pub lifetime: u32,
    /// Per-flame random lifetime variation, 0..1.
    pub lifetime_jitter: f32,
    /// A flame whose lifetime ends is reborn at its root (with a random phase per flame).
    pub respawn: bool,
    /// Frames over which a flame fades in after birth and out before death (0: no fade).
    pub fade: u32,
    /// Seed of the per-flame variations.
    pub seed: u32,
}

impl Default for FlameParams {
    fn default() -> Self {
        FlameParams {
            steps: 25,
            sides: 20,
            dt: 0.1,
            speed: 1.0,
            normalize: false,
            size: 1.0,
            size_jitter: 0.0,
            shape: Shape::perry(),
            center: Ramp::parse(DEFAULT_CENTER).unwrap_or(Ramp { keys: vec![(0.0, [1.0; 4])] }),
            edge: Ramp::parse(DEFAULT_EDGE).unwrap_or(Ramp { keys: vec![(0.0, [1.0, 1.0, 1.0, 0.0])] }),
            lifetime: 1000,
            lifetime_jitter: 0.0,
            respawn: false,
            fade: 0,
            seed: 0,
        }
    }
}

/// Candle centre colour: blue at the base, yellow-white body, orange tip fading out.
pub const DEFAULT_CENTER: &str = "0: 0.3 0.4 1 0.5; 0.15: 1 0.85 0.5 0.6; 0.6: 1 0.55 0.15 0.45; 1: 0.9 0.2 0.02 0";
/// Candle rim colour: the centre's hues, transparent, so particles are fuzzy.
pub const DEFAULT_EDGE: &str = "0: 0.2 0.25 1 0; 0.3: 1 0.5 0.1 0; 1: 0.8 0.15 0 0";

/// Where a flame starts and where it first heads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// The base `p(0)`.
    pub position: Vec3,
    /// Initial direction of `v_p` (normalized; zero means straight up).
    pub direction: Vec3,
}

impl Root {
    /// Roots from particles: position, and velocity as direction.
    pub fn from_particles(p: &Particles) -> Vec<Root> {
        p.particles
            .iter()
            .map(|q| Root { position: Vec3::from_array(q.position), direction: Vec3::from_array(q.velocity) })
            .collect()
    }
}

/// A deterministic uniform number in 0..1 from `(seed, flame, salt)` (SplitMix64).
pub fn unit_random(seed: u32, flame: usize, salt: u64) -> f32 {
    let mut z = (seed as u64) ^ ((flame as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) ^ salt.wrapping_mul(0xD1B5_4A32_D192_ED69);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// Checks parameters that no port range can: errors name the port.
pub fn validate_params(p: &FlameParams) -> Result<(), NodeError> {
    if p.steps == 0 {
        return Err(NodeError::port("steps", "must be at least 1: a flame is the trajectory of at least one particle step"));
    }
    if p.sides < 3 {
        return Err(NodeError::port("triangles", format!("a particle needs at least 3 triangles, got {}", p.sides)));
    }
    for (name, v) in [
        ("dt", p.dt),
        ("speed", p.speed),
        ("size", p.size),
        ("size_jitter", p.size_jitter),
        ("lifetime_jitter", p.lifetime_jitter),
    ] {
        if !v.is_finite() {
            return Err(NodeError::port(name, format!("must be finite, got {v}")));
        }
    }
    if p.lifetime == 0 {
        return Err(NodeError::port("lifetime", "must be at least 1 frame"));
    }
    Ok(())
}

/// The positions and velocities of one flame's particle over its `steps` steps at time `t`
/// (frames): `v(s+1) = v(s) + u∞(p(s), t)·dt` (optionally re-normalized), `p(s+1) = p(s) + v(s+1)·dt`.
pub fn trace(root: &Root, wind: &WindSampler, p: &FlameParams, t: f32) -> Vec<(Vec3, Vec3)> {
    let dir = if root.direction.length_squared() > 1e-12 { root.direction.normalize() } else { Vec3::Y };
    let (mut pos, mut vel) = (root.position, dir * p.speed);
    let mut out = Vec::with_capacity(p.steps);
    for s in 0..p.steps {
        out.push((pos, vel));
        if s + 1 == p.steps {
            break;
        }
        vel += wind.at(pos, root.position, t) * p.dt;
        if p.normalize {
            vel = vel.normalize_or_zero() * p.speed;
        }
        pos += vel * p.dt;
    }
    out
}

/// Frame `frame` of flames rooted at `roots`: every live flame's trajectory as fuzzy particles
/// (group = flame index, weight = age in steps), in root order. Deterministic for given inputs.
pub fn simulate_frame(roots: &[Root], wind: &WindField, p: &FlameParams, frame: usize) -> Result<Particles, NodeError> {
    validate_params(p)?;
    validate_wind(wind, "wind")?;
    let sampler = WindSampler::new(wind);
    let t = frame as f32;
    let per_flame: Vec<Vec<Particle>> = roots
        .par_iter()
        .enumerate()
        .map(|(i, root)| flame_particles(i, root, &sampler, p, frame, t))
        .collect::<Result<_, _>>()?;
    Ok(Particles { particles: per_flame.concat(), sides: p.sides, time: t })
}

/// Lifetime of flame `i` and its age at `frame`, or `None` when it is not alive.
pub fn flame_age(i: usize, p: &FlameParams, frame: usize) -> Option<(u32, u32)> {
    let jitter = p.lifetime_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(p.seed, i, 1) - 1.0);
    let life = ((p.lifetime as f32 * (1.0 + jitter)).round() as u32).max(1);
    if p.respawn {
        let phase = (unit_random(p.seed, i, 2) * life as f32) as u64;
        Some((life, ((frame as u64 + phase) % life as u64) as u32))
    } else {
        (frame < life as usize).then_some((life, frame as u32))
    }
}

fn flame_particles(
    i: usize,
    root: &Root,
    wind: &WindSampler,
    p: &FlameParams,
    frame: usize,
    t: f32,
) -> Result<Vec<Particle>, NodeError> {
    let Some((life, age)) = flame_age(i, p, frame) else { return Ok(Vec::new()) };
    let fade =
        if p.fade == 0 { 1.0 } else { ((age + 1) as f32 / p.fade as f32).min((life - age) as f32 / p.fade as f32).min(1.0) };
    let size = p.size * (1.0 + p.size_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(p.seed, i, 3) - 1.0));
    let path = trace(root, wind, p, t);
    if path.iter().any(|(q, v)| !q.is_finite() || !v.is_finite()) {
        return Err(NodeError::port("wind", format!("flame {i}: the wind field drives the particle to a non-finite position")));
    }
    let n = path.len();
    Ok(path
        .iter()
        .enumerate()
        .map(|(s, (q, v))| {
            let a = if n > 1 { s as f32 / (n - 1) as f32 } else { 0.0 };
            let mut center = p.center.eval(a);
            let mut edge = p.edge.eval(a);
            center[3] *= fade;
            edge[3] *= fade;
            let half = p.shape.scale(s, n) * size;
            Particle {
                position: q.to_array(),
                velocity: v.to_array(),
                size: half.to_array(),
                center,
                edge,
                weight: s as f32,
                group: i as u32,
            }
        })
        .collect())
}

fn roots_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.roots",
        "Particles",
        TimeDep::Source,
        "Flame roots: base points p(0) with initial directions of v_p (Perry 1994 §3.2.3, §3.4), laid out \
         as a row (candles), a grid, a ring or a random disc (a campfire bed). Output particles carry the \
         root in `position` and the direction in `velocity`.",
    )
    .input(PortDesc::choice("layout", &["row", "grid", "ring", "disc"], "row", "How the roots are placed."))
    .input(PortDesc::int("count", 1, (1, 100_000), "Number of roots."))
    .input(PortDesc::vec3("center", [0.0, 0.0, 0.0], "Centre of the layout."))
    .input(PortDesc::float("spacing", 2.5, (0.0, 1000.0), "Distance between neighbours (row, grid)."))
    .input(PortDesc::float("radius", 2.0, (0.0, 1000.0), "Radius (ring, disc)."))
    .input(PortDesc::vec3("direction", [0.0, 1.0, 0.0], "Initial direction of every flame."))
    .input(PortDesc::float("spread", 0.0, (0.0, 1.0), "Random tilt of each direction (0: all equal)."))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Seed of disc placement and tilt."))
    .output("roots", PortType::Particles, "Root particles.")
}

/// Root positions and directions for a layout (see `particles.roots`).
#[allow(clippy::too_many_arguments)]
pub fn layout_roots(
    layout: &str,
    count: usize,
    center: Vec3,
    spacing: f32,
    radius: f32,
    direction: Vec3,
    spread: f32,
    seed: u32,
) -> Vec<Root> {
    let dir = if direction.length_squared() > 1e-12 { direction.normalize() } else { Vec3::Y };
    let cols = (count as f32).sqrt().ceil().max(1.0) as usize;
    (0..count)
        .map(|i| {
            let offset = match layout {
                "grid" => {
                    let (r, c) = ((i / cols) as f32, (i % cols) as f32);
                    let rows = count.div_ceil(cols) as f32;
                    Vec3::new((c - (cols as f32 - 1.0) / 2.0) * spacing, 0.0, (r - (rows - 1.0) / 2.0) * spacing)
                }
                "ring" => {
                    let a = std::f32::consts::TAU * i as f32 / count as f32;
                    Vec3::new(a.cos() * radius, 0.0, a.sin() * radius)
                }
                "disc" => {
                    let r = radius * unit_random(seed, i, 11).sqrt();
                    let a = std::f32::consts::TAU * unit_random(seed, i, 12);
                    Vec3::new(a.cos() * r, 0.0, a.sin() * r)
                }
                _ => Vec3::new((i as f32 - (count as f32 - 1.0) / 2.0) * spacing, 0.0, 0.0),
            };
            let tilt = Vec3::new(unit_random(seed, i, 13) - 0.5, unit_random(seed, i, 14) - 0.5, unit_random(seed, i, 15) - 0.5);
            let d = (dir + tilt * (2.0 * spread)).normalize_or_zero();
            Root { position: center + offset, direction: if d == Vec3::ZERO { dir } else { d } }
        })
        .collect()
}

fn finite_vec3(i: &Inputs<'_>, name: &str) -> Result<Vec3, NodeError> {
    let v = i.vec3(name)?;
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    } else {
        Err(NodeError::port(name, format!("must be finite, got ({}, {}, {})", v[0], v[1], v[2])))
    }
}

fn seed(i: &Inputs<'_>, name: &str) -> Result<u32, NodeError> {
    let v = i.int(name)?;
    u32::try_from(v).map_err(|_| NodeError::port(name, format!("must be 0..=4294967295, got {v}")))
}

fn cook_roots(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let roots = layout_roots(
        i.choice("layout")?,
        i.usize("count")?,
        finite_vec3(i, "center")?,
        i.float("spacing")? as f32,
        i.float("radius")? as f32,
        finite_vec3(i, "direction")?,
        i.float("spread")? as f32,
        seed(i, "seed")?,
    );
    let particles = roots
        .iter()
        .enumerate()
        .map(|(k, r)| Particle {
            position: r.position.to_array(),
            velocity: r.direction.to_array(),
            group: k as u32,
            ..Particle::default()
        })
        .collect();
    Ok(vec![Value::Particles(Arc::new(Particles { particles, sides: 0, time: 0.0 }))])
}

fn particle_flame_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.particle_flame",
        "Particles",
        TimeDep::Simulation,
        "Perry's particle flames (Perry 1994 §3.2.1–3.2.3): each root grows a flame that is the long-exposure \
         trajectory of one particle of `triangles` Gouraud triangles (a fuzzy N-gon: centre vertex with the \
         centre RGBA, rim vertices with the edge RGBA) moved `steps` steps through the wind field by \
         v(s+1) = v(s) + u∞·dt, optionally re-normalized. The particle's x/y scale follows footnote 1 \
         (0.67 + 0.4 sin(π·age/24), y slope 0.032) or user ramps; colours follow centre and edge ramps over \
         age (`pos: r g b a; …`). Each flame has a lifetime l_f (Table 3.1) with per-flame jitter from \
         `seed`. Frame T samples the noise at k_p·p − k_s·T·ĵ, so frames are deterministic and independent. \
         Render with particles.render_flames.",
    )
    .input(PortDesc::new("roots", PortType::Particles, "Flame roots (position, direction in velocity): particles.roots."))
    .input(PortDesc {
        default: Some(Value::WindField(Arc::new(WindField::default()))),
        ..PortDesc::new("wind", PortType::WindField, "Wind field (particles.wind_field); default: Perry's candle wind.")
    })
    .input(PortDesc::int("frames", 48, (1, 100_000), "Number of frames."))
    .input(PortDesc::float("fps", 24.0, (1.0, 240.0), "Frames per second."))
    .input(PortDesc::int("steps", 25, (1, 1000), "Particle steps per flame (Figure 3-3: 25)."))
    .input(PortDesc::int("triangles", 20, (3, 256), "Triangles per particle (Figure 3-3: 20)."))
    .input(PortDesc::float("dt", 0.1, (0.001, 10.0), "Time step of the trajectory integration."))
    .input(PortDesc::float("speed", 1.0, (0.0, 100.0), "Initial speed along the root direction; with normalize, the kept speed."))
    .input(PortDesc::bool("normalize", false, "Re-normalize |v_p| every step (§3.2.3; for intense winds)."))
    .input(PortDesc::float("size", 1.0, (0.0, 1000.0), "Particle radius in world units (footnote 1: unit circle)."))
    .input(PortDesc::float("size_jitter", 0.0, (0.0, 1.0), "Random per-flame size variation."))
    .input(PortDesc::choice("shape", &["perry", "ramp"], "perry", "Footnote 1's sine/linear shape, or the width/height ramps."))
    .input(PortDesc::float("x_base", 0.67, (0.0, 100.0), "Footnote 1 width scale at the base (0.67)."))
    .input(PortDesc::float("x_amp", 0.4, (-100.0, 100.0), "Footnote 1 width bulge amplitude (0.4)."))
    .input(PortDesc::float("y_slope", 0.032, (0.0, 10.0), "Footnote 1 height scale growth per step (0.032)."))
    .input(PortDesc::string("width_ramp", "0: 0.67; 0.5: 1.07; 1: 0.67", "Width scale over normalized age (shape = ramp)."))
    .input(PortDesc::string("height_ramp", "0: 0; 1: 0.768", "Height scale over normalized age (shape = ramp)."))
    .input(PortDesc::string("center_ramp", DEFAULT_CENTER, "Centre vertex RGBA over normalized age: `pos: r g b a; …`."))
    .input(PortDesc::string("edge_ramp", DEFAULT_EDGE, "Rim vertex RGBA over normalized age: `pos: r g b a; …`."))
    .input(PortDesc::int("lifetime", 1000, (1, 1000), "Flame lifetime l_f in frames (Table 3.1)."))
    .input(PortDesc::float("lifetime_jitter", 0.0, (0.0, 1.0), "Random per-flame lifetime variation."))
    .input(PortDesc::bool("respawn", false, "Rebirth a flame at its root when its lifetime ends."))
    .input(PortDesc::int("fade", 0, (0, 1000), "Frames of fade-in after birth and fade-out before death."))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Seed of the per-flame variations."))
    .output("flames", PortType::clip_of(PortType::Particles), "Per frame, every live flame's particles.")
}

fn ramp<const N: usize>(i: &Inputs<'_>, name: &str) -> Result<Ramp<N>, NodeError> {
    Ramp::parse(i.string(name)?).map_err(|m| NodeError::port(name, m))
}

/// Reads [`FlameParams`] from the node's inputs; errors name the port.
pub fn params_from_inputs(i: &Inputs<'_>) -> Result<FlameParams, NodeError> {
    let shape = match i.choice("shape")? {
        "ramp" => Shape::Ramp { width: ramp(i, "width_ramp")?, height: ramp(i, "height_ramp")? },
        _ => Shape::Perry {
            x_base: i.float("x_base")? as f32,
            x_amp: i.float("x_amp")? as f32,
            y_slope: i.float("y_slope")? as f32,
        },
    };
    let lifetime = i.usize("lifetime")?;
    let p = FlameParams {
        steps: i.usize("steps")?,
        sides: u32::try_from(i.usize("triangles")?).map_err(|_| NodeError::port("triangles", "too large"))?,
        dt: i.float("dt")? as f32,
        speed: i.float("speed")? as f32,
        normalize: i.bool("normalize")?,
        size: i.float("size")? as f32,
        size_jitter: i.float("size_jitter")? as f32,
        shape,
        center: ramp(i, "center_ramp")?,
        edge: ramp(i, "edge_ramp")?,
        lifetime: u32::try_from(lifetime).map_err(|_| NodeError::port("lifetime", "too large"))?,
        lifetime_jitter: i.float("lifetime_jitter")? as f32,
        respawn: i.bool("respawn")?,
        fade: u32::try_from(i.usize("fade")?).map_err(|_| NodeError::port("fade", "too large"))?,
        seed: seed(i, "seed")?,
    };
    validate_params(&p)?;
    Ok(p)
}

struct FlameSource {
    roots: Vec<Root>,
    wind: WindField,
    params: FlameParams,
    frames: usize,
}

impl FrameSource for FlameSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::Particles(Arc::new(simulate_frame(&self.roots, &self.wind, &self.params, index)?)))
    }
}

fn cook_particle_flame(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let roots_value = i.get("roots")?;
    let roots = Root::from_particles(i.particles("roots")?);
    if let Some(k) = roots.iter().position(|r| !r.position.is_finite() || !r.direction.is_finite()) {
        return Err(NodeError::port("roots", format!("root {k} has a non-finite position or direction")));
    }
    let wind_value = i.get("wind")?;
    let wind = (**i.wind_field("wind")?).clone();
    validate_wind(&wind, "wind")?;
    let params = params_from_inputs(i)?;
    let frames = i.usize("frames")?;
    let fps = i.float("fps")?;
    let mut h = Fingerprinter::new();
    "particles.particle_flame".hash(&mut h);
    roots_value.hash_into(&mut h);
    wind_value.hash_into(&mut h);
    format!("{params:?}").hash(&mut h);
    frames.hash(&mut h);
    let clip = Clip::new(PortType::Particles, fps, h.finish(), Arc::new(FlameSource { roots, wind, params, frames }));
    Ok(vec![Value::Clip(clip)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::LargeWind;

    fn up_root(x: f32, z: f32) -> Root {
        Root { position: Vec3::new(x, 0.0, z), direction: Vec3::Y }
    }

    #[test]
    fn without_wind_the_trajectory_is_vertical() {
        let wind = WindField { noise_c: 0.0, large: LargeWind::None, ..WindField::default() };
        let p = FlameParams::default();
        let path = trace(&up_root(1.5, -2.0), &WindSampler::new(&wind), &p, 7.0);
        assert_eq!(path.len(), 25);
        for (s, (q, _)) in path.iter().enumerate() {
            assert_eq!((q.x, q.z), (1.5, -2.0), "step {s}");
            if s > 0 {
                assert!(q.y > path[s - 1].0.y, "rises at step {s}");
            }
        }
        // v(0) = 1, a = k_g = 1, dt = 0.1: y(24) = Σ_{s=1..24} (1 + 0.1 s) · 0.1 = 2.4 + 3.0.
        assert!((path[24].0.y - 5.4).abs() < 1e-4, "{}", path[24].0.y);
    }

    #[test]
    fn noise_moves_the_tip_more_than_the_base() {
        let still = WindField { noise_c: 0.0, ..WindField::default() };
        let noisy = WindField { noise_c: 0.04, k_s: 0.3, seed: 5, ..WindField::default() };
        let p = FlameParams::default();
        let mut tip_sum = 0.0;
        for frame in 0..8 {
            let t = frame as f32;
            let a = trace(&up_root(0.3, 0.1), &WindSampler::new(&still), &p, t);
            let b = trace(&up_root(0.3, 0.1), &WindSampler::new(&noisy), &p, t);
            let dev = |s: usize| (a[s].0 - b[s].0).length();
            assert_eq!(dev(0), 0.0);
            assert!(dev(3) < dev(24), "frame {frame}: base {} tip {}", dev(3), dev(24));
            tip_sum += dev(24);
        }
        assert!(tip_sum > 1e-3, "the noise moves the tip at all: {tip_sum}");
    }

    #[test]
    fn k_p_zero_makes_every_flame_move_identically() {
        let roots: Vec<Root> = (0..5).map(|k| up_root(k as f32 * 3.7, k as f32 * -1.3)).collect();
        let p = FlameParams::default();
        let offsets = |k_p: f32| -> Vec<Vec<Vec3>> {
            let w = WindSampler::new(&WindField { k_p, noise_c: 0.04, ..WindField::default() });
            roots.iter().map(|r| trace(r, &w, &p, 4.0).iter().map(|(q, _)| *q - r.position).collect()).collect()
        };
        let same = offsets(0.0);
        for f in &same[1..] {
            for (a, b) in f.iter().zip(&same[0]) {
                assert!((*a - *b).length() < 1e-5, "{a} vs {b}");
            }
        }
        let differ = offsets(1.0);
        assert!(differ[1].iter().zip(&differ[0]).any(|(a, b)| (*a - *b).length() > 1e-4));
    }

    #[test]
    fn the_same_seed_gives_the_same_frames() {
        let roots: Vec<Root> = (0..6).map(|k| up_root(k as f32, 0.0)).collect();
        let wind = WindField { seed: 3, ..WindField::default() };
        let p = FlameParams {
            lifetime: 20,
            lifetime_jitter: 0.5,
            size_jitter: 0.3,
            respawn: true,
            fade: 3,
            seed: 9,
            ..FlameParams::default()
        };
        for frame in [0, 5, 31] {
            assert_eq!(simulate_frame(&roots, &wind, &p, frame).unwrap(), simulate_frame(&roots, &wind, &p, frame).unwrap());
        }
        let other = FlameParams { seed: 10, ..p.clone() };
        assert_ne!(simulate_frame(&roots, &wind, &p, 5).unwrap(), simulate_frame(&roots, &wind, &other, 5).unwrap());
        let frame = simulate_frame(&roots, &wind, &p, 5).unwrap();
        assert_eq!(frame.particles.len(), 6 * 25);
        assert_eq!(frame.sides, 20);
    }

    #[test]
    fn footnote_1_shape_and_lifetimes() {
        let s = Shape::perry();
        assert_eq!(s.scale(0, 25), Vec2::new(0.67, 0.0));
        let mid = s.scale(12, 25);
        assert!((mid.x - 1.07).abs() < 1e-6 && (mid.y - 0.384).abs() < 1e-6);
        let end = s.scale(24, 25);
        assert!((end.x - 0.67).abs() < 1e-5 && (end.y - 0.768).abs() < 1e-6);
        let p = FlameParams { lifetime: 10, ..FlameParams::default() };
        assert_eq!(flame_age(0, &p, 9), Some((10, 9)));
        assert_eq!(flame_age(0, &p, 10), None);
    }

    #[test]
    fn ramps_parse_interpolate_and_report_errors() {
        let r: Ramp<4> = Ramp::parse("1: 0 0 0 0; 0: 1 1 1 1").unwrap();
        assert_eq!(r.eval(0.25), [0.75; 4]);
        assert_eq!(r.eval(-1.0), [1.0; 4]);
        assert!(Ramp::<4>::parse("0: 1 2").unwrap_err().contains("needs 4"));
        assert!(Ramp::<1>::parse("").is_err());
        assert!(Ramp::<1>::parse("x: 1").is_err());
    }

    #[test]
    fn zero_steps_nan_wind_and_bad_ramps_are_errors_naming_the_port() {
        let desc = particle_flame_desc();
        let mut values: Vec<Value> = desc
            .inputs
            .iter()
            .map(|p| p.default.clone().unwrap_or_else(|| Value::Particles(Arc::new(Particles::default()))))
            .collect();
        let port_of = |values: &[Value]| match cook_particle_flame(&Inputs::new(&desc, values), &CookCtx::default()) {
            Err(NodeError::Port { port, .. }) => port,
            other => panic!("expected a port error, got {other:?}"),
        };
        let steps = desc.input_index("steps").unwrap();
        values[steps] = Value::Int(0);
        assert_eq!(port_of(&values), "steps");
        values[steps] = Value::Int(25);
        let wind = desc.input_index("wind").unwrap();
        values[wind] = Value::WindField(Arc::new(WindField { k_s: f32::NAN, ..WindField::default() }));
        assert_eq!(port_of(&values), "wind");
        values[wind] = Value::WindField(Arc::new(WindField::default()));
        values[desc.input_index("center_ramp").unwrap()] = Value::String("0: 1 1".into());
        assert_eq!(port_of(&values), "center_ramp");
    }

    #[test]
    fn table_3_1_lifetime_range_is_the_port_range() {
        let desc = particle_flame_desc();
        assert_eq!(desc.inputs[desc.input_index("lifetime").unwrap()].range, Some((1.0, 1000.0)));
    }
}
