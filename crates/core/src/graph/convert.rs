//! Parameters between their file form ([`ParamValue`]) and typed values: kinds, ranges, colours,
//! `${VAR}` expansion and where relative paths resolve.

use std::path::{Path, PathBuf};

use super::LoadCtx;
use crate::document::ParamValue;
use crate::error::{DiagnosticKind, shortened};
use crate::limits::{inside, may_read};
use crate::node::{PathRole, PortDesc};
use crate::value::{PortType, Value};

pub(super) fn resolve_default(port: &PortDesc, ctx: &LoadCtx) -> Option<Value> {
    match (&port.default, port.path_role) {
        (Some(Value::Path(p)), Some(role)) => Some(Value::Path(resolve_path(p, role, ctx))),
        (d, _) => d.clone(),
    }
}

fn resolve_path(p: &Path, role: PathRole, ctx: &LoadCtx) -> PathBuf {
    if p.is_absolute() {
        return p.to_path_buf();
    }
    match (role, &ctx.options.output_dir) {
        (PathRole::Output, Some(out)) => out.join(p),
        _ => ctx.dir.join(p),
    }
}

/// Expands `${NAME}` from the environment; an unset variable is an error naming it.
pub fn expand_vars(text: &str) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("${") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        let end = after.find('}').ok_or_else(|| format!("unclosed '${{' in \"{text}\""))?;
        let name = &after[..end];
        match std::env::var(name) {
            Ok(v) if !v.is_empty() => out.push_str(&v),
            _ => {
                return Err(format!(
                    "environment variable {name} is not set (used in \"{text}\"); set it, e.g. `export {name}=/path`"
                ));
            }
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

fn number(pv: &ParamValue) -> Option<f64> {
    match pv {
        ParamValue::Int(v) => Some(*v as f64),
        ParamValue::Float(v) => Some(*v),
        _ => None,
    }
}

fn numbers<const N: usize>(pv: &ParamValue) -> Option<[f64; N]> {
    match pv {
        ParamValue::List(items) if items.len() == N => {
            let mut out = [0.0; N];
            for (o, item) in out.iter_mut().zip(items) {
                *o = number(item)?;
            }
            Some(out)
        }
        _ => None,
    }
}

/// Parses `#rrggbb` or `#rrggbbaa` into straight RGBA in 0..1.
pub fn parse_hex_color(s: &str) -> Option<[f32; 4]> {
    let hex = s.strip_prefix('#')?;
    if !(hex.len() == 6 || hex.len() == 8) || !hex.is_ascii() {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok().map(|b| b as f32 / 255.0);
    let a = if hex.len() == 8 { byte(6)? } else { 1.0 };
    Some([byte(0)?, byte(2)?, byte(4)?, a])
}

fn check_range(v: f64, port: &PortDesc) -> Result<(), (DiagnosticKind, String)> {
    match port.range {
        Some((lo, hi)) if !(lo..=hi).contains(&v) => {
            Err((DiagnosticKind::OutOfRange, format!("{v} is outside the range {lo}..={hi}")))
        }
        _ if v.is_nan() => Err((DiagnosticKind::OutOfRange, "NaN is not a valid value".to_string())),
        _ => Ok(()),
    }
}

/// Converts a parameter from a file to a typed value for `port`, checking kind and range; a
/// keyframed or expression value becomes [`Value::Anim`], its keys checked against the range.
pub(super) fn param_to_value(pv: &ParamValue, port: &PortDesc, ctx: &LoadCtx) -> Result<Value, (DiagnosticKind, String)> {
    match crate::value::animated_param(pv, &port.ty) {
        Ok(Some(animated)) => return animated_value(animated, port),
        Ok(None) => {}
        Err(message) => return Err((DiagnosticKind::Animation, message)),
    }
    let wrong = |what: &str| (DiagnosticKind::WrongKind, format!("needs {what}, got {}", shortened(&pv.to_string())));
    match &port.ty {
        PortType::Float => {
            let v = number(pv).ok_or_else(|| wrong("a number"))?;
            check_range(v, port)?;
            Ok(Value::Float(v))
        }
        PortType::Int => {
            let ParamValue::Int(v) = pv else { return Err(wrong("an integer")) };
            check_range(*v as f64, port)?;
            Ok(Value::Int(*v))
        }
        PortType::Bool => match pv {
            ParamValue::Bool(b) => Ok(Value::Bool(*b)),
            _ => Err(wrong("true or false")),
        },
        PortType::Color => {
            let c = match pv {
                ParamValue::String(s) => parse_hex_color(s),
                _ => numbers::<4>(pv)
                    .map(|c| c.map(|v| v as f32))
                    .or_else(|| numbers::<3>(pv).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0])),
            };
            c.map(Value::Color).ok_or_else(|| wrong("a colour: (r, g, b), (r, g, b, a) or \"#rrggbb\""))
        }
        PortType::Ramp(width) => {
            // Older files hold the text form; it reads as it always did.
            let keys = match pv {
                ParamValue::String(text) => crate::value::RampKeys::parse_legacy(text, *width),
                other => crate::value::RampKeys::from_param(other, *width),
            };
            keys.map(|k| Value::Ramp(std::sync::Arc::new(k))).map_err(|m| (DiagnosticKind::WrongKind, m))
        }
        PortType::Points => {
            // Older files hold the text form; it reads as it always did.
            let points = match pv {
                ParamValue::String(text) => crate::value::Points::parse_legacy(text),
                other => crate::value::Points::from_param(other),
            };
            points.map(|p| Value::Points(std::sync::Arc::new(p))).map_err(|m| (DiagnosticKind::WrongKind, m))
        }
        PortType::Vec2 => numbers::<2>(pv).map(Value::Vec2).ok_or_else(|| wrong("(x, y)")),
        PortType::Vec3 => numbers::<3>(pv).map(Value::Vec3).ok_or_else(|| wrong("(x, y, z)")),
        PortType::String => match pv {
            ParamValue::String(s) => Ok(Value::String(s.clone())),
            _ => Err(wrong("a string")),
        },
        PortType::Enum => match pv {
            ParamValue::String(s) if port.options.iter().any(|o| o == s) => Ok(Value::Enum(s.clone())),
            ParamValue::String(s) => {
                Err((DiagnosticKind::OutOfRange, format!("\"{s}\" is not one of: {}", port.options.join(", "))))
            }
            _ => Err(wrong(&format!("one of: {}", port.options.join(", ")))),
        },
        PortType::Path => match pv {
            ParamValue::String(s) => {
                let expanded = match expand_vars(s) {
                    Ok(e) => e,
                    Err(_) if ctx.options.describe_only => s.clone(),
                    Err(m) => return Err((DiagnosticKind::UnsetVariable, m)),
                };
                let role = port.path_role.unwrap_or(PathRole::Input);
                let path = resolve_path(Path::new(&expanded), role, ctx);
                if role == PathRole::Output && !ctx.options.allow_outside_out && !inside(&path, &ctx.root) {
                    let what = if ctx.options.output_dir.is_some() { "the output folder (--out)" } else { "the graph's folder" };
                    return Err((
                        DiagnosticKind::OutsideOutput,
                        format!(
                            "\"{s}\" writes to {}, outside {what} {}; write a path inside it, or render with \
                             --allow-outside-out",
                            path.display(),
                            ctx.root.display()
                        ),
                    ));
                }
                // An empty path is "not set": the node says so when it cooks.
                if role == PathRole::Input && !expanded.is_empty() {
                    may_read(&path).map_err(|m| (DiagnosticKind::OutsideReadRoots, m))?;
                }
                Ok(Value::Path(path))
            }
            _ => Err(wrong("a path string")),
        },
        // Every data type (images, masks, clips, databases…): see `PortType::is_parameter`.
        _ => Err((
            DiagnosticKind::WrongKind,
            format!("is a {} input: connect another node's output to it instead of writing a value", port.ty),
        )),
    }
}

