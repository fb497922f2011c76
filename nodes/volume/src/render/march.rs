//! The ray march of `volume.render`: for each pixel a ray from the camera through the active
//! bricks' bounds, in steps tied to the voxel size (jittered per pixel against banding), skipping
//! inactive bricks whole, each step a homogeneous segment (Beer–Lambert) that absorbs, scatters
//! the lights once (their transmittance read from precomputed shadow volumes, the phase function
//! Henyey–Greenstein's) plus an ambient term, and emits the fire's blackbody light; the march
//! stops once the ray is opaque (Kajiya & Von Herzen 1984's single-scattering model, as Fedkiw,
//! Stam & Jensen 2001 §4 render smoke).

use glam::{IVec3, Vec3, Vec4};
use pyrograph_core::{Channels, Image};
use pyrograph_render::View;
use rayon::prelude::*;

use super::blackbody::Table;
use super::clear::clear_bricks;
use super::light::{Light, LightKind, Sampler, exit_distance, henyey_greenstein, transmittance};
use super::sweep::directional_transmittance;
use crate::grid::sample::floor_i;
use crate::grid::{DIM, NONE, Volume, brick_of};

/// How the volume looks.
#[derive(Clone, Debug)]
pub struct Look {
    /// Extinction per unit of density per world unit.
    pub extinction: f32,
    /// Single-scattering albedo per channel.
    pub albedo: Vec3,
    /// Henyey–Greenstein anisotropy.
    pub anisotropy: f32,
    /// Ambient light, scattered unshadowed and isotropically.
    pub ambient: Vec3,
    /// Light emitted per world unit by a flame value of 1.
    pub exposure: f32,
    /// Emission per unit of temperature, relative to the flame's.
    pub glow: f32,
    /// Kelvin at temperature 0 and at temperature 1 (linear between, beyond 1 extrapolated).
    pub kelvin: [f32; 2],
    /// March step in voxels.
    pub step: f32,
    /// Straight RGBA behind the volume.
    pub background: Vec4,
    /// Seeds the per-pixel jitter (the frame, so a sequence's noise moves and a chunk of frames
    /// renders the same as the whole).
    pub seed: u64,
    /// Multiple scattering, approximated by octaves of single scattering.
    pub octaves: Octaves,
}

/// Most octaves [`Octaves`] takes.
pub const MAX_OCTAVES: usize = 8;

/// Per octave: its share of the light times its phase function, for one scattering angle.
pub type Phases = [f32; MAX_OCTAVES];

/// Per light, what is the same all along a ray for a directional light: its strength × phase
/// (single scattering) or its octaves' phases (several octaves). Kept apart so single scattering's
/// inner loop carries one vector per light, not the octaves' array.
#[derive(Default)]
struct PerRay {
    lit: Vec<Option<Vec3>>,
    phases: Vec<Option<Phases>>,
}

/// Multiple scattering approximated by octaves of single scattering (Wrenninge 2015,
/// "Art-directable multiple volumetric scattering", as Frostbite's volumes (Hillaire 2016) and
/// production renderers use it): octave i scatters `albedo`^i of the light, sees the shadows'
/// extinction scaled by `extinction`^i (so its transmittance is T^(extinction^i): light that
/// bounced inside the smoke reaches deeper) and a phase function `anisotropy`^i as anisotropic.
/// It reuses the shadow volumes single scattering already has, so it costs a power per octave per
/// sample instead of paths. One octave is single scattering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Octaves {
    /// How many octaves (1 to [`MAX_OCTAVES`]).
    pub count: u32,
    /// a: each octave's share of the previous one's light (at most `extinction`).
    pub albedo: f32,
    /// b: each octave's shadow extinction relative to the previous one's.
    pub extinction: f32,
    /// c: each octave's anisotropy relative to the previous one's.
    pub anisotropy: f32,
}

impl Octaves {
    /// Single scattering.
    pub const SINGLE: Octaves = Octaves { count: 1, albedo: 0.25, extinction: 0.25, anisotropy: 0.5 };

    /// Each octave's share of the light times its Henyey–Greenstein phase for the cosine `cos`
    /// between the light's travel and the scattered direction, base anisotropy `g`.
    #[inline]
    pub fn phases(&self, cos: f32, g: f32) -> Phases {
        let mut out = [0.0; MAX_OCTAVES];
        out[0] = henyey_greenstein(cos, g);
        let (mut share, mut g) = (1.0, g);
        for o in out.iter_mut().take(self.count as usize).skip(1) {
            share *= self.albedo;
            g *= self.anisotropy;
            *o = share * henyey_greenstein(cos, g);
        }
        out
    }

