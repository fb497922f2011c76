//! Embers and sparks (`particles.embers`): a second particle family beside the flames — small hot
//! particles thrown up from the flame roots, carried by the same wind field as the flames (Perry
//! 1994 §3.2.3: convection plus noise gusts) against drag, cooling along their own colour ramp,
//! and drawn as short long-exposure streaks (§3.2.2) over a shutter of a fraction of a frame.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::{Anim, AnimError, Cook};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{AtPort, Clip, ClipOf, CookCtx, FrameSource, NodeError, PortType, Value, port};

use crate::flame::{Ramp, unit_random};
use crate::types::WindField;
use crate::wind::{WindSampler, validate_wind};
use pyrograph_render::{Particle, Particles};

/// Cooling embers: white-yellow, orange, then dull red fading out.
pub const EMBER_RAMP: &str = "0: 1 0.9 0.55 1; 0.3: 1 0.55 0.12 0.9; 0.75: 0.8 0.18 0.03 0.6; 1: 0.5 0.05 0.01 0";

pyrograph_core::ports! {
    /// How sparks are born, move and look: the ports of `particles.embers` after roots and wind.
    #[derive(PartialEq)]
    pub struct EmberParams {
        /// Sparks born per frame, over all roots; sampled at every sub-step, so a keyed burst of sparks starts when its key does.
        #[range(0.0, 10_000.0)]
        rate: Anim<f32> = Anim::constant(2.0),
        /// Lifetime of a spark in frames.
        #[range(1, 10_000)]
        lifetime: u32 = 30,
        /// Random per-spark lifetime variation.
        #[range(0.0, 1.0)]
        lifetime_jitter: f32 = 0.5,
        /// Initial speed in world units per second, along the root direction.
        #[range(0.0, 1000.0)]
        speed: f32 = 2.5,
        /// Random tilt of each spark's initial direction (0: along the root's).
        #[range(0.0, 1.0)]
        spread: f32 = 0.5,
        /// Scale of the wind field's acceleration on a spark (buoyancy and gusts).
        #[range(0.0, 100.0)]
        wind_scale: f32 = 1.0,
        /// Drag: the fraction of its velocity a spark loses per second.
        #[range(0.0, 100.0)]
        drag: f32 = 0.8,
        /// Spark radius in world units.
        #[range(0.0, 1000.0)]
        size: f32 = 0.025,
        /// Shutter in frames: how much of its path a spark streaks over.
        #[range(0.0, 10.0)]
        shutter: f32 = 0.6,
        /// Particles along a streak.
        #[range(2, 64)]
        samples: usize = 5,
        /// Colour over normalized age: `[(position, (r, g, b, a)), …]`.
        color_ramp: Ramp<4> = Ramp::preset(EMBER_RAMP),
        /// Seed of births, roots, directions and lifetimes.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

/// Integration steps per frame: sparks are fast and small, so the path is stepped finely.
const SUBSTEPS: usize = 4;

/// Where a spark born at `root` at `birth` (frames), heading `dir`, is at every substep from
/// birth until `until` (frames): the wind's acceleration `wind_scale · u∞(p, t)` stepped
/// explicitly, the drag exactly (`v · e^(−drag·h)`), so a strong drag at a low frame rate damps
/// instead of overshooting.
fn spark_path(root: Vec3, dir: Vec3, birth: f64, until: f64, fps: f64, wind: &WindSampler, p: &EmberParams) -> Vec<Vec3> {
    let h = 1.0 / (fps * SUBSTEPS as f64);
    let steps = ((until - birth) * SUBSTEPS as f64).ceil().max(0.0) as usize;
    let (mut pos, mut vel) = (root, dir * p.speed);
    let mut out = Vec::with_capacity(steps + 1);
    out.push(pos);
    for k in 0..steps {
        let t = (birth + k as f64 / SUBSTEPS as f64) as f32;
        vel = vel * (-p.drag * h as f32).exp() + wind.at(pos, root, t) * (p.wind_scale * h as f32);
        pos += vel * h as f32;
        out.push(pos);
    }
    out
}

/// The sparks that may be alive at `now` (frames), as (number, birth frame): spark j is born when
/// the count of births, the integral of the rate from frame 0, reaches j. Before frame 0 the rate
/// is frame 0's, so the first frame is already steady. A constant rate gives births at j / rate; an
/// animated one is integrated at the sub-steps (the rate held over each), from frame 0 on every
/// call, so a frame cooked alone sees the same births as in a full cook.
fn births(rate: &Anim<f32>, fps: f64, now: f64, longest: f64) -> Result<Vec<(i64, f64)>, AnimError> {
    let from = now - longest;
    if !rate.is_animated() {
        let r = *rate.value() as f64;
        let first = (from * r).floor() as i64;
        let last = (now * r).floor() as i64;
        return Ok((first..=last).map(|j| (j, j as f64 / r)).collect());
    }
    let mut out = Vec::new();
    let r0 = rate.at(0.0, fps)? as f64;
    if from < 0.0 && r0 > 0.0 {
        // Born before frame 0, at frame 0's rate: spark j (≤ 0) at j / r0.
        let first = (from * r0).floor() as i64;
        let last = (now.min(0.0) * r0).floor().min(-1.0) as i64;
        out.extend((first..=last).map(|j| (j, j as f64 / r0)));
    }
    let h = 1.0 / SUBSTEPS as f64;
    let mut count = 0.0f64;
    let mut next = 0i64;
    for k in 0..=(now * SUBSTEPS as f64).floor() as usize {
        let t0 = k as f64 * h;
        let r = rate.at(t0, fps)? as f64;
        let end = count + r * h;
        while r > 0.0 && (next as f64) <= end {
            let birth = t0 + (next as f64 - count) / r;
            if birth > now {
                break;
            }
            if birth >= from {
                out.push((next, birth));
            }
            next += 1;
        }
        count = end;
    }
    Ok(out)
}

/// Why a frame of sparks could not be simulated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EmberError {
    /// An animated parameter could not be sampled.
    #[error(transparent)]
    Param(#[from] AnimError),
    /// The wind field drove a spark to a non-finite position.
    #[error("spark {0}: the wind field drives it to a non-finite position")]
    Wind(i64),
}

/// Frame `frame` of sparks from `roots`: every spark alive at the frame, as a streak of
/// `samples` particles along its last `shutter` frames (group = spark, `trails`).
pub fn simulate_embers(
    roots: &[(Vec3, Vec3)],
    wind: &WindField,
    p: &EmberParams,
    fps: f64,
    frame: usize,
) -> Result<Particles, EmberError> {
    let mut particles = Vec::new();
    if roots.is_empty() || (!p.rate.is_animated() && *p.rate.value() <= 0.0) {
        return Ok(Particles { particles, sides: 8, time: frame as f32, trails: true });
    }
    let sampler = WindSampler::at_rate(wind, fps);
    let now = frame as f64;
    let longest = p.lifetime as f64 * (1.0 + p.lifetime_jitter.clamp(0.0, 1.0) as f64);
    for (j, birth) in births(&p.rate, fps, now, longest)? {
        let key = j.rem_euclid(1 << 40) as usize;
        let jitter = p.lifetime_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(p.seed, key, 31) - 1.0);
        let life = (p.lifetime as f64 * (1.0 + jitter as f64)).max(1.0);
        let age = now - birth;
        if age < 0.0 || age >= life {
            continue;
        }
        let (root, root_dir) = roots[(unit_random(p.seed, key, 32) * roots.len() as f32) as usize % roots.len()];
        let tilt =
            Vec3::new(unit_random(p.seed, key, 33) - 0.5, unit_random(p.seed, key, 34) - 0.5, unit_random(p.seed, key, 35) - 0.5);
        let dir = (root_dir.normalize_or(Vec3::Y) + tilt * (2.0 * p.spread)).normalize_or(Vec3::Y);
        let path = spark_path(root, dir, birth, now, fps, &sampler, p);
        if path.iter().any(|q| !q.is_finite()) {
            return Err(EmberError::Wind(j));
        }
        let color = p.color_ramp.eval((age / life) as f32);
        let edge = [color[0], color[1], color[2], 0.0];
        // The streak: `samples` points over the last `shutter` frames (not before birth).
        let at = |frames_ago: f64| {
            let s = ((age - frames_ago).max(0.0) * SUBSTEPS as f64).min((path.len() - 1) as f64);
            let (i, f) = (s.floor() as usize, (s - s.floor()) as f32);
            let next = path[(i + 1).min(path.len() - 1)];
            path[i] + (next - path[i]) * f
        };
        let n = p.samples.max(2);
        for k in 0..n {
            let ago = p.shutter as f64 * (1.0 - k as f64 / (n - 1) as f64);
            particles.push(Particle {
                position: at(ago).to_array(),
                size: [p.size, p.size],
                center: color,
                edge,
                weight: age as f32,
                group: key as u32,
                ..Particle::default()
            });
        }
    }
    Ok(Particles { particles, sides: 8, time: frame as f32, trails: true })
}

pyrograph_core::node! {
    /// Embers and sparks, a second particle family beside the flames: sparks born at `rate` per frame at
    /// random roots, thrown up along the root direction, carried by the flames' wind field (Perry 1994
    /// §3.2.3: convection and noise gusts) against drag, cooling along their own colour ramp over their
    /// lifetime, and drawn as short long-exposure streaks (§3.2.2) over `shutter` frames. Frames are
    /// deterministic and independent. Render with the sparks input of particles.render_flames.
    #[node("particles.embers", "Particles", Simulation)]
    pub struct Embers {
        /// Where sparks start (position, direction in velocity): particles.roots or particles.mesh_roots.
        roots: Arc<Particles>,
        /// Wind field (particles.wind_field); default: Perry's candle wind.
        wind: Arc<WindField> = Arc::new(WindField::default()),
        /// Length and rate of the clip (`frames`, `fps`).
        timeline: pyrograph_core::Timeline,
        /// The sparks.
        params: EmberParams,
    }
    /// Per frame, every live spark's streak.
    -> sparks: ClipOf<Arc<Particles>>
}

struct EmberSource {
    roots: Vec<(Vec3, Vec3)>,
    wind: WindField,
    params: EmberParams,
    fps: f64,
    frames: usize,
}

impl FrameSource for EmberSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        let sparks = simulate_embers(&self.roots, &self.wind, &self.params, self.fps, index).map_err(|e| match e {
            EmberError::Param(e) => e.into(),
            wind @ EmberError::Wind(_) => NodeError::port(port!(Embers, wind), wind.to_string()),
        })?;
        Ok(Value::custom(Arc::new(sparks)))
    }
}

