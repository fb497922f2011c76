//! Animated parameters: a Float, Int, Bool, Vec2, Vec3 or Color parameter may hold, instead of a
//! constant, a keyframed channel ([`channel`]) or an expression of `frame`, `time` and `fps`
//! ([`expr`]). Vectors and colours animate per component, as Houdini's channels do:
//! `(keys([(0, 0.0), (40, 2.5)]), 0, 0)` animates x and keeps y and z.
//!
//! In a graph file:
//! - `keys([(frame, value), (frame, value, interpolation), …])`, optionally followed by the
//!   extrapolation on both sides (`keys([…], cycle)`) or before and after (`keys([…], hold, linear)`).
//!   Interpolations: `smooth` (the default: a cubic through the keys that never overshoots),
//!   `linear`, `constant`, `ease` (flat at both keys), `tangent(slope)` or `tangent(in, out)`
//!   (explicit slopes in value per frame). Extrapolations: `hold` (the default), `cycle`, `linear`.
//! - `expr("0.5 + 0.2 * sin(time * 3)")`.
//!
//! Who samples: a per-frame node fed a clip cooks frame `f` with its parameters sampled at `f`
//! (by the evaluator); a simulation samples the parameters it declares as `Anim` (in `declare`)
//! itself, at every step. Every sampled value is checked against the port's range.

pub mod channel;
pub mod expr;

use std::hash::Hash;
use std::sync::Arc;

use crate::document::ParamValue;
use crate::fingerprint::Fingerprinter;

pub use channel::{Channel, Extrap, Interp, Key};
pub use expr::Expr;

/// One animated number: a constant, a keyframed channel or an expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Track {
    /// The same value at every frame.
    Const(f64),
    /// A keyframed channel.
    Keys(Arc<Channel>),
    /// An expression of `frame`, `time` and `fps`.
    Expr(Arc<Expr>),
}

impl Track {
    /// The value at `frame` (fractional for sub-steps) of a clip running at `fps`.
    pub fn sample(&self, frame: f64, fps: f64) -> Result<f64, String> {
        match self {
            Track::Const(v) => Ok(*v),
            Track::Keys(c) => Ok(c.sample(frame)),
            Track::Expr(e) => {
                e.eval(frame, fps).map_err(|err| format!("expression \"{}\": {err}", crate::error::shortened(e.text())))
            }
        }
    }
}

/// The kinds of parameter that can be animated, by their components. (The value module maps
/// them to port types: this module stays below the values it samples into.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// A Float.
    Float,
    /// An Int: samples round to the nearest integer.
    Int,
    /// A Bool: keys step; true above 0.5 (keys) or non-zero (expressions).
    Bool,
    /// Two floats.
    Vec2,
    /// Three floats.
    Vec3,
    /// Linear RGBA.
    Color,
}

impl Shape {
    /// Number of components.
    pub fn width(self) -> usize {
        match self {
            Shape::Float | Shape::Int | Shape::Bool => 1,
            Shape::Vec2 => 2,
            Shape::Vec3 => 3,
            Shape::Color => 4,
        }
    }

    /// The name the node reference uses for the type.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Float => "Float",
            Shape::Int => "Int",
            Shape::Bool => "Bool",
            Shape::Vec2 => "Vec2",
            Shape::Vec3 => "Vec3",
            Shape::Color => "Color",
        }
    }
}

/// An animated parameter value: one track per component (one for Float, Int and Bool, two for
/// Vec2, three for Vec3, four for Color), with the parameter as it was written.
#[derive(Clone, Debug, PartialEq)]
pub struct Animated {
    shape: Shape,
    tracks: Vec<Track>,
    written: ParamValue,
}

impl Animated {
    /// The kind of value the samples are.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// One track per component.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }

    /// The value as written in the graph file (`keys(…)`, `expr(…)` or a tuple of them).
    pub fn written(&self) -> &ParamValue {
        &self.written
    }

    /// The components at `frame` of a clip at `fps` (unused ones 0).
    pub fn components(&self, frame: f64, fps: f64) -> Result<[f64; 4], String> {
        let mut c = [0.0f64; 4];
        for (slot, track) in c.iter_mut().zip(&self.tracks) {
            *slot = track.sample(frame, fps)?;
        }
        Ok(c)
    }

    /// Feeds the animation's content into a hasher (for cache fingerprints).
    pub fn hash_into(&self, h: &mut Fingerprinter) {
        self.written.to_string().hash(h);
    }

    /// A one-line description: the value as written.
    pub fn summary(&self) -> String {
        self.written.to_string()
    }
}

/// Reads an animated parameter written for a parameter of kind `shape` (`keys(…)`, `expr(…)`,
/// or for vectors and colours a tuple whose components may be either). `Ok(None)` when `pv`
/// holds no form (a plain constant, converted as before). Errors say which component and key.
pub fn from_param(pv: &ParamValue, shape: Shape) -> Result<Option<Animated>, String> {
    if !pv.is_animated() {
        return Ok(None);
    }
    let width = shape.width();
    let tracks = match pv {
        ParamValue::Call(..) if width == 1 => vec![track(pv, shape)?],
        ParamValue::Call(..) => {
            return Err(format!(
                "animate a {} per component: write a tuple such as (keys([(0, 0.0), (24, 1.0)]), 0, 0), one entry per component",
                shape.name()
            ));
        }
        ParamValue::List(items) => {
            let ok = items.len() == width || (shape == Shape::Color && items.len() == 3);
            if !ok {
                return Err(format!("a {} has {width} components, got {}", shape.name(), items.len()));
            }
            let mut tracks = Vec::with_capacity(4);
            for (i, item) in items.iter().enumerate() {
                tracks.push(track(item, shape).map_err(|e| format!("component {} ({}): {e}", i + 1, component_name(shape, i)))?);
            }
            if tracks.len() == 3 && width == 4 {
                tracks.push(Track::Const(1.0));
            }
            tracks
        }
        _ => return Ok(None),
    };
    Ok(Some(Animated { shape, tracks, written: pv.clone() }))
}