/// An animated parameter, its keys checked against the port's range (values between keys are
/// checked when they are sampled, with the frame named).
fn animated_value(animated: crate::anim::Animated, port: &PortDesc) -> Result<Value, (DiagnosticKind, String)> {
    if let Some((lo, hi)) = port.range {
        for track in animated.tracks() {
            let crate::anim::Track::Keys(channel) = track else { continue };
            if let Some((i, k)) = channel.keys().iter().enumerate().find(|(_, k)| !(lo..=hi).contains(&k.value)) {
                return Err((
                    DiagnosticKind::OutOfRange,
                    format!("key {} (frame {}): {} is outside the range {lo}..={hi}", i + 1, k.frame, k.value),
                ));
            }
            // Keys in range can still overshoot between them with explicit tangents.
            let (low, high) = channel.value_bounds();
            if let Some(x) = [low, high].into_iter().find(|x| !(lo..=hi).contains(x)) {
                return Err((
                    DiagnosticKind::OutOfRange,
                    format!(
                        "between its keys the curve reaches {x:.4}, outside the range {lo}..={hi}: its tangents overshoot; \
                         make them flatter or use smooth"
                    ),
                ));
            }
        }
    }
    Ok(Value::Anim(std::sync::Arc::new(animated)))
}

/// Converts a typed constant back to its file form (for presets and the editor).
pub fn value_to_param(v: &Value) -> Option<ParamValue> {
    Some(match v {
        Value::Float(x) => ParamValue::Float(*x),
        Value::Int(x) => ParamValue::Int(*x),
        Value::Bool(x) => ParamValue::Bool(*x),
        Value::Color(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x as f64)).collect()),
        Value::Vec2(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x)).collect()),
        Value::Vec3(c) => ParamValue::List(c.iter().map(|x| ParamValue::Float(*x)).collect()),
        Value::String(s) | Value::Enum(s) => ParamValue::String(s.clone()),
        Value::Path(p) => ParamValue::String(p.display().to_string()),
        Value::Anim(a) => a.written().clone(),
        Value::Ramp(r) => r.to_param(),
        Value::Points(p) => p.to_param(),
        Value::Image(_) | Value::Mask(_) | Value::Contours(_) | Value::Custom(_) | Value::Clip(_) => {
            return None;
        }
    })
}