impl Cook for Embers {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Particles>>, NodeError> {
        let roots: Vec<(Vec3, Vec3)> =
            self.roots.particles.iter().map(|q| (Vec3::from_array(q.position), Vec3::from_array(q.velocity))).collect();
        if let Some(k) = roots.iter().position(|(p, d)| !p.is_finite() || !d.is_finite()) {
            return Err(NodeError::port(port!(Embers, roots), format!("root {k} has a non-finite position or direction")));
        }
        validate_wind(&self.wind).at_port(port!(Embers, wind))?;
        let mut h = Fingerprinter::new();
        "particles.embers".hash(&mut h);
        Value::custom(self.roots.clone()).hash_into(&mut h);
        Value::custom(self.wind.clone()).hash_into(&mut h);
        format!("{:?}", self.params).hash(&mut h);
        (self.timeline.frames, self.timeline.fps.to_bits()).hash(&mut h);
        let source = EmberSource {
            roots,
            wind: (*self.wind).clone(),
            params: self.params,
            fps: self.timeline.fps,
            frames: self.timeline.frames,
        };
        let clip = Clip::new(PortType::of::<Particles>(), self.timeline.fps, h.finish(), Arc::new(source));
        Ok(ClipOf::new(clip))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::LargeWind;

    fn calm() -> WindField {
        WindField { noise_c: 0.0, large: LargeWind::None, ..WindField::default() }
    }

