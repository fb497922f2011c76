//! Keyframe edits of Float, Int and Bool parameters: setting, toggling, moving, deleting, copying and
//! pasting keys, each one undo step (a drag of a key, many moves, is one step until sealed).
//! The document edits themselves are [`crate::keys`]; here they are checked against the port
//! (its range, and that the keys still make a curve) before they reach the document.

use pyrograph_frontend::core::anim::Track;
use pyrograph_frontend::core::value::animated_param;
use pyrograph_frontend::core::{Animated, ParamValue, PortDesc, PortType};

use super::Editor;
use crate::keys::{self, KeyDoc, KeyList, frame_text};

/// An animated parameter of a node, read.
#[derive(Clone, Debug)]
pub struct AnimParam {
    /// The parameter's port.
    pub port: PortDesc,
    /// Its value as written (`keys(…)`, `expr(…)`, or a tuple of them).
    pub value: ParamValue,
    /// The animation: one track per component.
    pub animated: Animated,
}

impl AnimParam {
    /// Whether it is a Float or Int parameter (the ones the key tools edit).
    pub fn is_scalar(&self) -> bool {
        matches!(self.port.ty, PortType::Float | PortType::Int)
    }

    /// Its keys, for a keyed Float or Int parameter.
    pub fn keys(&self) -> Option<KeyList> {
        if self.is_scalar() { KeyList::read(&self.value) } else { None }
    }
}

/// Whether key values of `port` are whole numbers (Int, and Bool as 0 and 1).
fn whole(port: &PortDesc) -> bool {
    matches!(port.ty, PortType::Int | PortType::Bool)
}

/// A constant left by deleting the last key, in the port's kind (a Bool's 0 or 1 as false or true).
fn as_port_constant(port: &PortDesc, value: ParamValue) -> ParamValue {
    match (&port.ty, keys::constant(&value)) {
        (PortType::Bool, Some(v)) if !value.is_animated() => ParamValue::Bool(v > 0.5),
        _ => value,
    }
}

/// A readable number: up to 4 decimals, no trailing zeros.
pub fn value_text(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
    if s == "-0" { "0".into() } else { s.to_string() }
}

impl Editor {
    /// The frame the preview shows (the playhead).
    pub fn frame(&self) -> usize {
        self.current_frame()
    }

    /// While the preview plays: how many frames after each previewed one the cook worker cooks
    /// ahead into the frame cache (0 when it stops).
    pub fn set_read_ahead(&mut self, frames: usize) {
        self.cooker.set_read_ahead(frames);
    }

    /// Frames per second of the previewed clip (24 until a clip has been cooked).
    pub fn fps(&self) -> f64 {
        self.preview.as_ref().map(|p| p.fps).filter(|f| *f > 0.0).unwrap_or(24.0)
    }

    /// The animated parameters of `node` that read, in port order.
    pub fn animated_params(&self, node: &str) -> Vec<AnimParam> {
        let (Some(desc), Some(nd)) = (self.desc(node), self.doc.node(node)) else { return Vec::new() };
        desc.inputs
            .iter()
            .filter_map(|port| {
                let value = nd.params.get(&port.name).filter(|v| v.is_animated())?;
                let animated = animated_param(value, &port.ty).ok()??;
                Some(AnimParam { port: port.clone(), value: value.clone(), animated })
            })
            .collect()
    }

    /// The port of a Float or Int parameter `param` of `node`.
    pub fn scalar_port(&self, node: &str, param: &str) -> Result<PortDesc, String> {
        let desc = self.desc(node).ok_or_else(|| format!("node '{node}' has no known parameters"))?;
        let port = desc.inputs.iter().find(|p| p.name == param).ok_or_else(|| format!("'{node}' has no parameter '{param}'"))?;
        match port.ty {
            PortType::Float | PortType::Int | PortType::Bool => Ok(port.clone()),
            ref other => Err(format!("{node}.{param} is a {other} parameter: keys are set on Float, Int and Bool parameters")),
        }
    }

    /// The value of a Float or Int parameter at `frame`: its constant, or its animation sampled
    /// (an Int's keys sample unrounded here, so a key set from it keeps the curve's value).
    pub fn scalar_at(&self, node: &str, port: &PortDesc, frame: f64) -> Result<f64, String> {
        let value = self.param_value(node, port).ok_or_else(|| format!("{node}.{} has no value", port.name))?;
        match animated_param(&value, &port.ty)? {
            Some(a) => match a.tracks().first() {
                Some(Track::Keys(c)) => Ok(c.sample(frame)),
                Some(t) => t.sample(frame, self.fps()),
                None => Err(format!("{node}.{} has no track", port.name)),
            },
            None => keys::constant(&value).ok_or_else(|| format!("{node}.{} holds {value}, not a number", port.name)),
        }
    }