    /// The octaves' light through a shadow of transmittance `t`: Σ phases[i] × t^(extinction^i).
    #[inline]
    pub fn through(&self, phases: &Phases, t: f32) -> f32 {
        let mut sum = phases[0] * t;
        if t <= 0.0 {
            return sum;
        }
        let (ln_t, mut b) = (t.ln(), 1.0);
        for p in &phases[1..(self.count as usize).min(MAX_OCTAVES)] {
            b *= self.extinction;
            sum += p * (b * ln_t).exp();
        }
        sum
    }
}

/// Light groups a render keeps apart: the beauty adds every light into group 0; the six-way maps
/// keep one light per axis direction.
pub const GROUPS: usize = 6;

/// What one ray gathers in front of whatever is behind the volume.
#[derive(Clone, Copy, Debug)]
pub struct Gathered {
    /// Light of the sun and point lights scattered toward the camera, per light group.
    pub scattered: [Vec3; GROUPS],
    /// Ambient light scattered toward the camera.
    pub ambient: Vec3,
    /// The fire's emitted light reaching the camera.
    pub emitted: Vec3,
    /// The fraction of what is behind that reaches the camera.
    pub transmit: f32,
    /// Distance along the ray (from the near plane) where the opacity first reached one half.
    pub depth: f32,
    /// Opacity-weighted sums of the world position and of the velocity, and the weights' sum.
    pub motion: (Vec3, Vec3, f32),
}

impl Gathered {
    fn new() -> Gathered {
        Gathered {
            scattered: [Vec3::ZERO; GROUPS],
            ambient: Vec3::ZERO,
            emitted: Vec3::ZERO,
            transmit: 1.0,
            depth: f32::INFINITY,
            motion: (Vec3::ZERO, Vec3::ZERO, 0.0),
        }
    }

    /// All the light the volume sends toward the camera.
    pub fn light(&self) -> Vec3 {
        self.scattered.iter().sum::<Vec3>() + self.ambient + self.emitted
    }
}

/// A ray: where it leaves the near plane and its unit direction.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// On the near plane.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

/// An opaque surface seen through a pixel (a mesh drawn by the rasterizer): how far along the
/// ray (from the near plane) and its colour.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// Distance from the near plane along the pixel's ray; infinite where no surface is.
    pub distance: f32,
    /// Its (lit) colour.
    pub colour: Vec3,
}

/// What a render sees besides the volume: lights (each in a group), surfaces per pixel (row
/// major), and whether to gather the velocity for motion vectors.
pub struct Scene<'a> {
    /// The lights.
    pub lights: &'a [Light],
    /// Each light's group (below [`GROUPS`]); empty puts every light in group 0.
    pub groups: &'a [usize],
    /// Opaque surfaces, one per pixel, if any.
    pub surfaces: Option<&'a [Surface]>,
    /// Gather the velocity field ("vel") for motion vectors.
    pub motion: bool,
}

/// The fields a march reads, all on the volume's bricks (so one sample's eight corners serve
/// every field), and the sampler that finds those corners.
struct Fields<'a> {
    at: Sampler<'a>,
    density: Option<&'a [f32]>,
    temperature: Option<&'a [f32]>,
    flame: Option<&'a [f32]>,
    velocity: Option<&'a [[f32; 3]]>,
    /// Per light: its transmittance volume and its group.
    shadows: Vec<(&'a [f32], usize)>,
    /// Per brick: nothing in it to absorb or glow ([`clear_bricks`]), so stepped over.
    clear: &'a [bool],
}

/// Renders `v` seen through `view`, lit by `lights`, over the look's background: the beauty
/// frame (straight RGBA).
pub fn render(v: &Volume, view: &View, lights: &[Light], look: &Look) -> Image {
    let scene = Scene { lights, groups: &[], surfaces: None, motion: false };
    let data = gather(v, view, &scene, look, |g, _, _| {
        let bg = look.background;
        let c = g.light() + bg.truncate() * bg.w * g.transmit;
        let alpha = 1.0 - g.transmit * (1.0 - bg.w);
        let straight = if alpha > 0.0 { c / alpha } else { Vec3::ZERO };
        [straight.x, straight.y, straight.z, alpha]
    });
    Image::from_vec(view.width(), view.height(), Channels::Rgba, data.into_flattened())
        .unwrap_or_else(|| Image::new(view.width(), view.height(), Channels::Rgba))
}

