//! Perry's particle flames (Perry 1994 §3.2.1–3.2.3): each flame is the long-exposure
//! trajectory of one fuzzy particle moved through the wind field, plus the `particles.roots`
//! and `particles.particle_flame` nodes.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use noise::{NoiseFn, Perlin};
use pyrograph_core::declare::{Anim, Cook, Port};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::value::RampKeys;
use pyrograph_core::{AtPort, Clip, ClipOf, CookCtx, FrameSource, NodeError, PortType, Value, port};
use rayon::prelude::*;

use crate::types::WindField;
use crate::wind::{WindSampler, finite3, validate_wind};
use pyrograph_render::{Particle, Particles};

/// A piecewise-linear ramp over normalized age 0..1 with `N` components per key: a ColorRamp
/// (N = 4) or Curve (N = 1) port, written `[(position, value), …]` in a graph file (older files'
/// text form `"pos: v…; pos: v…"` still reads).
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

    /// A built-in ramp (a port default), written in the short text form for the declaration's sake.
    ///
    /// # Panics
    /// When `text` does not parse: a declaration error, caught by every test that builds a default.
    pub fn preset(text: &str) -> Self {
        Ramp::parse(text).unwrap_or_else(|e| panic!("built-in ramp '{text}': {e}"))
    }

    /// Parses the text form `"pos: v…; pos: v…"`, e.g. `"0: 1 0.5 0 1; 1: 1 0 0 0"` (N = 4).
    pub fn parse(text: &str) -> Result<Self, String> {
        Self::from_keys(&RampKeys::parse_legacy(text, N)?)
    }

    fn from_keys(keys: &RampKeys) -> Result<Self, String> {
        if keys.width() != N {
            return Err(format!("needs keys of {N} values, got {}", keys.width()));
        }
        // Ports hold f64; the particles compute in f32, so rounding here is the intent.
        let keys = keys.keys().iter().map(|(p, v)| (*p as f32, std::array::from_fn(|c| v[c] as f32))).collect();
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

impl<const N: usize> Port for Ramp<N> {
    fn port_type() -> PortType {
        PortType::Ramp(N)
    }
    fn into_value(self) -> Value {
        // The shortest decimal of each f32, so defaults print as declared (0.1, not 0.10000000149…).
        let short = |x: f32| x.to_string().parse::<f64>().unwrap_or(f64::from(x));
        let keys = self
            .keys
            .iter()
            .map(|(p, v)| {
                let mut c = [0.0f64; 4];
                c.iter_mut().zip(v).for_each(|(o, x)| *o = short(*x));
                (short(*p), c)
            })
            .collect();
        match RampKeys::new(N, keys) {
            Ok(k) => Value::Ramp(Arc::new(k)),
            // `Ramp::new` keeps keys finite and sorted, which is all `RampKeys::new` checks.
            Err(m) => Value::String(m),
        }
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        match v {
            Value::Ramp(keys) => Ramp::from_keys(keys),
            other => Err(format!("needs a ramp, got {}", other.type_name())),
        }
    }
}

pyrograph_core::choice! {
    /// How a particle's x/y scale changes with age.
    pub enum Shape {
        /// Perry's footnote 1: `x = x_base + x_amp·sin(π·age/max_age)`, `y = y_slope·age` (age in steps).
        Perry = "perry",
        /// User ramps of the x and y scale over normalized age.
        Ramp = "ramp",
    }
}

pyrograph_core::ports! {
    /// The colours of a flame's particles over normalized age, shared by every node that grows
    /// particle flames.
    #[derive(PartialEq)]
    pub struct FlameColors {
        /// Centre vertex RGBA over normalized age: `[(position, (r, g, b, a)), …]`.
        center_ramp: Ramp<4> = Ramp::preset(DEFAULT_CENTER),
        /// Rim vertex RGBA over normalized age: `[(position, (r, g, b, a)), …]`.
        edge_ramp: Ramp<4> = Ramp::preset(DEFAULT_EDGE),
    }
}

pyrograph_core::ports! {
    /// Everything about a flame but its root and its wind: the ports of `particles.particle_flame`
    /// after roots, wind, frames and fps.
    #[derive(PartialEq)]
    pub struct FlameParams {
        /// Particle steps per flame (Figure 3-3: 25).
        #[range(1, 1000)]
        steps: usize = 25,
        /// Triangles per particle (Figure 3-3: 20).
        #[range(3, 256)]
        triangles: u32 = 20,
        /// Time step of the trajectory integration.
        #[range(0.001, 10.0)]
        dt: f32 = 0.1,
        /// Initial speed along the root direction; with normalize, the kept speed.
        #[range(0.0, 100.0)]
        speed: f32 = 1.0,
        /// Re-normalize |v_p| every step (§3.2.3; for intense winds).
        normalize: bool = false,
        /// Particle radius in world units (footnote 1: unit circle); animatable per frame.
        #[range(0.0, 1000.0)]
        size: Anim<f32> = Anim::constant(1.0),
        /// Random per-flame size variation.
        #[range(0.0, 1.0)]
        size_jitter: f32 = 0.0,
        /// Footnote 1's sine/linear shape, or the width/height ramps.
        shape: Shape = Shape::Perry,
        /// Footnote 1 width scale at the base (0.67).
        #[range(0.0, 100.0)]
        x_base: f32 = 0.67,
        /// Footnote 1 width bulge amplitude (0.4).
        #[range(-100.0, 100.0)]
        x_amp: f32 = 0.4,
        /// Footnote 1 height scale growth per step (0.032).
        #[range(0.0, 10.0)]
        y_slope: f32 = 0.032,
        /// Width scale over normalized age (shape = ramp).
        width_ramp: Ramp<1> = Ramp::preset("0: 0.67; 0.5: 1.07; 1: 0.67"),
        /// Height scale over normalized age (shape = ramp).
        height_ramp: Ramp<1> = Ramp::preset("0: 0; 1: 0.768"),
        /// The particles' colours.
        colors: FlameColors = FlameColors::default(),
        /// Flame lifetime l_f in frames (Table 3.1).
        #[range(1, 1000)]
        lifetime: u32 = 1000,
        /// Random per-flame lifetime variation.
        #[range(0.0, 1.0)]
        lifetime_jitter: f32 = 0.0,
        /// Rebirth a flame at its root when its lifetime ends.
        respawn: bool = false,
        /// Frames of fade-in after birth and fade-out before death.
        #[range(0, 1000)]
        fade: u32 = 0,
        /// Relative amplitude of each flame's flicker: the flame (trajectory and particles) grows and
        /// shrinks about its root with band-limited noise over time, as a real flame does (0: steady).
        #[range(0.0, 0.9)]
        flicker: f32 = 0.0,
        /// Flicker rate in noise cycles per frame.
        #[range(0.0, 10.0)]
        flicker_rate: f32 = 0.2,
        /// Seed of the per-flame variations.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

impl FlameParams {
    /// What is wrong with the parameters, as (the port, why), or `None` when a flame can be
    /// simulated with them.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        let p = self;
        if p.steps == 0 {
            return Some((
                port!(FlameParams, steps),
                "must be at least 1: a flame is the trajectory of at least one particle step".into(),
            ));
        }
        if p.triangles < 3 {
            return Some((port!(FlameParams, triangles), format!("a particle needs at least 3 triangles, got {}", p.triangles)));
        }
        for (name, v) in [
            (port!(FlameParams, dt), p.dt),
            (port!(FlameParams, speed), p.speed),
            (port!(FlameParams, size), *p.size.value()),
            (port!(FlameParams, size_jitter), p.size_jitter),
            (port!(FlameParams, lifetime_jitter), p.lifetime_jitter),
        ] {
            if !v.is_finite() {
                return Some((name, format!("must be finite, got {v}")));
            }
        }
        if p.lifetime == 0 {
            return Some((port!(FlameParams, lifetime), "must be at least 1 frame".into()));
        }
        None
    }

    /// Checks the parameters a flame is made with; errors name the port.
    pub fn validate(&self) -> Result<(), NodeError> {
        self.problem().map_or(Ok(()), |(port, why)| Err(NodeError::port(port, why)))
    }

    /// The parameters as they are at `frame` of a clip at `fps`: animated ones sampled (a flame is a
    /// long exposure at its frame, so one sample serves the frame). Errors name the port and frame.
    pub fn at_frame(&self, frame: f64, fps: f64) -> Result<FlameParams, NodeError> {
        if !self.size.is_animated() {
            return Ok(self.clone());
        }
        Ok(FlameParams { size: Anim::constant(self.size.at(frame, fps)?), ..self.clone() })
    }

    /// The `(x, y)` scale of a particle of age `step` in a trajectory of `steps` steps.
    pub fn scale(&self, step: usize, steps: usize) -> Vec2 {
        let a = if steps > 1 { step as f32 / (steps - 1) as f32 } else { 0.0 };
        match self.shape {
            Shape::Perry => Vec2::new(self.x_base + self.x_amp * (std::f32::consts::PI * a).sin(), self.y_slope * step as f32),
            Shape::Ramp => Vec2::new(self.width_ramp.eval(a)[0], self.height_ramp.eval(a)[0]),
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

/// Why a frame of flames could not be simulated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FlameError {
    /// A parameter no flame can be made with: its field (port) and why.
    #[error("port '{0}': {1}")]
    Param(&'static str, String),
    /// The wind field is not finite, or drives a particle to a non-finite position.
    #[error("{0}")]
    Wind(String),
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
pub fn simulate_frame(roots: &[Root], wind: &WindField, p: &FlameParams, frame: usize) -> Result<Particles, FlameError> {
    if let Some((field, why)) = p.problem() {
        return Err(FlameError::Param(field, why));
    }
    validate_wind(wind).map_err(FlameError::Wind)?;
    let sampler = WindSampler::new(wind);
    let t = frame as f32;
    let per_flame: Vec<Vec<Particle>> = roots
        .par_iter()
        .enumerate()
        .map(|(i, root)| flame_particles(i, root, &sampler, p, frame, t))
        .collect::<Result<_, _>>()?;
    Ok(Particles { particles: per_flame.concat(), sides: p.triangles, time: t, trails: true })
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

/// How much flame `i` is scaled about its root at time `t` (frames): 1 + flicker × 1-D Perlin
/// noise of `t · flicker_rate`, a different stretch of noise per flame.
pub fn flicker(i: usize, p: &FlameParams, t: f32) -> f32 {
    if p.flicker == 0.0 {
        return 1.0;
    }
    let noise = Perlin::new(p.seed ^ 0x5EED_F11C);
    let n = noise.get([(t * p.flicker_rate) as f64, i as f64 * 7.31 + 0.5, 0.25]) as f32;
    (1.0 + p.flicker * n).max(0.05)
}

fn flame_particles(
    i: usize,
    root: &Root,
    wind: &WindSampler,
    p: &FlameParams,
    frame: usize,
    t: f32,
) -> Result<Vec<Particle>, FlameError> {
    let Some((life, age)) = flame_age(i, p, frame) else { return Ok(Vec::new()) };
    let fade =
        if p.fade == 0 { 1.0 } else { ((age + 1) as f32 / p.fade as f32).min((life - age) as f32 / p.fade as f32).min(1.0) };
    let stretch = flicker(i, p, t);
    let size = stretch * *p.size.value() * (1.0 + p.size_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(p.seed, i, 3) - 1.0));
    let mut path = trace(root, wind, p, t);
    if stretch != 1.0 {
        path.iter_mut().for_each(|(q, _)| *q = root.position + (*q - root.position) * stretch);
    }
    if path.iter().any(|(q, v)| !q.is_finite() || !v.is_finite()) {
        return Err(FlameError::Wind(format!("flame {i}: the wind field drives the particle to a non-finite position")));
    }
    let n = path.len();
    Ok(path
        .iter()
        .enumerate()
        .map(|(s, (q, v))| {
            let a = if n > 1 { s as f32 / (n - 1) as f32 } else { 0.0 };
            let mut center = p.colors.center_ramp.eval(a);
            let mut edge = p.colors.edge_ramp.eval(a);
            center[3] *= fade;
            edge[3] *= fade;
            let half = p.scale(s, n) * size;
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

pyrograph_core::choice! {
    /// How `particles.roots` places its roots.
    pub enum Layout {
        /// A row along x (candles).
        Row = "row",
        /// A square-ish grid in the ground plane.
        Grid = "grid",
        /// Evenly around a circle.
        Ring = "ring",
        /// At random in a disc (a campfire bed).
        Disc = "disc",
    }
}

pyrograph_core::node! {
    /// Flame roots: base points p(0) with initial directions of v_p (Perry 1994 §3.2.3, §3.4), laid out
    /// as a row (candles), a grid, a ring or a random disc (a campfire bed). Output particles carry the
    /// root in `position` and the direction in `velocity`.
    #[node("particles.roots", "Particles", Source)]
    pub struct Roots {
        /// How the roots are placed.
        layout: Layout = Layout::Row,
        /// Number of roots.
        #[range(1, 100_000)]
        count: usize = 1,
        /// Centre of the layout.
        center: [f32; 3] = [0.0, 0.0, 0.0],
        /// Distance between neighbours (row, grid).
        #[range(0.0, 1000.0)]
        spacing: f32 = 2.5,
        /// Radius (ring, disc).
        #[range(0.0, 1000.0)]
        radius: f32 = 2.0,
        /// Initial direction of every flame.
        direction: [f32; 3] = [0.0, 1.0, 0.0],
        /// Random tilt of each direction (0: all equal).
        #[range(0.0, 1.0)]
        spread: f32 = 0.0,
        /// Seed of disc placement and tilt.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
    /// Root particles.
    -> roots: Arc<Particles>
}

/// Root positions and directions for a layout (see `particles.roots`).
#[allow(clippy::too_many_arguments)]
pub fn layout_roots(
    layout: Layout,
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
                Layout::Grid => {
                    let (r, c) = ((i / cols) as f32, (i % cols) as f32);
                    let rows = count.div_ceil(cols) as f32;
                    Vec3::new((c - (cols as f32 - 1.0) / 2.0) * spacing, 0.0, (r - (rows - 1.0) / 2.0) * spacing)
                }
                Layout::Ring => {
                    let a = std::f32::consts::TAU * i as f32 / count as f32;
                    Vec3::new(a.cos() * radius, 0.0, a.sin() * radius)
                }
                Layout::Disc => {
                    let r = radius * unit_random(seed, i, 11).sqrt();
                    let a = std::f32::consts::TAU * unit_random(seed, i, 12);
                    Vec3::new(a.cos() * r, 0.0, a.sin() * r)
                }
                Layout::Row => Vec3::new((i as f32 - (count as f32 - 1.0) / 2.0) * spacing, 0.0, 0.0),
            };
            let tilt = Vec3::new(unit_random(seed, i, 13) - 0.5, unit_random(seed, i, 14) - 0.5, unit_random(seed, i, 15) - 0.5);
            let d = (dir + tilt * (2.0 * spread)).normalize_or_zero();
            Root { position: center + offset, direction: if d == Vec3::ZERO { dir } else { d } }
        })
        .collect()
}

impl Cook for Roots {
    fn cook(self, _: &CookCtx) -> Result<Arc<Particles>, NodeError> {
        let roots = layout_roots(
            self.layout,
            self.count,
            Vec3::from_array(finite3(self.center).at_port(port!(Roots, center))?),
            self.spacing,
            self.radius,
            Vec3::from_array(finite3(self.direction).at_port(port!(Roots, direction))?),
            self.spread,
            self.seed,
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
        Ok(Arc::new(Particles { particles, sides: 0, time: 0.0, trails: false }))
    }
}

pyrograph_core::node! {
    /// Perry's particle flames (Perry 1994 §3.2.1–3.2.3): each root grows a flame that is the long-exposure
    /// trajectory of one particle of `triangles` Gouraud triangles (a fuzzy N-gon: centre vertex with the
    /// centre RGBA, rim vertices with the edge RGBA) moved `steps` steps through the wind field by
    /// v(s+1) = v(s) + u∞·dt, optionally re-normalized. The particle's x/y scale follows footnote 1
    /// (0.67 + 0.4 sin(π·age/24), y slope 0.032) or user ramps; colours follow centre and edge ramps over
    /// age (`[(position, (r, g, b, a)), …]`). Each flame has a lifetime l_f (Table 3.1) with per-flame jitter from
    /// `seed`. Frame T samples the noise at k_p·p − k_s·T·ĵ, so frames are deterministic and independent.
    /// Render with particles.render_flames.
    #[node("particles.particle_flame", "Particles", Simulation)]
    pub struct ParticleFlame {
        /// Flame roots (position, direction in velocity): particles.roots.
        roots: Arc<Particles>,
        /// Wind field (particles.wind_field); default: Perry's candle wind.
        wind: Arc<WindField> = Arc::new(WindField::default()),
        /// Length and rate of the clip (`frames`, `fps`).
        timeline: pyrograph_core::Timeline,
        /// The flames.
        params: FlameParams,
    }
    /// Per frame, every live flame's particles.
    -> flames: ClipOf<Arc<Particles>>
}

struct FlameSource {
    roots: Vec<Root>,
    wind: WindField,
    params: FlameParams,
    frames: usize,
    fps: f64,
}

impl ParticleFlame {
    /// A flame simulation's error as the node's: a parameter's names its port, the wind's the wind
    /// port.
    fn error(e: FlameError) -> NodeError {
        match e {
            FlameError::Param(port, why) => NodeError::port(port, why),
            FlameError::Wind(why) => NodeError::port(port!(ParticleFlame, wind), why),
        }
    }
}

impl FrameSource for FlameSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        // Frame T is a long exposure at time T, so an animated wind or size is sampled once, at T.
        let wind = self.wind.at_frame(index as f64, self.fps)?;
        let params = self.params.at_frame(index as f64, self.fps)?;
        Ok(Value::custom(Arc::new(simulate_frame(&self.roots, &wind, &params, index).map_err(ParticleFlame::error)?)))
    }
}

impl Cook for ParticleFlame {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Particles>>, NodeError> {
        let roots = Root::from_particles(&self.roots);
        if let Some(k) = roots.iter().position(|r| !r.position.is_finite() || !r.direction.is_finite()) {
            return Err(NodeError::port(port!(ParticleFlame, roots), format!("root {k} has a non-finite position or direction")));
        }
        validate_wind(&self.wind).at_port(port!(ParticleFlame, wind))?;
        self.params.validate()?;
        let mut h = Fingerprinter::new();
        "particles.particle_flame".hash(&mut h);
        Value::custom(self.roots.clone()).hash_into(&mut h);
        Value::custom(self.wind.clone()).hash_into(&mut h);
        format!("{:?}", self.params).hash(&mut h);
        self.timeline.frames.hash(&mut h);
        self.timeline.fps.to_bits().hash(&mut h);
        let (frames, fps) = (self.timeline.frames, self.timeline.fps);
        let source = FlameSource { roots, wind: (*self.wind).clone(), params: self.params, frames, fps };
        let clip = Clip::new(PortType::of::<Particles>(), self.timeline.fps, h.finish(), Arc::new(source));
        Ok(ClipOf::new(clip))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::LargeWind;
    use pyrograph_core::declare::Declared;

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
        let s = FlameParams::default();
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
        let desc = ParticleFlame::desc();
        let mut values: Vec<Value> = desc
            .inputs
            .iter()
            .map(|p| p.default.clone().unwrap_or_else(|| Value::custom(Arc::new(Particles::default()))))
            .collect();
        let cook = |values: &[Value]| pyrograph_core::testing::read::<ParticleFlame>(values)?.cook(&CookCtx::default());
        let port_of = |values: &[Value]| match cook(values) {
            Err(NodeError::Port { port, .. }) => port,
            other => panic!("expected a port error, got {:?}", other.err()),
        };
        let steps = desc.input_index("steps").unwrap();
        values[steps] = Value::Int(0);
        assert_eq!(port_of(&values), "steps");
        values[steps] = Value::Int(25);
        let wind = desc.input_index("wind").unwrap();
        values[wind] = Value::custom(Arc::new(WindField { k_s: f32::NAN, ..WindField::default() }));
        assert_eq!(port_of(&values), "wind");
        values[wind] = Value::custom(Arc::new(WindField::default()));
        values[desc.input_index("center_ramp").unwrap()] = Value::String("0: 1 1".into());
        assert_eq!(port_of(&values), "center_ramp");
    }

    #[test]
    fn table_3_1_lifetime_range_is_the_port_range() {
        let desc = ParticleFlame::desc();
        assert_eq!(desc.inputs[desc.input_index("lifetime").unwrap()].range, Some((1.0, 1000.0)));
    }

    #[test]
    fn an_animated_size_is_sampled_at_each_frame_and_checked_against_its_range() {
        let size = |text: &str| {
            let v = pyrograph_core::value::animated_param(&pyrograph_core::ParamValue::parse_cli(text), &PortType::Float);
            let desc = ParticleFlame::desc();
            let port = &desc.inputs[desc.input_index("size").unwrap()];
            <Anim<f32> as Port>::from_port(&Value::Anim(Arc::new(v.unwrap().unwrap())), port).unwrap()
        };
        let p = FlameParams { size: size("keys([(0, 0.1, linear), (10, 0.3)])"), ..FlameParams::default() };
        let roots = [up_root(0.0, 0.0)];
        let wind = WindField::default();
        let width = |frame: usize| {
            let q = p.at_frame(frame as f64, 24.0).unwrap();
            simulate_frame(&roots, &wind, &q, frame).unwrap().particles[0].size[0]
        };
        let (w0, w5, w10) = (width(0), width(5), width(10));
        assert!((w5 / w0 - 2.0).abs() < 1e-4 && (w10 / w0 - 3.0).abs() < 1e-4, "{w0} {w5} {w10}");
        let wild = FlameParams { size: size("expr(\"frame * 200\")"), ..FlameParams::default() };
        let e = wild.at_frame(6.0, 24.0).unwrap_err().to_string();
        assert!(e.contains("size") && e.contains("frame 6") && e.contains("1200"), "{e}");
    }
}