    #[test]
    fn sparks_rise_stream_and_cool() {
        let roots = [(Vec3::ZERO, Vec3::Y)];
        let p =
            EmberParams { rate: Anim::constant(3.0), lifetime: 20, lifetime_jitter: 0.0, spread: 0.0, ..EmberParams::default() };
        let frame = simulate_embers(&roots, &calm(), &p, 24.0, 40).unwrap();
        assert!(frame.trails);
        // Born every third of a frame, living 20 frames: about 60 alive, 5 streak particles each.
        let sparks = frame.particles.len() / p.samples;
        assert!((58..=61).contains(&sparks), "{sparks} sparks");
        for streak in frame.particles.chunks(p.samples) {
            assert!(streak.iter().all(|q| q.group == streak[0].group));
            // Straight up without wind noise, the newest particle highest.
            assert!(streak.windows(2).all(|w| w[1].position[1] >= w[0].position[1]));
            assert!(streak.iter().all(|q| q.position[0].abs() < 1e-5 && q.position[2].abs() < 1e-5));
        }
        // Older sparks are higher and cooler (less green, lower alpha).
        let young = frame.particles.iter().min_by(|a, b| a.weight.total_cmp(&b.weight)).unwrap();
        let old = frame.particles.iter().max_by(|a, b| a.weight.total_cmp(&b.weight)).unwrap();
        assert!(old.position[1] > young.position[1] && old.center[1] < young.center[1] && old.center[3] < young.center[3]);
    }

