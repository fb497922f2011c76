//! A Python node's declaration (what `@node` in `pyrograph_plugin.py` reports) and its checked
//! translation into a [`NodeDesc`], so a plugin node lists, wires and validates like a built-in.

use pyrograph_core::value::{PortType, RampKeys};
use pyrograph_core::{NodeDesc, PathRole, PortDesc, TimeDep, Value};
use serde::Deserialize;
use serde_json::Value as Json;

/// One `@node` function, as the worker describes it.
#[derive(Debug, Clone, Deserialize)]
pub struct NodeDecl {
    /// The stable, namespaced type name (`studio.heat_haze`).
    pub type_name: String,
    /// The palette category.
    pub category: String,
    /// The one-line doc.
    pub doc: String,
    /// How it depends on time: `per_frame`.
    pub time: String,
    /// The Python function's name.
    pub function: String,
    /// The line of its `def`.
    pub line: u64,
    /// Inputs, in the function's parameter order.
    pub inputs: Vec<PortDecl>,
    /// Outputs, in declared order.
    pub outputs: Vec<PortDecl>,
}

/// One port of a Python node.
#[derive(Debug, Clone, Deserialize)]
pub struct PortDecl {
    /// The parameter's name.
    pub name: String,
    /// `float`, `int`, `bool`, `string`, `enum`, `color`, `vec2`, `vec3`, `path`, `image`, `mask`,
    /// `color_ramp`, `curve`, `clip` (of images) or `points`.
    pub kind: String,
    /// The port's doc.
    #[serde(default)]
    pub doc: String,
    /// The Python default; none for a required port.
    #[serde(default)]
    pub default: Option<Json>,
    /// The allowed range of a number.
    #[serde(default)]
    pub range: Option<(f64, f64)>,
    /// An enumeration's options.
    #[serde(default)]
    pub options: Vec<String>,
    /// For images: `any`, `gray` or `rgba`.
    #[serde(default)]
    pub channels: Option<String>,
}

/// Whether `name` is a namespaced type name: dot-separated lower-case identifiers, at least two.
pub fn valid_type_name(name: &str) -> bool {
    let parts: Vec<&str> = name.split('.').collect();
    parts.len() >= 2 && parts.iter().all(|p| valid_identifier(p))
}

fn valid_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some('a'..='z')) && chars.all(|c| matches!(c, 'a'..='z' | '0'..='9' | '_'))
}

impl NodeDecl {
    /// The node description, or what is wrong with the declaration (in the plugin author's terms).
    pub fn to_desc(&self) -> Result<NodeDesc, String> {
        if !valid_type_name(&self.type_name) {
            return Err(format!(
                "'{}' is not a type name: use lower-case words joined by dots, with a namespace (studio.heat_haze)",
                self.type_name
            ));
        }
        let time = match self.time.as_str() {
            "per_frame" => TimeDep::PerFrame,
            "whole_clip" => TimeDep::WholeClip,
            other => return Err(format!("time '{other}' is not supported: per_frame or whole_clip")),
        };
        if self.outputs.is_empty() {
            return Err("a node needs at least one output".into());
        }
        let clips_allowed = |p: &PortDecl| match p.kind.as_str() {
            "clip" if time != TimeDep::WholeClip => {
                Err("clips are for whole_clip nodes (pyrograph applies a per_frame node to every frame itself)".to_string())
            }
            _ => Ok(()),
        };
        let mut desc = NodeDesc::new(&self.type_name, &self.category, time, &self.doc);
        for p in &self.inputs {
            let port = clips_allowed(p).and_then(|()| p.input_desc()).map_err(|e| format!("input '{}': {e}", p.name))?;
            desc = desc.input(port);
        }
        for p in &self.outputs {
            let ty = clips_allowed(p).and_then(|()| p.output_type()).map_err(|e| format!("output '{}': {e}", p.name))?;
            desc = desc.output(&p.name, ty, &p.doc);
        }
        for ports in [&desc.inputs, &desc.outputs] {
            if let Some(twice) = ports.iter().enumerate().find(|(i, p)| ports[..*i].iter().any(|q| q.name == p.name)) {
                return Err(format!("two ports are named '{}'", twice.1.name));
            }
        }
        Ok(desc)
    }
}

impl PortDecl {
    fn port_type(&self) -> Result<PortType, String> {
        Ok(match self.kind.as_str() {
            "float" => PortType::Float,
            "int" => PortType::Int,
            "bool" => PortType::Bool,
            "string" => PortType::String,
            "enum" => PortType::Enum,
            "color" => PortType::Color,
            "vec2" => PortType::Vec2,
            "vec3" => PortType::Vec3,
            "path" => PortType::Path,
            "image" => PortType::Image,
            "mask" => PortType::Mask,
            "color_ramp" => PortType::Ramp(4),
            "curve" => PortType::Ramp(1),
            "clip" => PortType::clip_of(PortType::Image),
            "points" => PortType::Points,
            other => return Err(format!("kind '{other}' is not one pyrograph knows")),
        })
    }