    /// Sets a key at `frame` with the value the parameter has there, or removes the key at
    /// `frame` if there is one. Returns whether a key is there afterwards.
    pub fn toggle_key(&mut self, node: &str, param: &str, frame: f64) -> Result<bool, String> {
        let r = self.toggle_key_inner(node, param, frame);
        self.report(r)
    }

    fn toggle_key_inner(&mut self, node: &str, param: &str, frame: f64) -> Result<bool, String> {
        let port = self.scalar_port(node, param)?;
        let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
        if let Some(i) = KeyList::read(&current).and_then(|l| l.find(frame)) {
            self.delete_key_inner(node, param, i)?;
            return Ok(false);
        }
        if keys::is_expr(&current) {
            return Err(format!("{node}.{param}: an expression drives it; stop animating it before setting keys"));
        }
        let mut value = self.scalar_at(node, &port, frame)?;
        if whole(&port) {
            value = value.round();
        }
        if port.ty == PortType::Bool {
            // A switch steps from key to key, as Houdini's toggles do: one edit, one undo step.
            let at = |e: String| format!("{node}.{param}: {e}");
            let (keyed, i) = keys::set_key(&current, frame, value, true).map_err(at)?;
            let stepped = keys::set_interp(&keyed, i, ParamValue::String("constant".into()), true).map_err(at)?;
            self.commit_keys(node, &port, stepped, None)?;
            return Ok(true);
        }
        self.set_key_inner(node, param, frame, value)?;
        Ok(true)
    }

    /// Sets a key at (`frame`, `value`) (replacing the value of a key there); returns its index.
    pub fn set_key(&mut self, node: &str, param: &str, frame: f64, value: f64) -> Result<usize, String> {
        let r = self.set_key_inner(node, param, frame, value);
        self.report(r)
    }

