//! Animated parameters as port values: which port types animate, and sampling an animation into
//! a [`Value`] of its port's type, checked against the port's range. Here rather than in
//! `anim`, so that module stays below the values it samples into.

use crate::anim::{Animated, Shape, Track};
use crate::document::ParamValue;
use crate::value::{PortType, Value};

impl Shape {
    /// The kind of animated value a port of type `ty` takes; `None` for ports that cannot animate.
    pub fn of(ty: &PortType) -> Option<Shape> {
        Some(match ty {
            PortType::Float => Shape::Float,
            PortType::Int => Shape::Int,
            PortType::Bool => Shape::Bool,
            PortType::Vec2 => Shape::Vec2,
            PortType::Vec3 => Shape::Vec3,
            PortType::Color => Shape::Color,
            _ => return None,
        })
    }

    /// The port type of its samples.
    pub fn port_type(self) -> PortType {
        match self {
            Shape::Float => PortType::Float,
            Shape::Int => PortType::Int,
            Shape::Bool => PortType::Bool,
            Shape::Vec2 => PortType::Vec2,
            Shape::Vec3 => PortType::Vec3,
            Shape::Color => PortType::Color,
        }
    }
}

/// [`crate::anim::from_param`] for a port of type `ty`: `Ok(None)` for a plain constant, an
/// error for a form on a port that cannot animate.
pub fn animated_param(pv: &ParamValue, ty: &PortType) -> Result<Option<Animated>, String> {
    match Shape::of(ty) {
        Some(shape) => crate::anim::from_param(pv, shape),
        None if pv.is_animated() => {
            Err(format!("a {ty} parameter cannot be animated: only numbers, true/false, vectors and colours can"))
        }
        None => Ok(None),
    }
}

impl Animated {
    /// The port type the samples have.
    pub fn port_type(&self) -> PortType {
        self.shape().port_type()
    }

    /// The value at `frame` of a clip at `fps`, as a value of the port's type: Int rounds to the
    /// nearest integer, Bool is true above 0.5 (keys) or non-zero (expressions).
    pub fn sample(&self, frame: f64, fps: f64) -> Result<Value, String> {
        let c = self.components(frame, fps)?;
        Ok(match self.shape() {
            Shape::Int => Value::Int(c[0].round() as i64),
            Shape::Bool => Value::Bool(match &self.tracks()[0] {
                Track::Expr(_) => c[0] != 0.0,
                _ => c[0] > 0.5,
            }),
            Shape::Vec2 => Value::Vec2([c[0], c[1]]),
            Shape::Vec3 => Value::Vec3([c[0], c[1], c[2]]),
            Shape::Color => Value::Color(c.map(|x| x as f32)),
            Shape::Float => Value::Float(c[0]),
        })
    }

    /// [`Animated::sample`] checked against an inclusive `range` (Float and Int ports) and for
    /// NaN; the error names the frame.
    pub fn sample_in(&self, frame: f64, fps: f64, range: Option<(f64, f64)>) -> Result<Value, String> {
        let at = |f: f64| if f.fract() == 0.0 { format!("at frame {f}") } else { format!("at frame {f:.3}") };
        let v = self.sample(frame, fps).map_err(|e| format!("{}: {e}", at(frame)))?;
        let x = match v {
            Value::Float(x) => Some(x),
            Value::Int(i) => Some(i as f64),
            _ => None,
        };
        match (x, range) {
            (Some(x), _) if x.is_nan() => Err(format!("{} the value is NaN", at(frame))),
            (Some(x), Some((lo, hi))) if !(lo..=hi).contains(&x) => {
                Err(format!("{} the animated value {x} is outside the range {lo}..={hi}", at(frame)))
            }
            _ => Ok(v),
        }
    }
}
