//! Keys on Vec2, Vec3 and Color parameters: a vector animates per component, as Houdini's
//! channels do (`(keys([...]), keys([...]), 0.5)`), and the key toggle keys every component at
//! once: all of them at the playhead's value when any lacks a key there, or none when all have
//! one. Each toggle is one undo step.

use pyrograph_frontend::core::value::animated_param;
use pyrograph_frontend::core::{ParamValue, PortDesc, PortType};

use super::Editor;
use crate::keys::{self, KeyList, frame_text};

/// How many components a parameter of type `ty` animates (`None` for the non-vector types).
pub fn components(ty: &PortType) -> Option<usize> {
    match ty {
        PortType::Vec2 => Some(2),
        PortType::Vec3 => Some(3),
        PortType::Color => Some(4),
        _ => None,
    }
}

/// The per-component values of a vector parameter as written: a constant, keys or an expression
/// each (a colour written `"#rrggbb"` or with three components gets its alpha of 1).
pub fn split(value: &ParamValue, n: usize) -> Option<Vec<ParamValue>> {
    let mut parts = match value {
        ParamValue::List(items) => items.clone(),
        ParamValue::String(hex) if n == 4 => {
            pyrograph_frontend::core::graph::parse_hex_color(hex)?.iter().map(|c| ParamValue::Float(f64::from(*c))).collect()
        }
        _ => return None,
    };
    if n == 4 && parts.len() == 3 {
        parts.push(ParamValue::Float(1.0));
    }
    (parts.len() == n).then_some(parts)
}

/// Whether every component of a vector value has a key at `frame`.
pub fn all_keyed_at(value: &ParamValue, n: usize, frame: f64) -> bool {
    split(value, n).is_some_and(|parts| parts.iter().all(|p| KeyList::read(p).is_some_and(|l| l.find(frame).is_some())))
}

impl Editor {
    /// The port of a Vec2, Vec3 or Color parameter `param` of `node`, and its component count.
    fn vector_port(&self, node: &str, param: &str) -> Result<(PortDesc, usize), String> {
        let desc = self.desc(node).ok_or_else(|| format!("node '{node}' has no known parameters"))?;
        let port = desc.inputs.iter().find(|p| p.name == param).ok_or_else(|| format!("'{node}' has no parameter '{param}'"))?;
        let n =
            components(&port.ty).ok_or_else(|| format!("{node}.{param} is a {} parameter, not a vector or colour", port.ty))?;
        Ok((port.clone(), n))
    }

    /// Keys every component of a vector or colour parameter at `frame` with the value it has
    /// there, or, when every component has a key at `frame`, removes those keys. Returns whether
    /// keys are there afterwards. One undo step.
    pub fn toggle_vector_key(&mut self, node: &str, param: &str, frame: f64) -> Result<bool, String> {
        let r = self.toggle_vector_key_inner(node, param, frame);
        if let Err(e) = &r {
            self.set_status(e.clone(), true);
        }
        r
    }

    fn toggle_vector_key_inner(&mut self, node: &str, param: &str, frame: f64) -> Result<bool, String> {
        let (port, n) = self.vector_port(node, param)?;
        let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
        let parts = split(&current, n).ok_or_else(|| {
            format!("{node}.{param}: an expression drives it as a whole; stop animating it before setting keys")
        })?;
        let fps = self.fps();
        let remove = all_keyed_at(&current, n, frame);
        let mut out = Vec::with_capacity(n);
        for (c, part) in parts.iter().enumerate() {
            let at = |e: String| format!("{node}.{param}, component {}: {e}", c + 1);
            if keys::is_expr(part) {
                return Err(at("an expression drives it; stop animating it before setting keys".into()));
            }
            let list = KeyList::read(part);
            let here = list.as_ref().and_then(|l| l.find(frame));
            out.push(match (remove, here) {
                (true, Some(i)) => keys::remove_key(part, i, false).map_err(at)?,
                (false, Some(_)) => part.clone(),
                _ => {
                    let value = match animated_param(part, &PortType::Float).map_err(at)? {
                        Some(a) => a.tracks()[0].sample(frame, fps).map_err(at)?,
                        None => keys::constant(part).ok_or_else(|| at(format!("{part} is not a number")))?,
                    };
                    keys::set_key(part, frame, value, false).map_err(at)?.0
                }
            });
        }
        let new = ParamValue::List(out);
        animated_param(&new, &port.ty).map_err(|e| format!("{node}.{param}: {e}"))?;
        self.edit(None, |d| d.set_param(node, param, new))?;
        let what = if remove { "keys removed" } else { "keyed" };
        self.set_status(format!("{node}.{param} {what} at frame {}", frame_text(frame)), false);
        Ok(!remove)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_colour_splits_into_four_components_whatever_its_form() {
        let four = |v: &str| split(&ParamValue::parse_cli(v), 4).map(|p| p.len());
        assert_eq!(four("(1, 0.5, 0)"), Some(4));
        assert_eq!(four("\"#ff8000\""), Some(4));
        assert_eq!(four("(keys([(0, 1.0), (10, 0.0)]), 0.5, 0, 1)"), Some(4));
        assert_eq!(four("expr(\"sin(time)\")"), None);
        assert!(all_keyed_at(&ParamValue::parse_cli("(keys([(0, 1.0)]), keys([(0, 2.0)]))"), 2, 0.0));
        assert!(!all_keyed_at(&ParamValue::parse_cli("(keys([(0, 1.0)]), 2.0)"), 2, 0.0));
    }
}