    fn set_key_inner(&mut self, node: &str, param: &str, frame: f64, value: f64) -> Result<usize, String> {
        let port = self.scalar_port(node, param)?;
        let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
        let (new, i) = keys::set_key(&current, frame, value, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
        self.commit_keys(node, &port, new, None)?;
        self.set_status(format!("key {}: {node}.{param} @ {} = {}", i + 1, frame_text(frame), value_text(value)), false);
        Ok(i)
    }

    /// Moves key `index` to (`frame`, `value`); returns its new index (a move past a neighbour
    /// reorders the keys; onto another key's frame it is refused). Moves of one key coalesce
    /// into one undo step until [`Editor::seal`], as a drag is one step.
    pub fn move_key(&mut self, node: &str, param: &str, index: usize, frame: f64, value: f64) -> Result<usize, String> {
        let r = self.move_key_inner(node, param, index, frame, value);
        self.report(r)
    }

    fn move_key_inner(&mut self, node: &str, param: &str, index: usize, frame: f64, value: f64) -> Result<usize, String> {
        let port = self.scalar_port(node, param)?;
        let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
        let (new, i) = keys::move_key(&current, index, frame, value, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
        self.commit_keys(node, &port, new, Some(&format!("keys:{node}.{param}")))?;
        Ok(i)
    }

    /// Gives key `index` the explicit slope `slope` on both sides (`tangent(slope)`). Changes of
    /// one key's tangent coalesce into one undo step until [`Editor::seal`], as a drag is one step.
    pub fn set_key_tangent(&mut self, node: &str, param: &str, index: usize, slope: f64) -> Result<(), String> {
        let r = (|| {
            let port = self.scalar_port(node, param)?;
            let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
            let new = keys::set_tangent(&current, index, slope, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
            self.commit_keys(node, &port, new, Some(&format!("tangent:{node}.{param}")))
        })();
        self.report(r)
    }

    /// Deletes key `index`; the last key deleted leaves the constant it held.
    pub fn delete_key(&mut self, node: &str, param: &str, index: usize) -> Result<(), String> {
        let r = self.delete_key_inner(node, param, index);
        self.report(r)
    }

    fn delete_key_inner(&mut self, node: &str, param: &str, index: usize) -> Result<(), String> {
        let port = self.scalar_port(node, param)?;
        let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
        let new = keys::remove_key(&current, index, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
        let new = as_port_constant(&port, new);
        self.commit_keys(node, &port, new, None)?;
        self.set_status(format!("deleted key {} of {node}.{param}", index + 1), false);
        Ok(())
    }

    /// Deletes the keys at the given (parameter, frame) pairs of `node`, as one undo step.
    /// Returns how many were deleted.
    pub fn delete_keys_at(&mut self, node: &str, at: &[(String, f64)]) -> Result<usize, String> {
        let r = self.delete_keys_at_inner(node, at);
        self.report(r)
    }

    fn delete_keys_at_inner(&mut self, node: &str, at: &[(String, f64)]) -> Result<usize, String> {
        let mut changed: Vec<(String, ParamValue)> = Vec::new();
        for (param, frame) in at {
            let port = self.scalar_port(node, param)?;
            let current = match changed.iter().rev().find(|(p, _)| p == param) {
                Some((_, v)) => v.clone(),
                None => self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?,
            };
            let Some(i) = KeyList::read(&current).and_then(|l| l.find(*frame)) else { continue };
            let new = keys::remove_key(&current, i, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
            let new = as_port_constant(&port, new);
            self.check_keys(node, &port, &new)?;
            changed.push((param.clone(), new));
        }
        let n = changed.len();
        self.edit(None, |d| changed.into_iter().try_for_each(|(p, v)| d.set_param(node, &p, v)))?;
        self.set_status(format!("deleted {n} key(s) of {node}"), false);
        Ok(n)
    }

    /// Copies keys `indices` of `node.param` for [`Editor::paste_keys`]; returns how many.
    pub fn copy_keys(&mut self, node: &str, param: &str, indices: &[usize]) -> usize {
        let list = self.doc.node(node).and_then(|nd| nd.params.get(param)).and_then(KeyList::read);
        self.key_clipboard = list.map(|l| l.copy(indices)).unwrap_or_default();
        let n = self.key_clipboard.len();
        self.set_status(format!("copied {n} key(s) of {node}.{param}"), n == 0);
        n
    }

    /// The keys [`Editor::copy_keys`] copied (frames relative to the first).
    pub fn copied_keys(&self) -> &[KeyDoc] {
        &self.key_clipboard
    }

    /// Pastes the copied keys into `node.param`, the first at `frame` (replacing keys at their frames).
    pub fn paste_keys(&mut self, node: &str, param: &str, frame: f64) -> Result<(), String> {
        let r = (|| {
            let port = self.scalar_port(node, param)?;
            let current = self.param_value(node, &port).ok_or_else(|| format!("{node}.{param} has no value"))?;
            let copied = self.key_clipboard.clone();
            let new = keys::paste_keys(&current, &copied, frame, whole(&port)).map_err(|e| format!("{node}.{param}: {e}"))?;
            self.commit_keys(node, &port, new, None)?;
            self.set_status(format!("pasted {} key(s) into {node}.{param} at frame {}", copied.len(), frame_text(frame)), false);
            Ok(())
        })();
        self.report(r)
    }

    /// Puts an error in the status line.
    fn report<T>(&mut self, r: Result<T, String>) -> Result<T, String> {
        if let Err(e) = &r {
            self.set_status(e.clone(), true);
        }
        r
    }

    /// Writes a parameter value made by a key edit, after [`Editor::check_keys`].
    fn commit_keys(&mut self, node: &str, port: &PortDesc, new: ParamValue, coalesce: Option<&str>) -> Result<(), String> {
        self.check_keys(node, port, &new)?;
        self.edit(coalesce, |d| d.set_param(node, &port.name, new))
    }

    /// Checks a parameter value made by a key edit: its keys make a curve and every keyed (or
    /// constant) value is in the port's range.
    fn check_keys(&self, node: &str, port: &PortDesc, new: &ParamValue) -> Result<(), String> {
        let name = &port.name;
        let values: Vec<(Option<f64>, f64)> = match animated_param(new, &port.ty).map_err(|e| format!("{node}.{name}: {e}"))? {
            Some(_) => KeyList::read(new).map(|l| l.keys.iter().map(|k| (Some(k.frame), k.value)).collect()).unwrap_or_default(),
            None => keys::constant(new).map(|v| vec![(None, v)]).unwrap_or_default(),
        };
        if let Some((lo, hi)) = port.range
            && let Some((frame, v)) = values.iter().find(|(_, v)| !(lo..=hi).contains(v))
        {
            let at = frame.map_or(String::new(), |f| format!(" at frame {}", frame_text(f)));
            return Err(format!("{node}.{name}: {}{at} is outside the range {lo}..={hi}; the key is not set", value_text(*v)));
        }
        // Between the keys, an explicit tangent can carry the curve past them.
        if let (Some((lo, hi)), Ok(Some(a))) = (port.range, animated_param(new, &port.ty))
            && let Some(Track::Keys(c)) = a.tracks().first()
        {
            let (min, max) = c.value_bounds();
            if min < lo || max > hi {
                return Err(format!(
                    "{node}.{name}: the curve would reach {} between its keys, outside the range {lo}..={hi}; not changed",
                    value_text(if min < lo { min } else { max })
                ));
            }
        }
        Ok(())
    }
}