    #[test]
    fn strong_drag_at_a_low_frame_rate_stays_finite() {
        let roots = [(Vec3::ZERO, Vec3::Y)];
        let p = EmberParams { drag: 100.0, ..EmberParams::default() };
        let frame = simulate_embers(&roots, &calm(), &p, 1.0, 20).unwrap();
        assert!(!frame.particles.is_empty());
        assert!(frame.particles.iter().all(|q| q.position.iter().all(|x| x.is_finite() && x.abs() < 100.0)));
    }

    #[test]
    fn frames_are_deterministic_and_steady_from_the_first() {
        let roots = [(Vec3::ZERO, Vec3::Y), (Vec3::X, Vec3::Y)];
        let p = EmberParams::default();
        let a = simulate_embers(&roots, &WindField::default(), &p, 24.0, 0).unwrap();
        let b = simulate_embers(&roots, &WindField::default(), &p, 24.0, 0).unwrap();
        assert_eq!(a, b);
        let later = simulate_embers(&roots, &WindField::default(), &p, 24.0, 30).unwrap();
        let ratio = a.particles.len() as f32 / later.particles.len() as f32;
        assert!((0.6..1.6).contains(&ratio), "already burning at frame 0: {} vs {}", a.particles.len(), later.particles.len());
        assert!(simulate_embers(&[], &WindField::default(), &p, 24.0, 3).unwrap().particles.is_empty());
    }

    #[test]
    fn a_keyed_rate_bursts_when_its_key_comes() {
        use pyrograph_core::declare::Port;
        let keyed = pyrograph_core::ParamValue::parse_cli("keys([(0, 2.0, constant), (20, 12.0, constant)])");
        let animated = pyrograph_core::anim::from_param(&keyed, pyrograph_core::anim::Shape::Float).unwrap().unwrap();
        let rate = Anim::<f32>::from_value(&Value::Anim(Arc::new(animated))).unwrap();
        let roots = [(Vec3::ZERO, Vec3::Y)];
        let steady = EmberParams::default();
        let burst = EmberParams { rate, ..EmberParams::default() };
        let frame = |p: &EmberParams, f| simulate_embers(&roots, &calm(), p, 24.0, f).unwrap();
        // Up to frame 20 the keyed rate is the constant 2: the same sparks, bit for bit.
        for f in [0, 7, 19, 20] {
            assert_eq!(frame(&steady, f), frame(&burst, f), "frame {f}");
        }
        let (a, b) = (frame(&steady, 40).particles.len(), frame(&burst, 40).particles.len());
        println!("particles at frame 40: {a} at rate 2, {b} with the rate keyed to 12 at frame 20");
        assert!(b > 3 * a, "{b} vs {a}");
    }
}
