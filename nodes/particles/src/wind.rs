//! The flame wind field `u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t)` (Perry 1994 §3.2.3) and
//! the `particles.wind_field` node that describes it.

use std::sync::Arc;

use glam::Vec3;
use noise::{NoiseFn, Perlin};
use pyrograph_core::{
    CookCtx, FnNode, Inputs, LargeWind, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep, Value, WindField,
};

/// Adds `particles.wind_field`.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(wind_field_desc(), cook_wind_field));
}

/// The world's up axis `ĵ`, along which eq. 3.1 measures height and time scrolls the noise.
pub const UP: Vec3 = Vec3::Y;

/// Step for the central differences of the noise gradient, in noise-lattice units.
const GRAD_EPS: f64 = 1e-3;

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// Checks every number of `wind` is finite; the error names `port` and the field.
pub fn validate_wind(wind: &WindField, port: &str) -> Result<(), NodeError> {
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
        Some((name, v)) => Err(NodeError::port(port, format!("wind {name} must be finite, got {v}"))),
        None if wind.height_unit <= 0.0 => Err(NodeError::port(port, "wind height_unit must be positive")),
        None => Ok(()),
    }
}

/// Evaluates a [`WindField`]: the noise lattice is built once per field.
pub struct WindSampler {
    field: WindField,
    perlin: Perlin,
}