/// Marches every pixel of `view` through `v` and maps what each ray gathered (and the surface
/// behind it, if any) to `C` values, row major. Transmittances are precomputed per light.
pub fn gather<const C: usize>(
    v: &Volume,
    view: &View,
    scene: &Scene,
    look: &Look,
    map: impl Fn(&Gathered, Option<&Surface>, Ray) -> [f32; C] + Sync,
) -> Vec<[f32; C]> {
    let density = v.scalar("density");
    let (temperature, flame) = (v.scalar("temperature"), v.scalar("flame"));
    let read: Vec<&[f32]> = [density, temperature, flame].into_iter().flatten().collect();
    let clear = clear_bricks(&v.topology, &read);
    let shadow_fields: Vec<Vec<f32>> = match density {
        Some(d) => {
            // Shadows are smooth: a voxel's step toward the light is enough.
            let step = look.step.max(1.0) * v.transform.voxel_size as f32;
            scene
                .lights
                .iter()
                .map(|l| match l.kind {
                    LightKind::Directional(toward) => directional_transmittance(v, d, look.extinction, toward),
                    LightKind::Point(_) => transmittance(v, d, look.extinction, l, step, &clear),
                })
                .collect()
        }
        None => Vec::new(),
    };
    let group = |k: usize| scene.groups.get(k).copied().unwrap_or(0).min(GROUPS - 1);
    let fields = Fields {
        // Locates samples only (index, brick, corners): its own field is never read.
        at: Sampler::new(v, &[]),
        density,
        temperature,
        flame,
        velocity: v.vector("vel").filter(|_| scene.motion),
        shadows: shadow_fields.iter().enumerate().map(|(k, s)| (s.as_slice(), group(k))).collect(),
        clear: &clear,
    };
    let table = Table::new(look.kelvin[0], look.kelvin[1]);
    let (w, h) = (view.width() as usize, view.height() as usize);
    let inverse = view.view_proj().inverse();
    // Nothing to march without a field that absorbs or emits: the background alone.
    let shows = density.is_some() || fields.temperature.is_some() || fields.flame.is_some();
    let bounds = v
        .topology
        .voxel_bounds()
        .filter(|_| shows)
        .map(|(lo, hi)| (v.transform.to_world(lo.as_vec3() - 0.5), v.transform.to_world(hi.as_vec3() + 0.5)));
    let mut data = vec![[0.0f32; C]; w * h];
    data.par_chunks_mut(w).enumerate().for_each(|(row, out)| {
        let mut fixed = PerRay::default();
        for (col, px) in out.iter_mut().enumerate() {
            let ndc = |z: f32| {
                let x = (col as f32 + 0.5) / w as f32 * 2.0 - 1.0;
                let y = 1.0 - (row as f32 + 0.5) / h as f32 * 2.0;
                inverse.project_point3(Vec3::new(x, y, z))
            };
            let surface = scene.surfaces.map(|s| &s[row * w + col]).filter(|s| s.distance.is_finite());
            let (near, far) = (ndc(0.0), ndc(1.0));
            let gathered = match bounds {
                Some((lo, hi)) => {
                    let jitter = hash01(look.seed, row as u64, col as u64);
                    let stop = surface.map_or(f32::INFINITY, |s| s.distance);
                    let ray = (near, far, stop);
                    march(v, &fields, (scene.lights, &mut fixed), look, &table, ray, (lo, hi), jitter)
                }
                None => Gathered::new(),
            };
            let ray = Ray { origin: near, direction: (far - near).normalize_or(Vec3::NEG_Z) };
            *px = map(&gathered, surface, ray);
        }
    });
    data
}