fn component_name(shape: Shape, i: usize) -> &'static str {
    match shape {
        Shape::Color => ["red", "green", "blue", "alpha"][i.min(3)],
        _ => ["x", "y", "z", "w"][i.min(3)],
    }
}

/// One component: a number, `keys(…)` or `expr(…)`.
fn track(pv: &ParamValue, shape: Shape) -> Result<Track, String> {
    match pv {
        ParamValue::Int(v) => Ok(Track::Const(*v as f64)),
        ParamValue::Float(v) => Ok(Track::Const(*v)),
        ParamValue::Bool(b) if shape == Shape::Bool => Ok(Track::Const(if *b { 1.0 } else { 0.0 })),
        ParamValue::Call(name, arg) => match name.as_str() {
            "keys" => keys(arg, shape).map(|c| Track::Keys(Arc::new(c))),
            "expr" => match &**arg {
                ParamValue::String(text) => Expr::parse(text)
                    .map(|e| Track::Expr(Arc::new(e)))
                    .map_err(|e| format!("expression \"{}\": {e}", crate::error::shortened(text))),
                other => Err(format!("expr takes the expression as a string, e.g. expr(\"sin(time)\"), got {other}")),
            },
            other => Err(format!("unknown form '{other}(…)': a parameter takes keys([...]) or expr(\"...\")")),
        },
        other => Err(format!("needs a number, keys([...]) or expr(\"...\"), got {other}")),
    }
}

/// `keys([(frame, value[, interpolation]), …][, extrapolation[, extrapolation]])`.
fn keys(arg: &ParamValue, shape: Shape) -> Result<Channel, String> {
    let ParamValue::List(items) = arg else {
        return Err(format!("keys takes a list of (frame, value) keys, e.g. keys([(0, 0.2), (40, 1.5)]), got {arg}"));
    };
    let (list, extras) = ParamValue::key_args(items).unwrap_or((items, &[]));
    let (before, after) = match extras {
        [] => (Extrap::Hold, Extrap::Hold),
        [both] => (extrap(both)?, extrap(both)?),
        [b, a] => (extrap(b)?, extrap(a)?),
        _ => return Err("keys takes the key list and at most two extrapolations (before, after)".into()),
    };
    let mut parsed = Vec::with_capacity(list.len());
    for (i, k) in list.iter().enumerate() {
        parsed.push(key(k, shape).map_err(|e| format!("key {}: {e}", i + 1))?);
    }
    Channel::new(parsed, before, after).map_err(|e| e.to_string())
}

fn extrap(pv: &ParamValue) -> Result<Extrap, String> {
    match pv {
        ParamValue::String(s) => {
            Extrap::parse(s).ok_or_else(|| format!("'{s}' is not an extrapolation; use one of: {}", Extrap::NAMES.join(", ")))
        }
        other => Err(format!("an extrapolation is one of {}, got {other}", Extrap::NAMES.join(", "))),
    }
}

fn number(pv: &ParamValue, shape: Shape) -> Option<f64> {
    match pv {
        ParamValue::Int(v) => Some(*v as f64),
        ParamValue::Float(v) => Some(*v),
        ParamValue::Bool(b) if shape == Shape::Bool => Some(if *b { 1.0 } else { 0.0 }),
        _ => None,
    }
}

/// `(frame, value)` or `(frame, value, interpolation)`.
fn key(pv: &ParamValue, shape: Shape) -> Result<Key, String> {
    let ParamValue::List(parts) = pv else {
        return Err(format!("a key is (frame, value) or (frame, value, interpolation), got {pv}"));
    };
    let (frame, value, mode) = match parts.as_slice() {
        [f, v] => (f, v, None),
        [f, v, m] => (f, v, Some(m)),
        _ => return Err(format!("a key is (frame, value) or (frame, value, interpolation), got {pv}")),
    };
    let frame = number(frame, Shape::Float).ok_or_else(|| format!("the frame must be a number, got {frame}"))?;
    let value = number(value, shape).ok_or_else(|| format!("the value must be a number, got {value}"))?;
    let interp = match mode {
        None if shape == Shape::Bool => Interp::Constant,
        None => Interp::Smooth,
        Some(m) => interp(m)?,
    };
    Ok(Key { frame, value, interp })
}

fn interp(pv: &ParamValue) -> Result<Interp, String> {
    let names = || format!("{}, tangent(slope) or tangent(in, out)", Interp::NAMES.join(", "));
    match pv {
        ParamValue::String(s) => {
            Interp::parse(s).ok_or_else(|| format!("'{s}' is not an interpolation; use one of: {}", names()))
        }
        ParamValue::Call(name, arg) if name == "tangent" => {
            let slopes: Vec<f64> = match &**arg {
                ParamValue::List(items) => items.iter().filter_map(|x| number(x, Shape::Float)).collect(),
                other => number(other, Shape::Float).into_iter().collect(),
            };
            match slopes.as_slice() {
                [s] => Ok(Interp::Tangent { in_slope: *s, out_slope: *s }),
                [i, o] => Ok(Interp::Tangent { in_slope: *i, out_slope: *o }),
                _ => Err(format!("tangent takes one slope or two (in, out), in value per frame, got tangent{arg}")),
            }
        }
        other => Err(format!("'{other}' is not an interpolation; use one of: {}", names())),
    }
}

#[cfg(test)]
mod tests;
