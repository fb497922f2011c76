//! [`Anim`]: the port type of a parameter a node samples itself over time (a simulation's
//! animated parameter), beside the plain port types of `declare`.

use std::sync::Arc;

use super::Port;
use crate::error::NodeError;
use crate::node::PortDesc;
use crate::value::{PortType, Value};

/// A parameter the node samples itself at every step of a simulation: a constant, or keys or an
/// expression ([`crate::anim`]). `p.size.at(frame, fps)?` is the value at a (fractional) frame,
/// checked against the port's range; the error names the port and the frame.
#[derive(Clone, Debug)]
pub struct Anim<T> {
    constant: T,
    animated: Option<Sampled>,
}

/// An animated parameter that could not be sampled (an expression failing at a frame, a value
/// outside the port's range): the port it was set on and why. Algorithms that sample parameters
/// pass it on in their own errors; a node's error names the port.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("port '{port}': {message}")]
pub struct AnimError {
    /// The port the animation was set on.
    pub port: String,
    /// What went wrong, at which frame.
    pub message: String,
}

impl From<AnimError> for NodeError {
    fn from(e: AnimError) -> Self {
        NodeError::Port { port: e.port, message: e.message }
    }
}

/// An animation with the port it was set on: its name and range, for the checks and errors of
/// every sample.
type Sampled = (Arc<crate::anim::Animated>, String, Option<(f64, f64)>);

impl<T: Port + Clone> Anim<T> {
    /// The same value at every frame.
    pub fn constant(value: T) -> Self {
        Anim { constant: value, animated: None }
    }

    /// The value at `frame` of a clip at `fps`.
    pub fn at(&self, frame: f64, fps: f64) -> Result<T, AnimError> {
        let Some((animated, port, range)) = &self.animated else { return Ok(self.constant.clone()) };
        let error = |message| AnimError { port: port.clone(), message };
        let v = animated.sample_in(frame, fps, *range).map_err(error)?;
        T::from_value(&v).map_err(error)
    }

    /// The value at frame 0 (the value, when it does not change).
    pub fn value(&self) -> &T {
        &self.constant
    }

    /// Whether the value changes over time.
    pub fn is_animated(&self) -> bool {
        self.animated.is_some()
    }

    /// The animation, if any (for fingerprints and descriptions).
    pub fn animation(&self) -> Option<&Arc<crate::anim::Animated>> {
        self.animated.as_ref().map(|(a, _, _)| a)
    }
}

impl<T: Port + Clone> From<T> for Anim<T> {
    fn from(value: T) -> Self {
        Anim::constant(value)
    }
}

impl<T: PartialEq> PartialEq for Anim<T> {
    fn eq(&self, other: &Self) -> bool {
        self.constant == other.constant
            && match (&self.animated, &other.animated) {
                (None, None) => true,
                (Some(a), Some(b)) => a.0 == b.0,
                _ => false,
            }
    }
}

impl<T: Port + Clone> Port for Anim<T> {
    fn port_type() -> PortType {
        T::port_type()
    }
    fn into_value(self) -> Value {
        match self.animated {
            Some((a, _, _)) => Value::Anim(a),
            None => self.constant.into_value(),
        }
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        match v {
            Value::Anim(a) => {
                // Without the port (a value built in code), its first sample stands for the constant.
                let constant = T::from_value(&a.sample(0.0, 24.0)?)?;
                Ok(Anim { constant, animated: Some((a.clone(), "(a value built in code)".into(), None)) })
            }
            other => T::from_value(other).map(Anim::constant),
        }
    }
    fn from_port(v: &Value, port: &PortDesc) -> Result<Self, String> {
        match v {
            Value::Anim(a) => {
                let first = a.sample_in(0.0, 24.0, port.range)?;
                let constant = T::from_value(&first)?;
                Ok(Anim { constant, animated: Some((a.clone(), port.name.clone(), port.range)) })
            }
            other => T::from_value(other).map(Anim::constant),
        }
    }
    fn options() -> Vec<String> {
        T::options()
    }
    fn sampled_by_node() -> bool {
        true
    }
}