/// What a ray from `segment.0` toward `segment.1`, stopped at distance `segment.2` (an opaque
/// surface), gathers through the box `bounds`.
#[allow(clippy::too_many_arguments)]
fn march(
    v: &Volume,
    f: &Fields,
    (lights, fixed): (&[Light], &mut PerRay),
    look: &Look,
    table: &Table,
    segment: (Vec3, Vec3, f32),
    bounds: (Vec3, Vec3),
    jitter: f32,
) -> Gathered {
    let (origin, end, stop) = segment;
    let length = (end - origin).length();
    let d = (end - origin) / length.max(1e-30);
    let mut g = Gathered::new();
    let Some((t0, t1)) = slab(origin, d, bounds.0, bounds.1) else { return g };
    // A directional light's strength and phase are the same all along the ray.
    let octaves = look.octaves;
    let several = octaves.count > 1;
    fixed.lit.clear();
    fixed.phases.clear();
    for l in lights {
        let (lit, phases) = match l.kind {
            LightKind::Directional(to_light) if several => (None, Some(octaves.phases(to_light.dot(d), look.anisotropy))),
            LightKind::Directional(to_light) => (Some(l.color * henyey_greenstein(to_light.dot(d), look.anisotropy)), None),
            LightKind::Point(_) => (None, None),
        };
        fixed.lit.push(lit);
        fixed.phases.push(phases);
    }
    let (t0, t1) = (t0.max(0.0), t1.min(length).min(stop));
    let h = v.transform.voxel_size as f32;
    let step = look.step * h;
    let mut k = 0u64;
    let start = t0 + jitter * step;
    let brick_world = h * DIM as f32;
    let mut memo = (glam::IVec3::MAX, None);
    loop {
        let t = start + k as f32 * step;
        if t >= t1 || g.transmit < 1e-3 {
            break;
        }
        let p = origin + d * t;
        let s = &f.at;
        let ip = s.index(p);
        let Some(b) = s.brick_cached(ip, &mut memo).filter(|b| !f.clear[*b]) else {
            // An inactive brick or one with nothing in it: skip to where the ray leaves its 8³ cell.
            let cell = brick_of(IVec3::new(floor_i(ip.x + 0.5), floor_i(ip.y + 0.5), floor_i(ip.z + 0.5))).as_vec3();
            let lo = s.origin_world() + (cell * DIM as f32 - 0.5) * h;
            let exit = t + exit_distance(p, d, lo, lo + brick_world);
            k = (((exit - start) / step).floor() as u64 + 1).max(k + 1);
            continue;
        };
        k += 1;
        // The last step ends at the surface, if one stops the ray inside the volume.
        let dt = step.min(t1 - t);
        let c = s.corners(b, ip);
        let density = f.density.map_or(0.0, |d| c.sample(d).max(0.0));
        let temperature = f.temperature.map_or(0.0, |t| c.sample(t).max(0.0));
        let flame = f.flame.map_or(0.0, |fl| c.sample(fl).max(0.0));
        let sigma = look.extinction * density;
        let strength = flame + look.glow * temperature;
        // A homogeneous segment: the source (scattering + emission) integrated against its own
        // attenuation, exactly.
        // No smoke here (much of a ray): exp(−0) is 1 and spares the call.
        let a = if sigma == 0.0 { 1.0 } else { (-sigma * dt).exp() };
        let through = g.transmit * if sigma > 1e-8 { (1.0 - a) / sigma } else { dt };
        if strength > 0.0 {
            let kelvin = look.kelvin[0] + (look.kelvin[1] - look.kelvin[0]) * temperature;
            g.emitted += table.at(kelvin) * (look.exposure * strength * through);
        }
        if sigma > 0.0 {
            let scatter = look.albedo * (sigma * through);
            g.ambient += scatter * look.ambient;
            for ((light, (shadow, group)), (lit, phases)) in
                lights.iter().zip(&f.shadows).zip(fixed.lit.iter().zip(&fixed.phases))
            {
                let t = c.sample(shadow);
                if several {
                    // Octaves of scattering: the light's strength through each octave's thinner shadow.
                    let (strength, phases) = match *phases {
                        Some(phases) => (light.color, phases),
                        None => {
                            let (to_light, strength) = light.toward(p, h);
                            (strength, octaves.phases(to_light.dot(d), look.anisotropy))
                        }
                    };
                    g.scattered[*group] += scatter * strength * octaves.through(&phases, t);
                } else {
                    // The light travels along −to_light and leaves toward the camera along −d.
                    let lit = lit.unwrap_or_else(|| {
                        let (to_light, strength) = light.toward(p, h);
                        strength * henyey_greenstein(to_light.dot(d), look.anisotropy)
                    });
                    g.scattered[*group] += scatter * lit * t;
                }
            }
            let opacity = g.transmit * (1.0 - a);
            if let Some(vel) = f.velocity {
                let mut u = Vec3::ZERO;
                for (at, w) in c.at.iter().zip(c.w) {
                    if *at != NONE {
                        u += Vec3::from_array(vel[*at as usize]) * w;
                    }
                }
                g.motion.0 += p * opacity;
                g.motion.1 += u * opacity;
                g.motion.2 += opacity;
            }
            if g.transmit * a <= 0.5 && g.depth.is_infinite() {
                g.depth = t;
            }
        }
        g.transmit *= a;
    }
    g
}

/// Where a ray from `o` along unit `d` enters and leaves the box `lo..hi`, if it meets it.
pub(super) fn slab(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
    let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t1 >= 0.0).then_some((t0, t1))
}

/// A number in [0, 1) from a seed and a pixel (SplitMix64's finaliser): the same pixel of the
/// same frame always jitters the same.
fn hash01(seed: u64, row: u64, col: u64) -> f32 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ row.wrapping_mul(0xBF58_476D_1CE4_E5B9)
        ^ col.wrapping_add(0x94D0_49BB_1331_11EB);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}