impl WindSampler {
    /// A sampler for `field`.
    pub fn new(field: &WindField) -> Self {
        WindSampler { field: field.clone(), perlin: Perlin::new(field.seed) }
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

    /// `N(q)`: the gradient of band-limited (Perlin) noise at noise-space point `q`, by central
    /// differences.
    pub fn noise_gradient(&self, q: Vec3) -> Vec3 {
        let q = [q.x as f64, q.y as f64, q.z as f64];
        let mut g = [0.0f32; 3];
        for (axis, out) in g.iter_mut().enumerate() {
            let (mut a, mut b) = (q, q);
            a[axis] += GRAD_EPS;
            b[axis] -= GRAD_EPS;
            *out = ((self.perlin.get(a) - self.perlin.get(b)) / (2.0 * GRAD_EPS)) as f32;
        }
        Vec3::from_array(g)
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

    /// The whole field `u∞ = −k_g g + w_L + w_S`.
    pub fn at(&self, p: Vec3, p0: Vec3, t: f32) -> Vec3 {
        -v3(self.field.gravity) * self.field.k_g + self.large(p) + self.small(p, p0, t)
    }
}

fn wind_field_desc() -> NodeDesc {
    NodeDesc::new(
        "particles.wind_field",
        "Particles",
        TimeDep::Source,
        "The wind field flames move in (Perry 1994 §3.2.3): u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t). \
         w_L is constant, a vortex, or the negative motion of a moving object (§3.4); w_S is eq. 3.1, \
         the gradient of band-limited noise at k_p·p − k_s·T·ĵ scaled by C and by the height above the \
         flame's base. Ranges of C, k_p and k_s are Perry's Table 3.1.",
    )
    .input(PortDesc::vec3("gravity", [0.0, -1.0, 0.0], "Gravity g (Perry: −ĵ)."))
    .input(PortDesc::float("k_g", 1.0, (0.0, 10.0), "Convection coefficient k_g: flames rise against gravity (Perry: 1.0)."))
    .input(PortDesc::choice(
        "large_scale",
        &["none", "constant", "vortex", "moving_object"],
        "none",
        "Large-scale wind w_L: none, the constant `wind`, a vortex, or −`object_velocity` (§3.4).",
    ))
    .input(PortDesc::vec3("wind", [0.0, 0.0, 0.0], "Constant wind vector (large_scale = constant)."))
    .input(PortDesc::vec3("object_velocity", [0.0, 0.0, 0.0], "Velocity of the burning object (large_scale = moving_object)."))
    .input(PortDesc::vec3("vortex_center", [0.0, 0.0, 0.0], "A point on the vertical vortex axis (large_scale = vortex)."))
    .input(PortDesc::float("vortex_strength", 1.0, (-100.0, 100.0), "Tangential wind speed at the vortex radius."))
    .input(PortDesc::float("vortex_radius", 1.0, (0.001, 1000.0), "Vortex core radius (Rankine vortex)."))
    .input(PortDesc::float("noise_c", 0.04, (0.0, 0.04), "Flame noisiness C of eq. 3.1 (Table 3.1; footnote 5: 0.04)."))
    .input(PortDesc::float(
        "k_p",
        1.0,
        (0.1, 10.0),
        "Inverse inter-flame cohesion k_p: position scale into the noise (Table 3.1).",
    ))
    .input(PortDesc::float("k_s", 0.1, (0.0, 1.0), "Flame sampling k_s: noise scroll per frame (Table 3.1)."))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Seed of the noise field."))
    .input(PortDesc::float(
        "height_unit",
        1.0,
        (0.0001, 1000.0),
        "World length of one unit of eq. 3.1's height factor (Perry counts integration steps); smaller bends more.",
    ))
    .output("wind", PortType::WindField, "The wind field, for particles.particle_flame.")
}

fn finite_vec3(i: &Inputs<'_>, name: &str) -> Result<[f32; 3], NodeError> {
    let v = i.vec3(name)?;
    if v.iter().all(|x| x.is_finite()) {
        Ok(v.map(|x| x as f32))
    } else {
        Err(NodeError::port(name, format!("must be finite, got ({}, {}, {})", v[0], v[1], v[2])))
    }
}

fn finite_float(i: &Inputs<'_>, name: &str) -> Result<f32, NodeError> {
    let v = i.float(name)?;
    if v.is_finite() { Ok(v as f32) } else { Err(NodeError::port(name, format!("must be finite, got {v}"))) }
}

/// Builds the [`WindField`] described by the node's inputs; errors name the port.
pub fn wind_from_inputs(i: &Inputs<'_>) -> Result<WindField, NodeError> {
    let large = match i.choice("large_scale")? {
        "none" => LargeWind::None,
        "constant" => LargeWind::Constant(finite_vec3(i, "wind")?),
        "moving_object" => LargeWind::MovingObject(finite_vec3(i, "object_velocity")?),
        "vortex" => LargeWind::Vortex {
            center: finite_vec3(i, "vortex_center")?,
            strength: finite_float(i, "vortex_strength")?,
            radius: finite_float(i, "vortex_radius")?,
        },
        other => return Err(NodeError::port("large_scale", format!("unknown option '{other}'"))),
    };
    let seed = i.int("seed")?;
    Ok(WindField {
        gravity: finite_vec3(i, "gravity")?,
        k_g: finite_float(i, "k_g")?,
        large,
        noise_c: finite_float(i, "noise_c")?,
        k_p: finite_float(i, "k_p")?,
        k_s: finite_float(i, "k_s")?,
        seed: u32::try_from(seed).map_err(|_| NodeError::port("seed", format!("must be 0..=4294967295, got {seed}")))?,
        height_unit: match finite_float(i, "height_unit")? {
            h if h > 0.0 => h,
            h => return Err(NodeError::port("height_unit", format!("must be positive, got {h}"))),
        },
    })
}

fn cook_wind_field(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    Ok(vec![Value::WindField(Arc::new(wind_from_inputs(i)?))])
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let e = validate_wind(&w, "wind").unwrap_err();
        assert!(matches!(&e, NodeError::Port { port, .. } if port == "wind"), "{e}");
        let desc = wind_field_desc();
        let mut values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap()).collect();
        values[desc.input_index("large_scale").unwrap()] = Value::Enum("constant".into());
        values[desc.input_index("wind").unwrap()] = Value::Vec3([f64::NAN, 0.0, 0.0]);
        let e = wind_from_inputs(&Inputs::new(&desc, &values)).unwrap_err();
        assert!(matches!(&e, NodeError::Port { port, .. } if port == "wind"), "{e}");
    }

    #[test]
    fn table_3_1_ranges_are_the_port_ranges() {
        let desc = wind_field_desc();
        let range = |n: &str| desc.inputs[desc.input_index(n).unwrap()].range;
        assert_eq!(range("k_p"), Some((0.1, 10.0)));
        assert_eq!(range("noise_c"), Some((0.0, 0.04)));
        assert_eq!(range("k_s"), Some((0.0, 1.0)));
    }
}
