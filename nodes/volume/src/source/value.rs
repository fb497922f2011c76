//! The `VolumeSource` value: emitters, each a geometry the graph already makes (particles, the
//! burning front of a fire spread, cloth flames, a mesh's surface, spheres, point lists) with
//! its own rates, animated like any parameter. A simulation asks it for [`Splat`]s at every
//! sub-step.

use std::hash::Hash;
use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::{Anim, AnimError};
use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{Clip, CookCtx, NodeError, TypeInfo, ValueType};
use pyrograph_nodes_cloth::state::ClothState;
use pyrograph_nodes_particles::types::SpreadState;
use pyrograph_render::Particles;

/// Most masses of one cloth flame that emit (spread evenly over its rows and columns).
const CLOTH_POINTS_PER_FLAME: usize = 32;

/// A point that emits from `start` seconds on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedPoint {
    /// World position.
    pub position: [f32; 3],
    /// Velocity the emitter may pass on (`inherit`).
    pub velocity: [f32; 3],
    /// Seconds from which it emits.
    pub start: f32,
}

/// Where an emitter emits.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Fixed points (roots, a point list, a mesh's surface samples).
    Points(Arc<Vec<TimedPoint>>),
    /// Every particle of each frame of a clip (particle flames, embers).
    Particles(Clip),
    /// The live flame roots of each frame of a fire spread: where its faces burn.
    Spread(Clip),
    /// The masses of each frame's cloth flames.
    Cloth(Clip),
    /// One sphere whose centre may move.
    Sphere(Anim<[f32; 3]>),
}

/// How much an emitter emits; each sampled at every sub-step.
#[derive(Clone, Debug, PartialEq)]
pub struct Rates {
    /// Fuel added per second at the centre of each splat.
    pub fuel: Anim<f32>,
    /// Smoke density added per second.
    pub smoke: Anim<f32>,
    /// Temperature the splat holds its voxels at (at least).
    pub temperature: Anim<f32>,
    /// Velocity the splat gives the air (world units per second).
    pub velocity: Anim<[f32; 3]>,
    /// Radius of each splat in world units.
    pub radius: Anim<f32>,
    /// Fraction of each point's own velocity added to `velocity`.
    pub inherit: f32,
}

/// One emitter: a geometry and its rates, named by the input it came from for errors.
#[derive(Clone, Debug)]
pub struct Emitter {
    /// Which input of which source node it came from (`particles`, `sphere`, …).
    pub label: String,
    /// Where.
    pub geometry: Geometry,
    /// How much.
    pub rates: Rates,
}

/// A sphere of emission at one sub-step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// World centre.
    pub position: Vec3,
    /// World radius.
    pub radius: f32,
    /// Fuel per second at the centre.
    pub fuel: f32,
    /// Smoke per second at the centre.
    pub smoke: f32,
    /// Temperature held at the centre.
    pub temperature: f32,
    /// Velocity given to the air at the centre.
    pub velocity: Vec3,
}

/// The emitters feeding a simulation (`volume.source` makes one; several are merged by the
/// simulation's source inputs).
#[derive(Clone, Debug, Default)]
pub struct VolumeSource {
    /// The emitters, in order.
    pub emitters: Vec<Emitter>,
}