    fn input_desc(&self) -> Result<PortDesc, String> {
        if !valid_identifier(&self.name) {
            return Err("a port name is lower-case letters, digits and '_'".into());
        }
        let ty = self.port_type()?;
        if ty == PortType::Points {
            return Err("a plugin cannot take points yet".into());
        }
        let mut port = PortDesc::new(&self.name, ty.clone(), &self.doc);
        if let Some((lo, hi)) = self.range {
            if !matches!(ty, PortType::Float | PortType::Int) || lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
                return Err(format!("range ({lo}, {hi}) needs a number port and low ≤ high"));
            }
            port.range = Some((lo, hi));
        }
        if ty == PortType::Enum {
            if self.options.is_empty() {
                return Err("an enumeration needs options".into());
            }
            port.options = self.options.clone();
        }
        if ty == PortType::Path {
            port.path_role = Some(PathRole::Input);
        }
        if let Some(json) = &self.default {
            let value = default_value(&ty, json).ok_or_else(|| format!("default {json} is not a {}", self.kind))?;
            pyrograph_core::declare::check_range(&port, &value)?;
            if let Value::Enum(o) = &value
                && !port.options.contains(o)
            {
                return Err(format!("default '{o}' is not one of the options"));
            }
            port.default = Some(value);
        }
        Ok(port)
    }

    fn output_type(&self) -> Result<PortType, String> {
        let ty = self.port_type()?;
        match ty {
            PortType::Image | PortType::Mask | PortType::Points | PortType::Float | PortType::Int | PortType::Bool => Ok(ty),
            _ if ty.clip_element().is_some() => Ok(ty),
            _ => Err(format!("a plugin cannot output a {} yet (image, mask, clip, points, float, int or bool)", self.kind)),
        }
    }
}

