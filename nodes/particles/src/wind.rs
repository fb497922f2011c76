//! The flame wind field `u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t)` (Perry 1994 §3.2.3) and
//! the `particles.wind_field` node that describes it.

use std::sync::Arc;

use crate::types::{LargeWind, WindAnimation, WindField};
use glam::{DVec3, Vec3};
use noise::permutationtable::{NoiseHasher, PermutationTable};
use pyrograph_core::declare::{Anim, Cook};
use pyrograph_core::{AtPort, CookCtx, NodeError, port};

/// The world's up axis `ĵ`, along which eq. 3.1 measures height and time scrolls the noise.
pub const UP: Vec3 = Vec3::Y;

/// The gradient vectors of the `noise` crate's 3-D Perlin lattice, indexed by the corner's
/// hash `& 15` (as `noise::core::perlin::perlin_3d` assigns them).
const LATTICE_GRADIENTS: [[f64; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
];

/// `noise::Perlin`'s scale from the raw lattice sum to about [−1, 1] in 3-D (2/√3).
const PERLIN_SCALE: f64 = 1.154_700_538_379_251_5;

/// The lattice of `noise::Perlin::new(seed)`: its permutation table, read out through the
/// crate's own hasher so the lattice hash below is a few inlined lookups (the crate's hasher is
/// a call per corner that folds over a slice; 8 per wind sample).
#[derive(Clone, Debug)]
struct Lattice {
    perm: [u8; 256],
}

impl Lattice {
    fn new(seed: u32) -> Self {
        let table = PermutationTable::new(seed);
        // Hashing one coordinate `a` gives the table's entry at `a & 255`.
        Lattice { perm: std::array::from_fn(|a| table.hash(&[a as isize]) as u8) }
    }

    /// `P[i & 255]`.
    #[inline(always)]
    fn p(&self, i: usize) -> usize {
        usize::from(self.perm[i & 255])
    }

    /// The analytic gradient of `noise::Perlin::new(seed)`'s 3-D noise at `q`. Written by hand
    /// because the `noise` crate evaluates values only; a gradient by central differences cost
    /// six noise evaluations per wind sample, 69 % of simulating 1,000 flames. Same lattice,
    /// hash (`P[P[P[x] ^ y] ^ z]` on the low 8 bits), corner convention and quintic fade as
    /// `noise::core::perlin::perlin_3d`, differentiated (the clamp of the value to [−1, 1] is
    /// not: it does not act inside that range); the tests check it against central differences
    /// of the crate's own noise.
    fn gradient(&self, q: [f64; 3]) -> DVec3 {
        // The crate's `floor_to_isize`: one below the truncation for values ≤ 0 (an integer
        // coordinate ≤ 0 sits at distance 1 in its cell, not 0; the noise is the same either way).
        let cell = |v: f64| if v <= 0.0 { v as isize - 1 } else { v as isize };
        let (cx, cy, cz) = (cell(q[0]), cell(q[1]), cell(q[2]));
        let d = DVec3::new(q[0] - cx as f64, q[1] - cy as f64, q[2] - cz as f64);
        let fade = |t: f64| {
            let t = t.clamp(0.0, 1.0);
            (t * t * t * (t * (t * 6.0 - 15.0) + 10.0), 30.0 * t * t * (t - 1.0) * (t - 1.0))
        };
        let ((u, du), (v, dv), (w, dw)) = (fade(d.x), fade(d.y), fade(d.z));
        let px = [self.p(cx as usize), self.p(cx.wrapping_add(1) as usize)];
        // Corner (i, j, k): its gradient and the gradient's dot product with the offset to `q`.
        let corner = |i: usize, j: usize, k: usize| {
            let pxy = self.p(px[i] ^ (cy.wrapping_add(j as isize) as usize & 255));
            let h = self.p(pxy ^ (cz.wrapping_add(k as isize) as usize & 255)) & 15;
            let g = DVec3::from_array(LATTICE_GRADIENTS[h]);
            (g, g.dot(d - DVec3::new(i as f64, j as f64, k as f64)))
        };
        // (Eight calls written out: `array::map` over the corners was not inlined.)
        let ((g000, n000), (g100, n100), (g010, n010), (g110, n110)) =
            (corner(0, 0, 0), corner(1, 0, 0), corner(0, 1, 0), corner(1, 1, 0));
        let ((g001, n001), (g101, n101), (g011, n011), (g111, n111)) =
            (corner(0, 0, 1), corner(1, 0, 1), corner(0, 1, 1), corner(1, 1, 1));
        // The trilinear blend as a polynomial in the faded coordinates (u, v, w), written once
        // for the corner values and once for the corner gradients.
        let k1 = n100 - n000;
        let k2 = n010 - n000;
        let k3 = n001 - n000;
        let k4 = n000 - n100 - n010 + n110;
        let k5 = n000 - n010 - n001 + n011;
        let k6 = n000 - n100 - n001 + n101;
        let k7 = -n000 + n100 + n010 - n110 + n001 - n101 - n011 + n111;
        let blended = g000
            + (g100 - g000) * u
            + (g010 - g000) * v
            + (g001 - g000) * w
            + (g000 - g100 - g010 + g110) * (u * v)
            + (g000 - g010 - g001 + g011) * (v * w)
            + (g000 - g100 - g001 + g101) * (w * u)
            + (-g000 + g100 + g010 - g110 + g001 - g101 - g011 + g111) * (u * v * w);
        let chain = DVec3::new(
            du * (k1 + k4 * v + k6 * w + k7 * v * w),
            dv * (k2 + k5 * w + k4 * u + k7 * w * u),
            dw * (k3 + k6 * u + k5 * v + k7 * u * v),
        );
        (blended + chain) * PERLIN_SCALE
    }
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// Checks every number of `wind` is finite; the error names the field (the node names its port).
pub fn validate_wind(wind: &WindField) -> Result<(), String> {
    let mut fields: Vec<(&str, f32)> =
        vec![("k_g", wind.k_g), ("C", wind.noise_c), ("k_p", wind.k_p), ("k_s", wind.k_s), ("height_unit", wind.height_unit)];
    fields.extend(wind.gravity.iter().map(|g| ("gravity", *g)));
    match &wind.large {
        LargeWind::None => {}
        LargeWind::Constant(v) | LargeWind::MovingObject(v) => fields.extend(v.iter().map(|x| ("w_L", *x))),
        LargeWind::Vortex { center, strength, radius } => {
            fields.extend(center.iter().map(|x| ("vortex center", *x)));
            fields.push(("vortex strength", *strength));
            fields.push(("vortex radius", *radius));
        }
    }
    match fields.iter().find(|(_, v)| !v.is_finite()) {
        Some((name, v)) => Err(format!("wind {name} must be finite, got {v}")),
        None if wind.height_unit <= 0.0 => Err("wind height_unit must be positive".to_string()),
        None => Ok(()),
    }
}

/// Evaluates a [`WindField`]: the noise lattice is built once per field. An animated field is
/// sampled at the time of each call, so a particle stepped through a gust feels it when it blows.
pub struct WindSampler {
    field: WindField,
    lattice: Lattice,
    fps: f64,
}

impl WindSampler {
    /// A sampler for `field`, whose animated parameters (if any) run at 24 frames per second.
    pub fn new(field: &WindField) -> Self {
        WindSampler::at_rate(field, 24.0)
    }

    /// A sampler for `field` in a clip at `fps` (what an expression's `time` counts in).
    pub fn at_rate(field: &WindField, fps: f64) -> Self {
        WindSampler { field: field.clone(), lattice: Lattice::new(field.seed), fps }
    }

    /// The field being sampled.
    pub fn field(&self) -> &WindField {
        &self.field
    }

    /// The large-scale wind `w_L(p)`.
    pub fn large(&self, p: Vec3) -> Vec3 {
        match &self.field.large {
            LargeWind::None => Vec3::ZERO,
            LargeWind::Constant(v) => v3(*v),
            LargeWind::MovingObject(v) => -v3(*v),
            LargeWind::Vortex { center, strength, radius } => {
                let r = p - v3(*center);
                let r = r - UP * r.dot(UP);
                let d = r.length();
                if d < 1e-9 {
                    return Vec3::ZERO;
                }
                let radius = radius.max(1e-6);
                let speed = if d < radius { strength * d / radius } else { strength * radius / d };
                UP.cross(r / d) * speed
            }
        }
    }

    /// `N(q)`: the gradient of band-limited (Perlin, `noise::Perlin` seeded with the field's
    /// seed) noise at noise-space point `q`.
    pub fn noise_gradient(&self, q: Vec3) -> Vec3 {
        self.lattice.gradient([q.x as f64, q.y as f64, q.z as f64]).as_vec3()
    }

    /// The small-scale wind of eq. 3.1 at `p` for a particle rooted at `p0`, at time `t`
    /// (frames): `((p − p0)·ĵ / height_unit) C N(k_p p − k_s t ĵ)`.
    pub fn small(&self, p: Vec3, p0: Vec3, t: f32) -> Vec3 {
        let f = &self.field;
        if f.noise_c == 0.0 {
            return Vec3::ZERO;
        }
        let height = (p - p0).dot(UP) / f.height_unit;
        let q = p * f.k_p - UP * (f.k_s * t);
        self.noise_gradient(q) * (height * f.noise_c)
    }

    /// The whole field `u∞ = −k_g g + w_L + w_S` at time `t` (frames).
    pub fn at(&self, p: Vec3, p0: Vec3, t: f32) -> Vec3 {
        if self.field.animation.is_none() {
            return -v3(self.field.gravity) * self.field.k_g + self.large(p) + self.small(p, p0, t);
        }
        // A sample that fails (an expression giving NaN) makes the wind NaN, which the particle
        // nodes report as a wind that drives a particle to a non-finite position.
        let Ok(field) = self.field.at_frame(f64::from(t), self.fps) else { return Vec3::NAN };
        let now = WindSampler { field, lattice: self.lattice.clone(), fps: self.fps };
        now.at(p, p0, t)
    }
}

pyrograph_core::choice! {
    /// The large-scale wind `w_L` of a [`WindField`].
    pub enum LargeScale {
        /// No large-scale wind.
        None = "none",
        /// The constant `wind`.
        Constant = "constant",
        /// A vortex about a vertical axis.
        Vortex = "vortex",
        /// The negative velocity of a moving burning object (§3.4).
        MovingObject = "moving_object",
    }
}

pyrograph_core::node! {
    /// The wind field flames move in (Perry 1994 §3.2.3): u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t).
    /// w_L is constant, a vortex, or the negative motion of a moving object (§3.4); w_S is eq. 3.1,
    /// the gradient of band-limited noise at k_p·p − k_s·T·ĵ scaled by C and by the height above the
    /// flame's base. Ranges of C, k_p and k_s are Perry's Table 3.1.
    #[node("particles.wind_field", "Particles", Source)]
    pub struct WindFieldNode {
        /// Gravity g (Perry: −ĵ).
        gravity: [f32; 3] = [0.0, -1.0, 0.0],
        /// Convection coefficient k_g: flames rise against gravity (Perry: 1.0).
        #[range(0.0, 10.0)]
        k_g: Anim<f32> = Anim::constant(1.0),
        /// Large-scale wind w_L: none, the constant `wind`, a vortex, or −`object_velocity` (§3.4).
        large_scale: LargeScale = LargeScale::None,
        /// Constant wind vector (large_scale = constant); animate it for gusts.
        wind: Anim<[f32; 3]> = Anim::constant([0.0, 0.0, 0.0]),
        /// Velocity of the burning object (large_scale = moving_object).
        object_velocity: [f32; 3] = [0.0, 0.0, 0.0],
        /// A point on the vertical vortex axis (large_scale = vortex).
        vortex_center: [f32; 3] = [0.0, 0.0, 0.0],
        /// Tangential wind speed at the vortex radius.
        #[range(-100.0, 100.0)]
        vortex_strength: f32 = 1.0,
        /// Vortex core radius (Rankine vortex).
        #[range(0.001, 1000.0)]
        vortex_radius: f32 = 1.0,
        /// Flame noisiness C of eq. 3.1 (Table 3.1; footnote 5: 0.04).
        #[range(0.0, 0.04)]
        noise_c: Anim<f32> = Anim::constant(0.04),
        /// Inverse inter-flame cohesion k_p: position scale into the noise (Table 3.1).
        #[range(0.1, 10.0)]
        k_p: f32 = 1.0,
        /// Flame sampling k_s: noise scroll per frame (Table 3.1).
        #[range(0.0, 1.0)]
        k_s: f32 = 0.1,
        /// Seed of the noise field.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
        /// World length of one unit of eq. 3.1's height factor (Perry counts integration steps); smaller bends more.
        #[range(0.0001, 1000.0)]
        height_unit: f32 = 1.0,
    }
    /// The wind field, for particles.particle_flame.
    -> wind: Arc<WindField>
}

/// `v` when every component is finite, else why not (the node names the port).
pub(crate) fn finite3(v: [f32; 3]) -> Result<[f32; 3], String> {
    if v.iter().all(|x| x.is_finite()) { Ok(v) } else { Err(format!("must be finite, got ({}, {}, {})", v[0], v[1], v[2])) }
}

fn finite(v: f32) -> Result<f32, String> {
    if v.is_finite() { Ok(v) } else { Err(format!("must be finite, got {v}")) }
}

impl WindFieldNode {
    /// The [`WindField`] the ports describe; errors name the port.
    pub fn field(&self) -> Result<WindField, NodeError> {
        let large = match self.large_scale {
            LargeScale::None => LargeWind::None,
            LargeScale::Constant => LargeWind::Constant(finite3(*self.wind.value()).at_port(port!(WindFieldNode, wind))?),
            LargeScale::MovingObject => {
                LargeWind::MovingObject(finite3(self.object_velocity).at_port(port!(WindFieldNode, object_velocity))?)
            }
            LargeScale::Vortex => LargeWind::Vortex {
                center: finite3(self.vortex_center).at_port(port!(WindFieldNode, vortex_center))?,
                strength: finite(self.vortex_strength).at_port(port!(WindFieldNode, vortex_strength))?,
                radius: finite(self.vortex_radius).at_port(port!(WindFieldNode, vortex_radius))?,
            },
        };
        Ok(WindField {
            gravity: finite3(self.gravity).at_port(port!(WindFieldNode, gravity))?,
            k_g: finite(*self.k_g.value()).at_port(port!(WindFieldNode, k_g))?,
            large,
            noise_c: finite(*self.noise_c.value()).at_port(port!(WindFieldNode, noise_c))?,
            k_p: finite(self.k_p).at_port(port!(WindFieldNode, k_p))?,
            k_s: finite(self.k_s).at_port(port!(WindFieldNode, k_s))?,
            seed: self.seed,
            height_unit: match finite(self.height_unit).at_port(port!(WindFieldNode, height_unit))? {
                h if h > 0.0 => h,
                h => return Err(NodeError::port(port!(WindFieldNode, height_unit), format!("must be positive, got {h}"))),
            },
            animation: self.animation(),
        })
    }

    /// The ports that change over time, for the field to sample at each frame or step.
    fn animation(&self) -> Option<Arc<WindAnimation>> {
        let anim = WindAnimation {
            wind: self.wind.is_animated().then(|| self.wind.clone()),
            noise_c: self.noise_c.is_animated().then(|| self.noise_c.clone()),
            k_g: self.k_g.is_animated().then(|| self.k_g.clone()),
        };
        (anim != WindAnimation::default()).then(|| Arc::new(anim))
    }
}

impl Cook for WindFieldNode {
    fn cook(self, _: &CookCtx) -> Result<Arc<WindField>, NodeError> {
        Ok(Arc::new(self.field()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::declare::Declared;
    use pyrograph_core::{Inputs, Value};

    #[test]
    fn still_air_is_pure_convection() {
        let w = WindField { noise_c: 0.0, ..WindField::default() };
        let s = WindSampler::new(&w);
        assert_eq!(s.at(Vec3::new(3.0, 2.0, 1.0), Vec3::ZERO, 5.0), Vec3::Y);
    }

    #[test]
    fn small_scale_wind_grows_with_height_and_vanishes_at_the_base() {
        let s = WindSampler::new(&WindField::default());
        let p0 = Vec3::new(0.3, 0.0, 0.2);
        assert_eq!(s.small(p0, p0, 3.0), Vec3::ZERO);
        let g = s.noise_gradient(Vec3::new(0.3, 1.0, 0.2) - Vec3::Y * 0.3);
        let w1 = s.small(p0 + Vec3::Y, p0, 3.0);
        assert!((w1 - g * 0.04).length() < 1e-6, "{w1} vs {g}");
    }

    #[test]
    fn the_noise_gradient_is_the_derivative_of_the_noise_crates_perlin_noise() {
        use noise::{NoiseFn, Perlin};
        let mut rng = pyrograph_testing::Lcg::new(12_345);
        let mut next = || rng.next_f64();
        for seed in [0u32, 7, 90_210] {
            let (perlin, lattice) = (Perlin::new(seed), Lattice::new(seed));
            // Random points, negative ones and lattice planes (where the cell changes) included.
            let mut points: Vec<[f64; 3]> = (0..400).map(|_| [0; 3].map(|_: i32| 40.0 * next() - 20.0)).collect();
            points.extend([[0.0, 0.0, 0.0], [1.0, -2.0, 3.0], [-0.5, 4.0, 0.25]]);
            for q in points {
                let g = lattice.gradient(q).to_array();
                let eps = 1e-5;
                for a in 0..3 {
                    let (mut hi, mut lo) = (q, q);
                    hi[a] += eps;
                    lo[a] -= eps;
                    let numeric = (perlin.get(hi) - perlin.get(lo)) / (2.0 * eps);
                    assert!((g[a] - numeric).abs() < 1e-6, "seed {seed} at {q:?}, axis {a}: {} vs {numeric}", g[a]);
                }
            }
        }
    }

    #[test]
    fn vortex_circulates_around_the_vertical_axis_and_moving_objects_feel_headwind() {
        let large = LargeWind::Vortex { center: [0.0; 3], strength: 2.0, radius: 1.0 };
        let s = WindSampler::new(&WindField { large, ..WindField::default() });
        let w = s.large(Vec3::new(2.0, 5.0, 0.0));
        assert!((w - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{w}");
        let m = WindSampler::new(&WindField { large: LargeWind::MovingObject([1.0, 0.0, 0.0]), ..WindField::default() });
        assert_eq!(m.large(Vec3::ZERO), Vec3::new(-1.0, 0.0, 0.0));
    }

    #[test]
    fn nan_wind_is_an_error_naming_the_port() {
        let w = WindField { large: LargeWind::Constant([f32::NAN, 0.0, 0.0]), ..WindField::default() };
        assert_eq!(validate_wind(&w).unwrap_err(), "wind w_L must be finite, got NaN");
        let desc = WindFieldNode::desc();
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap()).collect();
        values[desc.input_index("large_scale").unwrap()] = Value::Enum("constant".into());
        values[desc.input_index("wind").unwrap()] = Value::Vec3([f64::NAN, 0.0, 0.0]);
        let e = WindFieldNode::read(&Inputs::new(&desc, &values)).and_then(|n| n.field()).unwrap_err();
        assert!(matches!(&e, NodeError::Port { port, .. } if port == "wind"), "{e}");
    }

    #[test]
    fn table_3_1_ranges_are_the_port_ranges() {
        let desc = WindFieldNode::desc();
        let range = |n: &str| desc.inputs[desc.input_index(n).unwrap()].range;
        assert_eq!(range("k_p"), Some((0.1, 10.0)));
        assert_eq!(range("noise_c"), Some((0.0, 0.04)));
        assert_eq!(range("k_s"), Some((0.0, 1.0)));
    }
}