/// Why a source could not give its splats at a sub-step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SourceError {
    /// A frame of a clip the source emits from failed to cook (the upstream node's error, or a
    /// cancelled cook), passed on as it is.
    #[error(transparent)]
    Upstream(#[from] NodeError),
    /// An animated rate could not be sampled.
    #[error(transparent)]
    Rate(#[from] AnimError),
    /// A rate, point or clip the source cannot emit from.
    #[error("{0}")]
    Bad(String),
}

impl From<SourceError> for NodeError {
    fn from(e: SourceError) -> Self {
        match e {
            SourceError::Upstream(e) => e,
            SourceError::Rate(e) => e.into(),
            SourceError::Bad(m) => NodeError::msg(m),
        }
    }
}

impl VolumeSource {
    /// Every splat at (fractional) `frame` of a clip at `fps`. Geometry from a clip is read at the
    /// frame the sub-step falls in (its last frame once the clip ends). Errors name the
    /// emitter, the frame and the point.
    pub fn splats(&self, frame: f64, fps: f64, ctx: &CookCtx) -> Result<Vec<Splat>, SourceError> {
        let mut out = Vec::new();
        for e in &self.emitters {
            emitter_splats(e, frame, fps, ctx, &mut out)?;
        }
        Ok(out)
    }
}

fn emitter_splats(e: &Emitter, frame: f64, fps: f64, ctx: &CookCtx, out: &mut Vec<Splat>) -> Result<(), SourceError> {
    let r = &e.rates;
    let (fuel, smoke, temperature) = (r.fuel.at(frame, fps)?, r.smoke.at(frame, fps)?, r.temperature.at(frame, fps)?);
    let (velocity, radius) = (Vec3::from_array(r.velocity.at(frame, fps)?), r.radius.at(frame, fps)?);
    let bad = |what: String| SourceError::Bad(format!("source '{}' at frame {frame:.3}: {what}", e.label));
    for (name, v) in
        [("the fuel rate", fuel), ("the smoke rate", smoke), ("the held temperature", temperature), ("the splat radius", radius)]
    {
        if !v.is_finite() {
            return Err(bad(format!("{name} is {v}")));
        }
    }
    if !velocity.is_finite() {
        return Err(bad(format!("the velocity is {velocity}")));
    }
    let seconds = (frame / fps) as f32;
    let first = out.len();
    let mut push = |p: Vec3, v: Vec3| {
        out.push(Splat { position: p, radius, fuel, smoke, temperature, velocity: velocity + v * r.inherit });
    };
    match &e.geometry {
        Geometry::Points(points) => {
            for q in points.iter().filter(|q| q.start <= seconds) {
                push(Vec3::from_array(q.position), Vec3::from_array(q.velocity));
            }
        }
        Geometry::Sphere(centre) => push(Vec3::from_array(centre.at(frame, fps)?), Vec3::ZERO),
        Geometry::Particles(clip) => {
            if let Some(ps) = clip_frame::<Particles>(clip, frame, ctx)? {
                ps.particles.iter().for_each(|q| push(Vec3::from_array(q.position), Vec3::from_array(q.velocity)));
            }
        }
        Geometry::Spread(clip) => {
            if let Some(s) = clip_frame::<SpreadState>(clip, frame, ctx)? {
                s.roots.iter().for_each(|q| push(Vec3::from_array(q.position), Vec3::from_array(q.direction)));
            }
        }
        Geometry::Cloth(clip) => {
            if let Some(c) = clip_frame::<ClothState>(clip, frame, ctx)? {
                cloth_points(&c, &mut push);
            }
        }
    }
    if let Some((k, s)) = out[first..].iter().enumerate().find(|(_, s)| !s.position.is_finite() || !s.velocity.is_finite()) {
        return Err(bad(format!("point {k} is not finite (position {}, velocity {})", s.position, s.velocity)));
    }
    Ok(())
}

/// Frame ⌊`frame`⌋ of `clip` (its last once it ends), `None` for an empty clip.
fn clip_frame<T: ValueType>(clip: &Clip, frame: f64, ctx: &CookCtx) -> Result<Option<Arc<T>>, SourceError> {
    if clip.is_empty() {
        return Ok(None);
    }
    let index = (frame.max(0.0).floor() as usize).min(clip.len() - 1);
    let v = clip.get(index, ctx)?;
    v.downcast::<T>()
        .map(Some)
        .ok_or_else(|| SourceError::Bad(format!("expected a clip of {}, got {}", T::INFO.name, v.summary())))
}

/// Up to [`CLOTH_POINTS_PER_FLAME`] masses of each cloth flame, spread over its rows and columns.
fn cloth_points(c: &ClothState, push: &mut impl FnMut(Vec3, Vec3)) {
    let (w, h) = (c.width as usize, c.height as usize);
    let stride = ((w * h) as f32 / CLOTH_POINTS_PER_FLAME as f32).sqrt().ceil().max(1.0) as usize;
    for (f, root) in c.roots.iter().enumerate() {
        let Some(masses) = c.flame(f) else { continue };
        for row in (0..h).step_by(stride) {
            for col in (0..w).step_by(stride) {
                push(Vec3::from_array(*root) + Vec3::from_array(masses[row * w + col]), Vec3::ZERO);
            }
        }
    }
}

impl ValueType for VolumeSource {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "VolumeSource",
        doc: "Emitters of fuel, heat, smoke and velocity for volume.simulate (Fedkiw, Stam & Jensen 2001 §3.4 sources).",
        color: [230, 120, 90],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        for e in &self.emitters {
            e.label.hash(h);
            format!("{:?}", e.rates).hash(h);
            match &e.geometry {
                Geometry::Points(ps) => {
                    (0u8, ps.len()).hash(h);
                    ps.iter().for_each(|q| hash_f32s(h, &[q.position.as_slice(), &q.velocity, &[q.start]].concat()));
                }
                Geometry::Particles(c) => (1u8, c.fingerprint()).hash(h),
                Geometry::Spread(c) => (2u8, c.fingerprint()).hash(h),
                Geometry::Cloth(c) => (3u8, c.fingerprint()).hash(h),
                Geometry::Sphere(a) => (4u8, format!("{a:?}")).hash(h),
            }
        }
    }

    fn byte_size(&self) -> usize {
        self.emitters.iter().map(|e| if let Geometry::Points(p) = &e.geometry { p.len() * 28 } else { 64 }).sum::<usize>() + 64
    }

    fn summary(&self) -> String {
        let labels: Vec<&str> = self.emitters.iter().map(|e| e.label.as_str()).collect();
        format!("VolumeSource {} emitters ({})", self.emitters.len(), labels.join(", "))
    }
}