/// The value a JSON default stands for, if it has the port's type.
fn default_value(ty: &PortType, json: &Json) -> Option<Value> {
    let floats = |n: usize| -> Option<Vec<f64>> {
        let a = json.as_array().filter(|a| a.len() == n)?;
        a.iter().map(Json::as_f64).collect()
    };
    Some(match ty {
        PortType::Float => Value::Float(json.as_f64().filter(|x| x.is_finite())?),
        PortType::Int => Value::Int(json.as_i64()?),
        PortType::Bool => Value::Bool(json.as_bool()?),
        PortType::String => Value::String(json.as_str()?.to_string()),
        PortType::Enum => Value::Enum(json.as_str()?.to_string()),
        PortType::Color => {
            let c = floats(4)?;
            Value::Color([c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32])
        }
        PortType::Vec2 => Value::Vec2(floats(2)?.try_into().ok()?),
        PortType::Vec3 => Value::Vec3(floats(3)?.try_into().ok()?),
        PortType::Ramp(width) => {
            let keys = json.as_array()?.iter().map(|row| {
                let row: Vec<f64> =
                    row.as_array().filter(|r| r.len() == 1 + width)?.iter().map(Json::as_f64).collect::<Option<_>>()?;
                let mut values = [0.0; 4];
                values[..*width].copy_from_slice(&row[1..]);
                Some((row[0], values))
            });
            Value::Ramp(std::sync::Arc::new(RampKeys::new(*width, keys.collect::<Option<_>>()?).ok()?))
        }
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heat_haze() -> NodeDecl {
        serde_json::from_value(serde_json::json!({
            "type_name": "studio.heat_haze", "category": "Studio", "doc": "Shimmers a frame.",
            "time": "per_frame", "function": "heat_haze", "line": 5,
            "inputs": [
                {"name": "image", "kind": "image", "doc": "Frame", "default": null, "range": null, "options": [], "channels": "any"},
                {"name": "amount", "kind": "float", "doc": "Pixels", "default": 4.0, "range": [0.0, 20.0], "options": [], "channels": null},
                {"name": "axis", "kind": "enum", "doc": "", "default": "vertical", "range": null, "options": ["vertical", "horizontal"], "channels": null},
                {"name": "tint", "kind": "color", "default": [1, 0.5, 0, 1]}
            ],
            "outputs": [{"name": "image", "kind": "image", "doc": "", "default": null}]
        }))
        .unwrap()
    }

    #[test]
    fn a_declaration_becomes_a_description() {
        let d = heat_haze().to_desc().unwrap();
        assert_eq!((d.type_name.as_str(), d.category.as_str(), d.time), ("studio.heat_haze", "Studio", TimeDep::PerFrame));
        assert!(d.inputs[0].is_required());
        assert_eq!(d.inputs[1].range, Some((0.0, 20.0)));
        assert!(matches!(d.inputs[1].default, Some(Value::Float(4.0))));
        assert_eq!(d.inputs[2].options, ["vertical", "horizontal"]);
        assert!(matches!(d.inputs[3].default, Some(Value::Color([1.0, 0.5, 0.0, 1.0]))));
        assert_eq!(d.outputs[0].ty, PortType::Image);
    }

    #[test]
    fn bad_declarations_say_what_is_wrong() {
        type Break = Box<dyn Fn(&mut NodeDecl)>;
        let cases: Vec<(Break, &str)> = vec![
            (Box::new(|d| d.type_name = "heat_haze".into()), "is not a type name"),
            (Box::new(|d| d.type_name = "Studio.Haze".into()), "is not a type name"),
            (Box::new(|d| d.time = "source".into()), "time 'source' is not supported"),
            (Box::new(|d| d.inputs[0].kind = "clip".into()), "input 'image': clips are for whole_clip nodes"),
            (Box::new(|d| d.outputs[0].kind = "clip".into()), "output 'image': clips are for whole_clip nodes"),
            (Box::new(|d| d.inputs[0].kind = "points".into()), "input 'image': a plugin cannot take points"),
            (Box::new(|d| d.inputs[1].default = Some(serde_json::json!(40.0))), "input 'amount': 40 is outside the range 0..=20"),
            (Box::new(|d| d.inputs[1].default = Some(serde_json::json!("x"))), "input 'amount': default \"x\" is not a float"),
            (Box::new(|d| d.inputs[2].default = Some(serde_json::json!("diagonal"))), "default 'diagonal' is not one of"),
            (Box::new(|d| d.inputs[2].options.clear()), "needs options"),
            (Box::new(|d| d.inputs[0].kind = "texture".into()), "input 'image': kind 'texture'"),
            (Box::new(|d| d.inputs[0].range = Some((0.0, 1.0))), "needs a number port"),
            (Box::new(|d| d.inputs[3].name = "amount".into()), "two ports are named 'amount'"),
            (Box::new(|d| d.inputs[3].name = "Tint".into()), "lower-case"),
            (Box::new(|d| d.outputs[0].kind = "path".into()), "cannot output a path"),
            (Box::new(|d| d.outputs.clear()), "at least one output"),
        ];
        for (break_it, expected) in cases {
            let mut d = heat_haze();
            break_it(&mut d);
            let e = d.to_desc().unwrap_err();
            assert!(e.contains(expected), "{e:?} should contain {expected:?}");
        }
    }

    #[test]
    fn a_whole_clip_node_takes_and_makes_clips_and_an_emitter_makes_points() {
        let mut d = heat_haze();
        d.time = "whole_clip".into();
        d.inputs[0].kind = "clip".into();
        d.outputs[0].kind = "clip".into();
        let desc = d.to_desc().unwrap();
        assert_eq!(desc.time, TimeDep::WholeClip);
        assert_eq!(
            (&desc.inputs[0].ty, &desc.outputs[0].ty),
            (&PortType::clip_of(PortType::Image), &PortType::clip_of(PortType::Image))
        );
        let mut d = heat_haze();
        d.outputs[0].kind = "points".into();
        assert_eq!(d.to_desc().unwrap().outputs[0].ty, PortType::Points);
    }

    #[test]
    fn ramps_and_curves_take_their_keys_as_defaults() {
        let mut d = heat_haze();
        d.inputs[3].kind = "color_ramp".into();
        d.inputs[3].default = Some(serde_json::json!([[0.0, 0, 0, 0, 1], [1.0, 1, 0.8, 0.3, 1]]));
        let desc = d.to_desc().unwrap();
        let Some(Value::Ramp(keys)) = &desc.inputs[3].default else { panic!("{:?}", desc.inputs[3].default) };
        assert_eq!((keys.width(), keys.keys()), (4, &[(0.0, [0.0, 0.0, 0.0, 1.0]), (1.0, [1.0, 0.8, 0.3, 1.0])][..]));
        d.inputs[3].kind = "curve".into();
        assert!(d.to_desc().unwrap_err().contains("is not a curve"), "a colour ramp's keys are not a curve's");
        d.inputs[3].default = Some(serde_json::json!([[1.0, 0.0], [0.0, 1.0]]));
        assert!(d.to_desc().is_err(), "keys out of position order");
        d.inputs[3].default = Some(serde_json::json!([[0.0, 0.5]]));
        assert_eq!(d.to_desc().unwrap().inputs[3].ty, PortType::Ramp(1));
    }

    #[test]
    fn an_input_and_an_output_may_share_a_name() {
        // `image` in, `image` out: the usual filter, as built-in nodes do.
        assert!(heat_haze().to_desc().is_ok());
    }
}
